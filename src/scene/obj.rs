//! OBJ/MTL → world-space triangle meshes (tobj, triangulated, single index).
//!
//! MTL mapping: `Kd` → Lambert albedo; a non-zero `Ks` makes it a Blinn-Phong
//! material (kd = Kd, ks = Ks, exponent = Ns); `Ke` → emitted radiance (the mesh
//! becomes an area light). Texture maps and the other MTL keys are ignored.

use super::geometry::{filter_triangles, Xform};
use crate::brdf::Material;
use crate::math::{cross, Vec2, Vec3};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Kd when the MTL material does not give one (the MTL convention's default).
const DEFAULT_KD: f32 = 0.8;

/// A material read from an MTL file.
#[derive(Clone, Debug)]
pub(super) struct ObjMaterial {
    pub name: String,
    pub material: Material,
    pub emission: Vec3,
}

/// One OBJ object/group in world space, degenerate triangles removed.
#[derive(Clone, Debug)]
pub(super) struct ObjMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    /// Index into the returned material list.
    pub material: Option<usize>,
    pub degenerate: usize,
    /// As tobj read it, before the degenerate filter: what each frame of an
    /// `obj_sequence` must repeat.
    pub topology: Topology,
}

/// One OBJ object's vertex and triangle counts and a hash of its triangle
/// indices, as tobj read them (before the degenerate filter, which depends on
/// the positions and so may differ from frame to frame).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Topology {
    pub vertices: usize,
    pub triangles: usize,
    pub index_hash: u64,
}

impl Topology {
    fn of(m: &tobj::Mesh) -> Self {
        // FNV-1a over the index bytes: deterministic, and a mismatch only has to be
        // detected, not located.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for &i in &m.indices {
            for b in i.to_le_bytes() {
                h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
            }
        }
        Self {
            vertices: m.positions.len() / 3,
            triangles: m.indices.len() / 3,
            index_hash: h,
        }
    }
}

/// One object of a frame of an OBJ sequence: only what moves (its materials
/// and texture coordinates are the rest mesh's).
#[derive(Clone, Debug)]
pub(super) struct FrameObject {
    pub topology: Topology,
    /// World space (the shape's transform applied), as [`load`] maps them.
    pub positions: Vec<Vec3>,
    /// World-space vertex normals; empty when the file has none.
    pub normals: Vec<Vec3>,
}

fn asset_err(path: &Path, message: impl Into<String>) -> crate::Error {
    crate::Error::Asset {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

fn finite3(v: [f32; 3]) -> Option<Vec3> {
    let v = Vec3::from(v);
    v.is_finite().then_some(v)
}

/// Where material `name`'s `key` is set: the MTL file (of those the OBJ at `obj`
/// names) and the 1-based line. tobj does not say which library a material came
/// from, so an error about a value is located by reading them again.
fn locate_mtl_key(obj: &Path, name: &str, key: &str) -> Option<(PathBuf, usize)> {
    for lib in super::mtl_libraries(obj).ok()? {
        let text = std::fs::read_to_string(&lib).ok()?;
        let mut inside = false;
        for (i, line) in text.lines().enumerate() {
            let mut words = line.split_whitespace();
            match words.next() {
                Some("newmtl") => inside = words.collect::<Vec<_>>().join(" ") == name,
                Some(k) if inside && k == key => return Some((lib, i + 1)),
                _ => {}
            }
        }
    }
    None
}

/// An error about `key` of MTL material `name`, naming the MTL file and line where
/// they can be found (the error's path stays the OBJ the scene names).
fn mtl_value_err(obj: &Path, name: &str, key: &str, what: String) -> crate::Error {
    let place = match locate_mtl_key(obj, name, key) {
        Some((lib, line)) => format!("{} line {line}: ", lib.display()),
        None => String::new(),
    };
    asset_err(obj, format!("{place}material `{name}`: `{key}` {what}"))
}

/// Converts one MTL material; non-finite or negative values are an error rather
/// than a silent black or NaN surface.
fn convert_material(path: &Path, m: &tobj::Material) -> crate::Result<ObjMaterial> {
    let colour = |key: &str, v: Option<[f32; 3]>| -> crate::Result<Option<Vec3>> {
        match v {
            None => Ok(None),
            Some(c) => match finite3(c) {
                Some(c) if c.min_element() >= 0.0 => Ok(Some(c)),
                _ => Err(mtl_value_err(
                    path,
                    &m.name,
                    key,
                    format!("must be finite and non-negative, got {c:?}"),
                )),
            },
        }
    };
    let kd = colour("Kd", m.diffuse)?.unwrap_or(Vec3::splat(DEFAULT_KD));
    let ks = colour("Ks", m.specular)?.unwrap_or(Vec3::ZERO);
    let emission = colour("Ke", m.emissive)?.unwrap_or(Vec3::ZERO);
    let material = if ks == Vec3::ZERO {
        Material::Lambert { albedo: kd }
    } else {
        // MTL's default Ns is 0 (a cosine-free, i.e. uniform, lobe); keep it as is.
        let exponent = m.shininess.unwrap_or(0.0);
        if !(exponent.is_finite() && exponent >= 0.0) {
            return Err(mtl_value_err(
                path,
                &m.name,
                "Ns",
                format!("must be finite and non-negative, got {exponent}"),
            ));
        }
        Material::BlinnPhong { kd, ks, exponent }
    };
    Ok(ObjMaterial {
        name: m.name.clone(),
        material,
        emission,
    })
}

/// Peak bytes of loading an OBJ per byte of the file: tobj's vertex and index
/// lists, its single-index map and the mesh made from them. Measured as the
/// peak RSS of a render stopped right after the load (2026-12-05): a 68 MB
/// grid of 1 M vertices and 2 M triangles (six-digit coordinates) peaks at
/// 354 MB, 5.2×; shorter numbers raise the ratio a little, so 6 here.
const OBJ_LOAD_BYTES_PER_FILE_BYTE: u64 = 6;

/// Refuses, naming the file, an OBJ whose load would not fit the memory
/// available, or `--max-memory` when the run set it (`crate::memory::cap`,
/// `crate::memory::limited`): the allocator would otherwise stop the process
/// halfway through, or the kernel kill it.
fn check_obj_fits(path: &Path, file: &std::fs::File) -> crate::Result<()> {
    let size = file.metadata().map(|m| m.len()).unwrap_or(0);
    let need = size.saturating_mul(OBJ_LOAD_BYTES_PER_FILE_BYTE);
    let what = format!(
        "loading this {:.0} MiB OBJ",
        size as f64 / (1u64 << 20) as f64
    );
    match crate::memory::exceeds(need, crate::memory::limit(), &what) {
        Some(message) => Err(asset_err(
            path,
            format!("{message}; simplify the mesh or free memory"),
        )),
        None => Ok(()),
    }
}

/// Reads the OBJ at `path` with tobj, resolving each `mtllib` beside it as tobj
/// does, but remembering which MTL file failed so the message can name it.
fn read_obj(path: &Path) -> crate::Result<(Vec<tobj::Model>, Vec<tobj::Material>)> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let file = std::fs::File::open(path).map_err(|source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    check_obj_fits(path, &file)?;
    let _doing = crate::memory::doing(path, "loading the OBJ");
    let failed_mtl: RefCell<Option<(PathBuf, String)>> = RefCell::new(None);
    let dir = path.parent().unwrap_or(Path::new(""));
    let load_mtl = |name: &Path| {
        let mtl = dir.join(name);
        let result = match std::fs::metadata(&mtl) {
            Ok(m) if m.is_file() => tobj::load_mtl(&mtl).map_err(|e| (e, format!("{e}"))),
            Ok(m) => Err((
                tobj::LoadError::OpenFileFailed,
                format!("it is {}, not a regular file", crate::error::file_kind(&m)),
            )),
            Err(e) => Err((tobj::LoadError::OpenFileFailed, e.to_string())),
        };
        result.map_err(|(e, why)| {
            failed_mtl.borrow_mut().get_or_insert((mtl, why));
            e
        })
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut std::io::BufReader::new(file), &options, load_mtl)
            .map_err(|e| asset_err(path, format!("invalid OBJ: {e}")))?;
    // tobj reports a missing or malformed `mtllib` separately; an OBJ without any
    // `mtllib` gives an empty list, which is fine (the scene then names a material).
    let materials = materials.map_err(|e| match failed_mtl.take() {
        Some((mtl, why)) => asset_err(
            path,
            format!("cannot load its MTL library {}: {why}", mtl.display()),
        ),
        None => asset_err(path, format!("cannot load its MTL library: {e}")),
    })?;
    Ok((models, materials))
}

/// The vertex positions of a tobj mesh mapped through `xf`.
fn world_positions(m: &tobj::Mesh, xf: &Xform) -> Vec<Vec3> {
    m.positions
        .chunks_exact(3)
        .map(|p| xf.point(Vec3::new(p[0], p[1], p[2])))
        .collect()
}

/// The file's vertex normals in world space, or none when it has not one per vertex.
fn file_normals(
    m: &tobj::Mesh,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    xf: &Xform,
) -> Vec<Vec3> {
    if m.normals.len() != 3 * positions.len() {
        return Vec::new();
    }
    let raw: Vec<Vec3> = m
        .normals
        .chunks_exact(3)
        .map(|n| Vec3::new(n[0], n[1], n[2]))
        .collect();
    world_normals(&raw, positions, triangles, xf)
}

/// One frame of an OBJ sequence: each object's topology, world-space positions
/// and normals, read by the same tobj call as [`load`] (its MTL libraries
/// included, though only the rest mesh's materials are used).
pub(super) fn load_frame(path: &Path, xf: &Xform) -> crate::Result<Vec<FrameObject>> {
    let (models, _materials) = read_obj(path)?;
    Ok(models
        .into_iter()
        .map(|model| {
            let m = &model.mesh;
            let positions = world_positions(m, xf);
            // Filtered as in `load`, so that a frame equal to the rest mesh gets
            // its very normals (the fallback for a bad one sums these triangles).
            let raw = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]);
            let (triangles, _) = filter_triangles(&positions, raw, xf.mirrors());
            let normals = file_normals(m, &positions, &triangles, xf);
            FrameObject {
                topology: Topology::of(m),
                positions,
                normals,
            }
        })
        .collect())
}

/// Loads `path`, maps it through `xf` and drops degenerate triangles.
pub(super) fn load(path: &Path, xf: &Xform) -> crate::Result<(Vec<ObjMesh>, Vec<ObjMaterial>)> {
    let (models, materials) = read_obj(path)?;
    let materials = materials
        .iter()
        .map(|m| convert_material(path, m))
        .collect::<crate::Result<Vec<_>>>()?;

    let mut meshes = Vec::with_capacity(models.len());
    for model in models {
        let m = &model.mesh;
        let positions = world_positions(m, xf);
        let triangles = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]);
        let (triangles, degenerate) = filter_triangles(&positions, triangles, xf.mirrors());
        let uvs: Vec<Vec2> = if m.texcoords.len() == 2 * positions.len() {
            m.texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], t[1]))
                .collect()
        } else {
            Vec::new()
        };
        let normals = file_normals(m, &positions, &triangles, xf);
        if let Some(id) = m.material_id {
            if id >= materials.len() {
                return Err(asset_err(
                    path,
                    format!(
                        "object `{}` uses material #{id} but the MTL library defines {}",
                        model.name,
                        materials.len()
                    ),
                ));
            }
        }
        meshes.push(ObjMesh {
            name: model.name,
            positions,
            normals,
            uvs,
            triangles,
            material: m.material_id,
            degenerate,
            topology: Topology::of(m),
        });
    }
    Ok((meshes, materials))
}

/// Vertex normals in world space (inverse transpose, renormalised). A normal that
/// is zero or not finite is replaced by the area-weighted normal of the triangles
/// around its vertex, so the renderer never sees a NaN shading frame.
fn world_normals(
    raw: &[Vec3],
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    xf: &Xform,
) -> Vec<Vec3> {
    let mut out: Vec<Option<Vec3>> = raw.iter().map(|&n| xf.normal(n)).collect();
    if out.iter().any(Option::is_none) {
        let mut acc = vec![Vec3::ZERO; positions.len()];
        for t in triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let n = cross(b - a, c - a);
            for &i in t {
                acc[i as usize] += n;
            }
        }
        for (o, a) in out.iter_mut().zip(acc) {
            if o.is_none() {
                let n = a.normalize_or_zero();
                *o = Some(if n == Vec3::ZERO { Vec3::Y } else { n });
            }
        }
    }
    out.into_iter().map(|n| n.unwrap_or(Vec3::Y)).collect()
}

/// Area-weighted vertex normals for a mesh that has none (the `smooth_normals`
/// key). Vertices at bit-identical positions share one normal: OBJ exporters
/// often split vertices along texture seams or patch borders (the Utah teapot),
/// and unwelded normals would show those seams as creases.
pub(super) fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    // `+ 0.0` turns −0.0 into +0.0 so that both weld together.
    let key = |p: Vec3| {
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]
    };
    let mut groups: HashMap<[u32; 3], usize> = HashMap::with_capacity(positions.len());
    let group: Vec<usize> = positions
        .iter()
        .map(|&p| {
            let next = groups.len();
            *groups.entry(key(p)).or_insert(next)
        })
        .collect();
    let mut acc = vec![Vec3::ZERO; groups.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        // |cross| = twice the area: the sum is area-weighted.
        let n = cross(b - a, c - a);
        for &i in t {
            acc[group[i as usize]] += n;
        }
    }
    group
        .iter()
        .map(|&g| {
            let n = acc[g].normalize_or_zero();
            if n == Vec3::ZERO {
                Vec3::Y
            } else {
                n
            }
        })
        .collect()
}
