//! Grouping emissive triangles into convex polygonal lights (`plie::io::lights`).

use glam::Vec3;
use plie::io::lights::{add_lights, group_lights, EmissiveTriangle, LightGroup, ZeroAreaLight};
use plie::{Material, SceneBuilder, TriId};

fn v(x: f32, y: f32) -> Vec3 {
    Vec3::new(x, y, 0.0)
}

/// Triangles (counter-clockwise around +z) with ids in order and radiance 1.
fn tris(list: &[[Vec3; 3]]) -> Vec<EmissiveTriangle> {
    list.iter()
        .enumerate()
        .map(|(i, t)| EmissiveTriangle { id: TriId(i as u32), vertices: *t, radiance: Vec3::ONE })
        .collect()
}

/// The quad `a b c d` as two triangles.
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

fn square(x: f32, y: f32) -> [[Vec3; 3]; 2] {
    quad(v(x, y), v(x + 1.0, y), v(x + 1.0, y + 1.0), v(x, y + 1.0))
}

fn area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Every input triangle is in exactly one light, and every light is a valid convex polygon whose
/// area is that of its triangles (so the scene builder accepts it).
fn check(input: &[EmissiveTriangle], lights: &[LightGroup]) {
    let mut used = vec![0; input.len()];
    for l in lights {
        let tri_area: f32 = l.triangles.iter().map(|t| area(&input[t.idx()].vertices)).sum();
        let light = plie::Light::new(l.polygon.clone(), l.radiance, l.triangles.clone())
            .unwrap_or_else(|e| panic!("invalid light polygon {:?}: {e}", l.polygon));
        assert!((light.area - tri_area).abs() <= 1e-4 * tri_area, "{} vs {tri_area}", light.area);
        let n = input[l.triangles[0].idx()].vertices;
        assert!(light.normal.dot((n[1] - n[0]).cross(n[2] - n[0])) > 0.0, "emits on the triangles' front side");
        for t in &l.triangles {
            used[t.idx()] += 1;
        }
    }
    assert!(used.iter().all(|&u| u == 1), "{used:?}");
    // The scene builder accepts the lights too.
    let mut b = SceneBuilder::new("t");
    let m = b.material(Material { name: "lamp".into(), albedo: Vec3::ONE, emission: Vec3::ONE, texture: None });
    for t in input {
        b.triangle(t.vertices[0], t.vertices[1], t.vertices[2], m);
    }
    add_lights(&mut b, input).unwrap();
    b.build().unwrap();
}

fn group(list: &[[Vec3; 3]]) -> Vec<LightGroup> {
    let input = tris(list);
    let lights = group_lights(&input).unwrap();
    check(&input, &lights);
    lights
}

#[test]
fn quad_of_two_triangles_is_one_light() {
    let l = group(&square(0.0, 0.0));
    assert_eq!(l.len(), 1);
    assert_eq!(l[0].polygon, [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]);
}

#[test]
fn duplicated_and_slightly_noisy_vertices_are_welded() {
    let mut t = square(100.0, 100.0);
    t[1][0] += Vec3::new(3e-5, -2e-5, 1e-5); // a re-printed coordinate, off in the 7th digit
    assert_eq!(group(&t).len(), 1);
    assert_eq!(group(&t)[0].polygon.len(), 4);
}

#[test]
fn fans_are_one_light() {
    let hex: Vec<Vec3> = (0..6).map(|i| i as f32 * std::f32::consts::TAU / 6.0).map(|a| v(a.cos(), a.sin())).collect();
    let from_vertex: Vec<[Vec3; 3]> = (1..5).map(|i| [hex[0], hex[i], hex[i + 1]]).collect();
    let l = group(&from_vertex);
    assert_eq!((l.len(), l[0].polygon.len()), (1, 6));
    let from_center: Vec<[Vec3; 3]> = (0..6).map(|i| [Vec3::ZERO, hex[i], hex[(i + 1) % 6]]).collect();
    let l = group(&from_center);
    assert_eq!((l.len(), l[0].polygon.len()), (1, 6), "the center is interior, not a corner");
}

#[test]
fn grid_of_quads_and_collinear_edge_points_give_a_rectangle() {
    let grid: Vec<[Vec3; 3]> = (0..3).flat_map(|i| (0..2).flat_map(move |j| square(i as f32, j as f32))).collect();
    let l = group(&grid);
    assert_eq!((l.len(), l[0].polygon.len()), (1, 4));
    // A square split at the midpoint of its bottom edge into three triangles.
    let m = v(0.5, 0.0);
    let l = group(&[[v(0.0, 0.0), m, v(0.0, 1.0)], [m, v(1.0, 1.0), v(0.0, 1.0)], [m, v(1.0, 0.0), v(1.0, 1.0)]]);
    assert_eq!((l.len(), l[0].polygon.len()), (1, 4));
}

#[test]
fn l_shape_is_split_into_convex_lights() {
    let shape: Vec<[Vec3; 3]> = [square(0.0, 0.0), square(1.0, 0.0), square(0.0, 1.0)].concat();
    let l = group(&shape);
    assert!(l.len() == 2 || l.len() == 3, "{} lights", l.len());
    // A ring (a square with a square hole) splits too.
    let ring: Vec<[Vec3; 3]> = (0..3)
        .flat_map(|i| (0..3).filter(move |&j| !(i == 1 && j == 1)).flat_map(move |j| square(i as f32, j as f32)))
        .collect();
    assert!(group(&ring).len() >= 4);
}

#[test]
fn separate_quads_with_the_same_material_are_separate_lights() {
    let l = group(&[square(0.0, 0.0), square(2.0, 0.0)].concat());
    assert_eq!(l.len(), 2);
    // Touching at a corner only is not sharing an edge either.
    assert_eq!(group(&[square(0.0, 0.0), square(1.0, 1.0)].concat()).len(), 2);
}

#[test]
fn different_plane_facing_or_radiance_are_separate_lights() {
    // Bent along the shared edge x = 1.
    let bent = [[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)], [v(1.0, 0.0), Vec3::new(1.0, 0.0, 1.0), v(1.0, 1.0)]];
    assert_eq!(group(&bent).len(), 2);
    // Same plane, but the second triangle faces the other way (same edge direction).
    let flipped = [[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)], [v(0.0, 0.0), v(0.0, 1.0), v(1.0, 1.0)]];
    assert_eq!(group(&flipped).len(), 2);
    // Same quad, different radiance.
    let mut input = tris(&square(0.0, 0.0));
    input[1].radiance = Vec3::splat(2.0);
    let lights = group_lights(&input).unwrap();
    check(&input, &lights);
    assert_eq!(lights.len(), 2);
}

#[test]
fn zero_area_emissive_triangle_is_reported_by_index() {
    let input = tris(&[square(0.0, 0.0)[0], [v(0.0, 0.0), v(1.0, 0.0), v(3.0, 0.0)]]);
    assert_eq!(group_lights(&input), Err(ZeroAreaLight { index: 1 }));
}
