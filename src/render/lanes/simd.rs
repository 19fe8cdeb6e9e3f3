//! Eight f32 lanes, two ways: `wide::f32x8` (two SSE registers on the x86-64-v2
//! build) and AVX's 256-bit registers where the CPU has AVX2, chosen at run
//! time as the 8-wide BVH is. Both do IEEE-exact operations, so the kernel's
//! results are the same bits either way.

use crate::math::Vec3;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Sub};

/// What the lane kernel asks of eight f32s. Comparisons return masks (all
/// bits set per true lane), which `select` and `bitmask` read.
pub(super) trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
{
    fn splat(x: f32) -> Self;
    fn load(a: [f32; 8]) -> Self;
    fn store(self) -> [f32; 8];
    /// Lanes of `t` where `self` is set, of `f` elsewhere.
    fn select(self, t: Self, f: Self) -> Self;
    fn lt(self, o: Self) -> Self;
    fn gt(self, o: Self) -> Self;
    fn le(self, o: Self) -> Self;
    fn eq(self, o: Self) -> Self;
    /// Unordered not-equal (true for NaN), as glam's `cmpne`.
    fn ne(self, o: Self) -> Self;
    fn abs(self) -> Self;
    /// The SSE `max`: `self > o ? self : o` (as glam's `Vec3A::max`).
    fn max(self, o: Self) -> Self;
    fn sqrt(self) -> Self;
    fn is_finite(self) -> Self;
    fn is_inf(self) -> Self;
    fn is_sign_negative(self) -> Self;
    /// Bit l: lane l's mask is set.
    fn bitmask(self) -> u32;
    /// The x, y and z planes of eight vectors (a transpose).
    fn from_rows(rows: &[Vec3; 8]) -> [Self; 3];
    /// Eight vectors from their x, y and z planes (the hidden lane, which no
    /// operation reads, zero for `Avx` and z for `wide`).
    fn to_rows(planes: [Self; 3]) -> [Vec3; 8];
}

impl Lanes for wide::f32x8 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        wide::f32x8::splat(x)
    }
    #[inline(always)]
    fn load(a: [f32; 8]) -> Self {
        wide::f32x8::new(a)
    }
    #[inline(always)]
    fn store(self) -> [f32; 8] {
        self.to_array()
    }
    #[inline(always)]
    fn select(self, t: Self, f: Self) -> Self {
        wide::f32x8::select(self, t, f)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self {
        self.simd_lt(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        self.simd_gt(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        self.simd_le(o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self {
        self.simd_eq(o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> Self {
        self.simd_ne(o)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        wide::f32x8::abs(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        wide::f32x8::fast_max(self, o)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        wide::f32x8::sqrt(self)
    }
    #[inline(always)]
    fn is_finite(self) -> Self {
        wide::f32x8::is_finite(self)
    }
    #[inline(always)]
    fn is_inf(self) -> Self {
        wide::f32x8::is_inf(self)
    }
    #[inline(always)]
    fn is_sign_negative(self) -> Self {
        wide::f32x8::is_sign_negative(self)
    }
    #[inline(always)]
    fn bitmask(self) -> u32 {
        self.to_bitmask()
    }
    #[inline(always)]
    fn from_rows(rows: &[Vec3; 8]) -> [Self; 3] {
        [0, 1, 2].map(|c| wide::f32x8::new(std::array::from_fn(|l| rows[l][c])))
    }
    #[inline(always)]
    fn to_rows(planes: [Self; 3]) -> [Vec3; 8] {
        let [x, y, z] = planes.map(|p| p.to_array());
        std::array::from_fn(|l| Vec3::new(x[l], y[l], z[l]))
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx::Avx;

#[cfg(target_arch = "x86_64")]
mod avx {
    //! The intrinsics are `unsafe` outside an AVX function; every method is
    //! `#[inline(always)]` and called only through `kernel::shade8_avx2`,
    //! which enables AVX2 and whose contract is a CPU that has it (the
    //! generic `kernel::shade8` is `unsafe` for that reason). SAFETY of each
    //! block below: that contract.
    use super::Lanes;
    use crate::math::Vec3;
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Sub};

    #[derive(Clone, Copy)]
    pub(in crate::render::lanes) struct Avx(__m256);

    macro_rules! binary {
        ($tr:ident, $f:ident, $op:ident) => {
            impl $tr for Avx {
                type Output = Avx;
                #[inline(always)]
                fn $f(self, o: Avx) -> Avx {
                    Avx(unsafe { $op(self.0, o.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_ps);
    binary!(Sub, sub, _mm256_sub_ps);
    binary!(Mul, mul, _mm256_mul_ps);
    binary!(Div, div, _mm256_div_ps);
    binary!(BitAnd, bitand, _mm256_and_ps);
    binary!(BitOr, bitor, _mm256_or_ps);

    impl Neg for Avx {
        type Output = Avx;
        /// The sign bit flipped, as scalar negation does (0 − x would lose −0).
        #[inline(always)]
        fn neg(self) -> Avx {
            Avx(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
        }
    }

    impl Avx {
        #[inline(always)]
        fn cmp<const P: i32>(self, o: Avx) -> Avx {
            Avx(unsafe { _mm256_cmp_ps::<P>(self.0, o.0) })
        }
    }

    impl Lanes for Avx {
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Avx(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn load(a: [f32; 8]) -> Self {
            Avx(unsafe { _mm256_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        fn store(self) -> [f32; 8] {
            let mut a = [0.0; 8];
            unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn select(self, t: Self, f: Self) -> Self {
            Avx(unsafe { _mm256_blendv_ps(f.0, t.0, self.0) })
        }
        #[inline(always)]
        fn lt(self, o: Self) -> Self {
            self.cmp::<_CMP_LT_OQ>(o)
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Self {
            self.cmp::<_CMP_GT_OQ>(o)
        }
        #[inline(always)]
        fn le(self, o: Self) -> Self {
            self.cmp::<_CMP_LE_OQ>(o)
        }
        #[inline(always)]
        fn eq(self, o: Self) -> Self {
            self.cmp::<_CMP_EQ_OQ>(o)
        }
        #[inline(always)]
        fn ne(self, o: Self) -> Self {
            self.cmp::<_CMP_NEQ_UQ>(o)
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Avx(unsafe { _mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX))) })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            Avx(unsafe { _mm256_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Avx(unsafe { _mm256_sqrt_ps(self.0) })
        }
        #[inline(always)]
        fn is_finite(self) -> Self {
            self.abs().lt(Self::splat(f32::INFINITY))
        }
        #[inline(always)]
        fn is_inf(self) -> Self {
            self.abs().eq(Self::splat(f32::INFINITY))
        }
        #[inline(always)]
        fn is_sign_negative(self) -> Self {
            Avx(unsafe {
                _mm256_castsi256_ps(_mm256_srai_epi32::<31>(_mm256_castps_si256(self.0)))
            })
        }
        #[inline(always)]
        fn bitmask(self) -> u32 {
            unsafe { _mm256_movemask_ps(self.0) as u32 }
        }
        /// Rows l and l + 4 side by side, then the 4×4 transposes of both
        /// halves at once.
        #[inline(always)]
        fn from_rows(rows: &[Vec3; 8]) -> [Self; 3] {
            let r = rows.map(__m128::from);
            unsafe {
                let pair =
                    |a: __m128, b: __m128| _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(a), b);
                let (a0, a1, a2, a3) = (
                    pair(r[0], r[4]),
                    pair(r[1], r[5]),
                    pair(r[2], r[6]),
                    pair(r[3], r[7]),
                );
                let t0 = _mm256_unpacklo_ps(a0, a1);
                let t1 = _mm256_unpackhi_ps(a0, a1);
                let t2 = _mm256_unpacklo_ps(a2, a3);
                let t3 = _mm256_unpackhi_ps(a2, a3);
                [
                    Avx(_mm256_shuffle_ps::<0x44>(t0, t2)),
                    Avx(_mm256_shuffle_ps::<0xee>(t0, t2)),
                    Avx(_mm256_shuffle_ps::<0x44>(t1, t3)),
                ]
            }
        }
        #[inline(always)]
        fn to_rows(planes: [Self; 3]) -> [Vec3; 8] {
            let [x, y, z] = planes.map(|p| p.0);
            unsafe {
                let zero = _mm256_setzero_ps();
                let t0 = _mm256_unpacklo_ps(x, y);
                let t1 = _mm256_unpackhi_ps(x, y);
                let t2 = _mm256_unpacklo_ps(z, zero);
                let t3 = _mm256_unpackhi_ps(z, zero);
                let r04 = _mm256_shuffle_ps::<0x44>(t0, t2);
                let r15 = _mm256_shuffle_ps::<0xee>(t0, t2);
                let r26 = _mm256_shuffle_ps::<0x44>(t1, t3);
                let r37 = _mm256_shuffle_ps::<0xee>(t1, t3);
                let lo = |v: __m256| Vec3::from(_mm256_castps256_ps128(v));
                let hi = |v: __m256| Vec3::from(_mm256_extractf128_ps::<1>(v));
                [
                    lo(r04),
                    lo(r15),
                    lo(r26),
                    lo(r37),
                    hi(r04),
                    hi(r15),
                    hi(r26),
                    hi(r37),
                ]
            }
        }
    }
}
