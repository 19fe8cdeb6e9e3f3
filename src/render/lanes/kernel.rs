//! The lane kernel: eight path vertices shaded at once, each lane the
//! operations of `interaction`, `LightSet::sample`, the Lambertian
//! `Material::eval`/`pdf`/`sample`, `power_heuristic` and `accel::offset` in
//! their order (so a lane's bits are the scalar code's), over any [`Lanes8`].
//! The shading formulas are the scalar code's own functions, generic over
//! `math::lanes::Lanes` (`math::warp`, `math::spawn`, `LaneFrame`, `accel`'s
//! triangle point, default error and shadow segment, `lights::area_point_pdf`,
//! `interaction::interpolated_normal`, `path::power_heuristic`,
//! `brdf::lambert_f`/`lambert_pdf8`); what is here is gathering, masking and
//! scattering.

use super::{Gathered, LightKind, Rows, LANES};
use crate::accel::{default_error_of, segment_to, triangle_point_error};
use crate::brdf::{lambert_f, lambert_pdf8, mirror_reflect};
use crate::math::lanes::{LaneFrame, Lanes8, V3};
use crate::math::spawn::offset_ray_origin;
use crate::math::warp::{cosine_hemisphere, cosine_hemisphere_pdf_z};
use crate::render::interaction::{face_ray, interpolated_normal};
use crate::render::lights::area_point_pdf;
use crate::render::path::power_heuristic;

/// What [`shade8`] writes, per lane. About 1.1 KB: the kernel writes it in
/// place (a slot of the batch's vector), since returning it by value cost a
/// copy per call (`memmove`, ~1.2 % of a cornell profile).
#[derive(Clone, Default)]
pub(super) struct Shaded8 {
    /// Bit l: lane l's path goes on from this hit (ω_o above the surface).
    pub alive: u32,
    pub p: Rows,
    /// The shading frame's normal (the first hit's AOV).
    pub normal: Rows,
    /// Bit l: lane l has direct light to test, `ld` along the shadow segment
    /// from `shadow_o` in `shadow_d`, up to `shadow_t`.
    pub direct: u32,
    pub ld: Rows,
    pub shadow_o: Rows,
    pub shadow_d: Rows,
    pub shadow_t: [f32; LANES],
    /// Bit l: lane l's BSDF sample continues the path.
    pub next: u32,
    pub next_o: Rows,
    pub next_d: Rows,
    pub weight: Rows,
    pub pdf: [f32; LANES],
}

/// [`shade8`] in AVX's 256-bit registers.
///
/// # Safety
/// The CPU must have AVX2 (`is_x86_feature_detected!`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn shade8_avx2(g: &Gathered, out: &mut Shaded8) {
    // SAFETY: this function runs only where the CPU has AVX2 (its contract).
    unsafe { shade8::<crate::math::lanes::Avx>(g, out) }
}

/// [`shade8`] in `wide`'s lanes, which any build's CPU runs.
pub(super) fn shade8_wide(g: &Gathered, out: &mut Shaded8) {
    // SAFETY: `wide` uses only what the build targets.
    unsafe { shade8::<wide::f32x8>(g, out) }
}

/// A lane's hit as `interaction` sets it up.
struct Hit8<L> {
    p: V3<L>,
    p_error: V3<L>,
    /// The geometric normal, toward the ray.
    ng: V3<L>,
    frame: LaneFrame<L>,
    wo: V3<L>,
}

/// A lane's light sample: its point `q` (for a shadow segment), the
/// direction, density and whether it is a direction only (`unbounded`).
struct Light8<L> {
    q: V3<L>,
    d: V3<L>,
    wi: V3<L>,
    pdf: L,
    sampled: L,
    unbounded: L,
}

/// The shading of eight hits: `interaction`, the light sample, the
/// Lambertian eval, pdf and sample, MIS and both rays' offsets, as `li` and
/// the functions it calls compute them.
///
/// # Safety
/// The CPU must run `L`'s instructions (AVX2 for `Avx`): the lane types'
/// methods are safe functions that do not check.
#[inline(always)]
unsafe fn shade8<L: Lanes8>(g: &Gathered, out: &mut Shaded8) {
    let zero = L::splat(0.0);
    let h = hit8::<L>(g);
    let alive = h.wo.z.gt(zero);
    let albedo = V3::<L>::load(&g.albedo);
    let light = light8(g, &h);
    // `Material::eval` (Lambert) and the checks of `sample_ld`.
    let wil = h.frame.to_local(light.wi);
    let upper =
        h.wo.is_finite()
            .and(wil.is_finite())
            .and(h.wo.z.gt(zero))
            .and(wil.z.gt(zero));
    let f = lambert_f(albedo);
    let f_nonzero = f.x.ne(zero).or(f.y.ne(zero)).or(f.z.ne(zero));
    let direct = alive
        .and(light.sampled)
        .and(upper)
        .and(light.wi.dot(h.ng).gt(zero))
        .and(f_nonzero);
    // `Material::pdf` (Lambert), lane by lane: an f64 formula.
    let bsdf_pdf = L::load(lambert_pdf8(wil.x.store(), wil.y.store(), wil.z.store()));
    let weight_mis = power_heuristic(light.pdf, bsdf_pdf);
    let ld = V3::load(&g.beta)
        .mul_v(f)
        .mul(wil.z)
        .mul_v(V3::load(&g.light_le))
        .mul(weight_mis / light.pdf);
    let (shadow_o, shadow_d, shadow_t) = shadow8(g, &h, &light);

    // The BSDF sample (`lambert::sample`).
    let local = cosine_hemisphere(L::load(g.u_dir[0]), L::load(g.u_dir[1]));
    let pdf = cosine_hemisphere_pdf_z(local.z);
    let (direct, local, pdf, sampled_dir) = if g.mirrors {
        // A mirror's lanes (`mirror::sample`): no light sample (a delta
        // lobe), the reflection about the normal, an infinite density (the
        // next emitter counts in full).
        let mirror = L::load(g.mirror).gt(zero);
        let reflected = mirror_reflect(h.wo);
        (
            mirror.select(zero.ne(zero), direct),
            V3::select(mirror, reflected, local),
            mirror.select(L::splat(f32::INFINITY), pdf),
            mirror.select(reflected.z.gt(zero), pdf.gt(zero)),
        )
    } else {
        (direct, local, pdf, pdf.gt(zero))
    };
    let wi_next = h.frame.to_world(local);
    // (`continue_path` also asks for a finite weight: the albedo was
    // sanitised when the lane scene was built.)
    let next = alive.and(sampled_dir).and(wi_next.dot(h.ng).gt(zero));
    let next_o = offset_ray_origin(h.p, h.p_error, h.ng, wi_next);
    *out = Shaded8 {
        alive: alive.bitmask(),
        p: h.p.store(),
        normal: h.frame.n.store(),
        direct: direct.bitmask(),
        ld: ld.store(),
        shadow_o: shadow_o.store(),
        shadow_d: shadow_d.store(),
        shadow_t: shadow_t.store(),
        next: next.bitmask(),
        next_o: next_o.store(),
        next_d: wi_next.store(),
        weight: albedo.store(),
        pdf: pdf.store(),
    };
}

/// `interaction`'s set-up of the lanes' hits: the surface point and its
/// error bound, the normals toward the ray, the frame and ω_o in it.
#[inline(always)]
fn hit8<L: Lanes8>(g: &Gathered) -> Hit8<L> {
    let zero = L::splat(0.0);
    let dir = V3::<L>::load(&g.dir);
    let (b1, b2) = (L::load(g.bary[0]), L::load(g.bary[1]));
    // `triangle_point_with_normal`: the vertices weighted, and the error bound.
    // (The loads spelt out: an array's `map` would be a closure of its own,
    // out of line and without AVX.)
    let v = [V3::load(&g.v[0]), V3::load(&g.v[1]), V3::load(&g.v[2])];
    let (p, p_error) = triangle_point_error(v, b1, b2);
    // A sphere's lanes: `sphere_point`'s, computed while gathering.
    let (p, p_error) = if g.spheres {
        let sphere = L::load(g.sphere).gt(zero);
        (
            V3::select(sphere, V3::load(&g.sphere_p), p),
            V3::select(sphere, V3::load(&g.sphere_error), p_error),
        )
    } else {
        (p, p_error)
    };
    // `interaction`'s floor: spawned rays clear the tree's padded boxes.
    let floor = L::splat(g.spawn_floor);
    let p_error = V3 {
        x: p_error.x.max(floor),
        y: p_error.y.max(floor),
        z: p_error.z.max(floor),
    };
    // `triangle_interaction`'s shading normal: the vertices' normals
    // interpolated and normalised, the geometric one where that gives zero.
    let n = V3::load(&g.n);
    let ns = if g.smooth {
        let vn = [V3::load(&g.vn[0]), V3::load(&g.vn[1]), V3::load(&g.vn[2])];
        interpolated_normal(vn, b1, b2, n)
    } else {
        n
    };
    // `interaction::finish`: normals toward the ray, the shading normal folded
    // back where it is not above the surface, the frame.
    let (ng, ns, _) = face_ray(dir, n, ns);
    let frame = LaneFrame::from_normal(ns);
    let wo = frame.to_local(dir.neg());
    Hit8 {
        p,
        p_error,
        ng,
        frame,
        wo,
    }
}

/// The lanes' light samples (`LightSet::sample` → `sample_area_point`; the
/// other lights' drawn before the kernel, or a constant sky's mapped here).
#[inline(always)]
fn light8<L: Lanes8>(g: &Gathered, h: &Hit8<L>) -> Light8<L> {
    let zero = L::splat(0.0);
    let kind = L::load(g.kind);
    let w = V3::<L>::load(&g.light_w);
    let q = V3::load(&g.light[0])
        .mul(w.x)
        .add(V3::load(&g.light[1]).mul(w.y))
        .add(V3::load(&g.light[2]).mul(w.z));
    let kind_is = |k: LightKind| kind.eq(L::splat(k as u32 as f32));
    // A drawn point's lanes (a sphere light's sample).
    let q = if g.other_lights {
        V3::select(kind_is(LightKind::DrawnPoint), V3::load(&g.drawn_q), q)
    } else {
        q
    };
    // `sample_area_point`, then `LightSet::sample`'s pick and checks.
    let (d, wi, pdf, defined) = area_point_pdf(q, V3::load(&g.light_n), L::load(g.light_area), h.p);
    let light_pdf = pdf * L::load(g.light_pick);
    let sampled = kind_is(LightKind::Area)
        .and(defined)
        .and(light_pdf.gt(zero))
        .and(light_pdf.is_finite());
    if !g.other_lights {
        return Light8 {
            q,
            d,
            wi,
            pdf: light_pdf,
            sampled,
            unbounded: zero.ne(zero),
        };
    }
    // The other lights' lanes: a sample drawn before the kernel (its
    // density checked there), or a constant sky's cosine-weighted direction
    // in this frame (`LightSet::sample_env`).
    let drawn = kind_is(LightKind::Drawn).or(kind_is(LightKind::DrawnPoint));
    let in_frame = kind_is(LightKind::EnvInFrame);
    let wi_frame = h.frame.to_world(cosine_hemisphere(
        L::load(g.u_light[0]),
        L::load(g.u_light[1]),
    ));
    // `env_pdf`'s cosine density, then the pick.
    let pdf_frame = cosine_hemisphere_pdf_z(wi_frame.dot(h.frame.n)) * L::load(g.light_pick);
    let other = drawn.or(in_frame);
    let wi_other = V3::select(drawn, V3::load(&g.drawn_wi), wi_frame);
    let pdf_other = drawn.select(L::load(g.drawn_pdf), pdf_frame);
    let frame_ok = in_frame.and(pdf_frame.gt(zero)).and(pdf_frame.is_finite());
    Light8 {
        q,
        d,
        wi: V3::select(other, wi_other, wi),
        pdf: other.select(pdf_other, light_pdf),
        sampled: drawn.or(frame_ok).or(sampled),
        unbounded: kind_is(LightKind::Drawn).or(in_frame),
    }
}

/// The shadow rays: `spawn_ray_to` (both ends offset, then
/// `SurfacePoint::segment`); toward the environment `spawn_ray`, unbounded.
#[inline(always)]
fn shadow8<L: Lanes8>(g: &Gathered, h: &Hit8<L>, light: &Light8<L>) -> (V3<L>, V3<L>, L) {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let (q, d) = (light.q, light.d);
    let shadow_o = offset_ray_origin(
        h.p,
        h.p_error,
        h.ng,
        V3::select(light.unbounded, light.wi, d),
    );
    // `offset_ray_origin`'s default error bound, for a light's point.
    let shadow_end = offset_ray_origin(q, default_error_of(q), V3::load(&g.light_n), d.neg());
    let (dir, t, empty) = segment_to(shadow_o, shadow_end);
    // `SurfacePoint::segment`'s empty segment.
    let shadow_d = V3::select(
        empty,
        V3 {
            x: zero,
            y: zero,
            z: one,
        },
        dir,
    );
    let shadow_t = empty.select(zero, t);
    (
        shadow_o,
        V3::select(light.unbounded, light.wi, shadow_d),
        light.unbounded.select(L::splat(f32::INFINITY), shadow_t),
    )
}
