//! End-to-end exactness: images rendered with the same seed are bit-identical across visibility modes
//! and across thread counts (SPEC §5).

mod support;

use glam::Vec3;
use plie::lie::PlieParams;
use plie::render::{render, NoProgress, RenderSettings};
use plie::visibility::Mode;
use plie::Scene;
use support::Built;

fn image(scene: &Scene, mode: Mode, threads: usize, settings: &RenderSettings) -> Vec<Vec3> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let built = Built::new(scene, PlieParams::thesis());
        let vis = built.vis(scene, mode);
        let camera = scene.camera_or_default();
        render(scene, &camera, settings, &built.bvh, Some(&built.octree), vis.as_ref(), &NoProgress).unwrap().pixels
    })
}

fn bits(p: &[Vec3]) -> Vec<[u32; 3]> {
    p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
}

fn check(scene: &Scene, settings: &RenderSettings) {
    let reference = bits(&image(scene, Mode::Brute, 2, settings));
    let lit = reference.iter().filter(|p| p.iter().any(|&c| f32::from_bits(c) > 0.0)).count();
    assert!(lit > reference.len() / 4, "{}: the image is mostly black ({lit} lit pixels)", scene.name);
    for mode in Mode::ALL {
        for threads in [1, 2] {
            if mode == Mode::Brute && threads == 2 {
                continue;
            }
            let got = bits(&image(scene, mode, threads, settings));
            let diff = got.iter().zip(&reference).filter(|(a, b)| a != b).count();
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
fn images_are_bit_identical_across_modes_and_threads_shared() {
    let settings = RenderSettings { width: 32, height: 32, eye_rays: 1, shadow_rays: 4, seed: 9 };
    for scene in support::load_shared() {
        check(&scene, &settings);
    }
}
