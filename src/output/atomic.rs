//! Atomic file replacement: write a temporary file next to the target, fsync it,
//! then rename it over the target.
//!
//! Why: a render can take minutes and may fail (or be interrupted) while an output
//! is being encoded. Writing in place would leave a truncated file *and* destroy the
//! previous good one. `rename(2)` within one directory is atomic on POSIX file
//! systems, so a reader sees either the old file or the complete new one, never a
//! mix. The temporary file lives in the target's own directory because a rename
//! across file systems is not atomic (and fails with `EXDEV`).

use crate::Error;
use std::fs::{File, OpenOptions};
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temporary files of concurrent writers inside one process (the
/// PID alone distinguishes processes).
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// A fully written and fsynced temporary file that has not yet replaced its target.
///
/// Dropping it without [`Staged::commit`] removes the temporary file, so every
/// early return (and even a panic) cleans up. Staging several files first and
/// committing them afterwards lets a caller (the CLI writes an EXR and a PNG) make
/// all fallible encoding happen before any visible output is touched.
#[derive(Debug)]
pub struct Staged {
    temp: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl Staged {
    /// The path this file will have after [`Staged::commit`].
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the temporary file over the target. On failure the temporary file is
    /// removed and the previous target (if any) is untouched.
    pub fn commit(mut self) -> crate::Result<()> {
        std::fs::rename(&self.temp, &self.target)
            .map_err(|e| output_error(&self.target, format!("cannot replace the file: {e}")))?;
        self.committed = true;
        // Make the rename itself durable. Best effort: some file systems refuse to
        // fsync a directory, and the data is already safely in the new file.
        if let Ok(dir) = File::open(parent_dir(&self.target)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// Writes a temporary file for `target` with `write`, flushes and fsyncs it. Any
/// error (from `write` or from the file system) removes the temporary file.
pub fn stage<F>(target: &Path, write: F) -> crate::Result<Staged>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), String>,
{
    let file_name = target
        .file_name()
        .ok_or_else(|| output_error(target, "the path does not name a file".into()))?;
    let temp = parent_dir(target).join(format!(
        ".{}.tmp-{}-{}",
        file_name.to_string_lossy(),
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    // `create_new` never clobbers a file we did not create ourselves.
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(|e| output_error(target, format!("cannot create a temporary file: {e}")))?;
    // From here on the guard owns the temporary file and removes it on any exit.
    let staged = Staged {
        temp,
        target: target.to_path_buf(),
        committed: false,
    };
    let mut writer = BufWriter::new(file);
    write(&mut writer).map_err(|m| output_error(target, m))?;
    let file = writer
        .into_inner()
        .map_err(|e| output_error(target, format!("cannot write: {}", e.error())))?;
    file.sync_all()
        .map_err(|e| output_error(target, format!("cannot sync to disk: {e}")))?;
    Ok(staged)
}

/// Replaces `target` atomically with what `write` produces (stage, then commit).
pub fn write_atomic<F>(target: &Path, write: F) -> crate::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), String>,
{
    stage(target, write)?.commit()
}

/// The directory a file lives in; `""` (a bare file name) means the current one.
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

pub(crate) fn output_error(path: &Path, message: String) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        message,
    }
}
