//! Shared numerics: rays, orthonormal frames, sample warps, the low-discrepancy
//! sampler and piecewise-constant distributions. Everything here is pure and `Copy`
//! where possible so that it can be used from any thread without state.

pub mod distribution;
pub mod dual;
pub mod lanes;
pub mod quadrature;
pub mod sampler;
pub mod scalar;
pub mod sh;
pub mod spawn;
pub mod vmf;
pub mod warp;

pub use glam::Vec2;
/// The crate's 3-vector (points, directions, RGB): glam's 16-byte SIMD-aligned
/// `Vec3A`, so that each vector operation is one SSE instruction instead of three
/// scalar ones (−8 % instructions on a cornell render, benches/README.md). Lane
/// for lane the same IEEE operations as the scalar `glam::Vec3`, except
/// `normalize` (v / |v|, one rounding, where the scalar type multiplies by
/// 1 / |v|) and min/max with NaN operands (never relied on: NaN is tested for).
pub type Vec3 = glam::Vec3A;

/// The cross product `a × b` as plain products and differences, one rounding
/// each. glam's own `Vec3A::cross` fuses a multiply into the subtraction (an
/// FMA) when the build targets a CPU with FMA (`-C target-cpu=native`), which
/// changes the bits of every normal and frame built from it; this one rounds
/// alike in every build, so a native build renders the portable build's image
/// bit for bit (`clippy.toml` keeps glam's out of the crate).
#[inline(always)]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    use glam::Vec3Swizzles;
    a.yzx() * b.zxy() - a.zxy() * b.yzx()
}

/// A ray `o + t d`, valid for `t` in `[t_min, t_max]`. `d` need not be normalised
/// for intersection, but every producer in this crate normalises it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_min: f32,
    pub t_max: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    pub fn segment(origin: Vec3, dir: Vec3, t_max: f32) -> Self {
        Self {
            origin,
            dir,
            t_min: 0.0,
            t_max,
        }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// An orthonormal basis; `n` is the local +z axis. BRDFs work in this local frame,
/// where `cos θ = v.z`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// Builds a frame around a unit normal (Duff et al. 2017, "Building an
    /// Orthonormal Basis, Revisited": branchless and without the singularity at -z).
    /// [`lanes::LaneFrame::from_normal`] at `f32`, the lane kernel's formula.
    pub fn from_normal(n: Vec3) -> Self {
        let f = lanes::LaneFrame::<f32>::from_normal(lanes::V3::from_vec3(n));
        Self {
            s: f.s.to_vec3(),
            t: f.t.to_vec3(),
            n,
        }
    }

    /// [`lanes::frame_to_local`] on one vector (the lane kernel's formula).
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        lanes::frame_to_local(self.s, self.t, self.n, v)
    }

    /// [`lanes::frame_to_world`] on one vector.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        lanes::frame_to_world(self.s, self.t, self.n, v)
    }
}

/// atan2(y, x) within 1.2e-5 rad (a degree-11 odd minimax polynomial for atan
/// on [0, 1], folded to the four quadrants), about 3× cheaper than libm's: for
/// lookups that bin the angle (a cone map's azimuth), where that error moves no
/// direction but the few within it of a bin edge. 0 at the origin.
#[inline]
pub fn atan2_approx(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if hi.is_nan() || hi <= 0.0 {
        return 0.0;
    }
    let a = lo / hi;
    let s = a * a;
    let mut r = a
        * (0.999_977_3
            + s * (-0.332_623_5
                + s * (0.193_543_5 + s * (-0.116_432_87 + s * (0.052_653_32 - s * 0.011_721_2)))));
    if ay > ax {
        r = std::f32::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = std::f32::consts::PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// Rec.709 luminance of a linear RGB value.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Reflects `v` about `n` (both pointing away from the surface).
pub fn reflect(v: Vec3, n: Vec3) -> Vec3 {
    2.0 * v.dot(n) * n - v
}

/// Replaces NaN/Inf components by zero: the last guard before a value is accumulated,
/// so that one bad sample can never poison an output layer.
pub fn finite_or_zero(c: Vec3) -> Vec3 {
    Vec3::new(
        if c.x.is_finite() { c.x } else { 0.0 },
        if c.y.is_finite() { c.y } else { 0.0 },
        if c.z.is_finite() { c.z } else { 0.0 },
    )
}

/// The regular icosahedron on the unit sphere: 12 vertices and 20 counter-clockwise
/// faces (seen from outside), the level 0 of every icosphere.
pub fn icosahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let vertices = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let faces = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (vertices, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_approx_is_within_its_bound_everywhere() {
        let mut worst = 0.0f64;
        for i in 0..20_000 {
            let phi = -std::f64::consts::PI + (i as f64 + 0.37) * std::f64::consts::TAU / 20_000.0;
            let r = 1e-3 + (i % 7) as f64;
            let (y, x) = ((r * phi.sin()) as f32, (r * phi.cos()) as f32);
            let want = f64::from(y).atan2(f64::from(x));
            worst = worst.max((f64::from(atan2_approx(y, x)) - want).abs());
        }
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (1.0, 1.0),
            (-1.0, -1.0),
        ] {
            let want = f64::from(y).atan2(f64::from(x));
            worst = worst.max((f64::from(atan2_approx(y, x)) - want).abs());
        }
        assert!(worst < 1.2e-5, "{worst:e}");
        assert_eq!(atan2_approx(0.0, 0.0), 0.0);
    }

    #[test]
    fn frame_is_orthonormal_for_all_octants() {
        for &n in &[
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, -0.866).normalize(),
            Vec3::new(-1e-7, 1e-7, -1.0).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5);
            assert!((cross(f.s, f.t) - n).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.1, 0.7, -0.2);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
