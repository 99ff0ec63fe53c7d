//! Measures native Embree's ways of answering a light's samples from one point (packets of 1, 4, 8,
//! 16, coherent streams; filter or masks for the ray's own triangles) on one scene: the shading pass
//! of a 254x254 image, 1 eye ray, seed 1, in a one-thread pool, each variant `RUNS` times interleaved.
//! Prints per variant the least process CPU time (from /proc/self/stat, 10 ms ticks; less disturbed
//! by other processes than wall time on a shared machine) and the least wall time, and the occluded
//! count. `none` and `bvh` are measured alongside for scale. Last, how many of the default native
//! Embree's answers differ from `bvh`'s (exact) over the same shadow rays ([`plie::internals::compare`]).
//!
//! ```text
//! cargo run --release -p plie --features embree --example embree_packets -- SCENE [SHADOW_RAYS] [RUNS]
//! ```
//! SCENE is a built-in name or a scene file; the three scenes of ../shared/scenes/README.md with a
//! camera there get that camera.

use std::time::Instant;

use glam::Vec3;
use plie::internals::render::shade::shade;
use plie::internals::render::{HitBuffer, NoProgress};
use plie::visibility::bvh::Bvh;
use plie::visibility::embree::native::{Exclusion, NativeEmbree, Packet};
use plie::visibility::{BvhVisibility, NoVisibility, Visibility};
use plie::{Camera, Scene};

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')').expect("stat format") + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap();
    ticks / 100.0
}

fn load(arg: &str) -> Scene {
    let mut s = if arg.ends_with(".obj") || arg.ends_with(".gltf") || arg.ends_with(".glb") {
        plie::io::load_scene(std::path::Path::new(arg)).expect("scene file")
    } else {
        plie::scene::builtin::load(arg).expect("built-in scene")
    };
    let c = |eye: Vec3, target: Vec3, fov| Some(Camera::new(eye, target, Vec3::Y, fov).unwrap());
    let file = std::path::Path::new(arg).file_name().and_then(|f| f.to_str()).unwrap_or("");
    let camera = match file {
        "cornell-dragon.obj" | "cornell-dragon-100k.obj" | "cornell-bunny.obj" => {
            c(Vec3::new(278.0, 273.0, -800.0), Vec3::new(278.0, 273.0, 0.0), 39.3)
        }
        "conference-lit.obj" => c(Vec3::new(1550.0, 380.0, 550.0), Vec3::new(400.0, 150.0, -150.0), 60.0),
        _ => None,
    };
    s.camera = camera.or(s.camera);
    s
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(scene_arg) = args.first() else {
        eprintln!("usage: embree_packets SCENE [SHADOW_RAYS] [RUNS]");
        std::process::exit(2);
    };
    let rays: u32 = args.get(1).map_or(64, |a| a.parse().expect("SHADOW_RAYS"));
    let runs: usize = args.get(2).map_or(5, |a| a.parse().expect("RUNS"));
    let scene = load(scene_arg);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        let bvh = Bvh::build(&scene);
        let hits = HitBuffer::build(&scene, &scene.camera_or_default(), (254, 254, 1), &bvh, None);
        let mut variants: Vec<(String, Box<dyn Visibility>)> =
            vec![("none".into(), Box::new(NoVisibility)), ("bvh".into(), Box::new(BvhVisibility::new(&scene, &bvh)))];
        for exclusion in [Exclusion::Filter, Exclusion::Masks] {
            for packet in [Packet::One, Packet::Four, Packet::Eight, Packet::Sixteen, Packet::Stream] {
                let v = NativeEmbree::with(&scene, packet, exclusion).expect("Embree device");
                variants.push((format!("{packet:?}/{exclusion:?}"), Box::new(v)));
            }
        }
        let mut best = vec![(f64::INFINITY, f64::INFINITY, 0u64); variants.len()];
        for _ in 0..runs {
            for ((_, vis), b) in variants.iter().zip(best.iter_mut()) {
                let (c, t) = (cpu_seconds(), Instant::now());
                let (_, stats) = shade(&scene, &hits, vis.as_ref(), rays, 1, &NoProgress);
                let wall = t.elapsed().as_secs_f64();
                *b = (b.0.min(cpu_seconds() - c), b.1.min(wall), stats.occluded);
            }
        }
        println!(
            "{} ({} triangles), {rays} shadow rays, least of {runs} runs, 1 thread",
            scene.name,
            scene.triangle_count()
        );
        let native = NativeEmbree::new(&scene).expect("Embree device");
        let diff = plie::internals::compare::answer_diff(&scene, &hits, &native, variants[1].1.as_ref(), rays, 1);
        println!(
            "embree (default) against bvh: {} of {} answers differ ({:.2e})",
            diff.differing,
            diff.rays,
            diff.fraction()
        );
        println!("{:<18} {:>8} {:>8} {:>10}", "variant", "cpu s", "wall s", "occluded");
        for ((name, _), (cpu, wall, occ)) in variants.iter().zip(&best) {
            println!("{name:<18} {cpu:>8.2} {wall:>8.3} {occ:>10}");
        }
    });
}
