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

use super::locate::{Ctx, KeyPath};
use super::{Mesh, Scene, Sphere};
use crate::math::{cross, Vec3};
use glam::{Mat3, Quat, Vec4};
use serde::Deserialize;

/// Raw TOML of the block (serde reports unknown keys with their spans).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(super) struct AnimationRaw {
    #[serde(default)]
    frames: Option<u32>,
    #[serde(default)]
    objects: Vec<TrackRaw>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct TrackRaw {
    shape: String,
    #[serde(default)]
    keys: Vec<KeyRaw>,
    deform: Option<DeformRaw>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct KeyRaw {
    t: f32,
    #[serde(default)]
    translate: Option<[f32; 3]>,
    /// [axis_x, axis_y, axis_z, degrees]
    #[serde(default)]
    rotate: Option<[f32; 4]>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct DeformRaw {
    #[serde(rename = "type")]
    kind: DeformKind,
    /// Amount at t = 0 and t = 1.
    amount: [f32; 2],
}

/// A procedural deformation, about the bottom centre of the shape's rest box
/// (height H): `bend` shears x by amount·H·h² (h = height fraction), `twist` turns
/// about the vertical axis by amount·h radians, `squash` scales y by 1 − amount and
/// x, z by 1/√(1 − amount) (volume kept).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
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

pub(super) fn resolve(
    ctx: &Ctx,
    raw: &AnimationRaw,
    object_names: &[String],
) -> crate::Result<Animation> {
    let at = KeyPath::default().key("animation");
    let frames = raw.frames.unwrap_or(8);
    if frames == 0 {
        return Err(ctx.err(&at.key("frames"), "expected at least 1 frame"));
    }
    let mut tracks: Vec<Track> = Vec::new();
    for (i, t) in raw.objects.iter().enumerate() {
        let at = at.key("objects").index(i);
        let Some(pos) = object_names.iter().position(|n| *n == t.shape) else {
            let names: Vec<String> = object_names.iter().map(|n| format!("`{n}`")).collect();
            return Err(ctx.err(
                &at.key("shape"),
                format!(
                    "undefined shape `{}`; defined shapes: {}",
                    t.shape,
                    names.join(", ")
                ),
            ));
        };
        let object_id = pos as u32 + 1;
        if tracks.iter().any(|tr| tr.object_id == object_id) {
            return Err(ctx.err(
                &at.key("shape"),
                format!("shape `{}` is animated twice", t.shape),
            ));
        }
        let mut keys = Vec::with_capacity(t.keys.len());
        for (k, key) in t.keys.iter().enumerate() {
            keys.push(resolve_key(ctx, &at.key("keys").index(k), key)?);
        }
        if keys.windows(2).any(|w| w[1].t <= w[0].t) {
            return Err(ctx.err(&at.key("keys"), "expected keys in increasing t"));
        }
        let deform = match &t.deform {
            Some(d) => {
                let dat = at.key("deform").key("amount");
                if !d.amount.iter().all(|a| a.is_finite()) {
                    return Err(ctx.err(&dat, "expected two finite numbers"));
                }
                if d.kind == DeformKind::Squash
                    && d.amount.iter().any(|a| !(-1.0..0.95).contains(a))
                {
                    return Err(ctx.err(&dat, "a squash amount must lie in [-1, 0.95)"));
                }
                Some(Deform {
                    kind: d.kind,
                    amount: d.amount,
                })
            }
            None => None,
        };
        tracks.push(Track {
            object_id,
            keys,
            deform,
        });
    }
    Ok(Animation { frames, tracks })
}

fn resolve_key(ctx: &Ctx, at: &KeyPath, k: &KeyRaw) -> crate::Result<Key> {
    if !(k.t.is_finite() && (0.0..=1.0).contains(&k.t)) {
        return Err(ctx.err(
            &at.key("t"),
            format!("expected a time in [0, 1], got {}", k.t),
        ));
    }
    let translate = k.translate.unwrap_or([0.0; 3]);
    if !translate.iter().all(|x| x.is_finite()) {
        return Err(ctx.err(&at.key("translate"), "expected three finite numbers"));
    }
    let rotate = match k.rotate {
        None => Quat::IDENTITY,
        Some([x, y, z, deg]) => {
            let axis = Vec3::new(x, y, z);
            if !(axis.is_finite() && deg.is_finite()) || axis.length() < 1e-12 {
                return Err(ctx.err(
                    &at.key("rotate"),
                    "expected [axis_x, axis_y, axis_z, degrees] with a non-zero axis",
                ));
            }
            Quat::from_axis_angle(axis.normalize().into(), deg.to_radians())
        }
    };
    Ok(Key {
        t: k.t,
        translate: Vec3::from(translate),
        rotate,
    })
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
