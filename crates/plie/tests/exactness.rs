//! SPEC §5 exactness: every visibility mode answers every shadow ray exactly as brute force, on every
//! built-in scene and on the real scenes in ../shared/scenes/.
//!
//! Shadow rays (what the renderer shoots: `y` on a light, `x` in front of it) start on triangles, on
//! octree cell faces, edges and corners, and anywhere in the scene; every mode answers them. Free
//! segments (axis-parallel, or between any two points) have no light to look up, so only the modes
//! that do not use a P-LIE answer those.

mod support;

use glam::{Vec2, Vec3};
use plie::lie::PlieParams;
use plie::octree::{LeafId, Octree};
use plie::visibility::{Mode, QueryCtx, ShadowRay};
use plie::{LightId, Scene, TriId};
use rayon::prelude::*;
use support::{Built, TestRng};

/// Scenes above this many triangles compare with brute force on a subsample only.
const BRUTE_LIMIT: usize = 10_000;
const SEGMENTS: usize = 100_000;

/// A shading-like start point: on a triangle, on a leaf's face/edge/corner, or anywhere.
fn start_point(scene: &Scene, octree: &Octree, rng: &mut TestRng) -> (Vec3, TriId) {
    let b = scene.bounds;
    match rng.below(4) {
        0 | 1 => {
            let t = rng.below(scene.triangles.len());
            let (mut u, mut v) = (rng.f32(), rng.f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            (scene.triangles[t].point(u, v), TriId(t as u32))
        }
        2 => {
            let c = octree.leaf_bounds(LeafId(rng.below(octree.leaf_count()) as u32));
            let mut p = rng.point_in(c.min, c.max);
            for k in 0..3 {
                match rng.below(3) {
                    0 => p[k] = c.min[k],
                    1 => p[k] = c.max[k],
                    _ => {}
                }
            }
            (p, TriId(u32::MAX))
        }
        _ => (rng.point_in(b.min, b.max), TriId(u32::MAX)),
    }
}

/// Shadow rays: `y` uniform on a light, `x` strictly in front of it.
pub fn shadow_rays(scene: &Scene, octree: &Octree, n: usize, seed: u64) -> Vec<ShadowRay> {
    let mut rng = TestRng(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let li = rng.below(scene.lights.len());
        let light = &scene.lights[li];
        let y = light.sample(Vec2::new(rng.f32(), rng.f32()));
        let (x, tri) = start_point(scene, octree, &mut rng);
        if (x - y).dot(light.normal) > 0.0 {
            out.push(ShadowRay::new(x, y, LightId(li as u32), tri, octree.locate(x)));
        }
    }
    out
}

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
            panic!("{}: {mode} says {} for {what} {i} {:?}, brute force says {}", scene.name, got[i], sample[i], reference[i]);
        }
    }
    if big {
        let reference = answers(scene, built, Mode::Bvh, rays);
        for &mode in modes.iter().filter(|&&m| m != Mode::Brute && m != Mode::Bvh) {
            assert!(answers(scene, built, mode, rays) == reference, "{}: {mode} disagrees with bvh on {what}", scene.name);
        }
    }
}

fn check_scene(scene: &Scene) {
    let built = Built::new(scene, PlieParams::thesis());
    let rays = shadow_rays(scene, &built.octree, SEGMENTS, 1234);
    compare(scene, &built, "shadow ray", &Mode::ALL, &rays);
    let free: Vec<Mode> = Mode::ALL.into_iter().filter(|m| !m.needs_plie()).collect();
    let segs = free_segments(scene, &built.octree, SEGMENTS / 4, 99);
    compare(scene, &built, "free segment", &free, &segs);
}

#[test]
fn every_mode_matches_brute_force_on_builtin_scenes() {
    for scene in support::builtins() {
        check_scene(&scene);
    }
}

#[test]
fn every_mode_matches_brute_force_on_shared_scenes() {
    for scene in support::load_shared() {
        check_scene(&scene);
    }
}
