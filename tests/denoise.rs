//! The optional Intel Open Image Denoise baseline. The default build must say
//! how to enable it (and `render --denoise` must fail before rendering, writing
//! nothing); with `--features oidn` (after `eval "$(scripts/setup_oidn.sh)"`)
//! denoising a noisy render must bring it much closer to a converged one.

mod common;
use common::{run_in, temp_dir};
use std::path::{Path, PathBuf};

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml")
}

#[cfg(not(feature = "oidn"))]
#[test]
fn default_build_says_how_to_enable_the_denoiser() {
    use gradtrace::math::Vec3;
    assert!(!gradtrace::denoise::available());
    let plane = vec![Vec3::splat(0.5); 6];
    let msg = gradtrace::denoise::denoise(&plane, Some(&plane), Some(&plane), 3, 2)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("--features oidn"), "{msg}");
    assert!(msg.contains("scripts/setup_oidn.sh"), "{msg}");

    // The CLI fails at once (a 4096² render would take minutes otherwise).
    let dir = temp_dir("disabled");
    let scene = cornell();
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--denoise",
        "--width",
        "4096",
    ];
    let out = run_in(
        &dir,
        &[&args[..], &["--height", "4096", "--out", "x.exr"]].concat(),
    );
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: invalid option --denoise: "),
        "{err}"
    );
    assert!(err.contains("--features oidn"), "{err}");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
}

/// A noise-adaptive render's pixels carry unequal noise: denoising it is refused
/// with one line naming both options, before any work (with or without OIDN).
#[test]
fn denoise_rejects_noise_adaptive_renders() {
    let dir = temp_dir("noise_adaptive");
    let scene = cornell();
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--denoise",
        "--noise-threshold",
        "0.01",
    ];
    let out = run_in(&dir, &args);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--denoise") && err.contains("--noise-threshold"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
}

#[cfg(feature = "oidn")]
mod with_oidn {
    use super::*;
    use gradtrace::math::Vec3;
    use gradtrace::output::metrics::rmse;
    use gradtrace::output::names::RGB;
    use gradtrace::output::read_exr;
    use gradtrace::render::{render, RenderOptions, RenderOutput};

    fn render_scene(name: &str, spp: u32, seed: u32) -> RenderOutput {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name);
        let (scene, accel) = gradtrace::pipeline::load(&path).unwrap();
        let opts = RenderOptions {
            spp: Some(spp),
            seed: Some(seed),
            resolution: Some((96, 64)),
            aovs: true,
            ..Default::default()
        };
        render(&scene, &accel, &opts, &|_, _| {}).unwrap()
    }

    /// 4 spp against 256 spp (its own seed) of the three spheres under a smooth
    /// environment at 96×64: OIDN guided by the AOVs must cut the RMSE by more
    /// than 3× (measured 6.2×, the rest being mostly the reference's own noise),
    /// and give the same pixels when run twice. Not the Cornell box: there the
    /// smeared edge of the light (radiance 18) outweighs the gain elsewhere in
    /// RMSE (README.md, "Optional: denoiser").
    #[test]
    fn denoising_a_noisy_render_lowers_its_rmse_several_fold() {
        let reason = gradtrace::denoise::unavailable_reason();
        assert!(gradtrace::denoise::available(), "{reason}");
        let reference = render_scene("three_spheres_env.toml", 256, 99);
        let noisy = render_scene("three_spheres_env.toml", 4, 1);
        let (albedo, normal) = (noisy.albedo.as_deref(), noisy.normal.as_deref());
        let denoise =
            || gradtrace::denoise::denoise(&noisy.beauty, albedo, normal, 96, 64).unwrap();
        let clean: Vec<Vec3> = denoise();
        let before = rmse(&noisy.beauty, &reference.beauty).unwrap();
        let after = rmse(&clean, &reference.beauty).unwrap();
        let ratio = before / after;
        println!("RMSE noisy {before:.5}, denoised {after:.5}, ratio {ratio:.2}");
        assert!(ratio > 3.0, "noisy {before}, denoised {after}");
        assert_eq!(clean, denoise(), "OIDN on the CPU is deterministic");
        // Beauty only, no guides: still a denoiser, if a weaker one.
        let unguided = gradtrace::denoise::denoise(&noisy.beauty, None, None, 96, 64).unwrap();
        assert!(rmse(&unguided, &reference.beauty).unwrap() < before);
    }

    #[test]
    fn render_denoise_keeps_the_noisy_beauty_beside_the_denoised_one() {
        let dir = temp_dir("cli");
        let scene = cornell();
        let base = [
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "2",
            "--width",
            "32",
        ];
        let base = [&base[..], &["--height", "24", "--seed", "5"]].concat();
        let out = run_in(&dir, &[&base[..], &["--out", "plain.exr"]].concat());
        assert_eq!(out.status.code(), Some(0));
        let out = run_in(
            &dir,
            &[&base[..], &["--denoise", "--out", "dn.exr"]].concat(),
        );
        assert_eq!(out.status.code(), Some(0));
        assert!(String::from_utf8_lossy(&out.stdout).contains("denoised in"));
        let plain = read_exr(&dir.join("plain.exr")).unwrap();
        let dn = read_exr(&dir.join("dn.exr")).unwrap();
        let noisy = dn.vec3("noisy.", RGB).expect("noisy.R/G/B");
        assert_eq!(
            Some(noisy.clone()),
            plain.vec3("", RGB),
            "the render, bit for bit"
        );
        let clean = dn.vec3("", RGB).expect("R,G,B");
        assert_ne!(clean, noisy);
        assert!(dir.join("dn.png").is_file());
        // Every other layer is the plain render's.
        assert_eq!(dn.channels.len(), plain.channels.len() + 3);
    }

    /// `--strategy gradient --denoise`: the reconstruction stays as `noisy.R/G/B`,
    /// bit for bit the plain adaptive render's `R,G,B`, and the denoised one (guided
    /// by the one-ray-per-pixel G-buffer) is a different, finite image.
    #[test]
    fn adaptive_render_denoise_keeps_the_reconstruction() {
        let dir = temp_dir("adaptive_cli");
        let scene = cornell();
        let base = [
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "4",
            "--width",
            "48",
            "--height",
            "32",
        ];
        let base = [&base[..], &["--strategy", "gradient", "--budget", "0.25"]].concat();
        let out = run_in(&dir, &[&base[..], &["--out", "plain.exr"]].concat());
        assert_eq!(out.status.code(), Some(0));
        let out = run_in(
            &dir,
            &[&base[..], &["--denoise", "--out", "dn.exr"]].concat(),
        );
        assert_eq!(out.status.code(), Some(0), "{out:?}");
        assert!(String::from_utf8_lossy(&out.stdout).contains("denoised in"));
        let plain = read_exr(&dir.join("plain.exr")).unwrap();
        let dn = read_exr(&dir.join("dn.exr")).unwrap();
        let noisy = dn.vec3("noisy.", RGB).expect("noisy.R/G/B");
        assert_eq!(Some(noisy.clone()), plain.vec3("", RGB));
        let clean = dn.vec3("", RGB).expect("R,G,B");
        assert_ne!(clean, noisy);
        assert!(clean.iter().all(|c| c.is_finite()));
    }
}
