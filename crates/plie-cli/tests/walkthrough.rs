//! `plie render --camera-path`: walkthroughs end to end. Keyframe frames equal single renders with
//! that camera, bit for bit; a saved P-LIE gives the same frames as one built; `--resume` keeps
//! existing frames; bad paths, ranges and patterns are one-line errors.

mod support;

use std::path::Path;

use support::{fails_with, plie, stderr};

const SMALL: [&str; 8] = ["--width", "20", "--height", "16", "--eye-rays", "1", "--shadow-rays", "3"];

/// A path of cornell-cube-2 with keyframes at frames 0, 2 and 4.
fn write_path(dir: &Path, interpolation: &str) -> String {
    let p = dir.join("path.json");
    let k = |f: u32, x: f32| {
        format!(r#"{{"frame": {f}, "eye": [{x}, 273, -800], "target": [278, 273, 0], "up": [0, 1, 0], "fov": 39.3}}"#)
    };
    let text = format!(
        r#"{{"interpolation": "{interpolation}", "keyframes": [{}, {}, {}]}}"#,
        k(0, 278.0),
        k(2, 378.0),
        k(4, 178.0)
    );
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

fn render(args: &[&str]) {
    let mut all = vec!["render", "--scene", "cornell-cube-2", "--quiet"];
    all.extend_from_slice(args);
    all.extend_from_slice(&SMALL);
    let o = plie(&all);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn keyframes_match_single_renders_and_a_loaded_plie_matches_a_built_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let path = write_path(d, "catmull-rom");
    let pattern = d.join("built_###.pfm");
    render(&["--camera-path", &path, "--visibility", "grid", "-o", pattern.to_str().unwrap()]);
    for f in 0..=4 {
        assert!(d.join(format!("built_{f:03}.pfm")).exists(), "frame {f} missing");
    }
    // Frame 2 is a keyframe: the same image as a single render from its camera.
    let single = d.join("single.pfm");
    render(&[
        "--eye",
        "378,273,-800",
        "--target",
        "278,273,0",
        "--up",
        "0,1,0",
        "--fov",
        "39.3",
        "--visibility",
        "bvh",
        "-o",
        single.to_str().unwrap(),
    ]);
    assert_eq!(read(&single), read(&d.join("built_002.pfm")));
    // In-between frames are new cameras.
    assert_ne!(read(&d.join("built_001.pfm")), read(&d.join("built_002.pfm")));
    assert_ne!(read(&d.join("built_001.pfm")), read(&d.join("built_000.pfm")));

    // The same frames from a saved P-LIE, frames 1..3 only.
    let file = d.join("c.plie");
    let o = plie(&["build", "--scene", "cornell-cube-2", "-o", file.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let loaded = d.join("loaded_#.pfm");
    render(&[
        "--camera-path",
        &path,
        "--frames",
        "1..3",
        "--plie",
        file.to_str().unwrap(),
        "-o",
        loaded.to_str().unwrap(),
    ]);
    for f in 1..=3 {
        assert_eq!(read(&d.join(format!("loaded_{f}.pfm"))), read(&d.join(format!("built_00{f}.pfm"))), "frame {f}");
    }
    assert!(!d.join("loaded_0.pfm").exists() && !d.join("loaded_4.pfm").exists());
}

#[test]
fn linear_and_catmull_rom_differ_between_keyframes_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for interp in ["linear", "catmull-rom"] {
        let sub = d.join(interp);
        std::fs::create_dir(&sub).unwrap();
        let path = write_path(&sub, interp);
        render(&["--camera-path", &path, "--frames", "2..3", "-o", sub.join("f#.pfm").to_str().unwrap()]);
    }
    assert_eq!(read(&d.join("linear/f2.pfm")), read(&d.join("catmull-rom/f2.pfm")));
    assert_ne!(read(&d.join("linear/f3.pfm")), read(&d.join("catmull-rom/f3.pfm")));
}

#[test]
fn resume_skips_existing_frames_and_without_it_they_are_rewritten() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let path = write_path(d, "linear");
    let pattern = d.join("f#.png");
    std::fs::write(d.join("f1.png"), b"kept").unwrap();
    let o = plie(
        &[
            &["render", "--scene", "cornell-cube-2", "--camera-path", &path, "--frames", "0..2", "--resume"][..],
            &["-o", pattern.to_str().unwrap()],
            &SMALL,
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("frame 1 (2 of 3) skipped"), "{}", stderr(&o));
    assert_eq!(read(&d.join("f1.png")), b"kept");
    assert!(read(&d.join("f0.png")).starts_with(b"\x89PNG") && read(&d.join("f2.png")).starts_with(b"\x89PNG"));
    render(&["--camera-path", &path, "--frames", "1", "-o", pattern.to_str().unwrap()]);
    assert!(read(&d.join("f1.png")).starts_with(b"\x89PNG"));
}

#[test]
fn bad_walkthroughs_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let path = write_path(d, "linear");
    let out = d.join("f_##.png");
    let out = out.to_str().unwrap();
    let run = |extra: &[&str], needle: &str| {
        let mut args = vec!["render", "--scene", "cornell-cube-2"];
        args.extend_from_slice(extra);
        fails_with(&args, needle);
    };
    run(&["--camera-path", &path, "-o", d.join("f.png").to_str().unwrap()], "one run of #");
    run(&["--camera-path", &path, "--frames", "3..9", "-o", out], "outside the camera path's frames 0..4");
    run(&["--camera-path", &path, "--frames", "3..1", "-o", out], "before the first");
    run(&["--camera-path", &path, "--eye", "1,2,3", "-o", out], "cannot be used with");
    run(&["--frames", "1..2", "-o", out], "--camera-path");
    let bad = d.join("bad.json");
    for (text, needle) in [
        ("{\"interpolation\": \"linear\"", "EOF while parsing"),
        ("{\"interpolation\": \"spline\", \"keyframes\": []}", "unknown variant"),
        ("{\"interpolation\": \"linear\", \"keyframes\": []}", "no keyframes"),
        (
            "{\"interpolation\": \"linear\", \"keyframes\": [{\"frame\": 0, \"eye\": [0,0,0], \"target\": [0,0,0], \"up\": [0,1,0], \"fov\": 40}]}",
            "coincide",
        ),
    ] {
        std::fs::write(&bad, text).unwrap();
        run(&["--camera-path", bad.to_str().unwrap(), "-o", out], needle);
    }
    run(&["--camera-path", d.join("missing.json").to_str().unwrap(), "-o", out], "missing.json");
    // A path of 4,294,967,296 frames: an error at once, not a check of every frame's camera.
    let long = d.join("long.json");
    std::fs::write(&long, std::fs::read_to_string(&path).unwrap().replace("\"frame\": 4", "\"frame\": 4294967295"))
        .unwrap();
    run(&["--camera-path", long.to_str().unwrap(), "-o", out], "at most 1000000");
    run(&["--camera-path", long.to_str().unwrap(), "--frames", "5..1000005", "-o", out], "asks for 1000001 frames");
}
