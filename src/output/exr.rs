//! OpenEXR reading and writing with the `exr` crate.
//!
//! One single-part, scan-line, ZIP-compressed (lossless) image with f32 channels.
//! Layers are expressed only through channel names (`normal.X`, `depth.Z`): a
//! single part with dotted names is what every EXR reader understands, and tev,
//! Nuke and OpenImageIO group such channels into layers by the text before the
//! last dot.

use super::atomic::{output_error, stage, Staged, RENDER_ID_KEY};
use super::{Channel, OutputImage};
use crate::Error;
use exr::meta::attribute::AttributeValue;
use exr::prelude::{
    read, AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    ReadChannels, ReadLayers, SmallVec, Text, WritableImage,
};
use std::path::Path;

/// Writes `image` as one EXR file, atomically (see [`super::atomic`]).
///
/// Rejects — before any file is created — an empty resolution, a channel whose
/// length is not `width * height`, duplicate or unusable channel names, and any
/// NaN or infinite value: a non-finite pixel silently poisons every downstream
/// tool (filters, metrics, viewers' auto-exposure), so it must never reach a file.
pub fn write_exr(path: &Path, image: &OutputImage) -> crate::Result<()> {
    stage_exr(path, image)?.commit()
}

/// Encodes `image` into a temporary file next to `path` without touching `path`;
/// [`Staged::commit`] puts it in place. Same checks as [`write_exr`].
pub fn stage_exr(path: &Path, image: &OutputImage) -> crate::Result<Staged> {
    stage_exr_tagged(path, image, None)
}

/// [`stage_exr`] with the render id of an EXR + PNG pair as the header attribute
/// [`RENDER_ID_KEY`] (see [`super::atomic`]).
pub(crate) fn stage_exr_tagged(
    path: &Path,
    image: &OutputImage,
    render_id: Option<&str>,
) -> crate::Result<Staged> {
    validate(path, image)?;
    let mut list = SmallVec::new();
    for ch in &image.channels {
        // `validate` checked the name; `new_or_none` cannot fail here, but a
        // library must not panic, so the error path stays.
        let name = Text::new_or_none(&ch.name)
            .ok_or_else(|| output_error(path, format!("bad channel name {:?}", ch.name)))?;
        list.push(AnyChannel::new(name, FlatSamples::F32(ch.data.clone())));
    }
    let mut attributes = LayerAttributes::default();
    if let Some(id) = render_id {
        let text = |s: &str| {
            Text::new_or_none(s).ok_or_else(|| output_error(path, format!("bad attribute {s:?}")))
        };
        attributes
            .other
            .insert(text(RENDER_ID_KEY)?, AttributeValue::Text(text(id)?));
    }
    let layer = Layer::new(
        (image.width, image.height),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let exr_image = Image::from_layer(layer);
    stage(path, |w| {
        exr_image
            .write()
            .to_buffered(w)
            .map_err(|e| format!("EXR encoder: {e}"))
    })
}

/// Reads every channel of every part of an EXR file as f32 (f16 and u32 samples
/// are converted). Channels of a named part get the part's name as a prefix
/// (`part.channel`), so multi-part files map onto the same flat naming. All parts
/// must share one resolution. Channel order is the file's (sorted by name).
pub fn read_exr(path: &Path) -> crate::Result<OutputImage> {
    check_header_size(path)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| match e {
            exr::error::Error::Io(source) => Error::Io {
                path: path.to_path_buf(),
                source,
            },
            other => Error::Asset {
                path: path.to_path_buf(),
                message: format!("invalid EXR: {other}"),
            },
        })?;
    let mut out: Option<OutputImage> = None;
    for layer in &image.layer_data {
        let (w, h) = (layer.size.width(), layer.size.height());
        let target = out.get_or_insert_with(|| OutputImage {
            width: w,
            height: h,
            channels: Vec::new(),
        });
        if (target.width, target.height) != (w, h) {
            return Err(Error::Asset {
                path: path.to_path_buf(),
                message: format!(
                    "parts have different resolutions ({}x{} and {w}x{h})",
                    target.width, target.height
                ),
            });
        }
        let prefix = layer
            .attributes
            .layer_name
            .as_ref()
            .map(|n| format!("{n}."))
            .unwrap_or_default();
        for ch in &layer.channel_data.list {
            target.channels.push(Channel {
                name: format!("{prefix}{}", ch.name),
                data: ch.sample_data.values_as_f32().collect(),
            });
        }
    }
    out.ok_or_else(|| Error::Asset {
        path: path.to_path_buf(),
        message: "the file holds no image part".into(),
    })
}

fn exr_error(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(source) => Error::Io {
            path: path.to_path_buf(),
            source,
        },
        other => Error::Asset {
            path: path.to_path_buf(),
            message: format!("invalid EXR: {other}"),
        },
    }
}

/// Rejects, from the header alone, a file whose parts claim more than
/// [`crate::scene::MAX_PIXELS`] pixels: the reader would allocate them before
/// noticing the file is short, and an allocation failure aborts the process.
fn check_header_size(path: &Path) -> crate::Result<()> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
    for h in &meta.headers {
        let (w, ht) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
        if w.saturating_mul(ht) > crate::scene::MAX_PIXELS {
            return Err(Error::Asset {
                path: path.to_path_buf(),
                message: format!(
                    "the header declares {w}×{ht} pixels, more than the {} supported",
                    crate::scene::MAX_PIXELS
                ),
            });
        }
    }
    Ok(())
}

/// The render id an EXR carries ([`RENDER_ID_KEY`]), from its header alone.
pub(crate) fn read_render_id(path: &Path) -> crate::Result<Option<String>> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
    Ok(meta.headers.iter().find_map(|h| {
        h.own_attributes
            .other
            .iter()
            .find(|(k, _)| Text::eq(k, RENDER_ID_KEY))
            .and_then(|(_, v)| match v {
                AttributeValue::Text(t) => Some(t.to_string()),
                _ => None,
            })
    }))
}

fn validate(path: &Path, image: &OutputImage) -> crate::Result<()> {
    let err = |m: String| Err(output_error(path, m));
    if image.width == 0 || image.height == 0 {
        return err(format!("empty resolution {}x{}", image.width, image.height));
    }
    // EXR stores the data window as i32 bounds.
    if image.width > i32::MAX as usize || image.height > i32::MAX as usize {
        return err(format!(
            "resolution {}x{} is too large for EXR",
            image.width, image.height
        ));
    }
    if image.channels.is_empty() {
        return err("no channels to write".into());
    }
    let n = image.width * image.height;
    let mut names = std::collections::HashSet::new();
    for ch in &image.channels {
        // EXR names are Latin-1 text of 1..=255 bytes; we keep to printable ASCII
        // so that every reader (and every shell) handles them.
        let printable = ch.name.bytes().all(|b| b.is_ascii_graphic());
        if ch.name.is_empty() || ch.name.len() > 255 || !printable {
            return err(format!(
                "channel name {:?} must be 1-255 printable ASCII characters",
                ch.name
            ));
        }
        if !names.insert(ch.name.as_str()) {
            return err(format!("channel {:?} appears twice", ch.name));
        }
        if ch.data.len() != n {
            return err(format!(
                "channel {:?} has {} values, expected {}x{} = {n}",
                ch.name,
                ch.data.len(),
                image.width,
                image.height
            ));
        }
        if let Some(i) = ch.data.iter().position(|v| !v.is_finite()) {
            return err(format!(
                "channel {:?} holds a non-finite value ({}) at pixel ({}, {})",
                ch.name,
                ch.data[i],
                i % image.width,
                i / image.width
            ));
        }
    }
    Ok(())
}
