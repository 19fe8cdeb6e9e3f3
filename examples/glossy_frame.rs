//! Times glossy-preview frames from a cached transfer and scores the image, for
//! measuring a rendering change without the full `preview glossy` run:
//!
//! cargo run --release --example glossy_frame -- SCENE CACHE.bin EXR [FRAMES [OUT.exr]]
//!
//! CACHE.bin: the transfer `gradtrace preview glossy` cached under its out dir
//! (default settings; opened under its stored key, so a source change since does
//! not invalidate it); EXR: that run's output (its `reference.*` channels). Prints
//! the fastest wall time and the least process CPU time of a frame at the scene's
//! resolution, the CPU time of blending every vertex's slices (a frame blends only
//! the vertices it sees, about half), and the RMSE of the 2 × 2-supersampled
//! frame against the reference over its mean luminance (what `preview.json`
//! reports as `rmse_over_mean`). OUT.exr: that frame and the reference, as the run's EXR.

use gradtrace::accel::Accel;
use gradtrace::math::luminance;
use gradtrace::preview::glossy::{self, PrefilteredEnv, Settings, Transfer};
use std::path::Path;
use std::time::Instant;

/// Process CPU seconds (NaN where the OS does not report them).
fn cpu_s() -> f64 {
    gradtrace::cpu_time::process_s().unwrap_or(f64::NAN)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: glossy_frame SCENE CACHE.bin EXR [FRAMES]");
        std::process::exit(2);
    }
    let scene = gradtrace::scene::load(Path::new(&args[1])).expect("scene");
    let frames: usize = args.get(4).map_or(10, |s| s.parse().unwrap());
    let settings = Settings::default();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let raw = std::fs::read(&args[2]).expect("cache file");
    // The transfer's bytes follow the cache entry's header.
    let bytes = gradtrace::pipeline::cache::byte_entry_payload(&raw).unwrap_or(&raw);
    let t = Transfer::stored_key(bytes)
        .and_then(|key| Transfer::decode(bytes, key, &scene, &settings))
        .expect("cache matches the scene and default settings");
    drop(raw);
    println!("{} vertices, {} bytes", t.vertices.len(), t.bytes());
    let env = PrefilteredEnv::new(scene.environment.as_ref().unwrap());
    let camera = &scene.camera;
    let _ = glossy::render(&t, &env, &scene, &accel, camera);
    let (mut best, mut best_cpu, mut best_lobes) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for _ in 0..frames {
        let (t0, c0) = (Instant::now(), cpu_s());
        let img = glossy::render(&t, &env, &scene, &accel, camera);
        best = best.min(t0.elapsed().as_secs_f64() * 1e3);
        best_cpu = best_cpu.min((cpu_s() - c0) * 1e3);
        std::hint::black_box(img);
        let c0 = cpu_s();
        std::hint::black_box(glossy::vertex_lobes(&t, camera));
        best_lobes = best_lobes.min((cpu_s() - c0) * 1e3);
    }
    println!(
        "frame: fastest {best:.1} ms wall, {best_cpu:.1} ms CPU (all vertices' lobes {best_lobes:.1} ms CPU; {} threads)",
        rayon::current_num_threads()
    );
    let img = gradtrace::output::read_exr(Path::new(&args[3])).expect("exr");
    let reference = img.vec3("reference.", ["R", "G", "B"]).unwrap();
    let image = glossy::render_supersampled(&t, &env, &scene, &accel, camera, 2);
    let rmse = gradtrace::output::metrics::rmse(&image, &reference).unwrap() as f64;
    let mean = reference.iter().map(|c| luminance(*c) as f64).sum::<f64>() / reference.len() as f64;
    if let Some(out) = args.get(5) {
        let mut img =
            gradtrace::output::OutputImage::new(camera.width as usize, camera.height as usize);
        img.push_vec3("", ["R", "G", "B"], &image);
        img.push_vec3("reference.", ["R", "G", "B"], &reference);
        gradtrace::output::write_exr(Path::new(out), &img).expect("write OUT.exr");
    }
    let finite = image.iter().all(|c| c.is_finite());
    println!(
        "rmse {rmse:.6e} = {:.4}% of the mean; all finite: {finite}",
        100.0 * rmse / mean
    );
}
