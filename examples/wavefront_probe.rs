//! Probe (issue 16, not a lever): what would an 8-wide SIMD shading stage save?
//!
//! Real cornell hits (rays from points inside the box, as `accel`'s cornell rays)
//! are shaded twice with the same random numbers, queries excluded:
//! - scalar: the path tracer's own per-vertex work (`interaction`, the light
//!   sample, BSDF eval/pdf, MIS, the BSDF sample, the continuation and shadow
//!   rays' origins), one hit at a time, as `PathTracer::li` does it;
//! - lanes: the same arithmetic on eight hits at once (AVX2 through `wide`'s
//!   f32x8: build with `RUSTFLAGS="-C target-cpu=x86-64-v3"`), the hit data
//!   gathered from per-triangle tables, as a wavefront's shading kernel would.
//!
//! Prints ns per vertex for both and the largest difference of their outputs.
//! Run: `RUSTFLAGS="-C target-cpu=x86-64-v3" cargo run --release --example wavefront_probe`

use gradtrace::accel::{Accel, PrimRef};
use gradtrace::math::{Ray, Vec2, Vec3};
use gradtrace::render::interaction::interaction;
use gradtrace::render::lights::LightSet;
use gradtrace::render::path::power_heuristic;
use gradtrace::scene;
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;
use wide::{f32x8, i32x8};

#[derive(Default, Clone, Copy)]
struct Out {
    ld: [f32; 3],
    shadow_o: [f32; 3],
    shadow_d: [f32; 3],
    shadow_t: f32,
    next_o: [f32; 3],
    next_d: [f32; 3],
    beta: [f32; 3],
}

fn xorshift(s: &mut u64) -> f32 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    (*s >> 40) as f32 / (1u64 << 24) as f32
}

fn main() {
    let scene = scene::load(Path::new("scenes/validation/cornell_256.toml")).expect("scene");
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let lights = LightSet::build(&scene);
    let emitter = scene
        .meshes
        .iter()
        .position(|m| m.emission != Vec3::ZERO)
        .expect("an emitter");
    let rect = scene.meshes[emitter].rect.expect("a rectangle light");
    let (lo, hi) = accel.bounds().expect("not empty");

    // Per-triangle tables (what a wavefront's gather reads) and the hits.
    let mut first = vec![0u32];
    for m in &scene.meshes {
        first.push(first.last().unwrap() + m.triangles.len() as u32);
    }
    let ntri = *first.last().unwrap() as usize;
    let mut tab = vec![vec![0f32; ntri]; 15];
    for (mi, m) in scene.meshes.iter().enumerate() {
        let albedo = match scene.materials[m.material as usize] {
            gradtrace::brdf::Material::Lambert { albedo } => albedo,
            _ => panic!("cornell is Lambertian"),
        };
        for (ti, t) in m.triangles.iter().enumerate() {
            let g = first[mi] as usize + ti;
            let v = t.map(|i| m.positions[i as usize]);
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            let vals = [
                v[0].x, v[0].y, v[0].z, v[1].x, v[1].y, v[1].z, v[2].x, v[2].y, v[2].z, n.x, n.y,
                n.z, albedo.x, albedo.y, albedo.z,
            ];
            for (k, x) in vals.into_iter().enumerate() {
                tab[k][g] = x;
            }
        }
    }

    let n = 1 << 16;
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut recs: Vec<(Ray, gradtrace::accel::Hit, u32, [f32; 6])> = Vec::with_capacity(n);
    while recs.len() < n {
        let f = |s: &mut u64| Vec3::new(xorshift(s), xorshift(s), xorshift(s));
        let o = lo + (hi - lo) * (0.05 + 0.9 * f(&mut seed));
        let d = (f(&mut seed) * 2.0 - Vec3::ONE).normalize_or_zero();
        if d.length_squared() < 0.5 {
            continue;
        }
        let ray = Ray::new(o, d);
        let Some(hit) = accel.intersect(&ray) else {
            continue;
        };
        let PrimRef::Triangle { mesh, tri } = hit.prim else {
            continue;
        };
        if mesh as usize == emitter {
            continue;
        }
        let u = [(); 6].map(|_| xorshift(&mut seed));
        recs.push((ray, hit, first[mesh as usize] + tri, u));
    }

    // Scalar: the path tracer's per-vertex work.
    let scalar = |out: &mut [Out]| {
        for ((ray, hit, _, u), o) in recs.iter().zip(out.iter_mut()) {
            let si = interaction(&scene, &accel, ray, hit);
            let material = &scene.materials[si.material as usize];
            let wo = si.frame.to_local(-ray.dir);
            if wo.z <= 0.0 {
                *o = Out::default();
                continue;
            }
            let bs = material.sample(wo, u[3], Vec2::new(u[4], u[5]));
            let mut r = Out::default();
            if let Some(ls) = lights.sample(&scene, si.p, &si.frame, 0.5, Vec2::new(u[1], u[2])) {
                let wi_local = si.frame.to_local(ls.wi);
                let f = material.eval(wo, wi_local);
                if wi_local.z > 0.0 && ls.wi.dot(si.ng) > 0.0 && f != Vec3::ZERO {
                    let (q, qn) = ls.point.unwrap();
                    let sr = si.spawn_ray_to(q, qn);
                    let w = power_heuristic(ls.pdf, material.pdf(wo, wi_local));
                    let ld = f * wi_local.z * ls.radiance * (w / ls.pdf);
                    r.ld = ld.to_array();
                    r.shadow_o = sr.origin.to_array();
                    r.shadow_d = sr.dir.to_array();
                    r.shadow_t = sr.t_max;
                }
            }
            if let Some(bs) = bs {
                let wi = si.frame.to_world(bs.wi);
                if wi.dot(si.ng) > 0.0 && bs.weight.is_finite() {
                    let next = si.spawn_ray(wi);
                    r.next_o = next.origin.to_array();
                    r.next_d = next.dir.to_array();
                    r.beta = bs.weight.to_array();
                }
            }
            *o = r;
        }
    };

    // Lanes: the hits as a wavefront's queue holds them (SoA), shaded eight at a time.
    let soa = |k: usize| -> Vec<f32> {
        recs.iter()
            .map(|(ray, hit, _, u)| match k {
                0..=2 => ray.dir.to_array()[k],
                3 => hit.bary.x,
                4 => hit.bary.y,
                _ => u[k - 5],
            })
            .collect()
    };
    let q: Vec<Vec<f32>> = (0..11).map(soa).collect();
    let tri: Vec<i32> = recs.iter().map(|r| r.2 as i32).collect();
    let light = (
        rect.corner,
        rect.edge_u,
        rect.edge_v,
        rect.normal(),
        rect.area(),
    );
    let le = scene.meshes[emitter].emission;
    let lanes = |out: &mut [Out]| {
        for (c, o) in out.chunks_exact_mut(8).enumerate() {
            shade8(c * 8, &q, &tri, &tab, light, le, o);
        }
    };

    let mut a = vec![Out::default(); n];
    let mut b = vec![Out::default(); n];
    scalar(&mut a);
    lanes(&mut b);
    let mut worst = 0f32;
    let mut agree = 0;
    for (x, y) in a.iter().zip(&b) {
        let fx = [x.ld, x.shadow_o, x.shadow_d, x.next_o, x.next_d, x.beta].concat();
        let fy = [y.ld, y.shadow_o, y.shadow_d, y.next_o, y.next_d, y.beta].concat();
        let d = fx
            .iter()
            .zip(&fy)
            .map(|(p, q)| (p - q).abs() / p.abs().max(1e-3))
            .fold((x.shadow_t - y.shadow_t).abs(), f32::max);
        worst = worst.max(d);
        agree += usize::from(fx == fy && x.shadow_t == y.shadow_t);
    }
    println!("{n} vertices; largest relative difference {worst:.2e}; bit-identical {agree}");
    // The sampler's part of a vertex, scalar: one path's eight dimensions
    // (`PixelSampler::block8`) at the first three bounces, as `li` reads them.
    let sample_dims = |acc: &mut f32| {
        for i in 0..n as u32 {
            let s = gradtrace::math::sampler::PixelSampler::new(i / 64, i % 64, 7);
            let d = 4 + 8 * (i % 3);
            *acc += s.block8(d)[i as usize % 8];
        }
    };
    for round in 0..5 {
        let t = Instant::now();
        let mut acc = 0.0;
        for _ in 0..10 {
            sample_dims(black_box(&mut acc));
        }
        let tsam = t.elapsed().as_secs_f64() / (10 * n) as f64;
        let t = Instant::now();
        for _ in 0..10 {
            scalar(black_box(&mut a));
        }
        let ts = t.elapsed().as_secs_f64() / (10 * n) as f64;
        let t = Instant::now();
        for _ in 0..10 {
            lanes(black_box(&mut b));
        }
        let tl = t.elapsed().as_secs_f64() / (10 * n) as f64;
        println!(
            "round {round}: sampler (scalar, incl. its set-up) {:.1} ns/vertex; shading: scalar {:.1} ns/vertex, lanes {:.1} ns/vertex, {:.2}x",
            tsam * 1e9,
            ts * 1e9,
            tl * 1e9,
            ts / tl
        );
    }
}

fn gather(table: &[f32], idx: i32x8) -> f32x8 {
    let i = idx.to_array();
    // AVX2's gather where the build has it.
    #[cfg(target_feature = "avx2")]
    unsafe {
        use std::arch::x86_64::*;
        let v =
            _mm256_i32gather_ps::<4>(table.as_ptr(), std::mem::transmute::<i32x8, __m256i>(idx));
        let _ = i;
        std::mem::transmute::<__m256, f32x8>(v)
    }
    #[cfg(not(target_feature = "avx2"))]
    f32x8::new(i.map(|k| table[k as usize]))
}

struct V3 {
    x: f32x8,
    y: f32x8,
    z: f32x8,
}

impl V3 {
    fn splat(v: Vec3) -> Self {
        Self {
            x: f32x8::splat(v.x),
            y: f32x8::splat(v.y),
            z: f32x8::splat(v.z),
        }
    }
    fn dot(&self, o: &V3) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    fn sub(&self, o: &V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    fn scale(&self, s: f32x8) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// pbrt-v4's offset (`accel::offset::offset_ray_origin_with_error`) in lanes.
fn offset8(p: &V3, e: &V3, n: &V3, dir: &V3) -> V3 {
    let d = n.x.abs() * e.x + n.y.abs() * e.y + n.z.abs() * e.z;
    let flip = dir.dot(n).simd_lt(f32x8::ZERO);
    let d = flip.select(-d, d);
    let one = |p: f32x8, n: f32x8| {
        let off = d * n;
        let po = p + off;
        let away = off.simd_eq(f32x8::ZERO).select(
            f32x8::ZERO,
            off.simd_lt(f32x8::ZERO)
                .select(f32x8::splat(-1.0), f32x8::ONE),
        );
        po + away * (po.abs() * f32x8::splat(f32::EPSILON)).max(f32x8::splat(f32::MIN_POSITIVE))
    };
    V3 {
        x: one(p.x, n.x),
        y: one(p.y, n.y),
        z: one(p.z, n.z),
    }
}

#[allow(clippy::too_many_arguments)]
fn shade8(
    at: usize,
    q: &[Vec<f32>],
    tri: &[i32],
    tab: &[Vec<f32>],
    light: (Vec3, Vec3, Vec3, Vec3, f32),
    le: Vec3,
    out: &mut [Out],
) {
    let ld8 = |k: usize| f32x8::new(q[k][at..at + 8].try_into().unwrap());
    let idx = i32x8::new(tri[at..at + 8].try_into().unwrap());
    let g = |k: usize| gather(&tab[k], idx);
    let zero = f32x8::ZERO;
    let one = f32x8::ONE;
    let dir = V3 {
        x: ld8(0),
        y: ld8(1),
        z: ld8(2),
    };
    let (b1, b2) = (ld8(3), ld8(4));
    let b0 = one - b1 - b2;
    let v0 = V3 {
        x: g(0),
        y: g(1),
        z: g(2),
    }
    .scale(b0);
    let v1 = V3 {
        x: g(3),
        y: g(4),
        z: g(5),
    }
    .scale(b1);
    let v2 = V3 {
        x: g(6),
        y: g(7),
        z: g(8),
    }
    .scale(b2);
    let p = V3 {
        x: v0.x + v1.x + v2.x,
        y: v0.y + v1.y + v2.y,
        z: v0.z + v1.z + v2.z,
    };
    let gamma7 = f32x8::splat(7.0 * f32::EPSILON * 0.5 / (1.0 - 7.0 * f32::EPSILON * 0.5));
    let err = V3 {
        x: (v0.x.abs() + v1.x.abs() + v2.x.abs()) * gamma7,
        y: (v0.y.abs() + v1.y.abs() + v2.y.abs()) * gamma7,
        z: (v0.z.abs() + v1.z.abs() + v2.z.abs()) * gamma7,
    };
    let n = V3 {
        x: g(9),
        y: g(10),
        z: g(11),
    };
    let albedo = V3 {
        x: g(12),
        y: g(13),
        z: g(14),
    };
    let front = dir.dot(&n).simd_lt(zero);
    let sgn = front.select(one, -one);
    let ng = n.scale(sgn);
    // Frame::from_normal (Duff et al. 2017).
    let s_ = ng.z.simd_lt(zero).select(-one, one);
    let a = -one / (s_ + ng.z);
    let b = ng.x * ng.y * a;
    let fs = V3 {
        x: one + s_ * ng.x * ng.x * a,
        y: s_ * b,
        z: -s_ * ng.x,
    };
    let ft = V3 {
        x: b,
        y: s_ + ng.y * ng.y * a,
        z: -ng.y,
    };
    let local = |v: &V3| V3 {
        x: v.dot(&fs),
        y: v.dot(&ft),
        z: v.dot(&ng),
    };
    let wo = local(&V3 {
        x: -dir.x,
        y: -dir.y,
        z: -dir.z,
    });
    let alive = wo.z.simd_gt(zero);

    // The light sample (one rectangle, picked with probability 1).
    let (corner, eu, ev, ln, area) = light;
    let (u1, u2) = (ld8(6), ld8(7));
    let c = V3::splat(corner);
    let (eu, ev) = (V3::splat(eu), V3::splat(ev));
    let lq = V3 {
        x: c.x + u1 * eu.x + u2 * ev.x,
        y: c.y + u1 * eu.y + u2 * ev.y,
        z: c.z + u1 * eu.z + u2 * ev.z,
    };
    let d = lq.sub(&p);
    let dist2 = d.dot(&d);
    let wi = d.scale(one / dist2.sqrt());
    let lnv = V3::splat(ln);
    let cos_l = -lnv.dot(&wi);
    let pdf_l = dist2 / (f32x8::splat(area) * cos_l);
    let wil = local(&wi);
    let f_ok = alive & cos_l.simd_gt(zero) & wil.z.simd_gt(zero) & wi.dot(&ng).simd_gt(zero);
    let inv_pi = f32x8::splat(std::f32::consts::FRAC_1_PI);
    let bsdf_pdf = wil.z / wil.dot(&wil).sqrt() * inv_pi;
    let (a2, b2_) = (pdf_l * pdf_l, bsdf_pdf * bsdf_pdf);
    let w = a2 / (a2 + b2_);
    let k = wil.z * (w / pdf_l) * inv_pi;
    let ld = V3 {
        x: f_ok.select(albedo.x * k * f32x8::splat(le.x), zero),
        y: f_ok.select(albedo.y * k * f32x8::splat(le.y), zero),
        z: f_ok.select(albedo.z * k * f32x8::splat(le.z), zero),
    };
    // The shadow segment, both ends offset.
    let so = offset8(&p, &err, &ng, &d);
    let lerr_s = lq.x.abs().max(lq.y.abs()).max(lq.z.abs()) * f32x8::splat(1.0 / 262_144.0)
        + f32x8::splat(1.0e-30);
    let lerr = V3 {
        x: lerr_s,
        y: lerr_s,
        z: lerr_s,
    };
    let neg_d = V3 {
        x: -d.x,
        y: -d.y,
        z: -d.z,
    };
    let end = offset8(&lq, &lerr, &lnv, &neg_d);
    let sd = end.sub(&so);
    let len = sd.dot(&sd).sqrt();
    let sdir = sd.scale(one / len);
    let st = len * f32x8::splat(1.0 - 1.0e-4);

    // The BSDF sample: the concentric map and its cosine-weighted z.
    let ox = f32x8::splat(2.0) * ld8(9) - one;
    let oy = f32x8::splat(2.0) * ld8(10) - one;
    let xm = ox.abs().simd_gt(oy.abs());
    let r = xm.select(ox, oy);
    let other = xm.select(oy, ox);
    let x = f32x8::splat(std::f32::consts::FRAC_PI_4) * (other / r);
    let x2 = x * x;
    let sin = x + x
        * x2
        * (f32x8::splat(-1.666_665_5e-1)
            + x2 * (f32x8::splat(8.332_161e-3) + x2 * f32x8::splat(-1.951_529_6e-4)));
    let cos = one - f32x8::splat(0.5) * x2
        + x2 * x2
            * (f32x8::splat(4.166_664_6e-2)
                + x2 * (f32x8::splat(-1.388_731_6e-3) + x2 * f32x8::splat(2.443_315_7e-5)));
    let (cs, sn) = (xm.select(cos, sin), xm.select(sin, cos));
    let lx = r * cs;
    let ly = r * sn;
    let lz = (one - r * r).max(zero).sqrt();
    let nwi = V3 {
        x: fs.x * lx + ft.x * ly + ng.x * lz,
        y: fs.y * lx + ft.y * ly + ng.y * lz,
        z: fs.z * lx + ft.z * ly + ng.z * lz,
    };
    let cont = alive & lz.simd_gt(zero) & nwi.dot(&ng).simd_gt(zero);
    let no = offset8(&p, &err, &ng, &nwi);

    let planes = [
        ld.x,
        ld.y,
        ld.z,
        f_ok.select(so.x, zero),
        f_ok.select(so.y, zero),
        f_ok.select(so.z, zero),
        f_ok.select(sdir.x, zero),
        f_ok.select(sdir.y, zero),
        f_ok.select(sdir.z, zero),
        f_ok.select(st, zero),
        cont.select(no.x, zero),
        cont.select(no.y, zero),
        cont.select(no.z, zero),
        cont.select(nwi.x, zero),
        cont.select(nwi.y, zero),
        cont.select(nwi.z, zero),
        cont.select(albedo.x, zero),
        cont.select(albedo.y, zero),
        cont.select(albedo.z, zero),
    ]
    .map(|v| v.to_array());
    for (l, o) in out.iter_mut().enumerate() {
        let v = |k: usize| planes[k][l];
        *o = Out {
            ld: [v(0), v(1), v(2)],
            shadow_o: [v(3), v(4), v(5)],
            shadow_d: [v(6), v(7), v(8)],
            shadow_t: v(9),
            next_o: [v(10), v(11), v(12)],
            next_d: [v(13), v(14), v(15)],
            beta: [v(16), v(17), v(18)],
        };
    }
}
