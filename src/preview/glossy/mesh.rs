//! The adaptive mesh (Sec. 4.3): every scene triangle is the root of a 1-to-4
//! midpoint subdivision tree. Neighbouring leaves differ by at most one level (a
//! split first splits coarser neighbours), so an edge holds at most one T-vertex;
//! [`AdaptiveMesh::resolve`] fans those away at the end. Vertices sit on the
//! original flat triangles, their normals interpolated as the path tracer does.

use crate::math::{cross, Vec2, Vec3};
use crate::scene::Mesh;
use std::collections::HashMap;

/// A transfer sample point on the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    pub position: Vec3,
    pub normal: Vec3,
    pub geometric_normal: Vec3,
    pub material: u32,
}

#[derive(Clone, Debug)]
struct Face {
    v: [u32; 3],
    /// Corners' barycentrics (b0, b1, b2) in the original triangle.
    bary: [Vec3; 3],
    mesh: u32,
    tri: u32,
    level: u8,
    /// The level the face's ancestor had when the adaptive refinement began
    /// ([`AdaptiveMesh::start_refinement`]): its depth limit counts from there.
    base: u8,
    /// First of four children, or `u32::MAX` for a leaf.
    children: u32,
}

/// A leaf after T-vertex resolution: triangles over global vertices, with their
/// corners in the leaf's own (u, v) parameters.
#[derive(Clone, Debug, Default)]
struct Resolved {
    tris: Vec<[u32; 3]>,
    params: Vec<[Vec2; 3]>,
}

pub struct AdaptiveMesh {
    pub vertices: Vec<Vertex>,
    faces: Vec<Face>,
    /// Root face of (mesh, triangle).
    roots: Vec<Vec<u32>>,
    /// World area of each root.
    root_area: Vec<Vec<f32>>,
    midpoints: HashMap<(u32, u32), u32>,
    /// The edge a midpoint vertex splits.
    parent_edge: HashMap<u32, (u32, u32)>,
    /// Leaves having this exact edge.
    edge_leaves: HashMap<(u32, u32), Vec<u32>>,
    /// Every split, in order: replaying it rebuilds the mesh (the cache stores it).
    pub split_log: Vec<u32>,
    resolved: Vec<Resolved>,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

fn corner_edges(v: [u32; 3]) -> [(u32, u32); 3] {
    [key(v[0], v[1]), key(v[1], v[2]), key(v[2], v[0])]
}

impl AdaptiveMesh {
    /// The unsubdivided scene meshes. Vertices are shared between triangles that
    /// share an index and a shading normal (flat-shaded creases get one each).
    pub fn new(meshes: &[Mesh]) -> Self {
        let mut m = Self {
            vertices: Vec::new(),
            faces: Vec::new(),
            roots: Vec::new(),
            root_area: Vec::new(),
            midpoints: HashMap::new(),
            parent_edge: HashMap::new(),
            edge_leaves: HashMap::new(),
            split_log: Vec::new(),
            resolved: Vec::new(),
        };
        for (mi, mesh) in meshes.iter().enumerate() {
            let mut ids: HashMap<(u32, [i32; 3]), u32> = HashMap::new();
            let mut roots = Vec::with_capacity(mesh.triangles.len());
            let mut areas = Vec::with_capacity(mesh.triangles.len());
            for (ti, t) in mesh.triangles.iter().enumerate() {
                let p = t.map(|i| mesh.positions[i as usize]);
                let normal = cross(p[1] - p[0], p[2] - p[0]);
                let n_geo = normal.normalize_or(Vec3::Y);
                let mut v = [0u32; 3];
                for c in 0..3 {
                    let n = if mesh.normals.is_empty() {
                        n_geo
                    } else {
                        mesh.normals[t[c] as usize]
                    };
                    let q = (n * 1000.0).round().as_ivec3().to_array();
                    v[c] = *ids.entry((t[c], q)).or_insert_with(|| {
                        m.vertices.push(Vertex {
                            position: p[c],
                            normal: n,
                            geometric_normal: n_geo,
                            material: mesh.material,
                        });
                        (m.vertices.len() - 1) as u32
                    });
                }
                roots.push(m.faces.len() as u32);
                areas.push(0.5 * normal.length());
                m.add_leaf(Face {
                    v,
                    bary: [Vec3::X, Vec3::Y, Vec3::Z],
                    mesh: mi as u32,
                    tri: ti as u32,
                    level: 0,
                    base: 0,
                    children: u32::MAX,
                });
            }
            m.roots.push(roots);
            m.root_area.push(areas);
        }
        m
    }

    fn add_leaf(&mut self, f: Face) {
        let id = self.faces.len() as u32;
        for e in corner_edges(f.v) {
            self.edge_leaves.entry(e).or_default().push(id);
        }
        self.faces.push(f);
    }

    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    pub fn is_leaf(&self, f: u32) -> bool {
        self.faces[f as usize].children == u32::MAX
    }

    pub fn face_vertices(&self, f: u32) -> [u32; 3] {
        self.faces[f as usize].v
    }

    pub fn face_level(&self, f: u32) -> u8 {
        self.faces[f as usize].level
    }

    /// Marks the current leaves as where the adaptive refinement starts: a long
    /// floor triangle tessellated four levels deep before it must still be free to
    /// split where a shadow falls on it.
    pub fn start_refinement(&mut self) {
        for f in 0..self.faces.len() {
            if self.is_leaf(f as u32) {
                self.faces[f].base = self.faces[f].level;
            }
        }
    }

    /// 1-to-4 splits between the face and the leaf it descends from at
    /// [`start_refinement`](Self::start_refinement).
    pub fn refinement_depth(&self, f: u32) -> u8 {
        let face = &self.faces[f as usize];
        face.level - face.base
    }

    /// World area of a face.
    pub fn face_area(&self, f: u32) -> f32 {
        let face = &self.faces[f as usize];
        self.root_area[face.mesh as usize][face.tri as usize] / 4f32.powi(face.level as i32)
    }

    /// Longest world edge of a face.
    pub fn face_longest_edge(&self, f: u32) -> f32 {
        let p = self.faces[f as usize]
            .v
            .map(|v| self.vertices[v as usize].position);
        (p[0] - p[1])
            .length()
            .max((p[1] - p[2]).length())
            .max((p[2] - p[0]).length())
    }

    /// The leaf faces.
    pub fn leaves(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.faces.len() as u32).filter(|&f| self.is_leaf(f))
    }

    /// The coarser leaf across each edge of leaf `f` (level one less), if any.
    fn coarser_neighbours(&self, f: u32) -> Vec<u32> {
        let face = &self.faces[f as usize];
        let mut out = Vec::new();
        for (a, b) in corner_edges(face.v) {
            if self.edge_leaves.get(&(a, b)).is_some_and(|l| l.len() > 1) {
                continue;
            }
            for (m, other) in [(a, b), (b, a)] {
                if let Some(&(p, q)) = self.parent_edge.get(&m) {
                    if other == p || other == q {
                        if let Some(leaves) = self.edge_leaves.get(&key(p, q)) {
                            out.extend(leaves.iter().copied().filter(|&g| g != f));
                        }
                    }
                }
            }
        }
        out
    }

    /// Splits leaf `f` 1-to-4, splitting coarser neighbours first so that levels
    /// differ by at most one. Returns the vertices created. `interp` gives a new
    /// vertex from the original mesh and the barycentrics there.
    pub fn split(&mut self, f: u32, interp: &dyn Fn(u32, u32, Vec3) -> Vertex) -> Vec<u32> {
        let mut created = Vec::new();
        if !self.is_leaf(f) {
            return created;
        }
        for g in self.coarser_neighbours(f) {
            if self.is_leaf(g) {
                created.extend(self.split(g, interp));
            }
        }
        self.split_log.push(f);
        let face = self.faces[f as usize].clone();
        let [a, b, c] = face.v;
        let [ba, bb, bc] = face.bary;
        let mut mid = |x: u32, y: u32, bx: Vec3, by: Vec3, created: &mut Vec<u32>| -> u32 {
            if let Some(&m) = self.midpoints.get(&key(x, y)) {
                return m;
            }
            let v = interp(face.mesh, face.tri, 0.5 * (bx + by));
            self.vertices.push(v);
            let m = (self.vertices.len() - 1) as u32;
            self.midpoints.insert(key(x, y), m);
            self.parent_edge.insert(m, key(x, y));
            created.push(m);
            m
        };
        let ab = mid(a, b, ba, bb, &mut created);
        let bcm = mid(b, c, bb, bc, &mut created);
        let ca = mid(c, a, bc, ba, &mut created);
        let (mab, mbc, mca) = (0.5 * (ba + bb), 0.5 * (bb + bc), 0.5 * (bc + ba));
        for e in corner_edges(face.v) {
            if let Some(l) = self.edge_leaves.get_mut(&e) {
                l.retain(|&x| x != f);
                if l.is_empty() {
                    self.edge_leaves.remove(&e);
                }
            }
        }
        self.faces[f as usize].children = self.faces.len() as u32;
        let children = [
            ([a, ab, ca], [ba, mab, mca]),
            ([ab, b, bcm], [mab, bb, mbc]),
            ([ca, bcm, c], [mca, mbc, bc]),
            ([ab, bcm, ca], [mab, mbc, mca]),
        ];
        for (v, bary) in children {
            self.add_leaf(Face {
                v,
                bary,
                mesh: face.mesh,
                tri: face.tri,
                level: face.level + 1,
                base: face.base,
                children: u32::MAX,
            });
        }
        created
    }

    /// Largest level difference between leaves sharing (part of) an edge.
    pub fn max_neighbour_level_difference(&self) -> u32 {
        let mut worst = 0;
        for f in self.leaves() {
            for (a, b) in corner_edges(self.faces[f as usize].v) {
                // A finer neighbour two levels down would put a midpoint of a
                // midpoint on this edge.
                if let Some(&m) = self.midpoints.get(&(a, b)) {
                    let deeper = [key(a, m), key(m, b)]
                        .iter()
                        .any(|e| self.midpoints.contains_key(e));
                    worst = worst.max(if deeper { 2 } else { 1 });
                }
            }
        }
        worst
    }

    /// Resolves T-vertices: a leaf with hanging midpoints is fanned from the first of
    /// them (or split 1-to-4 when all three edges carry one).
    pub fn resolve(&mut self) {
        let mut resolved = vec![Resolved::default(); self.faces.len()];
        let corners = [Vec2::ZERO, Vec2::X, Vec2::Y];
        for f in self.leaves().collect::<Vec<_>>() {
            let v = self.faces[f as usize].v;
            // Polygon: corner, then the hanging midpoint of the edge to the next.
            let mut poly: Vec<(u32, Vec2, bool)> = Vec::new();
            for i in 0..3 {
                let j = (i + 1) % 3;
                poly.push((v[i], corners[i], false));
                if let Some(&m) = self.midpoints.get(&key(v[i], v[j])) {
                    poly.push((m, 0.5 * (corners[i] + corners[j]), true));
                }
            }
            let r = &mut resolved[f as usize];
            let hanging = poly.iter().filter(|p| p.2).count();
            if hanging == 3 {
                let (p, m) = (|i: usize| poly[i], [1, 3, 5]);
                for tri in [
                    [0, m[0], m[2]],
                    [m[0], 2, m[1]],
                    [m[2], m[1], 4],
                    [m[0], m[1], m[2]],
                ] {
                    let t = tri.map(p);
                    r.tris.push(t.map(|x| x.0));
                    r.params.push(t.map(|x| x.1));
                }
            } else if hanging > 0 {
                let apex = poly.iter().position(|p| p.2).unwrap_or(0);
                let n = poly.len();
                for k in 1..n - 1 {
                    let t = [poly[apex], poly[(apex + k) % n], poly[(apex + k + 1) % n]];
                    r.tris.push(t.map(|x| x.0));
                    r.params.push(t.map(|x| x.1));
                }
            } else {
                r.tris.push(v);
                r.params.push(corners);
            }
        }
        self.resolved = resolved;
    }

    /// The watertight triangles after [`resolve`](Self::resolve).
    pub fn resolved_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.resolved.iter().flat_map(|r| r.tris.iter().copied())
    }

    /// The resolved triangle and weights at barycentrics (b1, b2) of original
    /// triangle `tri` of mesh `mesh`.
    pub fn locate(&self, mesh: u32, tri: u32, b: Vec2) -> Option<([u32; 3], [f32; 3])> {
        let mut f = *self.roots.get(mesh as usize)?.get(tri as usize)?;
        let (mut u, mut v) = (b.x, b.y);
        while !self.is_leaf(f) {
            let first = self.faces[f as usize].children;
            let (child, nu, nv) = if u >= 0.5 {
                (1, 2.0 * u - 1.0, 2.0 * v)
            } else if v >= 0.5 {
                (2, 2.0 * u, 2.0 * v - 1.0)
            } else if u + v < 0.5 {
                (0, 2.0 * u, 2.0 * v)
            } else {
                // Centre child (m_ab, m_bc, m_ca).
                (3, 2.0 * (u + v) - 1.0, 1.0 - 2.0 * u)
            };
            f = first + child;
            (u, v) = (nu, nv);
        }
        let r = self.resolved.get(f as usize)?;
        let p = Vec2::new(u, v);
        let mut best = None;
        let mut best_min = f32::NEG_INFINITY;
        for (t, q) in r.tris.iter().zip(&r.params) {
            let w = planar_barycentrics(q, p);
            let m = w[0].min(w[1]).min(w[2]);
            if m > best_min {
                best_min = m;
                best = Some((*t, w.map(|x| x.max(0.0))));
            }
        }
        best.map(|(t, w)| {
            let s = (w[0] + w[1] + w[2]).max(1e-12);
            (t, w.map(|x| x / s))
        })
    }
}

fn planar_barycentrics(q: &[Vec2; 3], p: Vec2) -> [f32; 3] {
    let d = (q[1] - q[0]).perp_dot(q[2] - q[0]);
    if d == 0.0 {
        return [1.0 / 3.0; 3];
    }
    let w1 = (p - q[0]).perp_dot(q[2] - q[0]) / d;
    let w2 = (q[1] - q[0]).perp_dot(p - q[0]) / d;
    [1.0 - w1 - w2, w1, w2]
}
