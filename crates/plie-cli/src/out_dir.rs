//! The output folder of `plie bench` (`--out`): checked before anything is measured, created only
//! when the first file is written (after the measurements), and removed again if the command fails
//! after creating it. Removal takes only what this run made: the files it wrote and then the folders
//! it created, each only if empty (`remove_dir`), so a folder that existed before, or a file that
//! another program put into the new folder, stays.
//!
//! Created late, the folder is not left behind by a failure while measuring (a scene that does not
//! load, an error in a mode) nor by an interruption while measuring (Ctrl-C).

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// An output folder and what this run created in it; dropped without [`OutDir::keep`], it removes
/// what the run created.
pub struct OutDir {
    path: PathBuf,
    /// The folders this run created, outermost first (`path` and its missing parents).
    created: Vec<PathBuf>,
    /// The files this run wrote into a folder it created.
    written: Vec<PathBuf>,
    /// The command succeeded: what it wrote stays.
    kept: bool,
}

impl OutDir {
    /// The folder `path`, not created yet: checked to be a folder, or to be one that can be created
    /// (by creating it and its missing parents, then removing them again).
    pub fn new(path: &Path) -> Result<OutDir> {
        let probe = create_missing(path).with_context(|| format!("cannot create directory {}", path.display()))?;
        remove_empty(&probe);
        Ok(OutDir { path: path.to_path_buf(), created: Vec::new(), written: Vec::new(), kept: false })
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `text` to the file `name` of the folder, atomically, creating the folder first if it
    /// is missing.
    pub fn write(&mut self, name: &str, text: &str) -> Result<()> {
        let created =
            create_missing(&self.path).with_context(|| format!("cannot create directory {}", self.path.display()))?;
        self.created.extend(created);
        let path = self.path.join(name);
        let io = |e| plie::Error::Io { path: path.clone(), source: e };
        // On failure the file is as before (and the temporary file gone): nothing to remember.
        plie::io::write_atomic(&path, |w| w.write_all(text.as_bytes()).map_err(io))
            .with_context(|| format!("cannot write {}", path.display()))?;
        if !self.created.is_empty() {
            self.written.push(path);
        }
        Ok(())
    }

    /// The command succeeded: the folder and its files stay.
    pub fn keep(mut self) {
        self.kept = true;
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if self.kept || self.created.is_empty() {
            return;
        }
        for file in &self.written {
            let _ = fs::remove_file(file);
        }
        remove_empty(&self.created);
    }
}

/// Creates `path` and its missing parents; the folders created, outermost first. Fails if `path`
/// exists but is not a folder.
fn create_missing(path: &Path) -> io::Result<Vec<PathBuf>> {
    let mut missing: Vec<&Path> =
        path.ancestors().take_while(|p| !p.as_os_str().is_empty() && fs::symlink_metadata(p).is_err()).collect();
    missing.reverse();
    let mut created = Vec::new();
    for dir in missing {
        match fs::create_dir(dir) {
            Ok(()) => created.push(dir.to_path_buf()),
            // Made meanwhile by someone else (or `a/..` after `a`): not ours.
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && dir.is_dir() => {}
            Err(e) => {
                remove_empty(&created);
                return Err(e);
            }
        }
    }
    if !path.is_dir() {
        remove_empty(&created);
        return Err(io::Error::new(io::ErrorKind::NotADirectory, "it exists and is not a directory"));
    }
    Ok(created)
}

/// Removes the folders `dirs` (outermost first), innermost first, each only if empty.
fn remove_empty(dirs: &[PathBuf]) {
    for dir in dirs.iter().rev() {
        let _ = fs::remove_dir(dir);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut n: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        n.sort();
        n
    }

    #[test]
    fn the_folder_is_created_by_the_first_file_and_kept_on_success() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a").join("b");
        let mut out = OutDir::new(&path).unwrap();
        assert!(!dir.path().join("a").exists(), "checked, not created");
        out.write("x.md", "x").unwrap();
        out.write("y.md", "y").unwrap();
        out.keep();
        assert_eq!(names(&path), ["x.md", "y.md"]);
    }

    #[test]
    fn a_failed_run_removes_what_it_created_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let top = dir.path().join("a");
        let path = top.join("b");
        {
            let mut out = OutDir::new(&path).unwrap();
            out.write("x.md", "x").unwrap();
        }
        assert!(!top.exists(), "the folders created and the file written are gone");

        // A file written, then a failure to write the next one (a folder of that name, put there by
        // someone else): the file goes, the other folder and so the new folders stay.
        {
            let mut out = OutDir::new(&path).unwrap();
            out.write("x.md", "x").unwrap();
            fs::create_dir(path.join("y.md")).unwrap();
            assert!(out.write("y.md", "y").is_err());
        }
        assert_eq!(names(&path), ["y.md"]);
        fs::remove_dir_all(&top).unwrap();

        // A folder that existed: kept with what was written into it.
        fs::create_dir(&top).unwrap();
        fs::write(top.join("old.md"), "old").unwrap();
        {
            let mut out = OutDir::new(&top).unwrap();
            out.write("x.md", "x").unwrap();
        }
        assert_eq!(names(&top), ["old.md", "x.md"]);
    }

    #[test]
    fn a_path_that_cannot_be_a_folder_is_an_error_and_creates_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        fs::write(&file, "f").unwrap();
        assert!(OutDir::new(&file).is_err());
        assert!(OutDir::new(&file.join("a").join("b")).is_err());
        assert_eq!(names(dir.path()), ["f"]);
    }
}
