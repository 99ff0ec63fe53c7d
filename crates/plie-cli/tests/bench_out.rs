//! `plie bench --out`: a run that fails leaves no folder it created (it used to leave an empty one
//! behind), and never touches a folder that existed before. Options and scene names are checked
//! before anything is measured or created; the folder is created when the results are written.

mod support;

use std::path::Path;

use support::{plie, stderr};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A failure with a one-line message containing `needle`, without a panic.
fn fails(args: &[&str], needle: &str) {
    let o = plie(args);
    let err = stderr(&o);
    assert!(!o.status.success(), "{args:?} should fail; stderr: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert_eq!(err.lines().filter(|l| !l.trim().is_empty()).count(), 1, "{args:?}: one line: {err}");
    assert!(err.contains(needle), "{args:?}: error should mention '{needle}': {err}");
}

#[test]
fn a_failed_bench_leaves_no_folder_behind() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nf 1 2 3\n").unwrap();
    let scenes = format!("cornell-cube-1,{}", s(&bad));
    let missing = format!("cornell-cube-1,{}", s(&dir.path().join("missing.obj")));
    // The folder and its missing parent: neither may stay.
    let new = dir.path().join("new");
    let out = new.join("out");
    let cases: [(&[&str], &str); 5] = [
        // A scene file that exists but does not load: found while measuring.
        (&["bench", "--quick", "-q", "--scenes", &scenes, "--out", s(&out)], "bad.obj"),
        (&["bench", "--path", "--quick", "-q", "--path-size", "8", "--scenes", &scenes, "--out", s(&out)], "bad.obj"),
        // A scene that does not exist, an option out of range: found before anything runs.
        (&["bench", "--quick", "-q", "--scenes", &missing, "--out", s(&out)], "missing.obj"),
        (&["bench", "--soft-shadows", "-q", "--scenes", &missing, "--out", s(&out)], "missing.obj"),
        (&["bench", "--path", "--quick", "-q", "--path-size", "0", "--out", s(&out)], "--path-size"),
    ];
    for (args, needle) in cases {
        fails(args, needle);
        assert!(!new.exists(), "{args:?} left {} behind", new.display());
    }
}

#[test]
fn a_failed_bench_keeps_a_folder_that_existed_and_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("report.md"), "earlier results").unwrap();
    fails(&["bench", "--quick", "-q", "--scenes", "cornell-cube-1,nosuch", "--out", s(&out)], "nosuch");
    let files: Vec<_> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(files, ["report.md"], "nothing added or removed");
    assert_eq!(std::fs::read_to_string(out.join("report.md")).unwrap(), "earlier results");
}

#[test]
fn a_bench_output_that_cannot_be_a_folder_is_an_error_before_measuring() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("file");
    std::fs::write(&file, "mine").unwrap();
    fails(&["bench", "--quick", "-q", "--out", s(&file)], "cannot create directory");
    fails(&["bench", "--quick", "-q", "--out", s(&file.join("out"))], "cannot create directory");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
}
