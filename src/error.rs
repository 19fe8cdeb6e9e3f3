//! The library's one error type. Every variant names the file it is about, so that
//! a user sees a single line saying where the problem is and what was expected.

use std::path::PathBuf;

/// Errors the library reports to callers; `main.rs` prints them and exits non-zero.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene file (or a file it references) could not be read.
    #[error("{path}: cannot read file: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The scene file is malformed: `location` names the key (and line when known),
    /// `message` says what was expected.
    #[error("{path}: {location}: {message}")]
    Scene {
        path: PathBuf,
        location: String,
        message: String,
    },
    /// An input file is unusable: a scene file that is not a regular UTF-8 file
    /// within the size limit, or an OBJ/MTL or image that is malformed. (While a
    /// scene loads, asset errors become `Scene` errors at the key naming the
    /// asset, with the asset's path in the message.)
    #[error("{path}: {message}")]
    Asset { path: PathBuf, message: String },
    /// Writing an output file failed; nothing was left at `path`.
    #[error("{path}: cannot write output: {message}")]
    Output { path: PathBuf, message: String },
    /// Render options are inconsistent (e.g. zero samples per pixel).
    #[error("invalid option {option}: {message}")]
    Option { option: String, message: String },
    /// Parts of a split render do not fit together; `path` names the part.
    #[error("{path}: cannot merge: {message}")]
    Merge { path: PathBuf, message: String },
    /// The run was interrupted (Ctrl-C) before it had anything to write.
    #[error("interrupted {0}")]
    Interrupted(String),
}

pub type Result<T> = std::result::Result<T, Error>;

/// An error and its causes as one line. Library errors already quote their source
/// in their own message, so a cause whose text is already there is skipped.
pub fn error_line<'a>(
    chain: impl Iterator<Item = &'a (dyn std::error::Error + 'static)>,
) -> String {
    let mut line = String::new();
    for cause in chain {
        let text = one_line(&cause.to_string());
        if !line.contains(&text) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&text);
        }
    }
    line
}

/// Collapses a possibly multi-line message (e.g. a TOML parser's snippet) into
/// one line, so that `error:` output stays one line per failure.
pub fn one_line(msg: &str) -> String {
    msg.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Makes a panic print one line, `error: internal error: <message> at <file:line>`,
/// once, however many worker threads panic (the caller turns it into status 1).
pub fn one_line_panics() {
    use std::sync::atomic::{AtomicBool, Ordering};
    static PANICKED: AtomicBool = AtomicBool::new(false);
    std::panic::set_hook(Box::new(|info| {
        if !PANICKED.swap(true, Ordering::SeqCst) {
            let payload = info.payload();
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into());
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            eprintln!("error: internal error: {}{at}", one_line(&msg));
        }
    }));
}

/// "a FIFO (named pipe)", "a directory", … for messages about non-regular files
/// (scene files, OBJs, EXR inputs and outputs alike).
pub fn file_kind(m: &std::fs::Metadata) -> &'static str {
    let t = m.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_file() {
        "a regular file"
    } else {
        "not a regular file"
    }
}
