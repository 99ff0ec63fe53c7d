//! Reading input files safely (SPEC §1 scene input): only regular files, only up to a size bound,
//! and only inside the scene's own folder unless the user opts in.
//!
//! - [`open_regular`] and [`read_bounded`] refuse devices, pipes and directories (`/dev/zero`,
//!   `/dev/urandom` would never end) and files above [`MAX_INPUT_BYTES`].
//! - [`resolve_in_scene`] turns a path written inside a scene file (an OBJ's `mtllib`, a glTF buffer
//!   URI, later textures and other referenced files) into a file path, and refuses absolute paths,
//!   `file:` URIs and paths that leave the scene's folder (`..`, symbolic links) unless
//!   [`LoadOptions::allow_outside_paths`] is set: a scene from elsewhere must not make plie read
//!   `/etc/passwd`.

use std::fs::File;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};

/// The largest input file plie reads (scene, material library, glTF buffer, `.plie`): 4 GiB.
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// How scene files are loaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Let a scene file name files outside its own folder (absolute paths, `..`, `file:` URIs).
    pub allow_outside_paths: bool,
}

/// Opens `path` for reading if it is a regular file no larger than `limit` bytes.
pub fn open_regular(path: &Path, limit: u64) -> Result<File> {
    let io = |source| Error::Io { path: path.to_path_buf(), source };
    // Without blocking: opening a FIFO for reading would otherwise wait for a writer forever.
    #[cfg(unix)]
    let file = {
        use std::os::unix::fs::OpenOptionsExt;
        std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK).open(path).map_err(io)?
    };
    #[cfg(not(unix))]
    let file = File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        let kind = if meta.is_dir() { "a directory" } else { "a device, pipe or socket" };
        return Err(invalid(path, format!("is {kind}, not a regular file")));
    }
    if meta.len() > limit {
        return Err(invalid(path, format!("is {} bytes, more than the limit of {limit} bytes", meta.len())));
    }
    Ok(file)
}

/// Reads a whole regular file of at most `limit` bytes (the bound also holds if it grows meanwhile).
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let file = open_regular(path, limit)?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    if bytes.len() as u64 > limit {
        return Err(invalid(path, format!("grew beyond the limit of {limit} bytes while being read")));
    }
    Ok(bytes)
}

/// The file named `name` inside a scene whose folder is `dir`; `what` names the reference in errors
/// ("mtllib", "buffer 0 URI"). Refuses absolute paths, URIs with a scheme (`file:`, `http:`) and
/// paths leaving `dir` unless `opts.allow_outside_paths`; `file:` URIs are then accepted.
pub fn resolve_in_scene(dir: &Path, name: &str, what: &str, opts: LoadOptions) -> Result<PathBuf, String> {
    let hint = "outside the scene's folder (pass --allow-outside-paths to allow it)";
    let local = match name.strip_prefix("file://") {
        Some(rest) if opts.allow_outside_paths => rest,
        Some(_) => return Err(format!("{what} '{}' is a file: URI, {hint}", short(name))),
        None => name,
    };
    if has_scheme(local) {
        return Err(format!("{what} '{}' is a URI with a scheme; only relative paths are supported", short(name)));
    }
    let rel = Path::new(local);
    if opts.allow_outside_paths {
        return Ok(dir.join(rel));
    }
    if rel.has_root() || rel.components().any(|c| matches!(c, Component::Prefix(_) | Component::RootDir)) {
        return Err(format!("{what} '{}' is an absolute path, {hint}", short(name)));
    }
    let mut depth = 0i32;
    for c in rel.components() {
        match c {
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            _ => {}
        }
        if depth < 0 {
            return Err(format!("{what} '{}' leaves the scene's folder with '..', {hint}", short(name)));
        }
    }
    let path = dir.join(rel);
    // A symbolic link may still point elsewhere: compare the resolved paths when the file exists.
    if let (Ok(real), Ok(base)) = (path.canonicalize(), dir_or_cwd(dir).canonicalize()) {
        if !real.starts_with(&base) {
            return Err(format!("{what} '{}' resolves to {}, {hint}", short(name), real.display()));
        }
    }
    Ok(path)
}

/// `dir`, or `.` when it is empty (a scene file given without a folder).
fn dir_or_cwd(dir: &Path) -> &Path {
    if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    }
}

/// `scheme:` at the start, as in a URI (`http:`, `file:`); a Windows drive letter is one character.
fn has_scheme(s: &str) -> bool {
    match s.find(':') {
        Some(i) if i > 1 => {
            let scheme = &s[..i];
            scheme.starts_with(|c: char| c.is_ascii_alphabetic())
                && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        }
        _ => false,
    }
}

/// At most 80 characters of a name from a file, for error messages.
pub fn short(s: &str) -> String {
    const MAX: usize = 80;
    if s.chars().count() <= MAX {
        return s.to_string();
    }
    let head: String = s.chars().take(MAX).collect();
    format!("{head}... ({} characters)", s.chars().count())
}

/// An [`Error::Parse`] without a line.
fn invalid(path: &Path, message: String) -> Error {
    Error::Parse { path: path.to_path_buf(), line: None, message }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn confines_paths_to_the_scene_folder() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let no = LoadOptions::default();
        assert_eq!(resolve_in_scene(d, "a.mtl", "mtllib", no).unwrap(), d.join("a.mtl"));
        assert_eq!(resolve_in_scene(d, "sub/../a.mtl", "mtllib", no).unwrap(), d.join("sub/../a.mtl"));
        for bad in ["/etc/passwd", "../../../../etc/passwd", "sub/../../x", "file:///etc/passwd", "http://x/y"] {
            let e = resolve_in_scene(d, bad, "mtllib", no).unwrap_err();
            assert!(e.contains("mtllib") && e.contains(bad), "{bad}: {e}");
        }
        let yes = LoadOptions { allow_outside_paths: true };
        assert_eq!(resolve_in_scene(d, "/etc/passwd", "x", yes).unwrap(), PathBuf::from("/etc/passwd"));
        assert_eq!(resolve_in_scene(d, "file:///etc/passwd", "x", yes).unwrap(), PathBuf::from("/etc/passwd"));
    }

    #[cfg(unix)]
    #[test]
    fn symbolic_links_out_of_the_folder_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::os::unix::fs::symlink("/etc/hostname", dir.path().join("link.mtl")).unwrap();
        let e = resolve_in_scene(dir.path(), "link.mtl", "mtllib", LoadOptions::default()).unwrap_err();
        assert!(e.contains("resolves to"), "{e}");
    }

    #[test]
    fn bounded_reads() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("f.bin");
        std::fs::write(&f, [7u8; 100]).unwrap();
        assert_eq!(read_bounded(&f, 100).unwrap().len(), 100);
        let e = read_bounded(&f, 99).unwrap_err().to_string();
        assert!(e.contains("100 bytes") && e.contains("limit of 99"), "{e}");
        let e = read_bounded(dir.path(), 99).unwrap_err().to_string();
        assert!(e.contains("directory"), "{e}");
        if Path::new("/dev/zero").exists() {
            let e = read_bounded(Path::new("/dev/zero"), MAX_INPUT_BYTES).unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
    }

    #[test]
    fn long_names_are_shortened() {
        let long = "9".repeat(1_000_000);
        let s = short(&long);
        assert!(s.len() < 120 && s.contains("1000000 characters"), "{s}");
    }
}
