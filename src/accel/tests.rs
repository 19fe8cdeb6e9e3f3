//! The accel's unit tests and their scenes (shared with `stream.rs`'s tests);
//! the trees are checked against [`BruteForce`].

pub(super) use super::brute_force::BruteForce;
use super::*;

/// Uniform f32s in [0, 1) from a 64-bit LCG: test data reproducible without a
/// dependency.
pub(super) fn lcg(mut seed: u64) -> impl FnMut() -> f32 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 40) as f32 / 16_777_216.0
    }
}

/// A closed, finely tessellated sphere (shared edges and vertices), a
/// heap of small overlapping quads, and analytic spheres.
fn scene() -> (Vec<Mesh>, Vec<Sphere>) {
    let globe = globe(40, 60);
    let mut next = lcg(7);
    let mut quads = Mesh {
        name: "quads".into(),
        ..Default::default()
    };
    add_quads(&mut quads, 500, 0.3, &mut next);
    let spheres = (0..20)
        .map(|k| Sphere {
            name: format!("s{k}"),
            center: Vec3::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0),
            radius: 0.05 + 0.2 * next(),
            material: 0,
            emission: Vec3::ZERO,
            bump: None,
            object_id: 0,
        })
        .collect();
    (vec![globe, quads], spheres)
}

/// The 8-wide and 4-wide trees (leaves of 1 to 8 primitives, so one or
/// two triangle4 blocks with sphere lanes; greedy and SAH collapse) find
/// closest hits bit-identical in distances and barycentrics and the same
/// occlusion as brute force.
#[test]
fn node_widths_and_leaf_sizes_agree_with_brute_force() {
    let (meshes, spheres) = scene();
    let mut next = lcg(11);
    let rays: Vec<Ray> = (0..3000)
        .map(|_| {
            let o = Vec3::new(next(), next(), next()) * 6.0 - 3.0;
            let d = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
            Ray::new(o, d.normalize_or(Vec3::X))
        })
        .collect();
    let widths: &[usize] = if bvh8::supported() { &[4, 8] } else { &[4] };
    let mut hits = 0;
    for &node_width in widths {
        for (max_prims_per_leaf, leaf_cost) in [1, 4, 8]
            .into_iter()
            .flat_map(|m| [(m, None), (m, Some(1.0))])
        {
            let preset = BuildPreset {
                node_width,
                max_prims_per_leaf,
                leaf_cost,
                ..BuildPreset::default()
            };
            let accel = Accel::build_with_preset(&meshes, &spheres, &preset);
            assert_eq!(matches!(accel.tree, Tree::Eight(_)), node_width == 8);
            let reference = BruteForce::new(&accel, &meshes, &spheres);
            for ray in &rays {
                let (a, b) = (accel.intersect(ray), reference.intersect(ray));
                assert_eq!(
                    a.map(|h| h.t.to_bits()),
                    b.map(|h| h.t.to_bits()),
                    "{ray:?}"
                );
                if let (Some(a), Some(b)) = (a, b) {
                    // Another primitive only on an exact tie (a shared edge).
                    if a.prim == b.prim {
                        assert_eq!(a.bary, b.bary, "{ray:?}");
                    }
                    hits += 1;
                }
                assert_eq!(accel.occluded(ray), reference.occluded(ray), "{ray:?}");
            }
        }
    }
    assert!(hits > 1000, "{hits}");
}

/// A closed unit sphere of `rings` × `segments` quads, each two
/// triangles sharing their edges and vertices with their neighbours.
pub(super) fn globe(rings: u32, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    let mut triangles = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * segments + j, i * segments + (j + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    Mesh {
        name: "globe".into(),
        positions,
        triangles,
        ..Default::default()
    }
}

/// `count` quads (two triangles each) of edges up to `size` at random
/// in [−2, 2]³.
pub(super) fn add_quads(mesh: &mut Mesh, count: usize, size: f32, next: &mut impl FnMut() -> f32) {
    for _ in 0..count {
        let o = Vec3::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0);
        let (u, v) = (
            Vec3::new(next(), 0.0, next()) * size,
            Vec3::new(0.0, next(), next()) * size,
        );
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([o, o + u, o + u + v, o + v]);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }
}
