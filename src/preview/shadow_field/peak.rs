//! An environment's bright, compact part (a sun), split off before the SH
//! projection and shaded like a sphere light at infinity: order-4 SH spread a
//! sun's shadow over tens of degrees and light the ground behind a wall that
//! hides it (generated seed 3 under `envs/sky.hdr`: RMSE 11.6 % of the mean
//! with the sun in the SH, 3.3 % with the sun removed from the sky, 3.4 % with
//! it split off). The split is exact: in a cap around the brightest direction,
//! the excess of the luminance over T goes to the cap's directions, the rest
//! to the SH; they add up to the environment whatever T and the cap are, which
//! only decide where the per-direction work is spent.

use super::combine::{cap_directions, LIGHT_DIRS};
use crate::math::sh::{ShF, COEFFS};
use crate::math::{luminance, Frame, Vec3};
use crate::scene::Environment;

/// The share of the sphere's solid angle whose brightest directions set T:
/// 4 %, a cap of 23°, about half the 45° that bands l ≤ 3 resolve, so what
/// stays in the SH is no sharper than they hold.
const PEAK_SOLID_ANGLE_SHARE: f64 = 0.04;
/// The excess counted around the brightest direction: within 30°.
const PEAK_SEARCH_COS: f32 = 0.866;
/// The cap holds this share of that excess (the rest, its faint fringe, stays
/// in the SH): a sun narrower than the search gets a cap its own size.
const PEAK_CAP_SHARE: f64 = 0.95;
/// A peak with less of the environment's luminance than this is not worth its
/// directions at every receiver.
const PEAK_MIN_SHARE: f64 = 0.02;

/// The environment as the combination takes it: SH of all of it but the peak.
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    pub sh: [ShF; 3],
    pub peak: Option<Peak>,
}

/// The excess of the environment over luminance `threshold`, in a cap.
#[derive(Clone, Debug)]
pub struct Peak {
    pub threshold: f32,
    pub axis: Vec3,
    pub cos_max: f32,
    pub dirs: [Vec3; LIGHT_DIRS],
    /// Direction k's excess radiance times its share of the cap's solid angle,
    /// scaled so that the sum is the excess's integral.
    pub power: [Vec3; LIGHT_DIRS],
    /// Order-4 SH of the excess's luminance (for the receiver's own SH shadowing).
    pub sh: ShF,
}

impl Peak {
    /// The part of radiance `v` above luminance `threshold` (its colour kept).
    pub fn excess(threshold: f32, v: Vec3) -> Vec3 {
        let l = luminance(v);
        if l > threshold && threshold.is_finite() {
            v * (1.0 - threshold / l)
        } else {
            Vec3::ZERO
        }
    }

    /// What the peak takes of radiance `v` in direction `d`: the excess, in the cap.
    pub fn part(&self, d: Vec3, v: Vec3) -> Vec3 {
        if d.dot(self.axis) >= self.cos_max {
            Self::excess(self.threshold, v)
        } else {
            Vec3::ZERO
        }
    }
}

impl EnvironmentLight {
    /// No light from the environment.
    pub fn none() -> Self {
        Self {
            sh: [[0.0; COEFFS]; 3],
            peak: None,
        }
    }

    /// The environment split into its peak, if it has a compact one, and the SH
    /// of the rest (of all of it otherwise: [`super::environment_sh`]).
    pub fn new(env: Option<&Environment>) -> Self {
        let Some(env) = env else {
            return Self::none();
        };
        if matches!(env, Environment::Constant { .. }) {
            return Self {
                sh: super::environment_sh(Some(env)),
                peak: None,
            };
        }
        let (rule, values) = super::environment_samples(env);
        let whole = || Self {
            sh: super::project_rgb(&rule, &values),
            peak: None,
        };
        let lum: Vec<f32> = values.iter().map(|v| luminance(*v)).collect();
        // T: the luminance above which lie the brightest directions holding
        // PEAK_SOLID_ANGLE_SHARE of the sphere.
        let mut order: Vec<usize> = (0..rule.len()).collect();
        order.sort_by(|&a, &b| lum[b].total_cmp(&lum[a]));
        let target = PEAK_SOLID_ANGLE_SHARE * 4.0 * std::f64::consts::PI;
        let mut acc = 0.0;
        let mut threshold = f32::INFINITY;
        for &i in &order {
            acc += rule[i].1;
            if acc >= target {
                threshold = lum[i];
                break;
            }
        }
        // The excess within PEAK_SEARCH_COS of the brightest direction: its
        // centroid is the axis, and the cap the angle holding PEAK_CAP_SHARE of it.
        let brightest = rule[order[0]].0.as_vec3a();
        let excess_lum: Vec<f32> = values
            .iter()
            .map(|v| luminance(Peak::excess(threshold, *v)))
            .collect();
        let near: Vec<usize> = (0..rule.len())
            .filter(|&i| {
                excess_lum[i] > 0.0 && rule[i].0.as_vec3a().dot(brightest) >= PEAK_SEARCH_COS
            })
            .collect();
        let axis = near
            .iter()
            .map(|&i| rule[i].0.as_vec3a() * (rule[i].1 as f32 * excess_lum[i]))
            .sum::<Vec3>()
            .normalize_or_zero();
        let mut by_angle: Vec<(f32, f64)> = near
            .iter()
            .map(|&i| {
                (
                    rule[i].0.as_vec3a().dot(axis),
                    rule[i].1 * f64::from(excess_lum[i]),
                )
            })
            .collect();
        by_angle.sort_by(|a, b| b.0.total_cmp(&a.0));
        let in_search: f64 = by_angle.iter().map(|x| x.1).sum();
        let mut acc = 0.0;
        let mut cos_cap = 1.0f32;
        for (c, e) in &by_angle {
            acc += e;
            cos_cap = *c;
            if acc >= PEAK_CAP_SHARE * in_search {
                break;
            }
        }
        // One quadrature step wider: the cap's edge falls between its samples.
        let step = std::f32::consts::PI / 96.0;
        let cos_max = (cos_cap.clamp(-1.0, 1.0).acos() + step).cos();
        let mut peak = Peak {
            threshold,
            axis,
            cos_max,
            dirs: [Vec3::ZERO; LIGHT_DIRS],
            power: [Vec3::ZERO; LIGHT_DIRS],
            sh: [0.0; COEFFS],
        };
        let part: Vec<Vec3> = rule
            .iter()
            .zip(&values)
            .map(|((d, _), v)| peak.part(d.as_vec3a(), *v))
            .collect();
        let total: f64 = rule
            .iter()
            .zip(&lum)
            .map(|((_, w), l)| w * f64::from(*l))
            .sum();
        let taken: f64 = rule
            .iter()
            .zip(&part)
            .map(|((_, w), p)| w * f64::from(luminance(*p)))
            .sum();
        if axis == Vec3::ZERO || taken.is_nan() || taken <= PEAK_MIN_SHARE * total {
            return whole();
        }
        let residual: Vec<Vec3> = values.iter().zip(&part).map(|(v, p)| *v - *p).collect();
        let sh = super::project_rgb(&rule, &residual);
        // Luminance is linear: its projection is the channels' combined.
        let [r, g, b] = super::project_rgb(&rule, &part);
        peak.sh = std::array::from_fn(|k| luminance(Vec3::new(r[k], g[k], b[k])));
        // The cap's directions, each with its excess; scaled to the excess's
        // integral by the quadrature (a sun narrower than the directions' spacing
        // is then a uniform disc of the cap, not lost).
        peak.dirs = cap_directions(&Frame::from_normal(axis), cos_max);
        let solid = std::f32::consts::TAU * (1.0 - cos_max) / LIGHT_DIRS as f32;
        let mut power = peak.dirs.map(|d| peak.part(d, env.eval(d)) * solid);
        let want: Vec3 = rule
            .iter()
            .zip(&part)
            .map(|((_, w), p)| *p * *w as f32)
            .sum();
        let got: Vec3 = power.iter().copied().sum();
        for c in 0..3 {
            for p in power.iter_mut() {
                p[c] = if got[c] > 0.0 {
                    p[c] * want[c] / got[c]
                } else {
                    want[c] / LIGHT_DIRS as f32
                };
            }
        }
        peak.power = power;
        Self {
            sh,
            peak: Some(peak),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sky(sharpness: f32) -> Environment {
        Environment::GaussianSky {
            direction: Vec3::new(0.3, 0.8, -0.5).normalize(),
            sharpness,
            peak: Vec3::new(40.0, 30.0, 20.0),
            ambient: Vec3::new(0.2, 0.3, 0.5),
        }
    }

    /// The split loses nothing: the SH of the rest plus what the cap's
    /// directions carry is the whole environment's integral (band 0, per
    /// channel), and the cap sits on the sun.
    #[test]
    fn the_split_keeps_every_channels_integral() {
        let env = sky(300.0);
        let whole = super::super::environment_sh(Some(&env));
        let light = EnvironmentLight::new(Some(&env));
        let pk = light.peak.as_ref().expect("a 6° sun is split off");
        assert!(pk.axis.dot(Vec3::new(0.3, 0.8, -0.5).normalize()) > 0.999);
        assert!(pk.cos_max > 0.95 && pk.cos_max < 0.9995, "{}", pk.cos_max);
        let y00 = 0.282_094_8f32;
        for c in 0..3 {
            let carried: f32 = pk.power.iter().map(|p| p[c]).sum();
            let got = light.sh[c][0] + y00 * carried;
            assert!(
                (got - whole[c][0]).abs() < 1e-4 * whole[c][0],
                "{c}: {got} vs {}",
                whole[c][0]
            );
        }
    }

    /// Nothing to split from a constant or a broad sky: the SH hold them.
    #[test]
    fn smooth_skies_stay_in_the_sh() {
        assert!(EnvironmentLight::new(Some(&sky(0.5))).peak.is_none());
        let c = Environment::Constant {
            radiance: Vec3::splat(1.0),
        };
        assert!(EnvironmentLight::new(Some(&c)).peak.is_none());
    }
}
