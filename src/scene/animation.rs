//! The `[animation]` block: per-shape rigid keyframes (translate, rotate about the
//! shape's rest bounding-box centre) and procedural deformations (bend, twist,
//! squash) whose amount runs linearly over the sequence. Time t ∈ [0, 1]: frame f
//! of N is at t = f/(N − 1). Format: `scenes/README.md`.
//!
//! ```toml
//! [animation]
//! frames = 8
//! [[animation.objects]]
//! shape = "ball"
//! keys = [{ t = 0, translate = [0, 0, 0] }, { t = 1, translate = [1, 0, 0], rotate = [0, 1, 0, 90] }]
//! [[animation.objects]]
//! shape = "blob"
//! deform = { type = "bend", amount = [0, 0.6] }
//! ```

use super::params::{list, Params};
use super::{Mesh, Scene, Sphere, MAX_MAGNITUDE};
use crate::math::{cross, Vec3};
use glam::{Mat3, Quat, Vec4};

/// Most frames a block may ask for: each is two files (as `--frames`).
pub const MAX_FRAMES: u32 = 10_000;

/// A procedural deformation, about the bottom centre of the shape's rest box
/// (height H): `bend` shears x by amount·H·h² (h = height fraction), `twist` turns
/// about the vertical axis by amount·h radians, `squash` scales y by 1 − amount and
/// x, z by 1/√(1 − amount) (volume kept).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeformKind {
    Bend,
    Twist,
    Squash,
}

/// One rigid keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    pub t: f32,
    pub translate: Vec3,
    pub rotate: Quat,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deform {
    pub kind: DeformKind,
    pub amount: [f32; 2],
}

/// The animation of one scene shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub object_id: u32,
    /// Sorted by t; empty: no rigid motion.
    pub keys: Vec<Key>,
    pub deform: Option<Deform>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Default number of frames.
    pub frames: u32,
    pub tracks: Vec<Track>,
}

const DEFORMS: &[(&str, DeformKind)] = &[
    ("bend", DeformKind::Bend),
    ("twist", DeformKind::Twist),
    ("squash", DeformKind::Squash),
];

/// Reads the `[animation]` table `p` against the scene's shape names. Every key
/// goes through [`Params`], so each message names its exact key path and line.
pub(super) fn read(p: &Params, object_names: &[String]) -> crate::Result<Animation> {
    let frames = p.u32("frames")?.unwrap_or(8);
    let objects = p.tables("objects")?.unwrap_or_default();
    p.finish()?;
    if frames == 0 {
        return Err(p.err(Some("frames"), "expected at least 1 frame, got 0"));
    }
    if frames > MAX_FRAMES {
        return Err(p.err(
            Some("frames"),
            format!("expected at most {MAX_FRAMES} frames (two files each), got {frames}"),
        ));
    }
    let mut tracks: Vec<Track> = Vec::with_capacity(objects.len());
    for o in &objects {
        let track = read_track(o, object_names)?;
        if tracks.iter().any(|t| t.object_id == track.object_id) {
            let name = &object_names[track.object_id as usize - 1];
            return Err(o.err(Some("shape"), format!("shape `{name}` is animated twice")));
        }
        tracks.push(track);
    }
    Ok(Animation { frames, tracks })
}

/// One `[[animation.objects]]` entry.
fn read_track(o: &Params, object_names: &[String]) -> crate::Result<Track> {
    let shape = o.string("shape")?;
    let keys = o.tables("keys")?.unwrap_or_default();
    let deform = o.table("deform")?;
    o.finish()?;
    let shape = o.need("shape", shape)?;
    let Some(pos) = object_names.iter().position(|n| n == shape) else {
        let names: Vec<&str> = object_names.iter().map(String::as_str).collect();
        let defined = if names.is_empty() {
            "the scene names no shapes".to_string()
        } else {
            format!("defined shapes: {}", list(&names))
        };
        return Err(o.err(
            Some("shape"),
            format!("undefined shape `{shape}`; {defined}"),
        ));
    };
    let mut out: Vec<Key> = Vec::with_capacity(keys.len());
    for (i, k) in keys.iter().enumerate() {
        let key = read_key(k)?;
        if let Some(prev) = out.last() {
            if key.t <= prev.t {
                return Err(k.err(
                    Some("t"),
                    format!(
                        "expected keys in increasing t, got t = {} after t = {} of keys[{}]",
                        key.t,
                        prev.t,
                        i - 1
                    ),
                ));
            }
        }
        out.push(key);
    }
    let deform = deform.as_ref().map(read_deform).transpose()?;
    Ok(Track {
        object_id: pos as u32 + 1,
        keys: out,
        deform,
    })
}

/// One rigid keyframe `{ t, translate, rotate }`.
fn read_key(k: &Params) -> crate::Result<Key> {
    let t = k.f32("t")?;
    let translate = k.f32s::<3>("translate")?;
    let rotate = k.f32s::<4>("rotate")?;
    k.finish()?;
    let t = k.need("t", t)?;
    if !(0.0..=1.0).contains(&t) {
        return Err(k.err(Some("t"), format!("expected a time in [0, 1], got {t}")));
    }
    let translate = Vec3::from(translate.unwrap_or([0.0; 3]));
    if translate.abs().max_element() > MAX_MAGNITUDE {
        return Err(k.err(
            Some("translate"),
            format!(
                "translation [{:?}, {:?}, {:?}] lies beyond ±{MAX_MAGNITUDE:e}, the largest \
                 coordinate magnitude supported (scene::MAX_MAGNITUDE)",
                translate.x, translate.y, translate.z
            ),
        ));
    }
    let rotate = match rotate {
        None => Quat::IDENTITY,
        Some([x, y, z, deg]) => {
            let mut axis = Vec3::new(x, y, z);
            if axis == Vec3::ZERO {
                return Err(k.err(
                    Some("rotate"),
                    format!(
                        "expected [axis_x, axis_y, axis_z, degrees] with a non-zero axis, got \
                         an axis of zero length [{x}, {y}, {z}]"
                    ),
                ));
            }
            // An axis whose length over- or underflows f32 is scaled first; the
            // usual lengths are normalised as they are (the same bits as before).
            if !(1e-18..1e18).contains(&axis.length()) {
                axis /= axis.abs().max_element();
            }
            Quat::from_axis_angle(axis.normalize().into(), deg.to_radians())
        }
    };
    Ok(Key {
        t,
        translate,
        rotate,
    })
}

/// `deform = { type, amount }`.
fn read_deform(d: &Params) -> crate::Result<Deform> {
    let kind = d.kind(DEFORMS)?;
    let amount = d.f32s::<2>("amount")?;
    d.finish()?;
    let amount = d.need("amount", amount)?;
    if amount.iter().any(|a| a.abs() > MAX_MAGNITUDE) {
        return Err(d.err(
            Some("amount"),
            format!(
                "amount [{:?}, {:?}] lies beyond ±{MAX_MAGNITUDE:e}, the largest magnitude \
                 supported (scene::MAX_MAGNITUDE)",
                amount[0], amount[1]
            ),
        ));
    }
    if kind == DeformKind::Squash && amount.iter().any(|a| !(-1.0..0.95).contains(a)) {
        return Err(d.err(
            Some("amount"),
            format!(
                "a squash amount must lie in [-1, 0.95), got [{}, {}]",
                amount[0], amount[1]
            ),
        ));
    }
    Ok(Deform { kind, amount })
}

/// Time of frame `f` of `n`.
pub fn frame_time(f: u32, n: u32) -> f32 {
    if n <= 1 {
        0.0
    } else {
        f as f32 / (n - 1) as f32
    }
}

/// Spherical linear interpolation of unit quaternions along the shorter arc,
/// in plain f32 arithmetic. glam's `Quat::slerp` takes its sines from a
/// polynomial with fused multiply-adds where the build targets FMA
/// (`-C target-cpu=native`), so a pose would depend on the build.
fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let (a, mut b) = (Vec4::from(a), Vec4::from(b));
    let mut dot = a.dot(b);
    if dot < 0.0 {
        b = -b;
        dot = -dot;
    }
    if dot > 1.0 - f32::EPSILON {
        // Nearly equal: the linear blend, renormalised (no division by sin θ ≈ 0).
        return Quat::from_vec4(a + (b - a) * s).normalize();
    }
    let theta = dot.acos();
    let q = (a * ((1.0 - s) * theta).sin() + b * (s * theta).sin()) / theta.sin();
    Quat::from_vec4(q)
}

impl Track {
    /// Rotation and translation at time t (linear / slerp between keys, held
    /// outside them).
    pub fn pose(&self, t: f32) -> (Mat3, Vec3) {
        let (first, last) = match (self.keys.first(), self.keys.last()) {
            (Some(a), Some(b)) => (a, b),
            _ => return (Mat3::IDENTITY, Vec3::ZERO),
        };
        let key = if t <= first.t {
            *first
        } else if t >= last.t {
            *last
        } else {
            let i = self.keys.iter().rposition(|k| k.t <= t).unwrap_or(0);
            let (a, b) = (self.keys[i], self.keys[(i + 1).min(self.keys.len() - 1)]);
            let s = if b.t > a.t {
                (t - a.t) / (b.t - a.t)
            } else {
                0.0
            };
            Key {
                t,
                translate: a.translate.lerp(b.translate, s),
                rotate: slerp(a.rotate, b.rotate, s),
            }
        };
        (Mat3::from_quat(key.rotate), key.translate)
    }

    /// Deformation amount at time t.
    pub fn amount(&self, t: f32) -> Option<(DeformKind, f32)> {
        self.deform
            .map(|d| (d.kind, d.amount[0] + (d.amount[1] - d.amount[0]) * t))
    }
}

/// The rest bounding box of a shape's triangles and spheres (what poses pivot about).
pub fn rest_box(scene: &Scene, object_id: u32) -> Option<(Vec3, Vec3)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for m in scene.meshes.iter().filter(|m| m.object_id == object_id) {
        for t in &m.triangles {
            for &v in t {
                lo = lo.min(m.positions[v as usize]);
                hi = hi.max(m.positions[v as usize]);
            }
        }
    }
    for s in scene.spheres.iter().filter(|s| s.object_id == object_id) {
        lo = lo.min(s.center - Vec3::splat(s.radius));
        hi = hi.max(s.center + Vec3::splat(s.radius));
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// A deformation applied to one point, about the box's bottom centre.
pub fn deform_point(kind: DeformKind, amount: f32, (lo, hi): (Vec3, Vec3), p: Vec3) -> Vec3 {
    let base = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    let height = (hi.y - lo.y).max(1e-12);
    let q = p - base;
    let h = q.y / height;
    let out = match kind {
        DeformKind::Bend => Vec3::new(q.x + amount * height * h * h, q.y, q.z),
        DeformKind::Twist => {
            let (s, c) = (amount * h).sin_cos();
            Vec3::new(c * q.x + s * q.z, q.y, -s * q.x + c * q.z)
        }
        DeformKind::Squash => {
            let side = 1.0 / (1.0 - amount).sqrt();
            Vec3::new(q.x * side, q.y * (1.0 - amount), q.z * side)
        }
    };
    base + out
}

impl Animation {
    /// The scene at frame `f` of `n`: every animated shape deformed, then moved
    /// rigidly about its rest box centre. Deformed meshes get area-weighted
    /// normals again when they had normals.
    pub fn scene_at(&self, scene: &Scene, f: u32, n: u32) -> Scene {
        let t = frame_time(f, n);
        let mut out = scene.clone();
        for track in &self.tracks {
            let Some(bx) = rest_box(scene, track.object_id) else {
                continue;
            };
            let centre = 0.5 * (bx.0 + bx.1);
            let (rot, trans) = track.pose(t);
            let place = |p: Vec3| centre + trans + rot * (p - centre);
            for m in out
                .meshes
                .iter_mut()
                .filter(|m| m.object_id == track.object_id)
            {
                if let Some((kind, a)) = track.amount(t) {
                    for p in &mut m.positions {
                        *p = deform_point(kind, a, bx, *p);
                    }
                    if !m.normals.is_empty() {
                        m.normals = area_normals(m);
                    }
                }
                for p in &mut m.positions {
                    *p = place(*p);
                }
                for nrm in &mut m.normals {
                    *nrm = (rot * *nrm).normalize_or_zero();
                }
                if let Some(r) = &mut m.rect {
                    r.corner = place(r.corner);
                    r.edge_u = rot * r.edge_u;
                    r.edge_v = rot * r.edge_v;
                }
            }
            for s in out
                .spheres
                .iter_mut()
                .filter(|s| s.object_id == track.object_id)
            {
                move_sphere(s, &place);
            }
        }
        out
    }

    pub fn track(&self, object_id: u32) -> Option<&Track> {
        self.tracks.iter().find(|t| t.object_id == object_id)
    }
}

fn move_sphere(s: &mut Sphere, place: &dyn Fn(Vec3) -> Vec3) {
    s.center = place(s.center);
}

/// Area-weighted vertex normals of a mesh (zero for unused vertices).
pub fn area_normals(m: &Mesh) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; m.positions.len()];
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let f = cross(b - a, c - a);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `a` and `b` are the same rotation to within `tol` per component
    /// (q and −q are the same rotation).
    fn same(a: Quat, b: Quat, tol: f32) -> bool {
        let b = if a.dot(b) < 0.0 { -b } else { b };
        (Vec4::from(a) - Vec4::from(b)).abs().max_element() <= tol
    }

    /// A rotation by `deg` degrees about the unit `axis`.
    fn rot(axis: [f32; 3], deg: f32) -> Quat {
        Quat::from_axis_angle(glam::Vec3::from(axis).normalize(), deg.to_radians())
    }

    #[test]
    fn slerp_turns_at_a_constant_rate_along_the_shorter_arc() {
        let (a, b) = (rot([0.0, 1.0, 0.0], 10.0), rot([0.0, 1.0, 0.0], 130.0));
        for s in [0.0, 0.25, 0.5, 0.9, 1.0] {
            // A known answer: the angle moves linearly, 10° → 130°.
            let want = rot([0.0, 1.0, 0.0], 10.0 + 120.0 * s);
            let got = slerp(a, b, s);
            assert!(
                got.dot(want).abs() > 1.0 - 1e-6,
                "s = {s}: {got:?} against {want:?}"
            );
        }
        // −b is the same rotation: the shorter arc still runs 10° → 130°.
        let got = slerp(a, -b, 0.5);
        assert!(same(got, rot([0.0, 1.0, 0.0], 70.0), 1e-6), "{got:?}");
    }

    #[test]
    #[allow(clippy::disallowed_methods)] // glam's slerp is the independent reference here
    fn slerp_agrees_with_glams_across_axes_and_angles() {
        let axes = [[1.0, 0.0, 0.0], [0.3, -0.8, 0.5], [-0.2, 0.1, 0.97]];
        for (i, &p) in axes.iter().enumerate() {
            for &q in &axes[i..] {
                for (da, db) in [(0.0, 179.0), (-40.0, 75.0), (20.0, 20.0 + 1e-3)] {
                    let (a, b) = (rot(p, da), rot(q, db));
                    for s in [0.1, 0.5, 0.8] {
                        let (ours, glams) = (slerp(a, b, s), a.slerp(b, s));
                        assert!(
                            ours.dot(glams).abs() > 1.0 - 1e-6
                                && (ours.length() - 1.0).abs() < 1e-5,
                            "{p:?} {da}° → {q:?} {db}°, s = {s}: {ours:?} against {glams:?}"
                        );
                    }
                }
            }
        }
    }
}
