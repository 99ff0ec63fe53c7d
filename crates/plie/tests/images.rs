//! End-to-end exactness: images rendered with the same seed are bit-identical across visibility modes
//! and across thread counts (SPEC §5).

mod support;

use glam::Vec3;
use plie::internals::lie::PlieParams;
use plie::internals::render::RenderSettings;
use plie::visibility::Mode;
use plie::Scene;
use support::Built;

/// Every mode's image, rendered in a pool of `threads` threads (structures built in that pool too).
fn images(scene: &Scene, threads: usize, settings: &RenderSettings) -> Vec<(Mode, Vec<Vec3>)> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let built = Built::new(scene, PlieParams::default());
        let camera = scene.camera_or_default();
        Mode::EXACT
            .into_iter()
            .map(|mode| {
                let vis = built.vis(scene, mode);
                (mode, support::render(scene, &camera, settings, &built.bvh, Some(built.octree()), vis.as_ref()))
            })
            .collect()
    })
}

fn bits(p: &[Vec3]) -> Vec<[u32; 3]> {
    p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
}

fn check(scene: &Scene, settings: &RenderSettings) {
    let two = images(scene, 2, settings);
    let reference = bits(&two[0].1);
    assert_eq!(two[0].0, Mode::Brute);
    let lit = reference.iter().filter(|p| p.iter().any(|&c| f32::from_bits(c) > 0.0)).count();
    assert!(lit > reference.len() / 4, "{}: the image is mostly black ({lit} lit pixels)", scene.name);
    for (threads, set) in [(2, two), (1, images(scene, 1, settings))] {
        for (mode, px) in set {
            let diff = bits(&px).iter().zip(&reference).filter(|(a, b)| a != b).count();
            assert_eq!(diff, 0, "{}: {mode} with {threads} threads differs from brute in {diff} pixels", scene.name);
        }
    }
}

#[test]
fn images_are_bit_identical_across_modes_and_threads_builtin() {
    let settings = RenderSettings { width: 40, height: 40, eye_rays: 1, shadow_rays: 4, seed: 7 };
    for scene in support::builtins() {
        check(&scene, &settings);
    }
}

#[test]
#[ignore = "exhaustive tier (real scenes): cargo test --workspace -- --ignored"]
fn images_are_bit_identical_across_modes_and_threads_shared() {
    let settings = RenderSettings { width: 32, height: 32, eye_rays: 1, shadow_rays: 4, seed: 9 };
    for scene in support::load_shared() {
        check(&scene, &settings);
    }
}
