//! estimator + budget → adaptively placed image samples (quadtree of Sec. 9.1).
//!
//! This stage decides *where* the image is evaluated; it never renders anything itself.
//! Whatever produces per-point estimates (the path tracer, or an analytic image in the
//! tests and benches) implements [`Estimator`]; [`refine`] spends a fixed sample budget
//! on a quadtree whose squares are refined in order of `metric × area`, and hands back a
//! [`SampleSet`] that `reconstruct` turns into pixels.
//!
//! Coordinates are continuous pixel coordinates: the image covers `[0, W] × [0, H]`, the
//! origin is the top-left corner, `u` grows to the right, `v` grows downwards and pixel
//! `(i, j)` has its centre at `(i + 0.5, j + 0.5)`. Gradients are per pixel in the same axes.

mod quadtree;

use crate::math::Vec2;
use crate::math::Vec3;
use crate::{Error, Result};

pub use quadtree::{refine, refine_with_progress, refine_with_stats, RefineStats};

/// Object id for "no object" (background / environment). Only equality matters.
pub const NO_OBJECT: u32 = u32::MAX;

/// What one evaluation of the image at a point returns.
///
/// `radiance`, the image gradient and the geometric ids are required; the optional
/// scalars feed the strategies that need renderer-side knowledge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleValue {
    /// Linear RGB radiance at the point.
    pub radiance: Vec3,
    /// ∂I/∂u, per pixel (u to the right), per channel — Eq. 26–28 in the renderer.
    pub grad_u: Vec3,
    /// ∂I/∂v, per pixel (v downwards), per channel.
    pub grad_v: Vec3,
    /// Id of the visible object ([`NO_OBJECT`] for the background). Squares whose
    /// neighbouring samples see different ids are always refined to pixel size, and the
    /// reconstruction never interpolates across different ids.
    pub object_id: u32,
    /// Depth along the camera's view axis (planar depth, positive: its inverse is
    /// affine in the image across a plane); `INFINITY` for the background. A
    /// depth step between neighbouring samples (read off their tangent planes,
    /// [`inv_depth_grad`](Self::inv_depth_grad); see [`surfaces_differ`]) counts as an
    /// object boundary (folds, self-occlusion silhouettes), for refinement and for
    /// reconstruction alike.
    pub depth: f32,
    /// ∇(1/depth) per pixel: the visible surface's tangent plane, in the form that is
    /// affine in image position under perspective. Lets the boundary test tell a
    /// surface seen at a slant (large but predicted depth change) from a fold or a
    /// self-occlusion silhouette whose depth step is small. Zero when unknown (or
    /// not finite), which predicts a constant depth.
    pub inv_depth_grad: Vec2,
    /// The geometric normal where the visible surface is flat-shaded (a cube's face,
    /// a mesh without vertex normals, bump-mapped or not), `None` where its shading
    /// normal is interpolated (smooth meshes, spheres). Two samples on facets with
    /// different normals lie across a crease, which such a surface shows as a jump
    /// in shading (a box's top and front) but no depth step or gradient reveals.
    pub facet_normal: Option<Vec3>,
    /// The shading normal at the visible point faces away from the camera, so the
    /// path ends there and the radiance drops to the emitted light: the black dots
    /// along a bump map's terminator. A change of side between neighbouring samples
    /// is a discontinuity like an object boundary (refined to pixel size, never
    /// interpolated across).
    pub back_facing: bool,
    /// Optional non-negative weight multiplied into every strategy's metric (e.g. to
    /// down-weight a region the caller cares less about). `None` means 1.
    pub importance: Option<f32>,
    /// Durand et al. 2005 frequency metric `(1/γ) 2kz/(n₀·v) Ω_ρ` (Sec. 9.1). The
    /// renderer fills it; required by [`Strategy::Durand`].
    pub durand: Option<f32>,
    /// Magnitude of the visibility (soft-shadow) image gradient, Eq. 45–49. The renderer
    /// fills it; required by [`Strategy::GradientVis`].
    pub vis_gradient: Option<f32>,
    /// Variance of the gradient estimate (summed over the six components of the 3×2
    /// Jacobian), when the estimator is Monte Carlo. The gradient strategies subtract
    /// it from |∇I|², so noise alone does not draw samples.
    pub gradient_variance: Option<f32>,
    /// Variance of the radiance estimate (summed over R, G, B), when the estimator is
    /// Monte Carlo. Radiance differences between samples (the `variance` strategy's
    /// metric, the jump that orders boundary cells) subtract it, so a firefly — one
    /// path carrying a sample's whole estimate — does not draw samples.
    pub radiance_variance: Option<f32>,
}

impl SampleValue {
    /// A sample of a smooth image on one object at unit depth, no optional data.
    pub fn new(radiance: Vec3, grad_u: Vec3, grad_v: Vec3) -> Self {
        Self {
            radiance,
            grad_u,
            grad_v,
            object_id: 0,
            depth: 1.0,
            inv_depth_grad: Vec2::ZERO,
            facet_normal: None,
            back_facing: false,
            importance: None,
            durand: None,
            vis_gradient: None,
            gradient_variance: None,
            radiance_variance: None,
        }
    }

    /// The object id and the side of the terminator ([`back_facing`](Self::back_facing))
    /// in one id: samples with different ids are never interpolated together.
    pub fn surface_id(&self) -> u64 {
        (u64::from(self.object_id) << 1) | u64::from(self.back_facing)
    }

    /// What the boundary test needs of this sample taken at `pos`.
    pub fn surface_point(&self, pos: Vec2) -> SurfacePoint {
        SurfacePoint {
            pos,
            surface: self.surface_id(),
            inv_depth: inverse_depth(self.depth),
            // A non-finite plane predicts nothing: zero predicts a constant depth.
            inv_depth_grad: if self.inv_depth_grad.is_finite() {
                self.inv_depth_grad
            } else {
                Vec2::ZERO
            },
            facet_normal: self.facet_normal,
        }
    }

    /// Frobenius norm of the 3×2 image Jacobian: |∇I| over all colour channels, so that
    /// an iso-luminant colour edge still counts.
    pub fn gradient_norm(&self) -> f32 {
        (self.grad_u.length_squared() + self.grad_v.length_squared()).sqrt()
    }

    /// |I_a − I_b| less the noise of the two estimates: max(|Î_a − Î_b| − σ, 0) with
    /// σ² = Var_a + Var_b (soft thresholding at one standard deviation). A one-path
    /// firefly of N (deviation X/N, variance ≈ X²/N² per channel) moves |Î_a − Î_b|
    /// by about σ and so contributes only the true difference, while a contrast well
    /// above the noise keeps its size. (√max(|Δ̂|² − σ², 0), unbiased for |Δ|², would
    /// keep the cross term 2Δ·f under its root: √(2|Δ|X/N) ≫ |Δ|.)
    pub fn contrast_denoised(&self, other: &SampleValue) -> f32 {
        let var = |v: &SampleValue| v.radiance_variance.unwrap_or(0.0).max(0.0);
        soft_threshold(
            (self.radiance - other.radiance).length(),
            var(self) + var(other),
        )
    }

    /// [`Self::gradient_norm`] less the estimator's noise: max(|Ĵ| − σ, 0) with σ² the
    /// variance of Ĵ, the same soft threshold as [`Self::contrast_denoised`] and for
    /// the same reason: √max(|Ĵ|² − σ², 0), though unbiased for |J|², keeps a
    /// firefly's cross term 2J·f under its root and lets one outlier path draw samples.
    pub fn gradient_norm_denoised(&self) -> f32 {
        soft_threshold(
            self.gradient_norm(),
            self.gradient_variance.unwrap_or(0.0).max(0.0),
        )
    }
}

/// `x` less one standard deviation of its noise, never below zero.
fn soft_threshold(x: f32, variance: f32) -> f32 {
    (x - variance.sqrt()).max(0.0)
}

/// Something that can evaluate the image at a continuous pixel position.
///
/// The renderer implements it (one converged estimate per call); the tests and benches
/// implement it with analytic images so that sampling and reconstruction can be checked
/// against exact answers. Must be deterministic: the same `p` gives the same value.
pub trait Estimator: Sync {
    fn estimate(&self, p: Vec2) -> SampleValue;
}

impl<F: Fn(Vec2) -> SampleValue + Sync> Estimator for F {
    fn estimate(&self, p: Vec2) -> SampleValue {
        self(p)
    }
}

/// Where the samples go. All strategies spend exactly the same number of samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Strategy {
    /// A regular (row-stratified) pattern, no quadtree: the baseline.
    Uniform,
    /// Analytic gradient magnitude |∇I| from the estimator (the paper's method, Sec. 9.1).
    Gradient,
    /// The Durand et al. 2005 metric, taken from [`SampleValue::durand`].
    Durand,
    /// Numerical contrast between neighbouring samples, |ΔI| / distance — the classic
    /// adaptive sampler the paper compares against (Sec. 9.2, Fig. 16–18).
    Variance,
    /// |∇I| plus the visibility-gradient magnitude [`SampleValue::vis_gradient`]
    /// (the extension suggested in Sec. 9.3).
    GradientVis,
    /// A Hessian estimate |ΔJ| / distance from the analytic gradients of neighbouring
    /// samples: the second-order criterion of Sec. 9.3 (Eq. 29 would give it exactly).
    SecondOrder,
}

impl Strategy {
    /// All strategies, for tables and CLI listings.
    pub const ALL: [Strategy; 6] = [
        Strategy::Uniform,
        Strategy::Gradient,
        Strategy::Durand,
        Strategy::Variance,
        Strategy::GradientVis,
        Strategy::SecondOrder,
    ];

    /// The snake_case name used in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Uniform => "uniform",
            Strategy::Gradient => "gradient",
            Strategy::Durand => "durand",
            Strategy::Variance => "variance",
            Strategy::GradientVis => "gradient_vis",
            Strategy::SecondOrder => "second_order",
        }
    }

    /// The other spellings [`Strategy::from_name`] accepts (earlier versions'
    /// and the issue tracker's).
    pub fn aliases(self) -> &'static [&'static str] {
        match self {
            Strategy::GradientVis => &["gradient+vis", "gradient-vis"],
            Strategy::SecondOrder => &["second-order", "second+order"],
            _ => &[],
        }
    }

    /// Parses [`Strategy::name`] (`+` and `-` may stand for `_`: `gradient+vis`,
    /// `second-order`); the error lists the valid choices.
    pub fn from_name(name: &str) -> Result<Self> {
        let canonical = name.replace(['+', '-'], "_");
        Self::ALL
            .into_iter()
            .find(|s| s.name() == canonical)
            .ok_or_else(|| Error::Option {
                option: "strategy".into(),
                message: format!(
                    "unknown strategy '{name}', expected one of: {}",
                    Self::ALL.map(|s| s.name()).join(", ")
                ),
            })
    }
}

/// Parameters of [`refine`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub strategy: Strategy,
    /// Samples per pixel: the refiner returns exactly `round(budget · W · H)` samples.
    /// Must lie in `(0, 16]`.
    pub budget: f32,
    /// Side of the initial blocks in pixels (the paper uses 8). Doubled as often as
    /// needed when the budget cannot pay for one sample per block.
    pub block_size: u32,
    /// Relative miss of the tangent-plane depth predictions above which two
    /// neighbouring samples of the same object may lie on different surfaces (see
    /// [`surfaces_differ`], which also tells curvature from steps). 0.02 catches the
    /// folds of a mesh, such as the 2.7% step on objects_bumpy's cow face.
    pub depth_tolerance: f32,
    /// The largest share of the budget that forced (boundary) splits may spend,
    /// in [0, 1]. Past it, boundary cells compete on their strategy's metric like
    /// any other: without a cap, silhouettes, creases and terminators can take the
    /// whole of a low budget and every strategy places the same samples.
    pub boundary_share: f32,
}

impl Settings {
    /// The paper's setup: 8×8 initial blocks, the given strategy and budget.
    pub fn new(strategy: Strategy, budget: f32) -> Self {
        Self {
            strategy,
            budget,
            block_size: 8,
            depth_tolerance: 0.02,
            boundary_share: 0.5,
        }
    }
}

/// One evaluated sample and the quadtree square it is the centre of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Position in continuous pixel coordinates (the centre of its cell).
    pub pos: Vec2,
    /// The cell (square, or rectangle where it is clipped by the image border).
    pub cell_min: Vec2,
    pub cell_max: Vec2,
    /// Bit `q` set when quadrant `q` (0 top-left, 1 top-right, 2 bottom-left,
    /// 3 bottom-right) was refined into a child cell. 0 for a leaf, 15 for a full split;
    /// anything else only for the one partial split that lands the budget exactly.
    pub split: u8,
    pub value: SampleValue,
}

impl Sample {
    /// The longer side of the cell, in pixels.
    pub fn size(&self) -> f32 {
        let e = self.cell_max - self.cell_min;
        e.x.max(e.y)
    }
}

/// The samples of one image, in creation order (deterministic).
#[derive(Clone, Debug, PartialEq)]
pub struct SampleSet {
    pub width: u32,
    pub height: u32,
    pub samples: Vec<Sample>,
    /// The [`Settings::depth_tolerance`] the set was refined with; the reconstruction
    /// uses it to keep surfaces of one object apart.
    pub depth_tolerance: f32,
}

impl SampleSet {
    /// The final partition of the image: every leaf cell, plus the quadrants of a
    /// partially split cell that got no child. Rectangles as `(min, max)`.
    pub fn leaf_regions(&self) -> Vec<(Vec2, Vec2)> {
        let mut out = Vec::new();
        for s in &self.samples {
            if s.split == 0 {
                out.push((s.cell_min, s.cell_max));
            } else if s.split != 15 {
                for q in 0..4u8 {
                    if s.split & (1 << q) == 0 {
                        out.push(quadrant(s.cell_min, s.cell_max, s.pos, q));
                    }
                }
            }
        }
        out
    }

    /// The `samples.density` plane: number of samples whose position falls in each
    /// pixel (row-major, top row first). It sums to the sample count, so it shows the
    /// sample locations as the paper's Fig. 14/15 do and integrates to the budget.
    pub fn density(&self) -> Vec<f32> {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut d = vec![0.0f32; w * h];
        if w == 0 || h == 0 {
            return d;
        }
        for s in &self.samples {
            let x = (s.pos.x.floor().max(0.0) as usize).min(w - 1);
            let y = (s.pos.y.floor().max(0.0) as usize).min(h - 1);
            d[y * w + x] += 1.0;
        }
        d
    }
}

/// Quadrant `q` of the cell `[min, max]` split at `centre`.
pub(crate) fn quadrant(min: Vec2, max: Vec2, centre: Vec2, q: u8) -> (Vec2, Vec2) {
    let (x0, x1) = if q & 1 == 0 {
        (min.x, centre.x)
    } else {
        (centre.x, max.x)
    };
    let (y0, y1) = if q & 2 == 0 {
        (min.y, centre.y)
    } else {
        (centre.y, max.y)
    };
    (Vec2::new(x0, y0), Vec2::new(x1, y1))
}

/// A sample as the boundary test sees it: where it is, which surface id it carries and
/// the inverse depth and tangent plane (as ∇(1/depth)) it found there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub pos: Vec2,
    /// [`SampleValue::surface_id`].
    pub surface: u64,
    /// 1/depth; 0 for the background (infinite depth).
    pub inv_depth: f32,
    pub inv_depth_grad: Vec2,
    /// [`SampleValue::facet_normal`].
    pub facet_normal: Option<Vec3>,
}

/// 1/depth, with the background (infinite or non-finite depth) at 0 and depths at or
/// below 0 clamped to the smallest positive float.
fn inverse_depth(depth: f32) -> f32 {
    if depth.is_finite() {
        1.0 / depth.max(f32::MIN_POSITIVE)
    } else {
        0.0
    }
}

/// True when two samples lie on different surfaces: a different [`surface id`]
/// (object, or side of a bump map's terminator), one of them on the background,
/// two facets of a flat-shaded surface whose normals differ by more than
/// [`CREASE_COS`] (a crease), or a step in depth between them. Two background
/// samples match.
///
/// A step is read off the tangent planes. Inverse depth is affine in image position
/// across a plane seen through a pinhole, so `1/d_a + ∇(1/d_a)·(x_b − x_a)` predicts
/// `1/d_b` exactly on a plane, and a floor seen at a grazing angle (depth changing
/// fast, but as predicted) is one surface. Where both predictions miss by more than
/// `tolerance` (relative to the nearer depth), the signs of the misses (actual minus
/// predicted inverse depth) tell a step from a curved surface:
/// * a convex surface lies behind both tangent planes: two negative misses, large
///   near a sphere's rim without any step — one surface;
/// * a step (an occluding fold): `b` behind `a`'s plane and `a` in front of `b`'s,
///   misses of opposite sign;
/// * a self-occlusion silhouette whose near side is seen edge-on: that plane
///   recedes steeply, so both samples lie in front of the other's plane — two
///   positive misses. A concave surface seen at a grazing angle gives the same, and
///   is then refined and kept apart like a step: budget spent, nothing blended.
///
/// With zero gradients this is the plain relative jump
/// `|d_a − d_b| > tolerance · max(d_a, d_b)`.
///
/// [`surface id`]: SampleValue::surface_id
#[inline]
pub fn surfaces_differ(a: &SurfacePoint, b: &SurfacePoint, tolerance: f32) -> bool {
    if a.surface != b.surface {
        return true;
    }
    let (qa, qb) = (a.inv_depth, b.inv_depth);
    if qa == 0.0 || qb == 0.0 {
        return (qa == 0.0) != (qb == 0.0);
    }
    if let (Some(na), Some(nb)) = (a.facet_normal, b.facet_normal) {
        if na.dot(nb) < CREASE_COS {
            return true;
        }
    }
    let step = b.pos - a.pos;
    // Actual minus predicted inverse depth, at b from a's plane and at a from b's.
    let miss_at_b = qb - qa - a.inv_depth_grad.dot(step);
    let miss_at_a = qa - qb + b.inv_depth_grad.dot(step);
    miss_at_b.abs().min(miss_at_a.abs()) > tolerance * qa.max(qb) && miss_at_b.max(miss_at_a) > 0.0
}

/// cos 1°: facet normals further apart are a crease (coplanar triangles of one face
/// agree to rounding).
pub const CREASE_COS: f32 = 0.999_847_7;
