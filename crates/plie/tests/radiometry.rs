//! The estimator of SPEC §2 against Lambert's analytic irradiance from a polygon.

use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use plie::internals::render::shade::{shade_hit, ShadeScratch};
use plie::internals::render::Hit;
use plie::visibility::Brute;
use plie::{SceneBuilder, TriId};

/// A 1 x 1 light at height 1 facing down over a large floor (albedo 0.5).
fn scene() -> plie::Scene {
    let mut b = SceneBuilder::new("lambert");
    let floor = b.diffuse("floor", Vec3::splat(0.5));
    b.quad(
        Vec3::new(-10.0, 0.0, -10.0),
        Vec3::new(-10.0, 0.0, 10.0),
        Vec3::new(10.0, 0.0, 10.0),
        Vec3::new(10.0, 0.0, -10.0),
        floor,
    );
    // Counter-clockwise seen from below: emits down.
    let poly =
        [Vec3::new(-0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, -0.5), Vec3::new(0.5, 1.0, 0.5), Vec3::new(-0.5, 1.0, 0.5)];
    b.light("light", &poly, Vec3::new(2.0, 3.0, 4.0));
    b.build().unwrap()
}

/// Lambert: integral of cos_x cos_y / r^2 over the polygon = 1/2 |sum_i theta_i (n . gamma_i)|.
fn lambert(x: DVec3, n: DVec3, poly: &[DVec3]) -> f64 {
    let mut s = 0.0;
    for i in 0..poly.len() {
        let a = (poly[i] - x).normalize();
        let b = (poly[(i + 1) % poly.len()] - x).normalize();
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        s += theta * n.dot(a.cross(b).normalize());
    }
    0.5 * s.abs()
}

fn hit(point: Vec3, normal: Vec3, tri: u32, front: bool) -> Hit {
    Hit { point, normal, dir: -normal, tri: TriId(tri), front, leaf: None }
}

#[test]
fn estimator_matches_lambert_polygon_irradiance() {
    let s = scene();
    let vis = Brute::new(&s);
    let n = 1024;
    let mut scratch = ShadeScratch::new(&s, n);
    let poly: Vec<DVec3> = s.lights[0].vertices.iter().map(|v| v.as_dvec3()).collect();
    for p in [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.3, 0.0, 0.2), Vec3::new(1.5, 0.0, -0.7)] {
        let h = hit(p, Vec3::Y, 0, true);
        let mut sum = DVec3::ZERO;
        let runs = 200;
        for r in 0..runs {
            sum += shade_hit(&s, &vis, &h, 42, (r, 0), &mut scratch).as_dvec3();
        }
        let got = sum / runs as f64;
        let expected = DVec3::new(2.0, 3.0, 4.0) * (0.5 / PI) * lambert(p.as_dvec3(), DVec3::Y, &poly);
        let rel = ((got - expected) / expected).abs().max_element();
        assert!(rel < 0.005, "at {p}: got {got}, expected {expected} (relative error {rel})");
    }
}

#[test]
fn points_behind_the_light_or_facing_away_get_exactly_zero() {
    let s = scene();
    let vis = Brute::new(&s);
    let mut scratch = ShadeScratch::new(&s, 16);
    // Above the light (it emits down): cos_y <= 0 for every sample.
    let above = hit(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, 0, true);
    assert_eq!(shade_hit(&s, &vis, &above, 1, (0, 0), &mut scratch), Vec3::ZERO);
    // A floor point whose shading normal points down (seen from below): cos_x <= 0.
    let away = hit(Vec3::new(0.0, 0.0, 0.0), -Vec3::Y, 0, false);
    assert_eq!(shade_hit(&s, &vis, &away, 1, (0, 0), &mut scratch), Vec3::ZERO);
}

#[test]
fn light_seen_directly_shows_ke_from_the_front_only() {
    let s = scene();
    let vis = Brute::new(&s);
    let mut scratch = ShadeScratch::new(&s, 16);
    let light_tri = s.lights[0].triangles[0].0;
    let p = Vec3::new(0.1, 1.0, 0.1);
    let front = hit(p, -Vec3::Y, light_tri, true);
    assert_eq!(shade_hit(&s, &vis, &front, 1, (0, 0), &mut scratch), Vec3::new(2.0, 3.0, 4.0));
    let back = hit(p, Vec3::Y, light_tri, false);
    assert_eq!(shade_hit(&s, &vis, &back, 1, (0, 0), &mut scratch), Vec3::ZERO);
}
