//! Acceleration structure tests: BVH traversal vs. brute force on a mixed scene,
//! ray interval handling, watertightness on closed meshes, rays inside spheres,
//! degenerate input, a pathologically deep scene, and robust ray spawning.

use gradtrace::accel::brute_force::BruteForce;
use gradtrace::accel::{offset_ray_origin, Accel, Hit, PrimRef};
use gradtrace::math::{Ray, Vec3};
use gradtrace::scene::{Mesh, Sphere};

mod common;
mod scenes;
use common::Rng;

/// Ranges and directions drawn from the shared test generator.
trait RngExt {
    fn range(&mut self, a: f32, b: f32) -> f32;
    fn vec(&mut self, a: f32, b: f32) -> Vec3;
    fn unit(&mut self) -> Vec3;
}

impl RngExt for Rng {
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next_f32()
    }
    fn vec(&mut self, a: f32, b: f32) -> Vec3 {
        Vec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }
    /// Uniform on the sphere, by rejection from the cube.
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

fn mesh(name: &str, positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    Mesh {
        name: name.into(),
        positions,
        triangles,
        ..Default::default()
    }
}

fn sphere(center: Vec3, radius: f32) -> Sphere {
    Sphere {
        name: "s".into(),
        center,
        radius,
        material: 0,
        emission: Vec3::ZERO,
        bump: None,
        object_id: 0,
    }
}

fn bunny() -> Mesh {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/models/stanford-bunny.obj"
    );
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )
    .expect("bunny OBJ loads");
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for m in &models {
        let base = positions.len() as u32;
        positions.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    mesh("bunny", positions, triangles)
}

/// Checks a BVH closest hit against the brute-force one: the same hit bit for bit
/// (both use the same primitive routine, and an exact tie in t goes to the
/// primitive first in input order, whatever order either visits them in).
fn same_hit(bvh: Option<Hit>, brute: Option<Hit>, ray: &Ray) {
    match (bvh, brute) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            assert_eq!(
                a.t.to_bits(),
                b.t.to_bits(),
                "t differs for {ray:?}: {a:?} vs {b:?}"
            );
            assert_eq!(a.prim, b.prim, "tie broken differently for {ray:?}");
            assert_eq!(a.bary, b.bary);
        }
        _ => panic!("BVH {bvh:?} vs brute force {brute:?} for {ray:?}"),
    }
}

/// The mixed scene: random triangles + spheres + the bunny (scaled ×8).
fn mixed_scene(rng: &mut Rng) -> (Vec<Mesh>, Vec<Sphere>) {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for i in 0..400u32 {
        let c = rng.vec(-1.0, 1.0);
        let s = rng.range(0.02, 0.3);
        positions.push(c + rng.vec(-s, s));
        positions.push(c + rng.vec(-s, s));
        positions.push(c + rng.vec(-s, s));
        triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mut b = bunny();
    for p in &mut b.positions {
        *p = *p * 8.0 + Vec3::new(0.1, -0.3, 0.2);
    }
    let spheres = (0..40)
        .map(|_| sphere(rng.vec(-1.2, 1.2), rng.range(0.01, 0.3)))
        .collect();
    (vec![mesh("random", positions, triangles), b], spheres)
}

#[test]
fn bvh_agrees_with_brute_force_on_mixed_scene() {
    let mut rng = Rng::new(7);
    let (meshes, spheres) = mixed_scene(&mut rng);
    let accel = Accel::build(&meshes, &spheres);
    let brute = BruteForce::new(&accel, &meshes, &spheres);
    let tris: usize = meshes.iter().map(|m| m.triangles.len()).sum();
    assert_eq!(accel.triangle_count(), tris);
    assert_eq!(accel.sphere_count(), spheres.len());
    assert_eq!(accel.primitive_count(), tris + spheres.len());
    println!(
        "mixed scene: {} triangles, {} spheres, {} nodes, depth {}, build {:?}",
        tris,
        spheres.len(),
        accel.node_count(),
        accel.depth(),
        accel.build_time()
    );
    let (mut hits, mut sphere_hits, mut occluded) = (0, 0, 0);
    let n = 2000;
    for i in 0..n {
        let origin = rng.vec(-1.5, 1.5);
        let mut ray = Ray::new(origin, rng.unit());
        if i % 4 == 1 {
            // Restricted interval.
            ray.t_min = rng.range(0.0, 1.0);
            ray.t_max = ray.t_min + rng.range(0.0, 2.0);
        } else if i % 4 == 2 {
            // Shadow-like segment towards a random point.
            let target = rng.vec(-1.5, 1.5);
            let d = target - origin;
            ray = Ray::segment(origin, d.normalize(), d.length());
        }
        let a = accel.intersect(&ray);
        let b = brute.intersect(&ray);
        same_hit(a, b, &ray);
        if let Some(h) = a {
            hits += 1;
            sphere_hits += matches!(h.prim, PrimRef::Sphere(_)) as usize;
            assert!(h.t >= ray.t_min && h.t <= ray.t_max);
            // The recomputed surface point is the ray's hit point, and the normal
            // is unit length.
            let sp = accel
                .surface_point(&ray, &h)
                .expect("hit refers to a primitive");
            assert!(
                (sp.p - ray.at(h.t)).length() < 1e-5,
                "{sp:?} vs {}",
                ray.at(h.t)
            );
            assert!((sp.n_geo.length() - 1.0).abs() < 1e-5);
            // A triangle hit's vertices from its leaf block are its mesh's, and
            // a hit of the brute force (no block) has none.
            if let PrimRef::Triangle { mesh, tri } = h.prim {
                let m = &meshes[mesh as usize];
                let want = m.triangles[tri as usize].map(|i| m.positions[i as usize]);
                let (v, n) = accel.hit_triangle(&h).expect("a triangle hit in a block");
                assert_eq!(v, want, "{ray:?}");
                assert_eq!(accel.hit_triangle(&b.expect("brute force agrees")), None);
                // Its normal, computed at build time, has the bits of the one
                // computed per hit, and is this triangle's (checked at f64).
                assert_eq!(n.to_array(), sp.n_geo.to_array(), "{ray:?}");
                let [p0, p1, p2] = want.map(|p| p.as_dvec3());
                let exact = (p1 - p0).cross(p2 - p0).normalize();
                assert!(n.as_dvec3().dot(exact) > 1.0 - 1e-6, "{n} vs {exact}");
            } else {
                assert_eq!(accel.hit_triangle(&h), None);
            }
        }
        let occ = accel.occluded(&ray);
        assert_eq!(occ, b.is_some(), "{ray:?}");
        if i % 8 == 0 {
            assert_eq!(occ, brute.occluded(&ray), "{ray:?}");
        }
        occluded += occ as usize;
    }
    println!("{n} rays: {hits} hits ({sphere_hits} on spheres), {occluded} occluded");
    // The test must exercise both kinds of primitives and both outcomes.
    assert!(hits > n / 4 && hits < n, "{hits}");
    assert!(sphere_hits > 50, "{sphere_hits}");
}

#[test]
fn accel_is_shareable_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Accel>();
}

#[test]
fn t_min_and_t_max_are_respected() {
    // Ten parallel quads at z = 1..=10 and a unit sphere at z = 20.
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 1..=10u32 {
        let z = k as f32;
        let b = positions.len() as u32;
        positions.extend([
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ]);
        triangles.extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
    }
    let (meshes, spheres) = (
        [mesh("stack", positions, triangles)],
        [sphere(Vec3::new(0.0, 0.0, 20.0), 1.0)],
    );
    let accel = Accel::build(&meshes, &spheres);
    let o = Vec3::new(0.1, 0.2, 0.0);
    let hit_t = |t_min: f32, t_max: f32| {
        let ray = Ray {
            origin: o,
            dir: Vec3::Z,
            t_min,
            t_max,
        };
        let h = accel.intersect(&ray).map(|h| h.t);
        assert_eq!(h.is_some(), accel.occluded(&ray));
        h
    };
    assert_eq!(hit_t(0.0, f32::INFINITY), Some(1.0));
    assert_eq!(hit_t(3.5, f32::INFINITY), Some(4.0));
    assert_eq!(hit_t(0.0, 3.5), Some(1.0));
    assert_eq!(hit_t(1.5, 3.5), Some(2.0));
    assert_eq!(hit_t(0.0, 0.5), None);
    assert_eq!(hit_t(4.2, 4.8), None);
    // Closed interval: a hit exactly at t_min or t_max counts.
    assert_eq!(hit_t(5.0, 5.0), Some(5.0));
    // Beyond the quads: the sphere's near root, then its far root (the ray is
    // 0.05 off the sphere's axis, so half the chord is √0.95).
    let half_chord = 0.95f32.sqrt();
    let near = hit_t(10.5, f32::INFINITY).expect("near root");
    assert!((near - (20.0 - half_chord)).abs() < 1e-5, "{near}");
    let far = hit_t(19.5, f32::INFINITY).expect("far root");
    assert!((far - (20.0 + half_chord)).abs() < 1e-5, "{far}");
    assert_eq!(hit_t(21.5, f32::INFINITY), None);
    // A negative t_min admits hits behind the origin.
    let behind = Ray {
        origin: Vec3::new(0.1, 0.2, 4.5),
        dir: Vec3::Z,
        t_min: -2.0,
        t_max: f32::INFINITY,
    };
    let t = accel.intersect(&behind).expect("hit behind the origin").t;
    assert!((t + 1.5).abs() < 1e-6, "{t}");
    let brute = BruteForce::new(&accel, &meshes, &spheres);
    assert_eq!(brute.intersect(&behind).map(|h| h.t), Some(t));
    // Hits closer than obvhs' internal 1e-4 node epsilon are still found.
    let ray = Ray::new(Vec3::new(0.1, 0.2, 1.0 - 3.0e-5), Vec3::Z);
    let h = accel.intersect(&ray).expect("hit at t = 3e-5");
    assert!((h.t - 3.0e-5).abs() < 1e-6, "{}", h.t);
}

fn cube(min: Vec3, max: Vec3) -> Mesh {
    let p = |i: u32| {
        Vec3::new(
            if i & 1 != 0 { max.x } else { min.x },
            if i & 2 != 0 { max.y } else { min.y },
            if i & 4 != 0 { max.z } else { min.z },
        )
    };
    let positions = (0..8).map(p).collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    mesh("cube", positions, triangles)
}

/// Shoots rays from interior points exactly at every vertex and at points on
/// every edge of a closed mesh; every ray must hit (closest and any-hit).
/// Returns (rays, leaks of the BVH, leaks of obvhs' non-watertight test).
fn leak_count(
    m: &Mesh,
    interior: &[Vec3],
    per_edge: usize,
    rng: &mut Rng,
) -> (usize, usize, usize) {
    let accel = Accel::build(std::slice::from_ref(m), &[]);
    let mut edges: Vec<(u32, u32)> = m
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let naive: Vec<obvhs::triangle::Triangle> = m
        .triangles
        .iter()
        .map(|t| obvhs::triangle::Triangle {
            v0: m.positions[t[0] as usize],
            v1: m.positions[t[1] as usize],
            v2: m.positions[t[2] as usize],
        })
        .collect();
    let (mut rays, mut leaks, mut naive_leaks) = (0, 0, 0);
    let mut shoot = |o: Vec3, target: Vec3| {
        let ray = Ray::new(o, (target - o).normalize());
        rays += 1;
        let hit = accel.intersect(&ray);
        let occ = accel.occluded(&ray);
        if hit.is_none() || !occ {
            leaks += 1;
        }
        let r = obvhs::ray::Ray::new_inf(o, ray.dir);
        if naive.iter().all(|t| t.intersect(&r) == f32::INFINITY) {
            naive_leaks += 1;
        }
    };
    for &o in interior {
        for &p in &m.positions {
            shoot(o, p);
        }
        for &(a, b) in &edges {
            let (pa, pb) = (m.positions[a as usize], m.positions[b as usize]);
            for k in 0..per_edge {
                // Midpoint, then random points along the edge.
                let s = if k == 0 { 0.5 } else { rng.next_f32() };
                shoot(o, pa + (pb - pa) * s);
            }
        }
    }
    (rays, leaks, naive_leaks)
}

#[test]
fn closed_meshes_are_watertight_at_edges_and_vertices() {
    let mut rng = Rng::new(3);
    // Icosphere (level 3: 1280 triangles) at an odd position and scale.
    let c = Vec3::new(10.3, -2.1, 5.7);
    let ico = scenes::icosphere_mesh(3, c, 3.7, 0);
    let interior = [
        c,
        c + Vec3::new(0.5, -1.1, 0.3),
        c + Vec3::new(-2.0, 1.3, 1.7),
        c + Vec3::new(1e-3, 2e-3, -3.0),
    ];
    let (rays, leaks, naive) = leak_count(&ico, &interior, 22, &mut rng);
    println!(
        "icosphere: {rays} rays at vertices/edges, {leaks} leaks (obvhs Möller–Trumbore: {naive})"
    );
    assert!(rays >= 100_000, "{rays}");
    assert_eq!(leaks, 0);

    // Cube: faces on the root box planes, axis-aligned edges.
    let cube = cube(Vec3::new(-1.0, -2.0, 0.5), Vec3::new(3.0, 1.5, 4.0));
    let interior = [
        Vec3::new(1.0, -0.25, 2.25),
        Vec3::new(-0.5, 1.0, 0.75),
        Vec3::new(2.9, -1.9, 3.9),
        Vec3::new(0.0, 0.0, 1.0),
    ];
    let (rays, leaks, naive) = leak_count(&cube, &interior, 2000, &mut rng);
    println!("cube: {rays} rays at vertices/edges, {leaks} leaks (obvhs Möller–Trumbore: {naive})");
    assert_eq!(leaks, 0);

    // Axis-parallel rays grazing the cube's faces from inside, through an edge.
    let accel = Accel::build(std::slice::from_ref(&cube), &[]);
    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let ray = Ray::new(Vec3::new(1.0, -0.25, 2.25), d);
        assert!(
            accel.intersect(&ray).is_some() && accel.occluded(&ray),
            "{d}"
        );
    }
}

#[test]
fn rays_from_inside_a_sphere_hit_its_far_side() {
    let mut rng = Rng::new(11);
    let c = Vec3::new(-3.0, 7.5, 100.0);
    let r = 2.5;
    let accel = Accel::build(&[], &[sphere(c, r), sphere(c + Vec3::X * 10.0, 1.0)]);
    let mut worst = 0.0f32;
    for _ in 0..20_000 {
        let o = c + rng.unit() * (r * rng.next_f32().sqrt() * 0.999);
        let d = rng.unit();
        let h = accel.intersect(&Ray::new(o, d)).expect("inside ray hits");
        assert_eq!(h.prim, PrimRef::Sphere(0));
        // Analytic far root in f64.
        let f = (o - c).as_dvec3();
        let dd = d.as_dvec3();
        let b = f.dot(dd);
        let t = -b + (b * b - (f.dot(f) - (r as f64).powi(2))).sqrt();
        let err = (h.t as f64 - t).abs();
        worst = worst.max(err as f32);
        assert!(err < 1e-4 * r as f64, "t {} vs {}", h.t, t);
    }
    println!("inside-sphere rays: worst |t − t_exact| = {worst:e}");
}

#[test]
fn degenerate_input_does_not_panic() {
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    let empty = Accel::build(&[], &[]);
    assert!(empty.intersect(&ray).is_none() && !empty.occluded(&ray));
    assert_eq!(empty.bounds(), None);

    // A zero-area triangle, a point triangle, bad indices, NaN vertex, bad spheres.
    let m = mesh(
        "bad",
        vec![
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(f32::NAN, 0.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 0, 0], [0, 1, 7], [0, 1, 3]],
    );
    let spheres = [
        sphere(Vec3::new(5.0, 0.0, 0.0), 0.0),
        sphere(Vec3::new(5.0, 0.0, 0.0), -1.0),
        sphere(Vec3::new(5.0, 0.0, 0.0), f32::INFINITY),
    ];
    let accel = Accel::build(std::slice::from_ref(&m), &spheres);
    assert_eq!(accel.rejected_count(), 5);
    assert_eq!(accel.triangle_count(), 2);
    for r in [
        ray,
        Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::X),
        Ray::new(Vec3::new(1.0, 0.0, -1.0), Vec3::Z),
        Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray {
            t_min: 2.0,
            t_max: 1.0,
            ..ray
        },
    ] {
        assert!(accel.intersect(&r).is_none(), "{r:?}");
        assert!(!accel.occluded(&r), "{r:?}");
    }
    // A single valid primitive (the root of the BVH is a leaf) and a single point.
    let one = Accel::build(&[], &[sphere(Vec3::new(5.0, 0.0, 0.0), 1.0)]);
    assert_eq!(one.intersect(&ray).map(|h| h.t), Some(4.0));
    let point = Accel::build(&[mesh("p", vec![Vec3::ONE; 3], vec![[0, 1, 2]])], &[]);
    assert!(point
        .intersect(&Ray::new(Vec3::ZERO, Vec3::ONE.normalize()))
        .is_none());
}

#[test]
fn pathological_deep_scene_matches_brute_force() {
    // Many tiny, nearly coincident triangles along a line whose spacing shrinks
    // geometrically: PLOC merges them into a chain, the deepest tree shape.
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // x from 1 down to 2^-40 ≈ 1e-12: below that the triangles' area (s² ≈ 1e-30)
    // approaches the f32 underflow limit and no f32 triangle test can hit them.
    let n = 1000u32;
    let x_of = |k: u32| 0.5f32.powf(k as f32 * 0.04);
    for k in 0..n {
        let x = x_of(k);
        let s = x * 1e-3;
        let b = positions.len() as u32;
        positions.extend([
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x + s, s, 0.0),
            Vec3::new(x, s, s),
        ]);
        triangles.push([b, b + 1, b + 2]);
    }
    // Plus exactly coincident copies of one tiny triangle (identical boxes, which
    // the build groups into a balanced subtree) and an onion of concentric
    // spheres: nested boxes, which PLOC can only chain (this makes the tree deep).
    let copies = 1500;
    let t = triangles[500];
    triangles.extend(std::iter::repeat_n(t, copies));
    let meshes = [mesh("line", positions, triangles)];
    let onion: Vec<Sphere> = (0..600)
        .map(|k| sphere(Vec3::new(3.0, 0.0, 0.0), 0.01 * 1.005f32.powi(k)))
        .collect();
    let accel = Accel::build(&meshes, &onion);
    let brute = BruteForce::new(&accel, &meshes, &onion);
    println!(
        "deep scene: depth {}, stack: {}, nodes {}",
        accel.depth(),
        accel.stack_size(),
        accel.node_count()
    );
    assert_eq!(accel.primitive_count(), n as usize + copies + onion.len());
    // The point of this scene: a stack far deeper than any regular tree needs
    // (the bunny's holds 46 entries; obvhs' CWBVH stack held 32).
    assert!(accel.depth() > 31 && accel.stack_size() > 64);
    let mut rng = Rng::new(5);
    let mut hits = 0;
    for i in 0..4000 {
        // Rays aimed at random triangles of the line from random directions, every
        // fourth one at the stack of coincident copies, every eighth from inside
        // the onion.
        if i % 8 == 3 {
            let o = Vec3::new(3.0, 0.0, 0.0) + rng.vec(-0.1, 0.1);
            let ray = Ray::new(o, rng.unit());
            let a = accel.intersect(&ray);
            same_hit(a, brute.intersect(&ray), &ray);
            assert!(matches!(a.map(|h| h.prim), Some(PrimRef::Sphere(_))));
            hits += 1;
            continue;
        }
        let k = if i % 4 == 0 {
            500
        } else {
            (rng.next_u64() % n as u64) as u32
        };
        let x = x_of(k);
        // The triangle's centroid.
        let s = x * 1e-3;
        let target = Vec3::new(x + s / 3.0, 2.0 * s / 3.0, s / 3.0);
        // Origins at a distance proportional to the triangle's scale, so that the
        // direction can resolve it in f32.
        let o = target + rng.unit() * x * rng.range(1e-2, 2.0);
        let ray = Ray::new(o, (target - o).normalize());
        let a = accel.intersect(&ray);
        same_hit(a, brute.intersect(&ray), &ray);
        assert_eq!(accel.occluded(&ray), a.is_some());
        hits += a.is_some() as usize;
    }
    println!("deep scene: {hits} / 4000 rays hit");
    assert!(hits > 3500, "{hits}");
}

#[test]
fn spawned_rays_do_not_self_intersect() {
    let mut rng = Rng::new(13);
    let c = Vec3::new(40.0, -20.0, 7.0);
    let ico_center = Vec3::new(-30.0, 12.0, 3.0);
    let ico = scenes::icosphere_mesh(2, ico_center, 5.0, 0);
    let accel = Accel::build(&[ico], &[sphere(c, 3.0)]);
    let mut checked = 0;
    for _ in 0..20_000 {
        // Hit one of the two convex objects from outside.
        let target = if rng.next_f32() < 0.5 { c } else { ico_center };
        let o = target + rng.unit() * 20.0;
        let ray = Ray::new(o, (target + rng.vec(-1.0, 1.0) - o).normalize());
        let Some(h) = accel.intersect(&ray) else {
            continue;
        };
        let sp = accel.surface_point(&ray, &h).expect("valid hit");
        // Leaving a convex object outward must not hit it again…
        let outward = if sp.n_geo.dot(sp.p - target) < 0.0 {
            -sp.n_geo
        } else {
            sp.n_geo
        };
        let mut out = rng.unit();
        if out.dot(outward) < 0.0 {
            out = -out;
        }
        // (it may hit the *other* object, far away).
        let is_sphere = |h: &Hit| matches!(h.prim, PrimRef::Sphere(_));
        if let Some(h3) = accel.intersect(&sp.spawn_ray(out)) {
            assert_ne!(
                is_sphere(&h3),
                is_sphere(&h),
                "self-hit leaving {h:?}: {h3:?}"
            );
            assert!(h3.t > 10.0);
        }
        // …and the plain helper gives the same guarantee.
        let o2 = offset_ray_origin(sp.p, sp.n_geo, out);
        if let Some(h3) = accel.intersect(&Ray::new(o2, out)) {
            assert_ne!(
                is_sphere(&h3),
                is_sphere(&h),
                "self-hit leaving {h:?}: {h3:?}"
            );
        }
        // Entering it must hit the same primitive kind again, beyond the origin.
        let inward = -out;
        let h2 = accel
            .intersect(&sp.spawn_ray(inward))
            .expect("entering ray hits the far side");
        assert!(h2.t > 0.0);
        assert_eq!(is_sphere(&h2), is_sphere(&h));
        checked += 1;
    }
    assert!(checked > 5000, "{checked}");
}

/// A ray spawned off a wall of a room (an axis-aligned box seen from inside,
/// each face its own leaf) starts outside that wall's padded leaf box, so the
/// traversal never tests the wall's own triangles: a ray spawned straight up
/// off the floor tests the ceiling's two triangles and nothing else. With the
/// hit point's rounding bound alone as the offset (the floor's removed) the
/// origin sits inside the floor's padding and the floor's two are tested too,
/// which is what `Accel::spawn_floor` saves (cornell −9 %).
#[test]
fn rays_spawned_off_a_wall_do_not_open_its_leaf() {
    let accel = Accel::build(&[cube(Vec3::splat(-1.0), Vec3::splat(1.0))], &[]);
    let floor = accel.spawn_floor();
    assert!(floor > 0.0 && floor < 1.0e-4, "{floor}");
    let mut rng = Rng::new(29);
    let (mut with, mut without) = (0, 0);
    for _ in 0..500 {
        let (x, z) = (rng.range(-0.9, 0.9), rng.range(-0.9, 0.9));
        let down = Ray::new(Vec3::new(x, 0.0, z), -Vec3::Y);
        let h = accel.intersect(&down).expect("the floor");
        let sp = accel.surface_point(&down, &h).expect("a triangle");
        assert!(sp.p_error.min_element() >= floor);
        let up = sp.spawn_ray(Vec3::Y);
        assert!(up.origin.y > -1.0 + floor, "{}", up.origin.y);
        with += accel.closest_hit_work(&up).1;
        let bare = gradtrace::accel::offset_ray_origin_with_error(
            sp.p,
            sp.p_error.min(Vec3::splat(floor * 0.01)),
            sp.n_geo,
            Vec3::Y,
        );
        without += accel.closest_hit_work(&Ray::new(bare, Vec3::Y)).1;
        assert_eq!(
            accel.intersect(&up).map(|h| h.prim),
            accel.intersect(&Ray::new(bare, Vec3::Y)).map(|h| h.prim)
        );
    }
    assert_eq!(with, 2 * 500, "the ceiling's two triangles per ray");
    assert_eq!(without, 4 * 500, "and the floor's two without the floor");
}

/// The floor stays a negligible fraction of a scene far from the origin,
/// whose box padding grows with its coordinates rather than its size.
#[test]
fn the_spawn_floor_follows_the_scene_size_far_from_the_origin() {
    let near = Accel::build(&[cube(Vec3::splat(-1.0), Vec3::splat(1.0))], &[]);
    let shift = Vec3::new(1.0e4, 0.0, -1.0e4);
    let far = Accel::build(
        &[cube(Vec3::splat(-1.0) + shift, Vec3::splat(1.0) + shift)],
        &[],
    );
    // Twice the padding (2^-16 of the largest coordinate) at the origin…
    assert_eq!(near.spawn_floor(), 2.0 / 65_536.0);
    // …and 2^-15 of the extent (2) far from it, not of the coordinates (1e4).
    assert_eq!(far.spawn_floor(), 2.0 / 32_768.0);
}

/// Rays leaving a convex object at grazing angles (cos θ from 1e-2 down to
/// 1e-6 against the geometric normal), near the origin and 1e4–1e6 away from it,
/// must never hit that object again, although the spawn offset is only the hit
/// point's rounding bound (a few ulps, where the path tracer's old offset was
/// 1e-4 of the coordinates). Spawned from the raw hit point instead, 7,097 of
/// 19,999 rays re-hit at the origin. (The triangle test's t > δt and the
/// widened sphere bound, which the worst-case analysis needs, are not what
/// this test catches: it passes without either.)
#[test]
fn grazing_spawned_rays_do_not_self_intersect_at_any_scale() {
    let mut rng = Rng::new(29);
    for shift in [
        Vec3::ZERO,
        Vec3::new(1.0e4, -3.0e3, 2.0e4),
        Vec3::new(-7.0e5, 1.0e6, 3.0e5),
    ] {
        let (ico_center, c) = (
            shift + Vec3::new(-30.0, 12.0, 3.0),
            shift + Vec3::new(40.0, -20.0, 7.0),
        );
        let ico = scenes::icosphere_mesh(3, ico_center, 5.0, 0);
        let accel = Accel::build(&[ico], &[sphere(c, 3.0)]);
        let (mut checked, mut self_hits) = (0, 0);
        for i in 0..20_000 {
            let target = if i % 2 == 0 { c } else { ico_center };
            let o = target + rng.unit() * 20.0;
            let ray = Ray::new(o, (target + rng.vec(-1.0, 1.0) - o).normalize());
            let Some(h) = accel.intersect(&ray) else {
                continue;
            };
            let sp = accel.surface_point(&ray, &h).expect("valid hit");
            let n = if sp.n_geo.dot(sp.p - target) < 0.0 {
                -sp.n_geo
            } else {
                sp.n_geo
            };
            // A tangent direction, tilted outward by cos θ = 10^-k.
            let r = rng.unit();
            let tangent = (r - n * r.dot(n)).normalize_or_zero();
            if tangent == Vec3::ZERO {
                continue;
            }
            let cos = 10f32.powf(-2.0 - 4.0 * rng.next_f32());
            let out = (n * cos + tangent * (1.0 - cos * cos).sqrt()).normalize();
            if out.dot(n) <= 0.0 {
                continue;
            }
            let is_sphere = |h: &Hit| matches!(h.prim, PrimRef::Sphere(_));
            if let Some(h2) = accel.intersect(&sp.spawn_ray(out)) {
                self_hits += (is_sphere(&h2) == is_sphere(&h)) as usize;
            }
            checked += 1;
        }
        assert!(checked > 15_000, "{checked}");
        assert_eq!(
            self_hits, 0,
            "{self_hits} of {checked} grazing rays re-hit their object (shift {shift})"
        );
    }
}

/// Rays spawned off the bunny scene's geometry (the mesh scaled by 8 and its
/// 6 × 6 floor, two large triangles) into the hemisphere of the side they
/// leave, by both spawning helpers, must never hit the triangle they leave
/// again. This is where the triangle test's t > δt (pbrt-v4 §6.8.4) is
/// needed: the origin offset is only the hit point's rounding bound, and
/// without δt 233 of 22,215 rays here re-hit their own (floor) triangle at
/// t ≈ 0 — a bunny render then traced 33 % more rays, each a spurious bounce.
#[test]
fn rays_spawned_off_a_mesh_never_re_hit_their_own_triangle() {
    let mut rabbit = bunny();
    rabbit.positions.iter_mut().for_each(|p| *p *= 8.0);
    let (lo, hi) = Accel::build(std::slice::from_ref(&rabbit), &[])
        .bounds()
        .unwrap();
    // The 6 × 6 floor it stands on in `bunny_env.toml`: two large triangles.
    let y = lo.y;
    let floor = mesh(
        "floor",
        vec![
            Vec3::new(-3.0, y, 3.0),
            Vec3::new(3.0, y, 3.0),
            Vec3::new(3.0, y, -3.0),
            Vec3::new(-3.0, y, -3.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let accel = Accel::build(&[rabbit, floor], &[]);
    let centre = (lo + hi) * 0.5;
    let mut rng = Rng::new(31);
    let (mut checked, mut self_hits) = (0, 0);
    for _ in 0..40_000 {
        let o = centre + rng.unit() * (hi - lo).max_element() * 2.0;
        let ray = Ray::new(o, (centre + rng.vec(-3.0, 3.0) - o).normalize());
        let Some(h) = accel.intersect(&ray) else {
            continue;
        };
        let sp = accel.surface_point(&ray, &h).expect("valid hit");
        // Leave on the side the ray came from, in any direction of that hemisphere.
        let n = if sp.n_geo.dot(ray.dir) < 0.0 {
            sp.n_geo
        } else {
            -sp.n_geo
        };
        let mut out = rng.unit();
        if out.dot(n) < 0.0 {
            out = -out;
        }
        if out.dot(n) <= 0.0 {
            continue;
        }
        for spawned in [
            sp.spawn_ray(out),
            Ray::new(offset_ray_origin(sp.p, sp.n_geo, out), out),
        ] {
            if let Some(h2) = accel.intersect(&spawned) {
                self_hits += (h2.prim == h.prim) as usize;
            }
        }
        checked += 1;
    }
    assert!(checked > 20_000, "{checked}");
    assert_eq!(
        self_hits, 0,
        "{self_hits} self-hits in {checked} spawned rays"
    );
}

/// A `n`×`n` grid of unit quads (2n² triangles) in the plane y = 0, moved by `offset`.
fn grid(n: u32, offset: Vec3) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(i as f32, 0.0, j as f32) / n as f32 + offset);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let c = a + n + 1;
            triangles.push([a, a + 1, c + 1]);
            triangles.push([a, c + 1, c]);
        }
    }
    mesh("grid", positions, triangles)
}

/// BVH closest and any hit against brute force for random rays through `lo..hi`.
fn check_against_brute_force(
    brute: &BruteForce,
    lo: Vec3,
    hi: Vec3,
    rays: usize,
    seed: u64,
) -> usize {
    let accel = brute.accel();
    let mut rng = Rng::new(seed);
    let mut hits = 0;
    for _ in 0..rays {
        let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let target = lo + (hi - lo) * t;
        let origin = target - rng.unit() * (hi - lo).max_element() * 2.0;
        let ray = Ray::new(origin, (target - origin).normalize());
        let b = brute.intersect(&ray);
        same_hit(accel.intersect(&ray), b, &ray);
        assert_eq!(accel.occluded(&ray), b.is_some(), "{ray:?}");
        hits += b.is_some() as usize;
    }
    hits
}

#[test]
fn huge_primitives_build_without_panic() {
    // Issue 18: a sphere of radius ≥ 1e19 (box areas overflow f32) or corners near
    // 1e30 made obvhs' BVH2 → CWBVH conversion index out of bounds.
    let g = grid(10, Vec3::ZERO);
    for radius in [1.0e19f32, 1.0e30] {
        let big = sphere(Vec3::new(0.0, -2.0 * radius, 0.0), radius);
        let spheres = [big, sphere(Vec3::Y, 0.5)];
        let accel = Accel::build(std::slice::from_ref(&g), &spheres);
        let brute = BruteForce::new(&accel, std::slice::from_ref(&g), &spheres);
        assert_eq!(accel.primitive_count(), 202, "radius {radius}");
        // The small primitives are still found exactly.
        let hits = check_against_brute_force(&brute, Vec3::ZERO, Vec3::new(1.0, 1.5, 1.0), 300, 3);
        assert!(hits > 100, "{hits}");
        // A ray straight down onto the huge sphere (beside the grid): the BVH
        // finds what brute force finds. (How well the f32 sphere test resolves
        // such radii is the primitive test's business, not the BVH's: at 1e19
        // |o − c|² overflows and it reports the far root.)
        let down = Ray::new(Vec3::new(-0.5, 1.0, -0.5), -Vec3::Y);
        let hit = accel.intersect(&down);
        same_hit(hit, brute.intersect(&down), &down);
        if radius == 1.0e19 {
            assert_eq!(hit.map(|h| h.prim), Some(PrimRef::Sphere(0)));
        }
    }
    // Corners at ±1e30 (the triangle test's products overflow there, so only the
    // BVH's agreement with brute force is asked for).
    let corners = cube(Vec3::splat(-1.0e30), Vec3::splat(1.0e30));
    let meshes = [corners, g.clone()];
    let accel = Accel::build(&meshes, &[]);
    let brute = BruteForce::new(&accel, &meshes, &[]);
    assert_eq!(accel.primitive_count(), 212);
    for dir in [Vec3::Y, -Vec3::X, Vec3::new(0.3, -0.2, 0.9).normalize()] {
        let from_inside = Ray::new(Vec3::new(0.3, 5.0, 0.2), dir);
        same_hit(
            accel.intersect(&from_inside),
            brute.intersect(&from_inside),
            &from_inside,
        );
    }
    let hits = check_against_brute_force(&brute, Vec3::ZERO, Vec3::new(1.0, 0.5, 1.0), 200, 4);
    assert!(hits > 50, "{hits}");
    // Tiny scales (down to subnormal coordinates) build too: the frame's scale
    // and the pad's 1e-30 floor keep every exponent in range.
    for scale in [1.0e-20f32, 1.0e-38, 1.0e-44] {
        let mut tiny = g.clone();
        for p in &mut tiny.positions {
            *p *= scale;
        }
        let accel = Accel::build(std::slice::from_ref(&tiny), &[]);
        let brute = BruteForce::new(&accel, std::slice::from_ref(&tiny), &[]);
        let ray = Ray::new(Vec3::new(0.5, 1.0, 0.5) * scale, -Vec3::Y);
        same_hit(accel.intersect(&ray), brute.intersect(&ray), &ray);
    }
    // Beyond the build's own limit (far past the scene's): rejected, not a panic.
    let beyond = sphere(Vec3::ZERO, 1.0e37);
    let accel = Accel::build(std::slice::from_ref(&g), &[beyond]);
    assert_eq!((accel.rejected_count(), accel.primitive_count()), (1, 200));
}

/// The fastest of three builds (the machine is shared; one slow run is noise).
fn build_time(meshes: &[Mesh]) -> std::time::Duration {
    (0..3)
        .map(|_| Accel::build(meshes, &[]).build_time())
        .min()
        .unwrap()
}

#[test]
fn build_is_as_fast_far_from_the_origin() {
    // Issue 18: far from the origin a small mesh's vertices collapse to a few f32
    // values; the coincident boxes made PLOC merge one pair per pass (O(n²), a
    // tree thousands deep): a 20k-triangle grid at 1e15 took 10 s, the bunny at
    // 1e15 412 s (0.1 s at the origin).
    let far = Vec3::new(1.0e12, -1.0e12, 1.0e12);
    let cases = [("grid", grid(100, Vec3::ZERO)), ("bunny", bunny())];
    for (name, m) in cases {
        let mut moved = m.clone();
        for p in &mut moved.positions {
            *p += far;
        }
        let (near_t, far_t) = (build_time(&[m]), build_time(std::slice::from_ref(&moved)));
        let accel = Accel::build(&[moved], &[]);
        println!(
            "{name}: build {near_t:?} at the origin, {far_t:?} at 1e12, depth {}",
            accel.depth()
        );
        assert!(far_t < near_t * 10, "{name}: {far_t:?} vs {near_t:?}");
        assert!(accel.depth() < 24, "{name}: depth {}", accel.depth());
    }
}

#[test]
fn bvh_agrees_with_brute_force_with_coincident_boxes() {
    // Duplicate boxes are grouped under one PLOC leaf: 300 copies of one triangle
    // (every copy a tie), the grid's quad pairs (equal boxes, different
    // triangles) and a grid whose vertices collapsed to a few values at 1e8.
    let tri = mesh(
        "copies",
        vec![
            Vec3::new(0.2, 0.3, 0.1),
            Vec3::new(0.8, 0.3, 0.2),
            Vec3::new(0.5, 0.9, 0.6),
        ],
        vec![[0, 1, 2]; 300],
    );
    let meshes = [tri, grid(30, Vec3::ZERO)];
    let accel = Accel::build(&meshes, &[]);
    assert!(accel.depth() < 24, "depth {}", accel.depth());
    let brute = BruteForce::new(&accel, &meshes, &[]);
    let hits = check_against_brute_force(&brute, Vec3::splat(-0.1), Vec3::splat(1.1), 3000, 5);
    assert!(hits > 1000, "{hits}");
    let mut collapsed = grid(40, Vec3::ZERO);
    for p in &mut collapsed.positions {
        *p = *p * 30.0 + Vec3::splat(1.0e8);
    }
    let accel = Accel::build(std::slice::from_ref(&collapsed), &[]);
    let (lo, hi) = accel.bounds().unwrap();
    let brute = BruteForce::new(&accel, std::slice::from_ref(&collapsed), &[]);
    let hits = check_against_brute_force(&brute, lo, hi + Vec3::Y, 500, 6);
    assert!(hits > 100, "{hits}");
}

#[test]
fn ties_on_shared_edges_go_the_same_way_for_every_tree_width_and_leaf_size() {
    // Rays through the grid's vertices and along its edges hit two or more
    // triangles at exactly the same t; the hit must not depend on the order the
    // tree visits them in (4- or 8-wide nodes, 1 to 8 primitives per leaf), nor
    // differ from brute force.
    let n = 16;
    let meshes = [grid(n, Vec3::ZERO), grid(n, Vec3::ZERO)];
    let mut trees = Vec::new();
    for width in [4, 8] {
        for leaf in [1, 4, 8] {
            let preset = gradtrace::accel::BuildPreset {
                node_width: width,
                max_prims_per_leaf: leaf,
                ..Default::default()
            };
            trees.push((
                (width, leaf),
                Accel::build_with_preset(&meshes, &[], &preset),
            ));
        }
    }
    let brute = BruteForce::new(&trees[0].1, &meshes, &[]);
    let mut rays = 0;
    let mut multi = 0;
    for j in 0..=n {
        for i in 0..=n {
            for (di, dj) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
                let target = Vec3::new(i as f32 + di, 0.0, j as f32 + dj) / n as f32;
                let origin = target + Vec3::new(0.3, 1.0, -0.2);
                let ray = Ray::new(origin, (target - origin).normalize());
                let want = brute.intersect(&ray);
                for (what, accel) in &trees {
                    let got = accel.intersect(&ray);
                    assert_eq!(got, want, "{what:?}: {ray:?}");
                }
                rays += 1;
                // The two meshes coincide: every hit is a tie, which mesh 0 wins.
                if let Some(h) = want {
                    assert!(matches!(h.prim, PrimRef::Triangle { mesh: 0, .. }), "{h:?}");
                    multi += 1;
                }
            }
        }
    }
    assert!(multi * 2 > rays, "{multi} hits (all ties) of {rays} rays");
}
