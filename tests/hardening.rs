//! Regression tests for the scene-input defects of issue 18 and the parser
//! refactor of issue 11: magnitude limits, header-size checks, exact array
//! lengths, misleading messages, input-size limits, the generic unread-key
//! check, and lights as shapes with emission. (The output-file defects are in
//! `atomic_kill.rs`.)

use gradtrace::math::Vec3;
use gradtrace::output::{self, atomic, OutputImage};
use gradtrace::scene::{self, MAX_MAGNITUDE};
use std::path::{Path, PathBuf};

const CAM: &str = "[camera]\nfrom = [0, 1, 5]\nto = [0, 0, 0]\nfov = 40\nresolution = [64, 48]\n";
const WHITE: &str = "[materials.w]\ntype = \"lambert\"\nalbedo = [1, 1, 1]\n";

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gradtrace-hard-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The one-line error of loading `text` as `dir/bad.toml`.
fn err_in(dir: &Path, text: &str) -> String {
    match scene::load_from_str(text, &dir.join("bad.toml")) {
        Ok(_) => panic!("scene should not load:\n{text}"),
        Err(e) => {
            let msg = e.to_string();
            println!("{msg}");
            assert!(!msg.contains('\n'), "one line: {msg}");
            msg
        }
    }
}

fn err_of(text: &str) -> String {
    err_in(Path::new("dir"), text)
}

fn assert_has(msg: &str, wanted: &[&str]) {
    for w in wanted {
        assert!(msg.contains(w), "message lacks {w:?}: {msg}");
    }
}

fn loads(text: &str) -> scene::Scene {
    scene::load_from_str(text, Path::new("dir/ok.toml"))
        .unwrap_or_else(|e| panic!("should load: {e}\n{text}"))
}

const SQUARE_OBJ: &str = "o sq\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";

#[test]
fn positions_radii_and_camera_beyond_max_magnitude_are_errors_naming_key_and_limit() {
    assert_eq!(MAX_MAGNITUDE, 1e12);
    let dir = scratch("magnitude");
    std::fs::write(
        dir.join("sq.obj"),
        SQUARE_OBJ.replace("v 1 1 0", "v 100 1 0"),
    )
    .unwrap();
    std::fs::write(
        dir.join("far.obj"),
        SQUARE_OBJ.replace("v 1 1 0", "v 1 1e30 0"),
    )
    .unwrap();
    let w = WHITE;
    let sphere = |c: &str, r: &str| {
        format!(
            "{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = {c}\nradius = {r}\nmaterial = \"w\"\n"
        )
    };
    let cases: Vec<(String, Vec<&str>)> = vec![
        (sphere("[0, 0, 0]", "1e19"), vec!["shapes[0].radius", "line 12"]),
        (sphere("[1e30, 0, 0]", "1"), vec!["shapes[0].center", "line 11"]),
        (sphere("[9e11, 0, 0]", "2e11"), vec!["shapes[0].radius"]),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\ncorner = [1e30, 0, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\nmaterial = \"w\"\n"),
            vec!["shapes[0].corner", "line 11"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"cube\"\nmaterial = \"w\"\ntransform = {{ translate = [2e12, 0, 0] }}\n"),
            vec!["shapes[0].transform", "line 12"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"cube\"\nmaterial = \"w\"\ntransform = {{ scale = 1e13 }}\n"),
            vec!["shapes[0].transform"],
        ),
        (
            format!("{CAM}[[lights]]\ntype = \"rect\"\nsize = [1e13, 1]\nradiance = [1, 1, 1]\n"),
            vec!["lights[0].size", "line 8"],
        ),
        (
            format!("{CAM}[[lights]]\ntype = \"sphere\"\ncenter = [0, 1e13, 0]\nradius = 1\nradiance = [1, 1, 1]\n"),
            vec!["lights[0].center"],
        ),
        (
            CAM.replace("from = [0, 1, 5]", "from = [0, 1, 1e13]") + "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n",
            vec!["camera.from", "line 2"],
        ),
        (
            CAM.replace("to = [0, 0, 0]", "to = [-3e12, 0, 0]") + "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n",
            vec!["camera.to", "line 3"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"mesh\"\nfile = \"sq.obj\"\nmaterial = \"w\"\ntransform = {{ scale = 1e11 }}\n"),
            vec!["shapes[0].file", "line 11", "sq.obj", "vertex"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"mesh\"\nfile = \"far.obj\"\nmaterial = \"w\"\n"),
            vec!["shapes[0].file", "far.obj", "1e30"],
        ),
    ];
    for (text, wanted) in &cases {
        let msg = err_in(&dir, text);
        assert_has(&msg, wanted);
        assert_has(&msg, &["1e12", "MAX_MAGNITUDE"]);
    }
    // At the limit everything still loads.
    loads(&sphere("[0, 0, 0]", "1e12"));
    loads(&format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\ncorner = [-1e12, 0, 1e12]\nedge_u = [2e12, 0, 0]\nedge_v = [0, 0, -2e12]\nmaterial = \"w\"\n"));
}

#[test]
fn huge_perpendicular_edges_are_reported_as_out_of_range_not_parallel() {
    let quad = |u: &str, v: &str| {
        format!("{CAM}{WHITE}[[shapes]]\ntype = \"quad\"\ncorner = [0, 0, 0]\nedge_u = {u}\nedge_v = {v}\nmaterial = \"w\"\n")
    };
    let msg = err_of(&quad("[2e30, 0, 0]", "[0, 0, 2e30]"));
    assert!(!msg.contains("parallel"), "{msg}");
    assert_has(&msg, &["shapes[0].edge_u", "MAX_MAGNITUDE"]);
    // Large but legal perpendicular edges load; truly parallel ones are parallel.
    let s = loads(&quad("[1e11, 0, 0]", "[0, 0, -1e11]"));
    assert!(s.meshes[0].rect.is_some(), "kept as a rectangle");
    assert_has(
        &err_of(&quad("[1e11, 0, 0]", "[2e11, 0, 0]")),
        &["parallel"],
    );
    // Tiny edges whose cross product underflows f32 have no usable normal.
    assert_has(
        &err_of(&quad("[1e-30, 0, 0]", "[0, 0, 1e-30]")),
        &["underflows"],
    );
}

/// A 1×1 EXR whose header is then edited to claim `side`² pixels.
fn exr_claiming(path: &Path, side: i32) {
    let mut img = OutputImage::new(1, 1);
    img.push_vec3("", output::names::RGB, &[Vec3::ONE]);
    output::write_exr(path, &img).unwrap();
    let mut bytes = std::fs::read(path).unwrap();
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes
            .windows(name.len())
            .position(|w| w == name)
            .expect("attribute present")
            + name.len()
            + 4; // the attribute's byte size
                 // xMin, yMin, xMax, yMax
        bytes[at + 8..at + 12].copy_from_slice(&(side - 1).to_le_bytes());
        bytes[at + 12..at + 16].copy_from_slice(&(side - 1).to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn an_environment_image_whose_header_claims_100000_squared_texels_is_an_error() {
    let dir = scratch("bigheader");
    exr_claiming(&dir.join("huge.exr"), 100_000);
    let hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n\x80\x80\x80\x81";
    std::fs::write(dir.join("huge.hdr"), hdr).unwrap();
    for file in ["huge.exr", "huge.hdr"] {
        let text = format!("{CAM}[environment]\ntype = \"image\"\nfile = \"{file}\"\n");
        let msg = err_in(&dir, &text);
        assert_has(&msg, &["environment.file", "line 8", file, "100000"]);
    }
    // The EXR reader of the output stage checks the header the same way.
    let e = output::read_exr(&dir.join("huge.exr"))
        .unwrap_err()
        .to_string();
    assert_has(&e, &["100000×100000"]);
    // A sane edited header still loads (the check is not over-eager).
    exr_claiming(&dir.join("one.exr"), 1);
    scene::load_from_str(
        &format!("{CAM}[environment]\ntype = \"image\"\nfile = \"one.exr\"\n"),
        &dir.join("ok.toml"),
    )
    .unwrap();
}

#[test]
fn fixed_length_arrays_reject_extra_and_missing_elements_on_every_key() {
    let w = WHITE;
    // (scene with `@` where the array goes, the array, key path, expected wording)
    let sphere = |k: &str| {
        format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"w\"\n{k} = @\n")
    };
    let quad = format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\nmaterial = \"w\"\n");
    let env = |kind: &str, extra: &str| format!("{CAM}[environment]\ntype = \"{kind}\"\n{extra}");
    let cases: Vec<(String, &str, &str, &str)> = vec![
        (CAM.replace("[0, 1, 5]", "@") + "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n", "[0, 1, 5]", "camera.from", "length 3"),
        (CAM.replace("to = [0, 0, 0]", "to = @") + "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n", "[0, 0, 0]", "camera.to", "length 3"),
        (format!("{CAM}up = @\n[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n"), "[0, 1, 0]", "camera.up", "length 3"),
        (CAM.replace("[64, 48]", "@") + "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n", "[64, 48]", "camera.resolution", "length 2"),
        (format!("{CAM}[materials.m]\ntype = \"lambert\"\nalbedo = @\n"), "[0.8, 0.8, 0.8]", "materials.m.albedo", "length 3"),
        (format!("{CAM}[materials.m]\ntype = \"blinn_phong\"\nkd = @\nks = [1, 1, 1]\nexponent = 1\n"), "[0.8, 0.8, 0.8]", "materials.m.kd", "length 3"),
        (format!("{CAM}[materials.m]\ntype = \"cook_torrance\"\nkd = [1, 1, 1]\nks = @\nexponent = 1\n"), "[0.8, 0.8, 0.8]", "materials.m.ks", "length 3"),
        (format!("{CAM}[materials.m]\ntype = \"mirror\"\nreflectance = @\n"), "[0.8, 0.8, 0.8]", "materials.m.reflectance", "length 3"),
        (sphere("emission"), "[1, 1, 1]", "shapes[0].emission", "length 3"),
        (format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = @\nradius = 1\nmaterial = \"w\"\n"), "[0, 0, 0]", "shapes[0].center", "length 3"),
        (format!("{quad}corner = @\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\n"), "[0, 0, 0]", "shapes[0].corner", "length 3"),
        (format!("{quad}corner = [0, 0, 0]\nedge_u = @\nedge_v = [0, 0, 1]\n"), "[1, 0, 0]", "shapes[0].edge_u", "length 3"),
        (format!("{quad}corner = [0, 0, 0]\nedge_u = [1, 0, 0]\nedge_v = @\n"), "[0, 0, 1]", "shapes[0].edge_v", "length 3"),
        (format!("{quad}size = @\n"), "[1, 2]", "shapes[0].size", "length 2"),
        (format!("{quad}transform = {{ translate = @ }}\n"), "[0, 1, 0]", "shapes[0].transform.translate", "length 3"),
        (format!("{quad}transform = {{ scale = @ }}\n"), "[1, 2, 3]", "shapes[0].transform.scale", "length 3"),
        (format!("{quad}transform = {{ rotate = @ }}\n"), "[0, 1, 0, 30]", "shapes[0].transform.rotate", "degrees]"),
        (format!("{quad}transform = {{ rotate = [@] }}\n"), "[0, 1, 0, 30]", "shapes[0].transform.rotate", "degrees]"),
        (format!("{quad}transform = {{ matrix = [@, [0, 1, 0, 0], [0, 0, 1, 0]] }}\n"), "[1, 0, 0, 0]", "shapes[0].transform.matrix[0]", "length 4"),
        (format!("{CAM}[[lights]]\ntype = \"sphere\"\ncenter = [0, 2, 0]\nradius = 1\nradiance = @\n"), "[1, 1, 1]", "lights[0].radiance", "length 3"),
        (format!("{CAM}[[lights]]\ntype = \"sphere\"\ncenter = @\nradius = 1\nradiance = [1, 1, 1]\n"), "[0, 2, 0]", "lights[0].center", "length 3"),
        (format!("{CAM}{w}[bumps.b]\ntype = \"sinusoids\"\nterms = [{{ amplitude = 0.1, frequency = @ }}]\n[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"w\"\nbump = \"b\"\n"), "[2, 1]", "bumps.b.terms[0].frequency", "length 2"),
        (env("constant", "radiance = @\n"), "[1, 1, 1]", "environment.radiance", "length 3"),
        (env("gaussian_sky", "direction = @\nsharpness = 1\npeak = [1, 1, 1]\n"), "[0, 1, 0]", "environment.direction", "length 3"),
        (env("gaussian_sky", "sharpness = 1\npeak = @\n"), "[1, 1, 1]", "environment.peak", "length 3"),
        (env("gaussian_sky", "sharpness = 1\npeak = [1, 1, 1]\nambient = @\n"), "[1, 1, 1]", "environment.ambient", "length 3"),
    ];
    let mut checked = 0;
    for (template, good, key, wording) in &cases {
        let lit = ["[[shapes]]", "[[lights]]", "[environment]"];
        let template = &if lit.iter().any(|l| template.contains(l)) {
            template.clone()
        } else {
            format!("{template}[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n")
        };
        // The well-formed array loads (so the failures below are the array's).
        loads(&template.replace('@', good));
        let inner = good.trim_start_matches('[').trim_end_matches(']');
        let shorter = inner.rsplit_once(", ").map(|(a, _)| a).unwrap();
        for bad in [
            format!("[{inner}, 9]"),
            format!("[{inner}, \"x\"]"),
            format!("[{inner}, nan]"),
            format!("[{shorter}]"),
        ] {
            let msg = err_of(&template.replace('@', &bad));
            assert_has(&msg, &[key, wording]);
            checked += 1;
        }
    }
    println!(
        "{checked} malformed arrays on {} keys rejected",
        cases.len()
    );
}

#[test]
fn a_folder_given_as_mesh_or_environment_is_called_a_folder() {
    let dir = scratch("folder");
    std::fs::create_dir_all(dir.join("models")).unwrap();
    let mesh =
        format!("{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"models\"\nmaterial = \"w\"\n");
    let env = format!("{CAM}[environment]\ntype = \"image\"\nfile = \"models\"\n");
    for (text, key) in [(mesh, "shapes[0].file"), (env, "environment.file")] {
        let msg = err_in(&dir, &text);
        assert_has(&msg, &[key, "is a directory", "models"]);
        assert!(!msg.contains("not found"), "{msg}");
    }
}

#[test]
fn mesh_and_environment_errors_name_the_scene_key_line_and_asset() {
    let dir = scratch("asset-key");
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n").unwrap();
    std::fs::write(dir.join("bad.hdr"), "not an image").unwrap();
    std::fs::write(dir.join("bad.exr"), "not an image").unwrap();
    let mesh =
        format!("{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"bad.obj\"\nmaterial = \"w\"\n");
    let msg = err_in(&dir, &mesh);
    assert_has(
        &msg,
        &[
            "bad.toml: shapes[0].file (line 11",
            "bad.obj",
            "invalid OBJ",
        ],
    );
    for file in ["bad.hdr", "bad.exr"] {
        let env = format!("{CAM}[environment]\ntype = \"image\"\nfile = \"{file}\"\n");
        let msg = err_in(&dir, &env);
        assert_has(&msg, &["bad.toml: environment.file (line 8", file]);
    }
}

#[test]
fn a_missing_or_unreadable_mtl_library_is_named() {
    let dir = scratch("mtl");
    std::fs::create_dir_all(dir.join("folder.mtl")).unwrap();
    for mtl in ["missing.mtl", "folder.mtl"] {
        let obj = format!("mtllib {mtl}\nusemtl red\n{SQUARE_OBJ}");
        std::fs::write(dir.join("m.obj"), obj).unwrap();
        let text = format!("{CAM}[[shapes]]\ntype = \"mesh\"\nfile = \"m.obj\"\n");
        let msg = err_in(&dir, &text);
        assert_has(&msg, &["shapes[0].file (line 8", "m.obj", mtl, "MTL"]);
    }
}

/// A bad value inside an MTL library names the scene key, the OBJ, and the MTL
/// file and line that set it (tobj alone does not say which library it was).
#[test]
fn a_bad_mtl_value_names_the_mtl_file_and_line() {
    let dir = scratch("mtl_value");
    let mtl = "newmtl red\nKd 0.8 0.1 0.1\n\nnewmtl shiny\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nNs -3\n";
    std::fs::write(dir.join("good.mtl"), "newmtl blue\nKd 0.1 0.1 0.8\n").unwrap();
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    let obj = format!("mtllib good.mtl\nmtllib m.mtl\nusemtl shiny\n{SQUARE_OBJ}");
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let text = format!("{CAM}[[shapes]]\ntype = \"mesh\"\nfile = \"m.obj\"\n");
    let msg = err_in(&dir, &text);
    assert_has(
        &msg,
        &[
            "shapes[0].file (line 8",
            "m.obj",
            "m.mtl line 7",
            "`shiny`",
            "`Ns`",
            "-3",
        ],
    );
    assert!(!msg.contains("good.mtl"), "{msg}");
    let mtl = mtl
        .replace("Kd 0.8 0.1 0.1", "Kd 0.8 -0.1 0.1")
        .replace("Ns -3", "Ns 3");
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    assert_has(&err_in(&dir, &text), &["m.mtl line 2", "`red`", "`Kd`"]);
}

#[test]
fn scene_files_are_size_limited_and_must_be_regular_files() {
    let dir = scratch("limits");
    let t0 = std::time::Instant::now();
    let zero = scene::load(Path::new("/dev/zero")).unwrap_err().to_string();
    assert_has(
        &zero,
        &["/dev/zero", "character device", "not a regular file"],
    );
    assert!(t0.elapsed().as_secs() < 2, "refused at once, not read");
    assert_has(
        &scene::load(&dir).unwrap_err().to_string(),
        &["a directory"],
    );
    // A sparse file just over the limit.
    let big = dir.join("big.toml");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(scene::MAX_SCENE_BYTES + 1).unwrap();
    assert_has(
        &scene::load(&big).unwrap_err().to_string(),
        &["big.toml", "16 MiB"],
    );
    let text = "#".repeat(scene::MAX_SCENE_BYTES as usize + 1);
    let e = scene::load_from_str(&text, Path::new("x.toml"))
        .unwrap_err()
        .to_string();
    assert_has(&e, &["16 MiB"]);
    let bin = dir.join("bin.toml");
    std::fs::write(&bin, b"[camera]\nfrom = \xff\n").unwrap();
    assert_has(&scene::load(&bin).unwrap_err().to_string(), &["not UTF-8"]);
    // A FIFO would block a reader forever; it is refused before opening.
    let fifo = dir.join("fifo.toml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        assert_has(&scene::load(&fifo).unwrap_err().to_string(), &["FIFO"]);
    }
}

#[test]
fn one_unread_key_check_covers_every_table() {
    let dir = scratch("unread");
    std::fs::write(dir.join("sq.obj"), SQUARE_OBJ).unwrap();
    std::fs::write(
        dir.join("sky.hdr"),
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n\x80\x80\x80\x81\x80\x40\x20\x82",
    )
    .unwrap();
    let w = WHITE;
    let bump =
        "[bumps.b]\ntype = \"sinusoids\"\nterms = [{ amplitude = 0.1, frequency = [2, 1] }]\n";
    let light =
        "[[lights]]\ntype = \"sphere\"\ncenter = [0, 3, 0]\nradius = 1\nradiance = [1, 1, 1]\n";
    // (a valid scene with `@` where `zzz = 1` goes, the text inserted there, the
    // key path of the error, a listed valid key)
    let cases: Vec<(String, &str, &str, &str)> = vec![
        (format!("@{CAM}{light}"), "", "zzz", "`camera`"),
        (format!("{CAM}@{light}"), "", "camera.zzz", "`resolution`"),
        (format!("{CAM}[render]\nspp = 1\n@{light}"), "", "render.zzz", "`rr_depth`"),
        (format!("{CAM}{w}@{light}"), "", "materials.w.zzz", "`albedo`"),
        (format!("{CAM}{bump}@{light}"), "", "bumps.b.zzz", "`terms`"),
        (format!("{CAM}{}{light}", bump.replace("[2, 1]", "[2, 1]@")), ", zzz = 1", "bumps.b.terms[0].zzz", "`phase`"),
        (format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"w\"\n@"), "", "shapes[0].zzz", "`radius`"),
        (format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\nmaterial = \"w\"\n@"), "", "shapes[0].zzz", "`edge_u`"),
        (format!("{CAM}{w}[[shapes]]\ntype = \"cube\"\nmaterial = \"w\"\n@"), "", "shapes[0].zzz", "`transform`"),
        (format!("{CAM}{w}[[shapes]]\ntype = \"mesh\"\nfile = \"sq.obj\"\nmaterial = \"w\"\n@"), "", "shapes[0].zzz", "`smooth_normals`"),
        (format!("{CAM}{w}[[shapes]]\ntype = \"cube\"\nmaterial = \"w\"\ntransform = {{ scale = 2@ }}\n"), ", zzz = 1", "shapes[0].transform.zzz", "`matrix`"),
        (format!("{CAM}{light}@"), "", "lights[0].zzz", "`radiance`"),
        (format!("{CAM}[[lights]]\ntype = \"rect\"\nradiance = [1, 1, 1]\n@"), "", "lights[0].zzz", "`size`"),
        (format!("{CAM}[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n@"), "", "environment.zzz", "`radiance`"),
        (format!("{CAM}[environment]\ntype = \"image\"\nfile = \"sky.hdr\"\n@"), "", "environment.zzz", "`scale`"),
        (format!("{CAM}[environment]\ntype = \"gaussian_sky\"\nsharpness = 1\npeak = [1, 1, 1]\n@"), "", "environment.zzz", "`ambient`"),
    ];
    for (template, insert, key, listed) in &cases {
        scene::load_from_str(&template.replace('@', ""), &dir.join("ok.toml"))
            .unwrap_or_else(|e| panic!("{e}\n{template}"));
        let insert = if insert.is_empty() {
            "zzz = 1\n"
        } else {
            insert
        };
        let text = template.replace('@', insert);
        let msg = err_in(&dir, &text);
        assert_has(&msg, &[&format!("{key} (line "), listed]);
    }
}

#[test]
fn a_light_is_a_shape_with_emission() {
    // The same sphere and rectangle as `[[lights]]` and as emitting `[[shapes]]`.
    let lights = format!(
        "{CAM}[[lights]]\ntype = \"sphere\"\ncenter = [1, 2, 3]\nradius = 0.5\nradiance = [4, 5, 6]\n\
         [[lights]]\ntype = \"rect\"\ncorner = [0, 2, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\nradiance = [7, 8, 9]\n"
    );
    let shapes = format!(
        "{CAM}[materials.black]\ntype = \"lambert\"\nalbedo = [0, 0, 0]\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [1, 2, 3]\nradius = 0.5\nmaterial = \"black\"\nemission = [4, 5, 6]\n\
         [[shapes]]\ntype = \"quad\"\ncorner = [0, 2, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\nmaterial = \"black\"\nemission = [7, 8, 9]\n"
    );
    let (a, b) = (loads(&lights), loads(&shapes));
    assert_eq!(a.spheres.len(), 1);
    assert_eq!(
        (
            a.spheres[0].center,
            a.spheres[0].radius,
            a.spheres[0].emission
        ),
        (
            b.spheres[0].center,
            b.spheres[0].radius,
            b.spheres[0].emission
        )
    );
    let (qa, qb) = (&a.meshes[0], &b.meshes[0]);
    assert_eq!(
        (&qa.positions, &qa.triangles, qa.emission, qa.rect),
        (&qb.positions, &qb.triangles, qb.emission, qb.rect)
    );
    assert_eq!(a.material_names, ["(lights)"]);
    assert_eq!(a.object_names, ["light1", "light2"]);
    assert_eq!(b.object_names, ["sphere1", "quad2"]);
    assert_eq!(a.emitter_count(), 2);
    assert_eq!(b.emitter_count(), 2);
}

#[test]
fn pair_files_carry_one_render_id_and_the_same_pixels_as_before() {
    let dir = scratch("pair");
    let beauty: Vec<Vec3> = (0..12)
        .map(|i| Vec3::new(i as f32 / 12.0, 0.5, 2.0))
        .collect();
    let mut img = OutputImage::new(4, 3);
    img.push_vec3("", output::names::RGB, &beauty);
    let (exr, png) = (dir.join("a.exr"), dir.join("a.png"));
    let id = atomic::write_pair(&exr, &img, &png, &beauty, 0.0).unwrap();
    assert_eq!(id.len(), 32);
    assert_eq!(
        atomic::check_pair(&exr, &png).unwrap(),
        atomic::PairState::Consistent(id.clone())
    );
    // Deterministic: the same image gets the same id; another image another.
    assert_eq!(atomic::render_id(&beauty, 4, 3, 0.0), id);
    assert_ne!(atomic::render_id(&beauty, 4, 3, 1.0), id);
    // The tagged files hold exactly what the untagged writers write.
    output::write_exr(&dir.join("b.exr"), &img).unwrap();
    output::write_png(&dir.join("b.png"), &beauty, 4, 3).unwrap();
    assert_eq!(
        output::read_exr(&exr).unwrap(),
        output::read_exr(&dir.join("b.exr")).unwrap()
    );
    let decode = |p: &Path| {
        let mut r = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()))
            .read_info()
            .unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        r.next_frame(&mut buf).unwrap();
        buf
    };
    assert_eq!(decode(&png), decode(&dir.join("b.png")));
    // Untagged files are reported as not provably a pair.
    assert!(matches!(
        atomic::check_pair(&dir.join("b.exr"), &dir.join("b.png")).unwrap(),
        atomic::PairState::Mismatched {
            exr: None,
            png: None
        }
    ));
}

/// Issue 57 item 7: every bad `obj_sequence` is one line naming the scene key and
/// line, and the frame file and number with what was expected and found.
#[test]
fn obj_sequence_errors_name_the_key_the_frame_file_and_the_mismatch() {
    let dir = scratch("objseq");
    std::fs::write(dir.join("sq.obj"), SQUARE_OBJ).unwrap();
    let moved = |dy: f32| {
        SQUARE_OBJ
            .lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(rest) => {
                    let v: Vec<f32> = rest.split(' ').map(|x| x.parse().unwrap()).collect();
                    format!("v {} {} {}\n", v[0], v[1] + dy, v[2])
                }
                None => format!("{l}\n"),
            })
            .collect::<String>()
    };
    for k in 0..3 {
        std::fs::write(dir.join(format!("sq_{k}.obj")), moved(0.1 * k as f32)).unwrap();
    }
    // Frame 1 of each broken set differs from the rest mesh in one way.
    let broken = [
        // (tobj keeps only the vertices faces use: the extra one is used.)
        (
            "extra_vertex",
            format!("{}v 9 9 9\nf 1/1 3/3 5/4\n", moved(0.1)),
        ),
        ("extra_face", format!("{}f 1/1 2/2 4/4\n", moved(0.1))),
        (
            "other_faces",
            moved(0.1).replace("f 1/1 3/3 4/4", "f 2/2 4/4 3/3"),
        ),
        ("nan", moved(0.1).replace("v 1 1.1 0", "v 1 nan 0")),
        (
            "two_objects",
            format!("{}o more\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf 5 6 7\n", moved(0.1)),
        ),
    ];
    for (name, text) in &broken {
        std::fs::write(dir.join(format!("{name}_0.obj")), moved(0.0)).unwrap();
        std::fs::write(dir.join(format!("{name}_1.obj")), text).unwrap();
    }
    let scene = |extra: &str| {
        format!(
            "{CAM}{WHITE}[[shapes]]\nname = \"plate\"\ntype = \"mesh\"\nfile = \"sq.obj\"\n\
             material = \"w\"\n[[shapes]]\nname = \"ball\"\ntype = \"sphere\"\n\
             center = [0, 3, 0]\nradius = 0.5\nmaterial = \"w\"\n\
             [animation]\n[[animation.objects]]\n{extra}"
        )
    };
    let seq = |shape: &str, pattern: &str, range: &str| {
        scene(&format!(
            "shape = \"{shape}\"\nobj_sequence = \"{pattern}\"\nframes = {range}\n"
        ))
    };
    // The sequence's line in `scene`: CAM 5 + WHITE 3 + shapes 11 + block 2, then
    // `shape`, so `obj_sequence` is line 23 and `frames` line 24.
    let key = "bad.toml: animation.objects[0].obj_sequence (line 23";
    let frames_key = "bad.toml: animation.objects[0].frames (line 24";
    let sq = dir.join("sq.obj").display().to_string();
    let cases: Vec<(String, Vec<String>)> = vec![
        (
            seq("plate", "sq_#.obj", "[0, 3]"),
            vec![
                key.into(),
                "frame 3 of [0, 3]".into(),
                "file not found".into(),
                "sq_3.obj".into(),
            ],
        ),
        (
            seq("plate", "extra_vertex_#.obj", "[0, 1]"),
            vec![
                key.into(),
                "extra_vertex_1.obj (frame 1) has 5 vertices in object `sq` where".into(),
                format!("{sq} has 4"),
            ],
        ),
        (
            seq("plate", "extra_face_#.obj", "[0, 1]"),
            vec![
                key.into(),
                "extra_face_1.obj (frame 1) has 3 triangles in object `sq` where".into(),
                format!("{sq} has 2"),
            ],
        ),
        (
            seq("plate", "other_faces_#.obj", "[0, 1]"),
            vec![
                key.into(),
                "other_faces_1.obj (frame 1) has other triangle indices in object `sq`".into(),
                format!("expected the topology of the shape's mesh {sq}"),
            ],
        ),
        (
            seq("plate", "nan_#.obj", "[0, 1]"),
            vec![
                key.into(),
                "nan_1.obj (frame 1): vertex 3 of object `sq`".into(),
                "expected finite coordinates".into(),
            ],
        ),
        (
            seq("plate", "two_objects_#.obj", "[0, 1]"),
            vec![
                key.into(),
                "two_objects_1.obj (frame 1) has 2 OBJ objects where".into(),
                format!("{sq} has 1"),
            ],
        ),
        (
            seq("plate", "sq_.obj", "[0, 2]"),
            vec![
                key.into(),
                "expected a frame-number placeholder in \"sq_.obj\": a run of `#`".into(),
            ],
        ),
        (
            seq("plate", "sq_#_#.obj", "[0, 2]"),
            vec![key.into(), "expected one run of `#`".into(), "got 2".into()],
        ),
        (
            seq("plate", "sq_#.obj", "[2, 1]"),
            vec![
                frames_key.into(),
                "empty frame range [2, 1]: expected [first, last] with first ≤ last".into(),
            ],
        ),
        (
            seq("ball", "sq_#.obj", "[0, 2]"),
            vec![
                key.into(),
                "shape `ball` is of type = \"sphere\"; an `obj_sequence` deforms a shape of \
                 type = \"mesh\""
                    .into(),
            ],
        ),
        (
            seq("cloth", "sq_#.obj", "[0, 2]"),
            vec![
                "animation.objects[0].shape (line 22".into(),
                "undefined shape `cloth`; defined shapes: `plate`, `ball`".into(),
            ],
        ),
        (
            scene(
                "shape = \"plate\"\ndeform = { type = \"bend\", amount = [0, 1] }\n\
                 obj_sequence = \"sq_#.obj\"\nframes = [0, 2]\n",
            ),
            vec![
                "animation.objects[0].obj_sequence (line 24".into(),
                "give either `deform` or `obj_sequence`, not both".into(),
            ],
        ),
        (
            scene("shape = \"plate\"\nobj_sequence = \"sq_#.obj\"\n"),
            vec![key.into(), "needs `frames = [first, last]`".into()],
        ),
        (
            scene("shape = \"plate\"\nframes = [0, 2]\n"),
            vec![
                "animation.objects[0].frames (line 23".into(),
                "an `obj_sequence`, which is missing".into(),
            ],
        ),
    ];
    for (text, wanted) in &cases {
        let msg = err_in(&dir, text);
        let wanted: Vec<&str> = wanted.iter().map(String::as_str).collect();
        assert_has(&msg, &wanted);
    }
    // The good sequence loads, its files counted as assets (cache keys see them).
    let ok =
        scene::load_from_str(&seq("plate", "sq_#.obj", "[0, 2]"), &dir.join("ok.toml")).unwrap();
    let anim = ok.animation.as_ref().unwrap();
    assert_eq!(anim.frames, 3, "the sequence's length is the default count");
    assert!(ok.assets.iter().any(|a| a.ends_with("sq_2.obj")));
}
