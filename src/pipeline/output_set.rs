//! What a run writes: the planes of a render or a reconstruction as one
//! [`OutputImage`], and the EXR + PNG pair written as a set through `output`.

use crate::math::Vec3;
use crate::output::names::*;
use crate::output::{self, ExrHeader, OutputImage};
use crate::reconstruct::Reconstruction;
use crate::render::RenderOutput;
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// The beauty (`R,G,B`) and every AOV plane the render produced (`normal.X/Y/Z`,
/// `depth.Z`, `albedo.R/G/B`, `object.id`, `variance.R/G/B`, and for gradient
/// renders `grad.u.R/G/B`, `grad.v.R/G/B` and the term magnitudes
/// `grad.{sv,dv,cv,cdv,vis,indirect,ratio}.Y`).
pub fn image_of_render(render: &RenderOutput) -> OutputImage {
    let mut img = OutputImage::new(render.width, render.height);
    img.push_vec3("", RGB, &render.beauty);
    if let Some(n) = &render.normal {
        img.push_vec3(NORMAL, XYZ, n);
    }
    if let Some(d) = &render.depth {
        img.push_scalar(DEPTH, d.clone());
    }
    if let Some(a) = &render.albedo {
        img.push_vec3(ALBEDO, RGB, a);
    }
    if let Some(id) = &render.object_id {
        img.push_scalar(OBJECT_ID, id.clone());
    }
    if let Some(v) = &render.variance {
        img.push_vec3(VARIANCE, RGB, v);
    }
    if let Some(g) = &render.gradients {
        img.push_vec3(GRAD_U, RGB, &g.grad_u);
        img.push_vec3(GRAD_V, RGB, &g.grad_v);
        let terms = [&g.sv, &g.dv, &g.cv, &g.cdv, &g.vis, &g.indirect, &g.ratio];
        for (name, plane) in GRAD_TERMS.iter().zip(terms) {
            img.push_scalar(name, plane.clone());
        }
    }
    if let Some(spp) = &render.spp_map {
        img.push_scalar(super::merge::SAMPLES_SPP, spp.clone());
    }
    if let Some(m) = &render.merge {
        super::merge::push_merge_planes(&mut img, m);
    }
    img
}

/// The reconstructed `R,G,B`, `samples.density` (samples per pixel) and
/// `samples.Y` (1 where a pixel holds at least one sample: Fig. 14/15's dots).
pub fn image_of_reconstruction(rec: &Reconstruction) -> OutputImage {
    let mut img = OutputImage::new(rec.width, rec.height);
    img.push_vec3("", RGB, &rec.image);
    img.push_scalar(SAMPLES_DENSITY, rec.density.clone());
    img.push_scalar(
        SAMPLES_Y,
        rec.density
            .iter()
            .map(|&d| if d > 0.0 { 1.0 } else { 0.0 })
            .collect(),
    );
    img
}

/// The EXR and PNG paths of a run: `out` names the EXR (default
/// `out/<scene_stem>.exr`), the PNG shares its stem.
pub fn output_paths(out: Option<&Path>, scene_stem: &str) -> Result<(PathBuf, PathBuf)> {
    let exr = match out {
        Some(p) => p.to_path_buf(),
        None => Path::new("out").join(format!("{scene_stem}.exr")),
    };
    let option_err = |message: String| Error::Option {
        option: "--out".into(),
        message,
    };
    if exr.file_name().is_none() {
        return Err(option_err(format!(
            "{}: does not name a file",
            exr.display()
        )));
    }
    let png = exr.with_extension("png");
    if png == exr {
        return Err(option_err(format!(
            "{}: names the PNG; give the EXR path (e.g. {})",
            exr.display(),
            exr.with_extension("exr").display()
        )));
    }
    for p in [&exr, &png] {
        if p.is_dir() {
            return Err(Error::Output {
                path: p.clone(),
                message: "is a directory".into(),
            });
        }
        output::input::check_output_target(p, "--out")?;
    }
    Ok((exr, png))
}

/// Writes `image` to `exr` and its beauty `beauty` tone-mapped to `png` as one
/// set: both files are encoded to anonymous temporary files first and put in
/// place only when both encodes succeeded, so a failure of either leaves every
/// previous output untouched; both carry one render id. Creates the output directory when missing and removes what
/// it created again if the write then fails.
pub fn write_output_set(
    image: &OutputImage,
    beauty: &[Vec3],
    exr: &Path,
    png: &Path,
) -> Result<()> {
    write_output_set_with_header(image, &ExrHeader::default(), beauty, exr, png)
}

/// [`write_output_set`] with an EXR header (data window, provenance attributes).
pub fn write_output_set_with_header(
    image: &OutputImage,
    header: &ExrHeader,
    beauty: &[Vec3],
    exr: &Path,
    png: &Path,
) -> Result<()> {
    let dir = exr.parent().filter(|d| !d.as_os_str().is_empty());
    let created = match dir {
        Some(d) => create_dirs(d)?,
        None => Vec::new(),
    };
    // One render id in both files, the PNG renamed first: a kill between the two
    // renames leaves a pair that `output::atomic::check_pair` reports as mismatched.
    let result = output::atomic::stage_pair(exr, image, header, png, beauty, 0.0)
        .and_then(|pair| pair.commit());
    if result.is_err() {
        // Innermost first; `remove_dir` only removes empty directories.
        for d in created.iter().rev() {
            let _ = std::fs::remove_dir(d);
        }
    }
    result
}

/// `create_dir_all` that returns the directories it created, outermost first.
fn create_dirs(dir: &Path) -> Result<Vec<PathBuf>> {
    let missing: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
        .map(Path::to_path_buf)
        .collect();
    // The first ancestor that exists must be a folder ("File exists" would hide it).
    if let Some(blocker) = dir.ancestors().find(|a| a.exists()).filter(|a| !a.is_dir()) {
        return Err(Error::Output {
            path: blocker.to_path_buf(),
            message: "is a file, not a folder: cannot create the output folder inside it".into(),
        });
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::Output {
        path: dir.to_path_buf(),
        message: format!("cannot create the output directory: {e}"),
    })?;
    Ok(missing.into_iter().rev().collect())
}
