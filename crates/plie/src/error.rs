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
    /// A part of a scene file named by its index is malformed (a glTF mesh primitive or node, a PLY
    /// vertex or face).
    #[error("{}: {element}: {message}", path.display())]
    SceneElement {
        /// The file.
        path: PathBuf,
        /// Which part.
        element: SceneElement,
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
    /// A `.plie` file cannot be used: see [`PlieFileError`] for why.
    #[error("{}: {problem}", path.display())]
    PlieFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: PlieFileError,
    },
    /// The P-LIE construction was interrupted ([`crate::progress::Progress::cancelled`]); nothing was
    /// built.
    #[error("interrupted")]
    Interrupted,
    /// Encoding an image failed.
    #[error("{}: cannot write image: {message}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// A part of a scene file, by index ([`Error::SceneElement`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneElement {
    /// glTF `meshes[mesh].primitives[primitive]`; `name` is the mesh's, if it has one.
    Primitive {
        /// Index of the mesh.
        mesh: usize,
        /// The mesh's name.
        name: Option<String>,
        /// Index of the primitive in the mesh.
        primitive: usize,
    },
    /// glTF `nodes[node]`.
    Node(usize),
    /// Record `index` (0-based) of the PLY element `element` (`vertex`, `face`), at `line` in an ASCII
    /// file.
    Ply {
        /// The element's name.
        element: &'static str,
        /// The record's index.
        index: usize,
        /// Its 1-based line (ASCII files).
        line: Option<usize>,
    },
}

impl std::fmt::Display for SceneElement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneElement::Primitive { mesh, name: Some(n), primitive } => {
                write!(f, "mesh '{n}' (mesh {mesh}), primitive {primitive}")
            }
            SceneElement::Primitive { mesh, name: None, primitive } => write!(f, "mesh {mesh}, primitive {primitive}"),
            SceneElement::Node(n) => write!(f, "node {n}"),
            SceneElement::Ply { element, index, line: None } => write!(f, "{element} {index}"),
            SceneElement::Ply { element, index, line: Some(l) } => write!(f, "{element} {index} (line {l})"),
        }
    }
}

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Why a `.plie` file cannot be used ([`Error::PlieFile`]). Each message is one line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PlieFileError {
    /// The file does not start with the `.plie` magic bytes.
    #[error("not a .plie file (wrong magic bytes)")]
    BadMagic,
    /// The file is shorter than the header.
    #[error("truncated .plie file (incomplete header)")]
    TruncatedHeader,
    /// Another format version.
    #[error(
        "made with .plie format version {found}; this plie reads version {supported}: rebuild it with `plie build`"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The payload is shorter than the header says.
    #[error("truncated .plie file ({have} of {expected} payload bytes)")]
    Truncated {
        /// Payload bytes present.
        have: u64,
        /// Payload bytes the header announces.
        expected: u64,
    },
    /// Bytes follow the payload.
    #[error("corrupted .plie file ({extra} bytes after the payload)")]
    TrailingBytes {
        /// How many.
        extra: u64,
    },
    /// The payload does not match its checksum.
    #[error("corrupted .plie file (checksum mismatch)")]
    Checksum,
    /// The checksum matches but the payload does not decode.
    #[error("corrupted .plie file: the checksum matches but the content is not a P-LIE (written by another program or altered): rebuild it with `plie build`")]
    Undecodable,
    /// The file was built for another scene.
    #[error("was built for another scene, not '{scene}' (rebuild it with `plie build`)")]
    OtherScene {
        /// The scene it was loaded for.
        scene: String,
    },
    /// The file was built with other parameters than the caller expects.
    #[error("was built with other parameters ({file}) than asked for ({asked})")]
    OtherParameters {
        /// The file's parameters, as command-line options.
        file: String,
        /// The expected ones.
        asked: String,
    },
    /// The parameters stored in the file are invalid.
    #[error("invalid parameters in file: {0}")]
    InvalidParameters(String),
    /// The octree rebuilt for the scene is not the one the P-LIE was built on.
    #[error("its octree differs from the one this plie builds for the scene: rebuild it")]
    OtherOctree,
    /// The P-LIE's tables are inconsistent (an index out of range, a list out of order...).
    #[error("inconsistent .plie file: {0}")]
    Inconsistent(String),
}
