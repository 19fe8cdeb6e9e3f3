//! scene file (TOML) + OBJ/MTL → [`Scene`]: plain data in world space, indices not
//! pointers. Parsing and validation live in `parse`; everything downstream
//! (accel, render, output) reads only the types defined here.

pub mod animation;
pub mod bump;
pub mod camera;
mod describe;
pub mod environment;
pub mod generate;
mod geometry;
mod locate;
mod obj;
mod params;
mod parse;

use crate::brdf::Material;
use crate::math::{cross, Vec2, Vec3};
use std::path::{Path, PathBuf};

pub use bump::Bump;
pub use camera::Camera;
pub use environment::Environment;
pub use parse::{MAX_PIXELS, MAX_SCENE_BYTES};

/// The largest coordinate magnitude a scene may hold: every position, radius,
/// extent (after transforms, OBJ vertices included) and camera coordinate lies
/// within ±1e12, or loading fails naming the key and this limit. It keeps every
/// product the renderer and the BVH form (squared distances, cross products of
/// edges) far inside the f32 range (1e12² = 1e24 ≪ 3.4e38), which the
/// acceleration structure relies on.
pub const MAX_MAGNITUDE: f32 = 1e12;

/// Loads a scene file and every asset it references. Errors name the file, the key
/// (and line when known) and what was expected.
pub fn load(path: &Path) -> crate::Result<Scene> {
    parse::load_scene(path)
}

/// Parses a scene from TOML text; `path` is used for error messages and as the base
/// directory of relative asset paths.
pub fn load_from_str(text: &str, path: &Path) -> crate::Result<Scene> {
    parse::scene_from_str(text, path)
}

/// The MTL files an OBJ names with `mtllib` that exist beside it (tobj reads
/// them itself, so the parser never sees their paths). Like tobj, the rest of the
/// line is one file name (spaces included).
fn mtl_libraries(obj: &Path) -> crate::Result<Vec<PathBuf>> {
    let text = std::fs::read(obj).map_err(|source| crate::Error::Io {
        path: obj.to_path_buf(),
        source,
    })?;
    let dir = obj.parent().unwrap_or(Path::new(""));
    Ok(String::from_utf8_lossy(&text)
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("mtllib"))
        .filter(|rest| rest.starts_with(char::is_whitespace))
        .map(|rest| dir.join(rest.trim()))
        .filter(|p| p.is_file())
        .collect())
}

/// Which estimator the renderer runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Unidirectional path tracing with next-event estimation and MIS.
    Path,
    /// Direct lighting only (one bounce of emitted light, with MIS); later stages
    /// analyse exactly this quantity.
    Direct,
}

impl Integrator {
    pub const ALL: [Integrator; 2] = [Integrator::Path, Integrator::Direct];

    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Path => "path",
            Integrator::Direct => "direct",
        }
    }
}

/// The `[render]` table: defaults that command-line options may override.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub spp: u32,
    /// Longest path, in segments from the camera (1 = only directly visible emitters).
    pub max_depth: u32,
    pub seed: u32,
    pub integrator: Integrator,
    /// Path depth from which Russian roulette may terminate paths.
    pub rr_depth: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            spp: 16,
            max_depth: 8,
            seed: 0,
            integrator: Integrator::Path,
            rr_depth: 5,
        }
    }
}

/// A rectangle `corner + s·edge_u + t·edge_v`, s,t ∈ \[0,1\]; kept for rectangular
/// area lights whose analytic form later stages need (solid angle, edges).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
}

impl Rect {
    pub fn normal(&self) -> Vec3 {
        cross(self.edge_u, self.edge_v).normalize()
    }
    pub fn area(&self) -> f32 {
        cross(self.edge_u, self.edge_v).length()
    }
}

/// A triangle mesh in world space. Quads (rectangles) are two-triangle meshes
/// with `rect` set; OBJ files give one mesh per OBJ object/group.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (world space, unit); empty when the mesh has none.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates; empty when the mesh has none. They are the
    /// (u, v) parameterisation of the bump map.
    pub uvs: Vec<Vec2>,
    /// Non-degenerate triangles only (degenerate ones are dropped at load time and
    /// counted in [`SceneStats::degenerate_triangles`]).
    pub triangles: Vec<[u32; 3]>,
    pub material: u32,
    /// Emitted radiance L_e (zero: not an emitter). Emission is one-sided, on the
    /// side the geometric normal points to (counter-clockwise winding).
    pub emission: Vec3,
    pub bump: Option<u32>,
    pub rect: Option<Rect>,
    /// 1-based id of the scene-file shape this mesh came from (0 = background).
    pub object_id: u32,
}

/// An exact analytic sphere (never tessellated). Its bump map, if any, is
/// parameterised by (u, v) = (φ / 2π, θ / π) with θ measured from +y.
#[derive(Clone, Debug)]
pub struct Sphere {
    pub name: String,
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
    /// Emitted radiance L_e on the outside (zero: not an emitter).
    pub emission: Vec3,
    pub bump: Option<u32>,
    pub object_id: u32,
}

/// What loading found and dropped; `info` prints it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneStats {
    pub triangles: usize,
    pub degenerate_triangles: usize,
    pub meshes_with_normals: usize,
}

/// A loaded scene. Shapes reference materials and bump maps by index.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file, for messages and for naming outputs.
    pub path: PathBuf,
    /// Every file the scene file references (meshes, environment maps), in the
    /// order it names them; with `path` and the OBJs' MTL libraries these are the
    /// inputs [`Scene::content_hash`] covers.
    pub assets: Vec<PathBuf>,
    pub camera: Camera,
    pub settings: RenderSettings,
    pub materials: Vec<Material>,
    pub material_names: Vec<String>,
    pub meshes: Vec<Mesh>,
    pub spheres: Vec<Sphere>,
    pub bumps: Vec<Bump>,
    pub environment: Option<Environment>,
    /// Names of the scene-file shapes, indexed by `object_id - 1`.
    pub object_names: Vec<String>,
    pub stats: SceneStats,
    /// The `[animation]` block, if any (`preview shadow-field --frames`).
    pub animation: Option<animation::Animation>,
    /// [`Scene::content_hash`], once computed (`Default` when building a scene).
    pub content_hash_memo: ContentHashMemo,
}

/// The content hash, computed once per loaded scene: it re-reads every input
/// file, and a run asks for it at each cache lookup and header it writes.
#[derive(Clone, Debug, Default)]
pub struct ContentHashMemo(std::sync::OnceLock<String>);

impl Scene {
    /// The scene's name: the file stem (`scenes/cornell.toml` → `cornell`).
    pub fn name(&self) -> String {
        self.path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into())
    }

    /// SHA-256 (hex) of everything the image depends on that lives in files: the
    /// scene file's bytes and those of every asset it references, including the
    /// MTL libraries of its OBJs. Keys caches (references, precomputed fields) so
    /// that an edited input is never answered from a stale file. Paths enter only
    /// relative to the scene's folder, so a moved project keeps its caches.
    /// Memoised: the files are read at the first call (`path` and `assets`
    /// do not change after loading).
    pub fn content_hash(&self) -> crate::Result<String> {
        if let Some(h) = self.content_hash_memo.0.get() {
            return Ok(h.clone());
        }
        let h = self.hash_files()?;
        Ok(self.content_hash_memo.0.get_or_init(|| h).clone())
    }

    fn hash_files(&self) -> crate::Result<String> {
        use sha2::{Digest, Sha256};
        let base = self.path.parent().unwrap_or(Path::new(""));
        let mut files = vec![self.path.clone()];
        for a in &self.assets {
            files.push(a.clone());
            if a.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) {
                files.extend(mtl_libraries(a)?);
            }
        }
        let mut h = Sha256::new();
        for f in &files {
            let bytes = std::fs::read(f).map_err(|source| crate::Error::Io {
                path: f.clone(),
                source,
            })?;
            let name = f.strip_prefix(base).unwrap_or(f).to_string_lossy();
            // Length-prefixed fields: no two different file lists hash alike.
            for field in [name.as_bytes(), &bytes] {
                h.update((field.len() as u64).to_le_bytes());
                h.update(field);
            }
        }
        Ok(crate::hex(&h.finalize()))
    }

    pub fn emitter_count(&self) -> usize {
        self.meshes
            .iter()
            .filter(|m| m.emission != Vec3::ZERO)
            .count()
            + self
                .spheres
                .iter()
                .filter(|s| s.emission != Vec3::ZERO)
                .count()
    }
}
