//! A shadow field's sample grid: SH vectors on concentric spheres around an entity
//! (Zhou et al. 2005, Sec. 3.1; 12 × 20 angular samples as in the deformable paper),
//! with trilinear lookup (radius in log scale, θ, φ wrapping).

use crate::math::sh::{ShF, COEFFS};
use crate::math::Vec3;

/// Where the samples of a field lie, relative to the entity's centre and in its
/// own (rest-pose) orientation. θ is measured from the local +z axis; samples
/// include both poles (θ_i = iπ/(n_θ−1)), φ_j = 2πj/n_φ, radii geometric from
/// `r_min` to `r_max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub n_theta: usize,
    pub n_phi: usize,
    pub n_radii: usize,
    pub r_min: f32,
    pub r_max: f32,
}

impl Grid {
    pub fn len(&self) -> usize {
        self.n_theta * self.n_phi * self.n_radii
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of sample (radius, θ, φ).
    pub fn index(&self, r: usize, t: usize, p: usize) -> usize {
        (r * self.n_theta + t) * self.n_phi + p
    }

    pub fn radius(&self, r: usize) -> f32 {
        if self.n_radii == 1 {
            return self.r_min;
        }
        self.r_min * (self.r_max / self.r_min).powf(r as f32 / (self.n_radii - 1) as f32)
    }

    /// Unit direction of angular sample (θ index, φ index) in the local frame.
    pub fn direction(&self, t: usize, p: usize) -> Vec3 {
        let theta = std::f32::consts::PI * t as f32 / (self.n_theta - 1) as f32;
        let phi = std::f32::consts::TAU * p as f32 / self.n_phi as f32;
        let s = theta.sin();
        Vec3::new(s * phi.cos(), s * phi.sin(), theta.cos())
    }

    /// Local offset of sample i from the centre.
    pub fn position(&self, i: usize) -> Vec3 {
        let p = i % self.n_phi;
        let t = (i / self.n_phi) % self.n_theta;
        let r = i / (self.n_phi * self.n_theta);
        self.direction(t, p) * self.radius(r)
    }

    /// The eight samples around local offset `q` with their trilinear weights, and
    /// the far-field scale (r_max/d)² (1 inside r_max) the caller applies to
    /// occlusion and radiance beyond the outermost sphere (a distant entity
    /// shrinks to a small cone whose solid angle falls as 1/d²).
    pub fn corners(&self, q: Vec3) -> ([(u32, f32); 8], f32) {
        let d = q.length().max(1e-30);
        let far = if d > self.r_max {
            (self.r_max / d).powi(2)
        } else {
            1.0
        };
        let log_ratio = (self.r_max / self.r_min).ln();
        let sr = if self.n_radii > 1 {
            ((d / self.r_min).ln() / log_ratio * (self.n_radii - 1) as f32)
                .clamp(0.0, (self.n_radii - 1) as f32)
        } else {
            0.0
        };
        let cos_t = (q.z / d).clamp(-1.0, 1.0);
        let st = cos_t.acos() / std::f32::consts::PI * (self.n_theta - 1) as f32;
        let mut sp = q.y.atan2(q.x) / std::f32::consts::TAU;
        if sp < 0.0 {
            sp += 1.0;
        }
        let sp = (sp * self.n_phi as f32).clamp(0.0, self.n_phi as f32);
        let (r0, fr) = split(sr, self.n_radii);
        let (t0, ft) = split(st, self.n_theta);
        let p0 = (sp.floor() as usize).min(self.n_phi - 1);
        let fp = sp - p0 as f32;
        let p1 = (p0 + 1) % self.n_phi;
        let r1 = (r0 + 1).min(self.n_radii - 1);
        let t1 = (t0 + 1).min(self.n_theta - 1);
        let mut out = [(0u32, 0.0f32); 8];
        let mut k = 0;
        for (r, wr) in [(r0, 1.0 - fr), (r1, fr)] {
            for (t, wt) in [(t0, 1.0 - ft), (t1, ft)] {
                for (p, wp) in [(p0, 1.0 - fp), (p1, fp)] {
                    out[k] = (self.index(r, t, p) as u32, wr * wt * wp);
                    k += 1;
                }
            }
        }
        (out, far)
    }
}

/// Integer cell and fraction of a clamped continuous index in [0, n − 1].
fn split(s: f32, n: usize) -> (usize, f32) {
    let i = (s.floor() as usize).min(n.saturating_sub(2));
    (i, (s - i as f32).clamp(0.0, 1.0))
}

/// One SH vector per grid sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub grid: Grid,
    pub data: Vec<ShF>,
}

impl Field {
    /// Trilinear interpolation at local offset `q`, times the far-field scale.
    #[inline]
    pub fn lookup(&self, q: Vec3) -> ShF {
        self.lookup_at(&self.grid.corners(q))
    }

    /// The interpolation at corners from [`Grid::corners`] (shared by fields on
    /// the same grid).
    #[inline]
    pub fn lookup_at(&self, (corners, far): &([(u32, f32); 8], f32)) -> ShF {
        let (corners, far) = (*corners, *far);
        let mut c = [0.0f32; COEFFS];
        for (i, w) in corners {
            if w == 0.0 {
                continue;
            }
            let s = &self.data[i as usize];
            let w = w * far;
            for k in 0..COEFFS {
                c[k] += w * s[k];
            }
        }
        c
    }

    /// The field of the entity rotated by `rot` (SH rotation of every sample;
    /// positions stay in the rest frame and the caller rotates the query).
    pub fn rotated(&self, rot: &crate::math::sh::Rotation) -> Field {
        Field {
            grid: self.grid,
            data: self.data.iter().map(|c| rot.apply_f32(c)).collect(),
        }
    }
}

/// The frame a grid sample's (or a query's) cone of directions is laid out in:
/// z towards the entity's centre, x and y along θ and φ of its offset `dir` (unit)
/// at azimuth `phi`. Tied to the grid's coordinates, not to the direction alone,
/// so that the samples at a pole (one point, n_φ azimuths) are interpolated in φ
/// as everywhere else.
pub fn cone_frame(dir: Vec3, phi: f32) -> crate::math::Frame {
    cone_frame_at_azimuth(dir, phi.sin_cos())
}

/// [`cone_frame`] with the azimuth given by its sine and cosine.
fn cone_frame_at_azimuth(dir: Vec3, (sin_p, cos_p): (f32, f32)) -> crate::math::Frame {
    let sin_t = (dir.x * dir.x + dir.y * dir.y).sqrt();
    crate::math::Frame {
        s: Vec3::new(dir.z * cos_p, dir.z * sin_p, -sin_t),
        t: Vec3::new(-sin_p, cos_p, 0.0),
        n: -dir,
    }
}

/// cos of the half-angle of the cone a bounding sphere of `radius` subtends from
/// distance `d`; −1 (every direction) from inside it.
pub fn cone_cos(d: f32, radius: f32) -> f32 {
    if d > radius * 1.0001 {
        let sin = radius / d;
        (1.0 - sin * sin).max(0.0).sqrt()
    } else {
        -1.0
    }
}

/// The unblurred visibility of an entity: at every grid sample, one bit per ray
/// (`side²` of them, stratified in (s, φ′) with s = (1 − cos θ′)/(1 − cos α)
/// uniform over the cone of half-angle α the bounding sphere subtends, θ′ and φ′
/// in [`cone_frame`]). Order-4 SH blur a small light's shadow to half its depth
/// and spread it over tens of degrees, so sphere lights look the occluders up
/// here instead; in cone coordinates neighbouring samples see the entity at the
/// same place, so the lookup interpolates its shape, not two copies of it.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeMap {
    pub grid: Grid,
    pub side: usize,
    /// `words()` u64 per sample, bit a·side + b set where ray (s index a, φ′
    /// index b) hits the entity.
    pub bits: Vec<u64>,
}

impl ConeMap {
    /// u64 words per sample.
    pub fn words(side: usize) -> usize {
        (side * side).div_ceil(64)
    }

    /// The cone frame and grid corners at rest-frame offset `q` from the centre,
    /// the entity bounded by `radius`: what every direction's lookup there shares.
    pub fn at(&self, q: Vec3, radius: f32) -> ConeLookup {
        let d = q.length().max(1e-30);
        // The azimuth atan2(q.y, q.x) by its sine and cosine (0 on the axis).
        let r = (q.x * q.x + q.y * q.y).sqrt();
        let azimuth = if r > 0.0 {
            (q.y / r, q.x / r)
        } else {
            (0.0, 1.0)
        };
        ConeLookup {
            frame: cone_frame_at_azimuth(q / d, azimuth),
            cos_max: cone_cos(d, radius),
            corners: self.grid.corners(q).0,
        }
    }

    /// Visibility in rest-frame direction `w` (unit) from where `at` was taken:
    /// the eight grid samples' bits at w's cone coordinates, weighted trilinearly
    /// (1 outside the cone).
    pub fn visibility(&self, at: &ConeLookup, w: Vec3) -> f32 {
        let c = w.dot(at.frame.n);
        if c < at.cos_max {
            return 1.0;
        }
        let s = (1.0 - c) / (1.0 - at.cos_max);
        // The cell needs the angle to a small fraction of 1/side of a turn.
        let mut u =
            crate::math::atan2_approx(w.dot(at.frame.t), w.dot(at.frame.s)) / std::f32::consts::TAU;
        if u < 0.0 {
            u += 1.0;
        }
        let n = self.side;
        let a = ((s * n as f32) as usize).min(n - 1);
        let b = ((u * n as f32) as usize).min(n - 1);
        let bit = a * n + b;
        let words = Self::words(n);
        let mut hidden = 0.0;
        for (i, wt) in at.corners {
            if wt != 0.0 && self.bits[i as usize * words + bit / 64] >> (bit % 64) & 1 == 1 {
                hidden += wt;
            }
        }
        (1.0 - hidden).clamp(0.0, 1.0)
    }
}

/// [`ConeMap::at`]'s result.
#[derive(Clone, Copy, Debug)]
pub struct ConeLookup {
    frame: crate::math::Frame,
    cos_max: f32,
    corners: [(u32, f32); 8],
}
