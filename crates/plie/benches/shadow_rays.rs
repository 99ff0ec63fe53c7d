//! Benchmark: shadow-ray throughput of every visibility mode on built-in scenes, one thread, the same
//! fixed set of shadow rays (points on triangles to light samples): the median of 15 timed passes
//! over the rays, after one warm-up pass. A plain timing loop rather than criterion, so that
//! `cargo test` does not compile criterion and its dependencies; `plie bench` is the full protocol.
//!
//! Run with `cargo bench -p plie --bench shadow_rays`.

use std::time::Instant;

use glam::Vec2;
use plie::internals::lie::PlieParams;
use plie::octree::Octree;
use plie::visibility::{Mode, QueryCtx, ShadowRay};
use plie::{Environment, LightId, Scene, TriId};

/// 4096 shadow rays from points on random triangles to light samples, `x` in front of the light.
fn rays(scene: &Scene, octree: &Octree) -> Vec<ShadowRay> {
    let mut state = 0x1234_5678_u64;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let mut out = Vec::new();
    while out.len() < 4096 {
        let t = ((next() * scene.triangles.len() as f32) as usize).min(scene.triangles.len() - 1);
        let li = ((next() * scene.lights.len() as f32) as usize).min(scene.lights.len() - 1);
        let (u, v) = (next() * 0.5, next() * 0.5);
        let x = scene.triangles[t].point(u, v);
        let y = scene.lights[li].sample(Vec2::new(next(), next()));
        if (x - y).dot(scene.lights[li].normal) > 0.0 && scene.tri_light[t].is_none() {
            out.push(ShadowRay::new(x, y, LightId(li as u32), TriId(t as u32), octree.locate(x)));
        }
    }
    out
}

/// Passes timed per mode; the median is reported.
const PASSES: usize = 15;

fn main() {
    // `cargo test --benches` runs benchmarks with `--bench` absent: do one quick pass only.
    let quick = !std::env::args().any(|a| a == "--bench");
    println!("{:<16} {:<9} {:>12} {:>12}", "scene", "mode", "ns/ray", "Mrays/s");
    for name in ["cornell-cube-3", "huis-a", "dragon", "boot"] {
        let scene = plie::scene::builtin::load(name).expect("built-in scene");
        let params = PlieParams::thesis();
        let (env, _) = Environment::build(&scene, &params).expect("valid parameters");
        let rays = rays(&scene, env.octree());
        for mode in Mode::EXACT.into_iter().filter(|m| *m != Mode::Brute) {
            let vis = env.visibility(mode, &scene).expect("mode");
            let mut ctx = QueryCtx::new(scene.triangle_count());
            let mut pass = || {
                let t = Instant::now();
                let blocked = rays.iter().filter(|r| vis.occluded(r, &mut ctx)).count();
                std::hint::black_box(blocked);
                t.elapsed().as_secs_f64()
            };
            pass();
            let mut times: Vec<f64> = (0..if quick { 1 } else { PASSES }).map(|_| pass()).collect();
            times.sort_by(f64::total_cmp);
            let per_ray = times[times.len() / 2] / rays.len() as f64;
            println!("{name:<16} {:<9} {:>12.1} {:>12.2}", mode.name(), per_ray * 1e9, 1e-6 / per_ray);
        }
    }
}
