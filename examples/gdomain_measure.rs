//! Measures the gradient-domain reconstruction (`pipeline::gdomain`): RMSE of the
//! primal and of every domain × norm against a reference render, and the solve's
//! time against the render's.
//!
//! `cargo run --release --example gdomain_measure -- SCENE W H SPP REF_SPP [BETA...]`

use gradtrace::pipeline::gdomain::{reconstruct_with, Domain, GradientDomain};
use gradtrace::reconstruct::poisson::{Norm, Settings};
use gradtrace::render::{render, RenderOptions};
use std::time::Instant;

fn rmse(a: &[glam::Vec3A], b: &[glam::Vec3A]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(a, b)| {
            (*a - *b)
                .to_array()
                .iter()
                .map(|d| f64::from(*d).powi(2))
                .sum::<f64>()
        })
        .sum();
    (s / (3 * a.len()) as f64).sqrt()
}

fn main() -> gradtrace::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene_path = std::path::Path::new(&args[1]);
    let num = |i: usize| args[i].parse::<u32>().expect("a number");
    let (w, h, spp, ref_spp) = (num(2), num(3), num(4), num(5));
    let betas: Vec<f32> = if args.len() > 6 {
        args[6..]
            .iter()
            .map(|b| b.parse().expect("a number"))
            .collect()
    } else {
        vec![0.2]
    };
    let (scene, accel) = gradtrace::pipeline::load(scene_path)?;
    let cache = std::env::temp_dir().join(format!(
        "gdomain-ref-{}-{w}x{h}-{ref_spp}.bin",
        scene_path.file_stem().unwrap().to_string_lossy()
    ));
    let reference: Vec<glam::Vec3A> = match std::fs::read(&cache) {
        Ok(bytes) if bytes.len() == (w * h * 12) as usize => bytes
            .chunks(12)
            .map(|c| {
                let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap());
                glam::Vec3A::new(f(0), f(1), f(2))
            })
            .collect(),
        _ => {
            let t = Instant::now();
            let opts = RenderOptions {
                spp: Some(ref_spp),
                resolution: Some((w, h)),
                ..Default::default()
            };
            let r = render(&scene, &accel, &opts, &|_, _| {})?.beauty;
            eprintln!("reference rendered in {:.1} s", t.elapsed().as_secs_f64());
            let bytes: Vec<u8> = r
                .iter()
                .flat_map(|v| v.to_array())
                .flat_map(f32::to_le_bytes)
                .collect();
            std::fs::write(&cache, bytes).ok();
            r
        }
    };
    let opts = RenderOptions {
        spp: Some(spp),
        resolution: Some((w, h)),
        aovs: true,
        gradients: true,
        vis_samples: Some(4),
        ..Default::default()
    };
    let t = Instant::now();
    let out = render(&scene, &accel, &opts, &|_, _| {})?;
    let render_s = t.elapsed().as_secs_f64();
    let primal = rmse(&out.beauty, &reference);
    println!(
        "{} {w}x{h} {spp} spp (ref {ref_spp}): render {render_s:.2} s, primal RMSE {primal:.5}",
        scene_path.display()
    );
    let ks: Vec<f32> = std::env::var("GDOMAIN_K")
        .map(|k| k.split(',').map(|k| k.parse().expect("a number")).collect())
        .unwrap_or(vec![4.0]);
    for (beta, consistency) in betas.iter().flat_map(|&b| ks.iter().map(move |&k| (b, k))) {
        for domain in [Domain::Full, Domain::Direct, Domain::Demodulated] {
            for norm in [Norm::L2, Norm::L1] {
                let gd = GradientDomain {
                    norm,
                    domain,
                    beta,
                    consistency,
                };
                let t = Instant::now();
                let sol = reconstruct_with(&out, &gd, &Settings::new(norm))?;
                let (img, its) = (sol.image, sol.iterations);
                let s = t.elapsed().as_secs_f64();
                let e = rmse(&img, &reference);
                if std::env::var_os("GDOMAIN_WORST").is_some() && norm == Norm::L2 {
                    let mut worst: Vec<(f32, usize)> = img
                        .iter()
                        .zip(&reference)
                        .map(|(a, b)| (*a - *b).abs().max_element())
                        .enumerate()
                        .map(|(i, e)| (e, i))
                        .collect();
                    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
                    for &(e, i) in &worst[..8] {
                        let aov = |p: &Option<Vec<f32>>| p.as_ref().map_or(-1.0, |p| p[i]);
                        println!(
                            "    worst ({}, {}): err {e:.3} ref {:.3} primal {:.3} id {} depth {:.2}",
                            i % w as usize,
                            i / w as usize,
                            reference[i].x,
                            out.beauty[i].x,
                            aov(&out.object_id),
                            aov(&out.depth)
                        );
                    }
                }
                println!(
                    "  beta {beta:<5} k {consistency:<3} {domain:<12?} {:<10} RMSE {e:.5} ({:.2}x primal) solve {s:.3} s ({:.1}% of render, {its} CG iterations)",
                    norm.name(),
                    primal / e,
                    100.0 * s / render_s
                );
            }
        }
    }
    Ok(())
}
