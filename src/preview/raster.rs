//! camera + meshes → the primitive each camera sample sees, by rasterising with a
//! depth buffer (the paper renders its previews on a GPU rasteriser), then the exact
//! hit by one ray–triangle test: the same `Hit` as a BVH ray cast, bit for bit, at a
//! fraction of its cost for a frame's coherent primary rays.
//!
//! Rasterising only proposes a candidate per sample; the answer always comes from
//! the accel's own watertight test. Coverage is widened by `SLACK` of a sample
//! spacing, so a sample on a shared edge is covered by both triangles and one of
//! them is kept; where the kept candidate's exact test misses (a sample just off its
//! edge), the sample is ray-cast. A sample no widened triangle covers sees nothing.
//! Everything before the exact test runs in f64, so that coverage is exact to far
//! below the slack even for a ground plane that reaches behind the camera (clipped
//! at a near plane, as a GPU does).

use crate::accel::{Accel, Hit, PrimRef};
use crate::math::Ray;
use crate::scene::{Camera, Mesh, Sphere};
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// How far outside a triangle, in sample spacings, a sample still counts as
/// covered: far above the f64 error of the edge functions and above the f32 error
/// of the camera ray it stands for (about 1e-3 of a sample at 1024 samples across).
const SLACK: f64 = 0.01;

/// Image rows per parallel band (each band owns its depth buffer).
const BAND_ROWS: usize = 8;

/// The candidate primitive of every camera sample of an `n × n`-per-pixel grid, in
/// the layout of `preview::glossy::render_supersampled`: image row `y` holds
/// `w·n·n` samples, pixel `x`'s at `x·n·n + ky·n + kx` for the sample at
/// `(x + (kx + ½)/n, y + (ky + ½)/n)`.
pub struct PrimaryVisibility {
    /// 1 + the input index of the kept triangle (triangles of mesh 0, mesh 1, …),
    /// 0 where no triangle covers the sample.
    candidate: Vec<u32>,
    /// Input index of each mesh's first triangle, one extra at the end.
    mesh_first: Vec<u32>,
}

/// One triangle (or a piece of one clipped at the near plane) in sample-grid
/// coordinates: edge functions positive inside and already widened by the slack,
/// 1/depth as an affine function, and the samples its box spans.
struct Setup {
    id: u32,
    edge: [[f64; 3]; 3],
    inv_depth: [f64; 3],
    x: (usize, usize),
    y: (usize, usize),
}

impl PrimaryVisibility {
    /// Rasterises `meshes` for `camera` at `n × n` samples per pixel (the shapes
    /// the accel was built from). `None` when rasterising cannot stand in for ray
    /// casting: spheres, or geometry within the near distance of the eye (where
    /// clipping would lose what a ray sees).
    pub fn rasterise(
        meshes: &[Mesh],
        spheres: &[Sphere],
        camera: &Camera,
        n: usize,
    ) -> Option<Self> {
        if !spheres.is_empty() {
            return None;
        }
        let n = n.max(1);
        let (w, h) = (camera.width as usize, camera.height as usize);
        let (gw, gh) = (w * n, h * n);
        let mut mesh_first = Vec::with_capacity(meshes.len() + 1);
        let mut count = 0u32;
        for m in meshes {
            mesh_first.push(count);
            count = count.checked_add(u32::try_from(m.triangles.len()).ok()?)?;
        }
        mesh_first.push(count);
        // A sample stores 1 + the triangle's input index (0: none): it must fit.
        count.checked_add(1)?;
        let near = near_distance(meshes, camera);
        let slopes = camera.frustum_slopes().as_dvec2();
        // Set up every triangle in parallel, in input order (a depth tie goes to
        // the first); `None` as soon as one reaches the eye.
        let pieces: Vec<[Option<Setup>; 2]> = meshes
            .par_iter()
            .enumerate()
            .flat_map(|(mi, m)| {
                let first = mesh_first[mi];
                m.triangles
                    .par_iter()
                    .enumerate()
                    .map(move |(ti, t)| (first + 1 + ti as u32, m, t))
            })
            .map(|(id, m, t)| {
                let [Some(a), Some(b), Some(c)] = t.map(|i| {
                    m.positions
                        .get(i as usize)
                        .copied()
                        .filter(|v| v.is_finite())
                }) else {
                    return Some([None, None]);
                };
                let tri = [a, b, c].map(|v| camera.view_coordinates(v));
                if near_eye(&tri, near, slopes) {
                    return None;
                }
                // A triangle clipped at the near plane is a quadrilateral: a fan of two.
                let grid: Vec<(DVec2, f64)> = clip_near(tri, near)
                    .iter()
                    .map(|v| (camera.view_to_pixel(*v) * n as f64, 1.0 / v.z))
                    .collect();
                let piece = |k: usize| {
                    (k + 1 < grid.len())
                        .then(|| setup(id, [grid[0], grid[k], grid[k + 1]], gw, gh))
                        .flatten()
                };
                Some([piece(1), piece(2)])
            })
            .collect::<Option<_>>()?;
        // Each band of rows depth-buffers only the setups that reach it.
        let bands = h.div_ceil(BAND_ROWS);
        let mut binned: Vec<Vec<&Setup>> = vec![Vec::new(); bands];
        for s in pieces.iter().flatten().flatten() {
            let rows = BAND_ROWS * n;
            for band in &mut binned[s.y.0 / rows..=(s.y.1 - 1) / rows] {
                band.push(s);
            }
        }
        let mut candidate = vec![0u32; gw * gh];
        candidate
            .par_chunks_mut(BAND_ROWS * n * gw)
            .zip(&binned)
            .enumerate()
            .for_each(|(b, (out, setups))| rasterise_band(setups, b * BAND_ROWS, out, w, n));
        Some(Self {
            candidate,
            mesh_first,
        })
    }

    /// The first hit of sample `i` along `ray` (the sample's camera ray): what
    /// `accel.intersect(ray)` returns.
    pub fn hit(&self, accel: &Accel, i: usize, ray: &Ray) -> Option<Hit> {
        let prim = self.candidate(i)?;
        accel
            .intersect_primitive(ray, prim)
            .or_else(|| accel.intersect(ray))
    }

    /// The triangle the depth buffer kept for sample `i`.
    fn candidate(&self, i: usize) -> Option<PrimRef> {
        let input = self.candidate.get(i)?.checked_sub(1)?;
        let mesh = self.mesh_first.partition_point(|&f| f <= input) - 1;
        Some(PrimRef::Triangle {
            mesh: mesh as u32,
            tri: input - self.mesh_first[mesh],
        })
    }
}

/// The near plane's depth: small against the scene and the camera's distance, so
/// that clipping there loses nothing a pixel shows (checked by [`near_eye`]).
fn near_distance(meshes: &[Mesh], camera: &Camera) -> f64 {
    let mut extent = camera.from.abs().max_element().max(1.0) as f64;
    for m in meshes {
        for p in &m.positions {
            if p.is_finite() {
                extent = extent.max(p.abs().max_element() as f64);
            }
        }
    }
    1e-5 * extent
}

/// Whether the triangle reaches into the part of the view frustum nearer than
/// `near` (within the sphere around the eye that holds it): such geometry would be
/// clipped away although a ray can see it.
fn near_eye(tri: &[DVec3; 3], near: f64, slopes: DVec2) -> bool {
    let radius = near * slopes.extend(1.0).length();
    closest_to_origin(tri).length_squared() <= radius * radius
}

/// The point of a triangle closest to the origin (Ericson, Real-Time Collision
/// Detection, 5.1.5: by the Voronoi region the origin falls in).
fn closest_to_origin([a, b, c]: &[DVec3; 3]) -> DVec3 {
    let (ab, ac, ap) = (*b - *a, *c - *a, -*a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = -*b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return *a + ab * (d1 / (d1 - d3));
    }
    let cp = -*c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return *a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return *b + (*c - *b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        // Degenerate (a segment or a point): the nearest vertex is close enough.
        return [*a, *b, *c]
            .into_iter()
            .min_by(|p, q| p.length_squared().total_cmp(&q.length_squared()))
            .unwrap_or(*a);
    }
    *a + ab * (vb / denom) + ac * (vc / denom)
}

/// The part of a triangle (view coordinates) at depth ≥ `near`: 0, 3 or 4
/// vertices in order (Sutherland–Hodgman against one plane).
fn clip_near(tri: [DVec3; 3], near: f64) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (tri[i], tri[(i + 1) % 3]);
        let (ina, inb) = (a.z >= near, b.z >= near);
        if ina {
            out.push(a);
        }
        if ina != inb {
            let t = (near - a.z) / (b.z - a.z);
            let mut p = a + (b - a) * t;
            p.z = near;
            out.push(p);
        }
    }
    out
}

/// Edge functions, depth plane and sample box of one screen triangle (grid
/// coordinates, 1/depth per vertex); `None` when it has no area or covers no
/// sample of the `gw × gh` grid.
fn setup(id: u32, v: [(DVec2, f64); 3], gw: usize, gh: usize) -> Option<Setup> {
    let p = v.map(|(p, _)| p);
    // Edge i runs from vertex i + 1 to vertex i + 2: E_i(q) = (b − a) × (q − a).
    let mut edge = [[0.0; 3]; 3];
    for (i, e) in edge.iter_mut().enumerate() {
        let (a, b) = (p[(i + 1) % 3], p[(i + 2) % 3]);
        let (ea, eb) = (-(b.y - a.y), b.x - a.x);
        *e = [ea, eb, -(ea * a.x + eb * a.y)];
    }
    let area = edge[0][0] * p[0].x + edge[0][1] * p[0].y + edge[0][2];
    if !(area.is_finite() && area != 0.0) {
        return None;
    }
    // Barycentric of vertex i is E_i / area: 1/depth is affine in the image.
    let mut inv_depth = [0.0; 3];
    for (i, e) in edge.iter().enumerate() {
        for k in 0..3 {
            inv_depth[k] += e[k] * v[i].1 / area;
        }
    }
    // Positive inside whatever the winding (materials are two-sided), widened.
    let sign = area.signum();
    for e in &mut edge {
        let len = e[0].hypot(e[1]);
        *e = [e[0] * sign, e[1] * sign, e[2] * sign + SLACK * len];
    }
    let lo = p[0].min(p[1]).min(p[2]) - DVec2::splat(SLACK + 0.5);
    let hi = p[0].max(p[1]).max(p[2]) + DVec2::splat(SLACK - 0.5);
    // Samples sit at (X + ½, Y + ½): X from ⌈lo.x⌉ to ⌊hi.x⌋.
    let span = |lo: f64, hi: f64, size: usize| {
        let a = lo.ceil().max(0.0);
        let b = hi.floor().min(size as f64 - 1.0);
        (a <= b).then(|| (a as usize, b as usize + 1))
    };
    Some(Setup {
        id,
        edge,
        inv_depth,
        x: span(lo.x, hi.x, gw)?,
        y: span(lo.y, hi.y, gh)?,
    })
}

/// Depth-buffers every setup over image rows `row0..` (as many as `out` holds) and
/// writes the kept ids in the sample layout of [`PrimaryVisibility`].
fn rasterise_band(setups: &[&Setup], row0: usize, out: &mut [u32], w: usize, n: usize) {
    let gw = w * n;
    let (g0, g1) = (row0 * n, row0 * n + out.len() / gw);
    let mut depth = vec![0.0f64; out.len()];
    let mut ids = vec![0u32; out.len()];
    for s in setups {
        let (y0, y1) = (s.y.0.max(g0), s.y.1.min(g1));
        for gy in y0..y1 {
            let qy = gy as f64 + 0.5;
            let row = (gy - g0) * gw;
            for gx in s.x.0..s.x.1 {
                let qx = gx as f64 + 0.5;
                let inside = s.edge.iter().all(|e| e[0] * qx + e[1] * qy + e[2] >= 0.0);
                if !inside {
                    continue;
                }
                let z = s.inv_depth[0] * qx + s.inv_depth[1] * qy + s.inv_depth[2];
                if z > depth[row + gx] {
                    depth[row + gx] = z;
                    ids[row + gx] = s.id;
                }
            }
        }
    }
    // Grid order → per-pixel sample order.
    let nn = n * n;
    for (i, id) in ids.iter().enumerate() {
        let (gy, gx) = (g0 + i / gw, i % gw);
        let (y, ky, x, kx) = (gy / n - row0, gy % n, gx / n, gx % n);
        out[y * w * nn + x * nn + ky * n + kx] = *id;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Vec2, Vec3};

    fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            name: "m".into(),
            positions,
            normals: vec![],
            uvs: vec![],
            triangles,
            material: 0,
            emission: Vec3::ZERO,
            bump: None,
            rect: None,
            object_id: 1,
        }
    }

    /// Every sample's hit equals the BVH's; returns how many samples there were
    /// and how many the fallback ray cast answered.
    fn check(meshes: &[Mesh], camera: &Camera, n: usize) -> (usize, usize) {
        let accel = Accel::build(meshes, &[]);
        let vis = PrimaryVisibility::rasterise(meshes, &[], camera, n).expect("rasterisable");
        let (w, h) = (camera.width as usize, camera.height as usize);
        let (mut hits, mut fallbacks) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                for k in 0..n * n {
                    let sub = Vec2::new((k % n) as f32 + 0.5, (k / n) as f32 + 0.5) / n as f32;
                    let ray = camera.generate_ray(Vec2::new(x as f32, y as f32) + sub);
                    let i = y * w * n * n + x * n * n + k;
                    let want = accel.intersect(&ray);
                    assert_eq!(vis.hit(&accel, i, &ray), want, "sample ({x}, {y}) #{k}");
                    hits += want.is_some() as usize;
                    let kept = vis
                        .candidate(i)
                        .and_then(|p| accel.intersect_primitive(&ray, p));
                    fallbacks += (want.is_some() && kept.is_none()) as usize;
                }
            }
        }
        assert!(
            hits > w * h * n * n / 10,
            "the view must show geometry ({hits} hits)"
        );
        (w * h * n * n, fallbacks)
    }

    /// A closed, finely tessellated sphere: many shared edges and vertices seen
    /// from every angle, both windings on screen, silhouettes.
    fn sphere_mesh(centre: Vec3, r: f32, rings: u32) -> Mesh {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        let segs = 2 * rings;
        for i in 0..=rings {
            let th = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segs {
                let ph = std::f32::consts::TAU * j as f32 / segs as f32;
                p.push(centre + r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
            }
        }
        for i in 0..rings {
            for j in 0..segs {
                let a = i * segs + j;
                let b = i * segs + (j + 1) % segs;
                t.push([a, a + segs, b]);
                t.push([b, a + segs, b + segs]);
            }
        }
        mesh(p, t)
    }

    #[test]
    fn rasterised_hits_equal_the_bvh_on_tessellated_spheres_from_many_views() {
        let meshes = [
            sphere_mesh(Vec3::ZERO, 1.0, 24),
            sphere_mesh(Vec3::new(0.6, 0.3, 0.9), 0.4, 9),
        ];
        let views = [
            Vec3::new(0.0, 0.0, 4.0),
            Vec3::new(3.0, 2.5, -1.0),
            Vec3::new(-0.2, -3.9, 0.3),
            Vec3::new(1.3, 0.1, 1.4),
        ];
        for (k, from) in views.into_iter().enumerate() {
            let cam = Camera::new(from, Vec3::ZERO, Vec3::Y, 50.0, 61 + 7 * k as u32, 47).unwrap();
            let (samples, fallbacks) = check(&meshes, &cam, 1 + k % 2);
            // Only samples within the slack of an edge need the ray cast.
            assert!(
                fallbacks * 50 < samples,
                "{fallbacks} fallbacks of {samples}"
            );
        }
    }

    #[test]
    fn rasterised_hits_equal_the_bvh_on_the_bundled_glossy_scenes() {
        // Real meshes: the teapot (gaps at the lid, thin spout) and the bunny on its
        // ground quad, at 2 × 2 samples per pixel.
        for name in ["glossy_teapot", "glossy_bunny"] {
            let path = format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
            let scene = crate::scene::load(std::path::Path::new(&path)).unwrap();
            let cam = scene.camera.with_resolution(80, 80).unwrap();
            let (samples, fallbacks) = check(&scene.meshes, &cam, 2);
            assert!(
                fallbacks * 50 < samples,
                "{name}: {fallbacks} fallbacks of {samples}"
            );
        }
    }

    #[test]
    fn a_ground_plane_behind_the_camera_is_clipped_not_lost() {
        // Two big triangles reaching far behind the eye, and a ball on them.
        let ground = mesh(
            vec![
                Vec3::new(-50.0, 0.0, -50.0),
                Vec3::new(50.0, 0.0, -50.0),
                Vec3::new(50.0, 0.0, 50.0),
                Vec3::new(-50.0, 0.0, 50.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let meshes = [ground, sphere_mesh(Vec3::new(0.0, 0.5, 0.0), 0.5, 8)];
        let from = Vec3::new(0.0, 1.0, 3.0);
        let cam = Camera::new(from, Vec3::new(0.0, 0.4, 0.0), Vec3::Y, 60.0, 64, 48).unwrap();
        check(&meshes, &cam, 2);
    }

    #[test]
    fn closest_point_of_a_triangle_to_the_origin_matches_dense_sampling() {
        let tris = [
            [
                DVec3::new(1.0, 0.2, 0.0),
                DVec3::new(0.0, 2.0, 1.0),
                DVec3::new(-1.0, 0.5, 3.0),
            ],
            [
                DVec3::new(-2.0, -1.0, 0.5),
                DVec3::new(2.0, -1.0, 0.5),
                DVec3::new(0.0, 2.0, 0.5),
            ],
            [
                DVec3::new(3.0, 3.0, 3.0),
                DVec3::new(4.0, 3.0, 3.0),
                DVec3::new(3.0, 5.0, 2.0),
            ],
        ];
        for tri in &tris {
            let got = closest_to_origin(tri).length();
            let mut best = f64::INFINITY;
            for i in 0..=400 {
                for j in 0..=400 - i {
                    let (u, v) = (i as f64 / 400.0, j as f64 / 400.0);
                    let p = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
                    best = best.min(p.length());
                }
            }
            assert!(got <= best + 1e-12 && got > best - 0.02, "{got} vs {best}");
        }
    }

    #[test]
    fn geometry_at_the_eye_and_spheres_fall_back_to_ray_casting() {
        let cam = Camera::new(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap();
        let through_eye = mesh(
            vec![
                Vec3::new(-1.0, -1.0, 3.0),
                Vec3::new(1.0, -1.0, 3.0),
                Vec3::new(0.0, 1.0, 3.0),
            ],
            vec![[0, 1, 2]],
        );
        assert!(PrimaryVisibility::rasterise(&[through_eye], &[], &cam, 1).is_none());
        let ball = Sphere {
            name: "s".into(),
            center: Vec3::ZERO,
            radius: 1.0,
            material: 0,
            emission: Vec3::ZERO,
            bump: None,
            object_id: 1,
        };
        let meshes = [sphere_mesh(Vec3::ZERO, 1.0, 4)];
        assert!(PrimaryVisibility::rasterise(&meshes, &[ball], &cam, 1).is_none());
        assert!(PrimaryVisibility::rasterise(&meshes, &[], &cam, 1).is_some());
    }
}
