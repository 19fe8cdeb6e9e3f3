//! Run-time combination (Zhou et al. 2005, Sec. 3.2 of the deformable paper): at a
//! receiver, the entities are sorted near to far; the receiver's transfer (clamped
//! cosine / π, times its self-visibility) is multiplied by each occluder's
//! visibility in turn (triple products), and each light adds its SRF dotted with
//! the transfer accumulated so far — the OOFs of the entities nearer than it.
//! The environment's SH, last, sees every occluder. A sphere light is the
//! exception: a few degrees wide, it is not low-frequency, so it is integrated
//! over its cap against the nearer entities' unblurred cone maps instead; so is
//! an environment's sun, split off its SH ([`super::peak`]).
//!
//! Multiplying the transfer rather than the lights' fields is the same integral
//! ∫ L·V₁⋯V_n·T for band-limited factors; it needs one product per occluder for
//! all lights together.

use super::field::{cone_cos, ConeMap, Field};
use super::peak::EnvironmentLight;
use super::precompute::EntityKind;
use crate::brdf::Material;
use crate::math::sh::{self, ShF, COEFFS};
use crate::math::{cross, warp, Frame, Vec2, Vec3};
use crate::scene::Rect;
use glam::Mat3;

/// An entity placed in the current frame.
#[derive(Clone, Debug)]
pub struct Placed {
    pub kind: EntityKind,
    pub center: Vec3,
    pub radius: f32,
    /// World → the rest frame of the entity's fields (the inverse of its rotation).
    pub to_rest: Mat3,
    /// Occlusion field with world-aligned coefficients (rotated to this frame).
    pub occlusion: Option<Field>,
    pub radiance: Option<[Field; 3]>,
    /// A deforming entity shades its own surface with its own field.
    pub self_from_field: bool,
    /// A sphere light's radiance: shaded over its exact cap ([`Combiner::shade`]).
    pub sphere_light: Option<Vec3>,
    /// The occlusion unblurred, which a sphere light's directions look up.
    pub visibility: Option<ConeMap>,
}

/// A glossy receiver's lobe seen from its viewer ([`super::glossy::GlossyLobe::receiver`]).
#[derive(Clone, Debug)]
pub struct GlossyReceiver<'a> {
    /// The lobe alone (kd = 0), evaluated at a sphere light's directions.
    pub lobe: &'a Material,
    /// ks, which scales `transfer`.
    pub ks: Vec3,
    /// The shading frame the renderer evaluates the lobe in.
    pub frame: Frame,
    pub wo_local: Vec3,
    /// Order-4 SH of f_s(·, ω_o)·max(n·ω_i, 0) for ks = 1, world-aligned.
    pub transfer: ShF,
}

/// What [`Combiner::shade_parts`] returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shade {
    /// Per unit diffuse albedo, as [`Combiner::shade`].
    pub diffuse: Vec3,
    /// The glossy lobe's reflected radiance (ks included); zero without one.
    pub glossy: Vec3,
    /// Entities combined.
    pub count: usize,
}

/// Directions per sphere light (or environment peak) and receiver ([`cap_directions`]).
pub const LIGHT_DIRS: usize = 32;
/// 1/φ: the spiral's turn per direction, as a fraction of a full turn.
const GOLDEN: f32 = 0.618_034;

/// Everything the combination reads for one frame.
#[derive(Clone, Debug)]
pub struct Combiner {
    pub entities: Vec<Placed>,
    /// The environment: RGB SH, and its peak (a sun) if split off.
    pub environment: EnvironmentLight,
}

/// A cone of light directions with what each carries (`Combiner::cap_light`).
pub struct Cap<'a> {
    pub axis: Vec3,
    pub cos_max: f32,
    pub dirs: &'a [Vec3; LIGHT_DIRS],
    /// Radiance times the direction's share of the cap's solid angle.
    pub power: &'a [Vec3; LIGHT_DIRS],
    /// Beyond this distance along a direction nothing hides the light.
    pub reach: f32,
}

/// `LIGHT_DIRS` directions uniform over the cap around `frame.n` on a
/// golden-angle spiral: a grid's rows of directions would enter an occluder's
/// edge together and step the penumbra.
pub fn cap_directions(frame: &Frame, cos_max: f32) -> [Vec3; LIGHT_DIRS] {
    std::array::from_fn(|k| {
        let u = Vec2::new(
            (k as f32 + 0.5) / LIGHT_DIRS as f32,
            (k as f32 * GOLDEN).fract(),
        );
        frame.to_world(warp::square_to_uniform_cone(u, cos_max))
    })
}

/// Receiver transfer of a Lambertian surface without the albedo: max(n·ω, 0)/π,
/// i.e. the clamped cosine's zonal coefficients √(4π/(2l+1)) z_l / π times Y_lm(n)
/// (f32, no square roots: the constants are folded; `tests/sh.rs` checks
/// `sh::clamped_cosine`, and the unit test below this against it).
#[inline]
pub fn diffuse_transfer(n: Vec3) -> ShF {
    // √(4π/(2l+1)) z_l / π for l = 0, 1, 2 (l = 3 vanishes), times the Y_lm constants.
    const A0: f32 = 1.0;
    const A1: f32 = 2.0 / 3.0;
    const A2: f32 = 0.25;
    let (x, y, z) = (n.x, n.y, n.z);
    let c0 = A0 * 0.282_094_8;
    let c1 = A1 * 0.488_602_5;
    let c2 = A2 * 1.092_548_4;
    let c20 = A2 * 0.315_391_57;
    let c22 = A2 * 0.546_274_2;
    [
        c0,
        c1 * y,
        c1 * z,
        c1 * x,
        c2 * x * y,
        c2 * y * z,
        c20 * (3.0 * z * z - 1.0),
        c2 * x * z,
        c22 * (x * x - y * y),
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ]
}

fn visibility_from_occlusion(o: &ShF) -> ShF {
    let mut v = o.map(|x| -x);
    v[0] += ONE0;
    v
}

/// The constant 1's only coefficient, √(4π).
const ONE0: f32 = 3.544_907_7;

impl Combiner {
    pub fn new(entities: Vec<Placed>, environment: EnvironmentLight) -> Self {
        Self {
            entities,
            environment,
        }
    }

    /// Light reaching a Lambertian receiver at `p` with normal `n` per unit albedo
    /// (the reflected radiance is albedo × this). `own` is the receiver's entity
    /// (skipped: its self-shadowing is `self_visibility`), `self_visibility` its
    /// per-vertex visibility, if any. Returns the value and the number of
    /// entities that were combined (not culled).
    pub fn shade(
        &self,
        p: Vec3,
        n: Vec3,
        own: Option<usize>,
        self_visibility: Option<&ShF>,
    ) -> (Vec3, usize) {
        let s = self.shade_parts(p, n, own, self_visibility, None);
        (s.diffuse, s.count)
    }

    /// [`shade`](Self::shade), and with `glossy` the glossy lobe's reflected
    /// radiance too: its SH transfer carried through the same triple products as
    /// the diffuse one (SRFs, quads, the environment), and each sphere light's
    /// cap directions weighted by the lobe itself (times the receiver's own SH
    /// shadowing share of that light, which is the diffuse transfer's). The
    /// diffuse result is the same, bit for bit, with or without `glossy`.
    pub fn shade_parts(
        &self,
        p: Vec3,
        n: Vec3,
        own: Option<usize>,
        self_visibility: Option<&ShF>,
        glossy: Option<&GlossyReceiver>,
    ) -> Shade {
        let bare = diffuse_transfer(n);
        let mut t = bare;
        let mut tg = glossy.map(|g| g.transfer);
        let mut shadows_itself = false;
        if let Some(v) = self_visibility {
            t = sh::product(&t, v);
            tg = tg.map(|g| sh::product(&g, v));
            shadows_itself = true;
        }
        if let Some(e) = own.map(|i| &self.entities[i]).filter(|e| e.self_from_field) {
            if let Some(occ) = &e.occlusion {
                let q = e.to_rest * (p - e.center);
                let v = visibility_from_occlusion(&occ.lookup(q));
                t = sh::product(&t, &v);
                tg = tg.map(|g| sh::product(&g, &v));
                shadows_itself = true;
            }
        }
        let self_t = t;
        // The receiver's own (SH) shadowing is as blurred as the method's: the
        // share of a sphere light it leaves, by the light's SH field.
        let share_of = |l: &ShF| -> f32 {
            let (all, kept) = (sh::dot_f32(&bare, l), sh::dot_f32(&self_t, l));
            if shadows_itself && all > 1e-12 {
                (kept / all).clamp(0.0, 1.0)
            } else {
                1.0
            }
        };
        let own_share = |e: &Placed, q: Vec3| -> f32 {
            e.radiance
                .as_ref()
                .filter(|_| shadows_itself)
                .map_or(1.0, |rad| share_of(&rad[1].lookup(q)))
        };

        // Near-to-far order of the entities that can matter (bounding sphere not
        // entirely below the receiver's horizon); on the stack up to 32 of them.
        let mut stack: [(f32, u32); 32] = [(0.0, 0); 32];
        let mut heap: Vec<(f32, u32)> = Vec::new();
        let mut count = 0;
        for (i, e) in self.entities.iter().enumerate() {
            if Some(i) == own || matches!(e.kind, EntityKind::Quad(_)) {
                continue;
            }
            let to_c = e.center - p;
            if n.dot(to_c) < -e.radius {
                continue;
            }
            let item = (to_c.length_squared(), i as u32);
            if count < stack.len() {
                stack[count] = item;
            } else {
                if heap.is_empty() {
                    heap.extend_from_slice(&stack);
                }
                heap.push(item);
            }
            count += 1;
        }
        let order = if heap.is_empty() {
            &mut stack[..count]
        } else {
            &mut heap[..]
        };
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut out = Vec3::ZERO;
        // The glossy lobe: sphere lights (ks in the lobe) and the SH part (unit ks).
        let (mut out_g, mut out_g_sh) = (Vec3::ZERO, Vec3::ZERO);
        for (k, &(_, i)) in order.iter().enumerate() {
            let e = &self.entities[i as usize];
            let q = e.to_rest * (p - e.center);
            if let Some(le) = e.sphere_light {
                let share = own_share(e, q);
                let (d, g) = self.sphere_light(p, n, e, le, &order[..k], own, glossy);
                out += share * d;
                out_g += share * g;
            }
            let Some(occ) = &e.occlusion else {
                continue;
            };
            // One set of trilinear corners for the occlusion and the radiance.
            let corners = occ.grid.corners(q);
            if let Some(rad) = e.radiance.as_ref().filter(|_| e.sphere_light.is_none()) {
                if !self.behind_a_quad(p, e.center, own) {
                    let l = [0, 1, 2].map(|c| rad[c].lookup_at(&corners));
                    out += Vec3::new(
                        sh::dot_f32(&t, &l[0]),
                        sh::dot_f32(&t, &l[1]),
                        sh::dot_f32(&t, &l[2]),
                    );
                    if let Some(g) = &tg {
                        out_g_sh += Vec3::new(
                            sh::dot_f32(g, &l[0]),
                            sh::dot_f32(g, &l[1]),
                            sh::dot_f32(g, &l[2]),
                        );
                    }
                }
            }
            let v = visibility_from_occlusion(&occ.lookup_at(&corners));
            t = sh::product(&t, &v);
            tg = tg.map(|g| sh::product(&g, &v));
        }
        let mut combined = count;
        for (i, e) in self.entities.iter().enumerate() {
            if let EntityKind::Quad(r) = e.kind {
                if Some(i) != own && above_horizon(&r, p, n) {
                    let v = quad_visibility(&r, p);
                    t = sh::product(&t, &v);
                    tg = tg.map(|g| sh::product(&g, &v));
                    combined += 1;
                }
            }
        }
        // The environment's peak sees every entity (it is farther than all).
        if let Some(pk) = &self.environment.peak {
            let share = share_of(&pk.sh);
            let cap = Cap {
                axis: pk.axis,
                cos_max: pk.cos_max,
                dirs: &pk.dirs,
                power: &pk.power,
                reach: f32::INFINITY,
            };
            let (d, g) = self.cap_light(p, n, &cap, order, own, glossy);
            out += share * d;
            out_g += share * g;
        }
        let env = &self.environment.sh;
        out += Vec3::new(
            sh::dot_f32(&t, &env[0]),
            sh::dot_f32(&t, &env[1]),
            sh::dot_f32(&t, &env[2]),
        );
        if let (Some(g), Some(r)) = (&tg, glossy) {
            out_g_sh += Vec3::new(
                sh::dot_f32(g, &env[0]),
                sh::dot_f32(g, &env[1]),
                sh::dot_f32(g, &env[2]),
            );
            out_g += r.ks * out_g_sh;
        }
        Shade {
            diffuse: out,
            glossy: out_g,
            count: combined,
        }
    }

    /// A sphere light's direct light at a Lambertian receiver per unit albedo,
    /// ∫ L·V·max(n·ω, 0)/π over the light's cap, by `LIGHT_DIRS` directions
    /// ([`cap_light`](Self::cap_light)). Order-4 SH cannot hold a light a few
    /// degrees wide: its product with an occluder's field leaves about half of
    /// the shadow lit and spreads the rest over tens of degrees (issue 57).
    #[allow(clippy::too_many_arguments)]
    fn sphere_light(
        &self,
        p: Vec3,
        n: Vec3,
        light: &Placed,
        le: Vec3,
        nearer: &[(f32, u32)],
        own: Option<usize>,
        glossy: Option<&GlossyReceiver>,
    ) -> (Vec3, Vec3) {
        let to_l = light.center - p;
        let d = to_l.length();
        let cos_max = cone_cos(d, light.radius);
        if cos_max <= -1.0 || !d.is_finite() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let frame = Frame::from_normal(to_l / d);
        let dirs = cap_directions(&frame, cos_max);
        let power = le * (std::f32::consts::TAU * (1.0 - cos_max) / LIGHT_DIRS as f32);
        let cap = Cap {
            axis: frame.n,
            cos_max,
            dirs: &dirs,
            power: &[power; LIGHT_DIRS],
            reach: d - light.radius,
        };
        self.cap_light(p, n, &cap, nearer, own, glossy)
    }

    /// Light from a cap of directions `cap` at a receiver: per unit diffuse
    /// albedo Σ_k V_k·max(n·ω_k, 0)·P_k/π, and with `glossy`, second,
    /// Σ_k V_k·f_s(ω_k, ω_o)·max(n·ω_k, 0)·P_k, f_s the renderer's own
    /// `Material::eval` (a highlight is as sharp as the lobe, not as order 4).
    /// P_k is direction k's radiance times its share of the cap's solid angle.
    /// V is exact for quads (per direction), and for the entities `nearer`
    /// than the light (the paper's near-to-far rule) the product of their
    /// unblurred cone maps; an entity without a map (a field rebuilt each
    /// frame) is as blurred as the method's: its SH visibility towards the
    /// axis. The receiver's own shadowing is the caller's (`own_share`).
    fn cap_light(
        &self,
        p: Vec3,
        n: Vec3,
        cap: &Cap,
        nearer: &[(f32, u32)],
        own: Option<usize>,
        glossy: Option<&GlossyReceiver>,
    ) -> (Vec3, Vec3) {
        let mut vis = [0.0f32; LIGHT_DIRS];
        let mut any = false;
        for k in 0..LIGHT_DIRS {
            vis[k] = n.dot(cap.dirs[k]).max(0.0);
            any |= vis[k] > 0.0;
        }
        if !any {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        // Quads (floors, walls) hide the light direction by direction, exactly.
        for (i, e) in self.entities.iter().enumerate() {
            if let EntityKind::Quad(r) = e.kind {
                if Some(i) != own {
                    for k in 0..LIGHT_DIRS {
                        if vis[k] > 0.0 && quad_hit(&r, p, cap.dirs[k], cap.reach) {
                            vis[k] = 0.0;
                        }
                    }
                }
            }
        }
        let mut scale = 1.0;
        let y_light = |v: &ShF| sh::dot_f32(v, &sh::eval_f32(cap.axis)).clamp(0.0, 1.0);
        let sin_max = (1.0 - cap.cos_max * cap.cos_max).max(0.0).sqrt();
        for &(_, j) in nearer {
            let e = &self.entities[j as usize];
            let to_e = e.center - p;
            let d_e = to_e.length();
            // Only an entity whose cone meets the light's can hide any of it:
            // skip it where the angle between their axes exceeds the sum of the
            // half-angles (which must be under π for that), compared by cosines.
            if d_e > e.radius {
                let (sin_e, cos_apart) = (e.radius / d_e, to_e.dot(cap.axis) / d_e);
                let cos_e = (1.0 - sin_e * sin_e).sqrt();
                if cap.cos_max > -cos_e && cos_apart < cap.cos_max * cos_e - sin_max * sin_e {
                    continue;
                }
            }
            let q = e.to_rest * (p - e.center);
            if let Some(map) = &e.visibility {
                let at = map.at(q, e.radius);
                for k in 0..LIGHT_DIRS {
                    if vis[k] > 0.0 {
                        vis[k] *= map.visibility(&at, e.to_rest * cap.dirs[k]);
                    }
                }
            } else if let Some(occ) = &e.occlusion {
                scale *= y_light(&visibility_from_occlusion(&occ.lookup(q)));
            }
        }
        let mut diffuse = Vec3::ZERO;
        for k in 0..LIGHT_DIRS {
            diffuse += vis[k] * cap.power[k];
        }
        let diffuse = diffuse * (scale / std::f32::consts::PI);
        let glossy = glossy.map_or(Vec3::ZERO, |g| {
            // vis holds cos·V already: the lobe's f is the only factor left.
            let mut f_sum = Vec3::ZERO;
            for k in 0..LIGHT_DIRS {
                if vis[k] > 0.0 {
                    let wi = g.frame.to_local(cap.dirs[k]);
                    f_sum += vis[k] * g.lobe.eval(g.wo_local, wi) * cap.power[k];
                }
            }
            f_sum * scale
        });
        (diffuse, glossy)
    }

    /// Whether a quad lies between `p` and a light's centre (an SH light is then
    /// hidden: its field holds no occluders of its own).
    fn behind_a_quad(&self, p: Vec3, light: Vec3, own: Option<usize>) -> bool {
        let (to_l, d) = ((light - p).normalize_or_zero(), (light - p).length());
        self.entities.iter().enumerate().any(|(i, e)| match e.kind {
            EntityKind::Quad(r) if Some(i) != own => quad_hit(&r, p, to_l, d),
            _ => false,
        })
    }
}

/// Whether the ray from `p` along unit `w` meets the quad before distance `reach`.
fn quad_hit(r: &Rect, p: Vec3, w: Vec3, reach: f32) -> bool {
    let n = cross(r.edge_u, r.edge_v);
    let denom = n.dot(w);
    if denom == 0.0 {
        return false;
    }
    let t = n.dot(r.corner - p) / denom;
    if !(t > 0.0 && t < reach) {
        return false;
    }
    let x = p + w * t - r.corner;
    let (s, v) = (
        x.dot(r.edge_u) / r.edge_u.length_squared(),
        x.dot(r.edge_v) / r.edge_v.length_squared(),
    );
    (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&v)
}

/// Whether any of the quad lies above the receiver's horizon (below it, it
/// hides nothing the clamped cosine sees).
fn above_horizon(r: &Rect, p: Vec3, n: Vec3) -> bool {
    [
        r.corner,
        r.corner + r.edge_u,
        r.corner + r.edge_v,
        r.corner + r.edge_u + r.edge_v,
    ]
    .iter()
    .any(|c| n.dot(*c - p) > 0.0)
}

/// The visibility SH a quad leaves a point `p`: 1 minus the projection of the
/// spherical quadrilateral it subtends, exact ([`sh::polygon_projection`]), so
/// a receiver next to a floor is as right as one far from it. A half-space,
/// which it replaced, hides the sky above a wall of finite height.
pub fn quad_visibility(r: &Rect, p: Vec3) -> ShF {
    let corners = [
        r.corner,
        r.corner + r.edge_u,
        r.corner + r.edge_u + r.edge_v,
        r.corner + r.edge_v,
    ]
    .map(|c| c - p);
    let normal = cross(r.edge_u, r.edge_v);
    let height = normal.dot(corners[0]);
    // In the quad's plane (or a degenerate quad) it hides nothing.
    let occ = if height.is_finite() && height != 0.0 {
        sh::polygon_projection(corners)
    } else {
        [0.0; COEFFS]
    };
    visibility_from_occlusion(&occ)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quad's visibility against a brute-force projection (a fine sphere
    /// quadrature, each direction tested against the quad) from far, from just
    /// above its middle, beside an edge and from behind (its errors are the
    /// brute force's own); a half-space, what the quad replaced, fails the close
    /// ones. The projection's exactness is `tests/sh.rs`'s.
    #[test]
    fn quad_visibility_matches_brute_force_projection() {
        let r = Rect {
            corner: Vec3::new(-1.0, 0.0, -0.5),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 1.0),
        };
        let rule = sh::sphere_quadrature(256, 512);
        for p in [
            Vec3::new(0.3, 4.0, 0.2),
            Vec3::new(0.1, 0.02, 0.05),
            Vec3::new(1.05, 0.1, 0.0),
            Vec3::new(-0.4, -0.3, 0.4),
        ] {
            let mut want = [0.0f64; COEFFS];
            want[0] = f64::from(ONE0);
            for (d, w) in &rule {
                if quad_hit(&r, p, d.as_vec3a(), f32::INFINITY) {
                    let y = sh::eval(*d);
                    for k in 0..COEFFS {
                        want[k] -= w * y[k];
                    }
                }
            }
            let got = quad_visibility(&r, p);
            let err: f64 = (0..COEFFS)
                .map(|k| (f64::from(got[k]) - want[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            let occ: f64 = (0..COEFFS)
                .map(|k| (want[k] - if k == 0 { f64::from(ONE0) } else { 0.0 }).powi(2))
                .sum::<f64>()
                .sqrt();
            eprintln!("{p}: error {err:.2e} of {occ:.3}");
            assert!(err < 0.02 * occ.max(0.01), "{p}: error {err} of {occ}");
        }
    }

    #[test]
    fn folded_transfer_is_the_clamped_cosine_over_pi() {
        for n in [Vec3::Y, Vec3::new(0.3, -0.5, 0.81).normalize(), -Vec3::X] {
            let want = sh::clamped_cosine(n.as_dvec3());
            let got = diffuse_transfer(n);
            for k in 0..COEFFS {
                let w = want[k] / std::f64::consts::PI;
                assert!(
                    (f64::from(got[k]) - w).abs() < 1e-6,
                    "{k}: {} vs {w}",
                    got[k]
                );
            }
        }
    }
}
