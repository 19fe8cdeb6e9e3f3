//! The lane kernel: eight path vertices shaded at once, each lane the
//! operations of `interaction`, `LightSet::sample`, the Lambertian
//! `Material::eval`/`pdf`/`sample`, `power_heuristic` and `accel::offset` in
//! their order (so a lane's bits are the scalar code's), over any [`Lanes`].

use super::simd::Lanes;
use super::{Gathered, LightKind, Rows, LANES};

/// Three planes of lanes: eight vectors.
#[derive(Clone, Copy)]
struct V8<L> {
    x: L,
    y: L,
    z: L,
}

impl<L: Lanes> V8<L> {
    #[inline(always)]
    fn splat(v: L) -> Self {
        Self { x: v, y: v, z: v }
    }
    #[inline(always)]
    fn load(rows: &Rows) -> Self {
        let [x, y, z] = L::from_rows(rows);
        Self { x, y, z }
    }
    #[inline(always)]
    fn store(self) -> Rows {
        L::to_rows([self.x, self.y, self.z])
    }
    /// glam's order: (x·x' + y·y') + z·z'.
    #[inline(always)]
    fn dot(self, o: Self) -> L {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    #[inline(always)]
    fn mul(self, s: L) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    fn mul_v(self, o: Self) -> Self {
        Self {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
    #[inline(always)]
    fn div(self, s: L) -> Self {
        Self {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }
    #[inline(always)]
    fn is_finite(self) -> L {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }
    /// glam's `normalize_or_zero`: times 1/|v| where that is finite and
    /// positive, else zero.
    #[inline(always)]
    fn normalize_or_zero(self) -> Self {
        let zero = L::splat(0.0);
        let rcp = L::splat(1.0) / self.dot(self).sqrt();
        select_v(
            rcp.is_finite() & rcp.gt(zero),
            self.mul(rcp),
            V8::splat(zero),
        )
    }
}

/// `Frame`'s basis in lanes.
struct Frame8<L> {
    s: V8<L>,
    t: V8<L>,
    n: V8<L>,
}

impl<L: Lanes> Frame8<L> {
    /// `Frame::from_normal` (Duff et al. 2017), operation for operation.
    #[inline(always)]
    fn from_normal(n: V8<L>) -> Self {
        let one = L::splat(1.0);
        let sign = n.z.is_sign_negative().select(-one, one);
        let a = -one / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            s: V8 {
                x: one + sign * n.x * n.x * a,
                y: sign * b,
                z: -sign * n.x,
            },
            t: V8 {
                x: b,
                y: sign + n.y * n.y * a,
                z: -n.y,
            },
            n,
        }
    }
    #[inline(always)]
    fn to_local(&self, v: V8<L>) -> V8<L> {
        V8 {
            x: v.dot(self.s),
            y: v.dot(self.t),
            z: v.dot(self.n),
        }
    }
    #[inline(always)]
    fn to_world(&self, v: V8<L>) -> V8<L> {
        self.s.mul(v.x).add(self.t.mul(v.y)).add(self.n.mul(v.z))
    }
}

/// `accel::offset_ray_origin_with_error` in lanes.
#[inline(always)]
fn offset8<L: Lanes>(p: V8<L>, p_error: V8<L>, n: V8<L>, dir: V8<L>) -> V8<L> {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let d = n.abs().dot(p_error);
    let offset = n.mul(d);
    let offset = select_v(dir.dot(n).lt(zero), offset.neg(), offset);
    let po = p.add(offset);
    V8 {
        x: po.x + away(offset.x, zero, one) * step(po.x),
        y: po.y + away(offset.y, zero, one) * step(po.y),
        z: po.z + away(offset.z, zero, one) * step(po.z),
    }
}

/// The offset's direction per axis: 0 where it is 0, else its sign.
#[inline(always)]
fn away<L: Lanes>(o: L, zero: L, one: L) -> L {
    o.eq(zero)
        .select(zero, o.is_sign_negative().select(-one, one))
}

/// One more ulp-sized step past the offset point.
#[inline(always)]
fn step<L: Lanes>(po: L) -> L {
    (po.abs() * L::splat(f32::EPSILON)).max(L::splat(f32::MIN_POSITIVE))
}

#[inline(always)]
fn select_v<L: Lanes>(m: L, t: V8<L>, f: V8<L>) -> V8<L> {
    V8 {
        x: m.select(t.x, f.x),
        y: m.select(t.y, f.y),
        z: m.select(t.z, f.z),
    }
}

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
    unsafe { shade8::<super::simd::Avx>(g, out) }
}

/// [`shade8`] in `wide`'s lanes, which any build's CPU runs.
pub(super) fn shade8_wide(g: &Gathered, out: &mut Shaded8) {
    // SAFETY: `wide` uses only what the build targets.
    unsafe { shade8::<wide::f32x8>(g, out) }
}

/// The shading of eight hits: `interaction`, the light sample, the
/// Lambertian eval, pdf and sample, MIS and both rays' offsets, as `li` and
/// the functions it calls compute them.
///
/// # Safety
/// The CPU must run `L`'s instructions (AVX2 for `simd::Avx`): the lane
/// types' methods are safe functions that do not check.
#[inline(always)]
unsafe fn shade8<L: Lanes>(g: &Gathered, out: &mut Shaded8) {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let frac_1_pi = L::splat(std::f32::consts::FRAC_1_PI);
    let dir = V8::<L>::load(&g.dir);
    let (b1, b2) = (L::load(g.bary[0]), L::load(g.bary[1]));
    // `triangle_point_with_normal`: the vertices weighted, and the error bound.
    let b0 = one - b1 - b2;
    let t0 = V8::load(&g.v[0]).mul(b0);
    let t1 = V8::load(&g.v[1]).mul(b1);
    let t2 = V8::load(&g.v[2]).mul(b2);
    let p = t0.add(t1).add(t2);
    let gamma7 = L::splat(crate::accel::gamma_bound(7));
    let p_error = t0.abs().add(t1.abs()).add(t2.abs()).mul(gamma7);
    // A sphere's lanes: `sphere_point`'s, computed while gathering.
    let (p, p_error) = if g.spheres {
        let sphere = L::load(g.sphere).gt(zero);
        (
            select_v(sphere, V8::load(&g.sphere_p), p),
            select_v(sphere, V8::load(&g.sphere_error), p_error),
        )
    } else {
        (p, p_error)
    };
    // `interaction`'s floor: spawned rays clear the tree's padded boxes.
    let floor = L::splat(g.spawn_floor);
    let p_error = V8 {
        x: p_error.x.max(floor),
        y: p_error.y.max(floor),
        z: p_error.z.max(floor),
    };
    // `triangle_interaction`'s shading normal: the vertices' normals
    // interpolated and normalised, the geometric one where that gives zero.
    let n = V8::load(&g.n);
    let ns = if g.smooth {
        let [n0, n1, n2] = [0, 1, 2].map(|k| V8::<L>::load(&g.vn[k]));
        let s = n0.mul(b0).add(n1.mul(b1)).add(n2.mul(b2));
        let s = s.normalize_or_zero();
        select_v(s.x.eq(zero) & s.y.eq(zero) & s.z.eq(zero), n, s)
    } else {
        n
    };
    // `interaction::finish`: normals toward the ray, the shading normal folded
    // back where it is not above the surface, the frame.
    let front = dir.dot(n).lt(zero);
    let sign = front.select(one, -one);
    let ng = n.mul(sign);
    let ns = ns.mul(sign);
    let ns = select_v(ns.dot(ng).le(L::splat(1e-4)), ng, ns);
    let frame = Frame8::from_normal(ns);
    let wo = frame.to_local(dir.neg());
    let alive = wo.z.gt(zero);
    let albedo = V8::load(&g.albedo);
    let beta = V8::load(&g.beta);

    // The light sample (`LightSet::sample` → `sample_area_point`).
    let kind = L::load(g.kind);
    let w = V8::load(&g.light_w);
    let q = V8::load(&g.light[0])
        .mul(w.x)
        .add(V8::load(&g.light[1]).mul(w.y))
        .add(V8::load(&g.light[2]).mul(w.z));
    let kind_is = |k: LightKind| kind.eq(L::splat(k as u32 as f32));
    // A drawn point's lanes (a sphere light's sample).
    let q = if g.other_lights {
        select_v(kind_is(LightKind::DrawnPoint), V8::load(&g.drawn_q), q)
    } else {
        q
    };
    let d = q.sub(p);
    let dist2 = d.dot(d);
    let area = L::load(g.light_area);
    let wi = d.div(dist2.sqrt());
    let ln = V8::load(&g.light_n);
    let cos_l = -ln.dot(wi);
    let light_pdf = dist2 / (area * cos_l) * L::load(g.light_pick);
    let sampled = kind_is(LightKind::Area)
        & dist2.gt(zero)
        & area.gt(zero)
        & cos_l.gt(zero)
        & light_pdf.gt(zero)
        & light_pdf.is_finite();
    // The other lights' lanes: a sample drawn before the kernel (its
    // density checked there), or a constant sky's cosine-weighted direction
    // in this frame (`LightSet::sample_env`).
    let (unbounded, wi, light_pdf, sampled) = if g.other_lights {
        let drawn = kind_is(LightKind::Drawn) | kind_is(LightKind::DrawnPoint);
        let in_frame = kind_is(LightKind::EnvInFrame);
        let wi_frame = frame.to_world(cosine_hemisphere8(
            L::load(g.u_light[0]),
            L::load(g.u_light[1]),
        ));
        // `env_pdf`'s cosine density, then the pick.
        let pdf_frame = wi_frame.dot(frame.n).max(zero) * frac_1_pi * L::load(g.light_pick);
        let other = drawn | in_frame;
        let wi_other = select_v(drawn, V8::load(&g.drawn_wi), wi_frame);
        let pdf_other = drawn.select(L::load(g.drawn_pdf), pdf_frame);
        (
            kind_is(LightKind::Drawn) | in_frame,
            select_v(other, wi_other, wi),
            other.select(pdf_other, light_pdf),
            drawn | in_frame & pdf_frame.gt(zero) & pdf_frame.is_finite() | sampled,
        )
    } else {
        (zero.ne(zero), wi, light_pdf, sampled)
    };
    // `Material::eval` (Lambert) and the checks of `sample_ld`.
    let wil = frame.to_local(wi);
    let upper = wo.is_finite() & wil.is_finite() & wo.z.gt(zero) & wil.z.gt(zero);
    let f = albedo.mul(frac_1_pi);
    let f_nonzero = f.x.ne(zero) | f.y.ne(zero) | f.z.ne(zero);
    let direct = alive & sampled & upper & wi.dot(ng).gt(zero) & f_nonzero;
    // `Material::pdf` (Lambert): wi's z normalised at f64, as `unit_z` does.
    let bsdf_pdf = L::load(lambert_pdf8([wil.x.store(), wil.y.store(), wil.z.store()]));
    let weight_mis = power_heuristic8(light_pdf, bsdf_pdf);
    let le = V8::load(&g.light_le);
    let ld = beta
        .mul_v(f)
        .mul(wil.z)
        .mul_v(le)
        .mul(weight_mis / light_pdf);
    // `spawn_ray_to`: both ends offset, then `SurfacePoint::segment`; toward
    // the environment `spawn_ray`, unbounded.
    let shadow_o = offset8(p, p_error, ng, select_v(unbounded, wi, d));
    let q_error = {
        let m = q.x.abs().max(q.y.abs()).max(q.z.abs());
        let e = m * L::splat(crate::accel::DEFAULT_REL_ERROR) + L::splat(1.0e-30);
        V8 { x: e, y: e, z: e }
    };
    let shadow_end = offset8(q, q_error, ln, d.neg());
    let span = shadow_end.sub(shadow_o);
    let len = span.dot(span).sqrt();
    // Not positive (NaN included) or infinite.
    let degenerate = len.gt(zero).select(len.is_inf(), zero.eq(zero));
    let shadow_d = select_v(
        degenerate,
        V8 {
            x: zero,
            y: zero,
            z: one,
        },
        span.div(len),
    );
    let shadow_t = degenerate.select(zero, len * L::splat(1.0 - crate::accel::SHADOW_EPSILON));
    let shadow_d = select_v(unbounded, wi, shadow_d);
    let shadow_t = unbounded.select(L::splat(f32::INFINITY), shadow_t);

    // The BSDF sample (`lambert::sample`).
    let local = cosine_hemisphere8(L::load(g.u_dir[0]), L::load(g.u_dir[1]));
    let pdf = local.z.gt(zero).select(local.z * frac_1_pi, zero);
    let (direct, local, pdf, sampled_dir) = if g.mirrors {
        // A mirror's lanes (`mirror::sample`): no light sample (a delta
        // lobe), the reflection about the normal, an infinite density (the
        // next emitter counts in full).
        let mirror = L::load(g.mirror).gt(zero);
        let reflected = V8 {
            x: -wo.x,
            y: -wo.y,
            z: wo.z,
        }
        .normalize_or_zero();
        (
            mirror.select(zero.ne(zero), direct),
            select_v(mirror, reflected, local),
            mirror.select(L::splat(f32::INFINITY), pdf),
            mirror.select(reflected.z.gt(zero), pdf.gt(zero)),
        )
    } else {
        (direct, local, pdf, pdf.gt(zero))
    };
    let wi_next = frame.to_world(local);
    // (`continue_path` also asks for a finite weight: the albedo was
    // sanitised when the lane scene was built.)
    let next = alive & sampled_dir & wi_next.dot(ng).gt(zero);
    let next_o = offset8(p, p_error, ng, wi_next);
    *out = Shaded8 {
        alive: alive.bitmask(),
        p: p.store(),
        normal: frame.n.store(),
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

/// `warp::square_to_cosine_hemisphere` in lanes: the concentric map, z from
/// its radius.
#[inline(always)]
fn cosine_hemisphere8<L: Lanes>(u0: L, u1: L) -> V8<L> {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let ox = L::splat(2.0) * u0 - one;
    let oy = L::splat(2.0) * u1 - one;
    let centre = ox.eq(zero) & oy.eq(zero);
    let x_major = ox.abs().gt(oy.abs());
    let r = x_major.select(ox, oy);
    let other = x_major.select(oy, ox);
    let (s, c) = sin_cos_quarter8(L::splat(std::f32::consts::FRAC_PI_4) * (other / r));
    let (cos, sin) = (x_major.select(c, s), x_major.select(s, c));
    let r = centre.select(zero, r);
    let rr = r.abs();
    V8 {
        x: centre.select(zero, r * cos),
        y: centre.select(zero, r * sin),
        z: (one - rr * rr).max(zero).sqrt(),
    }
}

/// `warp::sin_cos_quarter` in lanes, operation for operation.
#[inline(always)]
fn sin_cos_quarter8<L: Lanes>(x: L) -> (L, L) {
    let z = x * x;
    let s = ((L::splat(-1.951_529_6e-4) * z + L::splat(8.332_161e-3)) * z
        - L::splat(1.666_665_5e-1))
        * z
        * x
        + x;
    let c = ((L::splat(2.443_315_7e-5) * z - L::splat(1.388_731_6e-3)) * z
        + L::splat(4.166_664_6e-2))
        * z
        * z
        - L::splat(0.5) * z
        + L::splat(1.0);
    (s, c)
}

/// `path::power_heuristic` in lanes.
#[inline(always)]
fn power_heuristic8<L: Lanes>(f: L, g: L) -> L {
    let (f2, g2) = (f * f, g * g);
    let sum = f2 + g2;
    f2.is_inf().select(
        L::splat(1.0),
        sum.le(L::splat(0.0)).select(L::splat(0.0), f2 / sum),
    )
}

/// `Material::pdf` of a Lambertian for a direction above the horizon (the
/// caller masks the rest): cos θ normalised at f64, over π, made finite.
#[inline(always)]
fn lambert_pdf8(v: [[f32; LANES]; 3]) -> [f32; LANES] {
    std::array::from_fn(|l| {
        let (x, y, z) = (f64::from(v[0][l]), f64::from(v[1][l]), f64::from(v[2][l]));
        let len2 = x * x + y * y + z * z;
        let p = (z / len2.sqrt() * std::f64::consts::FRAC_1_PI) as f32;
        if p > 0.0 && p.is_finite() {
            p
        } else {
            0.0
        }
    })
}
