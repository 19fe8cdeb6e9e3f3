//! Opening a file that a command reads back (`merge`'s parts, `diff`'s images,
//! `render --resume`): one helper, so that each of them refuses the same things
//! before reading a byte — what is not a regular file (a FIFO would block the
//! reader forever, a device would feed it without end), and a file that is also
//! one of the command's outputs (compared by device and inode, not by spelling:
//! `./a.exr` and `a.exr` are one file, and writing it would replace the input).

use crate::Error;
use std::fs::{File, Metadata};
use std::path::Path;

use crate::error::file_kind;

/// (device, inode): what makes two paths one file.
#[cfg(unix)]
fn identity(m: &Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn identity(_m: &Metadata) -> Option<(u64, u64)> {
    None
}

/// Opens `path` for reading after checking that it is a regular file and none
/// of `outputs` (the files the command will write; those that do not exist yet
/// cannot be it). `what` says what was expected ("an EXR file").
pub fn open_input(path: &Path, what: &str, outputs: &[&Path]) -> crate::Result<File> {
    let err = |message: String| Error::Asset {
        path: path.to_path_buf(),
        message,
    };
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    // stat before open: opening a FIFO for reading blocks until a writer comes.
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(err(format!(
            "is {}, not a regular file; expected {what}",
            file_kind(&meta)
        )));
    }
    for out in outputs {
        let same = std::fs::metadata(out)
            .ok()
            .and_then(|m| identity(&m))
            .is_some_and(|id| Some(id) == identity(&meta));
        if same {
            return Err(err(format!(
                "is also the output {}, which would replace it; expected an output path other than the inputs",
                out.display()
            )));
        }
    }
    let file = open_nonblocking(path).map_err(io)?;
    // The path may have been swapped between the stat and the open.
    let now = file.metadata().map_err(io)?;
    if !now.is_file() || identity(&now) != identity(&meta) {
        return Err(err(format!(
            "changed while being opened (it is now {}); expected {what}",
            file_kind(&now)
        )));
    }
    Ok(file)
}

/// Opens without blocking, so that a FIFO swapped in after the check cannot
/// hang the open itself (the flag does nothing to a regular file's reads).
#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

/// Refuses an output path that exists and is not a regular file (after
/// following symbolic links): renaming over a FIFO or a device node would
/// replace it with a regular file, and over a directory fails only at the end.
/// A new path, or a regular file to be replaced, passes.
pub fn check_output_target(path: &Path, option: &str) -> crate::Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(Error::Output {
            path: path.to_path_buf(),
            message: format!(
                "is {}, not a regular file; expected {option} to name a regular file or a new path",
                file_kind(&m)
            ),
        }),
        _ => Ok(()),
    }
}
