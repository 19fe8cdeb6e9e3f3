//! Scene loading: located error messages for malformed files, OBJ/MTL loading,
//! environment images, and every bundled scene.

use gradtrace::brdf::Material;
use gradtrace::math::{cross, Vec3};
use gradtrace::scene::{self, Environment, Scene};
use std::path::{Path, PathBuf};

/// Five lines: every malformed case below starts on line 6.
const CAM: &str = "[camera]\nfrom = [0, 1, 5]\nto = [0, 0, 0]\nfov = 40\nresolution = [64, 48]\n";
const WHITE: &str = "[materials.w]\ntype = \"lambert\"\nalbedo = [1, 1, 1]\n"; // lines 6-8

fn err_of(text: &str) -> String {
    match scene::load_from_str(text, Path::new("dir/bad.toml")) {
        Ok(_) => panic!("scene should not load:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A scratch directory for files a test writes; unique per test and process.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gradtrace-scene-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn malformed_scenes_name_key_line_and_choices() {
    let w = WHITE;
    // (scene text, substrings the one-line message must contain)
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            format!("{CAM}fov_y = 3\n"),
            vec!["camera.fov_y", "line 6", "unknown field `fov_y`", "`fov`, `resolution`"],
        ),
        (
            "[camera]\nfrom = [0, 1, 5]\n".into(),
            vec!["camera", "line 1", "missing field `to`"],
        ),
        (
            format!("{CAM}[materials.w]\ntype = \"lambret\"\n"),
            vec!["materials.w.type", "line 7", "`lambert`, `blinn_phong`, `cook_torrance`, `mirror`"],
        ),
        (
            format!("{CAM}[materials.w]\ntype = \"lambert\"\nalbedo = [1, 1]\n"),
            vec!["materials.w.albedo", "line 8", "array of length 3"],
        ),
        (
            format!("{CAM}[materials.w]\ntype = \"mirror\"\nalbedo = [1, 1, 1]\n"),
            vec!["materials.w.albedo", "line 8", "does not apply", "`reflectance`"],
        ),
        (
            format!("{CAM}[materials.w]\ntype = \"blinn_phong\"\nkd = [1, 1, 1]\nks = [1, 1, 1]\n"),
            vec!["materials.w", "line 6", "needs `exponent`"],
        ),
        (
            format!("{CAM}[materials.w]\ntype = \"lambert\"\nalbedo = [1, nan, 1]\n"),
            vec!["materials.w.albedo", "line 8", "finite"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\nmaterial = \"w\"\n"),
            vec!["shapes[0].radius", "line 12", "positive", "-1"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nmaterial = \"w\"\n"),
            vec!["shapes[0]", "line 9", "needs `radius`"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"wihte\"\n"),
            vec!["shapes[0].material", "line 13", "undefined material `wihte`", "`w`"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"w\"\nbump = \"b\"\n"),
            vec!["shapes[0].bump", "line 14", "undefined bump `b`", "no [bumps.NAME]"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = \"big\"\nmaterial = \"w\"\n"),
            vec!["shapes[0].radius", "line 12", "expected f32"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"spher\"\n"),
            vec!["shapes[0].type", "line 10", "`sphere`, `quad`, `cube`, `mesh`"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\nmaterial = \"w\"\n"),
            vec!["shapes[0]", "line 9", "missing field `type`", "`sphere`, `quad`, `cube`, `mesh`"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\nradius = 1\nmaterial = \"w\"\n"),
            vec!["shapes[0].radius", "line 11", "does not apply to type = \"quad\"", "`corner`"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\ncorner = [0, 0, 0]\nedge_u = [0, 0, 0]\nedge_v = [0, 0, 1]\nmaterial = \"w\"\n"),
            vec!["shapes[0].edge_u", "line 12", "non-zero length"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\ncorner = [0, 0, 0]\nedge_u = [1, 0, 0]\nmaterial = \"w\"\n"),
            vec!["shapes[0]", "line 9", "`edge_v` is missing"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\nmaterial = \"w\"\ntransform = {{ rotate = [1, 0, 0] }}\n"),
            vec!["shapes[0].transform.rotate", "line 12", "[axis_x, axis_y, axis_z, degrees]"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"quad\"\nmaterial = \"w\"\ntransform = {{ skew = 1 }}\n"),
            vec!["shapes[0].transform.skew", "line 12", "`scale`, `rotate`, `translate`, `matrix`"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"cube\"\nmaterial = \"w\"\ntransform = {{ scale = [1, 0, 1] }}\n"),
            vec!["shapes[0].transform", "line 12", "singular"],
        ),
        (
            format!("{CAM}{w}[[shapes]]\ntype = \"mesh\"\nfile = \"models/missing.obj\"\nmaterial = \"w\"\n"),
            vec!["shapes[0].file", "line 11", "file not found", "missing.obj"],
        ),
        (
            format!("{CAM}{w}[bumps.b]\ntype = \"sinusoids\"\nterms = [{{ amplitude = 0.1, frequency = [2.5, 1] }}]\n[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"w\"\nbump = \"b\"\n"),
            vec!["shapes[0].bump", "line 17", "integer", "2.5"],
        ),
        (
            format!("{CAM}[[lights]]\ntype = \"spot\"\n"),
            vec!["lights[0].type", "line 7", "`sphere` or `rect`"],
        ),
        (
            format!("{CAM}[[lights]]\ntype = \"rect\"\ncorner = [0, 2, 0]\nedge_u = [1, 0, 0]\nedge_v = [1, 0, 1]\nradiance = [1, 1, 1]\n"),
            vec!["lights[0]", "line 6", "perpendicular"],
        ),
        (
            format!("{CAM}[[lights]]\ntype = \"sphere\"\ncenter = [0, 2, 0]\nradius = 1\nradiance = [1, -1, 1]\n"),
            vec!["lights[0].radiance", "line 10", "non-negative"],
        ),
        (
            format!("{CAM}[render]\nspp = 0\n"),
            vec!["render.spp", "line 7", "at least 1"],
        ),
        (
            format!("{CAM}[render]\nspp = -3\n"),
            vec!["render.spp", "line 7", "u32"],
        ),
        (
            format!("{CAM}[render]\nintegrator = \"bdpt\"\n"),
            vec!["render.integrator", "line 7", "`path` or `direct`"],
        ),
        (
            format!("{CAM}[environment]\ntype = \"sky\"\n"),
            vec!["environment.type", "line 7", "`constant`, `image`, `gaussian_sky`"],
        ),
        (
            format!("{CAM}[environment]\ntype = \"image\"\nfile = \"nope.hdr\"\n"),
            vec!["environment.file", "line 8", "file not found", "nope.hdr"],
        ),
        (
            format!("{CAM}[environment]\ntype = \"gaussian_sky\"\ndirection = [0, 0, 0]\nsharpness = 1\npeak = [1, 1, 1]\n"),
            vec!["environment.direction", "line 8", "non-zero"],
        ),
        (
            "[camera]\nfrom = [0, 0, 0]\nto = [0, 0, 0]\nfov = 40\nresolution = [8, 8]\n[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n".into(),
            vec!["camera", "line 1", "`from` and `to` must differ"],
        ),
        (
            format!("{CAM}fov = 200\n"),
            vec!["line 6", "duplicate key `fov`"],
        ),
        (
            format!("{CAM}[environment\n"),
            vec!["line 6", "invalid table header"],
        ),
        (CAM.to_string(), vec!["scene is empty"]),
        (
            format!("{CAM}# φ θ — non-ASCII comment\n[render]\nspp = 0\n"),
            vec!["render.spp", "line 8, column 7"],
        ),
    ];
    for (text, wanted) in &cases {
        let msg = err_of(text);
        println!("{msg}");
        assert!(msg.starts_with("dir/bad.toml: "), "names the file: {msg}");
        assert!(!msg.contains('\n'), "one line: {msg}");
        for w in wanted {
            assert!(
                msg.contains(w),
                "message lacks {w:?}: {msg}\n--- scene ---\n{text}"
            );
        }
    }
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A unit square (two triangles, tilted normals) plus three degenerate faces.
const SQUARE_OBJ: &str = "\
o square
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v nan 0 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 1 0 1
vn 1 0 1
vn 1 0 1
vn 1 0 1
f 1/1/1 2/2/2 3/3/3
f 1/1/1 3/3/3 4/4/4
f 1/1/1 1/1/1 2/2/2
f 1/1/1 2/2/2 5/1/1
f 1/1/1 6/1/1 3/3/3
";

#[test]
fn obj_mesh_is_transformed_with_normals_and_degenerates_counted() {
    let dir = scratch("obj");
    write(&dir, "square.obj", SQUARE_OBJ);
    // Non-uniform scale so that normals need the inverse transpose.
    let scene_path = write(
        &dir,
        "s.toml",
        &format!(
            "{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"square.obj\"\nmaterial = \"w\"\n\
             transform = {{ scale = [2, 1, 1], translate = [0, 0, -3] }}\n"
        ),
    );
    let s = scene::load(&scene_path).unwrap();
    println!("stats: {:?}", s.stats);
    assert_eq!(s.meshes.len(), 1);
    let m = &s.meshes[0];
    assert_eq!(m.triangles.len(), 2);
    assert_eq!(s.stats.triangles, 2);
    assert_eq!(
        s.stats.degenerate_triangles, 3,
        "repeated index, collinear, NaN"
    );
    assert_eq!(s.stats.meshes_with_normals, 1);
    assert_eq!(m.object_id, 1);
    assert_eq!(s.object_names, vec!["square".to_string()]);
    // Vertex 3 = (1, 1, 0) → (2, 1, −3).
    assert!(m
        .positions
        .iter()
        .any(|p| (*p - Vec3::new(2.0, 1.0, -3.0)).length() < 1e-6));
    // Normal (1, 0, 1) under diag(2, 1, 1): inverse transpose gives (½, 0, 1).
    let expect = Vec3::new(0.5, 0.0, 1.0).normalize();
    for n in &m.normals {
        assert!(
            (*n - expect).length() < 1e-5,
            "normal {n:?}, expected {expect:?}"
        );
    }
    // Kept triangles are counter-clockwise about +z.
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!(cross(b - a, c - a).z > 0.0);
    }
    assert_eq!(m.uvs.len(), m.positions.len());

    // A malformed OBJ is one Asset error naming the OBJ file.
    write(&dir, "broken.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n");
    let broken = write(
        &dir,
        "broken.toml",
        &format!(
            "{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"broken.obj\"\nmaterial = \"w\"\n"
        ),
    );
    let e = scene::load(&broken).unwrap_err().to_string();
    println!("{e}");
    assert!(e.contains("broken.obj") && e.contains("invalid OBJ"), "{e}");

    // A mirroring transform keeps the geometric normal on the same side.
    let mirrored = write(
        &dir,
        "m.toml",
        &format!(
            "{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"square.obj\"\nmaterial = \"w\"\n\
             transform = {{ scale = [-1, 1, 1] }}\n"
        ),
    );
    let s = scene::load(&mirrored).unwrap();
    let m = &s.meshes[0];
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!(
            cross(b - a, c - a).z > 0.0,
            "winding flipped back after mirroring"
        );
    }
}

#[test]
fn smooth_normals_weld_split_vertices_and_average_faces() {
    let dir = scratch("smooth");
    // Two unit right triangles folded 90° along the x axis; the shared edge is
    // stored twice (vertices 1, 2 and 4, 5), as exporters split seams.
    write(
        &dir,
        "fold.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\nf 4 5 6\n",
    );
    let p = write(
        &dir,
        "s.toml",
        &format!("{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"fold.obj\"\nmaterial = \"w\"\nsmooth_normals = true\n"),
    );
    let s = scene::load(&p).unwrap();
    let m = &s.meshes[0];
    assert_eq!(s.stats.meshes_with_normals, 1);
    let diag = Vec3::new(0.0, 1.0, 1.0).normalize();
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let expect = if p.y > 0.5 {
            Vec3::Z // only in the +z-facing triangle
        } else if p.z < -0.5 {
            Vec3::Y // only in the +y-facing triangle
        } else {
            diag // on the shared edge: both faces, equal areas
        };
        assert!(
            (*n - expect).length() < 1e-6,
            "vertex {p:?}: normal {n:?}, expected {expect:?}"
        );
    }
}

#[test]
fn mtl_ke_makes_an_emitter_and_ks_a_blinn_phong() {
    let dir = scratch("mtl");
    write(
        &dir,
        "lamp.mtl",
        "newmtl glow\nKd 0 0 0\nKe 4 3 2\n\nnewmtl shiny\nKd 0.5 0.4 0.3\nKs 0.2 0.2 0.2\nNs 50\n",
    );
    write(
        &dir,
        "lamp.obj",
        "mtllib lamp.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 1\no panel\nusemtl glow\nf 1 2 3\no body\nusemtl shiny\nf 1 4 2\n",
    );
    let scene_path = write(
        &dir,
        "s.toml",
        &format!("{CAM}[[shapes]]\ntype = \"mesh\"\nname = \"lamp\"\nfile = \"lamp.obj\"\n"),
    );
    let s = scene::load(&scene_path).unwrap();
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.emitter_count(), 1);
    let panel = s.meshes.iter().find(|m| m.name == "lamp/panel").unwrap();
    let body = s.meshes.iter().find(|m| m.name == "lamp/body").unwrap();
    assert_eq!(panel.emission, Vec3::new(4.0, 3.0, 2.0));
    assert_eq!(body.emission, Vec3::ZERO);
    assert_eq!(s.material_names[panel.material as usize], "lamp/glow");
    assert_eq!(
        s.materials[body.material as usize],
        Material::BlinnPhong {
            kd: Vec3::new(0.5, 0.4, 0.3),
            ks: Vec3::splat(0.2),
            exponent: 50.0
        }
    );
    assert!(panel.object_id == 1 && body.object_id == 1);

    // Without MTL and without `material` the error says what to add.
    write(&dir, "bare.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    let bare = write(
        &dir,
        "b.toml",
        &format!("{CAM}[[shapes]]\ntype = \"mesh\"\nfile = \"bare.obj\"\n"),
    );
    let e = scene::load(&bare).unwrap_err().to_string();
    assert!(
        e.contains("shapes[0]")
            && e.contains("line 6")
            && e.contains("give the shape a `material`"),
        "{e}"
    );
}

#[test]
fn exr_environment_is_read_row_zero_at_the_zenith() {
    let dir = scratch("exr");
    let (w, h) = (8usize, 4usize);
    exr::prelude::write_rgb_file(dir.join("env.exr"), w, h, |x, y| {
        (x as f32, y as f32, 0.5f32)
    })
    .unwrap();
    let scene_path = write(
        &dir,
        "s.toml",
        &format!("{CAM}[environment]\ntype = \"image\"\nfile = \"env.exr\"\nscale = 2\n"),
    );
    let s = scene::load(&scene_path).unwrap();
    let Some(Environment::Image {
        width,
        height,
        texels,
        scale,
    }) = &s.environment
    else {
        panic!("expected an image environment");
    };
    assert_eq!((*width, *height, *scale), (w, h, 2.0));
    assert_eq!(texels[2 * w + 5], Vec3::new(5.0, 2.0, 0.5));
    // Straight up reads row 0 (G = y = 0 there, clamped in v).
    let up = s.environment.as_ref().unwrap().eval(Vec3::Y);
    assert!(up.y.abs() < 1e-6, "{up:?}");
}

fn bundled(name: &str) -> Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

/// World-space bounds of everything with the given object id.
fn bounds(s: &Scene, id: u32) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for m in s.meshes.iter().filter(|m| m.object_id == id) {
        for t in &m.triangles {
            for &i in t {
                lo = lo.min(m.positions[i as usize]);
                hi = hi.max(m.positions[i as usize]);
            }
        }
    }
    for sp in s.spheres.iter().filter(|sp| sp.object_id == id) {
        lo = lo.min(sp.center - sp.radius);
        hi = hi.max(sp.center + sp.radius);
    }
    (lo, hi)
}

fn id_of(s: &Scene, name: &str) -> u32 {
    s.object_names.iter().position(|n| n == name).unwrap() as u32 + 1
}

/// The object's bounding-box centre projects inside the image.
fn assert_in_view(s: &Scene, name: &str) {
    let (lo, hi) = bounds(s, id_of(s, name));
    let p = s
        .camera
        .project(0.5 * (lo + hi))
        .expect("in front of the camera");
    let (w, h) = (s.camera.width as f32, s.camera.height as f32);
    println!("  {name}: bounds {lo:?}..{hi:?}, centre at pixel {p:?}");
    assert!(
        p.x > 0.0 && p.x < w && p.y > 0.0 && p.y < h,
        "{name} is out of view"
    );
}

/// The whole bounding box projects inside the image: the object is not cut off.
fn assert_fully_in_view(s: &Scene, name: &str) {
    let (lo, hi) = bounds(s, id_of(s, name));
    let (w, h) = (s.camera.width as f32, s.camera.height as f32);
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let p = s.camera.project(c).expect("in front of the camera");
        assert!(
            p.x >= 0.0 && p.x <= w && p.y >= 0.0 && p.y <= h,
            "{name}: corner {c:?} projects to {p:?}, outside {w}x{h}"
        );
    }
}

#[test]
fn every_bundled_scene_loads_and_frames_its_objects() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 5, "{names:?}");
    for n in &names {
        let s = bundled(n);
        println!(
            "{n}: {}x{} spp {} | {} meshes, {} spheres, {} emitters, stats {:?}",
            s.camera.width,
            s.camera.height,
            s.settings.spp,
            s.meshes.len(),
            s.spheres.len(),
            s.emitter_count(),
            s.stats
        );
        assert!(
            s.emitter_count() > 0 || s.environment.is_some(),
            "{n} has no light"
        );
        // The glossy teapot is 512² (the frame-time bar of its issue).
        assert!(
            s.camera.width * s.camera.height <= 512 * 512,
            "{n}: keep renders quick"
        );
        for name in &s.object_names {
            let id = id_of(&s, name);
            let emits = s
                .meshes
                .iter()
                .any(|m| m.object_id == id && m.emission != Vec3::ZERO)
                || s.spheres
                    .iter()
                    .any(|sp| sp.object_id == id && sp.emission != Vec3::ZERO);
            let (lo, hi) = bounds(&s, id);
            // Lights may be out of view; huge objects (ground, table) need not be centred.
            if !emits && (hi - lo).max_element() < 100.0 {
                assert_in_view(&s, name);
            }
        }
    }

    for (scene, objects) in [
        ("objects_bumpy.toml", &["teapot", "cow", "bumpy"][..]),
        ("bunny_env.toml", &["bunny"][..]),
        ("spheres_table.toml", &["diffuse", "glossy", "bumpy"][..]),
        ("three_spheres_env.toml", &["left", "middle", "right"][..]),
        ("cornell.toml", &["small-box", "large-box"][..]),
    ] {
        let s = bundled(scene);
        for o in objects {
            assert_fully_in_view(&s, o);
        }
    }

    // Objects rest on the ground (y = 0) and lights are above them.
    let s = bundled("objects_bumpy.toml");
    for name in ["teapot", "cow", "bumpy"] {
        let (lo, _) = bounds(&s, id_of(&s, name));
        assert!(
            lo.y.abs() < 2e-3,
            "{name} floats or sinks: min y = {}",
            lo.y
        );
    }
    let light_y = bounds(&s, id_of(&s, "area")).0.y;
    for name in ["teapot", "cow", "bumpy"] {
        assert!(bounds(&s, id_of(&s, name)).1.y < light_y);
    }
    let s = bundled("bunny_env.toml");
    let (lo, hi) = bounds(&s, id_of(&s, "bunny"));
    assert!(lo.y.abs() < 2e-3 && hi.y < bounds(&s, id_of(&s, "bulb")).0.y);
    // scripts/make_env.py's sky: 256×128, row 0 the (blue) zenith, the last row the
    // brown ground (0.22, 0.19, 0.16) up to RGBE quantisation.
    let Some(Environment::Image {
        width,
        height,
        texels,
        ..
    }) = &s.environment
    else {
        panic!("bunny_env has an image environment");
    };
    assert_eq!((*width, *height), (256, 128));
    let zenith = texels[0];
    assert!(zenith.z > zenith.x && zenith.z > 0.9, "{zenith:?}");
    let ground = texels[(height - 1) * width];
    assert!(
        (ground - Vec3::new(0.22, 0.19, 0.16)).length() < 0.01,
        "{ground:?}"
    );
    let s = bundled("spheres_table.toml");
    let table_top = bounds(&s, id_of(&s, "table")).1.y;
    assert!(table_top.abs() < 1e-3);
    // Each ball touches the curved table: centre distance = R + r.
    let table = s.spheres.iter().find(|sp| sp.name == "table").unwrap();
    for sp in s.spheres.iter().filter(|sp| sp.name != "table") {
        let gap = (sp.center - table.center).length() - (table.radius + sp.radius);
        assert!(gap.abs() < 1e-3, "{} floats/sinks by {gap}", sp.name);
    }
    assert_eq!(s.bumps.len(), 1);
    assert!(s.spheres.iter().any(|sp| sp.bump.is_some()));
}

#[test]
fn cornell_matches_mitsuba_cornell_box() {
    let s = bundled("cornell.toml");
    assert_eq!((s.camera.width, s.camera.height), (256, 256));
    assert_eq!((s.settings.spp, s.settings.max_depth), (64, 8));
    assert_eq!(s.camera.from, Vec3::new(0.0, 0.0, 3.9));
    assert_eq!(s.object_names.len(), 8);
    assert_eq!(s.emitter_count(), 1);
    // The light: 0.46 × 0.38 at y = 0.99, facing down, one rect.
    let light = s.meshes.iter().find(|m| m.name == "light").unwrap();
    let r = light.rect.expect("a quad keeps its rectangle");
    assert!((r.area() - 0.46 * 0.38).abs() < 1e-6);
    assert!((r.normal() - Vec3::NEG_Y).length() < 1e-6);
    let c = r.corner + 0.5 * (r.edge_u + r.edge_v);
    assert!((c - Vec3::new(0.0, 0.99, 0.01)).length() < 1e-6);
    assert_eq!(light.emission, Vec3::new(18.387, 13.9873, 6.75357));
    // Walls face into the box: the centre (0, 0, 0) is on their front side.
    for m in s
        .meshes
        .iter()
        .filter(|m| m.rect.is_some() && m.name != "light")
    {
        let r = m.rect.unwrap();
        assert!((r.area() - 4.0).abs() < 1e-5, "{}", m.name);
        assert!(
            (Vec3::ZERO - r.corner).dot(r.normal()) > 0.9,
            "{} faces away",
            m.name
        );
    }
    // Box bottoms as Mitsuba has them: the small one on the floor (y = −1), the
    // large one 1 cm through it (y = −0.4 − 0.61).
    for (name, bottom) in [("small-box", -1.0), ("large-box", -1.01)] {
        let (lo, _) = bounds(&s, id_of(&s, name));
        assert!((lo.y - bottom).abs() < 1e-5, "{name}: {lo:?}");
    }
    assert_eq!(
        s.materials[s.material_names.iter().position(|n| n == "red").unwrap()],
        Material::Lambert {
            albedo: Vec3::new(0.570068, 0.0430135, 0.0443706)
        }
    );
}

#[test]
fn transforms_compose_scale_then_rotations_in_order_then_translate() {
    let quad = |transform: &str| {
        let text = format!(
            "{CAM}{WHITE}[[shapes]]\ntype = \"quad\"\nmaterial = \"w\"\ntransform = {transform}\n"
        );
        let s = scene::load_from_str(&text, Path::new("t.toml")).unwrap();
        s.meshes[0].rect.unwrap()
    };
    // Corner (−1, −1, 0) → scale (−2, −1, 0) → R_x(−90°) (−2, 0, 1) → R_y(90°)
    // (1, 0, 2) → translate (1, 1, 2); the +z normal → +y.
    let r = quad(
        "{ scale = [2, 1, 1], rotate = [[1, 0, 0, -90], [0, 1, 0, 90]], translate = [0, 1, 0] }",
    );
    assert!(
        (r.corner - Vec3::new(1.0, 1.0, 2.0)).length() < 1e-5,
        "{r:?}"
    );
    assert!((r.normal() - Vec3::Y).length() < 1e-5, "{r:?}");
    assert!((r.area() - 8.0).abs() < 1e-5);
    // Mitsuba's floor matrix equals rotate x −90° then translate (0, −1, 0).
    let a = quad("{ matrix = [[1, 0, 0, 0], [0, -4.37114e-08, 1, -1], [0, -1, -4.37114e-08, 0]] }");
    let b = quad("{ rotate = [1, 0, 0, -90], translate = [0, -1, 0] }");
    for (x, y) in [
        (a.corner, b.corner),
        (a.edge_u, b.edge_u),
        (a.edge_v, b.edge_v),
    ] {
        assert!((x - y).length() < 1e-6, "{a:?} vs {b:?}");
    }
    // A mirroring transform keeps the front side on the transformed +z.
    let m = quad("{ scale = [-1, 1, 1] }");
    assert!((m.normal() - Vec3::Z).length() < 1e-6, "{m:?}");
}

/// The content hash covers the scene file, its OBJ and the OBJ's MTL library, and
/// nothing else: an edit of any input changes it, a moved folder does not.
#[test]
fn content_hash_changes_with_every_input_and_survives_a_move() {
    let d = scratch("hash");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
    write(&d, "m.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
    write(&d, "tri.obj", obj);
    let text = format!("{CAM}{WHITE}[[shapes]]\ntype = \"mesh\"\nfile = \"tri.obj\"\n\n[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n");
    let scene_path = write(&d, "s.toml", &text);
    let hash = || scene::load(&scene_path).unwrap().content_hash().unwrap();
    let h0 = hash();
    assert_eq!(h0.len(), 64);
    assert_eq!(h0, hash(), "deterministic");
    // Each input, edited and restored.
    for (name, edited, original) in [
        (
            "m.mtl",
            "newmtl red\nKd 0.8 0.2 0.1\n",
            "newmtl red\nKd 0.8 0.1 0.1\n",
        ),
        ("tri.obj", &obj.replace("v 1 0 0", "v 2 0 0"), obj),
        (
            "s.toml",
            &text.replace("radiance = [1, 1, 1]", "radiance = [2, 2, 2]"),
            &text,
        ),
    ] {
        write(&d, name, edited);
        assert_ne!(hash(), h0, "editing {name} must change the hash");
        write(&d, name, original);
        assert_eq!(hash(), h0, "restoring {name} restores the hash");
    }
    // The same files elsewhere hash the same.
    let moved = scratch("hash-moved");
    for name in ["m.mtl", "tri.obj", "s.toml"] {
        std::fs::copy(d.join(name), moved.join(name)).unwrap();
    }
    let h_moved = scene::load(&moved.join("s.toml"))
        .unwrap()
        .content_hash()
        .unwrap();
    assert_eq!(h_moved, h0);
}

/// A ball and a box (lines 9–18); an `[animation]` body appended starts on line 19.
fn animated(body: &str) -> String {
    format!(
        "{CAM}{WHITE}[[shapes]]\nname = \"ball\"\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\
         material = \"w\"\n[[shapes]]\nname = \"box\"\ntype = \"cube\"\nmaterial = \"w\"\n{body}"
    )
}

/// Issue 54, defects 16 and 19: every `[animation]` error names the exact key
/// path and its line (not the section header) in the project's words, and
/// translations and amounts keep to ±`scene::MAX_MAGNITUDE`.
#[test]
fn animation_errors_name_the_key_path_and_line() {
    let obj = "[animation]\n[[animation.objects]]\n"; // lines 19-20; keys from line 21
    let ball = format!("{obj}shape = \"ball\"\n"); // keys from line 22
                                                   // (the `[animation]` body, substrings the one-line message must contain)
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            "[animation]\nframes = 0\n".into(),
            vec!["animation.frames (line 20", "at least 1 frame"],
        ),
        (
            "[animation]\nframes = 10001\n".into(),
            vec!["animation.frames (line 20", "at most 10000", "10001"],
        ),
        (
            "[animation]\nframes = -2\n".into(),
            vec!["animation.frames (line 20", "u32"],
        ),
        (
            "[animation]\nframes = 2.5\n".into(),
            vec!["animation.frames (line 20", "u32"],
        ),
        (
            "[animation]\nframe = 3\n".into(),
            vec![
                "animation.frame (line 20",
                "unknown field `frame`",
                "`frames` or `objects`",
            ],
        ),
        (
            "[animation]\nobjects = 3\n".into(),
            vec!["animation.objects (line 20", "expected an array"],
        ),
        (
            "[animation]\nobjects = [1]\n".into(),
            vec!["animation.objects[0] (line 20", "expected a table"],
        ),
        (
            format!("{obj}keys = []\n"),
            vec!["animation.objects[0] (line 20", "missing field `shape`"],
        ),
        (
            format!("{obj}shape = \"bal\"\n"),
            vec![
                "animation.objects[0].shape (line 21",
                "undefined shape `bal`",
                "`ball`, `box`",
            ],
        ),
        (
            format!("{obj}shape = 7\n"),
            vec!["animation.objects[0].shape (line 21", "expected a string"],
        ),
        (
            format!("{ball}[[animation.objects]]\nshape = \"ball\"\n"),
            vec!["animation.objects[1].shape (line 23", "animated twice"],
        ),
        (
            format!("{ball}speed = 2\n"),
            vec![
                "animation.objects[0].speed (line 22",
                "unknown field `speed`",
                "`shape`, `keys`, `deform`",
            ],
        ),
        (
            format!("{ball}keys = {{ t = 0 }}\n"),
            vec!["animation.objects[0].keys (line 22", "expected an array"],
        ),
        (
            format!("{ball}keys = [0.5]\n"),
            vec!["animation.objects[0].keys[0] (line 22", "expected a table"],
        ),
        (
            format!("{ball}keys = [{{ translate = [0, 0, 0] }}]\n"),
            vec!["animation.objects[0].keys[0] (line 22", "missing field `t`"],
        ),
        (
            format!("{ball}keys = [{{ t = 0, scale = 2 }}]\n"),
            vec![
                "animation.objects[0].keys[0].scale (line 22",
                "unknown field `scale`",
                "`t`, `translate`, `rotate`",
            ],
        ),
        (
            format!("{ball}keys = [{{ t = 0, translate = [1, 2, 3, 4] }}]\n"),
            vec![
                "animation.objects[0].keys[0].translate (line 22",
                "array of length 3",
                "length 4",
            ],
        ),
        (
            format!("{ball}keys = [{{ t = 0, translate = [1, 2] }}]\n"),
            vec![
                "animation.objects[0].keys[0].translate (line 22",
                "array of length 3",
                "length 2",
            ],
        ),
        (
            format!("{ball}keys = [{{ t = 0, translate = [0, nan, 0] }}]\n"),
            vec!["animation.objects[0].keys[0].translate (line 22", "finite"],
        ),
        (
            format!("{ball}keys = [{{ t = 0, translate = [0, 1e39, 0] }}]\n"),
            vec!["animation.objects[0].keys[0].translate (line 22", "finite"],
        ),
        (
            format!(
                "{ball}keys = [\n  {{ t = 0 }},\n  {{ t = 1, translate = [1e30, 0, 0] }},\n]\n"
            ),
            vec![
                "animation.objects[0].keys[1].translate (line 24",
                "1e12",
                "MAX_MAGNITUDE",
            ],
        ),
        (
            format!("{ball}keys = [{{ t = 0, rotate = [0, 1, 0] }}]\n"),
            vec![
                "animation.objects[0].keys[0].rotate (line 22",
                "array of length 4",
                "length 3",
            ],
        ),
        (
            format!("{ball}keys = [{{ t = 0, rotate = [0, 0, 0, 90] }}]\n"),
            vec![
                "animation.objects[0].keys[0].rotate (line 22",
                "axis of zero length",
            ],
        ),
        (
            format!("{ball}keys = [{{ t = 0, rotate = [0, 1, 0, inf] }}]\n"),
            vec!["animation.objects[0].keys[0].rotate (line 22", "finite"],
        ),
        (
            format!("{ball}keys = [{{ t = 1.5 }}]\n"),
            vec!["animation.objects[0].keys[0].t (line 22", "[0, 1]", "1.5"],
        ),
        (
            format!("{ball}keys = [{{ t = -0.25 }}]\n"),
            vec!["animation.objects[0].keys[0].t (line 22", "[0, 1]", "-0.25"],
        ),
        (
            format!("{ball}keys = [{{ t = nan }}]\n"),
            vec!["animation.objects[0].keys[0].t (line 22", "finite"],
        ),
        (
            format!("{ball}keys = [{{ t = \"0\" }}]\n"),
            vec!["animation.objects[0].keys[0].t (line 22", "expected f32"],
        ),
        (
            format!("{ball}keys = [\n  {{ t = 0.5 }},\n  {{ t = 0.5 }},\n]\n"),
            vec![
                "animation.objects[0].keys[1].t (line 24",
                "increasing t",
                "0.5",
            ],
        ),
        (
            format!("{ball}keys = [\n  {{ t = 0.75 }},\n  {{ t = 0.25 }},\n]\n"),
            vec![
                "animation.objects[0].keys[1].t (line 24",
                "increasing t",
                "0.25",
            ],
        ),
        (
            format!("{ball}deform = \"bend\"\n"),
            vec!["animation.objects[0].deform (line 22", "expected a table"],
        ),
        (
            format!("{ball}deform = {{ type = \"wobble\", amount = [0, 1] }}\n"),
            vec![
                "animation.objects[0].deform.type (line 22",
                "unknown variant `wobble`",
                "`bend`, `twist`, `squash`",
            ],
        ),
        (
            format!("{ball}deform = {{ amount = [0, 1] }}\n"),
            vec![
                "animation.objects[0].deform (line 22",
                "missing field `type`",
                "`bend`, `twist`, `squash`",
            ],
        ),
        (
            format!("{ball}deform = {{ type = \"bend\" }}\n"),
            vec!["animation.objects[0].deform (line 22", "needs `amount`"],
        ),
        (
            format!("{ball}deform = {{ type = \"bend\", amount = [0, 1, 2] }}\n"),
            vec![
                "animation.objects[0].deform.amount (line 22",
                "array of length 2",
                "length 3",
            ],
        ),
        (
            format!("{ball}deform = {{ type = \"twist\", amount = [0, inf] }}\n"),
            vec!["animation.objects[0].deform.amount (line 22", "finite"],
        ),
        (
            format!("{ball}deform = {{ type = \"bend\", amount = [0, -1e30] }}\n"),
            vec![
                "animation.objects[0].deform.amount (line 22",
                "1e12",
                "MAX_MAGNITUDE",
            ],
        ),
        (
            format!("{ball}deform = {{ type = \"squash\", amount = [0, 0.99] }}\n"),
            vec!["animation.objects[0].deform.amount (line 22", "[-1, 0.95)"],
        ),
        (
            format!("{ball}deform = {{ type = \"bend\", amount = [0, 1], axis = 1 }}\n"),
            vec![
                "animation.objects[0].deform.axis (line 22",
                "does not apply to type = \"bend\"",
                "`amount`",
            ],
        ),
    ];
    // Every case is checked, then the failures listed together.
    let mut failed = Vec::new();
    for (body, wanted) in &cases {
        let text = animated(body);
        let msg = match scene::load_from_str(&text, Path::new("dir/bad.toml")) {
            Ok(_) => "(loaded)".to_string(),
            Err(e) => e.to_string(),
        };
        println!("{msg}");
        let lacks: Vec<&&str> = wanted.iter().filter(|w| !msg.contains(**w)).collect();
        if !msg.starts_with("dir/bad.toml: ") || msg.contains('\n') || !lacks.is_empty() {
            failed.push(format!("{body:?}\n  got {msg}\n  lacks {lacks:?}"));
        }
    }
    // A top-level key must come before the first table.
    let msg = err_of(&format!("animation = 3\n{}", animated("")));
    if !msg.contains("animation (line 1, column 13): expected a table") {
        failed.push(format!("animation = 3\n  got {msg}"));
    }
    assert!(
        failed.is_empty(),
        "{} of {} cases failed:\n{}",
        failed.len(),
        cases.len() + 1,
        failed.join("\n")
    );
}

/// The limits are inclusive (±1e12, 10000 frames), and an axis of any finite
/// non-zero length gives a finite rotation (a length that over- or underflows
/// f32 gave a NaN quaternion).
#[test]
fn animation_limits_admit_their_bounds_and_any_nonzero_axis() {
    let text = animated(
        "[animation]\nframes = 10000\n[[animation.objects]]\nshape = \"ball\"\n\
         keys = [{ t = 0, translate = [1e12, -1e12, 0], rotate = [1e30, 1e30, 0, 90] },\n\
         { t = 1, rotate = [0, 0, 1e-30, 90] }]\n\
         [[animation.objects]]\nshape = \"box\"\ndeform = { type = \"twist\", amount = [-1e12, 1e12] }\n",
    );
    let s = scene::load_from_str(&text, Path::new("dir/ok.toml")).unwrap_or_else(|e| panic!("{e}"));
    let a = s.animation.as_ref().unwrap();
    assert_eq!(a.frames, 10000);
    let k = &a.tracks[0].keys;
    assert_eq!(k[0].translate, Vec3::new(1e12, -1e12, 0.0));
    let want0 = glam::Quat::from_axis_angle(
        glam::Vec3::new(1.0, 1.0, 0.0).normalize(),
        90f32.to_radians(),
    );
    let want1 = glam::Quat::from_axis_angle(glam::Vec3::Z, 90f32.to_radians());
    for (got, want) in [(k[0].rotate, want0), (k[1].rotate, want1)] {
        assert!(
            got.is_finite() && got.dot(want).abs() > 1.0 - 1e-6,
            "{got:?} against {want:?}"
        );
    }
    assert_eq!(a.tracks[1].deform.unwrap().amount, [-1e12, 1e12]);
}

/// The bundled `[animation]` block reads to exactly what it says (the
/// reader's rewrite must not move a frame).
#[test]
fn bundled_animation_reads_exactly() {
    let s = bundled("shadowfield_deform.toml");
    let a = s.animation.as_ref().unwrap();
    assert_eq!(a.frames, 8);
    assert_eq!(a.tracks.len(), 2);
    let (bunny, ball) = (&a.tracks[0], &a.tracks[1]);
    assert_eq!(bunny.object_id, id_of(&s, "bunny"));
    assert!(bunny.keys.is_empty());
    let d = bunny.deform.unwrap();
    assert_eq!(
        (d.kind, d.amount),
        (scene::animation::DeformKind::Twist, [0.0, 1.4])
    );
    assert_eq!(ball.object_id, id_of(&s, "ball"));
    assert!(ball.deform.is_none());
    assert_eq!(ball.keys.len(), 2);
    assert_eq!((ball.keys[0].t, ball.keys[1].t), (0.0, 1.0));
    assert_eq!(ball.keys[0].translate, Vec3::ZERO);
    assert_eq!(ball.keys[0].rotate, glam::Quat::IDENTITY);
    assert_eq!(ball.keys[1].translate, Vec3::new(-0.6, 0.0, 0.5));
    let r = glam::Quat::from_axis_angle(glam::Vec3::Z, 120f32.to_radians());
    assert_eq!(ball.keys[1].rotate, r, "bit for bit");
}

/// The bundled OBJ sequence: eight files of the cloth's topology, the frame
/// count taken from them, and frame k of 8 exactly file k's vertices (no rigid
/// keys: the placement about the rest box rounds by an ulp at most, 1e-6 here).
#[test]
fn bundled_obj_sequence_reads_every_file() {
    let s = bundled("shadowfield_deform_seq.toml");
    let a = s.animation.as_ref().unwrap();
    assert_eq!(a.frames, 8, "the sequence's length");
    let seq = a.tracks[0].sequence.as_ref().unwrap();
    assert_eq!(a.tracks[0].object_id, id_of(&s, "cloth"));
    assert_eq!((seq.first, seq.frames.len()), (0, 8));
    let cloth = s
        .meshes
        .iter()
        .position(|m| m.name.starts_with("cloth"))
        .unwrap();
    assert_eq!(s.meshes[cloth].positions.len(), 169);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(dir.join("shadowfield_deform_seq.toml")).unwrap();
    let still = text.split("[animation]").next().unwrap().to_string();
    for k in [0u32, 3, 7] {
        let file = format!("models/cloth_{k:03}.obj");
        let one = still.replace("models/cloth_000.obj", &file);
        let want = scene::load_from_str(&one, &dir.join("one.toml")).unwrap();
        let posed = a.scene_at(&s, k, 8);
        let (got, want) = (&posed.meshes[cloth], &want.meshes[cloth]);
        let d = got
            .positions
            .iter()
            .zip(&want.positions)
            .map(|(p, q)| (*p - *q).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(d <= 1e-6, "frame {k}: {d}");
        assert_eq!(got.normals.len(), want.normals.len(), "smooth normals");
    }
}
