//! Content-keyed caches (compare's reference, the previews' precomputations and
//! references): one key rule, one folder rule, atomic writes, and reads that
//! validate what they find, so that a stale, partial or damaged entry is a
//! miss (recomputed and rewritten), never an error and never a wrong answer.
//!
//! An entry is the file `<name>-<first 16 hex of the key>.<ext>`; it carries its
//! full key and the seconds it took to compute inside itself (a byte entry in a
//! header with the payload's length and SHA-256, an EXR entry in its header's
//! attributes), so a file of another key, cut short or with a flipped bit reads
//! as a miss.

use crate::output::{self, ExrHeader, OutputImage};
use crate::Result;
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What the cached value depends on besides the scene and the settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Epoch {
    /// A path-traced reference: its pixels change exactly when the renderer's
    /// pinned pixels do ([`super::PIXEL_EPOCH`]).
    Pixels,
    /// A precomputation: any change of the source may change it
    /// ([`super::SOURCE_EPOCH`]).
    Source,
}

impl Epoch {
    fn text(self) -> &'static str {
        match self {
            Epoch::Pixels => super::PIXEL_EPOCH,
            Epoch::Source => super::SOURCE_EPOCH,
        }
    }
}

/// SHA-256 (64 hex digits) over length-prefixed parts: no two different part
/// lists hash alike.
fn key_of(parts: &[&str]) -> String {
    let mut h = Sha256::new();
    for part in parts {
        h.update((part.len() as u64).to_le_bytes());
        h.update(part.as_bytes());
    }
    crate::hex(&h.finalize())
}

/// A folder of cache entries.
#[derive(Clone, Debug)]
pub struct Cache {
    dir: PathBuf,
}

impl Cache {
    /// A command's caches: `<out>/cache` (the previews' precomputations and
    /// references).
    pub fn under(out_dir: &Path) -> Self {
        Self {
            dir: out_dir.join("cache"),
        }
    }

    /// `compare`'s reference lives beside its report, in `<out>` itself: the
    /// report names it (`reference.cache_key`) and a user finds it there.
    pub fn beside(out_dir: &Path) -> Self {
        Self {
            dir: out_dir.to_path_buf(),
        }
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The entry `name` for `scene_hash` (`Scene::content_hash`) and `settings`
    /// (every setting the value depends on, as text) at `epoch`.
    pub fn entry(
        &self,
        name: &str,
        ext: &str,
        epoch: Epoch,
        scene_hash: &str,
        settings: &str,
    ) -> Entry {
        let key = key_of(&[name, epoch.text(), scene_hash, settings]);
        let path = self.dir.join(format!("{name}-{}.{ext}", &key[..16]));
        Entry { path, key }
    }
}

/// A cached value and the seconds it took when it was computed.
#[derive(Clone, Debug, PartialEq)]
pub struct Hit<T> {
    pub value: T,
    pub seconds: f64,
}

/// One keyed file of a [`Cache`].
#[derive(Clone, Debug)]
pub struct Entry {
    path: PathBuf,
    key: String,
}

/// The first line of a byte entry.
const MAGIC: &str = "gradtrace cache 1";
/// The EXR attributes an image entry carries its key and time in.
const KEY_ATTR: &str = "gradtrace.cache_key";
const SECONDS_ATTR: &str = "gradtrace.cache_seconds";

impl Entry {
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The full key (64 hex digits).
    pub fn key(&self) -> &str {
        &self.key
    }

    /// The payload, if the file holds this key and its bytes are whole; every
    /// failure is a miss.
    pub fn read_bytes(&self) -> Option<Hit<Vec<u8>>> {
        let mut bytes = std::fs::read(&self.path).ok()?;
        let mut lines = Vec::with_capacity(5);
        let mut at = 0;
        for _ in 0..5 {
            let end = at + bytes.get(at..)?.iter().position(|&b| b == b'\n')?;
            lines.push(std::str::from_utf8(&bytes[at..end]).ok()?.to_string());
            at = end + 1;
        }
        let seconds: f64 = lines[2].parse().ok()?;
        let len: usize = lines[3].parse().ok()?;
        let payload = bytes.get(at..)?;
        let whole = lines[0] == MAGIC
            && lines[1] == self.key
            && seconds.is_finite()
            && payload.len() == len
            && crate::hex(&Sha256::digest(payload)) == lines[4];
        if !whole {
            return None;
        }
        let value = bytes.split_off(at);
        Some(Hit { value, seconds })
    }

    /// Writes `payload` atomically under this key (creating the folder).
    pub fn write_bytes(&self, payload: &[u8], seconds: f64) -> Result<()> {
        self.create_dir()?;
        let seconds = finite(seconds);
        output::write_atomic(&self.path, |w| {
            write!(
                w,
                "{MAGIC}\n{}\n{seconds}\n{}\n{}\n",
                self.key,
                payload.len(),
                crate::hex(&Sha256::digest(payload))
            )
            .and_then(|_| w.write_all(payload))
            .map_err(|e| e.to_string())
        })
    }

    /// The image, if the file is an EXR of this key whose every value is finite
    /// (a NaN written by another tool, a flipped bit) and `accept` takes it (its
    /// size, its channels); every failure is a miss.
    pub fn read_exr(&self, accept: impl FnOnce(&OutputImage) -> bool) -> Option<Hit<OutputImage>> {
        let (image, header) = output::read_exr_with_header(&self.path).ok()?;
        if header.get(KEY_ATTR) != Some(self.key.as_str()) {
            return None;
        }
        let seconds: f64 = header.get(SECONDS_ATTR)?.parse().ok()?;
        let finite = image
            .channels
            .iter()
            .all(|c| c.data.iter().all(|v| v.is_finite()));
        (finite && seconds.is_finite() && accept(&image)).then_some(Hit {
            value: image,
            seconds,
        })
    }

    /// Writes `image` atomically under this key, with `header`'s provenance and
    /// a render id of its own (of `beauty`), so that it says where it came from.
    pub fn write_exr(
        &self,
        image: &OutputImage,
        header: &ExrHeader,
        beauty: &[crate::math::Vec3],
        seconds: f64,
    ) -> Result<()> {
        self.create_dir()?;
        let mut header = header.clone();
        header
            .attributes
            .retain(|(n, _)| n != KEY_ATTR && n != SECONDS_ATTR);
        header.attributes.push((KEY_ATTR.into(), self.key.clone()));
        header
            .attributes
            .push((SECONDS_ATTR.into(), finite(seconds).to_string()));
        header.attributes.sort();
        output::atomic::write_exr_with_id(&self.path, image, &header, beauty).map(|_| ())
    }

    fn create_dir(&self) -> Result<()> {
        let dir = self.path.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|e| crate::Error::Output {
            path: dir.to_path_buf(),
            message: format!("cannot create the folder: {e}"),
        })
    }
}

/// The payload of a byte entry read straight from its file (five header lines,
/// then the bytes), without checking its key: for tools handed a cache file by
/// path (`examples/glossy_frame.rs`); `None` if `bytes` is no byte entry.
pub fn byte_entry_payload(bytes: &[u8]) -> Option<&[u8]> {
    let mut at = 0;
    for _ in 0..5 {
        at += bytes.get(at..)?.iter().position(|&b| b == b'\n')? + 1;
    }
    bytes
        .starts_with(format!("{MAGIC}\n").as_bytes())
        .then(|| &bytes[at..])
}

fn finite(seconds: f64) -> f64 {
    if seconds.is_finite() {
        seconds
    } else {
        0.0
    }
}
