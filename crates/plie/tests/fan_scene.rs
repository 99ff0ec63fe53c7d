//! A disc of 20,000 triangles around one centre (as an OBJ face of that many corners is
//! triangulated): PLOC would build its scene BVH in quadratic time, so the BVH is split top-down
//! (`visibility/bvh/top_down.rs`), and the octree would split around the centre to its depth
//! limit (`octree/hubs.rs`). Every exact mode still answers as brute force, per ray and per light,
//! over it.

mod support;

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};
use plie::internals::construct::refine::{MaxBlockers, RefineParams};
use plie::internals::lie::PlieParams;
use plie::visibility::{LightRays, QueryCtx};
use plie::{LightId, SceneBuilder, TriId};
use support::{Built, ExactModes, TestRng};

const N: usize = 20_000;

/// The disc of `N` segments, ten blades and a slab above it, and a light facing down.
fn disc() -> plie::Scene {
    let n = N;
    let mut b = SceneBuilder::new("disc");
    let w = b.diffuse("w", Vec3::splat(0.7));
    let rim = |i: usize| {
        let a = TAU * i as f32 / n as f32;
        Vec3::new(a.cos(), 0.0, a.sin())
    };
    for i in 0..n {
        b.triangle(Vec3::ZERO, rim(i + 1), rim(i), w);
    }
    // Blockers above the disc: a fan of ten blades around the centre, and a slab.
    for k in 0..10 {
        let (p, q) = (rim(k * n / 10) * 0.8, rim(k * n / 10 + n / 40) * 0.8);
        b.triangle(Vec3::Y * 0.3, p + Vec3::Y * 0.3, q + Vec3::Y * 0.35, w);
    }
    b.quad(
        Vec3::new(-0.2, 0.6, -0.9),
        Vec3::new(-0.2, 0.6, 0.9),
        Vec3::new(0.1, 0.6, 0.9),
        Vec3::new(0.1, 0.6, -0.9),
        w,
    );
    // Counter-clockwise seen from below: it shines down on the disc.
    let light =
        [Vec3::new(-0.3, 1.5, -0.3), Vec3::new(0.3, 1.5, -0.3), Vec3::new(0.3, 1.5, 0.3), Vec3::new(-0.3, 1.5, 0.3)];
    b.light("l", &light, Vec3::ONE);
    b.build().expect("a valid scene")
}

#[test]
fn every_mode_matches_brute_force_over_a_fan_of_20000_triangles() {
    let scene = disc();
    // The centre is a hub (`octree/hubs.rs`): its cells stop splitting. Counting its triangles one
    // by one split them to the default depth, into 44,108 leaves in 37.2 s.
    let built = Built::new(&scene, PlieParams::default());
    assert!(built.octree().leaf_count() <= 64, "{} leaves", built.octree().leaf_count());
    check(&scene, &built, 300);
}

/// Refinement splits the hub's leaves: their children without the hub hold more triangles than the
/// octree's limit, as their parents did. The octree stays valid and every mode exact.
#[test]
fn a_refined_p_lie_over_the_fan_is_valid_and_exact() {
    let scene = disc();
    let refine = RefineParams {
        umbra_full: true,
        umbra_free: true,
        blockers: Some(MaxBlockers::Adaptive),
        ..RefineParams::none()
    };
    let built = Built::refined(&scene, PlieParams { refine, ..PlieParams::default() });
    let report = built.env.validate(&scene);
    assert!(report.is_ok(), "{report:?}");
    assert!(built.octree().leaf_count() > 8, "{} leaves: nothing refined", built.octree().leaf_count());
    check(&scene, &built, 100);
}

/// `points` random points of the disc, 64 samples of the light each: every exact mode against brute
/// force, per ray and per light.
fn check(scene: &plie::Scene, built: &Built, points: usize) {
    let mut modes = ExactModes::new(built, scene);
    let mut ctx = QueryCtx::new(scene.triangles.len());
    let mut rng = TestRng(5);
    let (mut rays, mut blocked) = (0, 0);
    let l = &scene.lights[0];
    for _ in 0..points {
        let t = rng.below(N);
        let (u, v) = (rng.f32(), rng.f32());
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        let x = scene.triangles[t].point(u, v);
        let targets: Vec<Vec3> = (0..64).map(|_| l.sample(Vec2::new(rng.f32(), rng.f32()))).collect();
        let q = LightRays {
            origin: x,
            origin_tri: TriId(t as u32),
            leaf: built.octree().locate(x),
            light: LightId(0),
            targets: &targets,
        };
        rays += 64;
        blocked += modes.check(&format!("point {x} of triangle {t}"), &q, &mut ctx);
    }
    eprintln!("fan: {rays} shadow rays, {blocked} occluded");
    assert!(blocked > rays / 20 && blocked < rays - rays / 20, "{blocked} of {rays} occluded");
}
