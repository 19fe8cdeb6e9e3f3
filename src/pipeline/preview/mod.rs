//! Preview layers against the path-traced reference: precompute and shade with
//! `preview`, render the reference with `render`, score and write with `output`.

pub mod figures;
pub mod glossy;
pub mod shadow_field;

use crate::math::Vec3;
use crate::output::atomic::{SetIdHasher, StagedSet};
use crate::output::{ExrHeader, OutputImage};
use crate::pipeline::merge::attr;
use crate::scene::Scene;
use crate::Result;
use std::path::{Path, PathBuf};

/// Everything one preview run writes, gathered before anything is written, so
/// that all of it carries one render id and goes in place as one set (images
/// first, `preview.json` — the index — last: `output::atomic::StagedSet`).
#[derive(Default)]
pub(crate) struct PreviewSet {
    exrs: Vec<(PathBuf, OutputImage)>,
    pngs: Vec<(PathBuf, Vec<Vec3>, usize, usize)>,
    pages: Vec<(PathBuf, String)>,
}

impl PreviewSet {
    pub(crate) fn exr(&mut self, path: PathBuf, image: OutputImage) {
        self.exrs.push((path, image));
    }

    pub(crate) fn png(&mut self, path: PathBuf, rgb: Vec<Vec3>, width: usize, height: usize) {
        self.pngs.push((path, rgb, width, height));
    }

    /// A Markdown page; its id goes in as a final comment line.
    pub(crate) fn page(&mut self, path: PathBuf, text: String) {
        self.pages.push((path, text));
    }

    /// Writes the set with `index` (a JSON object) as `index_path`; every EXR
    /// gets `header`'s provenance. Returns the render id.
    pub(crate) fn write(
        self,
        index_path: &Path,
        index: serde_json::Value,
        header: &ExrHeader,
    ) -> Result<String> {
        // The id hashes every pixel and the summary: a rerun with other
        // settings, pixels or timings gets another id.
        let mut h = SetIdHasher::new();
        for (p, img) in &self.exrs {
            h.bytes(p.as_os_str().as_encoded_bytes()).image(img);
        }
        for (p, rgb, _, _) in &self.pngs {
            h.bytes(p.as_os_str().as_encoded_bytes()).rgb(rgb);
        }
        for (p, text) in &self.pages {
            h.bytes(p.as_os_str().as_encoded_bytes())
                .bytes(text.as_bytes());
        }
        h.bytes(index.to_string().as_bytes());
        let mut set = StagedSet::new(h.finish());
        for (p, img) in &self.exrs {
            set.stage_exr(p, img, header)?;
        }
        for (p, rgb, w, hgt) in &self.pngs {
            set.stage_png(p, rgb, *w, *hgt, 0.0)?;
        }
        for (p, text) in &self.pages {
            let text = format!("{text}\n<!-- render_id: {} -->\n", set.render_id());
            set.stage_bytes(p, text.as_bytes())?;
        }
        set.stage_index(index_path, index)?;
        let id = set.render_id().to_string();
        set.commit()?;
        Ok(id)
    }
}

/// The provenance attributes a preview's EXRs carry (those `render` writes that
/// apply: the reference's spp, the preview frame's time).
pub(crate) fn provenance(scene: &Scene, reference_spp: u32, frame_s: f64) -> Result<ExrHeader> {
    let mut attributes: Vec<(String, String)> = vec![
        (attr::VERSION.into(), super::VERSION.into()),
        (attr::COMMAND.into(), crate::pipeline::command_line()),
        (attr::SCENE_SHA256.into(), scene.content_hash()?),
        (attr::SPP.into(), reference_spp.to_string()),
        (attr::RENDER_TIME_S.into(), format!("{frame_s:.3}")),
    ];
    attributes.sort();
    Ok(ExrHeader {
        attributes,
        ..ExrHeader::default()
    })
}
