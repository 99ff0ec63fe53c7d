//! Files in and out: scenes (SPEC §1) from OBJ + MTL and glTF 2.0, images (SPEC §2, output) as PNG,
//! OpenEXR and PFM, all written atomically.
//!
//! - [`load_scene`] picks the loader by extension: [`obj::load_obj`], [`gltf::load_gltf`]. Both turn
//!   emissive triangles into convex polygonal lights with [`lights`].
//! - [`save_image`] writes radiance; [`load_pfm`] reads a PFM back for bit-exact comparisons.
//! - [`gltf_export::save_inspection_gltf`] writes what `plie inspect` shows as a glTF scene.
//! - [`write_atomic`] is the only way files are written: a temporary file, fsync, rename.
//! - [`input`] is the only way files are read: regular files only, bounded in size, and files named
//!   inside a scene only from the scene's folder unless [`LoadOptions::allow_outside_paths`].
//!
//! Every error names the file and, where the format has lines, the line. Loaders never panic on input;
//! what the underlying crates would panic on is checked before they see it.

pub mod atomic;
pub mod camera_path;
pub mod gltf;
pub(crate) mod gltf_export;
pub mod image;
pub mod input;
pub mod lights;
pub mod mitsuba;
mod mtl;
pub mod obj;
mod obj_lines;
pub(crate) mod plie_file;
pub mod ply;
pub mod serialized;
pub mod texture_file;
pub mod tri_mesh;

use std::path::Path;

pub use atomic::{write_atomic, WriteSeek};
pub use image::{load_pfm, save_image, ImageFormat};
pub use input::LoadOptions;

use crate::error::{Error, Result};
use crate::scene::Scene;

/// The scene file extensions [`load_scene`] understands (lower case, without the dot).
pub const SCENE_EXTENSIONS: [&str; 4] = ["obj", "gltf", "glb", "xml"];

/// Loads a scene file, choosing the format by extension (case-insensitive): `.obj` (with its MTL
/// files), `.gltf` or `.glb`, or a Mitsuba scene `.xml`. The scene is named after the file stem. The file's camera, if any, becomes
/// the scene camera; otherwise [`Scene::camera`] is `None`. Files the scene names are read only from
/// its own folder ([`LoadOptions::default`]).
pub fn load_scene(path: &Path) -> Result<Scene> {
    load_scene_with(path, LoadOptions::default())
}

/// [`load_scene`] with options.
pub fn load_scene_with(path: &Path, opts: LoadOptions) -> Result<Scene> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "obj" => obj::load_obj_with(path, opts),
        "gltf" | "glb" => gltf::load_gltf_with(path, opts),
        "xml" => mitsuba::load_mitsuba_with(path, opts),
        _ => Err(parse_error(
            path,
            None,
            format!(
                "unknown scene format '.{ext}'; supported: {}",
                SCENE_EXTENSIONS.map(|e| format!(".{e}")).join(", ")
            ),
        )),
    }
}

/// Checks, before long work, that an image can be written to `path`: a supported extension and an
/// existing directory.
pub fn check_image_path(path: &Path) -> Result<()> {
    ImageFormat::from_path(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(Error::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "the directory does not exist"),
        });
    }
    Ok(())
}

/// An [`Error::Parse`] for `path`.
pub(crate) fn parse_error(path: &Path, line: Option<usize>, message: String) -> Error {
    Error::Parse { path: path.to_path_buf(), line, message }
}

/// The scene name for a file: its stem.
pub(crate) fn scene_name(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Warnings about material features a file uses but plie does not render, from (what, material name)
/// pairs: one per kind of feature, naming up to three materials ([`Scene::warnings`]).
pub(crate) fn material_warnings(ignored: &[(String, String)]) -> Vec<String> {
    let mut kinds: Vec<&str> = ignored.iter().map(|(what, _)| what.as_str()).collect();
    kinds.sort_unstable();
    kinds.dedup();
    kinds
        .into_iter()
        .map(|what| {
            let mut names: Vec<&str> = ignored.iter().filter(|(w, _)| w == what).map(|(_, m)| m.as_str()).collect();
            names.dedup();
            let shown = names.iter().take(3).map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ");
            let more = if names.len() > 3 { format!(" and {} more", names.len() - 3) } else { String::new() };
            let s = if names.len() == 1 { "" } else { "s" };
            format!("material{s} {shown}{more}: {what}")
        })
        .collect()
}
