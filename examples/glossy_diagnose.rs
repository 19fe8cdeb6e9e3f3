//! Splits the glossy preview's error by path type and by cause, on a grid of pixel
//! centres: for each of the six lobes (Td and Tg × direct, indirect diffuse,
//! indirect glossy) the preview's value P (interpolated over the mesh and view
//! directions), the lobe S of a slice traced at the pixel's own point with many
//! paths (the fit and the prefilter, without interpolation or slice noise), and
//! the truth R those same paths carry with the environment evaluated where they
//! escape. Also the path-traced reference from the preview's EXR, if given.
//!
//! cargo run --release --example glossy_diagnose -- SCENE CACHE.bin [EXR|-] [STRIDE] [PATHS]
//! CACHE.bin: the transfer `gradtrace preview glossy` cached under its out dir
//! (default settings). Also writes /tmp/diag_{shape,spatial,angular,total}.png
//! (signed error maps, red = too bright). `PIXEL=x,y`: prints one pixel's lobes,
//! known lobes and own EM fit. Frame timing: the `glossy_frame` example.

use gradtrace::accel::{Accel, PrimRef};
use gradtrace::math::{luminance, Frame, Vec2, Vec3};
use gradtrace::preview::glossy::{self, fit, slice, PrefilteredEnv, Settings, Transfer};
use std::path::Path;

#[derive(Default, Clone, Copy)]
struct Acc {
    n: f64,
    sum_truth: f64,
    se: f64,
    bias: f64,
}

impl Acc {
    fn add(&mut self, value: f32, truth: f32) {
        let d = (value - truth) as f64;
        self.n += 1.0;
        self.sum_truth += truth as f64;
        self.se += d * d;
        self.bias += d;
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = gradtrace::scene::load(Path::new(&args[1])).expect("scene");
    let cache = &args[2];
    let exr = args.get(3).filter(|s| *s != "-");
    let stride: usize = args.get(4).map_or(8, |s| s.parse().unwrap());
    let paths: u32 = args.get(5).map_or(1024, |s| s.parse().unwrap());
    let settings = Settings::default();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let raw = std::fs::read(cache).expect("cache file");
    // The transfer's bytes follow the cache entry's header.
    let bytes = gradtrace::pipeline::cache::byte_entry_payload(&raw).unwrap_or(&raw);
    // The stored key: a source change since the run changes the key, not the slices.
    let t = Transfer::stored_key(bytes)
        .and_then(|key| Transfer::decode(bytes, key, &scene, &settings))
        .expect("cache holds this scene's transfer at default settings");
    let env_src = scene.environment.as_ref().unwrap();
    let env = PrefilteredEnv::new(env_src);
    let camera = &scene.camera;
    let lobes = glossy::vertex_lobes(&t, camera);
    let ico = glossy::icosphere::Icosphere::new(settings.max_angular_level.max(fit::FIT_LEVEL));
    let fits: Vec<fit::MaterialFit> = scene
        .materials
        .iter()
        .map(|m| fit::MaterialFit::new(m, &ico, settings.fit_samples).unwrap())
        .collect();
    let ctx = slice::TraceContext {
        scene: &scene,
        accel: &accel,
        fits: &fits,
        ico: &ico,
    };
    let reference = exr.map(|p| {
        let img = gradtrace::output::read_exr(Path::new(p)).expect("exr");
        img.vec3("reference.", ["R", "G", "B"]).unwrap()
    });
    let (w, h) = (camera.width as usize, camera.height as usize);
    if let Ok(px) = std::env::var("PIXEL") {
        let v: Vec<f32> = px.split(',').map(|x| x.parse().unwrap()).collect();
        let ray = camera.generate_ray(Vec2::new(v[0] + 0.5, v[1] + 0.5));
        let at = ctx.hit(&ray).unwrap().unwrap();
        let mut wo = at.frame.to_local(-ray.dir);
        wo.z = wo.z.abs();
        let wo = fit::clamp_view(wo);
        let value = |l: &slice::Lobe| luminance(l.alpha * env.lookup(l.mu, l.kappa));
        println!("wo {wo:?} n {:?}", at.frame.n);
        let e = fits[0].glossy_at(&ico, wo).unwrap();
        for k in &e.direct {
            println!(
                "known (local): {k:?} kappa_from_r {}",
                gradtrace::math::vmf::Vmf::from_mean_resultant(k.mean_dir * k.resultant).kappa
            );
        }
        let (sl, _) = ctx.trace(&at, Some(wo), paths, 1);
        for l in &sl {
            println!(
                "slice lobe {l:?} local mu {:?} value {}",
                at.frame.to_local(l.mu),
                value(l)
            );
        }
        let rad = ctx.radiance(&at, Some(wo), paths, 1, env_src);
        println!("R direct {}", luminance(rad[0]));
        let mut samples = Vec::new();
        ctx.walk(&at, Some(wo), paths, 1, |_, k, d, w| {
            if k == 0 {
                samples.push((at.frame.to_local(d).as_dvec3(), w.as_dvec3()))
            }
        });
        let m = fit::fit_mixture(&samples, paths as u64);
        let mut tot = 0.0;
        for k in &m {
            let lobe = gradtrace::math::vmf::Vmf::from_mean_resultant(k.mean_dir * k.resultant);
            let v = luminance(
                k.rgb.as_vec3a()
                    * env.lookup(at.frame.to_world(lobe.mu.as_vec3a()), lobe.kappa as f32),
            );
            tot += v;
            println!("own EM (local): {k:?} kappa {} value {v}", lobe.kappa);
        }
        println!("own EM total {tot}");
        return;
    }
    let pixels: Vec<(usize, usize)> = (0..h)
        .step_by(stride)
        .flat_map(|y| (0..w).step_by(stride).map(move |x| (x, y)))
        .collect();
    use rayon::prelude::*;
    // Per pixel: [P; 6], [S; 6], [R; 6], reference.
    type Row = (
        [f32; 6],
        [f32; 6],
        [f32; 6],
        f32,
        [f32; 6],
        [f32; 6],
        [f32; 6],
        f32,
    );
    let rows: Vec<Option<Row>> = pixels
        .par_iter()
        .enumerate()
        .map(|(n, &(x, y))| {
            let ray = camera.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let hit = accel.intersect(&ray)?;
            let PrimRef::Triangle { mesh, tri } = hit.prim else {
                return None;
            };
            let (ids, wts) = t.mesh.locate(mesh, tri, hit.bary)?;
            let p = glossy::shade_components(&lobes, &env, ids, wts).map(luminance);
            let at = ctx.hit(&ray)??;
            let mut wo = at.frame.to_local(-ray.dir);
            wo.z = wo.z.abs();
            let wo = fit::clamp_view(wo);
            let seed = n as u32 * 7919 + 1;
            let value = |l: &slice::Lobe| {
                if luminance(l.alpha) > 0.0 {
                    luminance(l.alpha * env.lookup(l.mu, l.kappa))
                } else {
                    0.0
                }
            };
            let mut s = [0f32; 6];
            let mut r = [0f32; 6];
            for (part, view) in [(0, None), (1, Some(wo))] {
                let (sl, _) = ctx.trace(&at, view, paths, seed + part as u32);
                let rad = ctx.radiance(&at, view, paths, seed + part as u32, env_src);
                for k in 0..4 {
                    s[3 * part + k % 3] += value(&sl[k]);
                }
                for k in 0..3 {
                    r[3 * part + k] = luminance(rad[k]);
                }
            }
            // Smc: the point's lobes integrated against the raw environment by sampling them.
            let mut smc = [0f32; 6];
            let mut s32 = [0f32; 6];
            for (part, view) in [(0, None), (1, Some(wo))] {
                let (sl, _) = ctx.trace(&at, view, paths, seed + part as u32);
                let (sl32, _) = ctx.trace(&at, view, settings.samples, seed + 99 + part as u32);
                for k in 0..4 {
                    let l = sl[k];
                    let v = gradtrace::math::vmf::Vmf::new(l.mu.as_dvec3(), l.kappa as f64);
                    let mut acc = Vec3::ZERO;
                    for i in 0..4096u32 {
                        let u = [
                            sobol_burley::sample(i, 0, seed) as f64,
                            sobol_burley::sample(i, 1, seed) as f64,
                        ];
                        acc += env_src.eval(v.sample(u).as_vec3a());
                    }
                    smc[3 * part + k % 3] += luminance(l.alpha * acc / 4096.0);
                    s32[3 * part + k % 3] += value(&sl32[k]);
                }
            }
            // V: the triangle's vertices traced at the exact view direction, blended.
            let mut vlobes = [[slice::Lobe::default(); 8]; 3];
            for (c, &vid) in ids.iter().enumerate() {
                let vx = &t.mesh.vertices[vid as usize];
                let frame = Frame::from_normal(vx.normal);
                let vat = slice::SurfaceSample {
                    position: vx.position,
                    geometric_normal: vx.geometric_normal,
                    frame,
                    material: vx.material,
                };
                let mut vwo = frame.to_local((camera.from - vx.position).normalize());
                vwo.z = vwo.z.abs();
                let (d, _) = ctx.trace(&vat, None, paths, seed + 7 + c as u32);
                let (g, _) = ctx.trace(
                    &vat,
                    Some(fit::clamp_view(vwo)),
                    paths,
                    seed + 17 + c as u32,
                );
                vlobes[c] = glossy::render_lobes(&d, &g, vx.normal, t.kd[vx.material as usize]);
            }
            let vv = glossy::shade_components(&vlobes, &env, [0, 1, 2], wts).map(luminance);
            let rf = reference
                .as_ref()
                .map_or(0.0, |img| luminance(img[y * w + x]));
            Some((p, s, r, rf, smc, s32, vv, wo.z))
        })
        .collect();
    let image_mean = reference.as_ref().map_or(1.0, |img| {
        img.iter().map(|c| luminance(*c) as f64).sum::<f64>() / img.len() as f64
    });
    let total_px = pixels.len() as f64;
    let names = [
        "Td direct",
        "Td ind-diff",
        "Td ind-glos",
        "Tg direct",
        "Tg ind-diff",
        "Tg ind-glos",
    ];
    println!(
        "grid {} pixels, {} on the mesh; image mean {image_mean:.4}; figures are RMSE over \
         the whole grid / image mean (background counted as 0 error), bias = mean error / image mean",
        pixels.len(),
        rows.iter().flatten().count()
    );
    println!(
        "{:<12} {:>9} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "component", "mean R", "P-R rmse", "P-R bias", "S-R rmse", "S-R bias", "P-S rmse"
    );
    let mut tot = [Acc::default(); 4];
    for k in 0..6 {
        let mut a = [Acc::default(); 3];
        for (p, s, r, ..) in rows.iter().flatten() {
            a[0].add(p[k], r[k]);
            a[1].add(s[k], r[k]);
            a[2].add(p[k], s[k]);
        }
        let f = |x: &Acc| (x.se / total_px).sqrt() / image_mean;
        println!(
            "{:<12} {:>9.4} {:>9.2}% {:>9.2}% {:>9.2}% {:>9.2}% {:>9.2}%",
            names[k],
            a[0].sum_truth / total_px,
            100.0 * f(&a[0]),
            100.0 * a[0].bias / total_px / image_mean,
            100.0 * f(&a[1]),
            100.0 * a[1].bias / total_px / image_mean,
            100.0 * f(&a[2]),
        );
    }
    for (p, s, r, rf, ..) in rows.iter().flatten() {
        let (p, s, r) = (p.iter().sum(), s.iter().sum(), r.iter().sum::<f32>());
        tot[0].add(p, r);
        tot[1].add(s, r);
        tot[2].add(*rf, r);
        tot[3].add(p, *rf);
    }
    let f = |x: &Acc| 100.0 * (x.se / total_px).sqrt() / image_mean;
    let b = |x: &Acc| 100.0 * x.bias / total_px / image_mean;
    let pair = |label: &str, k: Option<usize>, f: &dyn Fn(&Row) -> (f32, f32)| {
        let mut a = Acc::default();
        for row in rows.iter().flatten() {
            let (x, y) = f(row);
            a.add(x, y);
        }
        println!(
            "{label:<40} {:>7.2}% (bias {:>6.2}%) {}",
            100.0 * (a.se / total_px).sqrt() / image_mean,
            100.0 * a.bias / total_px / image_mean,
            k.map_or("all".to_string(), |k| names[k].to_string())
        );
    };
    let sum = |x: &[f32; 6]| x.iter().sum::<f32>();
    for k in [0, 3] {
        pair("prefilter: S vs Smc", Some(k), &|r| (r.1[k], r.4[k]));
        pair("lobe shape: Smc vs R", Some(k), &|r| (r.4[k], r.2[k]));
        pair("slice noise: S32 vs S", Some(k), &|r| (r.5[k], r.1[k]));
        pair("spatial interp: V vs S", Some(k), &|r| (r.6[k], r.1[k]));
        pair("angular interp + noise: P vs V", Some(k), &|r| {
            (r.0[k], r.6[k])
        });
    }
    pair("prefilter: S vs Smc", None, &|r| (sum(&r.1), sum(&r.4)));
    pair("lobe shape: Smc vs R", None, &|r| (sum(&r.4), sum(&r.2)));
    pair("spatial interp: V vs S", None, &|r| (sum(&r.6), sum(&r.1)));
    pair("angular interp + noise: P vs V", None, &|r| {
        (sum(&r.0), sum(&r.6))
    });
    let mut worst: Vec<(f32, (usize, usize), f32, f32)> = rows
        .iter()
        .zip(&pixels)
        .filter_map(|(r, p)| {
            r.as_ref()
                .map(|r| ((r.1[3] - r.2[3]).abs(), *p, r.1[3], r.2[3]))
        })
        .collect();
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    for x in worst.iter().take(8) {
        println!("worst S-R Tg direct at {:?}: S {} R {}", x.1, x.2, x.3);
    }
    // Tg direct's shape error by view elevation (cos θo bins of 0.2).
    for b in 0..5 {
        let (lo, hi) = (b as f32 * 0.2, (b + 1) as f32 * 0.2);
        let mut a = [Acc::default(); 3];
        for r in rows.iter().flatten().filter(|r| r.7 >= lo && r.7 < hi) {
            a[0].add(r.4[3], r.2[3]);
            a[1].add(r.6[3], r.1[3]);
            a[2].add(r.0[3], r.6[3]);
        }
        let f = |x: &Acc| 100.0 * (x.se / total_px).sqrt() / image_mean;
        println!(
            "cos θo in [{lo:.1},{hi:.1}): {:>5} px, shape {:.2}%, spatial {:.2}%, angular {:.2}%",
            a[0].n,
            f(&a[0]),
            f(&a[1]),
            f(&a[2])
        );
    }
    // Maps of |error| (Tg direct) at grid resolution: shape, spatial, angular+noise.
    let gw = w.div_ceil(stride);
    let gh = h.div_ceil(stride);
    for (name, sel) in [
        ("shape", 0usize),
        ("spatial", 1),
        ("angular", 2),
        ("total", 3),
    ] {
        let img: Vec<Vec3> = rows
            .iter()
            .map(|r| {
                r.as_ref().map_or(Vec3::ZERO, |r| {
                    let e = match sel {
                        0 => r.4[3] - r.2[3],
                        1 => r.6[3] - r.1[3],
                        2 => r.0[3] - r.6[3],
                        _ => sum(&r.0) - sum(&r.2),
                    };
                    let v = (e.abs() * 4.0 / image_mean as f32).min(1.0);
                    if e > 0.0 {
                        Vec3::new(v, 0.0, 0.0)
                    } else {
                        Vec3::new(0.0, 0.0, v)
                    }
                })
            })
            .collect();
        let up: Vec<Vec3> = (0..gh * 4)
            .flat_map(|y| (0..gw * 4).map(move |x| (x, y)))
            .map(|(x, y)| img[(y / 4) * gw + x / 4])
            .collect();
        gradtrace::output::write_png(
            Path::new(&format!("/tmp/diag_{name}.png")),
            &up,
            gw * 4,
            gh * 4,
        )
        .unwrap();
    }
    println!(
        "total: P-R {:.2}% (bias {:.2}%), S-R {:.2}% (bias {:.2}%), ref-R {:.2}% (bias {:.2}%), P-ref {:.2}%",
        f(&tot[0]),
        b(&tot[0]),
        f(&tot[1]),
        b(&tot[1]),
        f(&tot[2]),
        b(&tot[2]),
        f(&tot[3])
    );
}
