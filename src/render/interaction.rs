//! Ray hit → local surface description: position, geometric and shading normals,
//! (u, v) and its tangents, material, emission. Bump maps perturb the shading normal
//! here, and only on shapes that have one.

use crate::accel::{
    sphere_point, triangle_normal, triangle_point_with_normal, Accel, Hit, PrimRef, SurfacePoint,
};
use crate::math::lanes::{Lanes, Vector3};
use crate::math::{cross, Frame, Ray, Vec2, Vec3};
use crate::scene::Scene;
use std::f32::consts::{PI, TAU};

/// Everything shading needs at a hit point. Normals face the side the ray came
/// from (materials are two-sided); `front_face` records whether that is the side
/// the geometric normal originally pointed to (emission is one-sided).
#[derive(Clone, Copy, Debug)]
pub struct Interaction {
    pub p: Vec3,
    /// Absolute error bound of `p` per axis (pbrt-v4 §6.8): how far rays leaving
    /// the surface are offset ([`Interaction::spawn_ray`]).
    pub p_error: Vec3,
    pub t: f32,
    /// Geometric normal, flipped to face the incoming ray.
    pub ng: Vec3,
    /// Shading frame: interpolated/bumped normal, flipped like `ng`.
    pub frame: Frame,
    pub uv: Vec2,
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    pub front_face: bool,
    pub material: u32,
    /// Emitted radiance toward the ray origin (zero unless an emitter seen from its front).
    pub emission: Vec3,
    pub object_id: u32,
    pub prim: PrimRef,
}

/// Builds the [`Interaction`] of `hit` along `ray` (`accel`: the structure
/// that found it, built over `scene`).
pub fn interaction(scene: &Scene, accel: &Accel, ray: &Ray, hit: &Hit) -> Interaction {
    let mut si = match hit.prim {
        PrimRef::Triangle { mesh, tri } => triangle_interaction(scene, accel, ray, hit, mesh, tri),
        PrimRef::Sphere(i) => sphere_interaction(scene, ray, hit, i),
    };
    // Spawned rays clear the tree's padded boxes (`Accel::spawn_floor`).
    si.p_error = accel.spawn_error(si.p_error);
    si
}

fn triangle_interaction(
    scene: &Scene,
    accel: &Accel,
    ray: &Ray,
    hit: &Hit,
    mesh: u32,
    tri: u32,
) -> Interaction {
    let m = &scene.meshes[mesh as usize];
    // The vertices from the leaf block the traversal has just read (in cache)
    // rather than through the index buffer: on a large mesh those were two
    // dependent cache misses per hit. The indices only for normals and uvs.
    let index = || m.triangles[tri as usize].map(|i| i as usize);
    // With the unit normal the accel computed at build time.
    let ([p0, p1, p2], n) = accel.hit_triangle(hit).unwrap_or_else(|| {
        let v = index().map(|i| m.positions[i]);
        (v, triangle_normal(v))
    });
    let (b1, b2) = (hit.bary.x, hit.bary.y);
    let b0 = 1.0 - b1 - b2;
    // Interpolating the vertices is more accurate than o + t·d far from the
    // origin; the accel's routine also bounds its error.
    let sp = triangle_point_with_normal([p0, p1, p2], hit.bary, n);
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let ng_orig = sp.n_geo;
    let ns_orig = if m.normals.is_empty() {
        ng_orig
    } else {
        let [i0, i1, i2] = index();
        interpolated_normal(
            [m.normals[i0], m.normals[i1], m.normals[i2]],
            wide::f32x4::splat(b1),
            wide::f32x4::splat(b2),
            ng_orig,
        )
    };
    // (u, v) parameterisation: texture coordinates when present, else barycentric.
    let (uv, dpdu, dpdv) = if m.uvs.is_empty() {
        (Vec2::new(b1, b2), e1, e2)
    } else {
        let [i0, i1, i2] = index();
        let (t0, t1, t2) = (m.uvs[i0], m.uvs[i1], m.uvs[i2]);
        let uv = b0 * t0 + b1 * t1 + b2 * t2;
        let d1 = t1 - t0;
        let d2 = t2 - t0;
        let det = d1.x * d2.y - d1.y * d2.x;
        if det.abs() < 1e-12 {
            (uv, e1, e2)
        } else {
            let inv = 1.0 / det;
            (
                uv,
                (d2.y * e1 - d1.y * e2) * inv,
                (-d2.x * e1 + d1.x * e2) * inv,
            )
        }
    };
    finish(
        scene,
        ray,
        hit.t,
        &sp,
        ns_orig,
        uv,
        dpdu,
        dpdv,
        m.material,
        m.emission,
        m.bump,
        m.object_id,
        hit.prim,
    )
}

/// A triangle's shading normal: the vertices' normals `n` weighted by the
/// barycentrics (b0, b1, b2) and normalised (glam's `normalize_or_zero`),
/// the geometric `ng` where that is zero; on one hit or on the lane kernel's
/// eight. The select reads `normalize_or_zero`'s own test (1/|s| finite and
/// positive): where it holds, s/|s| has a component of at least ~1/√3, so
/// it is zero exactly where that test fails.
#[inline(always)]
pub(crate) fn interpolated_normal<V: Vector3>(n: [V; 3], b1: V::L, b2: V::L, ng: V) -> V {
    let zero = V::L::splat(0.0);
    let one = V::L::splat(1.0);
    let b0 = one - b1 - b2;
    let s = n[0].scale(b0).sum(n[1].scale(b1)).sum(n[2].scale(b2));
    let rcp = one / s.dot(s).sqrt();
    let unit = rcp.is_finite().and(rcp.gt(zero));
    s.scale(rcp).zip(
        ng,
        #[inline(always)]
        |s, g| unit.select(s, g),
    )
}

fn sphere_interaction(scene: &Scene, ray: &Ray, hit: &Hit, i: u32) -> Interaction {
    let s = &scene.spheres[i as usize];
    // Re-projected onto the surface: removes the error of o + t·d.
    let surface = sphere_point(s.center, s.radius, ray.at(hit.t));
    let n = surface.n_geo;
    // (u, v) = (φ / 2π, θ / π), θ from +y, φ = atan2(z, x).
    let theta = n.y.clamp(-1.0, 1.0).acos();
    let mut phi = n.z.atan2(n.x);
    if phi < 0.0 {
        phi += TAU;
    }
    let (sp, cp) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    let dpdphi = s.radius * Vec3::new(-st * sp, 0.0, st * cp);
    let dpdtheta = s.radius * Vec3::new(ct * cp, -st, ct * sp);
    let uv = Vec2::new(phi / TAU, theta / PI);
    finish(
        scene,
        ray,
        hit.t,
        &surface,
        n,
        uv,
        TAU * dpdphi,
        PI * dpdtheta,
        s.material,
        s.emission,
        s.bump,
        s.object_id,
        hit.prim,
    )
}

/// The geometric and shading normals turned toward the ray `dir` comes
/// along (two-sided materials), the shading normal folded back onto the
/// geometric one where it is not above it (on the far side it would let
/// light leak): on one hit, or on the lane kernel's eight. The mask: the
/// front faces.
#[inline(always)]
pub(crate) fn face_ray<V: Vector3>(dir: V, ng: V, ns: V) -> (V, V, V::L) {
    let zero = V::L::splat(0.0);
    let one = V::L::splat(1.0);
    let front = dir.dot(ng).lt(zero);
    let sign = front.select(one, -one);
    let ng = ng.map(
        #[inline(always)]
        |c| c * sign,
    );
    let ns = ns.map(
        #[inline(always)]
        |c| c * sign,
    );
    let fold = ns.dot(ng).le(V::L::splat(1e-4));
    let ns = ns.zip(
        ng,
        #[inline(always)]
        |s, g| fold.select(g, s),
    );
    (ng, ns, front)
}

/// Shared tail: applies the bump map, orients normals toward the ray, builds the frame.
/// Inlined into both shapes' set-up: called, its dozen arguments and 144-byte
/// result went through the stack on every hit.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn finish(
    scene: &Scene,
    ray: &Ray,
    t: f32,
    sp: &SurfacePoint,
    ns_orig: Vec3,
    uv: Vec2,
    dpdu: Vec3,
    dpdv: Vec3,
    material: u32,
    emission: Vec3,
    bump: Option<u32>,
    object_id: u32,
    prim: PrimRef,
) -> Interaction {
    let mut ns = ns_orig;
    if let Some(b) = bump {
        ns = bumped_normal(&scene.bumps[b as usize], uv, ns, dpdu, dpdv);
    }
    let (ng, ns, front) = face_ray(ray.dir, sp.n_geo, ns);
    let front_face = front.bitmask() & 1 != 0;
    // The frame is a function of the normal alone, continuous across a mesh:
    // samples stratified over a pixel (BSDF and cosine-sky directions) stay
    // stratified across the triangles the pixel covers. A frame aligned with
    // each triangle's dpdu turned every triangle's mapping by its own angle and
    // scattered them (bunny RMSE +8 %). Every BSDF here is isotropic, so the
    // tangent's direction is otherwise free.
    let frame = Frame::from_normal(ns);
    Interaction {
        p: sp.p,
        p_error: sp.p_error,
        t,
        ng,
        frame,
        uv,
        dpdu,
        dpdv,
        front_face,
        material,
        emission: if front_face { emission } else { Vec3::ZERO },
        object_id,
        prim,
    }
}

/// Normal of the displaced surface p + h(u,v)·n, to first order in h:
/// ∂p'/∂u ≈ ∂p/∂u + h_u n and ∂p'/∂v ≈ ∂p/∂v + h_v n (the h·∂n/∂u term is dropped,
/// as in pbrt, since bump heights are small against the radius of curvature).
pub fn bumped_normal(bump: &crate::scene::Bump, uv: Vec2, n: Vec3, dpdu: Vec3, dpdv: Vec3) -> Vec3 {
    let j = bump.eval(uv);
    let pu = dpdu + j.h_u * n;
    let pv = dpdv + j.h_v * n;
    let nb = cross(pu, pv).normalize_or_zero();
    if nb == Vec3::ZERO || !nb.is_finite() {
        return n;
    }
    // Keep the orientation of the unbumped normal whatever the handedness of (u, v).
    if nb.dot(n) < 0.0 {
        -nb
    } else {
        nb
    }
}

impl Interaction {
    /// The hit as the accel's robust spawning point (`accel::offset`, pbrt-v4
    /// §6.8.6): the one ray-offset mechanism of the renderer.
    pub fn surface(&self) -> SurfacePoint {
        SurfacePoint {
            p: self.p,
            p_error: self.p_error,
            n_geo: self.ng,
        }
    }

    /// A ray leaving the surface along the unit direction `dir`, its origin
    /// moved off the surface by `p`'s error bound (t_min = 0, no self-hit).
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        self.surface().spawn_ray_unit(dir)
    }

    /// A shadow ray to `target` on another surface (normal `target_n`), both
    /// ends offset, stopping short of the target.
    pub fn spawn_ray_to(&self, target: Vec3, target_n: Vec3) -> Ray {
        self.surface()
            .spawn_ray_to(&SurfacePoint::with_default_error(target, target_n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `interpolated_normal` selects on `normalize_or_zero`'s own test: it
    /// gives the bits of the former `normalize_or_zero`, then `== ZERO`,
    /// on zero, denormal, tiny, huge (overflowing), infinite and NaN sums.
    #[test]
    fn interpolated_normal_is_normalize_or_zero_then_the_zero_test() {
        let ng = Vec3::new(0.0, 0.6, 0.8);
        let vs = [
            Vec3::ZERO,
            Vec3::new(1e-23, 0.0, 0.0),
            Vec3::new(1e-20, -1e-21, 0.0),
            Vec3::new(1e-45, 0.0, -1e-45),
            Vec3::new(3e38, 3e38, 0.0),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(f32::NAN, 1.0, 0.0),
            Vec3::new(0.3, -0.2, 0.9),
            Vec3::new(-0.0, 0.0, -0.0),
        ];
        for (k, &a) in vs.iter().enumerate() {
            let b = vs[(k + 1) % vs.len()];
            let c = vs[(k + 4) % vs.len()];
            for (b1, b2) in [(0.0, 0.0), (0.25, 0.5), (1.0, 0.0), (0.1, 0.7)] {
                let b0 = 1.0 - b1 - b2;
                let n = (b0 * a + b1 * b + b2 * c).normalize_or_zero();
                let old = if n == Vec3::ZERO { ng } else { n };
                let new = interpolated_normal(
                    [a, b, c],
                    wide::f32x4::splat(b1),
                    wide::f32x4::splat(b2),
                    ng,
                );
                assert!(
                    (0..3).all(|i| old[i].to_bits() == new[i].to_bits()),
                    "{a} {b} {c} ({b1}, {b2}): {old} vs {new}"
                );
            }
        }
    }
}
