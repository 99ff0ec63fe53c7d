//! `plie render --scene scene.xml` end to end (issue 18): the Mitsuba film's size and sensor are the
//! defaults, options override them, and what plie changed or ignored is printed as warnings on stderr.

mod support;

use std::path::{Path, PathBuf};

use support::{plie, stderr};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../plie/tests/data/mitsuba").join(name)
}

fn png_size(path: &Path) -> (u32, u32) {
    let d = std::fs::read(path).unwrap();
    (u32::from_be_bytes(d[16..20].try_into().unwrap()), u32::from_be_bytes(d[20..24].try_into().unwrap()))
}

#[test]
fn film_size_is_the_default_and_options_override_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.png");
    let scene = data("meshes.xml");
    let args = [
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--eye-rays",
        "1",
        "--shadow-rays",
        "1",
    ];
    let o = plie(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(png_size(&out), (160, 120), "the film's size");
    let err = stderr(&o);
    assert!(err.contains("warning: ignored 1 emitter"), "{err}");
    assert!(err.contains("warning: materials plie cannot render yet") && err.contains("'blue-plastic'"), "{err}");
    assert!(err.contains("warning: dropped 1 shape"), "{err}");
    let o = plie(&[&args[..], &["--width", "40", "--quiet"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(png_size(&out), (40, 120), "--width overrides the film's width only");
    assert!(stderr(&o).is_empty(), "--quiet silences the warnings: {}", stderr(&o));
}

#[test]
fn a_bad_scene_file_is_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.xml");
    std::fs::write(&scene, "<scene version=\"3.0.0\">\n<shape type=\"cylinder\"/>\n</scene>\n").unwrap();
    let out = dir.path().join("o.png");
    let o = plie(&["render", "--scene", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("s.xml:2: <shape type=\"cylinder\">: shape type 'cylinder' is not supported"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
