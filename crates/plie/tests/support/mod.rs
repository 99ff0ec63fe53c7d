//! Shared fixtures for the integration tests: a deterministic generator, the scenes to test on, and
//! the real scenes in `../shared/scenes/`. Tests on the real scenes are in the exhaustive tier
//! (`#[ignore]`d: `cargo test --workspace -- --ignored` runs them) or, when fast, compiled as ignored
//! where the folder is absent (`build.rs` sets `plie_no_shared_scenes`); either way the summary
//! counts them. Run where the folder is absent anyway, they print a notice and return.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use plie::octree::{LeafId, Octree};
use plie::visibility::ShadowRay;
use plie::{LightId, Scene, TriId};

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
        eprintln!("notice: {} not found; skipping the test on real scenes", dir.display());
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

/// Every structure a visibility mode may need, built for one scene: its P-LIE environment (with
/// face grids) and the scene BVH.
pub struct Built {
    pub bvh: plie::visibility::bvh::Bvh,
    pub env: plie::Environment,
}

impl Built {
    /// Built with `params` plus face grids, refining the octree if `params.refine` asks.
    pub fn refined(scene: &Scene, params: plie::internals::lie::PlieParams) -> Built {
        Built::new(scene, params)
    }

    pub fn new(scene: &Scene, params: plie::internals::lie::PlieParams) -> Built {
        let params = plie::internals::lie::PlieParams { grids: plie::internals::lie::Grids::Build, ..params };
        let bvh = plie::visibility::bvh::Bvh::build(scene);
        let (env, _) = plie::Environment::build(scene, &params).expect("valid parameters");
        Built { bvh, env }
    }

    /// The octree (refined if the parameters asked for refinement).
    pub fn octree(&self) -> &Octree {
        self.env.octree()
    }

    /// The P-LIE.
    pub fn plie(&self) -> &plie::internals::lie::Plie {
        self.env.plie()
    }

    pub fn vis<'a>(
        &'a self,
        scene: &'a Scene,
        mode: plie::visibility::Mode,
    ) -> Box<dyn plie::visibility::Visibility + 'a> {
        self.env.visibility(mode, scene).unwrap()
    }
}

/// Brute force and every other exact mode over one built scene, to compare their answers.
pub struct ExactModes<'a> {
    brute: Box<dyn plie::visibility::Visibility + 'a>,
    modes: Vec<(plie::visibility::Mode, Box<dyn plie::visibility::Visibility + 'a>)>,
    out: Vec<bool>,
}

impl<'a> ExactModes<'a> {
    pub fn new(built: &'a Built, scene: &'a Scene) -> ExactModes<'a> {
        use plie::visibility::Mode;
        let modes = Mode::EXACT.into_iter().filter(|&m| m != Mode::Brute).map(|m| (m, built.vis(scene, m))).collect();
        ExactModes { brute: built.vis(scene, Mode::Brute), modes, out: Vec::new() }
    }

    /// Asserts that every exact mode answers each sample of `q`, ray by ray and per light, as brute
    /// force does (`what` names the case); returns how many brute force found occluded.
    pub fn check(
        &mut self,
        what: &str,
        q: &plie::visibility::LightRays,
        ctx: &mut plie::visibility::QueryCtx,
    ) -> usize {
        let n = q.targets.len();
        let reference: Vec<bool> = (0..n).map(|k| self.brute.occluded(&q.ray(k), ctx)).collect();
        for (mode, vis) in &self.modes {
            self.out.clear();
            self.out.resize(n, false);
            vis.occluded_light(q, &mut self.out, ctx);
            for (k, (&brute, &per_light)) in reference.iter().zip(&self.out).enumerate() {
                let ray: ShadowRay = q.ray(k);
                let per_ray = vis.occluded(&ray, ctx);
                assert!(
                    per_ray == brute && per_light == brute,
                    "{what}: {mode}: per-ray {per_ray}, per-light {per_light}, brute force {brute} for {ray:?}",
                );
            }
        }
        reference.iter().filter(|&&b| b).count()
    }
}

/// The construction (stages 1-7) on a given octree, without limits: what the tests that compare
/// builds on one octree need (users call [`plie::Environment::build`]).
pub fn construct(
    scene: &Scene,
    octree: &Octree,
    params: plie::internals::lie::PlieParams,
) -> plie::internals::construct::Built {
    plie::internals::construct::build_bounded(scene, octree.clone(), params, Default::default(), &plie::NoProgress)
        .expect("not cancelled")
}

/// The pixels `vis` renders: direct light, `settings`, `camera`, hits from `bvh` (leaves from
/// `octree` if given).
pub fn render(
    scene: &Scene,
    camera: &plie::Camera,
    settings: &plie::RenderSettings,
    bvh: &plie::visibility::bvh::Bvh,
    octree: Option<&Octree>,
    vis: &dyn plie::Visibility,
) -> Vec<Vec3> {
    let renderer = plie::Renderer::new().settings(*settings).camera(*camera);
    renderer.validate().expect("valid settings");
    renderer.render_with(scene, bvh, octree, vis).expect("rendered").pixels
}

/// A shading-like start point: on a triangle, on a leaf's face/edge/corner, or anywhere.
pub fn start_point(scene: &Scene, octree: &Octree, rng: &mut TestRng) -> (Vec3, TriId) {
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
