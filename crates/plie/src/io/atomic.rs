//! Atomic file writes for every output file (SPEC §2 output): write a temporary file in the target's
//! directory, fsync it, rename it over the target. A reader sees the old file or the complete new one,
//! never a torn write; on any error the target is untouched and the temporary file is removed
//! (`tempfile` deletes it on drop).

use std::fs::File;
use std::io::{self, BufWriter, Seek, Write};
use std::path::Path;

use crate::error::{Error, Result};

/// What [`write_atomic`] hands to the writing function: a buffered, seekable file (OpenEXR needs to
/// seek).
pub trait WriteSeek: Write + Seek {}
impl<T: Write + Seek> WriteSeek for T {}

/// Writes `path` atomically: `write` fills a temporary file in the same directory, which is then
/// flushed, fsynced and renamed over `path`. If `write` fails, or anything else does, `path` is left as
/// it was and the temporary file is removed. A missing or unwritable directory is an [`Error::Io`]
/// naming `path`. New files get mode 0644 on Unix (an existing target's permissions are kept).
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn WriteSeek) -> Result<()>) -> Result<()> {
    let io_err = |what: &str, e: io::Error| Error::Io {
        path: path.to_path_buf(),
        source: io::Error::new(e.kind(), format!("{what}: {e}")),
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(".plie-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| io_err(&format!("cannot create a temporary file in directory '{}'", dir.display()), e))?;
    let mut out = BufWriter::new(tmp);
    write(&mut out)?;
    let tmp = out.into_inner().map_err(|e| io_err("cannot write", e.into_error()))?;
    set_permissions(tmp.as_file(), path).map_err(|e| io_err("cannot set permissions", e))?;
    tmp.as_file().sync_all().map_err(|e| io_err("cannot sync", e))?;
    tmp.persist(path).map_err(|e| io_err("cannot rename the temporary file over the target", e.error))?;
    // Make the rename itself durable; not possible everywhere (e.g. directories on Windows), so best effort.
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Gives the temporary file the target's permissions, or 0644 for a new file (tempfile creates 0600).
#[cfg(unix)]
fn set_permissions(file: &File, target: &Path) -> io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    let perm = match std::fs::metadata(target) {
        Ok(m) => m.permissions(),
        Err(_) => std::fs::Permissions::from_mode(0o644),
    };
    file.set_permissions(perm)
}

#[cfg(not(unix))]
fn set_permissions(_file: &File, _target: &Path) -> io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, |w| w.write_all(b"one").map_err(|e| Error::Io { path: p.clone(), source: e })).unwrap();
        write_atomic(&p, |w| w.write_all(b"two").map_err(|e| Error::Io { path: p.clone(), source: e })).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file left");
    }
}
