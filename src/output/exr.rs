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
    read, AnyChannel, AnyChannels, Encoding, FlatSamples, Image, ImageAttributes, IntegerBounds,
    Layer, LayerAttributes, ReadChannels, ReadLayers, SmallVec, Text, WritableImage,
};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// Where an EXR's planes sit in the full image, and where they came from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExrHeader {
    /// The full image's size (the display window); (0, 0): the planes' own size.
    pub display: (usize, usize),
    /// The data window's top-left pixel inside the display window.
    pub origin: (usize, usize),
    /// String attributes, e.g. (`gradtrace.spp`, `64`).
    pub attributes: Vec<(String, String)>,
}

impl ExrHeader {
    /// The display window's size, or `(width, height)` (the planes' own) where
    /// the header gives none.
    pub fn display_or(&self, width: usize, height: usize) -> (usize, usize) {
        match self.display {
            (0, 0) => (width, height),
            d => d,
        }
    }

    /// The value of string attribute `name`.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

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
    stage_exr_with_header(path, image, &ExrHeader::default())
}

/// [`stage_exr`] with a data window inside a larger display window (a tile of an
/// image: viewers and `merge` place it) and string attributes in the header.
pub fn stage_exr_with_header(
    path: &Path,
    image: &OutputImage,
    header: &ExrHeader,
) -> crate::Result<Staged> {
    validate(path, image)?;
    let (attributes, display) = header_attributes(path, image, header)?;
    let mut list = SmallVec::new();
    for ch in &image.channels {
        // `validate` checked the name; `new_or_none` cannot fail here, but a
        // library must not panic, so the error path stays.
        let name = Text::new_or_none(&ch.name)
            .ok_or_else(|| output_error(path, format!("bad channel name {:?}", ch.name)))?;
        list.push(AnyChannel::new(name, FlatSamples::F32(ch.data.clone())));
    }
    let layer = Layer::new(
        (image.width, image.height),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let exr_image = Image::new(ImageAttributes::new(display), layer);
    stage(path, |w| {
        exr_image
            .write()
            .to_buffered(w)
            .map_err(|e| format!("EXR encoder: {e}"))
    })
}

/// [`stage_exr_with_header`] with the render id of an EXR + PNG pair as the
/// header attribute [`RENDER_ID_KEY`] (see [`super::atomic`]).
pub(crate) fn stage_exr_tagged(
    path: &Path,
    image: &OutputImage,
    header: &ExrHeader,
    render_id: &str,
) -> crate::Result<Staged> {
    let mut header = header.clone();
    header
        .attributes
        .push((RENDER_ID_KEY.to_string(), render_id.to_string()));
    stage_exr_with_header(path, image, &header)
}

/// Reads every channel of every part of an EXR file as f32 (f16 and u32 samples
/// are converted). Channels of a named part get the part's name as a prefix
/// (`part.channel`), so multi-part files map onto the same flat naming. All parts
/// must share one resolution. Channel order is the file's (sorted by name).
pub fn read_exr(path: &Path) -> crate::Result<OutputImage> {
    read_exr_with_header(path).map(|(image, _)| image)
}

/// The layer attributes (data window position, string attributes) and the
/// display window of `header`, checked: the data window inside the display
/// window, attribute names printable ASCII (values Latin-1; other characters
/// become `?`).
fn header_attributes(
    path: &Path,
    image: &OutputImage,
    header: &ExrHeader,
) -> crate::Result<(LayerAttributes, IntegerBounds)> {
    let display = header.display_or(image.width, image.height);
    let (x0, y0) = header.origin;
    if x0 + image.width > display.0
        || y0 + image.height > display.1
        || display.0 > i32::MAX as usize
        || display.1 > i32::MAX as usize
    {
        return Err(output_error(
            path,
            format!(
                "data window {}x{} at ({x0}, {y0}) does not fit the {}x{} display window",
                image.width, image.height, display.0, display.1
            ),
        ));
    }
    let mut attributes = LayerAttributes {
        layer_position: exr::math::Vec2(x0 as i32, y0 as i32),
        ..LayerAttributes::default()
    };
    for (name, value) in &header.attributes {
        if name.is_empty() || name.len() > 255 || !name.bytes().all(|b| b.is_ascii_graphic()) {
            return Err(output_error(
                path,
                format!("attribute name {name:?} must be 1-255 printable ASCII characters"),
            ));
        }
        let latin1: String = value
            .chars()
            .map(|c| if (c as u32) < 256 { c } else { '?' })
            .collect();
        let (Some(n), Some(v)) = (Text::new_or_none(name), Text::new_or_none(&latin1)) else {
            return Err(output_error(
                path,
                format!("attribute {name:?} is not text"),
            ));
        };
        attributes.other.insert(n, AttributeValue::Text(v));
    }
    Ok((attributes, IntegerBounds::from_dimensions(display)))
}

/// [`read_exr`] with the header: the display window, where the data window sits
/// in it, and every string attribute (sorted by name).
pub fn read_exr_with_header(path: &Path) -> crate::Result<(OutputImage, ExrHeader)> {
    read_exr_input(path, &[])
}

/// [`read_exr_with_header`] for a command that also writes `outputs`: the file
/// is opened by [`super::input::open_input`] (a regular file, none of the
/// outputs) and its header checked by `check_header`, all before any pixel
/// is allocated.
pub fn read_exr_input(path: &Path, outputs: &[&Path]) -> crate::Result<(OutputImage, ExrHeader)> {
    let mut file = super::input::open_input(path, "an EXR file", outputs)?;
    check_header(path, &file)?;
    file.seek(SeekFrom::Start(0)).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(BufReader::new(file))
        .map_err(|e| match e {
            // The header and the offsets were checked: what fails now is the data.
            exr::error::Error::Io(source) => Error::Asset {
                path: path.to_path_buf(),
                message: format!(
                    "cannot decode the pixel data ({source}); expected a complete, uncorrupted EXR file"
                ),
            },
            other => exr_error(path, other),
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
    let out = out.ok_or_else(|| Error::Asset {
        path: path.to_path_buf(),
        message: "the file holds no image part".into(),
    })?;
    let display = &image.attributes.display_window;
    let mut header = ExrHeader {
        display: (display.size.width(), display.size.height()),
        ..ExrHeader::default()
    };
    if let Some(layer) = image.layer_data.first() {
        // Not negative: `check_header` refused a data window outside the
        // display window (it used to be clamped to 0 here and accepted).
        let p = layer.attributes.layer_position - display.position;
        header.origin = (p.x() as usize, p.y() as usize);
    }
    let others = image.layer_data.iter().map(|l| &l.attributes.other);
    for other in others.chain([&image.attributes.other]) {
        for (name, value) in other {
            if let AttributeValue::Text(t) = value {
                header.attributes.push((name.to_string(), t.to_string()));
            }
        }
    }
    header.attributes.sort();
    header.attributes.dedup();
    Ok((out, header))
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

/// The most pixels an EXR part may declare to be read: 2²⁸, the largest image
/// a scene may ask for (`scene::MAX_PIXELS`).
pub const MAX_READ_PIXELS: u64 = 1 << 28;

/// Counts the bytes a reader handed out: where the header ended.
struct Counting<R> {
    inner: R,
    read: u64,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        Ok(n)
    }
}

/// Checks, from the header and the offset tables alone, what the decoder would
/// otherwise find out by allocating or seeking: every part's data window and the
/// display window at most [`MAX_READ_PIXELS`] (a claimed 10⁹² display window
/// was allocated by `merge` for the whole image), the data window inside the
/// display window (a tile's place in the image: a negative or overhanging
/// origin cannot be placed), and every chunk offset inside the file (one ≥ 2⁶³
/// made the decoder's seek fail with a bare "Invalid argument").
fn check_header(path: &Path, file: &File) -> crate::Result<()> {
    let err = |message: String| Error::Asset {
        path: path.to_path_buf(),
        message,
    };
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let len = file.metadata().map_err(io)?.len();
    let mut reader = Counting {
        inner: BufReader::new(file),
        read: 0,
    };
    let meta = exr::meta::MetaData::read_from_buffered(&mut reader, false)
        .map_err(|e| exr_error(path, e))?;
    let pixels = |w: usize, h: usize| (w as u64).saturating_mul(h as u64);
    let mut chunks = 0u64;
    for h in &meta.headers {
        let d = &h.shared_attributes.display_window;
        let (dw, dh) = (d.size.width(), d.size.height());
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        for (what, w, ht) in [("display", dw, dh), ("data", w, ht)] {
            if pixels(w, ht) > MAX_READ_PIXELS {
                return Err(err(format!(
                    "the header declares a {what} window of {w}×{ht} pixels; expected at most {MAX_READ_PIXELS} (2^28, as scene::MAX_PIXELS)"
                )));
            }
        }
        let p = h.own_attributes.layer_position;
        let (x0, y0) = (i64::from(p.x()), i64::from(p.y()));
        let (dx0, dy0) = (i64::from(d.position.x()), i64::from(d.position.y()));
        let (x1, y1) = (x0 + w as i64, y0 + ht as i64);
        let (dx1, dy1) = (dx0 + dw as i64, dy0 + dh as i64);
        if x0 < dx0 || y0 < dy0 || x1 > dx1 || y1 > dy1 {
            return Err(err(format!(
                "the data window ({x0}, {y0})–({x1}, {y1}) does not lie inside the display window ({dx0}, {dy0})–({dx1}, {dy1}); expected a data window inside the display window"
            )));
        }
        chunks += h.chunk_count as u64;
    }
    let table_end = reader.read.saturating_add(chunks.saturating_mul(8));
    if table_end > len {
        return Err(err(format!(
            "is {len} bytes long, shorter than its header and chunk offset table ({table_end} bytes); expected a complete EXR file"
        )));
    }
    let mut word = [0u8; 8];
    for k in 0..chunks {
        reader.read_exact(&mut word).map_err(io)?;
        let offset = u64::from_le_bytes(word);
        if offset < table_end || offset >= len {
            return Err(err(format!(
                "chunk {k}'s offset is {offset}, outside the file's {len} bytes of data (from byte {table_end}); expected an offset inside the file (the file is corrupt or truncated)"
            )));
        }
    }
    Ok(())
}

/// The render id an EXR carries ([`RENDER_ID_KEY`]), from its header alone.
pub(crate) fn read_render_id(path: &Path) -> crate::Result<Option<String>> {
    let file = super::input::open_input(path, "an EXR file", &[])?;
    let meta =
        exr::meta::MetaData::read_from_unbuffered(file, false).map_err(|e| exr_error(path, e))?;
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
