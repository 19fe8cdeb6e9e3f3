//! The environment prefiltered with vMF kernels (Sec. 6.2): level ℓ holds
//! E_κ(d) = ∫ γ_{d,κ}(s) L(s) ds for κ = KAPPA0 · 2^ℓ (κ doubles per level, as
//! the paper's mipmap), each on a lat-long grid just fine enough for its kernel;
//! past the last level the raw environment. A lobe of any κ is looked up between
//! the two levels around it, linearly in log κ.

use crate::math::Vec3;
use crate::scene::environment::{bilinear, latlong_to_direction, Environment};
use glam::DVec3;
use rayon::prelude::*;

pub const KAPPA0: f32 = 0.25;
/// Levels κ = 0.25 … 4096.
pub const LEVELS: usize = 15;
/// Resolution of the grid an analytic environment is tabulated on.
const ANALYTIC_WIDTH: usize = 512;

/// A lat-long grid in the scene's convention (columns centred at (i + ½)/W,
/// rows at v = j/(H − 1)).
#[derive(Clone, Debug)]
pub struct Grid {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
}

impl Grid {
    fn direction(&self, i: usize, j: usize) -> Vec3 {
        let u = (i as f32 + 0.5) / self.width as f32;
        let v = j as f32 / (self.height - 1) as f32;
        latlong_to_direction(crate::math::Vec2::new(u, v))
    }

    /// Solid angle of texel row j (its band of θ, clamped at the poles).
    fn row_solid_angle(&self, j: usize) -> f64 {
        let dt = std::f64::consts::PI / (self.height - 1) as f64;
        let t = j as f64 * dt;
        let (lo, hi) = (
            (t - 0.5 * dt).max(0.0),
            (t + 0.5 * dt).min(std::f64::consts::PI),
        );
        2.0 * std::f64::consts::PI / self.width as f64 * (lo.cos() - hi.cos())
    }

    pub fn lookup(&self, d: Vec3) -> Vec3 {
        self.lookup_uv(crate::scene::environment::direction_to_latlong(d))
    }

    fn lookup_uv(&self, uv: crate::math::Vec2) -> Vec3 {
        bilinear(&self.texels, self.width, self.height, uv)
    }

    /// [`bilinear`]'s value for (u, v) in [0, 1), the same arithmetic without its
    /// derivatives and integer divisions: a frame makes ~4 of these per lobe.
    #[inline]
    fn lookup_uv_fast(&self, uv: crate::math::Vec2) -> Vec3 {
        let (w, h) = (self.width, self.height);
        let x = uv.x * w as f32 - 0.5;
        let y = (uv.y * (h - 1) as f32).clamp(0.0, (h - 1) as f32);
        let x0 = x.floor();
        let y0 = y.floor().min((h - 2) as f32);
        let (fx, fy) = (x - x0, y - y0);
        // x ∈ [−½, w − ½): only x0 = −1 wraps.
        let xi0 = if x0 < 0.0 {
            w - 1
        } else {
            (x0 as usize).min(w - 1)
        };
        let xi1 = if xi0 + 1 == w { 0 } else { xi0 + 1 };
        let r0 = y0 as usize * w;
        let r1 = r0 + w;
        let t = &self.texels;
        (t[r0 + xi0] * (1.0 - fx) + t[r0 + xi1] * fx) * (1.0 - fy)
            + (t[r1 + xi0] * (1.0 - fx) + t[r1 + xi1] * fx) * fy
    }
}

pub struct PrefilteredEnv {
    pub levels: Vec<Grid>,
    pub raw: Grid,
    /// The environment convolved with the clamped cosine, ∫ L(s) max(0, n·s)/π ds:
    /// what an open diffuse receiver gets, which no vMF holds (the one with Td's
    /// mean cosine 2/3 leaks 4 % of its mass below the horizon and peaks at the
    /// normal; under the sky image it reads 0.86 of this, issue 57's dark floor).
    pub cosine: Grid,
    /// Whether `raw` is the environment's own image (then [`Self::background`]
    /// reads it instead of evaluating the environment).
    raw_is_image: bool,
}

impl PrefilteredEnv {
    pub fn new(env: &Environment) -> Self {
        let raw = match env {
            Environment::Image {
                width,
                height,
                texels,
                scale,
            } => {
                let scaled: Vec<Vec3> = texels.iter().map(|t| *t * *scale).collect();
                // A one-row image is constant in v: the grid needs both poles' rows.
                let rows = (*height).max(2);
                Grid {
                    width: *width,
                    height: rows,
                    texels: scaled.iter().cycle().take(width * rows).copied().collect(),
                }
            }
            other => tabulate(other),
        };
        let levels = (0..LEVELS)
            .map(|l| prefilter(&raw, KAPPA0 * 2f32.powi(l as i32)))
            .collect();
        let raw_is_image = matches!(env, Environment::Image { .. });
        let cosine = prefilter_cosine(&raw);
        Self {
            levels,
            raw,
            cosine,
            raw_is_image,
        }
    }

    /// The radiance seen straight along `d` (pixels that miss the scene): the
    /// image's bilinear lookup without the path tracer's derivative bookkeeping,
    /// the exact environment where `raw` is only a tabulation of it.
    pub fn background(&self, env: &Environment, d: Vec3) -> Vec3 {
        if self.raw_is_image {
            self.raw.lookup_uv_fast(latlong_fast(d))
        } else {
            env.eval(d)
        }
    }

    /// ∫ γ_{μ,κ}(s) L(s) ds, interpolated between levels in log₂ κ.
    pub fn lookup(&self, mu: Vec3, kappa: f32) -> Vec3 {
        let x = (kappa.max(KAPPA0) / KAPPA0).log2();
        let l = x.floor() as usize;
        let t = x - l as f32;
        // Every level shares the lat-long parameterisation: map the direction once.
        let uv = latlong_fast(mu);
        if l >= LEVELS {
            return self.raw.lookup_uv_fast(uv);
        }
        let next = self.levels.get(l + 1).unwrap_or(&self.raw);
        self.levels[l].lookup_uv_fast(uv) * (1.0 - t) + next.lookup_uv_fast(uv) * t
    }

    /// ∫ L(s) max(0, n·s)/π ds (`n` a unit normal): an open Lambert receiver's
    /// radiance over its albedo.
    pub fn lookup_cosine(&self, n: Vec3) -> Vec3 {
        self.cosine.lookup_uv_fast(latlong_fast(n))
    }

    pub fn bytes(&self) -> usize {
        self.levels
            .iter()
            .chain([&self.raw, &self.cosine])
            .map(|g| g.texels.len() * 12)
            .sum()
    }
}

/// atan2 through Abramowitz & Stegun 4.4.47 (Hastings' minimax polynomial on
/// [0, 1]; with its published 7-digit coefficients |error| ≤ 1.2e-5 rad) and the
/// octant identities: libm's atan2f was a tenth of a frame (two per lobe, eight
/// lobes per pixel). 1.2e-5 rad is 1/250 of a texel of a 2048-wide environment,
/// so no lookup moves visibly.
fn atan2_fast(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    // Signed zeros as libm: atan2(±0, −0) = ±π.
    let a = if hi == 0.0 { 0.0 } else { lo / hi };
    let a2 = a * a;
    let mut r = a
        * (0.999_866
            + a2 * (-0.330_299_5 + a2 * (0.180_141 + a2 * (-0.085_133 + a2 * 0.020_835_1))));
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x.is_sign_negative() {
        r = PI - r;
    }
    if y.is_sign_negative() {
        -r
    } else {
        r
    }
}

/// [`crate::scene::environment::direction_to_latlong`] with [`atan2_fast`].
fn latlong_fast(d: Vec3) -> crate::math::Vec2 {
    use std::f32::consts::{PI, TAU};
    let mut u = atan2_fast(d.x, -d.z) / TAU;
    if u < 0.0 {
        u += 1.0;
    }
    let v = atan2_fast((d.x * d.x + d.z * d.z).sqrt(), d.y) / PI;
    crate::math::Vec2::new(u.min(1.0 - f32::EPSILON), v.min(1.0 - f32::EPSILON))
}

fn tabulate(env: &Environment) -> Grid {
    let mut g = Grid {
        width: ANALYTIC_WIDTH,
        height: ANALYTIC_WIDTH / 2,
        texels: Vec::new(),
    };
    g.texels = (0..g.height)
        .flat_map(|j| (0..g.width).map(move |i| (i, j)))
        .map(|(i, j)| env.eval(g.direction(i, j)))
        .collect();
    g
}

/// Convolves `src` with a vMF kernel of concentration κ onto a grid of about
/// 16√κ × 8√κ texels (≥ 2.5 texels per kernel standard deviation, so bilinear
/// lookups stay within ~1 % of a smooth peak), summing only
/// the source texels where the kernel exceeds e^{−16} of its peak; the quadrature
/// is normalised by the kernel's own sum so that a constant is reproduced exactly.
fn prefilter(src: &Grid, kappa: f32) -> Grid {
    let width = ((16.0 * kappa.sqrt()).ceil() as usize).clamp(src.width.min(64), src.width);
    let height = (width / 2).max(2);
    let kappa = kappa as f64;
    let cos_cut = (1.0 - 16.0 / kappa).max(-1.0);
    let src_dirs: Vec<DVec3> = (0..src.height)
        .flat_map(|j| (0..src.width).map(move |i| (i, j)))
        .map(|(i, j)| src.direction(i, j).as_dvec3())
        .collect();
    let row_w: Vec<f64> = (0..src.height).map(|j| src.row_solid_angle(j)).collect();
    let row_cos: Vec<f64> = (0..src.height)
        .map(|j| (std::f64::consts::PI * j as f64 / (src.height - 1) as f64).cos())
        .collect();
    let dst = Grid {
        width,
        height,
        texels: Vec::new(),
    };
    let texels = (0..height * width)
        .into_par_iter()
        .map(|k| {
            let d = dst.direction(k % width, k / width).as_dvec3();
            let theta_d = d.y.clamp(-1.0, 1.0).acos();
            let mut sum = DVec3::ZERO;
            let mut wsum = 0.0;
            for j in 0..src.height {
                // Rows farther in θ than the cut cannot hold a texel inside it.
                let theta_s = row_cos[j].clamp(-1.0, 1.0).acos();
                if (theta_s - theta_d).cos() < cos_cut {
                    continue;
                }
                for i in 0..src.width {
                    let s = src_dirs[j * src.width + i];
                    let c = d.dot(s);
                    if c < cos_cut {
                        continue;
                    }
                    let w = (kappa * (c - 1.0)).exp() * row_w[j];
                    sum += src.texels[j * src.width + i].as_dvec3() * w;
                    wsum += w;
                }
            }
            if wsum > 0.0 {
                (sum / wsum).as_vec3a()
            } else {
                src.lookup(d.as_vec3a())
            }
        })
        .collect();
    Grid { texels, ..dst }
}

/// Convolves `src` with the clamped cosine max(0, n·s)/π onto a 64 × 32 grid (the
/// result is smooth, nearly a quadratic in n: bilinear lookups stay well within
/// 1 %), the quadrature normalised by the kernel's own sum as [`prefilter`]'s.
fn prefilter_cosine(src: &Grid) -> Grid {
    let dst = Grid {
        width: 64,
        height: 32,
        texels: Vec::new(),
    };
    let src_dirs: Vec<DVec3> = (0..src.height)
        .flat_map(|j| (0..src.width).map(move |i| (i, j)))
        .map(|(i, j)| src.direction(i, j).as_dvec3())
        .collect();
    let row_w: Vec<f64> = (0..src.height).map(|j| src.row_solid_angle(j)).collect();
    let texels = (0..dst.height * dst.width)
        .into_par_iter()
        .map(|k| {
            let n = dst.direction(k % dst.width, k / dst.width).as_dvec3();
            let mut sum = DVec3::ZERO;
            let mut wsum = 0.0;
            for (j, &rw) in row_w.iter().enumerate() {
                for i in 0..src.width {
                    let c = n.dot(src_dirs[j * src.width + i]);
                    if c > 0.0 {
                        sum += src.texels[j * src.width + i].as_dvec3() * (c * rw);
                        wsum += c * rw;
                    }
                }
            }
            if wsum > 0.0 {
                (sum / wsum).as_vec3a()
            } else {
                src.lookup(n.as_vec3a())
            }
        })
        .collect();
    Grid { texels, ..dst }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_latlong_is_within_its_stated_error_of_the_scenes_mapping() {
        let n = 50_000;
        let mut worst = 0f32;
        for k in 0..n {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let phi = k as f32 * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let d = Vec3::new(r * phi.cos(), z, r * phi.sin());
            for d in [
                d,
                Vec3::Y,
                -Vec3::Y,
                Vec3::X,
                -Vec3::Z,
                Vec3::new(-1.0, 0.0, -0.0),
            ] {
                let (a, b) = (
                    latlong_fast(d),
                    crate::scene::environment::direction_to_latlong(d),
                );
                let du = (a.x - b.x).abs();
                // u wraps at 0 ≡ 1.
                worst = worst.max(du.min(1.0 - du)).max((a.y - b.y).abs());
            }
        }
        // 1.2e-5 rad over 2π (u) or π (v), plus f32 rounding.
        assert!(
            worst < 1.2e-5 / std::f32::consts::PI + 3e-7,
            "worst {worst}"
        );
        assert!(worst > 1e-8, "the polynomial is not exact");
    }

    #[test]
    fn tiny_images_prefilter_without_overrunning() {
        for (width, height) in [(1, 1), (3, 1), (8, 4)] {
            let env = Environment::Image {
                width,
                height,
                texels: vec![Vec3::new(0.5, 1.0, 2.0); width * height],
                scale: 2.0,
            };
            let p = PrefilteredEnv::new(&env);
            // A constant environment stays constant through every level.
            for kappa in [0.3, 10.0, 5000.0] {
                let v = p.lookup(Vec3::new(0.6, 0.0, 0.8), kappa);
                assert!(
                    (v - Vec3::new(1.0, 2.0, 4.0)).abs().max_element() < 1e-3,
                    "{v}"
                );
            }
            assert_eq!(p.background(&env, Vec3::Y), Vec3::new(1.0, 2.0, 4.0));
        }
    }

    #[test]
    fn fast_lookup_is_the_shared_bilinear() {
        let (width, height) = (7, 5);
        let texels = (0..width * height)
            .map(|k| Vec3::new(k as f32, (k * k % 11) as f32, 1.0 / (k + 1) as f32))
            .collect();
        let g = Grid {
            width,
            height,
            texels,
        };
        for k in 0..2000 {
            let u = ((k as f32 * 0.618_034).fract()).min(1.0 - f32::EPSILON);
            let v = ((k as f32 * 0.414_213_5).fract()).min(1.0 - f32::EPSILON);
            let uv = crate::math::Vec2::new(u, v);
            assert_eq!(g.lookup_uv_fast(uv), g.lookup_uv(uv), "at {uv}");
        }
        for uv in [[0.0, 0.0], [1.0 - f32::EPSILON, 1.0 - f32::EPSILON]] {
            let uv = crate::math::Vec2::from(uv);
            assert_eq!(g.lookup_uv_fast(uv), g.lookup_uv(uv), "at {uv}");
        }
    }
}
