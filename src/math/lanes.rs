//! One lane arithmetic for code written once and run one value at a time or
//! several: `f32`, `wide::f32x4` (the 4-wide triangle test), `wide::f32x8`
//! and [`Avx`] (the 8-wide triangle test, the lane kernel). Every operation
//! is the IEEE one, never fused, so a lane of a generic formula computes the
//! bits the formula computes at `f32` (pbrt-v4's `wavefront/` calling
//! `PathIntegrator`'s BSDF code is the model).
//!
//! Comparisons return masks of the lane type itself, all bits set where they
//! hold (at `f32` too: `f32::from_bits(!0)`), which `select`, `and`, `or` and
//! `bitmask` read; ordered (false for NaN) but `ne`, unordered, as SSE's.

use super::Vec3;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// What a formula over lanes asks of its lane type.
pub trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    fn splat(x: f32) -> Self;
    /// Lanes of `t` where the mask `self` is set, of `f` elsewhere.
    fn select(self, t: Self, f: Self) -> Self;
    fn and(self, o: Self) -> Self;
    fn or(self, o: Self) -> Self;
    fn lt(self, o: Self) -> Self;
    fn gt(self, o: Self) -> Self;
    fn le(self, o: Self) -> Self;
    fn ge(self, o: Self) -> Self;
    fn eq(self, o: Self) -> Self;
    /// Unordered not-equal (true for NaN), as glam's `cmpne`.
    fn ne(self, o: Self) -> Self;
    fn abs(self) -> Self;
    /// The SSE `max`: `self > o ? self : o` (as glam's `Vec3A::max`; `o`
    /// where either is NaN).
    fn max(self, o: Self) -> Self;
    fn sqrt(self) -> Self;
    fn is_finite(self) -> Self;
    fn is_inf(self) -> Self;
    fn is_sign_negative(self) -> Self;
    /// Bit l: lane l's mask is set.
    fn bitmask(self) -> u32;
}

/// The mask of a condition at `f32`: all bits set, or none.
#[inline(always)]
fn mask(b: bool) -> f32 {
    f32::from_bits(if b { u32::MAX } else { 0 })
}

impl Lanes for f32 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    /// By the sign bit, as `blendv`: the compiler sees the comparison
    /// behind the mask and emits one select (as bit operations, a `li`
    /// render took 0.8 % more instructions).
    #[inline(always)]
    fn select(self, t: Self, f: Self) -> Self {
        if self.is_sign_negative() {
            t
        } else {
            f
        }
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        f32::from_bits(self.to_bits() & o.to_bits())
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        f32::from_bits(self.to_bits() | o.to_bits())
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self {
        mask(self < o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        mask(self > o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        mask(self <= o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self {
        mask(self >= o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self {
        mask(self == o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> Self {
        mask(self != o)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o {
            self
        } else {
            o
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn is_finite(self) -> Self {
        mask(f32::is_finite(self))
    }
    #[inline(always)]
    fn is_inf(self) -> Self {
        mask(f32::is_infinite(self))
    }
    #[inline(always)]
    fn is_sign_negative(self) -> Self {
        mask(f32::is_sign_negative(self))
    }
    #[inline(always)]
    fn bitmask(self) -> u32 {
        self.to_bits() >> 31
    }
}

/// `Lanes` for `wide`'s types from their own methods.
macro_rules! wide_lanes {
    ($($t:ty),*) => {$(
        impl Lanes for $t {
            #[inline(always)]
            fn splat(x: f32) -> Self {
                <$t>::splat(x)
            }
            #[inline(always)]
            fn select(self, t: Self, f: Self) -> Self {
                <$t>::select(self, t, f)
            }
            #[inline(always)]
            fn and(self, o: Self) -> Self {
                self & o
            }
            #[inline(always)]
            fn or(self, o: Self) -> Self {
                self | o
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
            fn ge(self, o: Self) -> Self {
                self.simd_ge(o)
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
                <$t>::abs(self)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                <$t>::fast_max(self, o)
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn is_finite(self) -> Self {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn is_inf(self) -> Self {
                <$t>::is_inf(self)
            }
            #[inline(always)]
            fn is_sign_negative(self) -> Self {
                <$t>::is_sign_negative(self)
            }
            #[inline(always)]
            fn bitmask(self) -> u32 {
                self.to_bitmask()
            }
        }
    )*};
}
wide_lanes!(wide::f32x4, wide::f32x8);

/// The eight-wide types' loads, stores and transposes (the lane kernel's
/// gathering and scattering).
pub trait Lanes8: Lanes {
    fn load(a: [f32; 8]) -> Self;
    fn store(self) -> [f32; 8];
    /// The x, y and z planes of eight vectors (a transpose).
    fn from_rows(rows: &[Vec3; 8]) -> [Self; 3];
    /// Eight vectors from their x, y and z planes (the hidden lane, which no
    /// operation reads, zero for `Avx` and z for `wide`).
    fn to_rows(planes: [Self; 3]) -> [Vec3; 8];
}

impl Lanes8 for wide::f32x8 {
    #[inline(always)]
    fn load(a: [f32; 8]) -> Self {
        wide::f32x8::new(a)
    }
    #[inline(always)]
    fn store(self) -> [f32; 8] {
        self.to_array()
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
pub use avx::Avx;

#[cfg(target_arch = "x86_64")]
mod avx {
    //! The intrinsics are `unsafe` outside an AVX function; every method is
    //! `#[inline(always)]` and called only from functions that enable AVX2
    //! and whose contract is a CPU that has it (the lane kernel's
    //! `shade8_avx2`, the 8-wide traversal and the ray streams). SAFETY of
    //! each block below: that contract.
    use super::{Lanes, Lanes8};
    use crate::math::Vec3;
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Neg, Sub};

    /// Eight f32 lanes in one AVX register.
    #[derive(Clone, Copy)]
    pub struct Avx(pub(crate) __m256);

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

        /// Lane `l` is the f32 at `base + offsets[l]` (offsets in f32s).
        ///
        /// # Safety
        /// AVX2; every lane's address inside one allocation, f32-aligned.
        #[inline(always)]
        pub(crate) unsafe fn gather(base: *const f32, offsets: __m256i) -> Self {
            Avx(_mm256_i32gather_ps::<4>(base, offsets))
        }
    }

    impl Lanes for Avx {
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Avx(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn select(self, t: Self, f: Self) -> Self {
            Avx(unsafe { _mm256_blendv_ps(f.0, t.0, self.0) })
        }
        #[inline(always)]
        fn and(self, o: Self) -> Self {
            Avx(unsafe { _mm256_and_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn or(self, o: Self) -> Self {
            Avx(unsafe { _mm256_or_ps(self.0, o.0) })
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
        fn ge(self, o: Self) -> Self {
            self.cmp::<_CMP_GE_OQ>(o)
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
            Avx(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
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
    }

    impl Lanes8 for Avx {
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

/// Three planes of lanes: as many vectors as `L` has lanes (one at `f32`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<L> {
    pub x: L,
    pub y: L,
    pub z: L,
}

// Methods rather than operators: `mul` and `div` take a lane, `mul_v` a
// vector, and a chain reads in the order the scalar code computes.
#[allow(clippy::should_implement_trait)]
impl<L: Lanes> V3<L> {
    #[inline(always)]
    pub fn splat(v: L) -> Self {
        Self { x: v, y: v, z: v }
    }
    /// glam's order: (x·x' + y·y') + z·z'.
    #[inline(always)]
    pub fn dot(self, o: Self) -> L {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// `f` on each component. (The methods below spell their components
    /// out: a closure in a generic function is a function of its own, which
    /// the compiler may leave out of line, and then its AVX operations too.)
    #[inline(always)]
    pub fn map(self, f: impl Fn(L) -> L) -> Self {
        Self {
            x: f(self.x),
            y: f(self.y),
            z: f(self.z),
        }
    }
    #[inline(always)]
    pub fn zip(self, o: Self, f: impl Fn(L, L) -> L) -> Self {
        Self {
            x: f(self.x, o.x),
            y: f(self.y, o.y),
            z: f(self.z, o.z),
        }
    }
    #[inline(always)]
    pub fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    #[inline(always)]
    pub fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    #[inline(always)]
    pub fn mul(self, s: L) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    pub fn mul_v(self, o: Self) -> Self {
        Self {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
    #[inline(always)]
    pub fn div(self, s: L) -> Self {
        Self {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
    #[inline(always)]
    pub fn neg(self) -> Self {
        Self {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }
    #[inline(always)]
    pub fn is_finite(self) -> L {
        self.x
            .is_finite()
            .and(self.y.is_finite())
            .and(self.z.is_finite())
    }
    /// Lanes of `t` where the mask `m` is set, of `f` elsewhere.
    #[inline(always)]
    pub fn select(m: L, t: Self, f: Self) -> Self {
        Self {
            x: m.select(t.x, f.x),
            y: m.select(t.y, f.y),
            z: m.select(t.z, f.z),
        }
    }
    /// glam's `normalize_or_zero`: times 1/|v| where that is finite and
    /// positive, else zero.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let zero = L::splat(0.0);
        let rcp = L::splat(1.0) / self.dot(self).sqrt();
        Self::select(
            rcp.is_finite().and(rcp.gt(zero)),
            self.mul(rcp),
            V3::splat(zero),
        )
    }
}

impl V3<f32> {
    #[inline(always)]
    pub fn from_vec3(v: Vec3) -> Self {
        Self {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
    #[inline(always)]
    pub fn to_vec3(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }
}

impl<L: Lanes8> V3<L> {
    #[inline(always)]
    pub fn load(rows: &[Vec3; 8]) -> Self {
        let [x, y, z] = L::from_rows(rows);
        Self { x, y, z }
    }
    #[inline(always)]
    pub fn store(self) -> [Vec3; 8] {
        L::to_rows([self.x, self.y, self.z])
    }
}

/// A 3-vector rule written once for both shapes of vectors: [`V3`] (a
/// vector per lane, its components in planes) and [`Vec3`] (one vector, its
/// components in the lanes of one SSE register, so that the scalar callers
/// keep their three-wide instructions).
pub trait Vector3: Copy {
    /// What a component is: `L` for `V3<L>`, the whole register for `Vec3`.
    type L: Lanes;
    /// The dot product (glam's order), wherever a component of
    /// [`zip`](Self::zip) reads it.
    fn dot(self, o: Self) -> Self::L;
    /// `f` on each component (callers mark `f` `#[inline(always)]`: see
    /// [`V3::map`]).
    fn map(self, f: impl Fn(Self::L) -> Self::L) -> Self;
    fn zip(self, o: Self, f: impl Fn(Self::L, Self::L) -> Self::L) -> Self;
    /// The components, each as a lane value (`Vec3`'s broadcast to the
    /// register, as glam's `v * s.x` does).
    fn components(self) -> [Self::L; 3];
    /// A vector from its components (`Vec3`'s from their first lanes).
    fn from_components(c: [Self::L; 3]) -> Self;
    /// `self + o` (named apart from `V3`'s inherent `add`).
    #[inline(always)]
    fn sum(self, o: Self) -> Self {
        self.zip(
            o,
            #[inline(always)]
            |a, b| a + b,
        )
    }
    /// `self - o`.
    #[inline(always)]
    fn diff(self, o: Self) -> Self {
        self.zip(
            o,
            #[inline(always)]
            |a, b| a - b,
        )
    }
    /// Each component times `s`.
    #[inline(always)]
    fn scale(self, s: Self::L) -> Self {
        self.map(
            #[inline(always)]
            |c| c * s,
        )
    }
    /// |component| each.
    #[inline(always)]
    fn abs_each(self) -> Self {
        self.map(
            #[inline(always)]
            |c| c.abs(),
        )
    }
}

impl<L: Lanes> Vector3 for V3<L> {
    type L = L;
    #[inline(always)]
    fn dot(self, o: Self) -> L {
        V3::dot(self, o)
    }
    #[inline(always)]
    fn map(self, f: impl Fn(L) -> L) -> Self {
        V3::map(self, f)
    }
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(L, L) -> L) -> Self {
        V3::zip(self, o, f)
    }
    #[inline(always)]
    fn components(self) -> [L; 3] {
        [self.x, self.y, self.z]
    }
    #[inline(always)]
    fn from_components([x, y, z]: [L; 3]) -> Self {
        Self { x, y, z }
    }
}

impl Vector3 for Vec3 {
    type L = wide::f32x4;
    /// glam's dot in every lane (`dot_into_vec`: its `dot`'s bits).
    #[inline(always)]
    fn dot(self, o: Self) -> wide::f32x4 {
        to_f32x4(self.dot_into_vec(o))
    }
    #[inline(always)]
    fn map(self, f: impl Fn(wide::f32x4) -> wide::f32x4) -> Self {
        from_f32x4(f(to_f32x4(self)))
    }
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(wide::f32x4, wide::f32x4) -> wide::f32x4) -> Self {
        from_f32x4(f(to_f32x4(self), to_f32x4(o)))
    }
    #[inline(always)]
    fn components(self) -> [wide::f32x4; 3] {
        // Spelt out: an array's `map` is a function of its own, left out of line.
        [
            wide::f32x4::splat(self.x),
            wide::f32x4::splat(self.y),
            wide::f32x4::splat(self.z),
        ]
    }
    #[inline(always)]
    fn from_components(c: [wide::f32x4; 3]) -> Self {
        Vec3::new(first(c[0]), first(c[1]), first(c[2]))
    }
}

/// Lane 0 of a register.
#[inline(always)]
fn first(v: wide::f32x4) -> f32 {
    from_f32x4(v).x
}

/// `v` in the local coordinates of the orthonormal frame (s, t, n): the one
/// formula of `Frame::to_local` and [`LaneFrame::to_local`].
#[inline(always)]
pub fn frame_to_local<V: Vector3>(s: V, t: V, n: V, v: V) -> V {
    V::from_components([v.dot(s), v.dot(t), v.dot(n)])
}

/// `v`'s local coordinates back in the world, `s·x + t·y + n·z` (glam's
/// order): `Frame::to_world` and [`LaneFrame::to_world`].
#[inline(always)]
pub fn frame_to_world<V: Vector3>(s: V, t: V, n: V, v: V) -> V {
    let [x, y, z] = v.components();
    #[inline(always)]
    fn add<L: Lanes>(a: L, b: L) -> L {
        a + b
    }
    s.map(
        #[inline(always)]
        |c| c * x,
    )
    .zip(
        t.map(
            #[inline(always)]
            |c| c * y,
        ),
        add::<V::L>,
    )
    .zip(
        n.map(
            #[inline(always)]
            |c| c * z,
        ),
        add::<V::L>,
    )
}

/// The register of a `Vec3` as `wide`'s (no instruction where both are SSE).
#[inline(always)]
fn to_f32x4(v: Vec3) -> wide::f32x4 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    {
        wide::f32x4::from(std::arch::x86_64::__m128::from(v))
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    {
        wide::f32x4::new([v.x, v.y, v.z, 0.0])
    }
}

#[inline(always)]
fn from_f32x4(v: wide::f32x4) -> Vec3 {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    {
        Vec3::from(std::arch::x86_64::__m128::from(v))
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    {
        let a = v.to_array();
        Vec3::new(a[0], a[1], a[2])
    }
}

/// `Frame` over lanes: the basis of Duff et al. 2017 ("Building an
/// Orthonormal Basis, Revisited"), the one formula for `Frame::from_normal`
/// and the lane kernel.
#[derive(Clone, Copy, Debug)]
pub struct LaneFrame<L> {
    pub s: V3<L>,
    pub t: V3<L>,
    pub n: V3<L>,
}

impl<L: Lanes> LaneFrame<L> {
    /// Branchless, without the singularity at −z.
    #[inline(always)]
    pub fn from_normal(n: V3<L>) -> Self {
        let one = L::splat(1.0);
        let sign = n.z.is_sign_negative().select(-one, one);
        let a = -one / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            s: V3 {
                x: one + sign * n.x * n.x * a,
                y: sign * b,
                z: -sign * n.x,
            },
            t: V3 {
                x: b,
                y: sign + n.y * n.y * a,
                z: -n.y,
            },
            n,
        }
    }
    #[inline(always)]
    pub fn to_local(&self, v: V3<L>) -> V3<L> {
        frame_to_local(self.s, self.t, self.n, v)
    }
    #[inline(always)]
    pub fn to_world(&self, v: V3<L>) -> V3<L> {
        frame_to_world(self.s, self.t, self.n, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The masks at `f32` select, combine and count as the wide types' do.
    #[test]
    fn f32_masks_work_as_the_wide_lanes() {
        let (a, b) = (1.5f32, f32::NAN);
        assert_eq!(a.lt(2.0).select(7.0, 9.0), 7.0);
        assert_eq!(a.gt(2.0).select(7.0, 9.0), 9.0);
        assert_eq!(b.ne(b).bitmask(), 1);
        assert_eq!(b.eq(b).bitmask(), 0);
        assert_eq!(a.lt(2.0).and(b.lt(2.0)).bitmask(), 0);
        assert_eq!(a.lt(2.0).or(b.lt(2.0)).bitmask(), 1);
        assert_eq!(Lanes::is_sign_negative(-0.0f32).select(-1.0, 1.0), -1.0);
        assert_eq!(Lanes::max(f32::NAN, 0.0), 0.0);
        assert!(Lanes::max(0.0, f32::NAN).is_nan());
        let w = wide::f32x4::new([1.5, f32::NAN, -0.0, 3.0]);
        let m = w.lt(wide::f32x4::splat(2.0));
        assert_eq!(m.bitmask(), 0b0101);
        for (l, x) in w.to_array().into_iter().enumerate() {
            assert_eq!(x.lt(2.0).bitmask(), (m.bitmask() >> l) & 1);
        }
    }
}
