//! Forward-mode dual numbers with `N` derivative lanes, and 3-vectors of them.
//!
//! The gradient stage differentiates the shading integrand at fixed light samples
//! (the first-order paper's "replace convolutions with the explicit shading
//! calculation", Sec. 9.1). Writing the integrand once over duals gives exact
//! derivatives of every term; seeding different lanes with the derivatives of
//! position, normal and view direction separates the paper's SV, CDV and DV terms
//! (Eq. 25) in one evaluation.

use super::Vec3;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A value and its derivatives along `N` independent directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const N: usize> {
    pub v: f32,
    pub d: [f32; N],
}

impl<const N: usize> Dual<N> {
    pub const fn constant(v: f32) -> Self {
        Self { v, d: [0.0; N] }
    }

    pub fn new(v: f32, d: [f32; N]) -> Self {
        Self { v, d }
    }

    /// Applies a scalar function with value `f` and derivative `df` at `self.v`.
    #[inline]
    fn chain(self, f: f32, df: f32) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= df;
        }
        Self { v: f, d }
    }

    pub fn sqrt(self) -> Self {
        let s = self.v.max(0.0).sqrt();
        self.chain(s, if s > 0.0 { 0.5 / s } else { 0.0 })
    }

    pub fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }

    pub fn ln(self) -> Self {
        self.chain(self.v.ln(), 1.0 / self.v)
    }

    /// ln(1 + x), accurate for small x.
    pub fn ln_1p(self) -> Self {
        self.chain(self.v.ln_1p(), 1.0 / (1.0 + self.v))
    }

    /// x^p for x ≥ 0 (negative inputs clamp to zero, as cosine lobes do).
    pub fn powf(self, p: f32) -> Self {
        if self.v <= 0.0 {
            return Self::constant(0.0);
        }
        let f = self.v.powf(p);
        self.chain(f, p * f / self.v)
    }

    pub fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r)
    }

    /// max(self, 0) with the derivative of the branch taken.
    pub fn max0(self) -> Self {
        if self.v > 0.0 {
            self
        } else {
            Self::constant(0.0)
        }
    }

    pub fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy − y dx) / (x² + y²)
        let r2 = self.v * self.v + x.v * x.v;
        let mut d = [0.0; N];
        if r2 > 0.0 {
            for (i, di) in d.iter_mut().enumerate() {
                *di = (x.v * self.d[i] - self.v * x.d[i]) / r2;
            }
        }
        Self {
            v: self.v.atan2(x.v),
            d,
        }
    }

    pub fn scale(self, s: f32) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= s;
        }
        Self { v: self.v * s, d }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        let mut d = self.d;
        for (a, b) in d.iter_mut().zip(o.d) {
            *a += b;
        }
        Self { v: self.v + o.v, d }
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        let mut d = self.d;
        for (a, b) in d.iter_mut().zip(o.d) {
            *a -= b;
        }
        Self { v: self.v - o.v, d }
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; N];
        for (i, x) in d.iter_mut().enumerate() {
            *x = self.d[i] * o.v + self.v * o.d[i];
        }
        Self { v: self.v * o.v, d }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        // (a/b)' = a'/b − a b'/b²
        let inv = 1.0 / o.v;
        let q = self.v * inv;
        let mut d = [0.0; N];
        for (i, x) in d.iter_mut().enumerate() {
            *x = (self.d[i] - q * o.d[i]) * inv;
        }
        Self { v: q, d }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Add<f32> for Dual<N> {
    type Output = Self;
    fn add(self, o: f32) -> Self {
        Self {
            v: self.v + o,
            d: self.d,
        }
    }
}

impl<const N: usize> Mul<f32> for Dual<N> {
    type Output = Self;
    fn mul(self, o: f32) -> Self {
        self.scale(o)
    }
}

/// A 3-vector of duals: a point or direction together with its derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DVec3<const N: usize> {
    pub x: Dual<N>,
    pub y: Dual<N>,
    pub z: Dual<N>,
}

impl<const N: usize> DVec3<N> {
    pub fn constant(v: Vec3) -> Self {
        Self {
            x: Dual::constant(v.x),
            y: Dual::constant(v.y),
            z: Dual::constant(v.z),
        }
    }

    /// A vector with value `v` whose derivative along lane `i` is `lanes[i]`.
    pub fn with_lanes(v: Vec3, lanes: [Vec3; N]) -> Self {
        let mut r = Self::constant(v);
        for (i, l) in lanes.iter().enumerate() {
            r.x.d[i] = l.x;
            r.y.d[i] = l.y;
            r.z.d[i] = l.z;
        }
        r
    }

    pub fn value(&self) -> Vec3 {
        Vec3::new(self.x.v, self.y.v, self.z.v)
    }

    /// The derivative along lane `i`.
    pub fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(self.x.d[i], self.y.d[i], self.z.d[i])
    }

    pub fn dot(self, o: Self) -> Dual<N> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    pub fn dot_const(self, o: Vec3) -> Dual<N> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    pub fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    pub fn length_squared(self) -> Dual<N> {
        self.dot(self)
    }

    pub fn length(self) -> Dual<N> {
        self.length_squared().sqrt()
    }

    pub fn normalize(self) -> Self {
        let inv = self.length().recip();
        self * inv
    }

    pub fn scale(self, s: f32) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl<const N: usize> Add for DVec3<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<const N: usize> Sub for DVec3<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<const N: usize> Neg for DVec3<N> {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Mul<Dual<N>> for DVec3<N> {
    type Output = Self;
    fn mul(self, s: Dual<N>) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        // g(t) = |normalize(p(t)) × c|^1.7 · exp(0.3 atan2(t, 1 + t²)) / sqrt(t² + 2)
        // exercises every rule once.
        let c = Vec3::new(-0.2, 0.9, 0.3);
        let g = |t: f32| -> Dual<1> {
            let x = Dual::new(t, [1.0]);
            let p = DVec3 {
                x: x * 0.5 + 0.3,
                y: x * 0.1 - Dual::constant(0.2),
                z: Dual::constant(1.0) - x * 0.4,
            };
            let n = p.normalize();
            let cr = n.cross(DVec3::constant(c));
            cr.length().powf(1.7) * (x.atan2(x * x + 1.0).scale(0.3)).exp() / (x * x + 2.0).sqrt()
        };
        for &t in &[-0.7f32, 0.1, 0.9] {
            let h = 1e-3;
            let fd = (g(t + h).v - g(t - h).v) / (2.0 * h);
            let an = g(t).d[0];
            assert!(
                (fd - an).abs() < 1e-3 * an.abs().max(1.0),
                "t {t}: {fd} vs {an}"
            );
        }
    }
}
