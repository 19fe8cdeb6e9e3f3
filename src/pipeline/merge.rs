//! `gradtrace merge`: EXR parts of one render (tiles, sample ranges) → the
//! whole render's EXR + PNG.
//!
//! Tiles are copied bit for bit into their place. Sample ranges of one tile are
//! combined from their statistics, in f64, each weighted by its sample count:
//! means (beauty, albedo, gradients) linearly; the variance of the mean by Chan et
//! al.'s parallel formula (M2 = Σ M2ᵢ + Σ nᵢ (mᵢ − m)², with M2ᵢ = Vᵢ nᵢ (nᵢ − 1));
//! normals from their unnormalised sums (`merge.normal_len`), depth over the
//! samples that hit (`merge.hits`), the gradient term magnitudes from the
//! luminances of their mean u and v components (`merge.grad.*`); the object id is
//! the lowest range's (the render's first sample). The result equals the one-pass
//! render up to rounding: see `tests/scale_out.rs` for the bounds.

use super::output_set::write_output_set_with_header;
use crate::output::names::{GRAD_TERMS, RGB};
use crate::output::{read_exr_input, Channel, ExrHeader, OutputImage};
use crate::render::{Crop, MergePlanes, GRAD_TERM_LUMINANCES};
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Per-pixel sample counts of a noise-adaptive render.
pub const SAMPLES_SPP: &str = "samples.spp";
/// Samples whose camera ray hit a surface.
pub const MERGE_HITS: &str = "merge.hits";
/// |Σ normal| / n.
pub const MERGE_NORMAL_LEN: &str = "merge.normal_len";
/// Prefix of the gradient terms' mean luminances (`merge.grad.sv.u`, ...).
pub const MERGE_GRAD: &str = "merge.grad.";

/// The provenance attributes every EXR header carries.
pub mod attr {
    pub const VERSION: &str = "gradtrace.version";
    pub const COMMAND: &str = "gradtrace.command";
    pub const SCENE_SHA256: &str = "gradtrace.scene_sha256";
    pub const SPP: &str = "gradtrace.spp";
    pub const SPP_RANGE: &str = "gradtrace.spp_range";
    pub const SEED: &str = "gradtrace.seed";
    pub const RENDER_TIME_S: &str = "gradtrace.render_time_s";
    /// Everything else that must agree between parts ([`RenderOptions::settings_key`]).
    ///
    /// [`RenderOptions::settings_key`]: crate::render::RenderOptions::settings_key
    pub const SETTINGS: &str = "gradtrace.settings";
}

/// Adds the `merge.*` planes to an image.
pub fn push_merge_planes(img: &mut OutputImage, m: &MergePlanes) {
    img.push_scalar(MERGE_HITS, m.hits.clone());
    img.push_scalar(MERGE_NORMAL_LEN, m.normal_len.clone());
    if let Some(terms) = &m.grad_terms {
        for (k, name) in GRAD_TERM_LUMINANCES.iter().enumerate() {
            let plane = terms.iter().map(|t| t[k]).collect();
            img.push_scalar(&format!("{MERGE_GRAD}{name}"), plane);
        }
    }
}

/// One part: an EXR written by `gradtrace render` (or `merge`) and its header.
#[derive(Clone, Debug)]
pub struct Part {
    pub path: PathBuf,
    pub image: OutputImage,
    pub header: ExrHeader,
}

impl Part {
    pub fn read(path: &Path) -> Result<Self> {
        Self::read_input(path, &[])
    }

    /// Reads a part of a command that writes `outputs` (none of which it may
    /// be), refusing a non-finite value here, where the part can be named: left
    /// to the EXR writer it was blamed on the output.
    pub fn read_input(path: &Path, outputs: &[&Path]) -> Result<Self> {
        let (image, header) = read_exr_input(path, outputs)?;
        let part = Self {
            path: path.to_path_buf(),
            image,
            header,
        };
        let w = part.image.width.max(1);
        let (x0, y0) = part.header.origin;
        for ch in &part.image.channels {
            if let Some(i) = ch.data.iter().position(|v| !v.is_finite()) {
                return Err(Error::Asset {
                    path: part.path.clone(),
                    message: format!(
                        "channel {:?} holds {} at pixel ({}, {}) of the image; expected finite values",
                        ch.name,
                        ch.data[i],
                        x0 + i % w,
                        y0 + i / w
                    ),
                });
            }
        }
        Ok(part)
    }

    fn error(&self, message: String) -> Error {
        Error::Merge {
            path: self.path.clone(),
            message,
        }
    }

    /// A provenance attribute, required.
    pub fn attr(&self, name: &str) -> Result<&str> {
        self.header.get(name).ok_or_else(|| {
            self.error(format!(
                "no {name} attribute in the header: not a part written by gradtrace render"
            ))
        })
    }

    /// The sample indices A..B this part holds.
    pub fn range(&self) -> Result<(u32, u32)> {
        let text = self.attr(attr::SPP_RANGE)?;
        parse_range(text)
            .ok_or_else(|| self.error(format!("{}: expected A:B, got {text:?}", attr::SPP_RANGE)))
    }

    /// The pixels this part covers in the full image.
    pub fn window(&self) -> Crop {
        let (x0, y0) = (self.header.origin.0 as u32, self.header.origin.1 as u32);
        Crop {
            x0,
            y0,
            x1: x0 + self.image.width as u32,
            y1: y0 + self.image.height as u32,
        }
    }

    /// The full image's size.
    pub fn display(&self) -> (usize, usize) {
        self.header.display_or(self.image.width, self.image.height)
    }
}

/// `A:B` with A < B.
pub fn parse_range(text: &str) -> Option<(u32, u32)> {
    let (a, b) = text.split_once(':')?;
    let (a, b) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
    (a < b).then_some((a, b))
}

/// One `merge` run as the command line describes it.
#[derive(Clone, Debug)]
pub struct MergeJob {
    pub parts: Vec<PathBuf>,
    pub out: PathBuf,
    /// The command line, for the header.
    pub command: String,
}

/// What a merge did, for the summary line.
#[derive(Clone, Debug)]
pub struct MergeSummary {
    pub parts: usize,
    pub tiles: usize,
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    pub exr: PathBuf,
    pub png: PathBuf,
}

/// "s" unless there is exactly one.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

impl std::fmt::Display for MergeSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "merged {} part{} ({} tile{}) into {}x{}, {} spp, wrote {} and {}",
            self.parts,
            plural(self.parts),
            self.tiles,
            plural(self.tiles),
            self.width,
            self.height,
            self.spp,
            self.exr.display(),
            self.png.display()
        )
    }
}

/// Reads every part, checks that they fit together and writes the merged EXR +
/// PNG; nothing is written when any check fails.
pub fn run(job: &MergeJob) -> Result<MergeSummary> {
    let (exr, png) = super::output_set::output_paths(Some(&job.out), "merged")?;
    let parts = job
        .parts
        .iter()
        .map(|p| Part::read_input(p, &[&exr, &png]))
        .collect::<Result<Vec<_>>>()?;
    let merged = merge_parts(&parts, &exr, &job.command)?;
    let beauty = merged.image.vec3("", RGB).unwrap_or_default();
    write_output_set_with_header(&merged.image, &merged.header, &beauty, &exr, &png)?;
    let tiles = group_by_window(&parts).len();
    Ok(MergeSummary {
        parts: parts.len(),
        tiles,
        width: merged.image.width,
        height: merged.image.height,
        spp: merged
            .header
            .get(attr::SPP)
            .and_then(|s| s.parse().ok())
            .unwrap_or(0),
        exr,
        png,
    })
}

/// The merged image and its header. `out` only names the result in errors.
#[derive(Clone, Debug)]
pub struct Merged {
    pub image: OutputImage,
    pub header: ExrHeader,
}

/// Merges `parts` (tiles, each as one or several sample ranges) into the whole
/// image: the checks first (same scene, settings, seed, display window and
/// channels; sample ranges of a tile disjoint and contiguous, the same for every
/// tile; tiles covering the image exactly once), then the combination.
pub fn merge_parts(parts: &[Part], out: &Path, command: &str) -> Result<Merged> {
    merge(parts, out, command, true)
}

/// Sample ranges of one tile (or of the whole image) merged into that tile:
/// what `render --resume` does with the file it continues.
pub fn merge_sample_ranges(parts: &[Part], out: &Path, command: &str) -> Result<Merged> {
    if let Some(p) = parts.iter().find(|p| p.window() != parts[0].window()) {
        return Err(p.error(format!(
            "covers pixels {} but {} covers {}",
            p.window(),
            parts[0].path.display(),
            parts[0].window()
        )));
    }
    merge(parts, out, command, false)
}

fn merge(parts: &[Part], out: &Path, command: &str, whole_image: bool) -> Result<Merged> {
    let first = parts.first().ok_or_else(|| Error::Merge {
        path: out.to_path_buf(),
        message: "no parts given".into(),
    })?;
    check_same_render(parts)?;
    let groups = group_by_window(parts);
    let mut range = None;
    let mut tiles = Vec::new();
    for group in &groups {
        let r = check_ranges(group)?;
        match range {
            None => range = Some((r, group[0])),
            Some((r0, p0)) if r0 != r => {
                return Err(group[0].error(format!(
                    "its tile holds samples {}:{} but {} (another tile) holds {}:{}",
                    r.0,
                    r.1,
                    p0.path.display(),
                    r0.0,
                    r0.1
                )))
            }
            Some(_) => {}
        }
        tiles.push((group[0].window(), combine_ranges(group)?));
    }
    let (range, _) = range.expect("at least one part");
    let display = first.display();
    let (image, origin) = if whole_image {
        check_coverage(&groups, display, out)?;
        (assemble(&tiles, display), (0, 0))
    } else {
        let (_, image) = tiles.pop().expect("one tile");
        (image, first.header.origin)
    };
    let seconds: f64 = parts
        .iter()
        .filter_map(|p| p.header.get(attr::RENDER_TIME_S)?.parse::<f64>().ok())
        .sum();
    let mut attributes = vec![
        (attr::VERSION.into(), super::VERSION.into()),
        (attr::COMMAND.into(), command.into()),
        (attr::SPP.into(), (range.1 - range.0).to_string()),
        (attr::SPP_RANGE.into(), format!("{}:{}", range.0, range.1)),
        (attr::RENDER_TIME_S.into(), format!("{seconds:.3}")),
    ];
    for name in [attr::SCENE_SHA256, attr::SEED, attr::SETTINGS] {
        attributes.push((name.into(), first.attr(name)?.into()));
    }
    attributes.sort();
    let header = ExrHeader {
        display,
        origin,
        attributes,
    };
    Ok(Merged { image, header })
}

/// Every part of the same scene, settings, seed, image size and channels as the first.
fn check_same_render(parts: &[Part]) -> Result<()> {
    let first = &parts[0];
    let names = |p: &Part| {
        let mut n: Vec<String> = p.image.channels.iter().map(|c| c.name.clone()).collect();
        n.sort();
        n
    };
    for p in parts {
        for (name, what) in [
            (
                attr::SCENE_SHA256,
                "a different scene (scene file or assets differ)",
            ),
            (attr::SETTINGS, "different settings"),
            (attr::SEED, "a different seed"),
        ] {
            let (a, b) = (p.attr(name)?, first.attr(name)?);
            if a != b {
                return Err(p.error(format!(
                    "rendered with {what} than {}: {name} is {a:?} here, {b:?} there",
                    first.path.display()
                )));
            }
        }
        if p.display() != first.display() {
            return Err(p.error(format!(
                "image size {:?} differs from {}'s {:?}",
                p.display(),
                first.path.display(),
                first.display()
            )));
        }
        if names(p) != names(first) {
            return Err(p.error(format!(
                "holds channels {:?}, but {} holds {:?}",
                names(p),
                first.path.display(),
                names(first)
            )));
        }
        if p.image.channel(SAMPLES_SPP).is_some() {
            return Err(p.error(
                "a noise-adaptive render (samples.spp): its pixels have different sample counts and do not merge".into(),
            ));
        }
        p.range()?;
    }
    Ok(())
}

/// The parts grouped by the pixels they cover, in order of first appearance.
fn group_by_window(parts: &[Part]) -> Vec<Vec<&Part>> {
    let mut groups: Vec<Vec<&Part>> = Vec::new();
    for p in parts {
        match groups.iter_mut().find(|g| g[0].window() == p.window()) {
            Some(g) => g.push(p),
            None => groups.push(vec![p]),
        }
    }
    groups
}

/// The sample ranges of one tile, sorted: disjoint and without gaps. Returns
/// their union.
fn check_ranges(group: &[&Part]) -> Result<(u32, u32)> {
    let mut sorted: Vec<(&Part, (u32, u32))> = Vec::new();
    for p in group {
        sorted.push((p, p.range()?));
    }
    sorted.sort_by_key(|(_, r)| *r);
    for pair in sorted.windows(2) {
        let ((p, a), (q, b)) = (pair[0], pair[1]);
        let clash = |what: &str| {
            q.error(format!(
                "its samples {}:{} {what} {}'s {}:{} (same tile)",
                b.0,
                b.1,
                p.path.display(),
                a.0,
                a.1
            ))
        };
        if b.0 < a.1 {
            return Err(clash("overlap"));
        }
        if b.0 > a.1 {
            return Err(clash(&format!(
                "leave samples {}:{} missing after",
                a.1, b.0
            )));
        }
    }
    Ok((sorted[0].1 .0, sorted[sorted.len() - 1].1 .1))
}

/// The tiles cover the `display` image exactly once. Found from the tiles'
/// rectangles alone, without a per-pixel map: a header may claim a display
/// window of 2²⁸ pixels around a one-pixel tile, and the map was allocated
/// before the gap was found.
fn check_coverage(groups: &[Vec<&Part>], display: (usize, usize), out: &Path) -> Result<()> {
    let (w, h) = display;
    let tiles: Vec<(&Part, Crop)> = groups.iter().map(|g| (g[0], g[0].window())).collect();
    let mut area = 0u64;
    for (k, (part, c)) in tiles.iter().enumerate() {
        if c.x1 as usize > w || c.y1 as usize > h {
            return Err(part.error(format!("its tile {c} lies outside the {w}x{h} image")));
        }
        for (other, o) in &tiles[..k] {
            let (x, y) = (c.x0.max(o.x0), c.y0.max(o.y0));
            if x < c.x1.min(o.x1) && y < c.y1.min(o.y1) {
                return Err(part.error(format!(
                    "its tile {c} overlaps {}'s tile {o} (pixel ({x}, {y}) is in both)",
                    other.path.display()
                )));
            }
        }
        area += u64::from(c.width()) * u64::from(c.height());
    }
    let total = w as u64 * h as u64;
    if area == total {
        return Ok(());
    }
    // Disjoint tiles inside the image with less area: some pixel is missing.
    // The first in row-major order starts a row (x = 0) or follows a tile
    // (x = its x1), on the first row (y = 0) or below a tile (y = its y1).
    let covered = |x: u32, y: u32| {
        tiles
            .iter()
            .any(|(_, c)| c.x0 <= x && x < c.x1 && c.y0 <= y && y < c.y1)
    };
    let xs = std::iter::once(0).chain(tiles.iter().map(|(_, c)| c.x1));
    let ys = std::iter::once(0).chain(tiles.iter().map(|(_, c)| c.y1));
    let first = ys
        .flat_map(|y| xs.clone().map(move |x| (y, x)))
        .filter(|&(y, x)| (x as usize) < w && (y as usize) < h && !covered(x, y))
        .min()
        .unwrap_or((0, 0));
    Err(Error::Merge {
        path: out.to_path_buf(),
        message: format!(
            "the parts leave {} of the {w}x{h} pixels uncovered, the first at ({}, {}): a tile is missing",
            total - area,
            first.1,
            first.0
        ),
    })
}

/// The tiles pasted into one `display`-sized image (the channels of the first).
fn assemble(tiles: &[(Crop, OutputImage)], display: (usize, usize)) -> OutputImage {
    let (w, h) = display;
    let mut out = OutputImage::new(w, h);
    for ch in &tiles[0].1.channels {
        let mut data = vec![0.0f32; w * h];
        for (c, img) in tiles {
            let src = &img.channel(&ch.name).expect("same channels, checked").data;
            let tw = img.width;
            for y in 0..img.height {
                let dst = (c.y0 as usize + y) * w + c.x0 as usize;
                data[dst..dst + tw].copy_from_slice(&src[y * tw..(y + 1) * tw]);
            }
        }
        out.push_scalar(&ch.name, data);
    }
    out
}

/// The sample ranges of one tile as one image (one part: itself, bit for bit).
fn combine_ranges(group: &[&Part]) -> Result<OutputImage> {
    if group.len() == 1 {
        return Ok(group[0].image.clone());
    }
    let mut sorted: Vec<&Part> = group.to_vec();
    sorted.sort_by_key(|p| p.range().map(|r| r.0).unwrap_or(0));
    let counts: Vec<f64> = sorted
        .iter()
        .map(|p| p.range().map(|(a, b)| (b - a) as f64))
        .collect::<Result<_>>()?;
    let total: f64 = counts.iter().sum();
    let img0 = &sorted[0].image;
    let n = img0.width * img0.height;
    let plane = |p: &Part, name: &str| -> Result<Vec<f64>> {
        p.image
            .channel(name)
            .map(|c| c.data.iter().map(|&v| v as f64).collect())
            .ok_or_else(|| {
                p.error(format!(
                    "no {name} channel, which merging sample ranges needs (render the ranges with --spp-range)"
                ))
            })
    };
    // Σ nᵢ xᵢ / Σ nᵢ over the parts, per pixel.
    let mean = |name: &str| -> Result<Vec<f64>> {
        let mut acc = vec![0.0f64; n];
        for (p, &c) in sorted.iter().zip(&counts) {
            for (a, v) in acc.iter_mut().zip(plane(p, name)?) {
                *a += c * v;
            }
        }
        Ok(acc.into_iter().map(|a| a / total).collect())
    };
    let mut merged: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for ch in &img0.channels {
        let name = ch.name.as_str();
        let data = match name {
            "object.id" => plane(sorted[0], name)?,
            MERGE_HITS => {
                let mut acc = vec![0.0f64; n];
                for p in &sorted {
                    for (a, v) in acc.iter_mut().zip(plane(p, name)?) {
                        *a += v;
                    }
                }
                acc
            }
            _ if is_linear_mean(name) => mean(name)?,
            _ => continue,
        };
        merged.insert(name.to_string(), data);
    }
    combine_variance(&sorted, &counts, &mut merged, &plane)?;
    combine_normal_and_depth(&sorted, &counts, &mut merged, &plane)?;
    combine_gradient_terms(&mut merged);
    let mut out = OutputImage::new(img0.width, img0.height);
    for ch in &img0.channels {
        let data = merged.get(&ch.name).ok_or_else(|| {
            sorted[0].error(format!(
                "channel {:?} cannot be combined across sample ranges",
                ch.name
            ))
        })?;
        out.channels.push(Channel {
            name: ch.name.clone(),
            data: data.iter().map(|&v| v as f32).collect(),
        });
    }
    Ok(out)
}

/// Planes that are plain means over a pixel's samples.
fn is_linear_mean(name: &str) -> bool {
    matches!(name, "R" | "G" | "B" | "grad.cv.Y")
        || name.starts_with("albedo.")
        || name.starts_with("grad.u.")
        || name.starts_with("grad.v.")
        || name.starts_with(MERGE_GRAD)
}

type PlaneOf<'a> = dyn Fn(&Part, &str) -> Result<Vec<f64>> + 'a;

/// Chan et al.'s parallel variance: the parts' M2 = V n (n − 1) plus the spread
/// of their means about the merged mean, back to the variance of the mean.
fn combine_variance(
    parts: &[&Part],
    counts: &[f64],
    merged: &mut BTreeMap<String, Vec<f64>>,
    plane: &PlaneOf,
) -> Result<()> {
    let total: f64 = counts.iter().sum();
    for c in RGB {
        let name = format!("variance.{c}");
        if parts[0].image.channel(&name).is_none() {
            continue;
        }
        let m = merged.get(c).cloned().unwrap_or_default();
        let mut m2 = vec![0.0f64; m.len()];
        for (p, &k) in parts.iter().zip(counts) {
            let (v, mi) = (plane(p, &name)?, plane(p, c)?);
            for i in 0..m2.len() {
                let d = mi[i] - m[i];
                m2[i] += v[i] * k * (k - 1.0) + k * d * d;
            }
        }
        let scale = if total < 2.0 {
            0.0
        } else {
            1.0 / (total * (total - 1.0))
        };
        merged.insert(name, m2.into_iter().map(|x| (x * scale).max(0.0)).collect());
    }
    Ok(())
}

/// The normal from the parts' unnormalised mean normals, the depth over the
/// samples that hit.
fn combine_normal_and_depth(
    parts: &[&Part],
    counts: &[f64],
    merged: &mut BTreeMap<String, Vec<f64>>,
    plane: &PlaneOf,
) -> Result<()> {
    let total: f64 = counts.iter().sum();
    if parts[0].image.channel("normal.X").is_some() {
        let n = parts[0].image.width * parts[0].image.height;
        let mut sum = vec![[0.0f64; 3]; n];
        for (p, &k) in parts.iter().zip(counts) {
            let len = plane(p, MERGE_NORMAL_LEN)?;
            for (a, axis) in ["X", "Y", "Z"].iter().enumerate() {
                for (i, v) in plane(p, &format!("normal.{axis}"))?.into_iter().enumerate() {
                    sum[i][a] += k * len[i] * v;
                }
            }
        }
        let mut planes = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut lens = vec![0.0; n];
        for (i, s) in sum.iter().enumerate() {
            let l = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            for a in 0..3 {
                planes[a][i] = if l > 0.0 { s[a] / l } else { 0.0 };
            }
            lens[i] = l / total;
        }
        for (a, axis) in ["X", "Y", "Z"].iter().enumerate() {
            merged.insert(format!("normal.{axis}"), std::mem::take(&mut planes[a]));
        }
        merged.insert(MERGE_NORMAL_LEN.into(), lens);
    }
    if parts[0].image.channel("depth.Z").is_some() {
        let hits = merged.get(MERGE_HITS).cloned().unwrap_or_default();
        let mut acc = vec![0.0f64; hits.len()];
        for p in parts {
            let (d, h) = (plane(p, "depth.Z")?, plane(p, MERGE_HITS)?);
            for i in 0..acc.len() {
                acc[i] += h[i] * d[i];
            }
        }
        let depth = acc.iter().zip(&hits).map(|(a, h)| a / h.max(1.0)).collect();
        merged.insert("depth.Z".into(), depth);
    }
    Ok(())
}

/// The term magnitudes (and CDV/SV) from the merged luminances of the terms'
/// mean u and v components, as `GradientPlanes::set` computes them.
fn combine_gradient_terms(merged: &mut BTreeMap<String, Vec<f64>>) {
    for term in ["sv", "dv", "cdv", "vis", "indirect"] {
        let (Some(u), Some(v)) = (
            merged.get(&format!("{MERGE_GRAD}{term}.u")),
            merged.get(&format!("{MERGE_GRAD}{term}.v")),
        ) else {
            continue;
        };
        let mag: Vec<f64> = u.iter().zip(v).map(|(a, b)| a.hypot(*b)).collect();
        merged.insert(format!("grad.{term}.Y"), mag);
    }
    let (Some(sv), Some(cdv)) = (merged.get(GRAD_TERMS[0]), merged.get(GRAD_TERMS[3])) else {
        return;
    };
    let ratio = sv
        .iter()
        .zip(cdv)
        .map(|(&s, &c)| {
            if c <= 0.0 {
                0.0
            } else {
                (c / s.max(1e-12)).min(1e12)
            }
        })
        .collect();
    merged.insert(GRAD_TERMS[6].into(), ratio);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_counts_in_the_singular_and_the_plural() {
        let s = |parts, tiles| {
            MergeSummary {
                parts,
                tiles,
                width: 4,
                height: 2,
                spp: 8,
                exr: "m.exr".into(),
                png: "m.png".into(),
            }
            .to_string()
        };
        assert!(
            s(2, 1).starts_with("merged 2 parts (1 tile) into 4x2"),
            "{}",
            s(2, 1)
        );
        assert!(s(1, 1).starts_with("merged 1 part (1 tile)"), "{}", s(1, 1));
        assert!(
            s(4, 4).starts_with("merged 4 parts (4 tiles)"),
            "{}",
            s(4, 4)
        );
    }
}
