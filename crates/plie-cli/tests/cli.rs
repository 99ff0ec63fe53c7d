//! The `plie` binary end to end: listing scenes, rendering, and bad input. Every bad input must give a
//! one-line error naming the problem and a non-zero exit, never a panic.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

use support::{fails_with, plie, stderr};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const GOOD_OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 0 1 1\nv 1 1 1\nv 1 1 0\n\
usemtl white\nf 1 3 2\nf 1 4 3\nusemtl lamp\nf 5 8 7\nf 5 7 6\n";
const GOOD_MTL: &str = "newmtl white\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n";

#[test]
fn scenes_lists_ten_scenes_and_the_stress_scene() {
    let o = plie(&["scenes"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for name in ["cornell-cube-1", "cornell-cube-5", "huis-a", "huis-c", "dragon", "boot"] {
        assert!(out.lines().any(|l| l.starts_with(name)), "missing {name} in {out}");
    }
    assert_eq!(out.lines().count(), 12, "header + ten scenes + balusters: {out}");
}

#[test]
fn render_writes_png_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.png");
    let o = plie(&[
        "render",
        "--scene",
        "cornell-cube-2",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "24",
        "--height",
        "20",
        "--eye-rays",
        "1",
        "--shadow-rays",
        "2",
        "--json",
        "--visibility",
        "bvh",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    for key in [
        "scene",
        "triangles",
        "lights",
        "visibility",
        "width",
        "height",
        "hit_buffer_seconds",
        "shading_seconds",
        "shadow_rays",
        "triangle_tests",
    ] {
        assert!(v.get(key).is_some(), "missing {key} in {v}");
    }
    assert_eq!(v["triangles"], 32);
    assert_eq!(v["visibility"], "bvh");
    assert!(v["shadow_rays"].as_u64().unwrap() > 0);
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
}

/// `plie render --json --stats` in `mode` on a small Cornell Cube 1: the JSON object and stderr.
fn render_json_and_stats(dir: &Path, mode: &str) -> (serde_json::Value, String) {
    let out = dir.join(format!("{mode}.png"));
    let o = plie(&[
        "render",
        "--scene",
        "cornell-cube-1",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "40",
        "--height",
        "40",
        "--eye-rays",
        "1",
        // One sample per light: asked ray by ray, so that every ray takes one of the per-ray
        // query's answer paths (2 or more take the per-light query, whose walks count their rays
        // as `scene_bvh` whatever the answer).
        "--shadow-rays",
        "1",
        "--visibility",
        mode,
        "--json",
        "--stats",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    (serde_json::from_slice(&o.stdout).expect("one JSON object on stdout"), stderr(&o))
}

const PATHS: [&str; 9] = [
    "no_record",
    "umbra",
    "lit",
    "blockers_hit",
    "blockers_miss",
    "own_leaf",
    "inside_leaf",
    "outside_octree",
    "scene_bvh",
];

#[test]
fn render_stats_and_json_report_how_shadow_rays_were_answered() {
    let dir = tempfile::tempdir().unwrap();
    let (bvh, bvh_stats) = render_json_and_stats(dir.path(), "bvh");
    for mode in ["lie", "umbra", "penumbra", "grid"] {
        let (v, stats) = render_json_and_stats(dir.path(), mode);
        let n = |k: &str| v[k].as_u64().unwrap_or_else(|| panic!("{mode}: no count {k} in {v}"));
        let answers = v["answers"].as_object().unwrap_or_else(|| panic!("{mode}: no answers object in {v}"));
        assert_eq!(answers.len(), PATHS.len(), "{mode}: {v}");
        let path = |k: &str| answers[k].as_u64().unwrap_or_else(|| panic!("{mode}: no path {k} in {v}"));
        assert_eq!(PATHS.iter().map(|k| path(k)).sum::<u64>(), n("shadow_rays"), "{mode}: one path per ray: {v}");
        let occluded: u64 = ["no_record", "umbra", "blockers_hit", "own_leaf"].iter().map(|k| path(k)).sum();
        assert_eq!(occluded, n("occluded"), "{mode}: {v}");
        assert!(path("blockers_hit") > 0, "{mode}: {v}");
        // No record of this small scene reaches the blocker cap.
        assert_eq!(path("scene_bvh"), 0, "{mode}: {v}");
        assert_eq!(n("blocker_tests") + n("own_leaf_tests"), n("triangle_tests"), "{mode}: {v}");
        let per_ray =
            v["blocker_tests_per_shadow_ray"].as_f64().unwrap() + v["own_leaf_tests_per_shadow_ray"].as_f64().unwrap();
        assert!((per_ray - v["triangle_tests_per_shadow_ray"].as_f64().unwrap()).abs() < 1e-9, "{mode}: {v}");
        // Same image settings, exact modes: the same shadow rays and answers as bvh.
        assert_eq!(
            (n("shadow_rays"), n("occluded")),
            (bvh["shadow_rays"].as_u64().unwrap(), bvh["occluded"].as_u64().unwrap())
        );

        assert!(stats.contains("answered by"), "{mode}: {stats}");
        for k in PATHS {
            let line = stats
                .lines()
                .find(|l| l.trim_start().starts_with(k))
                .unwrap_or_else(|| panic!("{mode}: no {k} line: {stats}"));
            let count: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
            assert_eq!(count, path(k), "{mode}: {line}");
            assert!(line.ends_with('%'), "{mode}: {line}");
        }
        assert!(
            stats.contains("blocker and") && stats.contains("own-leaf triangle tests per shadow ray"),
            "{mode}: {stats}"
        );
    }
    // Modes without a P-LIE count no paths: zeros in the JSON, no table.
    assert!(bvh["answers"].as_object().unwrap().values().all(|x| x == 0), "{bvh}");
    assert_eq!((bvh["blocker_tests"].as_u64(), bvh["own_leaf_tests"].as_u64()), (Some(0), Some(0)), "{bvh}");
    assert!(!bvh_stats.contains("answered by"), "{bvh_stats}");
}

#[test]
fn none_answers_every_shadow_ray_unoccluded_and_its_help_says_it_is_not_exact() {
    let o = plie(&["render", "--help"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let help = String::from_utf8_lossy(&o.stdout).split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(help.contains("References, NOT exact:"), "{help}");
    assert!(help.contains("`none` (no shadow test: every light sample counts as visible"), "{help}");
    let dir = tempfile::tempdir().unwrap();
    let (none, _) = render_json_and_stats(dir.path(), "none");
    let (bvh, _) = render_json_and_stats(dir.path(), "bvh");
    assert_eq!(none["shadow_rays"], bvh["shadow_rays"], "the same rays are shot");
    assert!(bvh["occluded"].as_u64().unwrap() > 0, "{bvh}");
    assert_eq!(none["occluded"].as_u64(), Some(0), "{none}");
}

#[test]
fn render_pfm_is_identical_for_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    for mode in ["brute", "octree", "bvh", "lie"] {
        let out = dir.path().join(format!("{mode}.pfm"));
        let o = plie(&[
            "render",
            "--scene",
            "cornell-cube-1",
            "-o",
            out.to_str().unwrap(),
            "--width",
            "16",
            "--height",
            "16",
            "--eye-rays",
            "1",
            "--shadow-rays",
            "3",
            "--visibility",
            mode,
            "--quiet",
            "--seed",
            "3",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        images.push(std::fs::read(&out).unwrap());
    }
    assert!(images[0].len() > 16 * 16 * 12);
    assert!(images.iter().all(|i| *i == images[0]), "every mode gives the same bytes");
}

#[test]
fn build_then_render_with_the_saved_p_lie() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("d.plie");
    let f = file.to_str().unwrap();
    let o = plie(&["build", "--scene", "cornell-cube-3", "-o", f, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    for key in ["build_seconds", "leaves", "records", "blockers_total", "bytes"] {
        assert!(v.get(key).is_some(), "missing {key} in {v}");
    }
    assert!(v["records"].as_u64().unwrap() > 0 && v["blockers_total"].as_u64().unwrap() > 0);
    let args = |out: &str, extra: &[&str]| {
        let mut a = vec![
            "render",
            "--scene",
            "cornell-cube-3",
            "-o",
            out,
            "--width",
            "20",
            "--height",
            "20",
            "--eye-rays",
            "1",
            "--shadow-rays",
            "3",
            "--visibility",
            "lie",
            "--quiet",
        ];
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let with = dir.path().join("with.pfm");
    let without = dir.path().join("without.pfm");
    let run = |a: Vec<String>| Command::new(env!("CARGO_BIN_EXE_plie")).args(a).output().unwrap();
    let o = run(args(with.to_str().unwrap(), &["--plie", f]));
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(args(without.to_str().unwrap(), &[]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&with).unwrap(), std::fs::read(&without).unwrap());
    // The same file used for another scene, or with an option that contradicts it: refused, naming
    // the option and both values.
    fails_with(
        &["render", "--scene", "cornell-cube-2", "-o", "/tmp/x.png", "--visibility", "lie", "--plie", f],
        "another scene",
    );
    fails_with(
        &[
            "render",
            "--scene",
            "cornell-cube-3",
            "-o",
            "/tmp/x.png",
            "--visibility",
            "lie",
            "--plie",
            f,
            "--max-triangles",
            "50",
        ],
        "--max-triangles 50 contradicts the P-LIE file",
    );
    std::fs::write(dir.path().join("bad.plie"), b"PLIE").unwrap();
    let bad = dir.path().join("bad.plie");
    fails_with(
        &[
            "render",
            "--scene",
            "cornell-cube-3",
            "-o",
            "/tmp/x.png",
            "--visibility",
            "lie",
            "--plie",
            bad.to_str().unwrap(),
        ],
        "bad.plie",
    );
}

#[test]
fn build_reports_propagation_and_no_propagation_turns_it_off() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("h.plie");
    let base = ["build", "--scene", "huis-a", "--max-triangles", "24", "-o", f.to_str().unwrap()];
    let json = |extra: &[&str]| {
        let o = plie(&[&base[..], extra, &["--json"]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).expect("one JSON object")
    };
    let on = json(&[]);
    let off = json(&["--no-propagation"]);
    let removed = on["propagation"]["records_removed"].as_u64().unwrap();
    assert!(removed > 0, "{on}");
    assert_eq!(off["propagation"]["enabled"], false);
    assert_eq!(off["propagation"]["records_removed"].as_u64(), Some(0));
    // Propagation only deletes fully dark records: as many or fewer records, none added.
    let records = |v: &serde_json::Value| v["records"].as_u64().unwrap();
    assert!(records(&on) <= records(&off));
    let o = plie(&base);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("propagation     {removed} records removed")), "{text}");
    assert!(text.contains("time saved"), "{text}");
}

#[test]
fn bad_scene_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "box.mtl", GOOD_MTL);
    let out = d.join("o.png");
    let out = out.to_str().unwrap();
    let cases: Vec<(PathBuf, &str)> = vec![
        (write(d, "empty.obj", ""), "empty.obj"),
        (write(d, "trunc.obj", &GOOD_OBJ[..GOOD_OBJ.len() - 4]), "trunc.obj"),
        (write(d, "badnum.obj", &GOOD_OBJ.replace("v 1 0 1", "v 1 0x 1")), "badnum.obj"),
        (write(d, "range.obj", &GOOD_OBJ.replace("f 1 3 2", "f 1 3 99")), "range.obj"),
        (write(d, "nan.obj", &GOOD_OBJ.replace("v 1 0 1", "v 1 nan 1")), "nan.obj"),
        (write(d, "inf.obj", &GOOD_OBJ.replace("v 1 0 1", "v 1 inf 1")), "inf.obj"),
        (write(d, "nolight.obj", &GOOD_OBJ.replace("usemtl lamp", "usemtl white")), "light"),
        (write(d, "nomtl.obj", &GOOD_OBJ.replace("box.mtl", "missing.mtl")), "missing.mtl"),
        (write(d, "bad.gltf", "{ this is not json"), "bad.gltf"),
        (write(d, "trunc.glb", "glTF\u{2}\0\0\0"), "trunc.glb"),
        (write(d, "scene.xyz", "hello"), "scene.xyz"),
    ];
    for (path, needle) in cases {
        fails_with(&["render", "--scene", path.to_str().unwrap(), "-o", out, "--width", "8", "--height", "8"], needle);
    }
    // A malformed MTL next to a good OBJ.
    let d2 = tempfile::tempdir().unwrap();
    write(d2.path(), "box.mtl", "newmtl white\nKd 0.8 zz 0.8\n");
    let obj = write(d2.path(), "m.obj", GOOD_OBJ);
    fails_with(&["render", "--scene", obj.to_str().unwrap(), "-o", out], "box.mtl");
}

#[test]
fn unknown_scene_and_bad_output_give_one_line_errors() {
    fails_with(&["render", "--scene", "no-such-scene", "-o", "/tmp/x.png"], "unknown scene");
    fails_with(&["render", "--scene", "missing-file.obj", "-o", "/tmp/x.png"], "missing-file.obj");
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("no/such/dir/out.png");
    fails_with(
        &["render", "--scene", "cornell-cube-1", "-o", bad.to_str().unwrap(), "--width", "8", "--height", "8"],
        "out.png",
    );
    let bad = dir.path().join("out.bmp");
    fails_with(
        &["render", "--scene", "cornell-cube-1", "-o", bad.to_str().unwrap(), "--width", "8", "--height", "8"],
        "out.bmp",
    );
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", "/tmp/x.png", "--width", "0"], "32768");
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", "/tmp/x.png", "--fov", "200"], "field of view");
}

#[test]
fn existing_output_is_kept_when_rendering_fails() {
    let dir = tempfile::tempdir().unwrap();
    let out = write(dir.path(), "keep.png", "precious");
    let obj = write(dir.path(), "broken.obj", "v 0 0 0\nf 1 2 3\n");
    let o = plie(&["render", "--scene", obj.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "precious");
}

#[test]
fn bench_quick_writes_report_csv_json_and_chart() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let o = plie(&["bench", "--quick", "--quiet", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |name: &str| std::fs::read_to_string(out.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let scenes = ["cornell-cube-1", "cornell-cube-3"];
    let modes: Vec<&str> =
        ["octree", "bvh", "lie", "umbra", "penumbra", "grid", "lie+u", "umbra+u", "penumbra+u", "grid+u"].into();

    let json: serde_json::Value = serde_json::from_str(&read("results.json")).expect("results.json parses");
    let names: Vec<&str> = json["scenes"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, scenes);

    let csv = read("results.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let (scene_col, mode_col) = (1, 3);
    assert_eq!((header[scene_col], header[mode_col]), ("scene", "mode"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.iter().all(|r| r.len() == header.len()), "ragged CSV:\n{csv}");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no {name}: {csv}"));
    let (blocker_col, own_col) = (col("blocker_tests_per_ray"), col("own_leaf_tests_per_ray"));
    let mut own_rows = 0;
    for r in rows.iter().filter(|r| r[0] == "shading") {
        let blocker: f64 = r[blocker_col].parse().unwrap();
        let own: f64 = r[own_col].parse().unwrap();
        let p_lie = ["lie", "umbra", "penumbra", "grid"].contains(&r[mode_col].trim_end_matches("+u"));
        assert_eq!(blocker > 0.0, p_lie, "test split of a {} row: {r:?}", r[mode_col]);
        // A light's samples test the leaf's own triangles only where its pyramid meets them, so a
        // small scene's P-LIE row may have none; the other modes never have any.
        assert!(p_lie || own == 0.0, "test split of a {} row: {r:?}", r[mode_col]);
        own_rows += usize::from(own > 0.0);
    }
    assert!(own_rows > 0, "no row tested a leaf's own triangles:\n{csv}");
    for s in scenes {
        for m in &modes {
            assert!(
                rows.iter().any(|r| r[0] == "shading" && r[scene_col] == s && r[mode_col] == *m),
                "no {s}/{m} row:\n{csv}"
            );
        }
    }

    let report = read("report.md");
    for heading in [
        "# plie bench",
        "## Construction",
        "## Shading",
        "## Weighted speed-ups",
        "| lie+u |",
        "refined s (leaves; records)",
        "## Break-even",
        "## Shadow-ray throughput",
    ] {
        assert!(report.contains(heading), "report lacks '{heading}':\n{report}");
    }
    for s in scenes {
        assert!(report.contains(s), "report lacks {s}");
    }
    let svg = read("shading.svg");
    assert!(svg.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "not an SVG");
    assert!(scenes.iter().all(|s| svg.contains(s)), "chart lacks the scene names");
}

/// The soft-shadow table: every mode (the floor and the per-ray `grid` among them) at 4, 16 and 64
/// shadow rays, once each, timed, with the same rays in every mode and the same occluded rays in
/// every exact mode; the report says that the modes' runs were interleaved.
#[test]
fn bench_soft_shadows_times_every_mode_at_every_ray_count() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("soft");
    let args = ["bench", "--soft-shadows", "--scenes", "cornell-cube-1", "--runs", "2", "--quiet", "--out"];
    let o = plie(&[&args[..], &[out.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("soft-shadows.json")).unwrap()).expect("JSON");
    assert_eq!(json["runs"], 2);
    let rows = json["rows"].as_array().unwrap();
    let modes = ["none", "bvh", "lie", "umbra", "penumbra", "grid", "grid+u", "grid/ray"];
    for n in [4, 16, 64] {
        for m in modes {
            let found: Vec<_> = rows.iter().filter(|r| r["mode"] == m && r["shadow_rays"] == n).collect();
            assert_eq!(found.len(), 1, "{m} at {n} rays: {found:?}");
            let r = found[0];
            assert_eq!(r["scene"], "cornell-cube-1");
            assert!(r["seconds"].as_f64().unwrap() > 0.0, "{r}");
            assert!(r["rays"].as_u64().unwrap() > 0, "{r}");
        }
        // The same rays in every mode, and the same occluded ones in every exact mode.
        let of = |m: &str, k: &str| rows.iter().find(|r| r["mode"] == m && r["shadow_rays"] == n).unwrap()[k].clone();
        assert!(modes.iter().all(|&m| of(m, "rays") == of("bvh", "rays")));
        assert!(modes[1..].iter().all(|&m| of(m, "occluded") == of("bvh", "occluded")));
        assert_eq!(of("none", "occluded"), 0);
    }
    let md = std::fs::read_to_string(out.join("soft-shadows.md")).unwrap();
    assert!(md.contains("median of 2 runs (the modes' runs interleaved)"), "{md}");
    for heading in ["## 4 shadow rays per light", "## 16 shadow rays per light", "## 64 shadow rays per light"] {
        assert!(md.contains(heading), "no '{heading}':\n{md}");
    }
}

#[test]
fn build_refines_by_umbra_and_render_uses_the_refined_p_lie() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("c5.plie");
    let fs = f.to_str().unwrap();
    let o = plie(&["build", "--scene", "cornell-cube-5", "--refine", "umbra", "-o", fs, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    let r = &v["refinement"];
    assert_eq!(r["criteria"], serde_json::json!(["umbra_full", "umbra_free"]));
    assert_eq!(r["max_split_depth"], 2);
    let added = r["leaves_added"].as_u64().unwrap();
    assert!(added > 0 && r["rounds"].as_u64().unwrap() >= 1, "{v}");
    let unrefined = r["unrefined"]["leaves"].as_u64().unwrap();
    assert_eq!(v["leaves"].as_u64().unwrap(), unrefined + added);
    // The text summary names the criteria and the before/after figures.
    let o = plie(&["build", "--scene", "cornell-cube-5", "--refine", "umbra", "-o", fs]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("refinement      +{added} leaves")) && text.contains("records"), "{text}");
    // Rendering with the saved, refined P-LIE gives the brute-force image.
    let img = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let base = ["render", "--scene", "cornell-cube-5", "--width", "24", "--height", "24", "--quiet", "-o"];
        let o = plie(&[&base[..], &[out.to_str().unwrap()], extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(out).unwrap()
    };
    let brute = img("brute.pfm", &["--visibility", "brute"]);
    assert_eq!(img("loaded.pfm", &["--visibility", "umbra", "--plie", fs, "--refine", "umbra"]), brute);
    assert_eq!(
        img("built.pfm", &["--visibility", "grid", "--refine", "umbra,blockers", "--max-blockers", "adaptive"]),
        brute
    );
    // The file describes itself (issue 18): loading it needs none of its build options, and an option
    // given that contradicts it is an error naming the option and both values.
    assert_eq!(img("described.pfm", &["--visibility", "umbra", "--plie", fs]), brute);
    let x = dir.path().join("x.png");
    fails_with(
        &[
            "render",
            "--scene",
            "cornell-cube-5",
            "--visibility",
            "lie",
            "--plie",
            fs,
            "--refine",
            "umbra-free",
            "-o",
            x.to_str().unwrap(),
        ],
        "--refine umbra-free contradicts the P-LIE file",
    );
    assert!(!x.exists());
}

#[test]
fn bad_refinement_options_give_one_line_errors() {
    let base = ["build", "--scene", "cornell-cube-1", "-o", "never.plie"];
    fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [base, extra].concat()
    }
    fails_with(&with(&base, &["--refine", "blockers"]), "--max-blockers");
    fails_with(&with(&base, &["--max-blockers", "10"]), "--refine blockers");
    // Values clap refuses: its error and usage hint, no panic.
    for (args, needle) in [(&["--max-blockers", "many"][..], "adaptive"), (&["--refine", "shadows"][..], "shadows")] {
        let o = plie(&with(&base, args));
        assert!(
            !o.status.success() && !stderr(&o).contains("panicked") && stderr(&o).contains(needle),
            "{}",
            stderr(&o)
        );
    }
    fails_with(&with(&base, &["--refine", "umbra", "--no-regions"]), "regions");
    fails_with(&with(&base, &["--refine", "umbra", "--max-split-depth", "40"]), "depth");
    assert!(!Path::new("never.plie").exists());
}

/// Issue 18: `plie build --refine umbra -o f.plie` then `plie render --plie f.plie` and `plie inspect
/// --plie f.plie` with no build option: the file's parameters are used. An option given explicitly
/// that contradicts the file is an error naming the option and both values; one that agrees is fine.
#[test]
fn a_plie_file_describes_itself() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("f.plie");
    let fs = f.to_str().unwrap();
    let o =
        plie(&["build", "--scene", "cornell-cube-1", "--refine", "umbra", "--max-triangles", "100", "-o", fs, "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.path().join("r.png");
    let render = [
        "render",
        "--scene",
        "cornell-cube-1",
        "--plie",
        fs,
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
    ];
    let o = plie(&render);
    assert!(o.status.success(), "render --plie without build options: {}", stderr(&o));
    let o = plie(&["inspect", "--scene", "cornell-cube-1", "--plie", fs, "--summary"]);
    assert!(o.status.success(), "inspect --plie without build options: {}", stderr(&o));
    let o = plie(&[&render[..], &["--max-triangles", "100", "--refine", "umbra", "--blocker-cap", "64"]].concat());
    assert!(o.status.success(), "options that agree with the file: {}", stderr(&o));
    for (extra, want) in [
        (&["--max-triangles", "200"][..], "--max-triangles 200 contradicts the P-LIE file"),
        (&["--max-triangles", "200"][..], "which was built with --max-triangles 100"),
        (&["--blocker-cap", "none"][..], "--blocker-cap none contradicts the P-LIE file"),
        (&["--no-grids"][..], "--no-grids contradicts the P-LIE file"),
        (&["--max-depth", "3"][..], "built with --max-depth 10"),
    ] {
        fails_with(&[&render[..], extra].concat(), want);
    }
    fails_with(
        &["inspect", "--scene", "cornell-cube-1", "--plie", fs, "--summary", "--no-propagation"],
        "--no-propagation contradicts the P-LIE file",
    );
}
