//! Shared fixtures for the integration tests: a deterministic generator, the scenes to test on, and
//! the real scenes in `../shared/scenes/` (skipped with a notice where that folder is absent).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use glam::Vec3;
use plie::Scene;

/// splitmix64: deterministic, seedable, no dependency.
pub struct TestRng(pub u64);

impl TestRng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    /// A uniform point in the box.
    pub fn point_in(&mut self, min: Vec3, max: Vec3) -> Vec3 {
        min + (max - min) * Vec3::new(self.f32(), self.f32(), self.f32())
    }
}

/// The folder of real scenes shared beside the project, if present.
pub fn shared_scenes() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("notice: {} not found; skipping the tests on real scenes", dir.display());
        None
    }
}

/// The lit OBJ scenes of `../shared/scenes/` used by the test suite (conference-lit is for benchmarks).
pub const SHARED_OBJS: [&str; 5] =
    ["CornellBox-Original.obj", "cornell-dragon.obj", "boat-lit.obj", "cornell-bunny.obj", "cornell-dragon-100k.obj"];

/// The camera ../shared/scenes/README.md gives for a file, if any.
pub fn readme_camera(file: &str) -> Option<plie::Camera> {
    let v = Vec3::new;
    let c = |eye, target, fov| plie::Camera::new(eye, target, Vec3::Y, fov).unwrap();
    match file {
        "cornell-dragon.obj" | "cornell-dragon-100k.obj" | "cornell-bunny.obj" => {
            Some(c(v(278.0, 273.0, -800.0), v(278.0, 273.0, 0.0), 39.3))
        }
        "boat-lit.obj" => Some(c(v(9.0, 4.0, -9.0), v(0.0, 1.0, 0.0), 40.0)),
        "conference-lit.obj" => Some(c(v(1550.0, 380.0, 550.0), v(400.0, 150.0, -150.0), 60.0)),
        _ => None,
    }
}

/// Loads the shared scenes that exist (empty where the folder is absent), with the README's cameras.
pub fn load_shared() -> Vec<Scene> {
    let Some(dir) = shared_scenes() else { return Vec::new() };
    SHARED_OBJS
        .iter()
        .map(|f| {
            let mut s = plie::io::load_scene(&dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            s.camera = readme_camera(f).or(s.camera);
            s
        })
        .collect()
}

/// Every built-in scene.
pub fn builtins() -> Vec<Scene> {
    plie::scene::builtin::NAMES.iter().map(|n| plie::scene::builtin::load(n).unwrap()).collect()
}

/// Every structure a visibility mode may need, built for one scene.
pub struct Built {
    pub bvh: plie::visibility::bvh::Bvh,
    pub octree: plie::octree::Octree,
    pub plie: plie::lie::Plie,
}

impl Built {
    pub fn new(scene: &Scene, params: plie::lie::PlieParams) -> Built {
        let params = plie::lie::PlieParams { grids: true, ..params };
        let bvh = plie::visibility::bvh::Bvh::build(scene);
        let octree = plie::octree::Octree::build(scene, params.octree());
        let (plie, _) = plie::construct::build(scene, &octree, params, &plie::render::NoProgress);
        Built { bvh, octree, plie }
    }

    pub fn vis<'a>(
        &'a self,
        scene: &'a Scene,
        mode: plie::visibility::Mode,
    ) -> Box<dyn plie::visibility::Visibility + 'a> {
        plie::visibility::for_mode(mode, scene, &self.bvh, &self.octree, Some(&self.plie)).unwrap()
    }
}
