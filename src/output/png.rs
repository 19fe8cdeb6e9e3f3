//! Tone-mapped 8-bit sRGB PNG for quick viewing: linear radiance × 2^exposure,
//! clamped to [0, 1], encoded with the sRGB transfer function (IEC 61966-2-1)
//! and rounded to the nearest of 256 levels. No filmic curve on purpose: the PNG
//! should show exactly what the EXR holds wherever it is in range.

use super::atomic::{output_error, stage, Staged, RENDER_ID_KEY};
use crate::math::Vec3;
use std::path::Path;

/// The sRGB opto-electronic transfer function (IEC 61966-2-1): linear \[0,1\] →
/// encoded \[0,1\]. Linear segment below 0.0031308, a 1/2.4 power above.
pub fn srgb_oetf(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear value → 8-bit sRGB code value: clamp, OETF, round to nearest.
pub fn to_srgb8(linear: f32) -> u8 {
    // `clamp` keeps NaN; callers reject NaN first, but map it to 0 rather than
    // letting `as u8` decide.
    let c = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    (srgb_oetf(c) * 255.0).round() as u8
}

/// Writes `rgb` (linear, row-major, top row first) as an sRGB PNG at exposure 0.
pub fn write_png(path: &Path, rgb: &[Vec3], width: usize, height: usize) -> crate::Result<()> {
    write_png_exposure(path, rgb, width, height, 0.0)
}

/// As [`write_png`], scaling the linear values by 2^`exposure` (photographic
/// stops) before clamping.
pub fn write_png_exposure(
    path: &Path,
    rgb: &[Vec3],
    width: usize,
    height: usize,
    exposure: f32,
) -> crate::Result<()> {
    stage_png(path, rgb, width, height, exposure)?.commit()
}

/// Encodes the PNG into a temporary file next to `path` without touching `path`;
/// [`Staged::commit`] puts it in place. Same checks as [`write_png`].
pub fn stage_png(
    path: &Path,
    rgb: &[Vec3],
    width: usize,
    height: usize,
    exposure: f32,
) -> crate::Result<Staged> {
    stage_png_tagged(path, rgb, width, height, exposure, None)
}

/// [`stage_png`] with the render id of an EXR + PNG pair as a `tEXt` chunk
/// [`RENDER_ID_KEY`] (see [`super::atomic`]). Encoded with the `png` crate
/// directly, with the settings `image`'s PngEncoder uses (balanced
/// compression, adaptive filter), which has no way to add a text chunk.
pub(crate) fn stage_png_tagged(
    path: &Path,
    rgb: &[Vec3],
    width: usize,
    height: usize,
    exposure: f32,
    render_id: Option<&str>,
) -> crate::Result<Staged> {
    let bytes = encode_srgb8(path, rgb, width, height, exposure)?;
    let (w, h) = (width as u32, height as u32);
    stage(path, |out| {
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Balanced);
        encoder.set_filter(png::Filter::Adaptive);
        if let Some(id) = render_id {
            encoder
                .add_text_chunk(RENDER_ID_KEY.into(), id.into())
                .map_err(|e| format!("PNG encoder: {e}"))?;
        }
        let mut writer = encoder
            .write_header()
            .map_err(|e| format!("PNG encoder: {e}"))?;
        writer
            .write_image_data(&bytes)
            .and_then(|()| writer.finish())
            .map_err(|e| format!("PNG encoder: {e}"))
    })
}

/// Encodes display-referred 8-bit RGB (interleaved, e.g. a false-colour error
/// map, which must not be tone-mapped again) into a temporary file next to
/// `path`; [`Staged::commit`] puts it in place.
pub fn stage_png_rgb8(
    path: &Path,
    rgb8: &[u8],
    width: usize,
    height: usize,
) -> crate::Result<Staged> {
    if width == 0 || height == 0 || rgb8.len() != 3 * width * height {
        return Err(output_error(
            path,
            format!(
                "{} bytes given for a {width}x{height} RGB image",
                rgb8.len()
            ),
        ));
    }
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => {
            let msg = format!("resolution {width}x{height} is too large for PNG");
            return Err(output_error(path, msg));
        }
    };
    stage(path, |out| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(out)
            .write_image(rgb8, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| format!("PNG encoder: {e}"))
    })
}

/// The render id a PNG carries ([`RENDER_ID_KEY`]), from its chunks before the
/// pixel data.
pub(crate) fn read_render_id(path: &Path) -> crate::Result<Option<String>> {
    let file = std::fs::File::open(path).map_err(|source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| crate::Error::Asset {
            path: path.to_path_buf(),
            message: format!("invalid PNG: {e}"),
        })?;
    Ok(reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .find(|t| t.keyword == RENDER_ID_KEY)
        .map(|t| t.text.clone()))
}

/// Validates the input and tone-maps it to interleaved 8-bit RGB.
fn encode_srgb8(
    path: &Path,
    rgb: &[Vec3],
    width: usize,
    height: usize,
    exposure: f32,
) -> crate::Result<Vec<u8>> {
    let err = |m: String| Err(output_error(path, m));
    if width == 0 || height == 0 {
        return err(format!("empty resolution {width}x{height}"));
    }
    // The PNG header stores u32 dimensions.
    if u32::try_from(width).is_err() || u32::try_from(height).is_err() {
        return err(format!("resolution {width}x{height} is too large for PNG"));
    }
    if rgb.len() != width * height {
        return err(format!(
            "{} pixels given, expected {width}x{height} = {}",
            rgb.len(),
            width * height
        ));
    }
    if !exposure.is_finite() {
        return err(format!("exposure must be finite, got {exposure}"));
    }
    if let Some(i) = rgb.iter().position(|p| !p.is_finite()) {
        return err(format!(
            "non-finite pixel {} at ({}, {})",
            rgb[i],
            i % width,
            i / width
        ));
    }
    let scale = exposure.exp2();
    Ok(rgb
        .iter()
        .flat_map(|p| (*p * scale).to_array())
        .map(to_srgb8)
        .collect())
}
