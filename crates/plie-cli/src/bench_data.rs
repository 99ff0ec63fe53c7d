//! What `plie bench` measures and what it found: the plan (scenes, image settings, runs) and the
//! results, serialised as results.json; read by the report, the chart and the soft-shadow table.

use plie::visibility::Mode;
use serde::Serialize;

/// What is measured: scenes, image settings, runs.
pub struct Plan {
    pub scenes: Vec<String>,
    /// Image sizes (width = height), 1 eye ray per pixel.
    pub sizes: Vec<u32>,
    /// Shadow rays per light.
    pub shadow_rays: Vec<u32>,
    pub runs: usize,
    pub modes: Vec<Mode>,
    /// The modes also measured on the refined P-LIE (those that use a P-LIE).
    pub refined_modes: Vec<Mode>,
}

impl Plan {
    /// The setting of the break-even figures: the largest image with the fewest shadow rays (254/4).
    pub fn break_even_setting(&self) -> (u32, u32) {
        (*self.sizes.iter().max().expect("a size"), *self.shadow_rays.iter().min().expect("a count"))
    }

    /// The setting of the single-threaded throughput: the smallest image, fewest shadow rays.
    pub fn throughput_setting(&self) -> (u32, u32) {
        (*self.sizes.iter().min().expect("a size"), *self.shadow_rays.iter().min().expect("a count"))
    }

    /// Progress steps per scene.
    pub fn steps_per_scene(&self, threads: usize) -> u64 {
        let m = self.modes.len() as u64;
        let settings = (self.sizes.len() * self.shadow_rays.len()) as u64;
        let single = if threads > 1 { m } else { 0 };
        1 + m * settings + single + self.refined_modes.len() as u64 * settings
    }
}

/// Everything measured; serialised as results.json.
#[derive(Serialize)]
pub struct Results {
    pub command: String,
    pub date: String,
    pub cores: usize,
    pub cpu: Option<String>,
    pub threads: usize,
    pub runs: usize,
    pub quick: bool,
    pub break_even_setting: (u32, u32),
    pub throughput_setting: (u32, u32),
    pub scenes: Vec<SceneResult>,
}

/// The figures of one scene.
#[derive(Serialize)]
pub struct SceneResult {
    pub name: String,
    pub triangles: usize,
    pub lights: usize,
    pub bvh_seconds: f64,
    pub octree_seconds: f64,
    pub builds: Vec<BuildResult>,
    /// All-threads rows for every setting, then 1-thread rows at the throughput setting.
    pub shading: Vec<Shading>,
    pub break_even: Vec<BreakEven>,
}

/// One P-LIE construction (median seconds of the construction alone, octree excluded).
#[derive(Serialize)]
pub struct BuildResult {
    /// "thesis" (`PlieParams::thesis()`), "grids" (`PlieParams::default()`), "blockers-only" (the
    /// thesis' parameters without regions), "no-propagation" (the thesis' without propagation),
    /// "refined" (the thesis' refined by umbra, at most 2 splits: test 2) or "refined-grids" (the
    /// same with face grids).
    pub config: &'static str,
    pub seconds: f64,
    pub leaves: usize,
    pub records: usize,
    pub records_removed_umbra: usize,
    pub records_removed_propagation: usize,
    pub blockers_mean: f64,
    pub blockers_max: u32,
}

/// The shading pass of one mode at one setting (median seconds).
#[derive(Serialize)]
pub struct Shading {
    pub mode: Mode,
    /// On the refined P-LIE (and its refined octree): the thesis' "+u" columns.
    pub refined: bool,
    pub size: u32,
    pub shadow_rays: u32,
    pub threads: usize,
    pub seconds: f64,
    pub rays: u64,
    pub triangle_tests_per_ray: f64,
    /// Of `triangle_tests_per_ray`, the tests of P-LIE blockers (P-LIE modes; 0 in the others).
    pub blocker_tests_per_ray: f64,
    /// Of `triangle_tests_per_ray`, the tests of the ray's own leaf (P-LIE modes; 0 in the others).
    pub own_leaf_tests_per_ray: f64,
    pub mrays_per_second: f64,
    pub mrays_per_second_per_core: f64,
}

/// Images after which `mode` (build + shading) beats `against` (build + shading); None: never.
#[derive(Serialize)]
pub struct BreakEven {
    pub mode: Mode,
    /// `mode` on the refined P-LIE, its build cost the refined construction.
    pub refined: bool,
    pub against: Mode,
    pub images: Option<u64>,
}

pub fn median(xs: &mut [f64]) -> f64 {
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

/// Median shading seconds of `mode` at (size, rays) with `threads` threads, on the unrefined P-LIE.
pub fn seconds(sc: &SceneResult, mode: Mode, size: u32, rays: u32, threads: usize) -> Option<f64> {
    seconds_of(sc, mode, false, size, rays, threads)
}

/// Median shading seconds of `mode` on the refined (`+u`) or unrefined P-LIE.
pub fn seconds_of(sc: &SceneResult, mode: Mode, refined: bool, size: u32, rays: u32, threads: usize) -> Option<f64> {
    let row = sc.shading.iter().find(|x| {
        x.mode == mode && x.refined == refined && x.size == size && x.shadow_rays == rays && x.threads == threads
    });
    row.map(|x| x.seconds)
}
