//! The library's error type. Everything that comes from outside (files, parameters, scenes) is checked
//! and reported with the path, line or index that is wrong; the library never panics on user input.

use std::path::PathBuf;

/// Errors returned by plie.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A scene or data file is malformed.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line, where the format has lines and it is known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The scene is not usable (no triangles, no lights, NaN coordinates, a bad light polygon ...).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// No built-in scene has this name.
    #[error("unknown scene '{name}' (built-in scenes: {known}); or give a path to an .obj/.gltf/.glb/.xml file")]
    UnknownScene {
        /// The name asked for.
        name: String,
        /// The built-in names, comma-separated.
        known: String,
    },
    /// The Embree device or scene could not be set up (feature `embree`).
    #[cfg(feature = "embree")]
    #[error("embree: {0}")]
    Embree(String),
    /// Encoding an image failed.
    #[error("{}: cannot write image: {message}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
