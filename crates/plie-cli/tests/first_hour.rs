//! What a new user is told (issue 17): help that stands alone, a description per built-in scene,
//! a warning for every option or material feature that is ignored, `--plie` choosing the P-LIE's
//! best mode, and the small things (`wrote FILE` with `--stats`, "1 light").

mod support;

use std::path::Path;

use support::{plie, stderr};

/// A small image, so each render takes milliseconds.
const SMALL: [&str; 8] = ["--width", "16", "--height", "16", "--eye-rays", "1", "--shadow-rays", "1"];

/// Runs `plie render` with `args` plus a small image, expecting success; returns stderr.
fn render_ok(args: &[&str]) -> String {
    let o = plie(&[&["render"][..], args, &SMALL[..]].concat());
    let err = stderr(&o);
    assert!(o.status.success(), "{args:?}: {err}");
    err
}

fn warnings(err: &str) -> Vec<&str> {
    err.lines().filter(|l| l.starts_with("warning: ")).collect()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn help_stands_alone() {
    let commands: [&[&str]; 5] = [&[], &["scenes"], &["render"], &["build"], &["inspect"]];
    for cmd in commands {
        let o = plie(&[cmd, &["--help"][..]].concat());
        assert!(o.status.success());
        let help = String::from_utf8_lossy(&o.stdout);
        for cited in ["SPEC", "§", "thesis", "mode a", "mode (a)", "Table"] {
            assert!(
                !help.contains(cited),
                "plie {cmd:?} --help cites '{cited}', a document users do not have:\n{help}"
            );
        }
    }
    let o = plie(&["render", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout).split_whitespace().collect::<Vec<_>>().join(" ");
    for words in [
        "`brute`: test every triangle",
        "`bvh`: a bounding volume hierarchy",
        "`grid`: a grid on each",
        "`none` (no shadow test",
        "with --plie, the fastest mode",
    ] {
        assert!(help.contains(words), "render --help should explain '{words}':\n{help}");
    }
}

#[test]
fn scenes_have_a_description_each() {
    let o = plie(&["scenes"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    for line in out.lines().skip(1) {
        let what = line.split_whitespace().skip(3).collect::<Vec<_>>();
        assert!(what.len() >= 4, "no description: {line}");
    }
    let o = plie(&["scenes", "--json"]);
    let first: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&o.stdout).lines().next().unwrap()).unwrap();
    assert!(first["description"].as_str().is_some_and(|d| d.contains("Cornell")), "{first}");
}

#[test]
fn build_offers_no_camera_options() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.plie");
    let o = plie(&["build", "--scene", "cornell-cube-2", "-o", path(&out), "--eye", "1,2,3"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--eye"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn options_a_mode_does_not_use_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("c.png");
    let file = dir.path().join("some.plie");
    std::fs::write(&file, b"not read").unwrap();
    let err = render_ok(&["--scene", "cornell-cube-2", "-o", path(&img), "--visibility", "bvh", "--plie", path(&file)]);
    let w = warnings(&err);
    assert!(w.len() == 1 && w[0].contains("--plie") && w[0].contains("ignored"), "{err}");

    let err = render_ok(&["--scene", "cornell-cube-2", "-o", path(&img), "--refine", "umbra", "--no-propagation"]);
    let w = warnings(&err);
    assert_eq!(w.len(), 2, "{err}");
    assert!(w[0].contains("--refine is ignored") && w[1].contains("--no-propagation is ignored"), "{err}");

    let err = render_ok(&["--scene", "cornell-cube-2", "-o", path(&img), "--visibility", "lie", "--no-grids"]);
    assert!(warnings(&err).iter().any(|l| l.contains("--no-grids is ignored")), "{err}");

    // Used options give no warning, and --quiet silences the rest.
    let err = render_ok(&["--scene", "cornell-cube-2", "-o", path(&img), "--visibility", "lie", "--refine", "umbra"]);
    assert!(warnings(&err).is_empty(), "{err}");
    let err = render_ok(&["--scene", "cornell-cube-2", "-o", path(&img), "--refine", "umbra", "-q"]);
    assert!(err.is_empty(), "{err}");
}

#[test]
fn plie_file_without_a_mode_uses_its_best_mode() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("c.png");
    let files: [(&[&str], &str); 3] =
        [(&[], "grid"), (&["--no-grids"], "penumbra"), (&["--no-regions", "--no-grids"], "lie")];
    for (extra, best) in files {
        let file = dir.path().join("c.plie");
        let o = plie(&[&["build", "--scene", "cornell-cube-2", "-q", "-o", path(&file)][..], extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let o = plie(
            &[
                &["render", "--scene", "cornell-cube-2", "-o", path(&img), "--plie", path(&file), "--json"][..],
                &SMALL[..],
            ]
            .concat(),
        );
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["visibility"], best, "{extra:?}");
        assert!(v["plie_load_seconds"].is_number(), "the file was read: {v}");
        assert!(warnings(&stderr(&o)).is_empty(), "{}", stderr(&o));
    }
}

#[test]
fn stats_keep_the_wrote_line_and_count_one_light() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("c.png");
    let err = render_ok(&["--scene", "cornell-cube-2", "-o", path(&img), "--stats"]);
    assert!(err.lines().any(|l| l.starts_with("wrote ") && l.contains("c.png")), "{err}");
    assert!(err.contains("(32 triangles, 1 light)"), "{err}");
    assert!(!err.contains("1 lights"), "{err}");
    let err = render_ok(&["--scene", "cornell-cube-4", "-o", path(&img), "--stats"]);
    assert!(err.contains("2 lights"), "{err}");
    let o = plie(&["build", "--scene", "cornell-cube-2", "-o", path(&dir.path().join("c.plie"))]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("1 light)") && !out.contains("-0.000"), "{out}");
}

#[test]
fn material_features_not_rendered_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 0 1 1\nv 1 1 1\nv 1 1 0\n\
               usemtl shiny\nf 1 3 2\nusemtl painted\nf 1 4 3\nusemtl lamp\nf 5 8 7\nf 5 7 6\n";
    let mtl = "newmtl shiny\nKd 0.5 0.5 0.5\nKs 0.9 0.9 0.9\nnewmtl painted\nKd 0.8 0.8 0.8\nKs 0 0 0\n\
               map_Kd missing.png\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n";
    std::fs::write(dir.path().join("s.obj"), obj).unwrap();
    std::fs::write(dir.path().join("m.mtl"), mtl).unwrap();
    let scene = dir.path().join("s.obj");
    let img = dir.path().join("s.png");
    let err = render_ok(&["--scene", path(&scene), "-o", path(&img)]);
    let w = warnings(&err);
    assert_eq!(w.len(), 2, "one warning per feature (Ks 0 0 0 is no specular): {err}");
    assert!(w.iter().any(|l| l.contains("'shiny'") && l.contains("Ks")), "{err}");
    assert!(w.iter().any(|l| l.contains("'painted'") && l.contains("map_Kd") && l.contains("missing")), "{err}");
    let err = render_ok(&["--scene", path(&scene), "-o", path(&img), "-q"]);
    assert!(err.is_empty(), "{err}");
}

#[cfg(not(feature = "embree"))]
#[test]
fn embree_without_the_feature_says_how_to_build_it() {
    let o = plie(&["render", "--scene", "cornell-cube-2", "-o", "x.png", "--visibility", "embree"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--features embree") && err.contains("libembree-dev"), "{err}");
}
