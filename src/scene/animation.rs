//! The `[animation]` block: per-shape rigid keyframes (translate, rotate about the
//! shape's rest bounding-box centre) and deformations: procedural ones (bend,
//! twist, squash) whose amount runs linearly over the sequence, or a numbered OBJ
//! sequence of the shape's topology (as the deformable shadow-fields paper animates
//! its models). Time t ∈ [0, 1]: frame f of N is at t = f/(N − 1). Format:
//! `scenes/README.md`.
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
//! [[animation.objects]]
//! shape = "cloth"                         # a type = "mesh" shape
//! obj_sequence = "models/cloth_###.obj"   # one `#` per digit, as Blender's output paths
//! frames = [0, 7]                         # first and last file number
//! ```
//!
//! An OBJ sequence is read whole while the scene loads, each file through the
//! scene's own OBJ loader and mapped by the shape's `transform`, so that a missing
//! or mismatched frame is an error before any work; it keeps positions (and the
//! file's normals, when the shape has normals and does not recompute them) of every
//! frame: 16 or 32 bytes per vertex and frame (`Vec3` is 16 bytes), 3.5 MiB for
//! 48 frames of a 4,800-vertex cloth without normals. Only the shadow-field preview
//! animates: `render` and a still preview show the shape's own mesh.

use super::geometry::Xform;
use super::obj::{self, Topology};
use super::params::{list, Params};
use super::{Mesh, Scene, Sphere, MAX_MAGNITUDE};
use crate::math::{cross, Vec3};
use glam::{Mat3, Quat, Vec4};
use std::path::PathBuf;

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
    /// Per-frame vertices from OBJ files (never together with `deform`).
    pub sequence: Option<ObjSequence>,
}

/// A numbered OBJ sequence of one mesh shape, spread over t ∈ [0, 1]: file
/// `first + s` at t = s/(M − 1) for M files, linear between neighbouring files.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjSequence {
    /// The pattern as written in the scene (`models/cloth_###.obj`).
    pub pattern: String,
    /// File number of `frames[0]`.
    pub first: u32,
    /// Per file, per scene mesh of the shape: its vertices that frame.
    pub frames: Vec<Vec<FrameMesh>>,
}

/// One scene mesh's vertices in one file of an [`ObjSequence`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrameMesh {
    /// Index into `Scene::meshes`.
    pub mesh: usize,
    /// World space: the shape's transform applied.
    pub positions: Vec<Vec3>,
    /// The file's normals in world space; empty: recomputed as `smooth_normals`
    /// does (or none, when the rest mesh is flat-shaded).
    pub normals: Vec<Vec3>,
}

/// What `[animation]` needs to know of a scene shape besides its name.
pub(super) struct ShapeSource {
    /// Its `type` (`"light"` for a `[[lights]]` entry), for messages.
    pub kind: &'static str,
    /// How a `type = "mesh"` shape's OBJ was read.
    pub obj: Option<ObjSource>,
}

pub(super) struct ObjSource {
    pub file: PathBuf,
    pub xf: Xform,
    pub smooth: bool,
    pub objects: Vec<ObjObject>,
}

/// One object of a shape's OBJ file and the scene mesh made of it (none when
/// none of its triangles was kept).
pub(super) struct ObjObject {
    pub name: String,
    pub topology: Topology,
    pub mesh: Option<usize>,
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

/// Reads the `[animation]` table `p` against the scene's shapes (names and, in
/// the same order, sources). Every key goes through [`Params`], so each message
/// names its exact key path and line.
pub(super) fn read(
    p: &Params,
    object_names: &[String],
    sources: &[ShapeSource],
) -> crate::Result<Animation> {
    let frames = p.u32("frames")?;
    let objects = p.tables("objects")?.unwrap_or_default();
    p.finish()?;
    let mut tracks: Vec<Track> = Vec::with_capacity(objects.len());
    for o in &objects {
        let track = read_track(o, object_names, sources)?;
        if tracks.iter().any(|t| t.object_id == track.object_id) {
            let name = &object_names[track.object_id as usize - 1];
            return Err(o.err(Some("shape"), format!("shape `{name}` is animated twice")));
        }
        tracks.push(track);
    }
    // Without a count, the longest OBJ sequence shows each of its files once.
    let longest = tracks
        .iter()
        .filter_map(|t| t.sequence.as_ref())
        .map(|s| s.frames.len() as u32)
        .max();
    let frames = frames.or(longest).unwrap_or(8);
    if frames == 0 {
        return Err(p.err(Some("frames"), "expected at least 1 frame, got 0"));
    }
    if frames > MAX_FRAMES {
        return Err(p.err(
            Some("frames"),
            format!("expected at most {MAX_FRAMES} frames (two files each), got {frames}"),
        ));
    }
    Ok(Animation { frames, tracks })
}

/// One `[[animation.objects]]` entry.
fn read_track(
    o: &Params,
    object_names: &[String],
    sources: &[ShapeSource],
) -> crate::Result<Track> {
    let shape = o.string("shape")?;
    let keys = o.tables("keys")?.unwrap_or_default();
    let deform = o.table("deform")?;
    let pattern = o.string("obj_sequence")?;
    let range = o.u32_pair("frames")?;
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
    let sequence = match (pattern, range) {
        (None, None) => None,
        (None, Some(_)) => {
            return Err(o.err(
                Some("frames"),
                "`frames = [first, last]` numbers the files of an `obj_sequence`, which is \
                 missing (the frame count is `[animation] frames`)",
            ))
        }
        (Some(_), None) => {
            return Err(o.err(
                Some("obj_sequence"),
                "an `obj_sequence` needs `frames = [first, last]`, the numbers of its first \
                 and last file",
            ))
        }
        (Some(_), Some(_)) if deform.is_some() => {
            return Err(o.err(
                Some("obj_sequence"),
                "give either `deform` or `obj_sequence`, not both",
            ))
        }
        (Some(pattern), Some(range)) => {
            Some(read_sequence(o, shape, &sources[pos], pattern, range)?)
        }
    };
    Ok(Track {
        object_id: pos as u32 + 1,
        keys: out,
        deform,
        sequence,
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

/// The one run of `#` in an `obj_sequence` pattern: (byte offset, width).
fn placeholder(pattern: &str) -> Result<(usize, usize), String> {
    let bytes = pattern.as_bytes();
    let starts: Vec<usize> = (0..bytes.len())
        .filter(|&i| bytes[i] == b'#' && (i == 0 || bytes[i - 1] != b'#'))
        .collect();
    match starts[..] {
        [start] => {
            let width = bytes[start..].iter().take_while(|&&b| b == b'#').count();
            Ok((start, width))
        }
        [] => Err(format!(
            "expected a frame-number placeholder in \"{pattern}\": a run of `#`, one per digit \
             (\"cloth_###.obj\" reads cloth_000.obj, cloth_001.obj, …)"
        )),
        _ => Err(format!(
            "expected one run of `#` (the frame number) in \"{pattern}\", got {}",
            starts.len()
        )),
    }
}

/// File name of frame `n`: the placeholder replaced by `n`, zero-padded to its
/// width (longer numbers in full, as Blender's `####`).
fn frame_name(pattern: &str, (start, width): (usize, usize), n: u32) -> String {
    format!(
        "{}{n:0width$}{}",
        &pattern[..start],
        &pattern[start + width..]
    )
}

/// Loads every file of `obj_sequence` for shape `shape` and checks each against
/// the topology of the shape's own mesh.
fn read_sequence(
    o: &Params,
    shape: &str,
    source: &ShapeSource,
    pattern: &str,
    [first, last]: [u32; 2],
) -> crate::Result<ObjSequence> {
    let key = Some("obj_sequence");
    let Some(src) = &source.obj else {
        let what = match source.kind {
            "light" => "a light".to_string(),
            kind => format!("of type = \"{kind}\""),
        };
        return Err(o.err(
            key,
            format!(
                "shape `{shape}` is {what}; an `obj_sequence` deforms a shape of type = \"mesh\""
            ),
        ));
    };
    let slot = placeholder(pattern).map_err(|m| o.err(key, m))?;
    if first > last {
        return Err(o.err(
            Some("frames"),
            format!(
                "empty frame range [{first}, {last}]: expected [first, last] with first ≤ last"
            ),
        ));
    }
    let count = u64::from(last - first) + 1;
    if count > u64::from(MAX_FRAMES) {
        return Err(o.err(
            Some("frames"),
            format!("expected at most {MAX_FRAMES} files, got {count} ([{first}, {last}])"),
        ));
    }
    let vertices: u64 = src
        .objects
        .iter()
        .filter(|x| x.mesh.is_some())
        .map(|x| x.topology.vertices as u64)
        .sum();
    let per_vertex = std::mem::size_of::<Vec3>() as u64 * if src.smooth { 1 } else { 2 };
    let what = format!("keeping the {count} frames of \"{pattern}\"");
    let need = count * vertices * per_vertex;
    if let Some(m) = crate::memory::exceeds(need, crate::memory::limit(), &what) {
        return Err(o.err(key, format!("{m}; use fewer frames or a coarser mesh")));
    }
    let at = o.path("obj_sequence");
    let rest = src.file.display();
    let mut frames = Vec::with_capacity(count as usize);
    for n in first..=last {
        let name = frame_name(pattern, slot, n);
        let file = o.ctx.asset(&at, &name).map_err(|e| match e {
            crate::Error::Scene {
                path,
                location,
                message,
            } => crate::Error::Scene {
                path,
                location,
                message: format!("frame {n} of [{first}, {last}]: {message}"),
            },
            other => other,
        })?;
        let objects = obj::load_frame(&file, &src.xf).map_err(|e| o.ctx.in_scene(&at, e))?;
        let bad = |what: String| {
            o.err(
                key,
                format!(
                    "{} (frame {n}) {what}, expected the topology of the shape's mesh {rest}",
                    file.display()
                ),
            )
        };
        if objects.len() != src.objects.len() {
            return Err(bad(format!(
                "has {} OBJ objects where {rest} has {}",
                objects.len(),
                src.objects.len()
            )));
        }
        let mut meshes = Vec::new();
        for (got, want) in objects.into_iter().zip(&src.objects) {
            let (g, w) = (got.topology, want.topology);
            let object = &want.name;
            if g.vertices != w.vertices {
                return Err(bad(format!(
                    "has {} vertices in object `{object}` where {rest} has {}",
                    g.vertices, w.vertices
                )));
            }
            if g.triangles != w.triangles {
                return Err(bad(format!(
                    "has {} triangles in object `{object}` where {rest} has {}",
                    g.triangles, w.triangles
                )));
            }
            if g.index_hash != w.index_hash {
                return Err(bad(format!(
                    "has other triangle indices in object `{object}` (same vertex and \
                     triangle counts)"
                )));
            }
            let out = got
                .positions
                .iter()
                .position(|q| !q.abs().cmple(Vec3::splat(MAX_MAGNITUDE)).all());
            if let Some(i) = out {
                let q = got.positions[i];
                return Err(o.err(
                    key,
                    format!(
                        "{} (frame {n}): vertex {} of object `{object}`, after the shape's \
                         transform, is [{:?}, {:?}, {:?}]; expected finite coordinates within \
                         ±{MAX_MAGNITUDE:e} (scene::MAX_MAGNITUDE)",
                        file.display(),
                        i + 1,
                        q.x,
                        q.y,
                        q.z
                    ),
                ));
            }
            if let Some(mesh) = want.mesh {
                meshes.push(FrameMesh {
                    mesh,
                    positions: got.positions,
                    normals: if src.smooth { Vec::new() } else { got.normals },
                });
            }
        }
        frames.push(meshes);
    }
    Ok(ObjSequence {
        pattern: pattern.to_string(),
        first,
        frames,
    })
}

impl ObjSequence {
    /// The files (indices into `frames`) that frame `f` of `n` lies between and the
    /// weight of the second, in integers so that frame f of n = M files is file f
    /// exactly.
    pub fn at(&self, f: u32, n: u32) -> (usize, usize, f32) {
        let last = self.frames.len().saturating_sub(1) as u64;
        if n <= 1 || last == 0 {
            return (0, 0, 0.0);
        }
        let den = u64::from(n - 1);
        let num = u64::from(f.min(n - 1)) * last;
        let (j, rem) = ((num / den) as usize, num % den);
        if rem == 0 {
            (j, j, 0.0)
        } else {
            (j, j + 1, rem as f32 / den as f32)
        }
    }

    /// Sets the shape's meshes in `out` to frame `f` of `n`; normals follow the
    /// file where it has them, else are recomputed as `smooth_normals` does (a
    /// flat-shaded rest mesh stays flat).
    fn apply(&self, out: &mut Scene, f: u32, n: u32) {
        let (a, b, w) = self.at(f, n);
        for (fa, fb) in self.frames[a].iter().zip(&self.frames[b]) {
            let m = &mut out.meshes[fa.mesh];
            m.positions = if w == 0.0 {
                fa.positions.clone()
            } else {
                let lerp = |(p, q): (&Vec3, &Vec3)| *p + (*q - *p) * w;
                fa.positions.iter().zip(&fb.positions).map(lerp).collect()
            };
            if m.normals.is_empty() {
                continue;
            }
            m.normals = if fa.normals.is_empty() || fb.normals.is_empty() {
                obj::smooth_normals(&m.positions, &m.triangles)
            } else if w == 0.0 {
                fa.normals.clone()
            } else {
                let blend = |(p, q): (&Vec3, &Vec3)| {
                    let v = (*p + (*q - *p) * w).normalize_or_zero();
                    if v == Vec3::ZERO {
                        *p
                    } else {
                        v
                    }
                };
                fa.normals.iter().zip(&fb.normals).map(blend).collect()
            };
        }
    }
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

    /// Whether the shape changes shape, not only pose: what it occludes must be
    /// rebuilt each frame.
    pub fn deforms(&self) -> bool {
        self.deform.is_some() || self.sequence.is_some()
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
    /// The scene at frame `f` of `n`: every animated shape deformed (or set to its
    /// OBJ sequence's vertices), then moved rigidly about its rest box centre. Deformed meshes get area-weighted
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
            if let Some(seq) = &track.sequence {
                seq.apply(&mut out, f, n);
            }
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
    fn a_pattern_has_one_run_of_hashes_padded_like_blenders() {
        let slot = placeholder("models/cloth_###.obj").unwrap();
        assert_eq!(slot, (13, 3));
        assert_eq!(
            frame_name("models/cloth_###.obj", slot, 7),
            "models/cloth_007.obj"
        );
        assert_eq!(
            frame_name("models/cloth_###.obj", slot, 1234),
            "models/cloth_1234.obj"
        );
        assert_eq!(
            frame_name("#.obj", placeholder("#.obj").unwrap(), 5),
            "5.obj"
        );
        assert!(placeholder("cloth.obj")
            .unwrap_err()
            .contains("placeholder"));
        assert!(placeholder("c_##_#.obj").unwrap_err().contains("got 2"));
    }

    #[test]
    fn sequence_frames_spread_over_the_animation() {
        let seq = |files: usize| ObjSequence {
            pattern: String::new(),
            first: 0,
            frames: vec![Vec::new(); files],
        };
        // As many frames as files: frame k is file k, exactly.
        for k in 0..48 {
            assert_eq!(seq(48).at(k, 48), (k as usize, k as usize, 0.0));
        }
        // Twice as many frames (less one): every other frame halfway.
        assert_eq!(seq(4).at(3, 7), (1, 2, 0.5));
        assert_eq!(seq(4).at(6, 7), (3, 3, 0.0));
        // Fewer frames than files skip files; one file or one frame holds file 0.
        assert_eq!(seq(5).at(1, 3), (2, 2, 0.0));
        assert_eq!(seq(1).at(3, 8), (0, 0, 0.0));
        assert_eq!(seq(6).at(0, 1), (0, 0, 0.0));
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
