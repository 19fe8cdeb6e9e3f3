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

/// Dense adaptive sampling for the gradient-domain strategy (issue 56, item 2):
/// a uniform base pass, then the rest of the budget per pixel by [`metric`],
/// then the same solve ([`reconstruct`]). The analytic gradient omits paths (a
/// mirror's reflection of the sun, indirect light's spatial variation), so a
/// gradient-only metric is blind exactly where the reconstruction needs samples;
/// the metric adds the noise and the contrast the gradient leaves unexplained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DenseAdaptive {
    /// Mean samples per pixel over the image: the budget.
    pub spp: u32,
    /// The share of the budget every pixel gets first (at least 2 samples, so
    /// that every pixel has a variance).
    pub base_fraction: f32,
    /// No pixel takes more than this many times the budget.
    pub max_factor: u32,
}

impl DenseAdaptive {
    /// A quarter of `spp` uniformly, at most 16 × `spp` in any pixel.
    pub fn new(spp: u32) -> Self {
        Self {
            spp,
            base_fraction: 0.25,
            max_factor: 16,
        }
    }

    /// Samples of the uniform pass: the budget itself below 4 spp (nothing to adapt).
    pub fn base_spp(&self) -> u32 {
        let b = (self.spp as f32 * self.base_fraction).round() as u32;
        if self.spp < 4 {
            self.spp
        } else {
            b.clamp(2, self.spp)
        }
    }

    fn check(&self) -> Result<()> {
        let bad = |message: String| {
            Err(Error::Option {
                option: "--dense-adaptive".into(),
                message,
            })
        };
        if self.spp == 0 {
            return bad("needs --spp ≥ 1".into());
        }
        if !(self.base_fraction > 0.0 && self.base_fraction <= 1.0) {
            return bad(format!(
                "base fraction {}: expected 0 < f ≤ 1",
                self.base_fraction
            ));
        }
        if self.max_factor == 0 {
            return bad("the per-pixel cap must be at least 1 × the budget".into());
        }
        Ok(())
    }
}

/// How much one more sample in each pixel is worth (luminance, radiance units per
/// sample; finite, ≥ 0), from a render of `spp` samples per pixel with gradients
/// and AOVs: σ_p + |∇I_p| + c_p, averaged with its 3×3 maximum (a pixel whose
/// few samples all missed a small bright feature still borrows its neighbour's).
/// σ_p, one sample's standard deviation (the render's own variance of the mean
/// × spp), covers every path, the ones the gradient omits included; |∇I_p|, the
/// analytic gradient, is the first-order paper's term; c_p, where a continuous
/// pair's difference disagrees with its gradient ([`poisson::drop_inconsistent`]),
/// is that pair's primal contrast: the gradient is incomplete there and the
/// solve will lean on the primal alone.
pub fn metric(out: &RenderOutput, spp: u32) -> Result<Vec<f32>> {
    let missing = |what: &str| Error::Option {
        option: "--dense-adaptive".into(),
        message: format!("needs the base pass's {what}"),
    };
    let g = out.gradients.as_ref().ok_or_else(|| missing("gradients"))?;
    let (Some(variance), Some(normal), Some(depth), Some(id)) =
        (&out.variance, &out.normal, &out.depth, &out.object_id)
    else {
        return Err(missing("AOVs"));
    };
    let (w, h) = (out.width, out.height);
    let n = w * h;
    let guides = Guides {
        object_id: id,
        depth,
        normal,
    };
    let (vx, vy) = poisson::continuous_pairs(w, h, &guides);
    let (dx, dy) = poisson::trapezoid_differences(w, h, &g.grad_u, &g.grad_v);
    let (mut cx, mut cy) = (vx.clone(), vy.clone());
    poisson::drop_inconsistent(
        w,
        &out.beauty,
        variance,
        (&dx, &dy),
        (&mut cx, &mut cy),
        GradientDomain::new(Norm::L1).consistency,
    );
    let lum = |c: Vec3| luminance(c).abs();
    let mut contrast = vec![0.0f32; n];
    for i in 0..n {
        for (valid, consistent, j) in [(&vx, &cx, i + 1), (&vy, &cy, i + w)] {
            if valid[i] && !consistent[i] {
                let c = lum(out.beauty[j] - out.beauty[i]);
                contrast[i] = contrast[i].max(c);
                contrast[j] = contrast[j].max(c);
            }
        }
    }
    let clean = |x: f32| if x.is_finite() && x > 0.0 { x } else { 0.0 };
    let raw: Vec<f32> = (0..n)
        .map(|i| {
            let sigma = (luminance(variance[i]).max(0.0) * spp as f32).sqrt();
            let grad = luminance(g.grad_u[i]).hypot(luminance(g.grad_v[i]));
            clean(sigma) + clean(grad) + clean(contrast[i])
        })
        .collect();
    Ok((0..n)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut m = 0.0f32;
            for yy in y.saturating_sub(1)..(y + 2).min(h) {
                for xx in x.saturating_sub(1)..(x + 2).min(w) {
                    m = m.max(raw[yy * w + xx]);
                }
            }
            0.5 * (raw[i] + m)
        })
        .collect())
}

/// `total` samples shared out in proportion to `metric`, at most `cap` a pixel
/// (what a capped pixel cannot take goes to the others, by their metric); whole
/// samples by largest remainder, ties to the lower index, so the result is a
/// function of the metric alone. All-zero metric: evenly.
pub fn allocate(metric: &[f32], total: u64, cap: u32) -> Vec<u32> {
    let n = metric.len();
    let mut out = vec![0u32; n];
    let total = total.min(u64::from(cap) * n as u64);
    if n == 0 || total == 0 {
        return out;
    }
    let m: Vec<f64> = metric
        .iter()
        .map(|&x| {
            if x.is_finite() && x > 0.0 {
                f64::from(x)
            } else {
                0.0
            }
        })
        .collect();
    let cap_f = f64::from(cap);
    let mut capped = vec![false; n];
    let mut share = vec![0.0f64; n];
    loop {
        let n_capped = capped.iter().filter(|&&c| c).count();
        let left = total as f64 - n_capped as f64 * cap_f;
        let free: f64 = (0..n).filter(|&i| !capped[i]).map(|i| m[i]).sum();
        let free_n = n - n_capped;
        if free_n == 0 {
            break;
        }
        let mut newly = false;
        let free_ix: Vec<usize> = (0..n).filter(|&i| !capped[i]).collect();
        for i in free_ix {
            share[i] = if free > 0.0 {
                left * m[i] / free
            } else {
                left / free_n as f64
            };
            if share[i] >= cap_f {
                share[i] = cap_f;
                capped[i] = true;
                newly = true;
            }
        }
        if !newly {
            break;
        }
    }
    let mut given = 0u64;
    for i in 0..n {
        out[i] = (share[i].max(0.0).floor() as u32).min(cap);
        given += u64::from(out[i]);
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        let fa = share[a] - share[a].floor();
        let fb = share[b] - share[b].floor();
        fb.total_cmp(&fa).then(a.cmp(&b))
    });
    while given < total {
        let before = given;
        for &i in &order {
            if given == total {
                break;
            }
            if out[i] < cap {
                out[i] += 1;
                given += 1;
            }
        }
        if given == before {
            break;
        }
    }
    out
}

/// A render with gradients and AOVs whose samples are placed by [`metric`]: the
/// base pass ([`DenseAdaptive::base_spp`]) in every pixel, the rest of
/// `dense.spp` × pixels by [`allocate`]. Deterministic for a seed, whatever the
/// thread count; `spp_map` holds each pixel's count. Solve it with [`reconstruct`]
/// (the variance plane is each pixel's own, so its primal weight follows its count).
pub fn render_dense_adaptive(
    scene: &crate::scene::Scene,
    accel: &crate::accel::Accel,
    opts: &crate::render::RenderOptions,
    dense: &DenseAdaptive,
) -> Result<RenderOutput> {
    dense.check()?;
    let opts = crate::render::RenderOptions {
        gradients: true,
        aovs: true,
        ..opts.clone()
    };
    let (w, h) = opts.resolution_of(scene);
    let pixels = u64::from(w) * u64::from(h);
    let base = dense.base_spp();
    let total = u64::from(dense.spp - base) * pixels;
    let cap = dense
        .spp
        .saturating_mul(dense.max_factor)
        .saturating_sub(base);
    crate::render::two_pass::render_two_pass(scene, accel, &opts, base, &|first| {
        Ok(allocate(&metric(first, base)?, total, cap))
    })
}
