//! The scalar type the materials and the environment are written over, so that one
//! implementation serves the path tracer (f64 inside the BRDFs, f32 for the
//! environment) and the gradient stage (forward-mode [`Dual`] numbers).
//!
//! Only the operations those formulas need are here. Constants are passed as f64
//! and rounded once to the type (an f32 constant survives the round trip exactly).
//! For f32 and f64 every method is the plain IEEE operation, so code generic over
//! `Scalar` performs, at those types, exactly the float operations it would if it
//! were written for them.

use super::dual::Dual;
use std::ops::{Add, Div, Mul, Neg, Sub};

pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Whether values carry derivatives (false for f32, f64): code that computes
    /// inputs only for the derivatives (the lat-long coordinates of an image
    /// environment) skips them when there are none.
    const HAS_DERIVATIVES: bool;
    /// A constant (zero derivatives).
    fn constant(c: f64) -> Self;
    /// The value, without derivatives.
    fn value(self) -> f64;
    /// `self · c` for a constant `c`.
    fn mul_const(self, c: f64) -> Self;
    /// `self + c` for a constant `c`.
    fn add_const(self, c: f64) -> Self;
    /// `max(self, c)` for a constant `c` (a floor); `c` when `self` is NaN.
    fn max_const(self, c: f64) -> Self;
    fn sqrt(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    fn ln_1p(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    /// A function of two arguments `a`, `b` known only by its `value` and partial
    /// derivatives `d_da`, `d_db` there (a texture lookup): chained into `a`'s and
    /// `b`'s derivatives.
    fn chain2(value: f64, a: Self, d_da: f64, b: Self, d_db: f64) -> Self;
}

macro_rules! impl_float_scalar {
    ($t:ty) => {
        impl Scalar for $t {
            const HAS_DERIVATIVES: bool = false;
            #[inline]
            fn constant(c: f64) -> Self {
                c as $t
            }
            #[inline]
            fn value(self) -> f64 {
                self as f64
            }
            #[inline]
            fn mul_const(self, c: f64) -> Self {
                self * c as $t
            }
            #[inline]
            fn add_const(self, c: f64) -> Self {
                self + c as $t
            }
            #[inline]
            fn max_const(self, c: f64) -> Self {
                self.max(c as $t)
            }
            #[inline]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline]
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            #[inline]
            fn ln(self) -> Self {
                <$t>::ln(self)
            }
            #[inline]
            fn ln_1p(self) -> Self {
                <$t>::ln_1p(self)
            }
            #[inline]
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
            }
            #[inline]
            fn chain2(value: f64, _: Self, _: f64, _: Self, _: f64) -> Self {
                value as $t
            }
        }
    };
}

impl_float_scalar!(f32);
impl_float_scalar!(f64);

impl<const N: usize> Scalar for Dual<N> {
    const HAS_DERIVATIVES: bool = true;
    #[inline]
    fn constant(c: f64) -> Self {
        Dual::constant(c as f32)
    }
    #[inline]
    fn value(self) -> f64 {
        self.v as f64
    }
    #[inline]
    fn mul_const(self, c: f64) -> Self {
        self.scale(c as f32)
    }
    #[inline]
    fn add_const(self, c: f64) -> Self {
        self + c as f32
    }
    #[inline]
    fn max_const(self, c: f64) -> Self {
        let c = c as f32;
        if self.v >= c {
            self
        } else {
            Dual::constant(c)
        }
    }
    #[inline]
    fn sqrt(self) -> Self {
        Dual::sqrt(self)
    }
    #[inline]
    fn exp(self) -> Self {
        Dual::exp(self)
    }
    #[inline]
    fn ln(self) -> Self {
        Dual::ln(self)
    }
    #[inline]
    fn ln_1p(self) -> Self {
        Dual::ln_1p(self)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        Dual::atan2(self, x)
    }
    #[inline]
    fn chain2(value: f64, a: Self, d_da: f64, b: Self, d_db: f64) -> Self {
        let (da, db) = (d_da as f32, d_db as f32);
        let mut r = Dual::constant(value as f32);
        for (l, d) in r.d.iter_mut().enumerate() {
            *d = da * a.d[l] + db * b.d[l];
        }
        r
    }
}

/// `a · b` for 3-vectors given as components (left to right, as glam's `dot`).
#[inline]
pub fn dot<T: Scalar>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a · c` for a constant vector `c` (left to right, as glam's `dot`).
#[inline]
pub fn dot_const<T: Scalar>(a: [T; 3], c: [f32; 3]) -> T {
    a[0].mul_const(c[0] as f64) + a[1].mul_const(c[1] as f64) + a[2].mul_const(c[2] as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ln, ln_1p and the floor are new to the duals: their lanes against central
    /// differences of the plain f64 functions.
    #[test]
    fn dual_rules_match_finite_differences() {
        let f = |x: Dual<1>| -> Dual<1> {
            let y = Scalar::ln(x.add_const(0.5)) + Scalar::ln_1p(-(x * x).mul_const(0.3));
            y.max_const(-10.0) * Scalar::exp(x)
        };
        let g = |x: f64| ((x + 0.5).ln() + (-(x * x) * 0.3).ln_1p()).max(-10.0) * x.exp();
        for &x in &[0.1f64, 0.4, 0.9] {
            let h = 1e-5;
            let fd = (g(x + h) - g(x - h)) / (2.0 * h);
            let d = f(Dual::new(x as f32, [1.0]));
            assert!((d.v as f64 - g(x)).abs() < 1e-6 * g(x).abs().max(1.0));
            assert!(
                (d.d[0] as f64 - fd).abs() < 1e-5 * fd.abs().max(1.0),
                "{x}: {} vs {fd}",
                d.d[0]
            );
        }
        // Below the floor the value is the constant, with no derivative.
        let low = Dual::new(-20.0f32, [1.0]).max_const(-10.0);
        assert_eq!((low.v, low.d[0]), (-10.0, 0.0));
    }

    /// chain2 adds the partials' contributions lane by lane; plain floats keep the value.
    #[test]
    fn chain2_chains_both_arguments() {
        let a = Dual::new(0.2f32, [1.0, 0.0]);
        let b = Dual::new(0.7f32, [0.5, 2.0]);
        let r = Dual::chain2(3.0, a, 4.0, b, -1.0);
        assert_eq!(r.v, 3.0);
        assert_eq!(r.d, [4.0 - 0.5, -2.0]);
        assert_eq!(<f32 as Scalar>::chain2(3.0, 0.2, 4.0, 0.7, -1.0), 3.0);
    }
}
