//! SPEC §5 exactness: every visibility mode answers every shadow ray exactly as brute force, on every
//! built-in scene (10k rays each in the fast tier, 100k in the exhaustive one) and on the real scenes
//! in ../shared/scenes/ (exhaustive tier).
//!
//! Shadow rays (what the renderer shoots: `y` on a light, `x` in front of it) start on triangles, on
//! octree cell faces, edges and corners, and anywhere in the scene; every mode answers them. Free
//! segments (axis-parallel, or between any two points) have no light to look up, so only the modes
//! that do not use a P-LIE answer those.

mod support;

use plie::internals::lie::PlieParams;
use plie::octree::Octree;
use plie::visibility::{Mode, QueryCtx, ShadowRay};
use plie::{LightId, Scene};
use rayon::prelude::*;
use support::{shadow_rays, start_point, Built, TestRng};

/// Scenes above this many triangles compare with brute force on a subsample only.
const BRUTE_LIMIT: usize = 10_000;
/// Shadow rays per scene: the exhaustive tier, and the fast tier (other rays: another seed).
const SEGMENTS: usize = 100_000;
const SEGMENTS_FAST: usize = 10_000;

/// Free segments: axis-parallel ones and ones between any two points of the (slightly grown) box.
fn free_segments(scene: &Scene, octree: &Octree, n: usize, seed: u64) -> Vec<ShadowRay> {
    let mut rng = TestRng(seed);
    let b = scene.bounds;
    let grow = b.size() * 0.05;
    let (lo, hi) = (b.min - grow, b.max + grow);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let (x, tri) = start_point(scene, octree, &mut rng);
        let y = if rng.below(2) == 0 {
            let k = rng.below(3);
            let mut y = x;
            y[k] = if rng.below(2) == 0 { lo[k] } else { hi[k] };
            y
        } else {
            rng.point_in(lo, hi)
        };
        if y != x {
            out.push(ShadowRay::new(x, y, LightId(rng.below(scene.lights.len()) as u32), tri, None));
        }
    }
    out
}

/// Answers of `mode` for every ray (in parallel, deterministic order).
fn answers(scene: &Scene, built: &Built, mode: Mode, rays: &[ShadowRay]) -> Vec<bool> {
    let vis = built.vis(scene, mode);
    rays.par_chunks(1024)
        .map_init(
            || QueryCtx::new(scene.triangles.len()),
            |ctx, chunk| chunk.iter().map(|r| vis.occluded(r, ctx)).collect::<Vec<_>>(),
        )
        .flatten()
        .collect()
}

fn compare(scene: &Scene, built: &Built, what: &str, modes: &[Mode], rays: &[ShadowRay]) {
    let big = scene.triangle_count() > BRUTE_LIMIT;
    let sample = if big { &rays[..2_000] } else { rays };
    let reference = answers(scene, built, Mode::Brute, sample);
    let blocked = reference.iter().filter(|&&b| b).count();
    assert!(blocked > 0 && blocked < reference.len(), "{}: {what} must include both answers", scene.name);
    for &mode in modes.iter().filter(|&&m| m != Mode::Brute) {
        let got = answers(scene, built, mode, sample);
        if let Some(i) = (0..got.len()).find(|&i| got[i] != reference[i]) {
            panic!(
                "{}: {mode} says {} for {what} {i} {:?}, brute force says {}",
                scene.name, got[i], sample[i], reference[i]
            );
        }
    }
    if big {
        let reference = answers(scene, built, Mode::Bvh, rays);
        for &mode in modes.iter().filter(|&&m| m != Mode::Brute && m != Mode::Bvh) {
            assert!(
                answers(scene, built, mode, rays) == reference,
                "{}: {mode} disagrees with bvh on {what}",
                scene.name
            );
        }
    }
}

fn check_scene(scene: &Scene, segments: usize, seed: u64) {
    let built = Built::new(scene, PlieParams::thesis());
    let rays = shadow_rays(scene, built.octree(), segments, seed);
    compare(scene, &built, "shadow ray", &Mode::EXACT, &rays);
    let free: Vec<Mode> = Mode::EXACT.into_iter().filter(|m| !m.needs_plie()).collect();
    let segs = free_segments(scene, built.octree(), segments / 4, seed + 1);
    compare(scene, &built, "free segment", &free, &segs);
}

#[test]
fn every_mode_matches_brute_force_on_builtin_scenes() {
    for scene in support::builtins() {
        check_scene(&scene, SEGMENTS_FAST, 5678);
    }
}

/// A floor, 300 small blockers and a 24-sided light: the shafts' planes are chosen from the first
/// 16 of a face's corners and the light's vertices, and must still hold the other vertices.
#[test]
fn every_mode_matches_brute_force_with_a_many_sided_light() {
    use glam::Vec3;
    let mut b = plie::SceneBuilder::new("many-sided light");
    let m = b.diffuse("white", Vec3::splat(0.5));
    b.quad(
        Vec3::new(-3.0, 0.0, -3.0),
        Vec3::new(-3.0, 0.0, 3.0),
        Vec3::new(3.0, 0.0, 3.0),
        Vec3::new(3.0, 0.0, -3.0),
        m,
    );
    let mut rng = TestRng(77);
    for _ in 0..300 {
        let c = rng.point_in(Vec3::new(-2.5, 0.3, -2.5), Vec3::new(2.5, 2.7, 2.5));
        let e1 = rng.point_in(Vec3::new(-0.2, 0.0, -0.2), Vec3::new(0.2, 0.0, 0.2));
        let e2 = rng.point_in(Vec3::new(-0.05, -0.2, 0.1), Vec3::new(0.05, 0.2, 0.1));
        b.triangle(c, c + e1, c + e2, m);
    }
    let light: Vec<Vec3> = (0..24)
        .map(|k| {
            let a = k as f32 / 24.0 * std::f32::consts::TAU;
            Vec3::new(1.5 * a.cos(), 3.0, 1.5 * a.sin())
        })
        .collect();
    b.light("disc", &light, Vec3::ONE);
    let scene = b.build().unwrap();
    check_scene(&scene, SEGMENTS_FAST, 91);
}

#[test]
#[ignore = "exhaustive tier (100k rays per scene): cargo test --workspace -- --ignored"]
fn every_mode_matches_brute_force_on_builtin_scenes_many_rays() {
    for scene in support::builtins() {
        check_scene(&scene, SEGMENTS, 1234);
    }
}

#[test]
#[ignore = "exhaustive tier (real scenes): cargo test --workspace -- --ignored"]
fn every_mode_matches_brute_force_on_shared_scenes() {
    for scene in support::load_shared() {
        check_scene(&scene, SEGMENTS, 1234);
    }
}
