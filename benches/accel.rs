//! Acceleration structure benchmarks on the Stanford bunny (69k triangles):
//! BVH build time, and closest-hit / shadow-ray (any-hit) throughput for
//! coherent (camera grid) and incoherent (random) rays and for a path tracer's
//! first bounce batched by pixel (`*/bounces`); and on the Cornell box
//! of `bench_mitsuba` (36 triangles) for a path tracer's bounce rays, from
//! random points inside the box in random directions (`*/cornell`). Criterion
//! reports the throughput in elements/s, i.e. rays/s.
//!
//! Run: `cargo bench --bench accel -- --warm-up-time 1 --measurement-time 3`
//!
//! With `GRADTRACE_ACCEL_RAYS=FILE` set, the bunny's triangles and both ray sets
//! (with our hit counts) are also written to FILE, and the Cornell box's to
//! FILE with `_cornell` before its extension, so that
//! `scripts/bench_embree.py` traces Embree on exactly the same rays. With
//! `GRADTRACE_ACCEL_PRESETS=1`, obvhs build presets are compared first by
//! load-independent figures: SAH cost, node and primitive tests per ray. With
//! `GRADTRACE_ACCEL_ONCE=coherent` (or `incoherent`, `cornell`, `all`) each query runs
//! once over that ray set and the bench exits: for instruction counts, e.g.
//! `valgrind --tool=callgrind --toggle-collect='*trace_once*' target/release/deps/accel-*`.

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use gradtrace::accel::{Accel, RayStream};
use gradtrace::math::{Ray, Vec3};
use gradtrace::scene::Mesh;

/// The bunny, or the OBJ named by `GRADTRACE_ACCEL_MESH` in its place (for the
/// load-independent figures of `GRADTRACE_ACCEL_PRESETS` on another mesh; the
/// bench ids keep their names).
fn load_bunny() -> Mesh {
    let path = std::env::var("GRADTRACE_ACCEL_MESH").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/models/stanford-bunny.obj"
        )
        .to_string()
    });
    let (models, _) = tobj::load_obj(
        &path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )
    .expect("the mesh (scenes/models/stanford-bunny.obj or GRADTRACE_ACCEL_MESH) loads");
    let mut mesh = Mesh {
        name: "bunny".into(),
        ..Default::default()
    };
    for m in &models {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        mesh.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    mesh
}

/// xorshift64* — deterministic rays without an extra dependency.
struct Rng(u64);

impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32) / 16_777_216.0
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.f32(), self.f32(), self.f32()) * 2.0 - 1.0;
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

const RES: usize = 256;

/// `scenes/validation/cornell_256.toml` (Mitsuba's `cornell_box()`), its
/// shapes merged into one mesh.
fn load_cornell() -> Mesh {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/validation/cornell_256.toml"
    );
    let scene = gradtrace::scene::load(std::path::Path::new(path))
        .expect("scenes/validation/cornell_256.toml loads");
    let mut mesh = Mesh {
        name: "cornell".into(),
        ..Default::default()
    };
    for m in &scene.meshes {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(&m.positions);
        mesh.triangles
            .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    mesh
}

/// Random points inside the box (its bounds shrunk by 1 % on each side) in
/// random directions: what a path tracer's bounces trace in a closed room.
fn interior_rays(lo: Vec3, hi: Vec3) -> Vec<Ray> {
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    let (lo, hi) = (lo + (hi - lo) * 0.01, hi - (hi - lo) * 0.01);
    (0..RES * RES)
        .map(|_| {
            let t = Vec3::new(rng.f32(), rng.f32(), rng.f32());
            Ray::new(lo + (hi - lo) * t, rng.unit())
        })
        .collect()
}

/// A pinhole camera's ray through (x, y) of a 256×256 grid framing the bunny.
fn camera_ray(lo: Vec3, hi: Vec3, x: f32, y: f32) -> Ray {
    let c = (lo + hi) * 0.5;
    let size = (hi - lo).max_element();
    let eye = c + Vec3::new(0.0, 0.0, 2.0 * size);
    let (u, v) = (x / RES as f32 - 0.5, y / RES as f32 - 0.5);
    Ray::new(eye, Vec3::new(u * 0.7, v * 0.7, -1.0).normalize())
}

/// The camera's primary rays, one through each pixel centre.
fn coherent_rays(lo: Vec3, hi: Vec3) -> Vec<Ray> {
    (0..RES * RES)
        .map(|i| camera_ray(lo, hi, (i % RES) as f32 + 0.5, (i / RES) as f32 + 0.5))
        .collect()
}

/// A path tracer's first bounce off the bunny as the lane shading batches it
/// (a batch is one pixel's samples): 256 pixels spread over those of the
/// camera's grid whose centre sees the bunny, 256 camera rays jittered in each, and from each first
/// hit a cosine-distributed direction about the face normal, pixel after
/// pixel. The rays share a small patch of origins and spread over the
/// hemisphere: what ray packets or streams could share, unlike the
/// incoherent set's. Origins are moved off the surface by 10⁻⁴ of the bunny's
/// size, so that Embree (t_near = 0) traces the same rays.
fn bounce_rays(accel: &Accel, mesh: &Mesh, lo: Vec3, hi: Vec3) -> Vec<Ray> {
    use gradtrace::accel::PrimRef;
    let mut rng = Rng(0x6A09_E667_F3BC_C909);
    let eps = (hi - lo).max_element() * 1e-4;
    let on_bunny: Vec<usize> = (coherent_rays(lo, hi).iter().enumerate())
        .filter_map(|(i, r)| accel.intersect(r).map(|_| i))
        .collect();
    let mut rays = Vec::with_capacity(RES * RES);
    for i in (0..RES).map(|k| on_bunny[k * on_bunny.len() / RES]) {
        for _ in 0..RES {
            let (x, y) = ((i % RES) as f32 + rng.f32(), (i / RES) as f32 + rng.f32());
            let r = camera_ray(lo, hi, x, y);
            let Some(hit) = accel.intersect(&r) else {
                rays.push(r); // past the silhouette: the camera ray itself
                continue;
            };
            let PrimRef::Triangle { tri, .. } = hit.prim else {
                unreachable!("the bunny is all triangles")
            };
            let [a, b, c] = mesh.triangles[tri as usize].map(|k| mesh.positions[k as usize]);
            let mut n = gradtrace::math::cross(b - a, c - a).normalize();
            if n.dot(r.dir) > 0.0 {
                n = -n;
            }
            let dir = loop {
                let d = n + rng.unit();
                if d.length_squared() > 1e-6 {
                    break d.normalize();
                }
            };
            rays.push(Ray::new(r.origin + r.dir * hit.t + n * eps, dir));
        }
    }
    rays
}

/// Random origins in the bunny's bounding box, random directions.
fn incoherent_rays(lo: Vec3, hi: Vec3) -> Vec<Ray> {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    (0..RES * RES)
        .map(|_| {
            let t = Vec3::new(rng.f32(), rng.f32(), rng.f32());
            Ray::new(lo + (hi - lo) * t, rng.unit())
        })
        .collect()
}

/// The environment variable `name` parsed as a `T`, if set. A value that does
/// not parse stops the bench with one line naming the variable and what was
/// expected, rather than silently timing the default in its place.
fn env_parse<T: std::str::FromStr>(name: &str, expected: &str) -> Option<T> {
    let v = std::env::var(name).ok()?;
    match v.parse() {
        Ok(t) => Some(t),
        Err(_) => bad_env(name, &v, expected),
    }
}

fn bad_env(name: &str, value: &str, expected: &str) -> ! {
    eprintln!("error: {name}={value:?}: expected {expected}");
    std::process::exit(2)
}

fn bench_accel(c: &mut Criterion) {
    let bunny = load_bunny();
    let meshes = [bunny];
    // GRADTRACE_ACCEL_WIDTH=4 times the 4-wide tree where the CPU would get the
    // 8-wide one (A/B on the same machine).
    let mut preset = gradtrace::accel::BuildPreset::default();
    if let Some(w) = env_parse("GRADTRACE_ACCEL_WIDTH", "4 or 8") {
        preset.node_width = w;
    }
    // GRADTRACE_ACCEL_LEAF / GRADTRACE_ACCEL_REINSERT / GRADTRACE_ACCEL_LEAF_COST:
    // another leaf size, reinsertion ratio or collapse leaf cost, for timing a
    // preset (`GRADTRACE_ACCEL_TIME`).
    if let Some(n) = env_parse("GRADTRACE_ACCEL_LEAF", "a leaf size in primitives") {
        preset.max_prims_per_leaf = n;
    }
    if let Some(r) = env_parse("GRADTRACE_ACCEL_REINSERT", "a reinsertion ratio (a number)") {
        preset.reinsertion_ratio = r;
    }
    // GRADTRACE_ACCEL_SEARCH: PLOC's search distance (low, medium, high, very_high).
    if let Ok(d) = std::env::var("GRADTRACE_ACCEL_SEARCH") {
        use obvhs::ploc::PlocSearchDistance as D;
        preset.search_distance = match d.as_str() {
            "low" => D::Low,
            "high" => D::High,
            "very_high" => D::VeryHigh,
            "medium" => D::Medium,
            _ => bad_env(
                "GRADTRACE_ACCEL_SEARCH",
                &d,
                "low, medium, high or very_high",
            ),
        };
    }
    // GRADTRACE_ACCEL_LEAF_COST: a number, or `greedy` for the greedy collapse.
    if let Ok(c) = std::env::var("GRADTRACE_ACCEL_LEAF_COST") {
        preset.leaf_cost = match c.as_str() {
            "greedy" => None,
            n => Some(n.parse().unwrap_or_else(|_| {
                bad_env("GRADTRACE_ACCEL_LEAF_COST", n, "a number or `greedy`")
            })),
        };
    }
    if let Ok(only) = std::env::var("GRADTRACE_ACCEL_ONCE") {
        if !["coherent", "incoherent", "cornell", "all"].contains(&only.as_str()) {
            bad_env(
                "GRADTRACE_ACCEL_ONCE",
                &only,
                "coherent, incoherent, cornell or all",
            );
        }
        let accel = Accel::build_with_preset(&meshes, &[], &preset);
        let (lo, hi) = accel.bounds().expect("bunny is not empty");
        let sets = [
            ("coherent", coherent_rays(lo, hi)),
            ("incoherent", incoherent_rays(lo, hi)),
        ];
        for (name, rays) in sets.iter().filter(|(n, _)| only == *n || only == "all") {
            let (closest, any) = trace_once(&accel, rays);
            println!("{name}: {closest} closest hits, {any} occluded");
        }
        if only == "cornell" || only == "all" {
            let cornell = Accel::build_with_preset(&[load_cornell()], &[], &preset);
            let (lo, hi) = cornell.bounds().expect("the box is not empty");
            let (closest, any) = trace_once(&cornell, &interior_rays(lo, hi));
            println!("cornell: {closest} closest hits, {any} occluded");
        }
        std::process::exit(0);
    }
    if std::env::var_os("GRADTRACE_ACCEL_TIME").is_some() {
        let accel = Accel::build_with_preset(&meshes, &[], &preset);
        let (lo, hi) = accel.bounds().expect("bunny is not empty");
        let sets = [
            ("coherent", coherent_rays(lo, hi)),
            ("incoherent", incoherent_rays(lo, hi)),
        ];
        time_queries(&accel, &sets);
        for (name, rays) in &sets {
            let (mut n, mut p, mut o) = (0u64, 0u64, 0u64);
            for r in rays {
                let (a, b) = accel.closest_hit_work(r);
                n += a as u64;
                p += b as u64;
                o += accel.occluded_work(r) as u64;
            }
            let k = rays.len() as f64;
            println!(
                "{name}: closest {:.2} nodes / {:.2} primitives per ray, any-hit {:.2} nodes",
                n as f64 / k,
                p as f64 / k,
                o as f64 / k
            );
        }
        std::process::exit(0);
    }

    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.bench_function("bunny", |b| {
        b.iter(|| Accel::build(black_box(&meshes), &[]))
    });
    g.finish();

    let accel = Accel::build_with_preset(&meshes, &[], &preset);
    let (lo, hi) = accel.bounds().expect("bunny is not empty");
    let sets = [
        ("coherent", coherent_rays(lo, hi)),
        ("incoherent", incoherent_rays(lo, hi)),
        ("bounces", bounce_rays(&accel, &meshes[0], lo, hi)),
    ];
    for (name, rays) in &sets {
        let hits = rays.iter().filter(|r| accel.intersect(r).is_some()).count();
        println!("{name}: {} rays, {hits} hit the bunny", rays.len());
    }
    if std::env::var_os("GRADTRACE_ACCEL_PRESETS").is_some() {
        compare_presets(&meshes, &sets);
    }
    let cornell = [load_cornell()];
    let cornell_accel = Accel::build_with_preset(&cornell, &[], &preset);
    let (lo, hi) = cornell_accel.bounds().expect("the box is not empty");
    let cornell_sets = [("cornell", interior_rays(lo, hi))];
    if let Some(path) = std::env::var_os("GRADTRACE_ACCEL_RAYS") {
        let path = std::path::PathBuf::from(path);
        write_rays(&path, &meshes[0], &accel, &sets).expect("GRADTRACE_ACCEL_RAYS is writable");
        let stem = path.file_stem().unwrap_or_default().to_string_lossy();
        let ext = path
            .extension()
            .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
        let cornell_path = path.with_file_name(format!("{stem}_cornell{ext}"));
        write_rays(&cornell_path, &cornell[0], &cornell_accel, &cornell_sets)
            .expect("GRADTRACE_ACCEL_RAYS's folder is writable");
    }

    let scenes = [(&accel, &sets[..]), (&cornell_accel, &cornell_sets[..])];
    let mut g = c.benchmark_group("closest_hit");
    for (accel, sets) in scenes {
        for (name, rays) in sets {
            g.throughput(Throughput::Elements(rays.len() as u64));
            g.bench_function(*name, |b| {
                b.iter(|| {
                    rays.iter()
                        .filter(|r| accel.intersect(black_box(r)).is_some())
                        .count()
                })
            });
        }
    }
    g.finish();

    // Baseline for context only: obvhs' own traversal and (non-watertight)
    // Möller–Trumbore triangles on the same BVH preset, no sphere support.
    let tris: Vec<obvhs::triangle::Triangle> = meshes[0]
        .triangles
        .iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: meshes[0].positions[t[0] as usize],
            v1: meshes[0].positions[t[1] as usize],
            v2: meshes[0].positions[t[2] as usize],
        })
        .collect();
    let mut core_build_time = std::time::Duration::ZERO;
    let reference = obvhs::cwbvh::builder::build_cwbvh_from_tris(
        &tris,
        obvhs::BvhBuildParams::medium_build(),
        &mut core_build_time,
    );
    let mut g = c.benchmark_group("obvhs_baseline_closest_hit");
    for (name, rays) in &sets {
        let orays: Vec<obvhs::ray::Ray> = rays
            .iter()
            .map(|r| obvhs::ray::Ray::new_inf(r.origin, r.dir))
            .collect();
        g.throughput(Throughput::Elements(rays.len() as u64));
        g.bench_function(*name, |b| {
            b.iter(|| {
                orays
                    .iter()
                    .filter(|r| {
                        let mut hit = obvhs::ray::RayHit::none();
                        reference.ray_traverse(**black_box(r), &mut hit, |ray, id| {
                            tris[reference.primitive_indices[id] as usize].intersect(ray)
                        })
                    })
                    .count()
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("shadow");
    for (accel, sets) in scenes {
        for (name, rays) in sets {
            g.throughput(Throughput::Elements(rays.len() as u64));
            g.bench_function(*name, |b| {
                b.iter(|| rays.iter().filter(|r| accel.occluded(black_box(r))).count())
            });
        }
    }
    g.finish();

    // The same cornell rays as ray streams (the lane shading's queries on
    // a small tree), in batches of the lanes' size.
    if cornell_accel.streams() {
        let mut stream = RayStream::default();
        for (group, any) in [("closest_hit_stream", false), ("shadow_stream", true)] {
            let mut g = c.benchmark_group(group);
            for (name, rays) in &cornell_sets {
                g.throughput(Throughput::Elements(rays.len() as u64));
                g.bench_function(*name, |b| {
                    b.iter(|| stream_hits(&cornell_accel, black_box(rays), any, &mut stream))
                });
            }
            g.finish();
        }
    }
}

/// Rays of a stream batch, as `render::LANE_BATCH`.
const STREAM_BATCH: usize = 256;

/// Hits (closest, or with `any` occluded) of `rays` traced as streams of
/// [`STREAM_BATCH`].
fn stream_hits(accel: &Accel, rays: &[Ray], any: bool, s: &mut RayStream) -> usize {
    let mut hits = 0;
    for batch in rays.chunks(STREAM_BATCH) {
        if any {
            accel.occluded_stream(batch.len(), |k| &batch[k], s);
            hits += (0..batch.len()).filter(|&k| s.occluded(k)).count();
        } else {
            accel.intersect_stream(batch.len(), |k| &batch[k], s);
            hits += (0..batch.len())
                .filter(|&k| s.hit(accel, k).is_some())
                .count();
        }
    }
    hits
}

/// Best of 15 interleaved passes per query and ray set, in Mrays/s: on a
/// shared machine the fastest pass is the one least disturbed by the load.
fn time_queries(accel: &Accel, sets: &[(&str, Vec<Ray>)]) {
    type Query<'a> = (&'a str, Box<dyn Fn(&Ray) -> bool + 'a>);
    let queries: Vec<Query> = vec![
        ("closest", Box::new(|r| accel.intersect(r).is_some())),
        ("shadow", Box::new(|r| accel.occluded(r))),
    ];
    let mut best = vec![f64::INFINITY; queries.len() * sets.len()];
    for _ in 0..15 {
        for (qi, (_, q)) in queries.iter().enumerate() {
            for (si, (_, rays)) in sets.iter().enumerate() {
                let t = std::time::Instant::now();
                black_box(rays.iter().filter(|r| q(black_box(r))).count());
                let dt = t.elapsed().as_secs_f64();
                let b = &mut best[qi * sets.len() + si];
                *b = b.min(dt);
            }
        }
    }
    for (qi, (qn, _)) in queries.iter().enumerate() {
        for (si, (sn, rays)) in sets.iter().enumerate() {
            let mrays = rays.len() as f64 / best[qi * sets.len() + si] / 1e6;
            println!("{qn}/{sn}: {mrays:.2} Mrays/s");
        }
    }
}

/// One closest-hit and one any-hit pass over `rays` (the callgrind target).
#[inline(never)]
fn trace_once(accel: &Accel, rays: &[Ray]) -> (usize, usize) {
    let closest = rays.iter().filter(|r| accel.intersect(r).is_some()).count();
    let any = rays.iter().filter(|r| accel.occluded(r)).count();
    (closest, any)
}

/// SAH cost, build time and traversal work (wide nodes and primitives tested
/// per closest-hit ray) of obvhs build presets and our collapses: figures the machine's load
/// cannot move (but the build time).
fn compare_presets(meshes: &[Mesh], sets: &[(&str, Vec<Ray>)]) {
    use gradtrace::accel::BuildPreset;
    use obvhs::ploc::{PlocSearchDistance as D, SortPrecision as P};
    let base = BuildPreset::default();
    let presets = [
        ("medium (default)", base),
        (
            "low",
            BuildPreset {
                search_distance: D::Low,
                search_depth_threshold: 2,
                ..base
            },
        ),
        (
            "high, reinsertion 0.2, u128",
            BuildPreset {
                search_distance: D::High,
                search_depth_threshold: 2,
                reinsertion_ratio: 0.2,
                sort_precision: P::U128,
                ..base
            },
        ),
        (
            "medium, reinsertion 1.0",
            BuildPreset {
                reinsertion_ratio: 1.0,
                search_depth_threshold: 1,
                ..base
            },
        ),
        (
            "very high, reinsertion 1.0, u128",
            BuildPreset {
                search_distance: D::VeryHigh,
                search_depth_threshold: 0,
                reinsertion_ratio: 1.0,
                sort_precision: P::U128,
                ..base
            },
        ),
        (
            "medium, greedy collapse",
            BuildPreset {
                leaf_cost: None,
                ..base
            },
        ),
        (
            "medium, ≤ 2 per leaf",
            BuildPreset {
                max_prims_per_leaf: 2,
                ..base
            },
        ),
        (
            "medium, 1 per leaf",
            BuildPreset {
                max_prims_per_leaf: 1,
                ..base
            },
        ),
    ];
    println!("| preset | SAH | nodes | build (ms, best of 3) | node / primitive tests per ray: coherent | incoherent |");
    println!("|---|---:|---:|---:|---:|---:|");
    for (name, preset) in presets {
        let build = || Accel::build_with_preset(meshes, &[], &preset);
        let ms = (0..3)
            .map(|_| build().build_time().as_secs_f64() * 1e3)
            .fold(f64::INFINITY, f64::min);
        let accel = build();
        let work: Vec<String> = sets
            .iter()
            .map(|(_, rays)| {
                let (n, p) = rays.iter().fold((0u64, 0u64), |(n, p), r| {
                    let (a, b) = accel.closest_hit_work(r);
                    (n + a as u64, p + b as u64)
                });
                let k = rays.len() as f64;
                format!("{:.2} / {:.2}", n as f64 / k, p as f64 / k)
            })
            .collect();
        println!(
            "| {name} | {:.2} | {} | {ms:.0} | {} | {} |",
            accel.sah_cost(),
            accel.node_count(),
            work[0],
            work[1]
        );
    }
}

/// The dump read by `scripts/bench_embree.py`, little-endian: b"GTRAYS1\0", vertex
/// and triangle counts (u32), vertices (f32 × 3), indices (u32 × 3), the number
/// of ray sets, then per set: name length and bytes, ray count, our closest-hit
/// and any-hit counts (u32), origins and directions (f32 × 3 each).
fn write_rays(
    path: &std::path::Path,
    mesh: &Mesh,
    accel: &Accel,
    sets: &[(&str, Vec<Ray>)],
) -> std::io::Result<()> {
    let mut out: Vec<u8> = b"GTRAYS1\0".to_vec();
    let u32s = |out: &mut Vec<u8>, v: &[u32]| v.iter().for_each(|x| out.extend(x.to_le_bytes()));
    u32s(
        &mut out,
        &[mesh.positions.len() as u32, mesh.triangles.len() as u32],
    );
    for p in &mesh.positions {
        p.to_array()
            .iter()
            .for_each(|x| out.extend(x.to_le_bytes()));
    }
    for t in &mesh.triangles {
        u32s(&mut out, t);
    }
    u32s(&mut out, &[sets.len() as u32]);
    for (name, rays) in sets {
        let closest = rays.iter().filter(|r| accel.intersect(r).is_some()).count();
        let any = rays.iter().filter(|r| accel.occluded(r)).count();
        u32s(&mut out, &[name.len() as u32]);
        out.extend(name.as_bytes());
        u32s(&mut out, &[rays.len() as u32, closest as u32, any as u32]);
        for r in rays {
            r.origin
                .to_array()
                .iter()
                .for_each(|x| out.extend(x.to_le_bytes()));
        }
        for r in rays {
            r.dir
                .to_array()
                .iter()
                .for_each(|x| out.extend(x.to_le_bytes()));
        }
    }
    std::fs::write(path, out)
}

criterion_group!(benches, bench_accel);
criterion_main!(benches);
