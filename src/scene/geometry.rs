//! Shape builders shared by the scene parser and the OBJ loader: affine
//! transforms (points, vectors, normals), the two-triangle quad, Mitsuba's cube,
//! and the degenerate-triangle filter. Everything here produces WORLD-space data.

use crate::math::{cross, Vec2, Vec3};
use glam::{Affine3A, Mat3};

/// An invertible affine map with its normal matrix (inverse transpose of the
/// linear part) precomputed.
#[derive(Clone, Copy, Debug)]
pub(super) struct Xform {
    affine: Affine3A,
    normal: Mat3,
    /// Negative determinant: the map mirrors, so counter-clockwise windings (and
    /// cross products of mapped edges) turn clockwise and must be flipped back.
    mirrors: bool,
}

impl Xform {
    /// `None` when the linear part is singular (or not finite), e.g. a scale of 0.
    pub(super) fn new(affine: Affine3A) -> Option<Self> {
        let linear = Mat3::from(affine.matrix3);
        let det = linear.determinant();
        if !(det.is_finite() && det.abs() > 1e-12 && affine.translation.is_finite()) {
            return None;
        }
        Some(Self {
            affine,
            normal: linear.inverse().transpose(),
            mirrors: det < 0.0,
        })
    }

    pub(super) fn identity() -> Self {
        Self {
            affine: Affine3A::IDENTITY,
            normal: Mat3::IDENTITY,
            mirrors: false,
        }
    }

    pub(super) fn point(&self, p: Vec3) -> Vec3 {
        self.affine.transform_point3a(p)
    }

    pub(super) fn vector(&self, v: Vec3) -> Vec3 {
        self.affine.transform_vector3a(v)
    }

    /// Transforms a normal with the inverse transpose and renormalises it; `None`
    /// when the input is zero or not finite.
    pub(super) fn normal(&self, n: Vec3) -> Option<Vec3> {
        let m = (self.normal * n).normalize_or_zero();
        (m != Vec3::ZERO && m.is_finite()).then_some(m)
    }

    pub(super) fn mirrors(&self) -> bool {
        self.mirrors
    }
}

/// Why a triangle was dropped; the count goes to `SceneStats`.
pub(super) fn is_degenerate(positions: &[Vec3], t: [u32; 3]) -> bool {
    let [a, b, c] = t;
    if a == b || b == c || a == c {
        return true;
    }
    let (Some(&p0), Some(&p1), Some(&p2)) = (
        positions.get(a as usize),
        positions.get(b as usize),
        positions.get(c as usize),
    ) else {
        return true;
    };
    if !(p0.is_finite() && p1.is_finite() && p2.is_finite()) {
        return true;
    }
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    // Zero area, or collinear to within f32 precision (sin of the angle between the
    // edges below ~1e-7): such a triangle has no usable normal or barycentrics.
    let normal = cross(e1, e2);
    let twice_area = normal.length();
    let scale = e1.length_squared().max(e2.length_squared());
    // The unit normal is normal / |normal|: |normal|² must be a normal f32 (a tiny
    // triangle's underflows to 0 or a subnormal, and its normal to NaN).
    let normalisable = normal.length_squared() >= f32::MIN_POSITIVE;
    !(normalisable && twice_area > 0.0 && twice_area > 1e-7 * scale)
}

/// Splits `triangles` into kept and dropped (degenerate) ones. With `flip` the
/// winding of every kept triangle is reversed (used after a mirroring transform,
/// so that the geometric normal still points to the side it pointed to before).
pub(super) fn filter_triangles(
    positions: &[Vec3],
    triangles: impl IntoIterator<Item = [u32; 3]>,
    flip: bool,
) -> (Vec<[u32; 3]>, usize) {
    let mut kept = Vec::new();
    let mut dropped = 0;
    for t in triangles {
        if is_degenerate(positions, t) {
            dropped += 1;
        } else if flip {
            kept.push([t[0], t[2], t[1]]);
        } else {
            kept.push(t);
        }
    }
    (kept, dropped)
}

/// Geometry of a quad `corner + s·edge_u + t·edge_v`: four vertices with
/// (u, v) = (s, t) and two counter-clockwise triangles about `edge_u × edge_v`.
pub(super) struct QuadGeometry {
    pub positions: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
}

pub(super) fn quad(corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> QuadGeometry {
    QuadGeometry {
        positions: vec![
            corner,
            corner + edge_u,
            corner + edge_u + edge_v,
            corner + edge_v,
        ],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Maps Mitsuba's canonical `rectangle` ([-size/2, size/2] in the xy plane,
/// front side +z) through `xf` to (corner, edge_u, edge_v). When `xf` mirrors,
/// the edges are swapped so that `edge_u × edge_v` is still the transformed +z
/// normal, as Mitsuba (which maps the normal by the inverse transpose) has it.
pub(super) fn rectangle_edges(xf: &Xform, size: Vec2) -> (Vec3, Vec3, Vec3) {
    let h = 0.5 * size;
    let corner = xf.point(Vec3::new(-h.x, -h.y, 0.0));
    let eu = xf.vector(Vec3::new(size.x, 0.0, 0.0));
    let ev = xf.vector(Vec3::new(0.0, size.y, 0.0));
    if xf.mirrors() {
        (corner, ev, eu)
    } else {
        (corner, eu, ev)
    }
}

/// Mitsuba's `cube`: [-1, 1]³ mapped by `xf`, 6 faces × 4 vertices (flat faces,
/// per-face (u, v) in [0, 1]²), 12 triangles wound counter-clockwise seen from
/// outside.
pub(super) fn cube(xf: &Xform) -> QuadGeometry {
    // (normal, tangent u, tangent v) with u × v = normal, for each face.
    let faces = [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ];
    let mut g = QuadGeometry {
        positions: Vec::with_capacity(24),
        uvs: Vec::with_capacity(24),
        triangles: Vec::with_capacity(12),
    };
    for (n, u, v) in faces {
        let base = g.positions.len() as u32;
        let q = quad(n - u - v, 2.0 * u, 2.0 * v);
        g.positions.extend(q.positions.iter().map(|&p| xf.point(p)));
        g.uvs.extend(q.uvs);
        for t in q.triangles {
            let t = [base + t[0], base + t[1], base + t[2]];
            g.triangles
                .push(if xf.mirrors() { [t[0], t[2], t[1]] } else { t });
        }
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn cube_faces_point_outwards_even_when_mirrored() {
        for affine in [
            Affine3A::from_scale_rotation_translation(
                glam::Vec3::new(0.3, 0.6, 0.2),
                Quat::from_rotation_y(0.3),
                glam::Vec3::new(1.0, 2.0, 3.0),
            ),
            Affine3A::from_scale(glam::Vec3::new(-1.0, 1.0, 1.0)),
        ] {
            let xf = Xform::new(affine).unwrap();
            let g = cube(&xf);
            let centre = xf.point(Vec3::ZERO);
            assert_eq!(g.triangles.len(), 12);
            for t in &g.triangles {
                let [a, b, c] = t.map(|i| g.positions[i as usize]);
                let n = cross(b - a, c - a);
                assert!(n.dot((a + b + c) / 3.0 - centre) > 0.0);
            }
        }
    }

    #[test]
    fn degenerate_triangles_are_recognised() {
        let p = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(f32::NAN, 0.0, 0.0),
        ];
        assert!(!is_degenerate(&p, [0, 1, 2]));
        assert!(is_degenerate(&p, [0, 0, 2]), "repeated index");
        assert!(is_degenerate(&p, [0, 1, 3]), "collinear");
        assert!(is_degenerate(&p, [0, 1, 4]), "NaN");
        assert!(is_degenerate(&p, [0, 1, 9]), "out of range");
        let tiny = [Vec3::ZERO, Vec3::X * 1e-20, Vec3::Y * 1e-20];
        assert!(is_degenerate(&tiny, [0, 1, 2]), "normal underflows");
    }
}
