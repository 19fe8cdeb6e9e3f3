//! The Cycles-style noise-adaptive sampler at the small budgets `compare` gives
//! it (issue 55): it adapts at 16 spp, beats uniform sampling at an equal sample
//! count, and holds its time limit from the first round on (issue 54).

mod common;
use common::{temp_dir, BIN};
use gradtrace::math::Vec3;
use gradtrace::render::noise_adaptive::{render_noise_adaptive, NoiseAdaptive};
use gradtrace::render::{render, RenderOptions, RenderOutput};
use std::time::{Duration, Instant};

/// The scene, written into a folder of the calling test's own (`name`): the
/// tests run in parallel, and a shared folder was removed under another test.
fn scene(
    name: &str,
) -> (
    gradtrace::scene::Scene,
    gradtrace::accel::Accel,
    std::path::PathBuf,
) {
    let dir = temp_dir(name);
    let path = dir.join("small_light.toml");
    std::fs::write(&path, common::small_light_scene(64, 48)).unwrap();
    let (scene, accel) = gradtrace::pipeline::load(&path).unwrap();
    (scene, accel, path)
}

fn options(seed: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        seed: Some(seed),
        spp: Some(spp),
        ..Default::default()
    }
}

fn spp_map(out: &RenderOutput) -> Vec<f64> {
    out.spp_map
        .as_ref()
        .unwrap()
        .iter()
        .map(|&c| c as f64)
        .collect()
}

/// `--spp 16 --noise-threshold 0.01` adapted nothing: Cycles' automatic minimum
/// (64 at 0.01) exceeded the budget, so every pixel took 16. Now the minimum and
/// the step follow the budget and the samples go where the noise is: the
/// noisiest quarter of the pixels (by their relative variance at 64 spp) gets on
/// average at least 1.5 times the samples of the quietest half.
#[test]
fn adapts_at_16_spp_and_samples_the_noisy_pixels_more() {
    let (scene, accel, _) = scene("adapts");
    let settings = NoiseAdaptive::new(0.01, 16);
    println!(
        "min spp {}, check every {}",
        settings.min_spp, settings.check_every
    );
    let out =
        render_noise_adaptive(&scene, &accel, &options(1, 16), &settings, &|_, _| {}).unwrap();
    let spp = spp_map(&out);
    let (lo, hi) = spp
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), &s| (a.min(s), b.max(s)));
    println!("samples.spp from {lo} to {hi}");
    assert!(lo < hi, "samples.spp is constant ({lo})");
    assert!(hi <= 16.0);

    // Noise: the variance of the pixel mean relative to its squared luminance.
    let probe = render(
        &scene,
        &accel,
        &RenderOptions {
            aovs: true,
            ..options(7, 64)
        },
        &|_, _| {},
    )
    .unwrap();
    let var = probe.variance.as_ref().unwrap();
    let lum = |v: Vec3| f64::from(v.x + v.y + v.z) / 3.0;
    let noise: Vec<f64> = (0..spp.len())
        .map(|i| lum(var[i]) / (lum(probe.beauty[i]).powi(2) + 1e-4))
        .collect();
    let mut order: Vec<usize> = (0..spp.len()).collect();
    order.sort_by(|&a, &b| noise[a].total_cmp(&noise[b]));
    let n = order.len();
    let mean = |idx: &[usize]| idx.iter().map(|&i| spp[i]).sum::<f64>() / idx.len() as f64;
    let (quiet, noisy) = (mean(&order[..n / 2]), mean(&order[n - n / 4..]));
    println!(
        "mean spp: quietest half {quiet:.2}, noisiest quarter {noisy:.2}, all {:.2}",
        mean(&order)
    );
    assert!(noisy >= 1.5 * quiet, "noisy {noisy} vs quiet {quiet}");
}

/// relMSE against a 4096-spp reference: the sampler under a sample limit of 16
/// spp per pixel (equal samples: the deterministic stand-in for equal time; it
/// never takes more than uniform does) against uniform 16 spp, seed by seed. The
/// adaptive run must be lower on every seed and at least 10 % lower on their mean.
#[test]
fn beats_uniform_at_an_equal_sample_count_on_a_small_bright_light() {
    let (scene, accel, _) = scene("beats-uniform");
    let reference = render(&scene, &accel, &options(99, 4096), &|_, _| {}).unwrap();
    let relmse =
        |img: &[Vec3]| gradtrace::output::metrics::relmse(img, &reference.beauty).unwrap() as f64;
    let pixels = (reference.width * reference.height) as u64;
    let (mut sum_a, mut sum_u) = (0.0, 0.0);
    for seed in 1..=4 {
        let uniform = render(&scene, &accel, &options(seed, 16), &|_, _| {}).unwrap();
        let mut settings = NoiseAdaptive::with_budget(0.01, 128, 16);
        settings.sample_limit = Some(16 * pixels);
        let adaptive =
            render_noise_adaptive(&scene, &accel, &options(seed, 16), &settings, &|_, _| {})
                .unwrap();
        let total: f64 = spp_map(&adaptive).iter().sum();
        let (a, u) = (relmse(&adaptive.beauty), relmse(&uniform.beauty));
        println!(
            "seed {seed}: adaptive {:.2} spp/pixel relMSE {a:.4e}, uniform 16 spp {u:.4e} (ratio {:.3})",
            total / pixels as f64,
            a / u
        );
        assert!(total <= (16 * pixels) as f64, "{total} samples");
        assert!(a < u, "seed {seed}: adaptive {a} vs uniform {u}");
        sum_a += a;
        sum_u += u;
    }
    assert!(
        sum_a < 0.9 * sum_u,
        "mean relMSE: adaptive {sum_a} vs uniform {sum_u}"
    );
}

/// Issue 54: `--spp 1000000 --noise-threshold 0 --time-limit 0.3` rendered its
/// first round (all of the million samples) before looking at the clock. Now it
/// stops within the limit plus one abandoned pass; the test allows 20 s (the
/// machine is shared) and kills the run past 60 s.
#[test]
fn the_time_limit_holds_from_the_first_round() {
    let (_, _, path) = scene("time-limit");
    let dir = path.parent().unwrap();
    let start = Instant::now();
    let mut child = std::process::Command::new(BIN)
        .args([
            "render",
            path.to_str().unwrap(),
            "--spp",
            "1000000",
            "--noise-threshold",
            "0",
            "--time-limit",
            "0.3",
            "--quiet",
            "--out",
            "limited.exr",
        ])
        .current_dir(dir)
        .spawn()
        .unwrap();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            child.wait().unwrap();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let secs = start.elapsed().as_secs_f64();
    println!("--time-limit 0.3 with --spp 1000000: {secs:.2} s");
    assert!(status.is_some(), "still running after {secs:.0} s: killed");
    assert!(status.unwrap().success());
    assert!(secs < 20.0, "{secs} s");
    let img = gradtrace::output::read_exr(&dir.join("limited.exr")).unwrap();
    let spp = &img.channel("samples.spp").unwrap().data;
    assert!(
        spp.iter().all(|s| (1.0..1_000_000.0).contains(s)),
        "{:?}",
        &spp[..4]
    );

    // The library call: a sample limit of 3 spp also stops after the 2-spp pass.
    let (scene, accel, _) = scene("sample-limit");
    let mut s = NoiseAdaptive::new(0.0, 1_000_000);
    s.sample_limit = Some(3 * 64 * 48);
    let out = render_noise_adaptive(&scene, &accel, &options(1, 16), &s, &|_, _| {}).unwrap();
    assert!(spp_map(&out).iter().all(|&c| c == 2.0));
}

/// `compare --equal cpu`'s limit: the process CPU time stops the sampler as the
/// wall-time limit does (from the first round on), so a million spp end in
/// seconds, not hours. (Other tests' threads share the process clock, so only
/// the stop is asserted, not how close to the limit it came.)
#[test]
fn the_cpu_time_limit_stops_the_sampler() {
    let (scene, accel, _) = scene("cpu-limit");
    let mut s = NoiseAdaptive::new(0.0, 1_000_000);
    s.cpu_time_limit = Some(Duration::from_secs_f64(0.3));
    let cpu0 = gradtrace::cpu_time::process_s().unwrap();
    let start = Instant::now();
    let out = render_noise_adaptive(&scene, &accel, &options(1, 16), &s, &|_, _| {}).unwrap();
    let (secs, cpu) = (
        start.elapsed().as_secs_f64(),
        gradtrace::cpu_time::process_s().unwrap() - cpu0,
    );
    println!("cpu limit 0.3 s: {secs:.2} s wall, {cpu:.2} s CPU");
    assert!(secs < 20.0, "{secs} s");
    assert!(cpu >= 0.3, "stopped before its limit: {cpu} s CPU");
    let spp = spp_map(&out);
    assert!(spp.iter().all(|&c| (1.0..1_000_000.0).contains(&c)));
}
