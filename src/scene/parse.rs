//! Scene file (TOML) → [`Scene`]. The format is documented key by key in
//! `scenes/README.md`.
//!
//! Two passes: serde turns the text into the `*Raw` structs below (so unknown keys,
//! unknown `type` names and wrong value types are reported by serde, with the
//! valid choices), then `Builder` checks values and references and produces the
//! world-space scene. Every error is one `Error::Scene` whose location names the
//! key path and its line/column (see `locate`).

use super::geometry::{self, Xform};
use super::locate::{root, Ctx, KeyPath};
use super::{bump::Sinusoid, SceneStats, Sphere};
use super::{obj, Bump, Camera, Environment, Integrator, Mesh, Rect, RenderSettings, Scene};
use crate::brdf::Material;
use crate::math::{Vec2, Vec3};
use glam::{Affine3A, Mat3, Quat};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

pub(super) fn load_scene(path: &Path) -> crate::Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    scene_from_str(&text, path)
}

pub(super) fn scene_from_str(text: &str, path: &Path) -> crate::Result<Scene> {
    let ctx = Ctx::new(text, path);
    let raw: FileRaw = toml::from_str(text).map_err(|e| ctx.toml_err(&e))?;
    Builder::new(&ctx).build(raw)
}

// ---------------------------------------------------------------------------
// Raw (serde) types: the file format, one struct per table.
// ---------------------------------------------------------------------------

type V3 = [f32; 3];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileRaw {
    camera: CameraRaw,
    #[serde(default)]
    render: RenderRaw,
    #[serde(default)]
    materials: BTreeMap<String, MaterialRaw>,
    #[serde(default)]
    bumps: BTreeMap<String, BumpRaw>,
    #[serde(default)]
    shapes: Vec<ShapeRaw>,
    #[serde(default)]
    lights: Vec<LightRaw>,
    environment: Option<EnvironmentRaw>,
    animation: Option<super::animation::AnimationRaw>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraRaw {
    from: V3,
    to: V3,
    #[serde(default = "default_up")]
    up: V3,
    /// Full vertical field of view in degrees.
    fov: f32,
    resolution: [u32; 2],
}

fn default_up() -> V3 {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RenderRaw {
    spp: Option<u32>,
    max_depth: Option<u32>,
    seed: Option<u32>,
    integrator: Option<IntegratorRaw>,
    rr_depth: Option<u32>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum IntegratorRaw {
    Path,
    Direct,
}

#[derive(Deserialize, Clone, Copy, Debug)]
#[serde(rename_all = "snake_case")]
enum MaterialType {
    Lambert,
    BlinnPhong,
    CookTorrance,
    Mirror,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialRaw {
    #[serde(rename = "type")]
    kind: MaterialType,
    albedo: Option<V3>,
    kd: Option<V3>,
    ks: Option<V3>,
    exponent: Option<f32>,
    reflectance: Option<V3>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
enum BumpType {
    Sinusoids,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BumpRaw {
    #[serde(rename = "type")]
    _kind: BumpType,
    terms: Vec<TermRaw>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TermRaw {
    amplitude: f32,
    frequency: [f32; 2],
    #[serde(default)]
    phase: f32,
}

#[derive(Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(rename_all = "snake_case")]
enum ShapeType {
    Sphere,
    Quad,
    Cube,
    Mesh,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeRaw {
    #[serde(rename = "type")]
    kind: ShapeType,
    name: Option<String>,
    material: Option<String>,
    bump: Option<String>,
    emission: Option<V3>,
    center: Option<V3>,
    radius: Option<f32>,
    corner: Option<V3>,
    edge_u: Option<V3>,
    edge_v: Option<V3>,
    size: Option<[f32; 2]>,
    transform: Option<TransformRaw>,
    file: Option<String>,
    /// Mesh only: compute welded, area-weighted vertex normals (replacing any in
    /// the file), so that a normal-less model is not shaded faceted.
    smooth_normals: Option<bool>,
}

#[derive(Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(rename_all = "snake_case")]
enum LightType {
    Sphere,
    Rect,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightRaw {
    #[serde(rename = "type")]
    kind: LightType,
    name: Option<String>,
    radiance: V3,
    center: Option<V3>,
    radius: Option<f32>,
    corner: Option<V3>,
    edge_u: Option<V3>,
    edge_v: Option<V3>,
    size: Option<[f32; 2]>,
    transform: Option<TransformRaw>,
}

#[derive(Deserialize, Clone, Copy, Debug)]
#[serde(rename_all = "snake_case")]
enum EnvironmentType {
    Constant,
    Image,
    GaussianSky,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentRaw {
    #[serde(rename = "type")]
    kind: EnvironmentType,
    radiance: Option<V3>,
    file: Option<String>,
    scale: Option<f32>,
    direction: Option<V3>,
    sharpness: Option<f32>,
    peak: Option<V3>,
    ambient: Option<V3>,
}

/// `transform = { scale, rotate, translate }` (applied in that order: scale, then
/// each rotation in list order, then translate) or `transform = { matrix }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformRaw {
    scale: Option<ScaleRaw>,
    rotate: Option<RotateRaw>,
    translate: Option<V3>,
    /// Row-major 3×4 or 4×4 (last row 0 0 0 1), as Mitsuba prints `to_world`.
    matrix: Option<Vec<[f32; 4]>>,
}

/// `scale = s` (uniform) or `scale = [sx, sy, sz]`.
struct ScaleRaw(V3);

/// `rotate = [axis_x, axis_y, axis_z, degrees]` or a list of them.
struct RotateRaw(Vec<[f32; 4]>);

fn number(v: &toml::Value) -> Option<f32> {
    match v {
        toml::Value::Integer(i) => Some(*i as f32),
        toml::Value::Float(f) => Some(*f as f32),
        _ => None,
    }
}

fn numbers<const N: usize>(v: &toml::Value) -> Option<[f32; N]> {
    let a = v.as_array()?;
    if a.len() != N {
        return None;
    }
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = number(x)?;
    }
    Some(out)
}

impl<'de> Deserialize<'de> for ScaleRaw {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = toml::Value::deserialize(d)?;
        number(&v)
            .map(|s| ScaleRaw([s; 3]))
            .or_else(|| numbers::<3>(&v).map(ScaleRaw))
            .ok_or_else(|| {
                D::Error::custom(format!(
                    "expected a number or [x, y, z] for `scale`, got {v}"
                ))
            })
    }
}

impl<'de> Deserialize<'de> for RotateRaw {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = toml::Value::deserialize(d)?;
        let single = numbers::<4>(&v).map(|r| vec![r]);
        let list = || {
            v.as_array()?
                .iter()
                .map(numbers::<4>)
                .collect::<Option<Vec<_>>>()
        };
        single.or_else(list).map(RotateRaw).ok_or_else(|| {
            D::Error::custom(format!(
                "expected [axis_x, axis_y, axis_z, degrees] or a list of them for `rotate`, got {v}"
            ))
        })
    }
}

// ---------------------------------------------------------------------------
// Value checks.
// ---------------------------------------------------------------------------

fn list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl Ctx<'_> {
    fn finite(&self, at: &KeyPath, x: f32) -> crate::Result<f32> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(at, format!("expected a finite number, got {x}")))
        }
    }

    fn vec3(&self, at: &KeyPath, v: V3) -> crate::Result<Vec3> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(Vec3::from(v))
        } else {
            Err(self.err(at, format!("expected three finite numbers, got {v:?}")))
        }
    }

    fn colour(&self, at: &KeyPath, v: V3) -> crate::Result<Vec3> {
        let c = self.vec3(at, v)?;
        if c.min_element() < 0.0 {
            return Err(self.err(at, format!("expected non-negative RGB values, got {v:?}")));
        }
        Ok(c)
    }

    fn positive(&self, at: &KeyPath, x: f32) -> crate::Result<f32> {
        if self.finite(at, x)? > 0.0 {
            Ok(x)
        } else {
            Err(self.err(at, format!("expected a positive number, got {x}")))
        }
    }

    fn non_negative(&self, at: &KeyPath, x: f32) -> crate::Result<f32> {
        if self.finite(at, x)? >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(at, format!("expected a non-negative number, got {x}")))
        }
    }

    /// `present` keys must all be in `allowed` for this `type`.
    fn only(
        &self,
        at: &KeyPath,
        kind: &str,
        present: &[(&str, bool)],
        allowed: &[&str],
    ) -> crate::Result<()> {
        match present.iter().find(|(k, is)| *is && !allowed.contains(k)) {
            Some((k, _)) => Err(self.err(
                &at.key(k),
                format!(
                    "`{k}` does not apply to type = \"{kind}\"; its keys are {}",
                    list(allowed)
                ),
            )),
            None => Ok(()),
        }
    }

    fn need<T>(&self, at: &KeyPath, kind: &str, key: &str, v: Option<T>) -> crate::Result<T> {
        v.ok_or_else(|| self.err(at, format!("type = \"{kind}\" needs `{key}`")))
    }

    fn transform(&self, at: &KeyPath, t: Option<&TransformRaw>) -> crate::Result<Xform> {
        let Some(t) = t else {
            return Ok(Xform::identity());
        };
        let affine = if let Some(rows) = &t.matrix {
            let m = at.key("matrix");
            if t.scale.is_some() || t.rotate.is_some() || t.translate.is_some() {
                return Err(self.err(
                    &m,
                    "give either `matrix` or `scale`/`rotate`/`translate`, not both",
                ));
            }
            if !(rows.len() == 3 || rows.len() == 4) {
                return Err(self.err(
                    &m,
                    format!("expected 3 or 4 rows of 4 numbers, got {} rows", rows.len()),
                ));
            }
            if rows.iter().flatten().any(|x| !x.is_finite()) {
                return Err(self.err(&m, "expected finite numbers"));
            }
            if rows.len() == 4 && rows[3] != [0.0, 0.0, 0.0, 1.0] {
                return Err(self.err(
                    &m,
                    format!(
                        "the last row must be [0, 0, 0, 1] (affine transforms only), got {:?}",
                        rows[3]
                    ),
                ));
            }
            let linear = Mat3::from_cols_array_2d(&[
                [rows[0][0], rows[1][0], rows[2][0]],
                [rows[0][1], rows[1][1], rows[2][1]],
                [rows[0][2], rows[1][2], rows[2][2]],
            ]);
            Affine3A::from_mat3_translation(linear, Vec3::new(rows[0][3], rows[1][3], rows[2][3]))
        } else {
            let scale = match &t.scale {
                Some(ScaleRaw(s)) => self.vec3(&at.key("scale"), *s)?,
                None => Vec3::ONE,
            };
            let mut a = Affine3A::from_scale(scale);
            if let Some(RotateRaw(rots)) = &t.rotate {
                for r in rots {
                    let rp = at.key("rotate");
                    let axis = self.vec3(&rp, [r[0], r[1], r[2]])?.normalize_or_zero();
                    let deg = self.finite(&rp, r[3])?;
                    if axis == Vec3::ZERO {
                        return Err(self.err(&rp, "rotation axis must be non-zero"));
                    }
                    a = Affine3A::from_quat(Quat::from_axis_angle(axis, deg.to_radians())) * a;
                }
            }
            if let Some(tr) = t.translate {
                a = Affine3A::from_translation(self.vec3(&at.key("translate"), tr)?) * a;
            }
            a
        };
        Xform::new(affine)
            .ok_or_else(|| self.err(at, "transform is singular (a zero scale?) or not finite"))
    }

    /// The quad geometry keys shared by `quad` shapes and `rect` lights:
    /// corner/edge_u/edge_v, or size (default [2, 2]) + transform.
    #[allow(clippy::too_many_arguments)]
    fn rect_geometry(
        &self,
        at: &KeyPath,
        corner: Option<V3>,
        edge_u: Option<V3>,
        edge_v: Option<V3>,
        size: Option<[f32; 2]>,
        transform: Option<&TransformRaw>,
    ) -> crate::Result<(Vec3, Vec3, Vec3)> {
        let explicit = corner.is_some() || edge_u.is_some() || edge_v.is_some();
        let (c, u, v) = if explicit {
            if size.is_some() || transform.is_some() {
                return Err(self.err(
                    at,
                    "give either `corner`/`edge_u`/`edge_v` or `size`/`transform`, not both",
                ));
            }
            let need = |k: &str, v: Option<V3>| {
                v.ok_or_else(|| {
                    self.err(
                        at,
                        format!("`corner`, `edge_u` and `edge_v` go together; `{k}` is missing"),
                    )
                })
            };
            (
                self.vec3(&at.key("corner"), need("corner", corner)?)?,
                self.vec3(&at.key("edge_u"), need("edge_u", edge_u)?)?,
                self.vec3(&at.key("edge_v"), need("edge_v", edge_v)?)?,
            )
        } else {
            let s = size.unwrap_or([2.0, 2.0]);
            let sp = at.key("size");
            let s = Vec2::new(self.positive(&sp, s[0])?, self.positive(&sp, s[1])?);
            let xf = self.transform(&at.key("transform"), transform)?;
            geometry::rectangle_edges(&xf, s)
        };
        for (k, e) in [("edge_u", u), ("edge_v", v)] {
            if e.length() <= 0.0 {
                return Err(self.err(&at.key(k), format!("`{k}` must have non-zero length")));
            }
        }
        // (Inputs are finite here, so `<=` is the exact negation of "has area".)
        if u.cross(v).length() <= 1e-7 * u.length() * v.length() {
            return Err(self.err(
                at,
                "`edge_u` and `edge_v` are parallel: the quad has no area",
            ));
        }
        Ok((c, u, v))
    }
}

fn perpendicular(u: Vec3, v: Vec3) -> bool {
    u.dot(v).abs() <= 1e-4 * u.length() * v.length()
}

// ---------------------------------------------------------------------------
// Raw → Scene.
// ---------------------------------------------------------------------------

/// Name of the black material given to the surfaces of `[[lights]]`.
const LIGHT_MATERIAL: &str = "(lights)";

struct Builder<'a> {
    ctx: &'a Ctx<'a>,
    materials: Vec<Material>,
    material_names: Vec<String>,
    material_index: HashMap<String, u32>,
    bumps: Vec<Bump>,
    bump_index: HashMap<String, u32>,
    meshes: Vec<Mesh>,
    spheres: Vec<Sphere>,
    object_names: Vec<String>,
    degenerate: usize,
}

impl<'a> Builder<'a> {
    fn new(ctx: &'a Ctx<'a>) -> Self {
        Self {
            ctx,
            materials: Vec::new(),
            material_names: Vec::new(),
            material_index: HashMap::new(),
            bumps: Vec::new(),
            bump_index: HashMap::new(),
            meshes: Vec::new(),
            spheres: Vec::new(),
            object_names: Vec::new(),
            degenerate: 0,
        }
    }

    fn build(mut self, raw: FileRaw) -> crate::Result<Scene> {
        let ctx = self.ctx;
        let settings = self.settings(&raw.render)?;
        let camera = self.camera(&raw.camera)?;
        for (name, m) in &raw.materials {
            let at = root("materials").key(name);
            let material = self.material(&at, m)?;
            self.add_material(name.clone(), material);
        }
        for (name, b) in &raw.bumps {
            let at = root("bumps").key(name);
            let bump = self.bump(&at, name, b)?;
            self.bump_index
                .insert(name.clone(), self.bumps.len() as u32);
            self.bumps.push(bump);
        }
        for (i, s) in raw.shapes.iter().enumerate() {
            self.shape(&root("shapes").index(i), s)?;
        }
        for (i, l) in raw.lights.iter().enumerate() {
            self.light(&root("lights").index(i), l)?;
        }
        let environment = raw
            .environment
            .as_ref()
            .map(|e| self.environment(&root("environment"), e))
            .transpose()?;
        if self.meshes.is_empty() && self.spheres.is_empty() && environment.is_none() {
            return Err(ctx.err(
                &KeyPath::default(),
                "the scene is empty: add [[shapes]], [[lights]] or an [environment]",
            ));
        }
        let stats = SceneStats {
            triangles: self.meshes.iter().map(|m| m.triangles.len()).sum(),
            degenerate_triangles: self.degenerate,
            meshes_with_normals: self.meshes.iter().filter(|m| !m.normals.is_empty()).count(),
        };
        let animation = raw.animation.as_ref();
        let animation = animation
            .map(|a| super::animation::resolve(ctx, a, &self.object_names))
            .transpose()?;
        Ok(Scene {
            path: ctx.file.to_path_buf(),
            assets: ctx.assets.take(),
            camera,
            settings,
            materials: self.materials,
            material_names: self.material_names,
            meshes: self.meshes,
            spheres: self.spheres,
            bumps: self.bumps,
            environment,
            object_names: self.object_names,
            stats,
            animation,
        })
    }

    fn add_material(&mut self, name: String, m: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.material_index.insert(name.clone(), id);
        self.material_names.push(name);
        self.materials.push(m);
        id
    }

    fn settings(&self, r: &RenderRaw) -> crate::Result<RenderSettings> {
        let d = RenderSettings::default();
        let at = root("render");
        let spp = r.spp.unwrap_or(d.spp);
        if spp == 0 {
            return Err(self.ctx.err(
                &at.key("spp"),
                "expected at least 1 sample per pixel, got 0",
            ));
        }
        let max_depth = r.max_depth.unwrap_or(d.max_depth);
        if max_depth == 0 {
            return Err(self.ctx.err(
                &at.key("max_depth"),
                "expected at least 1 (1 = only directly visible emitters), got 0",
            ));
        }
        Ok(RenderSettings {
            spp,
            max_depth,
            seed: r.seed.unwrap_or(d.seed),
            integrator: match r.integrator {
                None => d.integrator,
                Some(IntegratorRaw::Path) => Integrator::Path,
                Some(IntegratorRaw::Direct) => Integrator::Direct,
            },
            rr_depth: r.rr_depth.unwrap_or(d.rr_depth),
        })
    }

    fn camera(&self, c: &CameraRaw) -> crate::Result<Camera> {
        let ctx = self.ctx;
        let at = root("camera");
        let from = ctx.vec3(&at.key("from"), c.from)?;
        let to = ctx.vec3(&at.key("to"), c.to)?;
        let up = ctx.vec3(&at.key("up"), c.up)?;
        let fov = ctx.finite(&at.key("fov"), c.fov)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(ctx.err(
                &at.key("fov"),
                format!("expected the vertical field of view in degrees, in (0, 180), got {fov}"),
            ));
        }
        let [w, h] = c.resolution;
        if w == 0 || h == 0 {
            return Err(ctx.err(
                &at.key("resolution"),
                format!("expected [width, height] of at least 1 pixel each, got [{w}, {h}]"),
            ));
        }
        Camera::new(from, to, up, fov, w, h).map_err(|m| ctx.err(&at, m))
    }

    fn material(&self, at: &KeyPath, m: &MaterialRaw) -> crate::Result<Material> {
        let ctx = self.ctx;
        let present = [
            ("albedo", m.albedo.is_some()),
            ("kd", m.kd.is_some()),
            ("ks", m.ks.is_some()),
            ("exponent", m.exponent.is_some()),
            ("reflectance", m.reflectance.is_some()),
        ];
        let kind = match m.kind {
            MaterialType::Lambert => "lambert",
            MaterialType::BlinnPhong => "blinn_phong",
            MaterialType::CookTorrance => "cook_torrance",
            MaterialType::Mirror => "mirror",
        };
        let colour = |key: &str, v: Option<V3>| -> crate::Result<Vec3> {
            ctx.colour(&at.key(key), ctx.need(at, kind, key, v)?)
        };
        Ok(match m.kind {
            MaterialType::Lambert => {
                ctx.only(at, kind, &present, &["albedo"])?;
                Material::Lambert {
                    albedo: colour("albedo", m.albedo)?,
                }
            }
            MaterialType::BlinnPhong | MaterialType::CookTorrance => {
                ctx.only(at, kind, &present, &["kd", "ks", "exponent"])?;
                let kd = colour("kd", m.kd)?;
                let ks = colour("ks", m.ks)?;
                let exponent = ctx.non_negative(
                    &at.key("exponent"),
                    ctx.need(at, kind, "exponent", m.exponent)?,
                )?;
                if matches!(m.kind, MaterialType::BlinnPhong) {
                    Material::BlinnPhong { kd, ks, exponent }
                } else {
                    Material::CookTorrance { kd, ks, exponent }
                }
            }
            MaterialType::Mirror => {
                ctx.only(at, kind, &present, &["reflectance"])?;
                Material::Mirror {
                    reflectance: colour("reflectance", m.reflectance)?,
                }
            }
        })
    }

    fn bump(&self, at: &KeyPath, name: &str, b: &BumpRaw) -> crate::Result<Bump> {
        let ctx = self.ctx;
        if b.terms.is_empty() {
            return Err(ctx.err(&at.key("terms"), "expected at least one term"));
        }
        let mut terms = Vec::with_capacity(b.terms.len());
        for (i, t) in b.terms.iter().enumerate() {
            let tp = at.key("terms").index(i);
            terms.push(Sinusoid {
                amplitude: ctx.finite(&tp.key("amplitude"), t.amplitude)?,
                frequency: Vec2::new(
                    ctx.finite(&tp.key("frequency"), t.frequency[0])?,
                    ctx.finite(&tp.key("frequency"), t.frequency[1])?,
                ),
                phase: ctx.finite(&tp.key("phase"), t.phase)?,
            });
        }
        Ok(Bump {
            name: name.to_string(),
            terms,
        })
    }

    fn lookup(
        &self,
        at: &KeyPath,
        what: &str,
        name: &str,
        index: &HashMap<String, u32>,
    ) -> crate::Result<u32> {
        index.get(name).copied().ok_or_else(|| {
            let mut names: Vec<&str> = index
                .keys()
                .map(String::as_str)
                .filter(|n| *n != LIGHT_MATERIAL)
                .collect();
            names.sort_unstable();
            let defined = if names.is_empty() {
                format!("no [{what}s.NAME] table is defined")
            } else {
                format!("defined {what}s: {}", list(&names))
            };
            self.ctx
                .err(at, format!("undefined {what} `{name}`; {defined}"))
        })
    }

    fn shape(&mut self, at: &KeyPath, s: &ShapeRaw) -> crate::Result<()> {
        let ctx = self.ctx;
        let object_id = self.object_names.len() as u32 + 1;
        let present = [
            ("center", s.center.is_some()),
            ("radius", s.radius.is_some()),
            ("corner", s.corner.is_some()),
            ("edge_u", s.edge_u.is_some()),
            ("edge_v", s.edge_v.is_some()),
            ("size", s.size.is_some()),
            ("transform", s.transform.is_some()),
            ("file", s.file.is_some()),
            ("smooth_normals", s.smooth_normals.is_some()),
        ];
        const COMMON: [&str; 4] = ["name", "material", "bump", "emission"];
        let keys = |extra: &[&'static str]| -> Vec<&'static str> {
            COMMON.iter().chain(extra).copied().collect()
        };
        let kind = match s.kind {
            ShapeType::Sphere => "sphere",
            ShapeType::Quad => "quad",
            ShapeType::Cube => "cube",
            ShapeType::Mesh => "mesh",
        };
        let emission = match s.emission {
            Some(e) => Some(ctx.colour(&at.key("emission"), e)?),
            None => None,
        };
        let bump = match &s.bump {
            Some(b) => Some(self.lookup(&at.key("bump"), "bump", b, &self.bump_index)?),
            None => None,
        };
        let material = match &s.material {
            Some(m) => {
                Some(self.lookup(&at.key("material"), "material", m, &self.material_index)?)
            }
            None => None,
        };
        let need_material = || ctx.need(at, kind, "material", material);
        let name = s.name.clone();

        match s.kind {
            ShapeType::Sphere => {
                ctx.only(at, kind, &present, &keys(&["center", "radius"]))?;
                let center =
                    ctx.vec3(&at.key("center"), ctx.need(at, kind, "center", s.center)?)?;
                let radius =
                    ctx.positive(&at.key("radius"), ctx.need(at, kind, "radius", s.radius)?)?;
                if let Some(b) = bump {
                    self.check_sphere_bump(&at.key("bump"), b)?;
                }
                self.spheres.push(Sphere {
                    name: name.clone().unwrap_or_else(|| format!("sphere{object_id}")),
                    center,
                    radius,
                    material: need_material()?,
                    emission: emission.unwrap_or(Vec3::ZERO),
                    bump,
                    object_id,
                });
            }
            ShapeType::Quad => {
                ctx.only(
                    at,
                    kind,
                    &present,
                    &keys(&["corner", "edge_u", "edge_v", "size", "transform"]),
                )?;
                let (c, u, v) = ctx.rect_geometry(
                    at,
                    s.corner,
                    s.edge_u,
                    s.edge_v,
                    s.size,
                    s.transform.as_ref(),
                )?;
                let emission = emission.unwrap_or(Vec3::ZERO);
                if emission != Vec3::ZERO && !perpendicular(u, v) {
                    return Err(ctx.err(
                        at,
                        "an emitting quad must be a rectangle: `edge_u` and `edge_v` must be perpendicular",
                    ));
                }
                let material = need_material()?;
                self.push_quad(
                    name.clone().unwrap_or_else(|| format!("quad{object_id}")),
                    (c, u, v),
                    material,
                    emission,
                    bump,
                    object_id,
                );
            }
            ShapeType::Cube => {
                ctx.only(at, kind, &present, &keys(&["transform"]))?;
                let xf = ctx.transform(&at.key("transform"), s.transform.as_ref())?;
                let g = geometry::cube(&xf);
                self.meshes.push(Mesh {
                    name: name.clone().unwrap_or_else(|| format!("cube{object_id}")),
                    positions: g.positions,
                    normals: Vec::new(),
                    uvs: g.uvs,
                    triangles: g.triangles,
                    material: need_material()?,
                    emission: emission.unwrap_or(Vec3::ZERO),
                    bump,
                    rect: None,
                    object_id,
                });
            }
            ShapeType::Mesh => {
                ctx.only(
                    at,
                    kind,
                    &present,
                    &keys(&["file", "transform", "smooth_normals"]),
                )?;
                let fp = at.key("file");
                let file = ctx.asset(&fp, &ctx.need(at, kind, "file", s.file.clone())?)?;
                let xf = ctx.transform(&at.key("transform"), s.transform.as_ref())?;
                let stem = file
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| format!("mesh{object_id}"));
                let shape_name = name.clone().unwrap_or(stem);
                let smooth = s.smooth_normals.unwrap_or(false);
                self.push_obj(
                    at,
                    &file,
                    &xf,
                    &shape_name,
                    smooth,
                    material,
                    emission,
                    bump,
                    object_id,
                )?;
                self.object_names.push(shape_name);
                return Ok(());
            }
        }
        self.object_names
            .push(name.unwrap_or_else(|| format!("{kind}{object_id}")));
        Ok(())
    }

    /// On a sphere u = φ/2π wraps from 1 back to 0 at the φ = 0 seam, so a term
    /// sin(2π(f_u u + f_v v) + φ₀) is continuous there only for an integer f_u; a
    /// fractional one would crease the surface along a meridian.
    fn check_sphere_bump(&self, at: &KeyPath, b: u32) -> crate::Result<()> {
        let bump = &self.bumps[b as usize];
        if let Some(t) = bump.terms.iter().find(|t| t.frequency.x.fract() != 0.0) {
            return Err(self.ctx.err(
                at,
                format!(
                    "bump `{}` is on a sphere, where frequency[0] (f_u) must be an integer so that \
                     the height is continuous across the φ = 0 seam; got {}",
                    bump.name, t.frequency.x
                ),
            ));
        }
        Ok(())
    }

    fn push_quad(
        &mut self,
        name: String,
        (corner, edge_u, edge_v): (Vec3, Vec3, Vec3),
        material: u32,
        emission: Vec3,
        bump: Option<u32>,
        object_id: u32,
    ) {
        let g = geometry::quad(corner, edge_u, edge_v);
        self.meshes.push(Mesh {
            name,
            positions: g.positions,
            normals: Vec::new(),
            uvs: g.uvs,
            triangles: g.triangles,
            material,
            emission,
            bump,
            rect: perpendicular(edge_u, edge_v).then_some(Rect {
                corner,
                edge_u,
                edge_v,
            }),
            object_id,
        });
    }

    #[allow(clippy::too_many_arguments)]
    fn push_obj(
        &mut self,
        at: &KeyPath,
        file: &Path,
        xf: &Xform,
        shape_name: &str,
        smooth: bool,
        material: Option<u32>,
        emission: Option<Vec3>,
        bump: Option<u32>,
        object_id: u32,
    ) -> crate::Result<()> {
        let ctx = self.ctx;
        let (meshes, mtl) = obj::load(file, xf)?;
        // MTL materials join the scene's list as "<shape>/<mtl name>", only when used.
        let mut mtl_ids: Vec<Option<u32>> = vec![None; mtl.len()];
        let mut any_kept = false;
        for (k, m) in meshes.into_iter().enumerate() {
            self.degenerate += m.degenerate;
            if m.triangles.is_empty() {
                continue;
            }
            any_kept = true;
            let mesh_material = match (material, m.material) {
                (Some(id), _) => id,
                (None, Some(j)) => match mtl_ids[j] {
                    Some(id) => id,
                    None => {
                        let id = self.add_material(
                            format!("{shape_name}/{}", mtl[j].name),
                            mtl[j].material.clone(),
                        );
                        mtl_ids[j] = Some(id);
                        id
                    }
                },
                (None, None) => {
                    return Err(ctx.err(
                        at,
                        format!(
                            "object `{}` of {} has no MTL material; give the shape a `material`",
                            m.name,
                            file.display()
                        ),
                    ))
                }
            };
            if bump.is_some() && m.uvs.is_empty() {
                return Err(ctx.err(
                    &at.key("bump"),
                    format!(
                        "a bump map needs texture coordinates (vt), but object `{}` of {} has none",
                        m.name,
                        file.display()
                    ),
                ));
            }
            let mesh_emission = emission
                .or_else(|| m.material.map(|j| mtl[j].emission))
                .unwrap_or(Vec3::ZERO);
            let name = if m.name.is_empty() {
                format!("{shape_name}/{k}")
            } else {
                format!("{shape_name}/{}", m.name)
            };
            let normals = if smooth {
                obj::smooth_normals(&m.positions, &m.triangles)
            } else {
                m.normals
            };
            self.meshes.push(Mesh {
                name,
                positions: m.positions,
                normals,
                uvs: m.uvs,
                triangles: m.triangles,
                material: mesh_material,
                emission: mesh_emission,
                bump,
                rect: None,
                object_id,
            });
        }
        if !any_kept {
            return Err(ctx.err(
                &at.key("file"),
                format!("{} contains no (non-degenerate) triangles", file.display()),
            ));
        }
        Ok(())
    }

    fn light_material(&mut self) -> u32 {
        match self.material_index.get(LIGHT_MATERIAL) {
            Some(&id) => id,
            None => self.add_material(
                LIGHT_MATERIAL.into(),
                Material::Lambert { albedo: Vec3::ZERO },
            ),
        }
    }

    fn light(&mut self, at: &KeyPath, l: &LightRaw) -> crate::Result<()> {
        let ctx = self.ctx;
        let object_id = self.object_names.len() as u32 + 1;
        let radiance = ctx.colour(&at.key("radiance"), l.radiance)?;
        let present = [
            ("center", l.center.is_some()),
            ("radius", l.radius.is_some()),
            ("corner", l.corner.is_some()),
            ("edge_u", l.edge_u.is_some()),
            ("edge_v", l.edge_v.is_some()),
            ("size", l.size.is_some()),
            ("transform", l.transform.is_some()),
        ];
        let name = l
            .name
            .clone()
            .unwrap_or_else(|| format!("light{object_id}"));
        match l.kind {
            LightType::Sphere => {
                let kind = "sphere";
                ctx.only(
                    at,
                    kind,
                    &present,
                    &["name", "radiance", "center", "radius"],
                )?;
                let center =
                    ctx.vec3(&at.key("center"), ctx.need(at, kind, "center", l.center)?)?;
                let radius =
                    ctx.positive(&at.key("radius"), ctx.need(at, kind, "radius", l.radius)?)?;
                let material = self.light_material();
                self.spheres.push(Sphere {
                    name: name.clone(),
                    center,
                    radius,
                    material,
                    emission: radiance,
                    bump: None,
                    object_id,
                });
            }
            LightType::Rect => {
                let kind = "rect";
                ctx.only(
                    at,
                    kind,
                    &present,
                    &[
                        "name",
                        "radiance",
                        "corner",
                        "edge_u",
                        "edge_v",
                        "size",
                        "transform",
                    ],
                )?;
                let (c, u, v) = ctx.rect_geometry(
                    at,
                    l.corner,
                    l.edge_u,
                    l.edge_v,
                    l.size,
                    l.transform.as_ref(),
                )?;
                if !perpendicular(u, v) {
                    return Err(ctx.err(
                        at,
                        "a rect light must be a rectangle: `edge_u` and `edge_v` must be perpendicular",
                    ));
                }
                let material = self.light_material();
                self.push_quad(name.clone(), (c, u, v), material, radiance, None, object_id);
            }
        }
        self.object_names.push(name);
        Ok(())
    }

    fn environment(&self, at: &KeyPath, e: &EnvironmentRaw) -> crate::Result<Environment> {
        let ctx = self.ctx;
        let present = [
            ("radiance", e.radiance.is_some()),
            ("file", e.file.is_some()),
            ("scale", e.scale.is_some()),
            ("direction", e.direction.is_some()),
            ("sharpness", e.sharpness.is_some()),
            ("peak", e.peak.is_some()),
            ("ambient", e.ambient.is_some()),
        ];
        Ok(match e.kind {
            EnvironmentType::Constant => {
                let kind = "constant";
                ctx.only(at, kind, &present, &["radiance"])?;
                Environment::Constant {
                    radiance: ctx.colour(
                        &at.key("radiance"),
                        ctx.need(at, kind, "radiance", e.radiance)?,
                    )?,
                }
            }
            EnvironmentType::Image => {
                let kind = "image";
                ctx.only(at, kind, &present, &["file", "scale"])?;
                let file = ctx.asset(
                    &at.key("file"),
                    &ctx.need(at, kind, "file", e.file.clone())?,
                )?;
                let scale = ctx.non_negative(&at.key("scale"), e.scale.unwrap_or(1.0))?;
                super::environment::load_latlong(&file, scale)?
            }
            EnvironmentType::GaussianSky => {
                let kind = "gaussian_sky";
                ctx.only(
                    at,
                    kind,
                    &present,
                    &["direction", "sharpness", "peak", "ambient"],
                )?;
                let dp = at.key("direction");
                let direction = ctx
                    .vec3(&dp, e.direction.unwrap_or([0.0, 1.0, 0.0]))?
                    .normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(ctx.err(&dp, "expected a non-zero direction"));
                }
                Environment::GaussianSky {
                    direction,
                    sharpness: ctx.non_negative(
                        &at.key("sharpness"),
                        ctx.need(at, kind, "sharpness", e.sharpness)?,
                    )?,
                    peak: ctx.colour(&at.key("peak"), ctx.need(at, kind, "peak", e.peak)?)?,
                    ambient: ctx.colour(&at.key("ambient"), e.ambient.unwrap_or([0.0; 3]))?,
                }
            }
        })
    }
}
