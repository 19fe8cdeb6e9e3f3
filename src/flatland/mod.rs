//! 2D scene → exact shading, analytic/semianalytic/numerical visibility gradients.
//!
//! The paper's flatland verification (Sec. 6.3, Fig. 9 and 10): a flat diffuse
//! receiver (the x axis), a rectangle and a circle as blockers above it, and a
//! distant environment whose radiance varies as a Gaussian in angle, brightest
//! overhead. The cosine is folded into the lighting, so the transport operator of
//! Eq. (32) is just `T(θ) = L(θ) cos θ` and the shading is
//! `B(x) = ∫ T(θ) V(x, θ) dθ` over `θ ∈ (−π/2, π/2)`.
//!
//! In 2D the visibility is a union of blocked angular intervals, so `B` is computed
//! exactly (interval merging + Gauss–Legendre on each visible interval), and its
//! spatial gradient reduces to boundary terms at the visibility discontinuities
//! (Eq. 37): the lighting is distant, so `L_x = 0` and nothing else remains.
//!
//! Sign convention. Here `θ` is measured from the normal towards +x. A fixed blocker
//! point at distance `D` then moves to smaller angles as `x` grows:
//! `dα/dx = −cos α / D`, which is the `α_u = −cos α / D` of Appendix D (the paper's
//! Eq. 36 writes `+cos α / D` for the mirrored orientation of Fig. 7). With
//! `sgn_j = +1` for a visible→blocked transition in increasing `θ` (Fig. 8),
//! Eq. (37) therefore reads in this module
//! `B_x = −Σ_j sgn_j T(α_j) cos α_j / D_j`.
//!
//! One entry point for the figures: [`write_figures`]. The scene type [`Scene`]
//! carries every quantity the tests compare.

mod figures;
pub mod geometry;
pub mod sampling;

pub use figures::{write_figures, FigureSummary};
pub use geometry::{Blocker, Circle, Endpoint, Feature, Interval, Rect2};

use crate::math::quadrature::GaussLegendre;
use crate::{Error, Result};
use std::f64::consts::{FRAC_PI_2, PI};

/// Largest panel (radians) of the composite Gauss–Legendre rule for the smooth
/// lighting term over one visible interval: `L(θ) cos θ` is entire, so 16 points on
/// panels of 0.1 rad integrate it to f64 rounding, which is what lets finite
/// differences of the "exact" shading of Sec. 6.3 be compared with a tight tolerance.
pub(crate) const PANEL: f64 = 0.1;

/// Distant lighting with the receiver cosine folded in:
/// `T(θ) = (ambient + peak · exp(−θ² / (2 σ²))) · cos θ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    pub ambient: f64,
    pub peak: f64,
    /// Angular width σ of the Gaussian lobe, radians.
    pub sigma: f64,
}

impl Lighting {
    /// The transport term `T(θ)` of Eq. (32) for a diffuse receiver under this lighting.
    pub fn transport(&self, theta: f64) -> f64 {
        (self.ambient + self.peak * (-0.5 * theta * theta / (self.sigma * self.sigma)).exp())
            * theta.cos()
    }
}

/// How the semianalytic method places a discontinuity `α_j` found between two
/// consecutive angular samples `θ_k` (visible state differs from `θ_{k+1}`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Locate {
    /// The paper's choice (Sec. 6.3): `α_j = θ_k`, the sample before the change.
    Sample,
    /// Halfway between the two samples: halves the worst-case error at no cost.
    Midpoint,
    /// Bisection on the ray-cast visibility until the bracket is below 1e-12 rad;
    /// `D_j` then comes from a ray that grazes the defining blocker point.
    Bisection,
    /// As `Bisection`, and also bisect between neighbouring samples blocked by
    /// *different* blockers (the ray tracer's object id changes) to find a visible
    /// gap narrower than the sample spacing (two discontinuities `Bisection` misses
    /// near the angles where two shadows start to merge). Blockers are convex, so
    /// two samples blocked by the same blocker never hide a gap.
    BisectionGaps,
}

/// A visibility discontinuity found in image space: angle, distance to the
/// blocker along the blocked-side ray, and `sgn_j` (+1 visible→blocked in
/// increasing θ, −1 blocked→visible).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Discontinuity {
    pub angle: f64,
    pub distance: f64,
    pub sign: f64,
}

/// The flatland scene: blockers above the receiver line `y = 0` and the lighting.
#[derive(Clone, Debug)]
pub struct Scene {
    blockers: Vec<Blocker>,
    lighting: Lighting,
    rule: GaussLegendre,
}

impl Scene {
    /// Builds a scene after checking every blocker lies strictly above the receiver
    /// and the lighting is finite with `σ > 0`.
    pub fn new(blockers: Vec<Blocker>, lighting: Lighting) -> Result<Self> {
        for (i, b) in blockers.iter().enumerate() {
            b.validate(i)?;
        }
        let ok = lighting.ambient.is_finite()
            && lighting.peak.is_finite()
            && lighting.sigma.is_finite()
            && lighting.sigma > 0.0
            && lighting.ambient >= 0.0
            && lighting.peak >= 0.0;
        if !ok {
            return Err(Error::Option {
                option: "flatland lighting".into(),
                message: format!(
                    "need finite ambient >= 0, peak >= 0 and sigma > 0, got {lighting:?}"
                ),
            });
        }
        Ok(Self {
            blockers,
            lighting,
            rule: GaussLegendre::new(16),
        })
    }

    /// The scene used for the figures. The paper gives no numbers for Fig. 9, so
    /// these are chosen to match its schematic: a box to the left, a circle higher up
    /// to the right, their shadows overlapping in the middle of the receiver
    /// (so that interval merging matters), lighting a Gaussian lobe of σ = 0.6 rad
    /// overhead on a dim constant sky.
    pub fn paper_fig9() -> Self {
        let blockers = vec![
            Blocker::Rect(Rect2 {
                min: [-1.5, 1.0],
                max: [-0.5, 1.5],
            }),
            Blocker::Circle(Circle {
                center: [0.9, 1.8],
                radius: 0.45,
            }),
        ];
        let lighting = Lighting {
            ambient: 0.1,
            peak: 1.0,
            sigma: 0.6,
        };
        // The constants above satisfy every check in `new`.
        Self {
            blockers,
            lighting,
            rule: GaussLegendre::new(16),
        }
    }

    /// Receiver range shown in the figures.
    pub const FIG_RANGE: (f64, f64) = (-3.0, 3.0);

    pub fn blockers(&self) -> &[Blocker] {
        &self.blockers
    }

    pub fn lighting(&self) -> Lighting {
        self.lighting
    }

    /// The merged blocked intervals seen from `(x, 0)` (object space), sorted by angle.
    pub fn blocked_intervals(&self, x: f64) -> Vec<Interval> {
        let per_blocker = self
            .blockers
            .iter()
            .enumerate()
            .map(|(i, b)| b.interval(x, i))
            .collect();
        geometry::merge(per_blocker)
    }

    /// The owners of the discontinuities at `x`, in angular order: equal signatures at
    /// two points mean `B` is smooth between them (no corner switch, no merge event).
    pub fn signature(&self, x: f64) -> Vec<Feature> {
        self.blocked_intervals(x)
            .iter()
            .flat_map(|iv| [iv.lo.feature, iv.hi.feature])
            .collect()
    }

    /// Exact shading `B(x) = ∫ T(θ) V(x, θ) dθ`: the lighting integrated over the
    /// complement of the blocked intervals (Eq. 32 with the visibility made explicit).
    pub fn shading(&self, x: f64) -> f64 {
        self.shading_rotated(x, 0.0)
    }

    /// Shading with the transport rotated by `φ` against the fixed blockers,
    /// `B(x, φ) = ∫ T(θ − φ) V(x, θ) dθ`, the convolution of Eq. (32) read at outgoing
    /// angle `φ`; its `φ`-derivative at 0 is the angular gradient of Eq. (35).
    pub fn shading_rotated(&self, x: f64, phi: f64) -> f64 {
        let mut start = -FRAC_PI_2;
        let mut sum = 0.0;
        let t = |th: f64| self.lighting.transport(th - phi);
        for iv in self.blocked_intervals(x) {
            sum += self
                .rule
                .integrate(start, iv.lo.angle.min(FRAC_PI_2), PANEL, t);
            start = start.max(iv.hi.angle);
        }
        sum + self.rule.integrate(start, FRAC_PI_2, PANEL, t)
    }

    /// Analytic spatial gradient `dB/dx`, Eq. (37) with object-space discontinuities:
    /// each merged interval contributes its start (`sgn = +1`) and end (`sgn = −1`).
    pub fn grad_analytic(&self, x: f64) -> f64 {
        self.blocked_intervals(x)
            .iter()
            .map(|iv| {
                self.boundary_term(iv.lo.angle, iv.lo.distance, 1.0)
                    + self.boundary_term(iv.hi.angle, iv.hi.distance, -1.0)
            })
            .sum()
    }

    /// Analytic angular gradient `∂B(x, φ)/∂φ` at `φ = 0`, Eq. (35):
    /// `B_θ = −Σ_j sgn_j T(α_j)`. (The hemisphere limits add nothing: `T(±π/2) = 0`.)
    /// For the diffuse receiver of Fig. 9 the seen shading does not depend on the view
    /// angle; this is the derivative under a rotation of the lighting (cosine
    /// included) relative to the blockers, the quantity Eq. (35) describes.
    pub fn grad_angular_analytic(&self, x: f64) -> f64 {
        self.blocked_intervals(x)
            .iter()
            .map(|iv| -self.lighting.transport(iv.lo.angle) + self.lighting.transport(iv.hi.angle))
            .sum()
    }

    /// Eq. (35) at image-space discontinuities (no distance needed, only `α_j`).
    pub fn grad_angular_semianalytic(&self, x: f64, n: usize, locate: Locate) -> Result<f64> {
        Ok(self
            .discontinuities_sampled(x, n, locate)?
            .iter()
            .map(|d| -d.sign * self.lighting.transport(d.angle))
            .sum())
    }

    /// One term of Eq. (37) in this module's convention: `−sgn T(α) cos α / D`.
    fn boundary_term(&self, alpha: f64, distance: f64, sign: f64) -> f64 {
        -sign * self.lighting.transport(alpha) * alpha.cos() / distance
    }

    /// Nearest blocker hit along the ray from `(x, 0)` at angle `θ`, if any.
    pub fn cast(&self, x: f64, theta: f64) -> Option<f64> {
        self.cast_id(x, theta).map(|h| h.0)
    }

    /// Nearest hit distance and the index of the blocker hit.
    fn cast_id(&self, x: f64, theta: f64) -> Option<(f64, usize)> {
        self.blockers
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.hit(x, theta).map(|t| (t, i)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// The `n` uniform angular samples `θ_k = −π/2 + (k + ½) π / n`.
    fn sample_angle(n: usize, k: usize) -> f64 {
        -FRAC_PI_2 + (k as f64 + 0.5) * PI / n as f64
    }

    fn check_samples(n: usize) -> Result<()> {
        if n < 2 {
            return Err(Error::Option {
                option: "flatland angular samples".into(),
                message: format!("need at least 2 angular samples, got {n}"),
            });
        }
        Ok(())
    }

    /// Image-space discontinuities (Sec. 6.3 / 8.1): ray-cast `n` uniform angles,
    /// report every pair of neighbours whose visibility differs, placed by `locate`.
    /// `D_j` is the hit distance of the blocked-side ray. A blocked interval narrower
    /// than the sample spacing can fall between samples and is then missed: that is
    /// the method's inherent resolution limit.
    pub fn discontinuities_sampled(
        &self,
        x: f64,
        n: usize,
        locate: Locate,
    ) -> Result<Vec<Discontinuity>> {
        Self::check_samples(n)?;
        let mut out = Vec::new();
        let mut prev = self.cast_id(x, Self::sample_angle(n, 0));
        for k in 1..n {
            let (a, b) = (Self::sample_angle(n, k - 1), Self::sample_angle(n, k));
            let cur = self.cast_id(x, b);
            let changed = prev.is_some() != cur.is_some();
            match locate {
                Locate::Sample | Locate::Midpoint if changed => {
                    // Visible → blocked in increasing θ has sgn +1 (Fig. 8).
                    let sign = if cur.is_some() { 1.0 } else { -1.0 };
                    let angle = if locate == Locate::Sample {
                        a
                    } else {
                        0.5 * (a + b)
                    };
                    out.push(Discontinuity {
                        angle,
                        distance: prev.or(cur).map_or(f64::INFINITY, |h| h.0),
                        sign,
                    });
                }
                Locate::Bisection if changed => {
                    self.refine(x, (a, prev), (b, cur), false, &mut out)
                }
                Locate::BisectionGaps => self.refine(x, (a, prev), (b, cur), true, &mut out),
                _ => {}
            }
            prev = cur;
        }
        Ok(out)
    }

    /// Recursive bisection of the bracket `[a, b]` with the ray-cast states at its
    /// ends. Halves whose ends agree (same blocker, or both visible) are dropped;
    /// with `split_ids` false, halves whose ends are both blocked are dropped too.
    /// Below 1e-12 rad a remaining visibility change is emitted, with `D_j` the hit
    /// distance at the blocked end, i.e. along a ray grazing the defining point.
    fn refine(
        &self,
        x: f64,
        (a, sa): (f64, Option<(f64, usize)>),
        (b, sb): (f64, Option<(f64, usize)>),
        split_ids: bool,
        out: &mut Vec<Discontinuity>,
    ) {
        let same = |p: Option<(f64, usize)>, q: Option<(f64, usize)>| match (p, q) {
            (None, None) => true,
            (Some(p), Some(q)) => !split_ids || p.1 == q.1,
            _ => false,
        };
        if same(sa, sb) {
            return;
        }
        if b - a < 1e-12 {
            if sa.is_some() != sb.is_some() {
                out.push(Discontinuity {
                    angle: 0.5 * (a + b),
                    distance: sa.or(sb).map_or(f64::INFINITY, |h| h.0),
                    sign: if sb.is_some() { 1.0 } else { -1.0 },
                });
            }
            return;
        }
        let m = 0.5 * (a + b);
        let sm = self.cast_id(x, m);
        self.refine(x, (a, sa), (m, sm), split_ids, out);
        self.refine(x, (m, sm), (b, sb), split_ids, out);
    }

    /// Semianalytic gradient: Eq. (37) evaluated at the image-space discontinuities.
    pub fn grad_semianalytic(&self, x: f64, n: usize, locate: Locate) -> Result<f64> {
        Ok(self
            .discontinuities_sampled(x, n, locate)?
            .iter()
            .map(|d| self.boundary_term(d.angle, d.distance, d.sign))
            .sum())
    }

    /// Shading as a renderer would estimate it: midpoint rule over `n` uniform angular
    /// samples of ray-cast visibility. Piecewise constant in `x` (the stair steps that
    /// make numerical differentiation noisy in Fig. 9c).
    pub fn shading_sampled(&self, x: f64, n: usize) -> Result<f64> {
        Self::check_samples(n)?;
        let w = PI / n as f64;
        Ok((0..n)
            .map(|k| Self::sample_angle(n, k))
            .filter(|&th| self.cast(x, th).is_none())
            .map(|th| self.lighting.transport(th) * w)
            .sum())
    }

    /// Central finite difference of the exact shading with step `h`.
    pub fn grad_numerical(&self, x: f64, h: f64) -> Result<f64> {
        Self::check_step(h)?;
        Ok((self.shading(x + h) - self.shading(x - h)) / (2.0 * h))
    }

    /// Central finite difference of the `n`-sample shading with step `h`: the purely
    /// numerical gradient the paper compares against in Fig. 9c.
    pub fn grad_numerical_sampled(&self, x: f64, h: f64, n: usize) -> Result<f64> {
        Self::check_step(h)?;
        Ok((self.shading_sampled(x + h, n)? - self.shading_sampled(x - h, n)?) / (2.0 * h))
    }

    fn check_step(h: f64) -> Result<()> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::Option {
                option: "flatland finite-difference step".into(),
                message: format!("need a finite step > 0, got {h}"),
            });
        }
        Ok(())
    }
}

/// Normalised RMS difference `sqrt(Σ (a − b)²) / sqrt(Σ b²)` of `a` against the
/// reference `b`. Point-wise relative errors blow up where the gradient crosses
/// zero, so the error is relative to the RMS of the reference instead.
pub fn rms_relative(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        num.sqrt()
    }
}
