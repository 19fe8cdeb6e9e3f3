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
}

pub type Result<T> = std::result::Result<T, Error>;
