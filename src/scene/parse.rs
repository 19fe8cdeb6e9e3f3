//! Scene file (TOML) → [`Scene`]. The format is documented key by key in
//! `scenes/README.md`.
//!
//! The TOML text becomes a `toml::Table`; every table of it is then read through
//! a [`Params`] dictionary, whose typed getters check each value (finite
//! numbers, exact array lengths, valid choices) and whose [`Params::finish`]
//! reports any key the reader did not ask for. Shapes and lights share one
//! path: a `[[lights]]` entry is a shape whose emission (`radiance`) is required
//! and whose surface is the black `(lights)` material. Every error is one
//! `Error::Scene` whose location names the key path and its line/column (see
//! `locate`).

use super::animation::{ObjObject, ObjSource, ShapeSource};
use super::geometry::{self, Xform};
use super::locate::{Ctx, KeyPath};
use super::params::{self, list, Params};
use super::{bump::Sinusoid, SceneStats, Sphere, MAX_MAGNITUDE};
use super::{obj, Bump, Camera, Environment, Integrator, Mesh, Rect, RenderSettings, Scene};
use crate::brdf::Material;
use crate::math::{cross, Vec2, Vec3};
use glam::{Affine3A, Mat3, Quat};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;
use toml::Value;

/// The largest scene file accepted (16 MiB): scene files are a few kilobytes;
/// the limit turns `gradtrace info /dev/zero` or a mistyped path to a huge
/// file into one clear error instead of unbounded memory growth.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// The largest image: both sides at most 65 536 and at most 2²⁸ pixels (a
/// 16k × 16k render), so that the planes a render allocates stay addressable.
pub const MAX_PIXELS: u64 = 1 << 28;

pub(super) fn load_scene(path: &Path) -> crate::Result<Scene> {
    let text = read_scene_file(path)?;
    scene_from_str(&text, path)
}

fn input_err(path: &Path, message: String) -> crate::Error {
    crate::Error::Asset {
        path: path.to_path_buf(),
        message,
    }
}

/// Reads the scene file, refusing what is not a regular file of at most
/// [`MAX_SCENE_BYTES`] of UTF-8 (the read itself is bounded too: a file that
/// grows, or a /proc file that reports size 0, cannot exceed the limit).
fn read_scene_file(path: &Path) -> crate::Result<String> {
    let io = |source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        let what = crate::error::file_kind(&meta);
        return Err(input_err(
            path,
            format!("is {what}, not a regular file; expected a scene file (TOML)"),
        ));
    }
    let too_big = || {
        input_err(
            path,
            format!(
                "is larger than {} MiB, the limit for scene files (scene::MAX_SCENE_BYTES)",
                MAX_SCENE_BYTES >> 20
            ),
        )
    };
    if meta.len() > MAX_SCENE_BYTES {
        return Err(too_big());
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(io)?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(too_big());
    }
    String::from_utf8(bytes).map_err(|e| {
        input_err(
            path,
            format!(
                "is not UTF-8 text (invalid byte at offset {}); expected a scene file (TOML)",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

pub(super) fn scene_from_str(text: &str, path: &Path) -> crate::Result<Scene> {
    if text.len() as u64 > MAX_SCENE_BYTES {
        return Err(input_err(
            path,
            format!(
                "is larger than {} MiB, the limit for scene files (scene::MAX_SCENE_BYTES)",
                MAX_SCENE_BYTES >> 20
            ),
        ));
    }
    let ctx = Ctx::new(text, path);
    let doc: toml::Table = toml::from_str(text).map_err(|e| ctx.toml_err(&e))?;
    let top = Params::new(&ctx, KeyPath::default(), &doc);
    Builder::new(&ctx).build(&top)
}

type V3 = [f32; 3];

// ---------------------------------------------------------------------------
// Value checks.
// ---------------------------------------------------------------------------

fn positive(p: &Params, key: &str, x: f32) -> crate::Result<f32> {
    if x > 0.0 {
        Ok(x)
    } else {
        Err(p.err(Some(key), format!("expected a positive number, got {x}")))
    }
}

fn non_negative(p: &Params, key: &str, x: f32) -> crate::Result<f32> {
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(p.err(
            Some(key),
            format!("expected a non-negative number, got {x}"),
        ))
    }
}

/// An optional RGB colour: three finite, non-negative numbers.
fn colour(p: &Params, key: &'static str) -> crate::Result<Option<Vec3>> {
    let Some(v) = p.f32s::<3>(key)? else {
        return Ok(None);
    };
    if v.iter().any(|x| *x < 0.0) {
        return Err(p.err(
            Some(key),
            format!("expected non-negative RGB values, got {v:?}"),
        ));
    }
    Ok(Some(Vec3::from(v)))
}

/// Positions, radii, extents and camera coordinates must lie within
/// ±[`MAX_MAGNITUDE`]; `points` are checked after every transform.
fn within_range(
    p: &Params,
    key: Option<&str>,
    what: &str,
    points: impl IntoIterator<Item = Vec3>,
) -> crate::Result<()> {
    match points.into_iter().find(|&q| !in_range(q)) {
        Some(q) => Err(p.err(key, out_of_range(what, q))),
        None => Ok(()),
    }
}

/// Within ±[`MAX_MAGNITUDE`] (false for NaN).
fn in_range(q: Vec3) -> bool {
    q.abs().cmple(Vec3::splat(MAX_MAGNITUDE)).all()
}

fn out_of_range(what: &str, q: Vec3) -> String {
    // Debug writes 3e38 where Display writes 39 digits.
    let q = format!("[{:?}, {:?}, {:?}]", q.x, q.y, q.z);
    format!(
        "{what} {q} lies beyond ±{MAX_MAGNITUDE:e}, the largest coordinate magnitude \
         supported (scene::MAX_MAGNITUDE)"
    )
}

/// Directions of the same quad test in unit length, so that neither huge nor
/// tiny edges overflow or underflow the products.
fn unit(v: Vec3) -> Vec3 {
    (v / v.abs().max_element()).normalize()
}

fn perpendicular(u: Vec3, v: Vec3) -> bool {
    unit(u).dot(unit(v)).abs() <= 1e-4
}

/// `scale = s` (uniform) or `scale = [sx, sy, sz]`.
fn scale_of(p: &Params) -> crate::Result<Vec3> {
    let Some(v) = p.get("scale") else {
        return Ok(Vec3::ONE);
    };
    let at = p.path("scale");
    match v {
        Value::Integer(_) | Value::Float(_) => Ok(Vec3::splat(params::number(p.ctx, &at, v)?)),
        Value::Array(_) => Ok(Vec3::from(params::numbers::<3>(p.ctx, &at, v)?)),
        other => Err(p.err(
            Some("scale"),
            format!("expected a number or [x, y, z] for `scale`, got {other}"),
        )),
    }
}

/// `rotate = [axis_x, axis_y, axis_z, degrees]` or a list of them.
fn rotations_of(p: &Params) -> crate::Result<Vec<[f32; 4]>> {
    let Some(v) = p.get("rotate") else {
        return Ok(Vec::new());
    };
    let at = p.path("rotate");
    let bad = || {
        p.err(
            Some("rotate"),
            format!("expected [axis_x, axis_y, axis_z, degrees] or a list of them for `rotate`, got {v}"),
        )
    };
    let a = v.as_array().ok_or_else(bad)?;
    if a.iter().all(Value::is_array) && !a.is_empty() {
        a.iter()
            .enumerate()
            .map(|(i, r)| params::numbers::<4>(p.ctx, &at.index(i), r).map_err(|_| bad()))
            .collect()
    } else {
        params::numbers::<4>(p.ctx, &at, v)
            .map(|r| vec![r])
            .map_err(|_| bad())
    }
}

/// A row-major 3×4 (or 4×4 with last row 0 0 0 1) affine matrix.
fn matrix_of(p: &Params, v: &Value) -> crate::Result<Affine3A> {
    let at = p.path("matrix");
    let rows = match v.as_array() {
        Some(a) if a.len() == 3 || a.len() == 4 => a,
        _ => {
            return Err(p.err(
                Some("matrix"),
                format!("expected 3 or 4 rows of 4 numbers, got {v}"),
            ))
        }
    };
    let rows = rows
        .iter()
        .enumerate()
        .map(|(i, r)| params::numbers::<4>(p.ctx, &at.index(i), r))
        .collect::<crate::Result<Vec<_>>>()?;
    if rows.len() == 4 && rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(p.err(
            Some("matrix"),
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
    Ok(Affine3A::from_mat3_translation(
        linear,
        Vec3::new(rows[0][3], rows[1][3], rows[2][3]).into(),
    ))
}

/// `transform = { scale, rotate, translate }` (applied in that order: scale,
/// then each rotation in list order, then translate) or `transform = { matrix }`.
fn transform_of(p: &Params) -> crate::Result<Xform> {
    let scale = scale_of(p)?;
    let rotations = rotations_of(p)?;
    let translate = p.f32s::<3>("translate")?;
    let matrix = p.get("matrix");
    p.finish()?;
    let affine = if let Some(m) = matrix {
        if p.get("scale").is_some() || !rotations.is_empty() || translate.is_some() {
            return Err(p.err(
                Some("matrix"),
                "give either `matrix` or `scale`/`rotate`/`translate`, not both",
            ));
        }
        matrix_of(p, m)?
    } else {
        let mut a = Affine3A::from_scale(scale.into());
        for r in &rotations {
            let axis = Vec3::new(r[0], r[1], r[2]).normalize_or_zero();
            if axis == Vec3::ZERO {
                return Err(p.err(Some("rotate"), "rotation axis must be non-zero"));
            }
            a = Affine3A::from_quat(Quat::from_axis_angle(axis.into(), r[3].to_radians())) * a;
        }
        if let Some(t) = translate {
            a = Affine3A::from_translation(glam::Vec3::from(t)) * a;
        }
        a
    };
    let det = Mat3::from(affine.matrix3).determinant();
    if !det.is_finite() || !in_range(affine.translation) {
        return Err(p.err(
            None,
            format!(
                "the transform is too large (determinant {det:e}, translation {}); coordinates \
                 are limited to ±{MAX_MAGNITUDE:e} (scene::MAX_MAGNITUDE)",
                Vec3::from(affine.translation)
            ),
        ));
    }
    Xform::new(affine).ok_or_else(|| p.err(None, "transform is singular (a zero scale?)"))
}

// ---------------------------------------------------------------------------
// Shapes and lights: one path.
// ---------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq)]
enum Geometry {
    Sphere,
    Quad,
    Cube,
    Mesh,
}

/// What distinguishes `[[lights]]` from `[[shapes]]`: a light is a shape whose
/// emission is required (and called `radiance`), whose surface is the black
/// `(lights)` material, and whose quad is called `rect`.
struct Family {
    types: &'static [(&'static str, Geometry)],
    emission_key: &'static str,
    light: bool,
}

const SHAPES: Family = Family {
    types: &[
        ("sphere", Geometry::Sphere),
        ("quad", Geometry::Quad),
        ("cube", Geometry::Cube),
        ("mesh", Geometry::Mesh),
    ],
    emission_key: "emission",
    light: false,
};

const LIGHTS: Family = Family {
    types: &[("sphere", Geometry::Sphere), ("rect", Geometry::Quad)],
    emission_key: "radiance",
    light: true,
};

/// The keys of one shape entry, read and checked one by one (cross-key rules
/// and requirements come after [`Params::finish`]).
struct ShapeKeys<'a> {
    geometry: Geometry,
    name: Option<&'a str>,
    material: Option<u32>,
    bump: Option<u32>,
    emission: Option<Vec3>,
    center: Option<V3>,
    radius: Option<f32>,
    corner: Option<V3>,
    edge_u: Option<V3>,
    edge_v: Option<V3>,
    size: Option<[f32; 2]>,
    transform: Option<Xform>,
    file: Option<&'a str>,
    smooth_normals: Option<bool>,
}

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
    /// Beside `object_names`: what `[animation]` needs of each shape.
    sources: Vec<ShapeSource>,
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
            sources: Vec::new(),
            degenerate: 0,
        }
    }

    fn build(mut self, top: &Params) -> crate::Result<Scene> {
        let ctx = self.ctx;
        let camera = top.table("camera")?;
        let render = top.table("render")?;
        let materials = top.named_tables("materials")?;
        let bumps = top.named_tables("bumps")?;
        let shapes = top.tables("shapes")?.unwrap_or_default();
        let lights = top.tables("lights")?.unwrap_or_default();
        let environment = top.table("environment")?;
        let animation = top.table("animation")?;
        top.finish()?;
        let settings = match &render {
            Some(r) => settings(r)?,
            None => RenderSettings::default(),
        };
        let camera = camera_of(&top.need("camera", camera)?)?;
        for (name, m) in &materials {
            let material = material_of(m)?;
            self.add_material(name.to_string(), material);
        }
        for (name, b) in &bumps {
            let bump = bump_of(name, b)?;
            self.bump_index
                .insert(name.to_string(), self.bumps.len() as u32);
            self.bumps.push(bump);
        }
        for s in &shapes {
            self.shape(s, &SHAPES)?;
        }
        for l in &lights {
            self.shape(l, &LIGHTS)?;
        }
        let environment = environment.as_ref().map(environment_of).transpose()?;
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
        let animation = animation
            .as_ref()
            .map(|a| super::animation::read(a, &self.object_names, &self.sources))
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
            content_hash_memo: Default::default(),
        })
    }

    fn add_material(&mut self, name: String, m: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.material_index.insert(name.clone(), id);
        self.material_names.push(name);
        self.materials.push(m);
        id
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

    /// The id of the material or bump named at `key`, if the key is present.
    fn lookup(&self, p: &Params, key: &'static str, what: &str) -> crate::Result<Option<u32>> {
        let Some(name) = p.string(key)? else {
            return Ok(None);
        };
        let index = if what == "bump" {
            &self.bump_index
        } else {
            &self.material_index
        };
        if let Some(&id) = index.get(name) {
            return Ok(Some(id));
        }
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
        Err(p.err(Some(key), format!("undefined {what} `{name}`; {defined}")))
    }

    /// Reads every key of one `[[shapes]]`/`[[lights]]` entry, in the order its
    /// messages list them, then runs the unread-key check.
    fn read_shape<'p>(&self, p: &Params<'p>, fam: &Family) -> crate::Result<ShapeKeys<'p>> {
        let geometry = p.kind(fam.types)?;
        let name = p.string("name")?;
        let (material, bump) = if fam.light {
            (None, None)
        } else {
            (
                self.lookup(p, "material", "material")?,
                self.lookup(p, "bump", "bump")?,
            )
        };
        let emission = colour(p, fam.emission_key)?;
        let mut k = ShapeKeys {
            geometry,
            name,
            material,
            bump,
            emission,
            center: None,
            radius: None,
            corner: None,
            edge_u: None,
            edge_v: None,
            size: None,
            transform: None,
            file: None,
            smooth_normals: None,
        };
        if geometry == Geometry::Sphere {
            k.center = p.f32s::<3>("center")?;
            k.radius = p.f32("radius")?;
        }
        if geometry == Geometry::Quad {
            k.corner = p.f32s::<3>("corner")?;
            k.edge_u = p.f32s::<3>("edge_u")?;
            k.edge_v = p.f32s::<3>("edge_v")?;
            k.size = p.f32s::<2>("size")?;
        }
        if geometry == Geometry::Mesh {
            k.file = p.string("file")?;
        }
        if geometry != Geometry::Sphere {
            k.transform = p
                .table("transform")?
                .as_ref()
                .map(transform_of)
                .transpose()?;
        }
        if geometry == Geometry::Mesh {
            k.smooth_normals = p.bool("smooth_normals")?;
        }
        p.finish()?;
        Ok(k)
    }

    /// One `[[shapes]]` or `[[lights]]` entry.
    fn shape(&mut self, p: &Params, fam: &Family) -> crate::Result<()> {
        let object_id = self.object_names.len() as u32 + 1;
        let k = self.read_shape(p, fam)?;
        let (material, emission) = if fam.light {
            let radiance = p.need("radiance", k.emission)?;
            (Some(self.light_material()), Some(radiance))
        } else {
            (k.material, k.emission)
        };
        let prefix = if fam.light { "light" } else { p.kind_name() };
        let mut name = k
            .name
            .map(str::to_owned)
            .unwrap_or_else(|| format!("{prefix}{object_id}"));
        let need_material = || p.need("material", material);
        let mut obj_source = None;
        match k.geometry {
            Geometry::Sphere => {
                let center = Vec3::from(p.need("center", k.center)?);
                let radius = positive(p, "radius", p.need("radius", k.radius)?)?;
                within_range(p, Some("center"), "the centre", [center])?;
                let r = Vec3::splat(radius);
                within_range(
                    p,
                    Some("radius"),
                    "the sphere's extent",
                    [center - r, center + r],
                )?;
                if let Some(b) = k.bump {
                    self.check_sphere_bump(p, b)?;
                }
                self.spheres.push(Sphere {
                    name: name.clone(),
                    center,
                    radius,
                    material: need_material()?,
                    emission: emission.unwrap_or(Vec3::ZERO),
                    bump: k.bump,
                    object_id,
                });
            }
            Geometry::Quad => {
                let (c, u, v) = rect_geometry(p, &k)?;
                let emission = emission.unwrap_or(Vec3::ZERO);
                if (fam.light || emission != Vec3::ZERO) && !perpendicular(u, v) {
                    let what = if fam.light {
                        "a rect light"
                    } else {
                        "an emitting quad"
                    };
                    return Err(p.err(
                        None,
                        format!(
                            "{what} must be a rectangle: `edge_u` and `edge_v` must be perpendicular"
                        ),
                    ));
                }
                let material = need_material()?;
                self.push_quad(
                    name.clone(),
                    (c, u, v),
                    material,
                    emission,
                    k.bump,
                    object_id,
                );
            }
            Geometry::Cube => {
                let xf = k.transform.unwrap_or_else(Xform::identity);
                let g = geometry::cube(&xf);
                within_range(
                    p,
                    Some("transform"),
                    "the cube corner",
                    g.positions.iter().copied(),
                )?;
                self.meshes.push(Mesh {
                    name: name.clone(),
                    positions: g.positions,
                    normals: Vec::new(),
                    uvs: g.uvs,
                    triangles: g.triangles,
                    material: need_material()?,
                    emission: emission.unwrap_or(Vec3::ZERO),
                    bump: k.bump,
                    rect: None,
                    object_id,
                });
            }
            Geometry::Mesh => {
                let file = self.ctx.asset(&p.path("file"), p.need("file", k.file)?)?;
                if k.name.is_none() {
                    if let Some(stem) = file.file_stem() {
                        name = stem.to_string_lossy().into_owned();
                    }
                }
                let xf = k.transform.unwrap_or_else(Xform::identity);
                let surface = (material, emission, k.bump);
                let smooth = k.smooth_normals.unwrap_or(false);
                let objects = self.push_obj(p, &file, &xf, &name, smooth, surface, object_id)?;
                obj_source = Some(ObjSource {
                    file,
                    xf,
                    smooth,
                    objects,
                });
            }
        }
        self.object_names.push(name);
        self.sources.push(ShapeSource {
            kind: if fam.light { "light" } else { p.kind_name() },
            obj: obj_source,
        });
        Ok(())
    }

    /// On a sphere u = φ/2π wraps from 1 back to 0 at the φ = 0 seam, so a term
    /// sin(2π(f_u u + f_v v) + φ₀) is continuous there only for an integer f_u; a
    /// fractional one would crease the surface along a meridian.
    fn check_sphere_bump(&self, p: &Params, b: u32) -> crate::Result<()> {
        let bump = &self.bumps[b as usize];
        if let Some(t) = bump.terms.iter().find(|t| t.frequency.x.fract() != 0.0) {
            return Err(p.err(
                Some("bump"),
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

    /// The meshes of one OBJ file. `surface` = the shape's (material, emission,
    /// bump), each overriding the MTL's when given. Returns each OBJ object's
    /// name, topology and scene mesh (none when no triangle of it was kept).
    #[allow(clippy::too_many_arguments)]
    fn push_obj(
        &mut self,
        p: &Params,
        file: &Path,
        xf: &Xform,
        shape_name: &str,
        smooth: bool,
        (material, emission, bump): (Option<u32>, Option<Vec3>, Option<u32>),
        object_id: u32,
    ) -> crate::Result<Vec<ObjObject>> {
        let at = p.path("file");
        let (meshes, mtl) = obj::load(file, xf).map_err(|e| self.ctx.in_scene(&at, e))?;
        check_obj_range(p, file, &meshes)?;
        // MTL materials join the scene's list as "<shape>/<mtl name>", only when used.
        let mut mtl_ids: Vec<Option<u32>> = vec![None; mtl.len()];
        let mut any_kept = false;
        let mut objects = Vec::with_capacity(meshes.len());
        for (k, m) in meshes.into_iter().enumerate() {
            self.degenerate += m.degenerate;
            if m.triangles.is_empty() {
                objects.push(ObjObject {
                    name: m.name,
                    topology: m.topology,
                    mesh: None,
                });
                continue;
            }
            objects.push(ObjObject {
                name: m.name.clone(),
                topology: m.topology,
                mesh: Some(self.meshes.len()),
            });
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
                    return Err(p.err(
                        None,
                        format!(
                            "object `{}` of {} has no MTL material; give the shape a `material`",
                            m.name,
                            file.display()
                        ),
                    ))
                }
            };
            if bump.is_some() && m.uvs.is_empty() {
                return Err(p.err(
                    Some("bump"),
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
            return Err(p.err(
                Some("file"),
                format!("{} contains no (non-degenerate) triangles", file.display()),
            ));
        }
        Ok(objects)
    }
}

/// Every OBJ vertex, after the shape's transform, within ±[`MAX_MAGNITUDE`]. NaN
/// vertices are left to the degenerate-triangle filter, as documented.
fn check_obj_range(p: &Params, file: &Path, meshes: &[obj::ObjMesh]) -> crate::Result<()> {
    for m in meshes {
        let bad = m
            .positions
            .iter()
            .position(|&q| !q.is_nan() && !in_range(q));
        if let Some(i) = bad {
            let what = format!(
                "{}: vertex {} of object `{}`, after the shape's transform,",
                file.display(),
                i + 1,
                m.name
            );
            return Err(p.err(Some("file"), out_of_range(&what, m.positions[i])));
        }
    }
    Ok(())
}

/// The quad geometry keys shared by `quad` shapes and `rect` lights:
/// corner/edge_u/edge_v, or size (default [2, 2]) + transform.
fn rect_geometry(p: &Params, k: &ShapeKeys) -> crate::Result<(Vec3, Vec3, Vec3)> {
    let explicit = k.corner.is_some() || k.edge_u.is_some() || k.edge_v.is_some();
    let (c, u, v) = if explicit {
        if k.size.is_some() || k.transform.is_some() {
            return Err(p.err(
                None,
                "give either `corner`/`edge_u`/`edge_v` or `size`/`transform`, not both",
            ));
        }
        let need = |key: &str, v: Option<V3>| {
            v.map(Vec3::from).ok_or_else(|| {
                p.err(
                    None,
                    format!("`corner`, `edge_u` and `edge_v` go together; `{key}` is missing"),
                )
            })
        };
        let (c, u, v) = (
            need("corner", k.corner)?,
            need("edge_u", k.edge_u)?,
            need("edge_v", k.edge_v)?,
        );
        within_range(p, Some("corner"), "the corner", [c])?;
        within_range(p, Some("edge_u"), "the vertex", [c + u])?;
        within_range(p, Some("edge_v"), "the vertex", [c + v, c + u + v])?;
        (c, u, v)
    } else {
        let s = k.size.unwrap_or([2.0, 2.0]);
        let s = Vec2::new(positive(p, "size", s[0])?, positive(p, "size", s[1])?);
        let xf = k.transform.unwrap_or_else(Xform::identity);
        let (c, u, v) = geometry::rectangle_edges(&xf, s);
        let key = if k.transform.is_some() {
            "transform"
        } else {
            "size"
        };
        within_range(p, Some(key), "the vertex", [c, c + u, c + v, c + u + v])?;
        (c, u, v)
    };
    for (key, e) in [("edge_u", u), ("edge_v", v)] {
        if e == Vec3::ZERO {
            return Err(p.err(Some(key), format!("`{key}` must have non-zero length")));
        }
    }
    if cross(unit(u), unit(v)).length() <= 1e-7 {
        return Err(p.err(
            None,
            "`edge_u` and `edge_v` are parallel: the quad has no area",
        ));
    }
    // The renderer normalises edge_u × edge_v: its squared length must be a
    // normal f32, or the normal is NaN.
    if cross(u, v).length_squared() < f32::MIN_POSITIVE {
        return Err(p.err(None, "the quad is too small: its area underflows f32"));
    }
    Ok((c, u, v))
}

// ---------------------------------------------------------------------------
// The other tables.
// ---------------------------------------------------------------------------

fn settings(p: &Params) -> crate::Result<RenderSettings> {
    let d = RenderSettings::default();
    let spp = p.u32("spp")?;
    let max_depth = p.u32("max_depth")?;
    let seed = p.u32("seed")?;
    let integrator = p.choice(
        "integrator",
        &[("path", Integrator::Path), ("direct", Integrator::Direct)],
    )?;
    let rr_depth = p.u32("rr_depth")?;
    p.finish()?;
    let spp = spp.unwrap_or(d.spp);
    if spp == 0 {
        return Err(p.err(Some("spp"), "expected at least 1 sample per pixel, got 0"));
    }
    let max_depth = max_depth.unwrap_or(d.max_depth);
    if max_depth == 0 {
        return Err(p.err(
            Some("max_depth"),
            "expected at least 1 (1 = only directly visible emitters), got 0",
        ));
    }
    Ok(RenderSettings {
        spp,
        max_depth,
        seed: seed.unwrap_or(d.seed),
        integrator: integrator.unwrap_or(d.integrator),
        rr_depth: rr_depth.unwrap_or(d.rr_depth),
    })
}

fn camera_of(p: &Params) -> crate::Result<Camera> {
    let from = p.f32s::<3>("from")?;
    let to = p.f32s::<3>("to")?;
    let up = p.f32s::<3>("up")?;
    let fov = p.f32("fov")?;
    let resolution = p.u32_pair("resolution")?;
    p.finish()?;
    let from = Vec3::from(p.need("from", from)?);
    let to = Vec3::from(p.need("to", to)?);
    let up = Vec3::from(up.unwrap_or([0.0, 1.0, 0.0]));
    let fov = p.need("fov", fov)?;
    let [w, h] = p.need("resolution", resolution)?;
    within_range(p, Some("from"), "the camera position", [from])?;
    within_range(p, Some("to"), "the look-at point", [to])?;
    within_range(p, Some("up"), "the up vector", [up])?;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(p.err(
            Some("fov"),
            format!("expected the vertical field of view in degrees, in (0, 180), got {fov}"),
        ));
    }
    if w == 0 || h == 0 {
        return Err(p.err(
            Some("resolution"),
            format!("expected [width, height] of at least 1 pixel each, got [{w}, {h}]"),
        ));
    }
    if w > 65536 || h > 65536 || w as u64 * h as u64 > MAX_PIXELS {
        return Err(p.err(
            Some("resolution"),
            format!(
                "[{w}, {h}] is too large: at most 65536 pixels a side and {MAX_PIXELS} pixels in all"
            ),
        ));
    }
    Camera::new(from, to, up, fov, w, h).map_err(|m| p.err(None, m))
}

fn material_of(p: &Params) -> crate::Result<Material> {
    #[derive(Clone, Copy)]
    enum Kind {
        Lambert,
        BlinnPhong,
        CookTorrance,
        Mirror,
    }
    let kind = p.kind(&[
        ("lambert", Kind::Lambert),
        ("blinn_phong", Kind::BlinnPhong),
        ("cook_torrance", Kind::CookTorrance),
        ("mirror", Kind::Mirror),
    ])?;
    Ok(match kind {
        Kind::Lambert => {
            let albedo = colour(p, "albedo")?;
            p.finish()?;
            Material::Lambert {
                albedo: p.need("albedo", albedo)?,
            }
        }
        Kind::BlinnPhong | Kind::CookTorrance => {
            let kd = colour(p, "kd")?;
            let ks = colour(p, "ks")?;
            let exponent = p.f32("exponent")?;
            p.finish()?;
            let kd = p.need("kd", kd)?;
            let ks = p.need("ks", ks)?;
            let exponent = non_negative(p, "exponent", p.need("exponent", exponent)?)?;
            if matches!(kind, Kind::BlinnPhong) {
                Material::BlinnPhong { kd, ks, exponent }
            } else {
                Material::CookTorrance { kd, ks, exponent }
            }
        }
        Kind::Mirror => {
            let reflectance = colour(p, "reflectance")?;
            p.finish()?;
            Material::Mirror {
                reflectance: p.need("reflectance", reflectance)?,
            }
        }
    })
}

fn bump_of(name: &str, p: &Params) -> crate::Result<Bump> {
    p.kind(&[("sinusoids", ())])?;
    let terms = p.tables("terms")?;
    p.finish()?;
    let terms = p.need("terms", terms)?;
    if terms.is_empty() {
        return Err(p.err(Some("terms"), "expected at least one term"));
    }
    let mut out = Vec::with_capacity(terms.len());
    for t in &terms {
        let amplitude = t.f32("amplitude")?;
        let frequency = t.f32s::<2>("frequency")?;
        let phase = t.f32("phase")?;
        t.finish()?;
        out.push(Sinusoid {
            amplitude: t.need("amplitude", amplitude)?,
            frequency: Vec2::from(t.need("frequency", frequency)?),
            phase: phase.unwrap_or(0.0),
        });
    }
    Ok(Bump {
        name: name.to_string(),
        terms: out,
    })
}

fn environment_of(p: &Params) -> crate::Result<Environment> {
    #[derive(Clone, Copy)]
    enum Kind {
        Constant,
        Image,
        GaussianSky,
    }
    let kind = p.kind(&[
        ("constant", Kind::Constant),
        ("image", Kind::Image),
        ("gaussian_sky", Kind::GaussianSky),
    ])?;
    Ok(match kind {
        Kind::Constant => {
            let radiance = colour(p, "radiance")?;
            p.finish()?;
            Environment::Constant {
                radiance: p.need("radiance", radiance)?,
            }
        }
        Kind::Image => {
            let file = p.string("file")?;
            let scale = p.f32("scale")?;
            p.finish()?;
            let at = p.path("file");
            let file = p.ctx.asset(&at, p.need("file", file)?)?;
            let scale = non_negative(p, "scale", scale.unwrap_or(1.0))?;
            super::environment::load_latlong(&file, scale).map_err(|e| p.ctx.in_scene(&at, e))?
        }
        Kind::GaussianSky => {
            let direction = p.f32s::<3>("direction")?;
            let sharpness = p.f32("sharpness")?;
            let peak = colour(p, "peak")?;
            let ambient = colour(p, "ambient")?;
            p.finish()?;
            let direction = Vec3::from(direction.unwrap_or([0.0, 1.0, 0.0]));
            within_range(p, Some("direction"), "the direction", [direction])?;
            let direction = direction.normalize_or_zero();
            if direction == Vec3::ZERO {
                return Err(p.err(Some("direction"), "expected a non-zero direction"));
            }
            Environment::GaussianSky {
                direction,
                sharpness: non_negative(p, "sharpness", p.need("sharpness", sharpness)?)?,
                peak: p.need("peak", peak)?,
                ambient: ambient.unwrap_or(Vec3::ZERO),
            }
        }
    })
}
