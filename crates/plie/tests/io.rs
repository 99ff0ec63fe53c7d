//! Scene and image files (SPEC §1, §2 output): the real scenes in `shared/scenes` load with the counts
//! their README gives, every kind of bad input is an error naming the problem (never a panic), lights
//! are grouped into convex polygons, and images round-trip exactly.
//!
//! Tests that need `../shared/scenes` (beside the workspace) are reported as ignored when it is absent
//! (see `build.rs`).

#[path = "io/gltf.rs"]
mod gltf;
#[path = "io/images.rs"]
mod images;
#[path = "io/lights.rs"]
mod lights;
#[path = "io/robustness.rs"]
mod robustness;
mod support;

use std::path::{Path, PathBuf};

use glam::Vec3;
use plie::io::load_scene;
use plie::{Error, Scene};

/// Writes `files` (name, contents) into a fresh temporary directory.
pub fn temp_files(files: &[(&str, &[u8])]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, contents) in files {
        std::fs::write(dir.path().join(name), contents).unwrap();
    }
    dir
}

/// Loads `name` from a directory holding `files`.
pub fn load_from(files: &[(&str, &[u8])], name: &str) -> plie::Result<Scene> {
    let dir = temp_files(files);
    load_scene(&dir.path().join(name))
}

/// The error's text, asserting it is an `Error::Parse` naming a file called `file` and, if given, `line`
/// (or, without a line, an `Error::SceneElement` of that file: then the element and the message).
pub fn parse_error(r: plie::Result<Scene>, file: &str, line: Option<usize>) -> String {
    match r {
        Err(e @ Error::Parse { .. }) => {
            let Error::Parse { path, line: l, message } = &e else { unreachable!() };
            assert_eq!(path.file_name().unwrap(), file, "{e}");
            if line.is_some() {
                assert_eq!(*l, line, "{e}");
            }
            message.clone()
        }
        // A part of the file by index (glTF primitives and nodes): the part and the message.
        Err(Error::SceneElement { path, element, message }) if line.is_none() => {
            assert_eq!(path.file_name().unwrap(), file);
            format!("{element}: {message}")
        }
        Err(e) => panic!("expected a parse error, got {e:?}"),
        Ok(s) => panic!("expected an error, got a scene with {} triangles", s.triangle_count()),
    }
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// `../shared/scenes`, beside the workspace: the only place the real scenes are looked for.
fn scenes() -> Option<PathBuf> {
    support::shared_scenes()
}

const V3: &[u8] = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n";

// ---- Real scenes (shared/scenes/README.md) ----

/// Loads a real scene and checks its triangle count, lights and their radiance.
fn check_real(file: &str, triangles: usize, lights: &[(usize, Vec3)]) -> Option<Scene> {
    let dir = scenes()?;
    let s = load_scene(&dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.triangle_count() + s.degenerate_skipped, triangles, "{file}");
    assert_eq!(s.degenerate_skipped, 0, "{file}: README says no degenerate faces");
    assert_eq!(s.lights.len(), lights.len(), "{file}");
    for (l, (verts, radiance)) in s.lights.iter().zip(lights) {
        assert_eq!(l.vertices.len(), *verts, "{file}");
        assert_eq!(l.radiance, *radiance, "{file}");
    }
    assert!(s.camera.is_none(), "OBJ has no camera");
    assert_eq!(s.name, file.trim_end_matches(".obj"));
    Some(s)
}

#[test]
#[cfg_attr(plie_no_shared_scenes, ignore = "needs ../shared/scenes, absent when the tests were built")]
fn cornell_box_original() {
    let Some(s) = check_real("CornellBox-Original.obj", 36, &[(4, Vec3::new(17.0, 12.0, 4.0))]) else { return };
    let l = &s.lights[0];
    assert!((l.normal - Vec3::NEG_Y).length() < 1e-5, "README: the light faces down, got {}", l.normal);
    assert!(l.vertices.iter().all(|v| (v.y - 1.98).abs() < 1e-6));
    assert!((l.area - 0.47 * 0.38).abs() < 1e-4, "area {}", l.area);
    assert_eq!(l.triangles.len(), 2);
}

#[test]
#[cfg_attr(plie_no_shared_scenes, ignore = "needs ../shared/scenes, absent when the tests were built")]
fn cornell_dragon() {
    let Some(s) = check_real("cornell-dragon.obj", 2766, &[(4, Vec3::new(17.0, 12.0, 4.0))]) else { return };
    assert!((s.lights[0].normal - Vec3::NEG_Y).length() < 1e-5);
    assert!((s.lights[0].area - 130.0 * 105.0).abs() < 0.5, "130 x 105 mm, got {}", s.lights[0].area);
}

#[test]
#[cfg_attr(plie_no_shared_scenes, ignore = "needs ../shared/scenes, absent when the tests were built")]
fn cornell_dragon_100k() {
    let lights = [(4, Vec3::new(17.0, 12.0, 4.0)), (4, Vec3::new(6.0, 8.0, 14.0))];
    check_real("cornell-dragon-100k.obj", 100_034, &lights);
}

#[test]
#[cfg_attr(plie_no_shared_scenes, ignore = "needs ../shared/scenes, absent when the tests were built")]
fn cornell_bunny() {
    check_real("cornell-bunny.obj", 69_483, &[(4, Vec3::new(17.0, 12.0, 4.0))]);
}

#[test]
#[cfg_attr(plie_no_shared_scenes, ignore = "needs ../shared/scenes, absent when the tests were built")]
fn boat_lit() {
    let Some(s) = check_real("boat-lit.obj", 7520, &[(4, Vec3::new(400.0, 380.0, 350.0))]) else { return };
    assert!(s.materials.iter().any(|m| m.name == "ground"));
}

/// 331k triangles: in the exhaustive tier.
#[test]
#[ignore = "exhaustive tier (a 331k-triangle file): cargo test --workspace -- --ignored"]
fn conference_lit() {
    let Some(s) = check_real("conference-lit.obj", 331_183, &[(4, Vec3::new(12.0, 12.0, 11.0)); 2]) else { return };
    let m = s.materials.iter().find(|m| m.name == "mesh29_SG").unwrap();
    assert_eq!(m.albedo, Vec3::ONE, "two Kd lines: the last counts");
}

#[test]
#[cfg_attr(plie_no_shared_scenes, ignore = "needs ../shared/scenes, absent when the tests were built")]
fn meshes_without_materials_have_no_lights() {
    let Some(dir) = scenes() else { return };
    for file in ["bunny.obj", "dragon_2734.obj", "dragon_100k.obj"] {
        let msg = parse_error(load_scene(&dir.join(file)), file, None);
        assert!(msg.contains("no lights") && msg.contains("no mtllib"), "{file}: {msg}");
    }
}

// ---- Small OBJ files ----

#[test]
fn fixture_quad_light() {
    let s = load_scene(&data("quad-light.obj")).unwrap();
    assert_eq!((s.name.as_str(), s.triangle_count(), s.lights.len()), ("quad-light", 4, 1));
    let l = &s.lights[0];
    assert_eq!(l.vertices.len(), 4, "duplicated vertices are welded");
    assert!((l.normal - Vec3::NEG_Y).length() < 1e-6 && (l.area - 1.0).abs() < 1e-6);
    assert_eq!(l.radiance, Vec3::new(10.0, 8.0, 6.0));
    let grey = s.materials.iter().find(|m| m.name == "grey").unwrap();
    assert_eq!(grey.albedo, Vec3::splat(0.6), "the last Kd counts");
    assert!(!grey.is_emissive());
}

#[test]
fn faces_without_usemtl_get_the_default_material() {
    let obj = b"mtllib l.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl lamp\nf 1 3 2\n";
    let s = load_from(&[("a.obj", obj), ("l.mtl", b"newmtl lamp\nKe 1\n")], "a.obj").unwrap();
    assert_eq!(s.material_of(plie::TriId(0)).albedo, Vec3::splat(0.8));
    assert_eq!(s.lights[0].radiance, Vec3::ONE, "a single Ke value means grey");
    assert_eq!(s.lights[0].normal, Vec3::NEG_Z, "emits on the counter-clockwise side");
}

#[test]
fn polygons_weights_and_relative_indices() {
    let obj = b"mtllib l.mtl\nusemtl lamp\nv 0 0 0 2\nv 2 0 0 2\nv 2 2 0 2\nv 0 2 0 2\nvt 0 0\nvn 0 0 1\nvn 0 0 1\n\
                f -4/1/1 -3//2 -2 -1\n";
    let s = load_from(&[("a.obj", obj), ("l.mtl", b"newmtl lamp\nKe 1 1 1\n")], "a.obj").unwrap();
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.lights[0].vertices.len(), 4);
    assert!((s.lights[0].area - 1.0).abs() < 1e-6, "w divides: a unit square");
}

#[test]
fn several_libraries_on_one_mtllib_line() {
    let obj = b"mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\nusemtl lamp\nf 1 3 2\n";
    let files: &[(&str, &[u8])] =
        &[("s.obj", obj), ("a.mtl", b"newmtl red\nKd 1 0 0\n"), ("b.mtl", b"newmtl lamp\nKe 2 2 2\n")];
    let s = load_from(files, "s.obj").unwrap();
    assert_eq!(s.material_of(plie::TriId(0)).albedo, Vec3::X);
    assert_eq!(s.lights[0].radiance, Vec3::splat(2.0));
}

fn lit(obj: &[u8]) -> plie::Result<Scene> {
    let mut text = b"mtllib l.mtl\nusemtl lamp\n".to_vec();
    text.extend_from_slice(obj);
    load_from(&[("t.obj", &text), ("l.mtl", b"newmtl lamp\nKe 1 1 1\n")], "t.obj")
}

#[test]
fn empty_file() {
    assert!(parse_error(load_from(&[("e.obj", b"")], "e.obj"), "e.obj", None).contains("empty"));
    let msg = parse_error(load_from(&[("c.obj", b"# only a comment\n")], "c.obj"), "c.obj", None);
    assert!(msg.contains("no faces"), "{msg}");
}

#[test]
fn truncated_face_line() {
    let msg = parse_error(lit(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2"), "t.obj", Some(6));
    assert!(msg.contains("2 vertices") && msg.contains("truncated"), "{msg}");
    let msg = parse_error(lit(b"v 0 0 0\nv 1 0 0\nv 0 1"), "t.obj", Some(5));
    assert!(msg.contains("vertex 3 has 2 numbers") && msg.contains("truncated"), "{msg}");
}

#[test]
fn malformed_numbers() {
    let msg = parse_error(lit(b"v 0 0 0\nv 1 0x 0\n"), "t.obj", Some(4));
    assert!(msg.contains("malformed number '0x'") && msg.contains("vertex 2"), "{msg}");
    let mut obj = V3.to_vec();
    obj.extend_from_slice(b"f 1 2 three\n");
    let msg = parse_error(lit(&obj), "t.obj", Some(6));
    assert!(msg.contains("malformed vertex index 'three'"), "{msg}");
}

#[test]
fn index_out_of_range() {
    for (face, needle) in
        [("f 1 2 4", "index 4 out of range"), ("f -1 -2 -4", "index -4 out of range"), ("f 0 1 2", "index 0")]
    {
        let mut obj = V3.to_vec();
        obj.extend_from_slice(face.as_bytes());
        obj.push(b'\n');
        let msg = parse_error(lit(&obj), "t.obj", Some(6));
        assert!(msg.contains(needle), "{face}: {msg}");
    }
    // An index may only refer to vertices defined before its face.
    let msg = parse_error(lit(b"v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n"), "t.obj", Some(5));
    assert!(msg.contains("2 vertices are defined before"), "{msg}");
}

#[test]
fn non_finite_coordinates() {
    for (v, what) in
        [("v nan 0 0", "'nan'"), ("v 0 inf 0", "'inf'"), ("v 0 0 1e39", "'1e39'"), ("v 0 0 -infinity", "infinity")]
    {
        let obj = format!("v 0 0 0\n{v}\nv 0 1 0\nf 1 2 3\n");
        let msg = parse_error(lit(obj.as_bytes()), "t.obj", Some(4));
        assert!(msg.contains("vertex 2") && msg.contains("non-finite") && msg.contains(what), "{v}: {msg}");
    }
    let msg = parse_error(lit(b"v 1e30 0 0 1e-30\n"), "t.obj", Some(3));
    assert!(msg.contains("not finite after dividing by w"), "{msg}");
}

#[test]
fn missing_mtllib_is_an_error_naming_it() {
    let msg = parse_error(load_scene(&data("missing-mtllib.obj")), "missing-mtllib.obj", Some(2));
    assert!(msg.contains("nowhere.mtl") && msg.contains("cannot open"), "{msg}");
}

#[test]
fn undefined_material() {
    let files: &[(&str, &[u8])] = &[("t.obj", b"mtllib l.mtl\nusemtl glass\n"), ("l.mtl", b"newmtl lamp\nKe 1 1 1\n")];
    let msg = parse_error(load_from(files, "t.obj"), "t.obj", Some(2));
    assert!(msg.contains("'glass'") && msg.contains("l.mtl"), "{msg}");
    let msg = parse_error(load_from(&[("n.obj", b"usemtl lamp\n")], "n.obj"), "n.obj", Some(1));
    assert!(msg.contains("no mtllib comes before it"), "{msg}");
}

#[test]
fn malformed_mtl_lines_are_errors_not_panics() {
    // `Kd 0.5 0.5` makes tobj itself panic; the filter must catch it first.
    for (mtl, line, needle) in [
        ("newmtl lamp\nKd 0.5 0.5\n", 2, "3 numbers"),
        ("newmtl lamp\n\nKe 1 -1 1\n", 3, "negative"),
        ("newmtl lamp\nKe 1 x 1\n", 2, "malformed number 'x'"),
        ("newmtl lamp\nKd spectral file.rfl\n", 2, "spectral"),
        ("newmtl\n", 1, "without a name"),
    ] {
        let files: &[(&str, &[u8])] = &[("t.obj", b"mtllib l.mtl\nusemtl lamp\n"), ("l.mtl", mtl.as_bytes())];
        let msg = parse_error(load_from(files, "t.obj"), "l.mtl", Some(line));
        assert!(msg.contains(needle), "{mtl:?}: {msg}");
    }
}

#[test]
fn zero_area_light_is_an_error() {
    let msg = parse_error(lit(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n"), "t.obj", Some(8));
    assert!(msg.contains("zero area") && msg.contains("lamp"), "{msg}");
}

#[test]
fn binary_garbage_and_odd_inputs() {
    let msg =
        parse_error(load_from(&[("b.obj", &[0x89, b'P', b'N', b'G', 0xff, 0xfe, b'\n'])], "b.obj"), "b.obj", Some(1));
    assert!(msg.contains("UTF-8"), "{msg}");
    // Lines, points, normals and texture coordinates are ignored, whatever they hold (but a face's
    // indices must name ones that exist).
    let s = lit(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn x\nvt\nl 1 99\np 7\ns off\nf 1//1 2/1/ 3/1/-1\n").unwrap();
    assert_eq!(s.triangle_count(), 1);
}

#[test]
fn texture_and_normal_indices_out_of_range() {
    // They were dropped without a word; now they are errors like a vertex index (the face is line 8).
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
    for (face, needle) in [
        ("f 1/2 2/1 3/1", "texture coordinate index 2 out of range: 1 texture coordinates (vt) are defined"),
        ("f 1/1 2/1 3/-2", "texture coordinate index -2 out of range"),
        ("f 1/0 2/1 3/1", "texture coordinate index 0"),
        ("f 1/1/1 2/1/1 3/1/2", "normal index 2 out of range: 1 normals (vn) are defined"),
        ("f 1//1 2//-2 3//1", "normal index -2 out of range"),
        ("f 1//x 2//1 3//1", "malformed normal index '1//x'"),
    ] {
        let msg = parse_error(lit(format!("{head}{face}\n").as_bytes()), "t.obj", Some(8));
        assert!(msg.contains(needle), "{face}: {msg}");
    }
    // Only texture coordinates and normals defined before the face count.
    let msg = parse_error(lit(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\nvt 0 0\n"), "t.obj", Some(6));
    assert!(msg.contains("texture coordinate index 1 out of range: 0 texture"), "{msg}");
    // Relative (negative) indices keep working, for all three.
    let s = lit(format!("{head}vt 1 0\nf -3/-2/-1 -2/-1/-1 -1/-1/1\n").as_bytes()).unwrap();
    assert_eq!(s.triangle_count(), 1);
}

#[test]
fn non_finite_mtl_values() {
    // Also in statements plie ignores (d, Tr, Ns, Ks): the file is broken, whatever reads it.
    for stmt in ["d nan", "Tr -inf", "Ns 1e39", "Ks 0 NaN 0", "Kd 1 nan 1", "Ke 1 1 inf", "d -halo nan", "Ni infinity"]
    {
        let mtl = format!("newmtl lamp\nKe 1 1 1\n{stmt}\n");
        let files: &[(&str, &[u8])] = &[("t.obj", b"mtllib l.mtl\nusemtl lamp\n"), ("l.mtl", mtl.as_bytes())];
        let msg = parse_error(load_from(files, "t.obj"), "l.mtl", Some(3));
        let keyword = stmt.split(' ').next().unwrap();
        assert!(msg.contains(keyword) && msg.contains("non-finite"), "{stmt}: {msg}");
    }
    // Words that are not numbers are left alone.
    let mut obj = b"mtllib l.mtl\nusemtl lamp\n".to_vec();
    obj.extend_from_slice(V3);
    obj.extend_from_slice(b"f 1 2 3\n");
    let files: &[(&str, &[u8])] = &[("t.obj", &obj), ("l.mtl", b"newmtl lamp\nKe 1 1 1\nd -halo 0.5\nTf xyz 1 1 1\n")];
    assert_eq!(load_from(files, "t.obj").unwrap().lights.len(), 1);
}

#[test]
fn byte_order_marks_and_line_endings() {
    let obj = "mtllib l.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let mtl = "newmtl lamp\nKe 1 1 1\n";
    let bom = "\u{FEFF}";
    for (ending, with_bom) in [("\r", false), ("\r\n", false), ("\n", true), ("\r", true), ("\r\n", true)] {
        let bom = if with_bom { bom } else { "" };
        let obj = format!("{bom}{}", obj.replace('\n', ending));
        let mtl = format!("{bom}{}", mtl.replace('\n', ending));
        let s = load_from(&[("t.obj", obj.as_bytes()), ("l.mtl", mtl.as_bytes())], "t.obj");
        let s = s.unwrap_or_else(|e| panic!("{ending:?}, BOM {with_bom}: {e}"));
        assert_eq!((s.triangle_count(), s.lights.len()), (1, 1), "{ending:?}, BOM {with_bom}");
    }
    // Errors in a file with old Mac line endings name the right line.
    let obj = obj.replace("f 1 2 3", "f 1 2 4").replace('\n', "\r");
    let msg =
        parse_error(load_from(&[("t.obj", obj.as_bytes()), ("l.mtl", mtl.as_bytes())], "t.obj"), "t.obj", Some(6));
    assert!(msg.contains("index 4 out of range"), "{msg}");
    let mtl = format!("{bom}newmtl lamp\rKe 1 1 1\rd nan\r");
    let msg =
        parse_error(load_from(&[("t.obj", obj.as_bytes()), ("l.mtl", mtl.as_bytes())], "t.obj"), "l.mtl", Some(3));
    assert!(msg.contains("non-finite"), "{msg}");
}

#[test]
fn unknown_extension_and_missing_file() {
    let msg = parse_error(load_scene(Path::new("scene.ply")), "scene.ply", None);
    assert!(msg.contains(".obj, .gltf, .glb"), "{msg}");
    match load_scene(Path::new("/nonexistent/scene.obj")) {
        Err(Error::Io { path, .. }) => assert_eq!(path, Path::new("/nonexistent/scene.obj")),
        r => panic!("expected an I/O error, got {:?}", r.map(|s| s.name)),
    }
}
