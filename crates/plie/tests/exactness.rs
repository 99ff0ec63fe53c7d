//! SPEC §5 exactness: every visibility mode answers every shadow ray exactly as brute force, on every
//! built-in scene and on the real scenes in ../shared/scenes/. Segments: surface points to light
//! samples (real shadow rays), points on octree cell faces, edges and corners, axis-parallel segments,
//! and random segments through the scene.

mod support;

use glam::{Vec2, Vec3};
use plie::octree::{Octree, OctreeParams};
use plie::visibility::bvh::Bvh;
use plie::visibility::{for_mode, Mode, QueryCtx, ShadowRay};
use plie::{LightId, Scene, TriId};
use rayon::prelude::*;
use support::TestRng;

/// Scenes above this many triangles compare with brute force on a subsample only.
const BRUTE_LIMIT: usize = 10_000;
const SEGMENTS: usize = 100_000;

/// A reproducible mix of shadow rays for `scene`.
pub fn segments(scene: &Scene, octree: &Octree, n: usize, seed: u64) -> Vec<ShadowRay> {
    let mut rng = TestRng(seed);
    let b = scene.bounds;
    let grow = b.size() * 0.05;
    let (lo, hi) = (b.min - grow, b.max + grow);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let li = rng.below(scene.lights.len());
        let light = &scene.lights[li];
        let y = light.sample(Vec2::new(rng.f32(), rng.f32()));
        let kind = rng.below(5);
        let (x, tri) = match kind {
            // A point on a random triangle (a real shading point).
            0 | 1 => {
                let t = rng.below(scene.triangles.len());
                let (mut u, mut v) = (rng.f32(), rng.f32());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                (scene.triangles[t].point(u, v), TriId(t as u32))
            }
            // A point on a face, edge or corner of a random leaf.
            2 => {
                let leaf = plie::octree::LeafId(rng.below(octree.leaf_count()) as u32);
                let c = octree.leaf_bounds(leaf);
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
            // Any point in the scene's box.
            _ => (rng.point_in(lo, hi), TriId(u32::MAX)),
        };
        if kind == 4 && rng.below(2) == 0 {
            // Axis-parallel segment from x.
            let k = rng.below(3);
            let mut y2 = x;
            y2[k] = if rng.below(2) == 0 { lo[k] } else { hi[k] };
            if y2 != x {
                out.push(ShadowRay::new(x, y2, LightId(li as u32), tri, None));
            }
            continue;
        }
        if x != y {
            out.push(ShadowRay::new(x, y, LightId(li as u32), tri, octree.locate(x)));
        }
    }
    out
}

/// Answers of `mode` for every ray (in parallel, deterministic order).
fn answers(scene: &Scene, bvh: &Bvh, octree: &Octree, mode: Mode, rays: &[ShadowRay]) -> Vec<bool> {
    let vis = for_mode(mode, scene, bvh, octree);
    rays.par_chunks(1024)
        .map_init(
            || QueryCtx::new(scene.triangles.len()),
            |ctx, chunk| chunk.iter().map(|r| vis.occluded(r, ctx)).collect::<Vec<_>>(),
        )
        .flatten()
        .collect()
}

fn check_scene(scene: &Scene) {
    let bvh = Bvh::build(scene);
    let octree = Octree::build(scene, OctreeParams::default());
    let rays = segments(scene, &octree, SEGMENTS, 1234);
    let big = scene.triangle_count() > BRUTE_LIMIT;
    let sample = if big { &rays[..2_000] } else { &rays[..] };
    let reference = answers(scene, &bvh, &octree, Mode::Brute, sample);
    let blocked = reference.iter().filter(|&&b| b).count();
    assert!(blocked > 0 && blocked < reference.len(), "{}: the test rays must include both answers", scene.name);
    for mode in Mode::ALL.into_iter().filter(|&m| m != Mode::Brute) {
        let got = answers(scene, &bvh, &octree, mode, sample);
        if let Some(i) = (0..got.len()).find(|&i| got[i] != reference[i]) {
            panic!("{}: {mode} says {} for ray {i} {:?}, brute force says {}", scene.name, got[i], sample[i], reference[i]);
        }
    }
    if big {
        // The full count: every mode against the BVH.
        let reference = answers(scene, &bvh, &octree, Mode::Bvh, &rays);
        for mode in Mode::ALL.into_iter().filter(|&m| m != Mode::Brute && m != Mode::Bvh) {
            let got = answers(scene, &bvh, &octree, mode, &rays);
            assert!(got == reference, "{}: {mode} disagrees with bvh", scene.name);
        }
    }
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
