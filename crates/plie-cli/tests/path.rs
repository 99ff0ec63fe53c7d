//! `plie render --integrator path` and `plie bench --path` end to end: figures in `--json`, the same
//! image in every exact mode, one-line errors for bad options.

mod support;

use support::{fails_with, plie, stderr};

fn render_path(out: &str, mode: &str) -> serde_json::Value {
    let o = plie(&[
        "render",
        "--scene",
        "cornell-cube-2",
        "-o",
        out,
        "--width",
        "12",
        "--height",
        "10",
        "--integrator",
        "path",
        "--max-path-depth",
        "4",
        "--spp",
        "3",
        "--shadow-rays",
        "2",
        "--visibility",
        mode,
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

#[test]
fn path_json_counts_rays_by_kind_and_modes_agree() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("bvh.pfm");
    let b = dir.path().join("grid.pfm");
    let va = render_path(a.to_str().unwrap(), "bvh");
    let vb = render_path(b.to_str().unwrap(), "grid");
    assert_eq!(va["integrator"], "path");
    assert_eq!(va["camera_rays"], 12 * 10 * 3);
    assert!(va["bounce_rays"].as_u64().unwrap() > 0);
    assert!(va["shadow_rays"].as_u64().unwrap() > 0);
    assert!(va["shadow_test_seconds"].as_f64().unwrap() > 0.0);
    assert_eq!(va["locates"], 0, "bvh does not locate leaves");
    assert!(vb["locates"].as_u64().unwrap() > 0, "grid locates every path vertex");
    for k in ["camera_rays", "bounce_rays", "shadow_rays", "occluded"] {
        assert_eq!(va[k], vb[k], "{k}");
    }
    assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap(), "bvh and grid images differ");
}

#[test]
fn bad_path_options_give_one_line_errors() {
    let base = ["render", "--scene", "cornell-cube-1", "-o", "/tmp/plie-path-bad.png", "--width", "4", "--height", "4"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> { base.iter().chain(extra).copied().collect() };
    fails_with(&with(&["--integrator", "path", "--max-path-depth", "0"]), "max depth");
    fails_with(&with(&["--integrator", "path", "--max-path-depth", "-2"]), "max depth");
    fails_with(&with(&["--integrator", "path", "--spp", "0"]), "samples per pixel");
    fails_with(&with(&["--spp", "3"]), "square");
    let o = plie(&with(&["--spp", "4", "--eye-rays", "2"]));
    assert!(!o.status.success(), "--spp and --eye-rays together should be refused");
    assert!(!stderr(&o).contains("panicked"));
}

#[test]
fn direct_spp_sets_the_eye_rays() {
    let o = plie(&[
        "render",
        "--scene",
        "cornell-cube-1",
        "-o",
        "/tmp/plie-path-spp.png",
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "9",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["eye_rays"], 3);
    assert_eq!(v["integrator"], "direct");
}

#[test]
fn bench_path_quick_writes_the_path_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let o = plie(&["bench", "--path", "--quick", "--path-size", "8", "--out", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(out.join("path.md")).unwrap();
    assert!(md.contains("| cornell-cube-1 | 3 | bvh |") && md.contains("| cornell-cube-3 | 5 | grid |"), "{md}");
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("path.json")).unwrap()).unwrap();
    // 2 scenes x 2 depths x (bvh, grid, none).
    assert_eq!(rows.as_array().unwrap().len(), 12);
}
