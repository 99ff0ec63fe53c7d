//! Checks of the command line before any long work: outputs never overwrite an input, `build`
//! writes only `.plie`, output folders exist, `--threads` is bounded, and messages never echo a huge
//! argument back.
//!
//! The inputs a command knows before loading the scene (the scene file, `--plie`, `--camera-path`)
//! are checked at once by [`output_is_not_input`]; the files the scene file names (its MTL libraries,
//! textures, Mitsuba includes and meshes, glTF buffers and images) are known only once it is loaded
//! ([`plie::Scene::sources`]), so each command checks its outputs against them with
//! [`outputs_are_not_sources`] right after loading, before any rendering or writing.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

/// The most worker threads `--threads` accepts.
pub const MAX_THREADS: usize = 1024;

/// Sets the global rayon pool size (`--threads`, 1 to [`MAX_THREADS`]).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if !(1..=MAX_THREADS).contains(&t) {
            bail!("--threads {t} must be between 1 and {MAX_THREADS}");
        }
        if let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(t).build_global() {
            bail!("--threads {t}: cannot start the worker threads ({e})");
        }
    }
    Ok(())
}

/// Checks that `output` is a new file name in an existing folder and is none of `inputs` (compared
/// after resolving `.`, `..` and symbolic links, and by file identity when both exist).
pub fn output_is_not_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    output_folder_exists(output)?;
    if output.is_dir() {
        bail!("{}: is a directory; give a file name for -o", output.display());
    }
    not_an_input(output, inputs)
}

/// Checks that none of `outputs` (checked by [`output_is_not_input`] before the scene was loaded)
/// is one of `sources`, the files the loaded scene read ([`plie::Scene::sources`]); the same message.
pub fn outputs_are_not_sources(outputs: &[PathBuf], sources: &[PathBuf]) -> Result<()> {
    let sources: Vec<&Path> = sources.iter().map(PathBuf::as_path).collect();
    outputs.iter().try_for_each(|output| not_an_input(output, &sources))
}

/// Checks that `output` is none of `inputs` (compared after resolving `.`, `..` and symbolic links,
/// and by file identity when both exist).
fn not_an_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    let out = resolved(output);
    for input in inputs {
        if resolved(input) == out || same_file(output, input) {
            bail!(
                "{}: -o names an input of this command ({}); choose another output file",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Checks that the folder of `output` exists (one message for every command).
pub fn output_folder_exists(output: &Path) -> Result<()> {
    let dir = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!("{}: the output folder {} does not exist", output.display(), dir.display());
    }
    Ok(())
}

/// Checks that `build`'s output ends in `.plie` and is not an input.
pub fn plie_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    let ext = output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    if ext.as_deref() != Some("plie") {
        bail!("{}: plie build writes only .plie files; name the output FILE.plie", output.display());
    }
    output_is_not_input(output, inputs)
}

/// `path` made absolute, with its folder's symbolic links resolved (the file need not exist).
fn resolved(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (abs.parent().and_then(|d| d.canonicalize().ok()), abs.file_name()) {
        (Some(dir), Some(name)) => dir.join(name),
        _ => abs,
    }
}

/// Whether two existing paths are the same file (hard links included).
#[cfg(unix)]
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &Path, _: &Path) -> bool {
    false
}

/// The message with every word longer than 80 characters cut (a 1,000,000-digit argument is not
/// echoed back in full).
pub fn shorten_long_words(message: &str) -> String {
    const MAX: usize = 80;
    let mut out = String::with_capacity(message.len().min(4096));
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        let n = word.chars().count();
        if n > MAX {
            out.extend(word.chars().take(MAX));
            out.push_str(&format!("... ({n} characters)"));
        } else {
            out.push_str(word);
        }
        word.clear();
    };
    for ch in message.chars() {
        if ch.is_whitespace() || ch == '\'' || ch == '"' || ch == '`' {
            flush(&mut word, &mut out);
            out.push(ch);
        } else {
            word.push(ch);
        }
    }
    flush(&mut word, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_are_not_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("s.obj");
        std::fs::write(&scene, "v 0 0 0").unwrap();
        assert!(output_is_not_input(&dir.path().join("out.png"), &[&scene]).is_ok());
        let e = output_is_not_input(&scene, &[&scene]).unwrap_err().to_string();
        assert!(e.contains("names an input"), "{e}");
        let again = dir.path().join("sub/../s.obj");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        assert!(output_is_not_input(&again, &[&scene]).is_err(), "the same file by another name");
        let e = output_is_not_input(dir.path(), &[&scene]).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        let e = output_is_not_input(&dir.path().join("no/out.png"), &[]).unwrap_err().to_string();
        assert!(e.contains("output folder") && e.contains("does not exist"), "{e}");
    }

    #[test]
    fn outputs_are_not_files_the_scene_read() {
        let dir = tempfile::tempdir().unwrap();
        let (tex, mtl) = (dir.path().join("tex.png"), dir.path().join("m.mtl"));
        std::fs::write(&tex, "png").unwrap();
        std::fs::write(&mtl, "newmtl a").unwrap();
        let sources = [dir.path().join("s.obj"), mtl.clone(), tex.clone()];
        assert!(outputs_are_not_sources(&[dir.path().join("out.png")], &sources).is_ok());
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let e = outputs_are_not_sources(&[dir.path().join("sub/../tex.png")], &sources).unwrap_err().to_string();
        assert!(e.contains("names an input") && e.contains("tex.png") && !e.contains('\n'), "{e}");
        assert!(outputs_are_not_sources(std::slice::from_ref(&mtl), &sources).is_err(), "the MTL library");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&tex, dir.path().join("link.png")).unwrap();
            assert!(outputs_are_not_sources(&[dir.path().join("link.png")], &sources).is_err(), "through a link");
            std::fs::hard_link(&tex, dir.path().join("hard.png")).unwrap();
            assert!(outputs_are_not_sources(&[dir.path().join("hard.png")], &sources).is_err(), "a hard link");
        }
        // An output that passed the check before loading (the file did not exist then) is caught by
        // the check after, against what the scene read.
        let out = dir.path().join("late.png");
        output_is_not_input(&out, &[]).unwrap();
        std::fs::write(&out, "png").unwrap();
        assert!(outputs_are_not_sources(std::slice::from_ref(&out), std::slice::from_ref(&out)).is_err());
        assert!(outputs_are_not_sources(&[out], &sources).is_ok());
    }

    #[test]
    fn build_writes_only_plie() {
        let dir = tempfile::tempdir().unwrap();
        assert!(plie_output(&dir.path().join("a.plie"), &[]).is_ok());
        for bad in ["a.obj", "b.pfm", "c"] {
            let e = plie_output(&dir.path().join(bad), &[]).unwrap_err().to_string();
            assert!(e.contains("only .plie"), "{e}");
        }
    }

    #[test]
    fn threads_are_bounded() {
        for t in [0, MAX_THREADS + 1, 100_000] {
            let e = set_threads(Some(t)).unwrap_err().to_string();
            assert!(e.contains("between 1 and 1024"), "{e}");
        }
    }

    #[test]
    fn long_words_are_cut() {
        let m = format!("invalid value '{}' for '--width'", "9".repeat(1_000_000));
        let s = shorten_long_words(&m);
        assert!(s.len() < 200 && s.contains("(1000000 characters)") && s.contains("--width"), "{s}");
    }
}
