//! Output stage: EXR round trip, PNG tone mapping at known values, and the
//! atomic-write guarantees (a failed write leaves no temporary file and never
//! touches a previous output).

use gradtrace::math::Vec3;
use gradtrace::output::{
    self, read_exr, srgb_oetf, to_srgb8, write_atomic, write_exr, write_png, write_png_exposure,
    Channel, OutputImage,
};
use gradtrace::pipeline::output_set::image_of_render;
use gradtrace::render::{GradientPlanes, RenderOutput, RenderStats};
use gradtrace::Error;
use std::path::{Path, PathBuf};

/// A fresh, empty directory in the system temp dir, unique per test and process.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-output-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every entry of `dir`, sorted (to check that no temporary file was left).
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn assert_output_error(r: gradtrace::Result<()>, path: &Path) {
    match r {
        Err(Error::Output { path: p, message }) => {
            assert_eq!(p, path, "error names the target");
            assert!(!message.is_empty());
            println!("rejected as expected: {}: {message}", p.display());
        }
        other => panic!("expected Error::Output, got {other:?}"),
    }
}

/// Values that exercise the f32 bit patterns: negatives, denormals, large
/// magnitudes, values that f16 could not hold exactly.
fn tricky(n: usize, salt: u32) -> Vec<f32> {
    (0..n)
        .map(|i| {
            let k = (i as u32).wrapping_mul(2_654_435_761).wrapping_add(salt);
            match i % 5 {
                0 => (k as f32) * 1e-7 - 200.0,
                1 => f32::MIN_POSITIVE / 3.0,
                2 => 1.0 + f32::EPSILON * (k % 7) as f32,
                3 => -1.0e30 * (k % 3) as f32,
                _ => 0.1 * i as f32,
            }
        })
        .collect()
}

#[test]
fn exr_round_trip_is_exact() {
    let dir = temp_dir("roundtrip");
    let (w, h) = (7, 5);
    let names = [
        "R",
        "G",
        "B",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "depth.Z",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "object.id",
        "variance.R",
        "variance.G",
        "variance.B",
    ];
    let img = OutputImage {
        width: w,
        height: h,
        channels: names
            .iter()
            .enumerate()
            .map(|(i, n)| Channel {
                name: n.to_string(),
                data: tricky(w * h, i as u32),
            })
            .collect(),
    };
    let path = dir.join("img.exr");
    write_exr(&path, &img).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!((back.width, back.height), (w, h));
    assert_eq!(back.channels.len(), names.len());
    for ch in &img.channels {
        let got = back
            .channel(&ch.name)
            .unwrap_or_else(|| panic!("{} missing", ch.name));
        // Bitwise: f32 storage and lossless compression must not alter one bit.
        let a: Vec<u32> = ch.data.iter().map(|v| v.to_bits()).collect();
        let b: Vec<u32> = got.data.iter().map(|v| v.to_bits()).collect();
        assert_eq!(a, b, "channel {}", ch.name);
    }
    // Rows are top row first: pixel (x=3, y=4) is at index 4*w + 3 in both.
    assert_eq!(
        back.channel("depth.Z").unwrap().data[4 * w + 3],
        img.channel("depth.Z").unwrap().data[4 * w + 3]
    );
    assert_eq!(entries(&dir), vec!["img.exr"], "no temporary file left");
    println!(
        "round trip of {} channels at {w}x{h}: bit-exact",
        names.len()
    );
}

#[test]
fn image_of_render_names_every_plane() {
    let (w, h) = (3, 2);
    let n = w * h;
    let v = |s: f32| {
        (0..n)
            .map(|i| Vec3::new(s, s + i as f32, -s))
            .collect::<Vec<_>>()
    };
    let mut r = RenderOutput {
        width: w,
        height: h,
        spp: 4,
        beauty: v(1.0),
        variance: Some(v(2.0)),
        normal: Some(v(3.0)),
        depth: Some(vec![4.0; n]),
        albedo: Some(v(5.0)),
        object_id: Some(vec![6.0; n]),
        gradients: None,
        stats: RenderStats::default(),
        ..Default::default()
    };
    let img = image_of_render(&r);
    let names: Vec<&str> = img.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "R",
            "G",
            "B",
            "normal.X",
            "normal.Y",
            "normal.Z",
            "depth.Z",
            "albedo.R",
            "albedo.G",
            "albedo.B",
            "object.id",
            "variance.R",
            "variance.G",
            "variance.B"
        ]
    );
    assert_eq!(img.vec3("", output::names::RGB).unwrap(), r.beauty);
    assert_eq!(
        img.vec3("normal.", output::names::XYZ).unwrap(),
        r.normal.clone().unwrap()
    );
    assert_eq!(
        img.channel("G").unwrap().data,
        vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    );

    r.variance = None;
    r.normal = None;
    r.depth = None;
    r.albedo = None;
    r.object_id = None;
    let img = image_of_render(&r);
    let names: Vec<&str> = img.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["R", "G", "B"]);

    let s = |k: f32| vec![k; n];
    r.gradients = Some(GradientPlanes {
        grad_u: v(7.0),
        grad_v: v(8.0),
        sv: s(9.0),
        dv: s(10.0),
        cv: s(11.0),
        cdv: s(12.0),
        vis: s(13.0),
        indirect: s(15.0),
        ratio: s(14.0),
        // In memory only (for `--reconstruct`): no layer below.
        direct: v(16.0),
        direct_u: v(17.0),
        direct_v: v(18.0),
    });
    let img = image_of_render(&r);
    let names: Vec<&str> = img.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "R",
            "G",
            "B",
            "grad.u.R",
            "grad.u.G",
            "grad.u.B",
            "grad.v.R",
            "grad.v.G",
            "grad.v.B",
            "grad.sv.Y",
            "grad.dv.Y",
            "grad.cv.Y",
            "grad.cdv.Y",
            "grad.vis.Y",
            "grad.indirect.Y",
            "grad.ratio.Y"
        ]
    );
    assert_eq!(img.channel("grad.v.B").unwrap().data, vec![-8.0; n]);
    assert_eq!(img.channel("grad.cdv.Y").unwrap().data, s(12.0));
    assert_eq!(img.channel("grad.indirect.Y").unwrap().data, s(15.0));
    assert_eq!(img.channel("grad.ratio.Y").unwrap().data, s(14.0));
}

#[test]
fn srgb_known_values() {
    assert_eq!(to_srgb8(0.0), 0);
    assert_eq!(to_srgb8(1.0), 255);
    assert_eq!(to_srgb8(0.5), 188, "0.5 linear is 187.5.. → 188");
    assert_eq!(to_srgb8(-3.0), 0, "clamped below");
    assert_eq!(to_srgb8(7.0), 255, "clamped above");
    // 18% grey → 0.4613 → 117.6 → 118; the linear toe: 0.002 → 0.02584 → 6.6 → 7.
    assert_eq!(to_srgb8(0.18), 118);
    assert_eq!(to_srgb8(0.002), 7);
    // The two branches of the OETF meet at 0.0031308 (continuity to ~1e-7).
    let knee = 0.003_130_8_f32;
    assert!((12.92 * knee - (1.055 * knee.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
    assert!((srgb_oetf(0.5) - 0.735_356_9).abs() < 1e-6);
}

fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path).unwrap().to_rgb8();
    (img.width(), img.height(), img.into_raw())
}

#[test]
fn png_pixels_at_known_inputs() {
    let dir = temp_dir("png");
    let path = dir.join("img.png");
    // 3x2: row 0 = black, white, mid grey; row 1 = per-channel values, over-range, negative.
    let rgb = vec![
        Vec3::ZERO,
        Vec3::ONE,
        Vec3::splat(0.5),
        Vec3::new(0.0, 0.5, 1.0),
        Vec3::splat(100.0),
        Vec3::splat(-1.0),
    ];
    write_png(&path, &rgb, 3, 2).unwrap();
    let (w, h, px) = read_png(&path);
    assert_eq!((w, h), (3, 2));
    assert_eq!(
        px,
        vec![0, 0, 0, 255, 255, 255, 188, 188, 188, 0, 188, 255, 255, 255, 255, 0, 0, 0]
    );
    // Exposure: +1 stop turns 0.25 into 0.5.
    write_png_exposure(&path, &[Vec3::splat(0.25)], 1, 1, 1.0).unwrap();
    assert_eq!(read_png(&path).2, vec![188, 188, 188]);
    assert_eq!(entries(&dir), vec!["img.png"]);
}

#[test]
fn non_finite_values_are_rejected_and_nothing_is_written() {
    let dir = temp_dir("nan");
    let exr = dir.join("img.exr");
    let png = dir.join("img.png");
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut img = OutputImage::new(2, 2);
        img.push_vec3("", output::names::RGB, &[Vec3::ONE; 4]);
        img.push_scalar("depth.Z", vec![1.0, 2.0, bad, 4.0]);
        assert_output_error(write_exr(&exr, &img), &exr);
        let rgb = [Vec3::ONE, Vec3::new(0.0, bad, 0.0)];
        assert_output_error(write_png(&png, &rgb, 2, 1), &png);
    }
    assert!(
        entries(&dir).is_empty(),
        "nothing written: {:?}",
        entries(&dir)
    );
}

#[test]
fn malformed_images_are_rejected() {
    let dir = temp_dir("malformed");
    let exr = dir.join("img.exr");
    let short = OutputImage {
        width: 2,
        height: 2,
        channels: vec![Channel {
            name: "R".into(),
            data: vec![0.0; 3],
        }],
    };
    assert_output_error(write_exr(&exr, &short), &exr);
    let mut dup = OutputImage::new(1, 1);
    dup.push_scalar("R", vec![0.0]);
    dup.push_scalar("R", vec![1.0]);
    assert_output_error(write_exr(&exr, &dup), &exr);
    let mut bad_name = OutputImage::new(1, 1);
    bad_name.push_scalar("dépth", vec![0.0]);
    assert_output_error(write_exr(&exr, &bad_name), &exr);
    assert_output_error(write_exr(&exr, &OutputImage::new(0, 3)), &exr);
    assert_output_error(write_exr(&exr, &OutputImage::new(2, 2)), &exr);
    let png = dir.join("img.png");
    assert_output_error(write_png(&png, &[Vec3::ONE; 3], 2, 2), &png);
    assert!(entries(&dir).is_empty());
}

fn small_image(value: f32) -> OutputImage {
    let mut img = OutputImage::new(2, 1);
    img.push_vec3("", output::names::RGB, &[Vec3::splat(value); 2]);
    img
}

#[test]
fn missing_directory_is_an_output_error() {
    let dir = temp_dir("missingdir");
    let exr = dir.join("no/such/dir/img.exr");
    assert_output_error(write_exr(&exr, &small_image(1.0)), &exr);
    let png = dir.join("no/such/dir/img.png");
    assert_output_error(write_png(&png, &[Vec3::ONE], 1, 1), &png);
    assert!(entries(&dir).is_empty());
}

#[test]
fn target_that_is_a_directory_fails_after_staging_and_cleans_up() {
    // The temporary file is fully written before the rename fails, so this
    // exercises the cleanup path after a successful encode.
    let dir = temp_dir("isdir");
    let target = dir.join("img.exr");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), b"x").unwrap();
    assert_output_error(write_exr(&target, &small_image(1.0)), &target);
    let png = dir.join("img.png");
    std::fs::create_dir(&png).unwrap();
    assert_output_error(write_png(&png, &[Vec3::ONE], 1, 1), &png);
    assert_eq!(entries(&dir), vec!["img.exr", "img.png"]);
    assert_eq!(entries(&target), vec!["keep"]);
}

#[test]
fn failed_write_keeps_the_previous_output() {
    let dir = temp_dir("keep");
    let exr = dir.join("img.exr");
    write_exr(&exr, &small_image(0.25)).unwrap();
    let before = std::fs::read(&exr).unwrap();

    // Rejected input: the old file stays byte for byte.
    let mut bad = small_image(0.5);
    bad.channels[1].data[0] = f32::NAN;
    assert_output_error(write_exr(&exr, &bad), &exr);
    assert_eq!(std::fs::read(&exr).unwrap(), before);

    // An encoder that fails half-way through: the temporary file existed and had
    // bytes in it, and must be gone; the target is untouched.
    let r = write_atomic(&exr, |w| {
        use std::io::Write;
        w.write_all(&[0u8; 100_000]).map_err(|e| e.to_string())?;
        w.flush().map_err(|e| e.to_string())?;
        Err("simulated encoder failure".into())
    });
    assert_output_error(r, &exr);
    assert_eq!(std::fs::read(&exr).unwrap(), before);
    assert_eq!(entries(&dir), vec!["img.exr"], "no temporary file left");

    // A successful write replaces it.
    write_exr(&exr, &small_image(0.75)).unwrap();
    assert_eq!(
        read_exr(&exr).unwrap().channel("R").unwrap().data,
        vec![0.75; 2]
    );
    assert_eq!(entries(&dir), vec!["img.exr"]);
}

#[test]
fn staged_files_appear_only_on_commit() {
    let dir = temp_dir("staged");
    let exr = dir.join("a.exr");
    let png = dir.join("a.png");
    let s1 = output::stage_exr(&exr, &small_image(1.0)).unwrap();
    let s2 = output::stage_png(&png, &[Vec3::ONE], 1, 1, 0.0).unwrap();
    assert!(!exr.exists() && !png.exists());
    // Anonymous (O_TMPFILE) on Linux: no names at all; elsewhere two hidden
    // temporary names. Never the targets' names.
    let visible = entries(&dir);
    assert!(visible.len() <= 2, "{visible:?}");
    assert!(visible
        .iter()
        .all(|e| e.starts_with('.') && e.contains(".gtmp-")));
    drop(s2); // abandoned: its temporary file goes away
    s1.commit().unwrap();
    assert_eq!(entries(&dir), vec!["a.exr"]);
}

#[test]
fn read_exr_reports_missing_and_corrupt_files() {
    let dir = temp_dir("readerr");
    let missing = dir.join("nope.exr");
    assert!(matches!(read_exr(&missing), Err(Error::Io { .. })));
    let junk = dir.join("junk.exr");
    std::fs::write(&junk, b"not an exr file at all").unwrap();
    match read_exr(&junk) {
        Err(Error::Asset { path, .. }) | Err(Error::Io { path, .. }) => assert_eq!(path, junk),
        other => panic!("expected an error, got {other:?}"),
    }
}
