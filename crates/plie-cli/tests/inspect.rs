//! `plie inspect` end to end: the PNG shows the region colours on the inspected leaf, the glTF export
//! loads again with the `gltf` crate with the expected meshes and colours, the summary agrees with
//! `plie build`, and bad input gives a one-line error and a non-zero exit, never a panic.

mod support;

use std::path::Path;

use glam::Vec3;
use plie::geometry::Aabb;
use plie::internals::inspect::{BLOCKER_COLOUR, HIGHLIGHT_COLOUR, PENUMBRA_COLOUR, UMBRA_COLOUR};
use plie::io::image::srgb_encode;
use plie::octree::Octree;
use plie::Camera;
use plie::PlieParams;
use support::{fails_with, plie, stderr};

/// `X,Y,Z` of a point.
fn arg(p: Vec3) -> String {
    format!("{},{},{}", p.x, p.y, p.z)
}

/// Cornell Cube 1 (or 5), its octree as `plie inspect` builds it, and a point in the right-bottom-front
/// cell, whose every lit face lies in umbra (SPEC §6).
fn cornell_cell(name: &str) -> (plie::Scene, Octree, Vec3) {
    let scene = plie::scene::builtin::load(name).unwrap();
    let octree = Octree::build(&scene, PlieParams::default().octree()).expect("valid octree parameters");
    let p = octree.root_bounds().center() + Vec3::new(1.0, -1.0, 1.0);
    (scene, octree, p)
}

/// The 8-bit sRGB pixel a flat overlay colour becomes.
fn rgb8(c: Vec3) -> [u8; 3] {
    c.to_array().map(srgb_encode)
}

/// Pixel coordinates of `p` in a `w` x `h` image from `camera` (see `plie::scene::camera`).
fn project(camera: &Camera, p: Vec3, w: u32, h: u32) -> (f32, f32) {
    let f = (camera.target - camera.eye).normalize();
    let r = f.cross(camera.up).normalize();
    let u = r.cross(f);
    let d = p - camera.eye;
    let t = (camera.fov_deg.to_radians() * 0.5).tan();
    let (sx, sy) = (d.dot(r) / d.dot(f) / (t * w as f32 / h as f32), d.dot(u) / d.dot(f) / t);
    ((sx + 1.0) * 0.5 * w as f32, (1.0 - sy) * 0.5 * h as f32)
}

/// The screen rectangle (x0, y0, x1, y1) covered by box `b`.
fn screen_rect(camera: &Camera, b: &Aabb, w: u32, h: u32) -> (f32, f32, f32, f32) {
    let mut r = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 != 0 { b.max.x } else { b.min.x },
            if i & 2 != 0 { b.max.y } else { b.min.y },
            if i & 4 != 0 { b.max.z } else { b.min.z },
        );
        let (x, y) = project(camera, c, w, h);
        r = (r.0.min(x), r.1.min(y), r.2.max(x), r.3.max(y));
    }
    r
}

#[test]
fn png_of_cornell_cube_1_shows_umbra_inside_the_highlighted_leaf() {
    let (scene, octree, p) = cornell_cell("cornell-cube-1");
    let leaf = octree.leaf_bounds(octree.locate(p).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cell.png");
    let (w, h) = (160u32, 160u32);
    let o = plie(&[
        "inspect",
        "--scene",
        "cornell-cube-1",
        "--cell",
        &arg(p),
        "-o",
        out.to_str().unwrap(),
        "--width",
        &w.to_string(),
        "--height",
        &h.to_string(),
        "--eye-rays",
        "1",
        "--shadow-rays",
        "4",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("removed (fully in umbra)"), "the cell's faces are described: {err}");

    let img = image::open(&out).expect("a PNG the image crate reads").to_rgb8();
    assert_eq!(img.dimensions(), (w, h));
    let (x0, y0, x1, y1) = screen_rect(&scene.camera_or_default(), &leaf, w, h);
    let inside = |x: u32, y: u32, grow: f32| {
        x as f32 + 0.5 >= x0 - grow
            && x as f32 + 0.5 <= x1 + grow
            && y as f32 + 0.5 >= y0 - grow
            && y as f32 + 0.5 <= y1 + grow
    };
    let (umbra, highlight) = (rgb8(UMBRA_COLOUR), rgb8(HIGHLIGHT_COLOUR));
    let (mut umbra_in, mut umbra_out, mut highlight_px, mut rect_px) = (0, 0, 0, 0);
    for (x, y, px) in img.enumerate_pixels() {
        rect_px += inside(x, y, 0.0) as usize;
        if px.0 == umbra {
            if inside(x, y, 1.0) {
                umbra_in += 1;
            } else {
                umbra_out += 1;
            }
        }
        if px.0 == highlight && inside(x, y, 3.0) {
            highlight_px += 1;
        }
    }
    // Every lit face of this cell is removed, so drawn fully in umbra; the cell's back face faces the
    // camera and covers much of the cell's screen rectangle.
    assert!(umbra_in * 4 > rect_px, "umbra covers {umbra_in} of the leaf's {rect_px} pixels");
    assert_eq!(umbra_out, 0, "umbra colour only on the inspected leaf");
    assert!(highlight_px > 20, "the leaf's edges are highlighted ({highlight_px} pixels)");
    let penumbra = rgb8(PENUMBRA_COLOUR);
    assert!(img.pixels().all(|p| p.0 != penumbra), "a fully dark cell has no penumbra");
}

/// A loaded mesh: its name, its primitives' base colours, its vertex count.
type MeshInfo = (String, Vec<[f32; 4]>, usize);

/// Loads a glTF or GLB file; returns its meshes and its node names.
fn load_gltf(path: &Path) -> (Vec<MeshInfo>, Vec<String>) {
    let (doc, buffers, _) = gltf::import(path).expect("the gltf crate loads the export");
    let meshes = doc
        .meshes()
        .map(|m| {
            let colours = m.primitives().map(|p| p.material().pbr_metallic_roughness().base_color_factor()).collect();
            let vertices = m
                .primitives()
                .map(|p| p.reader(|b| Some(&buffers[b.index()])).read_positions().expect("positions").count())
                .sum();
            (m.name().unwrap_or_default().to_string(), colours, vertices)
        })
        .collect();
    let nodes = doc.nodes().map(|n| n.name().unwrap_or_default().to_string()).collect();
    (meshes, nodes)
}

#[test]
fn gltf_and_glb_exports_load_with_the_expected_meshes_and_colours() {
    let dir = tempfile::tempdir().unwrap();
    // Cornell Cube 2, the leaf with the tall block's umbra and penumbra on its up face.
    let (_, octree, _) = cornell_cell("cornell-cube-2");
    let p = octree.root_bounds().center() + Vec3::new(1.0, -1.0, 1.0);
    let leaf = octree.locate(p).unwrap();
    for ext in ["gltf", "glb"] {
        let out = dir.path().join(format!("cell.{ext}"));
        let o = plie(&["inspect", "--scene", "cornell-cube-2", "--cell", &arg(p), "-o", out.to_str().unwrap(), "-q"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let (meshes, nodes) = load_gltf(&out);
        let get = |name: &str| {
            meshes.iter().find(|m| m.0 == name).unwrap_or_else(|| panic!("{ext}: no mesh '{name}' in {meshes:?}"))
        };
        let colour = |c: Vec3| [c.x, c.y, c.z, 1.0];
        assert!(get("scene").1.len() >= 3, "one primitive per material");
        assert_eq!(get("clipped blockers").1, vec![colour(BLOCKER_COLOUR)]);
        assert!(get("blockers").2 > 0);
        assert_eq!(get(&format!("leaf {}", leaf.0)).1, vec![colour(HIGHLIGHT_COLOUR)]);
        assert_eq!(get(&format!("leaf {}", leaf.0)).2, 24, "12 edges as lines");
        assert_eq!(get("octree leaves").2 % 2, 0);
        assert_eq!(get("umbra up").1, vec![colour(UMBRA_COLOUR)]);
        assert_eq!(get("penumbra up").1, vec![colour(PENUMBRA_COLOUR)]);
        assert!(get("umbra up").2 % 3 == 0 && get("umbra up").2 > 0);
        assert!(nodes.iter().any(|n| n == "camera"), "{nodes:?}");
    }
    let a = std::fs::read(dir.path().join("cell.glb")).unwrap();
    assert_eq!(&a[..4], b"glTF");
}

#[test]
fn gltf_of_a_removed_face_has_full_umbra_and_no_penumbra() {
    let dir = tempfile::tempdir().unwrap();
    let (_, octree, p) = cornell_cell("cornell-cube-1");
    let b = octree.leaf_bounds(octree.locate(p).unwrap());
    let out = dir.path().join("up.gltf");
    let o = plie(&[
        "inspect",
        "--scene",
        "cornell-cube-1",
        "--cell",
        &arg(p),
        "--face",
        "up",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    let faces = v["inspection"]["faces"].as_array().unwrap();
    assert_eq!(faces.len(), 1);
    assert_eq!(faces[0]["status"], "removed");
    assert_eq!(faces[0]["umbra_fraction"], 1.0);
    assert!(!faces[0]["blockers"].as_array().unwrap().is_empty(), "blockers gathered again");
    let (meshes, _) = load_gltf(&out);
    assert!(meshes.iter().any(|m| m.0 == "umbra up" && m.2 == 6), "the whole face: {meshes:?}");
    assert!(!meshes.iter().any(|m| m.0.starts_with("penumbra")), "{meshes:?}");
    // The umbra lies on the face, just outside the cell.
    let (doc, buffers, _) = gltf::import(&out).unwrap();
    let mesh = doc.meshes().find(|m| m.name() == Some("umbra up")).unwrap();
    for prim in mesh.primitives() {
        for q in prim.reader(|b| Some(&buffers[b.index()])).read_positions().unwrap() {
            let q = Vec3::from(q);
            assert!(q.y > b.max.y && q.y - b.max.y < 1.0, "{q} above the up face at {}", b.max.y);
            assert!(q.x >= b.min.x && q.x <= b.max.x && q.z >= b.min.z && q.z <= b.max.z, "{q} on the face");
        }
    }
}

#[test]
fn summary_agrees_with_plie_build() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("c5.plie");
    let o = plie(&["build", "--scene", "cornell-cube-5", "-o", file.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let built: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for extra in [vec![], vec!["--plie", file.to_str().unwrap()]] {
        let mut args = vec!["inspect", "--scene", "cornell-cube-5", "--summary", "--json"];
        args.extend(extra);
        let o = plie(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
        let s = &v["summary"];
        assert_eq!(s["records"], built["records"]);
        assert_eq!(s["removed"], built["records_removed_umbra"]);
        assert_eq!(s["cannot_see_light"], built["records_removed_face_cannot_see_light"]);
        let leaves = s["leaves"].as_array().unwrap();
        assert_eq!(leaves.len(), built["leaves"].as_u64().unwrap() as usize);
        let rows: Vec<&serde_json::Value> = leaves.iter().flat_map(|l| l["faces"].as_array().unwrap()).collect();
        assert_eq!(rows.len(), leaves.len() * 6 * 2, "every face and both lights");
        let blockers: u64 = rows.iter().filter_map(|r| r["blockers"].as_u64()).sum();
        assert_eq!(blockers, built["blockers_total"].as_u64().unwrap());
        for r in &rows {
            let f = |k: &str| r[k].as_f64();
            match r["status"].as_str().unwrap() {
                "record" => {
                    let (u, p) = (f("umbra_fraction").unwrap(), f("penumbra_fraction").unwrap());
                    assert!((0.0..1.0).contains(&u) && (0.0..=1.0).contains(&p), "{r}");
                }
                "removed" => assert_eq!((f("umbra_fraction"), r["blockers"].is_null()), (Some(1.0), true), "{r}"),
                "cannot_see_light" => assert!(r["umbra_fraction"].is_null(), "{r}"),
                s => panic!("unknown status {s}"),
            }
        }
    }
}

#[test]
fn summary_text_lists_the_cell_of_a_point() {
    let (_, octree, p) = cornell_cell("cornell-cube-1");
    let leaf = octree.locate(p).unwrap();
    let o = plie(&["inspect", "--scene", "cornell-cube-1", "--summary", "--cell", &arg(p), "--light", "0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains(&format!("leaf {} ", leaf.0)), "{out}");
    assert_eq!(out.lines().filter(|l| l.starts_with("leaf ")).count(), 1, "{out}");
    let rows = |what: &str| out.lines().filter(|l| l.starts_with("  ") && l.contains(what)).count();
    assert_eq!(rows("removed (fully in umbra)"), 3, "{out}");
    assert_eq!(rows("cannot see the light"), 3, "{out}");
}

#[test]
fn bad_input_gives_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let png = png.to_str().unwrap();
    let (_, octree, p) = cornell_cell("cornell-cube-1");
    let cell = arg(p);
    let base = |extra: &[&str]| {
        let mut a = vec!["inspect", "--scene", "cornell-cube-1", "--width", "8", "--height", "8"];
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |extra: &[&str], needle: &str| {
        let a = base(extra);
        fails_with(&a.iter().map(String::as_str).collect::<Vec<_>>(), needle);
    };
    let far = arg(octree.root_bounds().max + Vec3::splat(10.0));
    run(&["--cell", &far, "-o", png], "outside the octree");
    run(&["--cell", &far, "--summary"], "outside the octree");
    run(&["--cell", &cell, "-o", png, "--light", "1"], "light 1 does not exist");
    run(&["--summary", "--light", "7"], "light 7 does not exist");
    run(&["--cell", &cell, "-o", png, "--face", "top"], "unknown face 'top'");
    // The right-bottom-front cell's down face cannot see the ceiling light.
    run(&["--cell", &cell, "-o", png, "--face", "down"], "cannot see light 0");
    run(&["--cell", &cell, "-o", dir.path().join("x.txt").to_str().unwrap()], "unknown output format '.txt'");
    run(&["--cell", &cell, "-o", dir.path().join("no/such/dir/x.png").to_str().unwrap()], "does not exist");
    run(&["--cell", &cell], "nothing to do");
    run(&["-o", png], "needs --cell");
    run(&["--cell", &cell, "-o", png, "--line-width", "0"], "line-width");
    run(&["--cell", &cell, "-o", png, "--plie", dir.path().join("missing.plie").to_str().unwrap()], "missing.plie");
    assert!(!Path::new(png).exists(), "nothing written on error");
    // A malformed point is refused by the argument parser: usage error, no panic.
    let o = plie(&["inspect", "--scene", "cornell-cube-1", "--cell", "1,2", "--summary"]);
    assert!(!o.status.success() && !stderr(&o).contains("panicked"), "{}", stderr(&o));
}
