//! a render with gradients and AOVs → its gradient-domain reconstruction
//! (`render --reconstruct poisson-l1|poisson-l2`, compare's `gradient-domain` row):
//! `reconstruct::poisson` fed with the renderer's analytic gradients.
//!
//! What is solved for (`Domain`): the analytic gradient is complete for the direct
//! light D at the first hit only; its indirect term has the curvature/bump and
//! camera terms of indirect light but not its spatial variation. Solving for D
//! alone (∂D from every term but the indirect one) and adding I − D back as
//! rendered is consistent, but leaves the indirect noise; solving for the whole
//! radiance I with the total gradient also smooths indirect light (where its
//! gradient is partial, towards it), and measured lower RMSE on every bundled scene
//! tried at 8 and 64 spp (ARCHITECTURE.md, "Gradient-domain reconstruction"), so
//! it is the default. Demodulating D by the albedo AOV (all materials are
//! untextured, so ∂(D/a) = ∂D/a inside a surface) changed the RMSE by < 3 %.

use crate::math::{luminance, Vec3};
use crate::reconstruct::poisson::{self, Guides, Norm, Problem, Settings, Solution};
use crate::render::RenderOutput;
use crate::{Error, Result};

/// Which image the Poisson solve reconstructs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// The radiance, with the total gradient (indirect term included).
    Full,
    /// The direct light D; I − D added back.
    Direct,
    /// D / albedo; times the albedo, plus I − D.
    Demodulated,
}

/// A gradient-domain reconstruction's settings.
#[derive(Clone, Copy, Debug)]
pub struct GradientDomain {
    pub norm: Norm,
    pub domain: Domain,
    /// β of [`poisson::primal_weights`]: a typical pixel's primal weight
    /// relative to one pair.
    pub beta: f32,
    /// k of [`poisson::drop_inconsistent`]; 0 keeps every continuous pair.
    pub consistency: f32,
}

impl GradientDomain {
    pub fn new(norm: Norm) -> Self {
        Self {
            norm,
            domain: Domain::Full,
            beta: 0.2,
            consistency: 4.0,
        }
    }
}

/// Albedo below this is no albedo to divide by (black or background).
const MIN_ALBEDO: f32 = 1e-3;

/// Pairs whose albedos differ by more than this fraction are dropped when
/// demodulating (∂(D/a) = ∂D/a holds only where a is constant).
const ALBEDO_JUMP: f32 = 0.01;

/// The reconstructed radiance of `out`, which must hold the gradient planes and
/// the AOVs.
pub fn reconstruct(out: &RenderOutput, gd: &GradientDomain) -> Result<Vec<Vec3>> {
    reconstruct_with(out, gd, &Settings::new(gd.norm)).map(|s| s.image)
}

/// [`reconstruct`] with the solver's settings; also returns its iteration count.
pub fn reconstruct_with(
    out: &RenderOutput,
    gd: &GradientDomain,
    settings: &Settings,
) -> Result<Solution> {
    let missing = |what: &str| Error::Option {
        option: "--reconstruct".into(),
        message: format!("needs the render's {what}"),
    };
    let g = out.gradients.as_ref().ok_or_else(|| missing("gradients"))?;
    let (Some(variance), Some(normal), Some(depth), Some(albedo), Some(id)) = (
        &out.variance,
        &out.normal,
        &out.depth,
        &out.albedo,
        &out.object_id,
    ) else {
        return Err(missing("AOVs (drop --no-aovs)"));
    };
    let (w, h) = (out.width, out.height);
    let guides = Guides {
        object_id: id,
        depth,
        normal,
    };
    let (mut vx, mut vy) = poisson::continuous_pairs(w, h, &guides);
    let ones = vec![Vec3::ONE; w * h];
    let (primal, gu, gv, scale): (Vec<Vec3>, &[Vec3], &[Vec3], Vec<Vec3>) = match gd.domain {
        Domain::Full => (out.beauty.clone(), &g.grad_u, &g.grad_v, ones),
        Domain::Direct => (g.direct.clone(), &g.direct_u, &g.direct_v, ones),
        Domain::Demodulated => {
            let a: Vec<Vec3> = albedo
                .iter()
                .map(|a| {
                    let keep = |c: f32| if c > MIN_ALBEDO { c } else { 1.0 };
                    Vec3::new(keep(a.x), keep(a.y), keep(a.z))
                })
                .collect();
            let differ = |p: usize, q: usize| {
                let d = (a[p] - a[q]).abs().max_element();
                d > ALBEDO_JUMP * a[p].min(a[q]).min_element()
            };
            for i in 0..w * h {
                if vx[i] && differ(i, i + 1) {
                    vx[i] = false;
                }
                if vy[i] && differ(i, i + w) {
                    vy[i] = false;
                }
            }
            (g.direct.clone(), &g.direct_u, &g.direct_v, a)
        }
    };
    let div = |v: &[Vec3]| -> Vec<Vec3> { v.iter().zip(&scale).map(|(v, a)| *v / *a).collect() };
    let (primal, gu, gv) = (div(&primal), div(gu), div(gv));
    let var: Vec<f32> = variance
        .iter()
        .zip(&scale)
        .map(|(v, a)| luminance(*v) / luminance(*a).powi(2))
        .collect();
    let alpha = poisson::primal_weights(&var, gd.beta);
    let (dx, dy) = poisson::trapezoid_differences(w, h, &gu, &gv);
    if gd.consistency > 0.0 {
        let var: Vec<Vec3> = variance
            .iter()
            .zip(&scale)
            .map(|(v, a)| *v / (*a * *a))
            .collect();
        poisson::drop_inconsistent(
            w,
            &primal,
            &var,
            (&dx, &dy),
            (&mut vx, &mut vy),
            gd.consistency,
        );
    }
    let problem = Problem {
        width: w,
        height: h,
        primal: &primal,
        weight: &alpha,
        dx: &dx,
        dy: &dy,
        valid_x: &vx,
        valid_y: &vy,
    };
    let solved = poisson::solve(&problem, settings).map_err(|message| Error::Option {
        option: "--reconstruct".into(),
        message,
    })?;
    let image = match gd.domain {
        Domain::Full => solved.image,
        Domain::Direct | Domain::Demodulated => solved
            .image
            .iter()
            .zip(&scale)
            .zip(g.direct.iter().zip(&out.beauty))
            .map(|((s, a), (d, i))| crate::math::finite_or_zero(*s * *a + (*i - *d)))
            .collect(),
    };
    Ok(Solution {
        image,
        iterations: solved.iterations,
    })
}
