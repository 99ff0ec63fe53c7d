//! Issue 16, hostile input: one regression test per reported case. Each asserts the clean outcome:
//! a non-zero exit, a one-line message naming the file, line or field and the limit, no panic, inputs
//! unchanged, and (where the case was a hang or a blow-up) a time and address-space bound the test
//! enforces by killing the process.

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use support::{fails_with, plie, stderr};

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const BOX_OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 0 1 1\nv 1 1 1\nv 1 1 0\n\
usemtl white\nf 1 3 2\nf 1 4 3\nusemtl lamp\nf 5 8 7\nf 5 7 6\n";
const BOX_MTL: &str = "newmtl white\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n";

/// Runs `plie args` with an address-space limit of `mem_mb` MiB (through `sh -c ulimit -v`) and
/// kills it after `limit`; returns its output and whether it finished in time.
fn plie_bounded(args: &[&str], mem_mb: u64, limit: Duration) -> (Output, bool) {
    let script = format!("ulimit -v {}; exec \"$0\" \"$@\"", mem_mb * 1024);
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(env!("CARGO_BIN_EXE_plie"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run plie");
    let start = Instant::now();
    let mut in_time = true;
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            in_time = false;
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    (child.wait_with_output().unwrap(), in_time)
}

/// Runs `plie args` under 2048 MiB and 60 s (asserted), and asserts that the files `inputs` are
/// unchanged after it.
fn plie_checked(args: &[&str], inputs: &[&Path]) -> Output {
    let before: Vec<Vec<u8>> = inputs.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let (o, in_time) = plie_bounded(args, 2048, Duration::from_secs(60));
    assert!(in_time, "{args:?}: killed after 60 s");
    for (p, b) in inputs.iter().zip(before) {
        assert!(std::fs::read(p).unwrap() == b, "{args:?}: {} changed", p.display());
    }
    o
}

/// A one-line error without a panic, containing every needle.
fn one_line_error(o: &Output, needles: &[&str]) -> String {
    let err = stderr(o);
    assert!(!o.status.success(), "should fail; stderr: {err}");
    assert_eq!(o.status.code(), Some(1), "a clean error exit, not a crash: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "error should mention '{n}': {err}");
    }
    err
}

/// A minimal glTF around `mesh`/`extra` members, with an embedded 3-triangle buffer when `buffer`.
fn gltf(members: &str) -> String {
    format!(r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}], {members}}}"#)
}

// 1. A primitive naming an accessor that does not exist once made the gltf crate panic.
#[test]
fn gltf_without_accessors_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let g = write(dir.path(), "noacc.gltf", gltf(r#""meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]"#));
    let png = dir.path().join("o.png");
    let lie = dir.path().join("o.plie");
    for args in [["render", "--scene", s(&g), "-o", s(&png)], ["build", "--scene", s(&g), "-o", s(&lie)]] {
        one_line_error(&plie_checked(&args, &[&g]), &["noacc.gltf", "accessor 0", "0 accessors"]);
    }
}

// 2. 201 coincident triangles (a 600-index face repeating the floor) split the octree into
//    1,220,836 leaves and took 18 s for a 16x16 render.
#[test]
fn coincident_triangles_render_quickly_in_bounded_memory() {
    render_copies(200);
}

/// The issue's 1,200-index face (401 coincident triangles). The octree is fine; the BVH (obvhs) over
/// 401 identical boxes is deeper than obvhs' 32-entry traversal stack, which `visibility/bvh.rs`
/// measures and then traverses with a growable stack (before, the test profile's debug assertions
/// panicked in obvhs' `CwBvh::validate`). Every exact mode renders the same image as brute force.
#[test]
fn four_hundred_coincident_triangles_render_exactly() {
    render_copies(400);
}

/// A blocker between the box's floor and lamp, so that the renders below have shadows to get right.
const BLOCKER: &str =
    "v 0.3 0.5 0.3\nv 0.7 0.5 0.3\nv 0.7 0.5 0.7\nv 0.3 0.5 0.7\nusemtl white\nf 9 10 11\nf 9 11 12\n";

/// Renders the box, a blocker and `copies` more copies of a floor triangle under 4 GiB and 120 s in
/// the modes `bvh` (the default), `brute`, `lie` and `grid`; all give the same image, bit for bit.
fn render_copies(copies: usize) {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "box.mtl", BOX_MTL);
    let face = format!("usemtl white\nf{}\n", " 1 3 2".repeat(copies));
    let obj = write(dir.path(), &format!("c{copies}.obj"), format!("{BOX_OBJ}{BLOCKER}{face}"));
    let mut images = Vec::new();
    for mode in ["bvh", "brute", "lie", "grid"] {
        let out = dir.path().join(format!("c-{mode}.pfm"));
        let args = [
            "render",
            "--scene",
            s(&obj),
            "-o",
            s(&out),
            "--width",
            "16",
            "--height",
            "16",
            "--json",
            "--threads",
            "2",
            "--visibility",
            mode,
        ];
        let (o, in_time) = plie_bounded(&args, 4096, Duration::from_secs(120));
        assert!(in_time, "{copies} copies, {mode}: killed after 120 s");
        assert!(o.status.success(), "{copies} copies, {mode}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        // Only the modes that use an octree build one.
        match v["octree_leaves"].as_u64() {
            Some(leaves) => assert_eq!(leaves, 8, "{copies} copies, {mode}: {leaves} octree leaves"),
            None => assert!(["bvh", "brute"].contains(&mode), "{copies} copies, {mode}: no octree"),
        }
        assert!(v["occluded"].as_u64().unwrap() > 0, "{copies} copies, {mode}: the blocker casts no shadow");
        images.push((mode, std::fs::read(&out).unwrap()));
    }
    for (mode, image) in &images[1..] {
        assert!(image == &images[0].1, "{copies} copies: {mode} differs from {}", images[0].0);
    }
}

/// The issue's glTF with 5,000 instances of one mesh aborted with a 9.6 GB allocation in
/// `construct::run_round`. Here the fuzz seed's floor is instanced 20,000 times more (coincident: the
/// octree stays small; the BVH's build took 70 s before crowded centres were grouped) with a small
/// blocker under the lamp; `bvh`, `lie` and `brute` render it under 4 GiB and 60 s each, to the same
/// image.
#[test]
fn twenty_thousand_instances_of_one_mesh_render_exactly_in_bounded_memory() {
    let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../plie/tests/fuzz/seeds/embedded.gltf");
    let mut g: serde_json::Value = serde_json::from_slice(&std::fs::read(seed).unwrap()).unwrap();
    let nodes = g["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    nodes.extend((0..20_000).map(|_| serde_json::json!({"mesh": 0})));
    nodes.push(serde_json::json!({"mesh": 0, "translation": [0.1, 1.0, 0.0], "scale": [0.2, 1.0, 0.2]}));
    let count = nodes.len();
    g["scenes"][0]["nodes"].as_array_mut().unwrap().extend((first..count).map(|n| serde_json::json!(n)));
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "inst.gltf", serde_json::to_vec(&g).unwrap());
    let mut images = Vec::new();
    for mode in ["bvh", "lie", "brute"] {
        let out = dir.path().join(format!("i-{mode}.pfm"));
        let args = [
            "render",
            "--scene",
            s(&scene),
            "-o",
            s(&out),
            "--width",
            "16",
            "--height",
            "16",
            "--json",
            "--threads",
            "2",
            "--visibility",
            mode,
        ];
        let (o, in_time) = plie_bounded(&args, 4096, Duration::from_secs(60));
        assert!(in_time, "{mode}: killed after 60 s");
        assert!(o.status.success(), "{mode}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["triangles"].as_u64().unwrap(), 2 * 20_002 + 2, "{mode}: {v}");
        match v["octree_leaves"].as_u64() {
            Some(leaves) => assert!(leaves <= 64, "{mode}: {v}"),
            None => assert!(["bvh", "brute"].contains(&mode), "{mode}: no octree"),
        }
        assert!(v["occluded"].as_u64().unwrap() > 0, "{mode}: the blocker casts no shadow");
        images.push((mode, std::fs::read(&out).unwrap()));
    }
    for (mode, image) in &images[1..] {
        assert!(image == &images[0].1, "{mode} differs from {}", images[0].0);
    }
}

/// The issue's large fan faces on the dragon aborted with a 4 GB allocation. A 1,200-index face over
/// the vertices of `cornell-dragon.obj` (1,198 long, crossing triangles) builds and renders under
/// 4 GiB and 300 s, to the same image in `lie` and `bvh`.
#[test]
#[ignore = "exhaustive tier: a fan face on a shared scene (about 15 s)"]
fn a_large_fan_face_on_the_dragon_renders_in_bounded_memory() {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    let Ok(obj) = std::fs::read_to_string(shared.join("cornell-dragon.obj")) else {
        eprintln!("notice: ../shared/scenes/cornell-dragon.obj is absent; skipping");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "cornell-dragon.mtl", std::fs::read(shared.join("cornell-dragon.mtl")).unwrap());
    let fan: String = (1..=1200).map(|i| format!(" {i}")).collect();
    let scene = write(dir.path(), "fan.obj", format!("{obj}\nf{fan}\n"));
    let mut images = Vec::new();
    for mode in ["lie", "bvh"] {
        let out = dir.path().join(format!("f-{mode}.pfm"));
        let args =
            ["render", "--scene", s(&scene), "-o", s(&out), "--width", "16", "--height", "16", "--visibility", mode];
        let (o, in_time) = plie_bounded(&args, 4096, Duration::from_secs(300));
        assert!(in_time, "{mode}: killed after 300 s");
        assert!(o.status.success(), "{mode}: {}", stderr(&o));
        images.push(std::fs::read(&out).unwrap());
    }
    assert!(images[0] == images[1], "lie differs from bvh");
}

// 3. Unbounded reads: `mtllib /dev/zero` aborted, a glTF buffer `/dev/urandom` hung.
#[test]
fn devices_are_not_read() {
    if !Path::new("/dev/zero").exists() {
        eprintln!("notice: no /dev/zero; skipping");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "z.obj", BOX_OBJ.replace("box.mtl", "/dev/zero"));
    let out = dir.path().join("o.png");
    let base = ["--width", "8", "--height", "8"];
    let mut args = vec!["render", "--scene", s(&obj), "-o", s(&out), "--allow-outside-paths"];
    args.extend(base);
    let (o, in_time) = plie_bounded(&args, 2048, Duration::from_secs(30));
    assert!(in_time);
    one_line_error(&o, &["z.obj:1", "/dev/zero", "not a regular file"]);
    let members = r#""buffers": [{"uri": "/dev/urandom", "byteLength": 36}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "accessors": [{"count": 3, "type": "VEC3", "componentType": 5126, "bufferView": 0, "min": [0,0,0], "max": [1,1,1]}], "bufferViews": [{"buffer": 0, "byteLength": 36}]"#;
    let g = write(dir.path(), "u.gltf", gltf(members));
    let mut args = vec!["render", "--scene", s(&g), "-o", s(&out), "--allow-outside-paths"];
    args.extend(base);
    let (o, in_time) = plie_bounded(&args, 2048, Duration::from_secs(30));
    assert!(in_time);
    one_line_error(&o, &["u.gltf", "buffer 0", "not a regular file"]);
    // `--plie /dev/zero` fails cleanly too.
    let o = plie(&["render", "--scene", "cornell-cube-1", "-o", s(&out), "--visibility", "lie", "--plie", "/dev/zero"]);
    one_line_error(&o, &["/dev/zero", "not a regular file"]);
}

// 4. Outputs overwriting inputs.
#[test]
fn outputs_never_overwrite_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "box.mtl", BOX_MTL);
    let obj = write(d, "x.obj", BOX_OBJ);
    let o = plie(&["build", "--scene", s(&obj), "-o", s(&obj)]);
    one_line_error(&o, &["x.obj", "only .plie"]);
    fails_with(&["build", "--scene", "cornell-cube-1", "-o", s(&d.join("b.pfm"))], "only .plie");
    // Same file by another spelling.
    let plie_file = d.join("x.plie");
    let o = plie(&["build", "--scene", "cornell-cube-1", "-o", s(&plie_file), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let plie_bytes = std::fs::read(&plie_file).unwrap();
    let pfm = write(d, "p.pfm", &plie_bytes);
    let o = plie(&["render", "--scene", "cornell-cube-1", "--visibility", "lie", "--plie", s(&pfm), "-o", s(&pfm)]);
    one_line_error(&o, &["p.pfm", "names an input"]);
    let g = write(d, "s.gltf", gltf(r#""meshes": []"#));
    let o = plie(&["inspect", "--scene", s(&g), "--cell", "0,0,0", "-o", s(&g)]);
    one_line_error(&o, &["s.gltf", "names an input"]);
    assert_eq!(std::fs::read_to_string(&g).unwrap(), gltf(r#""meshes": []"#), "the glTF is unchanged");
    let again = d.join(".").join("x.obj");
    let o = plie(&["render", "--scene", s(&obj), "-o", s(&again.with_extension("obj"))]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read_to_string(&obj).unwrap(), BOX_OBJ, "the scene is unchanged");
    assert_eq!(std::fs::read(&pfm).unwrap(), plie_bytes, "the P-LIE is unchanged");
}

// 5. Reading outside the scene's folder.
#[test]
fn scene_files_cannot_name_files_outside_their_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("o.png");
    for uri in ["../../../../etc/passwd", "/etc/passwd", "file:///etc/passwd"] {
        let members = format!(
            r#""buffers": [{{"uri": "{uri}", "byteLength": 36}}], "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}], "accessors": [{{"count": 3, "type": "VEC3", "componentType": 5126, "bufferView": 0, "min": [0,0,0], "max": [1,1,1]}}], "bufferViews": [{{"buffer": 0, "byteLength": 36}}]"#
        );
        let g = write(d, "p.gltf", gltf(&members));
        let o = plie(&["render", "--scene", s(&g), "-o", s(&out)]);
        let err = one_line_error(&o, &["p.gltf", "buffer 0", "--allow-outside-paths"]);
        if let Ok(m) = std::fs::metadata("/etc/passwd") {
            assert!(!err.contains(&format!("{} bytes", m.len())), "the file's size is not revealed: {err}");
        }
    }
    let obj = write(d, "m.obj", BOX_OBJ.replace("box.mtl", "/etc/passwd"));
    let o = plie(&["render", "--scene", s(&obj), "-o", s(&out)]);
    one_line_error(&o, &["m.obj:1", "mtllib", "/etc/passwd", "--allow-outside-paths"]);
    // With the option, an MTL file elsewhere is read.
    let lib = tempfile::tempdir().unwrap();
    let mtl = write(lib.path(), "box.mtl", BOX_MTL);
    let obj = write(d, "far.obj", BOX_OBJ.replace("box.mtl", s(&mtl)));
    fails_with(&["render", "--scene", s(&obj), "-o", s(&out)], "outside the scene's folder");
    let o =
        plie(&["render", "--scene", s(&obj), "-o", s(&out), "--width", "8", "--height", "8", "--allow-outside-paths"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// glTF image URIs are read since textures are (issue 18), within the same rules: a FIFO (which
/// would block a reader forever), a device or a file outside the scene's folder is a one-line error
/// naming the image, never a hang, and a FIFO inside the folder is refused as not a regular file.
#[test]
fn hostile_gltf_image_uris_are_clean_errors() {
    let dir = tempfile::tempdir().unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let (inside, outside) = (dir.path().join("fifo.png"), elsewhere.path().join("fifo.png"));
    for f in [&inside, &outside] {
        match Command::new("mkfifo").arg(f).status() {
            Ok(st) if st.success() => {}
            _ => {
                eprintln!("notice: no mkfifo; skipping");
                return;
            }
        }
    }
    let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../plie/tests/fuzz/seeds/embedded.gltf");
    let base: serde_json::Value = serde_json::from_slice(&std::fs::read(seed).unwrap()).unwrap();
    let cases = [
        (s(&outside), "outside the scene's folder"),
        ("../../../../etc/passwd", "outside the scene's folder"),
        ("/dev/zero", "outside the scene's folder"),
        ("fifo.png", "not a regular file"),
    ];
    for (uri, why) in cases {
        let mut g = base.clone();
        g["images"] = serde_json::json!([{ "uri": uri }]);
        g["textures"] = serde_json::json!([{"source": 0}]);
        g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = serde_json::json!({"index": 0});
        let scene = write(dir.path(), "tex.gltf", serde_json::to_vec(&g).unwrap());
        let before = std::fs::read(&scene).unwrap();
        let out = dir.path().join("o.png");
        let args = ["render", "--scene", s(&scene), "-o", s(&out), "--width", "8", "--height", "8"];
        let (o, in_time) = plie_bounded(&args, 2048, Duration::from_secs(30));
        assert!(in_time, "{uri}: killed after 30 s");
        one_line_error(&o, &["tex.gltf", "image 0", why]);
        assert_eq!(std::fs::read(&scene).unwrap(), before, "the input is unchanged");
        assert!(!out.exists(), "{uri}: no image written");
    }
}

// 6. Unbounded --threads.
#[test]
fn threads_are_bounded() {
    for t in ["100000", "10000", "0"] {
        let (o, in_time) = plie_bounded(
            &["render", "--scene", "cornell-cube-1", "-o", "/tmp/never.png", "--threads", t],
            2048,
            Duration::from_secs(10),
        );
        assert!(in_time);
        one_line_error(&o, &["--threads", "between 1 and 1024"]);
    }
}

// 7. A corrupted P-LIE with a valid checksum: `plie verify` finds it.
#[test]
fn verify_finds_a_corrupted_p_lie_with_a_valid_checksum() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("c.plie");
    let o = plie(&["build", "--scene", "cornell-cube-1", "-o", s(&file), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for full in [false, true] {
        let mut args = vec!["verify", s(&file), "--scene", "cornell-cube-1"];
        if full {
            args.push("--full");
        }
        let o = plie(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("OK"));
    }
    // Files whose records pass the blocker cap, so that the build's lift and cell budgets (and, with
    // refinement, the splits they lead to) shape them: the full check rebuilds within the limits
    // the file was built with, so a file as built passes it.
    for (scene, extra) in [("cornell-cube-1", &[][..]), ("huis-a", &["--refine", "umbra"][..])] {
        let capped = dir.path().join(format!("{scene}-capped.plie"));
        let mut args = vec!["build", "--scene", scene, "-o", s(&capped), "--quiet", "--blocker-cap", "2"];
        args.extend(extra);
        let o = plie(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = plie(&["verify", s(&capped), "--scene", scene, "--full"]);
        assert!(o.status.success(), "{scene}: {}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("OK"));
    }
    // The issue's case: 51 bytes zeroed at offset 347, the checksum rewritten.
    let mut b = std::fs::read(&file).unwrap();
    assert!(b[347..398].iter().any(|&x| x != 0), "the bytes change");
    b[347..398].fill(0);
    let sum = plie::internals::io::plie_file::checksum(&b[28..]);
    b[20..28].copy_from_slice(&sum.to_le_bytes());
    let bad = write(dir.path(), "bad.plie", &b);
    let o = plie_checked(&["verify", s(&bad), "--scene", "cornell-cube-1", "--full"], &[&bad]);
    one_line_error(&o, &["bad.plie"]);
    // A payload that is not a P-LIE at all, with a valid checksum.
    let mut junk = b[..28].to_vec();
    junk.extend([0xffu8; 64]);
    junk[12..20].copy_from_slice(&64u64.to_le_bytes());
    let sum = plie::internals::io::plie_file::checksum(&junk[28..]);
    junk[20..28].copy_from_slice(&sum.to_le_bytes());
    let junk = write(dir.path(), "junk.plie", &junk);
    let o = plie(&["verify", s(&junk), "--scene", "cornell-cube-1"]);
    let err = one_line_error(&o, &["junk.plie", "not a P-LIE", "plie build"]);
    assert!(!err.contains("varint") && !err.contains("Serde"), "{err}");
}

// 8. Messages a user can act on.
#[test]
fn messages_name_the_field_and_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("o.png");
    // Parameters of a P-LIE file as options, not Rust's Debug.
    let file = d.join("p.plie");
    assert!(plie(&["build", "--scene", "cornell-cube-1", "-o", s(&file), "--quiet"]).status.success());
    let o = plie(&[
        "render",
        "--scene",
        "cornell-cube-1",
        "-o",
        s(&out),
        "--visibility",
        "lie",
        "--plie",
        s(&file),
        "--max-triangles",
        "50",
    ]);
    let err = one_line_error(&o, &["p.plie", "--max-triangles 200", "--max-triangles 50"]);
    assert!(!err.contains("PlieParams") && !err.contains("RefineParams"), "{err}");
    // emissiveStrength 1e308: the field is named.
    let members = r#""buffers": [{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA", "byteLength": 36}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}], "materials": [{"emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e308}}}], "extensionsUsed": ["KHR_materials_emissive_strength"], "accessors": [{"count": 3, "type": "VEC3", "componentType": 5126, "bufferView": 0, "min": [0,0,0], "max": [1,1,1]}], "bufferViews": [{"buffer": 0, "byteLength": 36}]"#;
    let g = write(d, "e.gltf", gltf(members));
    let o = plie(&["render", "--scene", s(&g), "-o", s(&out)]);
    let err = one_line_error(&o, &["e.gltf", "emissiveStrength", "finite"]);
    assert!(!err.contains("Vec3("), "{err}");
    // Bad base64 in a data URI.
    let g = write(d, "b64.gltf", gltf(&members.replace("AAAAAAAAAAAAAAAAAACAPw", "AA,A")));
    fails_with(&["render", "--scene", s(&g), "-o", s(&out)], "not valid base64");
    // Output names without a format, or a directory.
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", s(&d.join("out"))], "no extension");
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", s(d)], "is a directory");
    // One message for a missing output folder, in every command.
    let missing = d.join("no/such");
    for (cmd, name) in [("render", "o.png"), ("build", "o.plie"), ("inspect", "o.png")] {
        let o = missing.join(name);
        let mut args = vec![cmd, "--scene", "cornell-cube-1", "-o", s(&o)];
        if cmd == "inspect" {
            args.extend(["--cell", "0,0,0"]);
        }
        fails_with(&args, "the output folder");
    }
    // A negative field of view is a field-of-view error, not an unknown argument.
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", s(&out), "--fov", "-10"], "field of view");
    // The real size limit.
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", s(&out), "--width", "4294967296"], "1..=32768");
    fails_with(&["render", "--scene", "cornell-cube-1", "-o", s(&out), "--width", "40000"], "1..=32768");
    // A huge number is not echoed back: on the command line (Linux caps one argument at 128 KiB)
    // and in a scene file (1,000,000 digits).
    let huge = "9".repeat(100_000);
    let o = plie(&["render", "--scene", "cornell-cube-1", "-o", s(&out), "--width", &huge]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.len() < 400, "{} bytes of error", err.len());
    assert!(err.contains("100000 characters"), "{err}");
    write(d, "box.mtl", BOX_MTL);
    let obj = write(d, "huge.obj", BOX_OBJ.replace("v 1 0 1", &format!("v 1 {} 1", "9".repeat(1_000_000))));
    let o = plie(&["render", "--scene", s(&obj), "-o", s(&out)]);
    let err = one_line_error(&o, &["huge.obj:4", "1000000 characters"]);
    assert!(err.len() < 400, "{} bytes of error", err.len());
}

// 9. Output into a pipe whose reader has gone (`plie scenes --json | head -1`): the process ends
// quietly (by SIGPIPE, as other command-line tools do), never with a panic.
#[test]
fn a_closed_pipe_on_stdout_is_no_panic() {
    for _ in 0..5 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_plie"))
            .args(["scenes", "--json"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run plie");
        // The reader goes before plie writes (nearly always: it has only just started).
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        assert!(!err.contains("panicked") && err.is_empty(), "{err}");
    }
}

// 10. Outputs overwriting the files a scene file names: the MTL library, a `map_Kd` texture, Mitsuba
// bitmaps, includes and meshes, glTF buffers and images (known once the scene is loaded, checked
// before anything is rendered or written): the same one-line error as for the scene file, and the
// file unchanged, also through a symbolic link and for a walkthrough's frame pattern.
#[test]
fn outputs_never_overwrite_files_the_scene_reads() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../plie/tests/fuzz/seeds");
    let seed = |name: &str| std::fs::read(seeds.join(name)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let small = ["--width", "8", "--height", "8", "--threads", "1"];
    let refused = |args: &[&str], input: &Path| {
        let mut all = args.to_vec();
        all.extend_from_slice(&small);
        let o = plie_checked(&all, &[input]);
        let name = input.file_name().unwrap().to_str().unwrap();
        one_line_error(&o, &[name, "names an input"]);
    };
    let works = |args: &[&str]| {
        let mut all = args.to_vec();
        all.extend_from_slice(&small);
        let o = plie(&all);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    };

    // OBJ + MTL with a texture; a second scene whose MTL library is named like an image.
    let tex = write(d, "tex.png", seed("tex.png"));
    let mtl = write(d, "t.mtl", format!("{}\nmap_Kd tex.png\n", String::from_utf8(seed("quad-light.mtl")).unwrap()));
    let obj = write(d, "t.obj", String::from_utf8(seed("scene.obj")).unwrap().replace("quad-light.mtl", "t.mtl"));
    let odd_mtl = write(d, "lib.png", std::fs::read(&mtl).unwrap());
    let odd = write(d, "odd.obj", std::fs::read_to_string(&obj).unwrap().replace("t.mtl", "lib.png"));
    works(&["render", "--scene", s(&obj), "-o", s(&d.join("ok.png")), "--quiet"]);
    refused(&["render", "--scene", s(&obj), "-o", s(&tex)], &tex);
    refused(&["render", "--scene", s(&obj), "-o", s(&d.join(".").join("tex.png"))], &tex);
    refused(&["inspect", "--scene", s(&obj), "--cell", "0,0.5,0", "-o", s(&tex)], &tex);
    refused(&["render", "--scene", s(&odd), "-o", s(&odd_mtl)], &odd_mtl);
    #[cfg(unix)]
    {
        let link = d.join("mtl-link.png");
        std::os::unix::fs::symlink(&mtl, &link).unwrap();
        refused(&["render", "--scene", s(&obj), "-o", s(&link)], &mtl);
        // A walkthrough's frame 0 is the texture, through a link.
        std::os::unix::fs::symlink(&tex, d.join("f_0.png")).unwrap();
        let k = |f: u32| {
            format!(r#"{{"frame": {f}, "eye": [0, 1, -4], "target": [0, 0.5, 0], "up": [0, 1, 0], "fov": 40}}"#)
        };
        let path =
            write(d, "path.json", format!(r#"{{"interpolation": "linear", "keyframes": [{}, {}]}}"#, k(0), k(1)));
        let pattern = d.join("f_#.png");
        refused(&["render", "--scene", s(&obj), "--camera-path", s(&path), "-o", s(&pattern)], &tex);
    }

    // Mitsuba: a bitmap (render and inspect), an include and a PLY mesh (through links).
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../plie/tests/data/mitsuba");
    let m = tempfile::tempdir().unwrap();
    for f in std::fs::read_dir(&data).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, m.path().join(f.file_name().unwrap())).unwrap();
    }
    let xml = m.path().join("textured.xml");
    let (checker, stripes) = (m.path().join("checker.png"), m.path().join("stripes.png"));
    works(&["render", "--scene", s(&xml), "-o", s(&m.path().join("ok.png")), "--quiet"]);
    refused(&["render", "--scene", s(&xml), "-o", s(&checker)], &checker);
    refused(&["inspect", "--scene", s(&xml), "--cell", "0,0.5,0", "-o", s(&stripes)], &stripes);
    #[cfg(unix)]
    for input in ["materials-3.xml", "back-wall.ply"] {
        let input = m.path().join(input);
        let link = m.path().join(format!("{}.pfm", input.file_stem().unwrap().to_str().unwrap()));
        std::os::unix::fs::symlink(&input, &link).unwrap();
        refused(&["render", "--scene", s(&xml), "-o", s(&link)], &input);
    }

    // glTF: an external buffer named like an image, and an image file.
    let mut g: serde_json::Value = serde_json::from_slice(&seed("external.gltf")).unwrap();
    g["buffers"][0]["uri"] = serde_json::json!("geometry.pfm");
    g["images"] = serde_json::json!([{ "uri": "wall.png" }]);
    g["textures"] = serde_json::json!([{ "source": 0 }]);
    g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = serde_json::json!({ "index": 0 });
    let gltf = write(d, "g.gltf", serde_json::to_vec(&g).unwrap());
    let buffer = write(d, "geometry.pfm", seed("external.bin"));
    let image = write(d, "wall.png", seed("tex.png"));
    works(&["render", "--scene", s(&gltf), "-o", s(&d.join("ok.pfm")), "--quiet"]);
    refused(&["render", "--scene", s(&gltf), "-o", s(&buffer)], &buffer);
    refused(&["render", "--scene", s(&gltf), "-o", s(&image)], &image);
    refused(&["inspect", "--scene", s(&gltf), "--cell", "0,0.5,0", "-o", s(&image)], &image);
}
