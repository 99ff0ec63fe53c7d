//! The ten built-in scenes of SPEC §6: they load, have the thesis' triangle and light counts, are
//! well-formed (no degenerate triangles, albedos in [0, 1], lights facing the scene and clear of other
//! geometry), have a camera looking at them, and have the character the thesis describes where that
//! can be checked (Cornell dimensions and wall colours, Cornell Cube 1's octant in umbra, the second
//! light of Huis C and the light of Boot out of view).

use glam::Vec3;
use plie::geometry::{Aabb, RayTest};
use plie::scene::builtin::{load, NAMES};
use plie::{Error, Scene};

/// (name, thesis triangle count, lights, count must be exact).
const EXPECTED: [(&str, usize, usize, bool); 10] = [
    ("cornell-cube-1", 16, 1, true),
    ("cornell-cube-2", 32, 1, true),
    ("cornell-cube-3", 1932, 1, true),
    ("cornell-cube-4", 34, 2, true),
    ("cornell-cube-5", 18, 2, true),
    ("huis-a", 4913, 1, false),
    ("huis-b", 5789, 1, false),
    ("huis-c", 5791, 2, false),
    ("dragon", 2766, 1, false),
    ("boot", 3974, 1, false),
];

const CORNELL: [&str; 6] =
    ["cornell-cube-1", "cornell-cube-2", "cornell-cube-3", "cornell-cube-4", "cornell-cube-5", "dragon"];

fn all() -> Vec<Scene> {
    NAMES.iter().map(|n| load(n).unwrap_or_else(|e| panic!("{n}: {e}"))).collect()
}

/// True if some triangle other than the light's own blocks the open segment `x -> y`.
fn blocked(s: &Scene, x: Vec3, y: Vec3) -> bool {
    let ray = RayTest::new(x, y - x, 1e-4, 1.0 - 1e-4);
    s.triangles.iter().zip(&s.tri_light).any(|(t, l)| l.is_none() && ray.hit(t).is_some())
}

/// True if `p` is inside the camera's view (square image).
fn in_view(s: &Scene, p: Vec3) -> bool {
    let c = s.camera.unwrap();
    let f = (c.target - c.eye).normalize();
    let r = f.cross(c.up).normalize();
    let u = r.cross(f);
    let d = p - c.eye;
    let z = d.dot(f);
    let t = (c.fov_deg.to_radians() * 0.5).tan();
    z > 0.0 && d.dot(r).abs() <= t * z && d.dot(u).abs() <= t * z
}

#[test]
fn names_and_counts_match_the_thesis() {
    assert_eq!(NAMES.len(), EXPECTED.len());
    for (s, &(name, tris, lights, exact)) in all().iter().zip(&EXPECTED) {
        assert_eq!(s.name, name);
        let n = s.triangle_count();
        if exact {
            assert_eq!(n, tris, "{name}: triangle count");
        } else {
            let err = (n as f64 - tris as f64).abs() / tris as f64;
            assert!(err <= 0.10, "{name}: {n} triangles, thesis {tris}");
        }
        assert_eq!(s.lights.len(), lights, "{name}: light count");
        assert_eq!(s.degenerate_skipped, 0, "{name}: degenerate triangles");
    }
}

#[test]
fn unknown_name_is_an_error() {
    match load("cornell-cube-6") {
        Err(Error::UnknownScene { name, known }) => {
            assert_eq!(name, "cornell-cube-6");
            assert!(known.contains("huis-a"));
        }
        other => panic!("expected UnknownScene, got {other:?}"),
    }
}

#[test]
fn generation_is_deterministic() {
    for n in NAMES {
        let (a, b) = (load(n).unwrap(), load(n).unwrap());
        assert_eq!(a.triangles, b.triangles, "{n}");
    }
}

#[test]
fn materials_are_lambertian_with_albedo_in_unit_range() {
    for s in all() {
        for m in &s.materials {
            assert!(m.albedo.min_element() >= 0.0 && m.albedo.max_element() <= 1.0, "{}: {}", s.name, m.name);
        }
    }
}

#[test]
fn lights_shine_into_the_scene_and_are_clear_of_other_geometry() {
    for s in all() {
        let step = 1e-3 * s.scale();
        for (i, l) in s.lights.iter().enumerate() {
            let c = l.center();
            assert!(s.bounds.contains(c + l.normal * step), "{} light {i} faces out of the scene", s.name);
            assert!(l.normal.dot(s.bounds.center() - c) > 0.0, "{} light {i} faces away", s.name);
            // Nothing lies on the light or right in front of or behind it.
            let eps = 1e-4 * s.scale();
            assert!(!blocked(&s, c - l.normal * eps, c + l.normal * eps), "{} light {i} touches geometry", s.name);
            // Its centre lights something: the first hit in front of it is not at the light itself.
            assert!(l.radiance.max_element() > 0.0);
        }
    }
}

#[test]
fn cameras_look_at_the_scene() {
    for s in all() {
        let c = s.camera.unwrap_or_else(|| panic!("{}: no camera", s.name));
        let to_center = (s.bounds.center() - c.eye).normalize();
        let angle = (c.target - c.eye).normalize().dot(to_center).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(angle < 25.0, "{}: camera looks {angle}° away from the scene centre", s.name);
        assert!(c.fov_deg > 20.0 && c.fov_deg < 90.0);
    }
}

#[test]
fn cornell_room_has_the_published_size_and_colours() {
    let s = load("cornell-cube-2").unwrap();
    let size = s.bounds.size();
    assert!((size - Vec3::new(556.0, 548.8, 559.2)).abs().max_element() < 5.0, "{size}");
    assert!(s.bounds.min.abs().max_element() < 1e-3);
    for n in CORNELL {
        let s = load(n).unwrap();
        let cam = s.camera.unwrap();
        let right = (cam.target - cam.eye).cross(cam.up);
        for (i, t) in s.triangles.iter().enumerate() {
            let m = s.material_of(plie::TriId(i as u32));
            let inward = t.normal().dot(s.bounds.center() - t.centroid()) > 0.0;
            match m.name.as_str() {
                "red" => {
                    assert!(t.v.iter().all(|v| (v.x - 556.0).abs() < 1e-3), "{n}: red wall not at x = 556");
                    assert!((t.centroid() - cam.eye).dot(right) < 0.0, "{n}: red wall not on the image's left");
                    assert!(inward, "{n}: red wall faces out");
                }
                "green" => assert!(t.v.iter().all(|v| v.x.abs() < 1e-3) && inward, "{n}: green wall"),
                _ => {}
            }
        }
        let white_walls = s.triangles.iter().enumerate().filter(|(i, t)| {
            let on_wall = t.v.iter().all(|v| v.y.abs() < 1e-3 || (v.y - 548.8).abs() < 1e-3)
                || t.v.iter().all(|v| (v.z - 559.2).abs() < 1e-3);
            on_wall && s.tri_light[*i].is_none() && s.material_of(plie::TriId(*i as u32)).name == "white"
        });
        for (_, t) in white_walls {
            assert!(t.normal().dot(s.bounds.center() - t.centroid()) > 0.0, "{n}: a white wall faces out");
        }
    }
}

/// `n x n` points on each of the six faces of `b`, corners and edges included.
fn face_points(b: &Aabb, n: usize) -> Vec<Vec3> {
    let mut out = Vec::new();
    for axis in 0..3 {
        let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [b.min[axis], b.max[axis]] {
            for i in 0..n {
                for j in 0..n {
                    let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
                    let mut x = Vec3::ZERO;
                    x[axis] = side;
                    x[a1] = b.min[a1] + (b.max[a1] - b.min[a1]) * u;
                    x[a2] = b.min[a2] + (b.max[a2] - b.min[a2]) * v;
                    out.push(x);
                }
            }
        }
    }
    out
}

/// Thesis §7.1: the right-bottom-front octree cell of Cornell Cube 1 is in umbra on every face. With
/// the root cube of SPEC §3 (centred on the scene, half-size the largest vertex distance) and SPEC's
/// directions (Right = +x, Down = -y, Front = +z), every segment from that cell's faces to the light
/// is blocked. The faces are sampled, and so are the faces of the cell's part inside the room (whose
/// corners are the hardest points to shade). The same holds in Cornell Cube 5 for its first light.
#[test]
fn cornell_cube_1_right_bottom_front_cell_is_in_umbra() {
    for name in ["cornell-cube-1", "cornell-cube-5"] {
        let s = load(name).unwrap();
        let c = s.bounds.center();
        let half = s.triangles.iter().flat_map(|t| t.v).map(|v| (v - c).length()).fold(0.0, f32::max);
        let cell = Aabb::new(Vec3::new(c.x, c.y - half, c.z), Vec3::new(c.x + half, c.y, c.z + half));
        let inside = Aabb::new(cell.min.max(s.bounds.min), cell.max.min(s.bounds.max));
        let light = &s.lights[0];
        let [v0, v1, _, v3] = [0, 1, 2, 3].map(|i| light.vertices[i]);
        let m = 5;
        for x in face_points(&cell, 13).into_iter().chain(face_points(&inside, 13)) {
            for k in 0..m * m {
                let (p, q) = ((k % m) as f32 / (m - 1) as f32, (k / m) as f32 / (m - 1) as f32);
                let y = v0 + (v1 - v0) * p + (v3 - v0) * q;
                assert!(blocked(&s, x, y), "{name}: {x} sees the light at {y}");
            }
        }
    }
}

#[test]
fn second_light_of_huis_c_and_the_light_of_boot_are_out_of_view() {
    let s = load("huis-c").unwrap();
    assert!(in_view(&s, s.lights[0].center()), "huis-c: the first light should be in view");
    assert!(s.lights[1].vertices.iter().all(|&v| !in_view(&s, v)), "huis-c: the second light is in view");
    let s = load("boot").unwrap();
    assert!(s.lights[0].vertices.iter().all(|&v| !in_view(&s, v)), "boot: the light is in view");
}

#[test]
fn boot_light_is_distant_and_faces_the_boat() {
    let s = load("boot").unwrap();
    let l = &s.lights[0];
    // The boat: everything but the water and the light, i.e. the triangles above the water line.
    let boat = s
        .triangles
        .iter()
        .zip(&s.tri_light)
        .filter(|(t, l)| l.is_none() && t.aabb().size().max_element() < 0.2 * s.scale())
        .fold(Aabb::EMPTY, |b, (t, _)| b.union(t.aabb()));
    let to_boat = boat.center() - l.center();
    assert!(to_boat.length() > 2.0 * boat.size().max_element(), "the light is not distant");
    assert!(l.normal.dot(to_boat.normalize()) > 0.7, "the light does not face the boat");
    assert!(l.area.sqrt() < 0.5 * to_boat.length(), "the light is not small for its distance");
}
