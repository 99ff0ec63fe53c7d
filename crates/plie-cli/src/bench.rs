//! `plie bench`: the thesis' measurement protocol (SPEC §7, Chapter 8) run in-process. For each scene:
//! P-LIE construction with the thesis' test-1 parameters (umbra/penumbra included), with face grids,
//! without regions (Table 8.4), without propagation, and refined by umbra with at most 2 splits (the
//! thesis' test 2, Table 8.3's second rows; with and without face grids); shading time of the hit
//! buffer (pass 2 alone) for every visibility mode but brute, and for the P-LIE modes on the refined
//! P-LIE (the "+u" columns of Tables A.1-A.3), at the thesis' image settings; shadow-ray throughput
//! with one thread and with all; and the break-even number of images. The files are written by
//! [`crate::bench_report`]. The options and scene names are checked before anything is measured, and
//! the `--out` folder is created only when the files are written ([`crate::out_dir`]): a run that
//! fails leaves no folder behind.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use plie::internals::render::shade::shade;
use plie::internals::render::{HitBuffer, NoProgress, Progress};
use plie::octree::Octree;
use plie::scene::builtin;
use plie::visibility::bvh::Bvh;
use plie::visibility::{self, Mode};
use plie::RefineParams;
use plie::{Camera, Environment, Scene, Shadows};
use plie::{Grids, PlieParams, Propagation, Regions};

use crate::bench_data::{median, BreakEven, BuildResult, Plan, Results, SceneResult, Shading};
use crate::bench_path::PathPlan;
use crate::out_dir::OutDir;
use crate::progress::Bar;
use crate::scene_arg::SceneArgs;

/// Options of `plie bench`.
#[derive(clap::Args)]
pub struct Args {
    /// A short run: 1 run, cornell-cube-1 and cornell-cube-3, 32x32 eye rays, 4 shadow rays per light.
    #[arg(long)]
    quick: bool,
    /// Scenes to measure: built-in names or scene files (default: the ten built-in scenes and the
    /// stress scene `balusters`).
    #[arg(long, value_name = "A,B,...", value_delimiter = ',')]
    scenes: Vec<String>,
    /// Directory for report.md, results.csv, results.json and shading.svg (created if missing, when
    /// they are written; a run that fails leaves no directory it created).
    #[arg(long, default_value = "bench-out", value_name = "DIR")]
    out: PathBuf,
    /// Runs per measurement, 1 to 1000; the median is reported (default 5, 1 with --quick and with
    /// --path).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1000))]
    runs: Option<u32>,
    #[command(flatten)]
    threads: crate::threads_arg::ThreadsArg,
    /// Directory of the thesis' figures (construction.tsv, shading-times.tsv).
    #[arg(long, default_value = "../shared/thesis", value_name = "DIR")]
    thesis: PathBuf,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Instead of the thesis' protocol: soft shadows at 4, 16 and 64 shadow rays per light, every
    /// mode against `none` (no shadow test) and `embree`, on the ten built-in scenes and the shared
    /// cornell-bunny, cornell-dragon-100k and conference-lit (writes soft-shadows.md/.json; runs
    /// default to 3).
    #[arg(long, conflicts_with = "path")]
    soft_shadows: bool,
    /// With --soft-shadows: the folder of the shared scenes.
    #[arg(long, default_value = "../shared/scenes", value_name = "DIR", requires = "soft_shadows")]
    shared: PathBuf,
    /// Measure the path-tracing table instead (path.md, path.json): max depth 3 and 5, 16 paths per
    /// pixel, on the ten built-in scenes and the conference room (default; --quick: cornell-cube-1 and
    /// cornell-cube-3, 32x32).
    #[arg(long)]
    path: bool,
    /// Path table: image width and height, 1 to 4096 (default 64; 32 with --quick).
    #[arg(long, value_name = "W", requires = "path", value_parser = clap::value_parser!(u32).range(1..=4096))]
    path_size: Option<u32>,
    /// Path table: the visibility modes (default bvh,grid).
    #[arg(long, value_name = "A,B,...", value_delimiter = ',', requires = "path")]
    path_modes: Vec<Mode>,
}

/// The plan `a` asks for.
fn plan(a: &Args) -> Result<Plan> {
    let runs = a.runs.map_or(if a.quick { 1 } else { 5 }, |r| r as usize);
    anyhow::ensure!(runs >= 1, "--runs must be at least 1");
    let scenes = match (a.scenes.is_empty(), a.quick) {
        (false, _) => a.scenes.clone(),
        (true, true) => vec!["cornell-cube-1".into(), "cornell-cube-3".into()],
        (true, false) => builtin::NAMES.iter().chain(&builtin::STRESS).map(|s| s.to_string()).collect(),
    };
    let (sizes, shadow_rays) = if a.quick { (vec![32], vec![4]) } else { (vec![126, 254], vec![4, 9]) };
    let modes: Vec<Mode> = Mode::EXACT.into_iter().filter(|m| *m != Mode::Brute).collect();
    let refined_modes = modes.iter().copied().filter(|m| m.needs_plie()).collect();
    Ok(Plan { scenes, sizes, shadow_rays, runs, modes, refined_modes })
}

/// What `plie bench` measures.
enum Table {
    /// The thesis' protocol.
    Thesis(Plan),
    /// `--soft-shadows` ([`crate::bench_soft`]).
    SoftShadows { scenes: Vec<String>, runs: usize },
    /// `--path` ([`crate::bench_path`]).
    Path(PathPlan),
}

impl Table {
    fn scenes(&self) -> &[String] {
        match self {
            Table::Thesis(plan) => &plan.scenes,
            Table::SoftShadows { scenes, .. } => scenes,
            Table::Path(p) => &p.scenes,
        }
    }
}

/// The table `a` asks for, its options and scenes checked: whatever they get wrong is found before
/// anything is measured or written.
fn table(a: &Args) -> Result<Table> {
    let table = if a.soft_shadows {
        let scenes = if a.scenes.is_empty() { crate::bench_soft::default_scenes(&a.shared) } else { a.scenes.clone() };
        let runs = a.runs.map_or(if a.quick { 1 } else { 3 }, |r| r as usize);
        Table::SoftShadows { scenes, runs }
    } else if a.path {
        Table::Path(path_plan(a, plan(a)?))
    } else {
        Table::Thesis(plan(a)?)
    };
    for name in table.scenes() {
        let scene = SceneArgs { scene: name.clone(), allow_outside_paths: false };
        scene.check_exists().with_context(|| format!("scene {name}"))?;
    }
    Ok(table)
}

pub fn run(a: &Args) -> Result<()> {
    a.threads.install()?;
    let table = table(a)?;
    // Checked now, created when the first file is written, removed again if this run fails.
    let mut out = OutDir::new(&a.out)?;
    match table {
        Table::SoftShadows { scenes, runs } => crate::bench_soft::run(&scenes, &mut out, runs, a.quiet)?,
        Table::Path(p) => {
            crate::bench_path::run(&p, &mut out, &Bar::new(a.quiet))?;
            if !a.quiet {
                eprintln!("wrote {}/{{path.md, path.json}}", a.out.display());
            }
        }
        Table::Thesis(plan) => run_thesis(a, &plan, &mut out)?,
    }
    out.keep();
    Ok(())
}

/// The thesis' protocol on `plan`'s scenes, written by [`crate::bench_report`].
fn run_thesis(a: &Args, plan: &Plan, out: &mut OutDir) -> Result<()> {
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let bar = Bar::new(a.quiet);
    bar.start("bench", plan.steps_per_scene(rayon::current_num_threads()) * plan.scenes.len() as u64);
    let mut scenes = Vec::new();
    for name in &plan.scenes {
        scenes.push(bench_scene(name, plan, &one, &bar).with_context(|| format!("scene {name}"))?);
    }
    bar.finish();
    let results = Results {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        date: crate::bench_report::utc_now(),
        cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        cpu: crate::bench_report::cpu_model(),
        threads: rayon::current_num_threads(),
        runs: plan.runs,
        quick: a.quick,
        break_even_setting: plan.break_even_setting(),
        throughput_setting: plan.throughput_setting(),
        scenes,
    };
    crate::bench_report::write_all(out, &a.thesis, plan, &results)?;
    if !a.quiet {
        eprintln!("wrote {}/{{report.md, results.csv, results.json, shading.svg}}", a.out.display());
    }
    Ok(())
}

/// The path table `a` asks for (`--path`), on `plan`'s scenes and the conference room.
fn path_plan(a: &Args, plan: Plan) -> PathPlan {
    let mut scenes = plan.scenes;
    let conference = std::path::Path::new("../shared/scenes/conference-lit.obj");
    if a.scenes.is_empty() && !a.quick {
        if conference.exists() {
            scenes.push(conference.display().to_string());
        } else if !a.quiet {
            eprintln!("notice: {} absent; the path table leaves out the conference room", conference.display());
        }
    }
    let modes = if a.path_modes.is_empty() { vec![Mode::Bvh, Mode::Grid] } else { a.path_modes.clone() };
    PathPlan {
        scenes,
        size: a.path_size.unwrap_or(if a.quick { 32 } else { 64 }),
        spp: 16,
        shadow_rays: 4,
        depths: vec![3, 5],
        modes,
        runs: a.runs.map_or(1, |r| r as usize),
    }
}

/// Loads a built-in scene or a scene file, with its camera (or a framing default).
fn load(name: &str) -> Result<(Scene, Camera)> {
    let args = SceneArgs { scene: name.to_string(), allow_outside_paths: false };
    let scene = args.load()?;
    let camera = scene.camera_or_default();
    Ok((scene, camera))
}

/// Runs `f` `runs` times; the last result and the median seconds.
fn timed<T>(runs: usize, mut f: impl FnMut() -> T) -> (T, f64) {
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        last = Some(f());
        times.push(t.elapsed().as_secs_f64());
    }
    (last.expect("at least one run"), median(&mut times))
}

/// Builds the environment `runs` times; `seconds` is the median construction time (the octree built
/// first is timed apart, as `octree_seconds`).
fn build_plie(
    scene: &Scene,
    params: PlieParams,
    config: &'static str,
    runs: usize,
) -> Result<(Environment, BuildResult)> {
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs.max(1) {
        let (env, stats) = Environment::build(scene, &params)?;
        times.push(stats.blockers.blockers_seconds);
        last = Some((env, stats));
    }
    let (env, s) = last.expect("at least one run");
    let r = BuildResult {
        config,
        seconds: median(&mut times),
        leaves: s.octree.leaves,
        records: s.blockers.records,
        records_removed_umbra: s.regions.records_removed_umbra,
        records_removed_propagation: s.propagation.records_removed,
        blockers_mean: s.blockers.blockers_mean,
        blockers_max: s.blockers.blockers_max,
    };
    Ok((env, r))
}

fn bench_scene(name: &str, plan: &Plan, one: &rayon::ThreadPool, bar: &Bar) -> Result<SceneResult> {
    let (scene, camera) = load(name)?;
    let (bvh, bvh_seconds) = timed(plan.runs, || Bvh::build(&scene));
    // The thesis' test-1 parameters with the default blocker cap (issue 15), as `plie build` uses.
    let thesis = PlieParams::thesis().bounded();
    thesis.octree().validate()?;
    let (octree, octree_seconds) =
        timed(plan.runs, || Octree::build(&scene, thesis.octree()).expect("valid octree parameters"));
    let (lie, b1) = build_plie(&scene, thesis, "thesis", plan.runs)?;
    let (grid, b2) = build_plie(&scene, PlieParams::default().bounded(), "grids", plan.runs)?;
    let no_regions = PlieParams { regions: Regions::Skip, ..thesis };
    let (_, b3) = build_plie(&scene, no_regions, "blockers-only", plan.runs)?;
    let no_propagation = PlieParams { propagation: Propagation::Off, ..thesis };
    let (_, b4) = build_plie(&scene, no_propagation, "no-propagation", plan.runs)?;
    let refined = PlieParams { refine: RefineParams::thesis_umbra(), ..thesis };
    let (r_lie, b5) = build_plie(&scene, refined, "refined", plan.runs)?;
    let (r_grid, b6) = build_plie(&scene, PlieParams { grids: Grids::Build, ..refined }, "refined-grids", plan.runs)?;
    let r_octree = r_lie.octree();
    bar.advance(1);
    let shadows = Shadows::with_octree_params(&scene, thesis.octree())?;
    let s = Structures { scene: &scene, shadows: &shadows, lie: &lie, grid: &grid };
    let r = Structures { scene: &scene, shadows: &shadows, lie: &r_lie, grid: &r_grid };
    let mut shading = Vec::new();
    let mut single = Vec::new();
    for &size in &plan.sizes {
        let hits = HitBuffer::build(&scene, &camera, (size, size, 1), &bvh, Some(&octree));
        for &mode in &plan.modes {
            let vis = s.visibility(mode)?;
            for &n in &plan.shadow_rays {
                shading.push(time_shading(&scene, &hits, vis.as_ref(), (mode, size, n), plan.runs));
                bar.advance(1);
                // One thread apart, unless all threads are one (the row above is that run).
                if (size, n) == plan.throughput_setting() && rayon::current_num_threads() > 1 {
                    single.push(one.install(|| time_shading(&scene, &hits, vis.as_ref(), (mode, size, n), plan.runs)));
                    bar.advance(1);
                }
            }
        }
        // The refined octree has other leaves: its own hit buffer (the same points and normals).
        let hits = HitBuffer::build(&scene, &camera, (size, size, 1), &bvh, Some(r_octree));
        for &mode in &plan.refined_modes {
            let vis = r.visibility(mode)?;
            for &n in &plan.shadow_rays {
                let mut row = time_shading(&scene, &hits, vis.as_ref(), (mode, size, n), plan.runs);
                row.refined = true;
                shading.push(row);
                bar.advance(1);
            }
        }
    }
    let builds = [(b1.seconds, b2.seconds), (b5.seconds, b6.seconds)];
    let break_even = break_even(plan, &shading, (octree_seconds, bvh_seconds), builds);
    shading.extend(single);
    Ok(SceneResult {
        name: scene.name.clone(),
        triangles: scene.triangle_count(),
        lights: scene.lights.len(),
        bvh_seconds,
        octree_seconds,
        builds: vec![b1, b2, b3, b4, b5, b6],
        shading,
        break_even,
    })
}

/// The structures of one scene, from which every mode's visibility is made.
struct Structures<'a> {
    scene: &'a Scene,
    /// The modes without a P-LIE.
    shadows: &'a Shadows<'a>,
    /// Built with the thesis' parameters (mode lie).
    lie: &'a Environment,
    /// Built with face grids (mode grid).
    grid: &'a Environment,
}

impl<'a> Structures<'a> {
    fn visibility(&self, mode: Mode) -> Result<Box<dyn visibility::Visibility + 'a>> {
        if !mode.needs_plie() {
            return Ok(self.shadows.visibility(mode)?);
        }
        let env = if mode == Mode::Grid { self.grid } else { self.lie };
        Ok(env.visibility(mode, self.scene)?)
    }
}

fn time_shading(
    scene: &Scene,
    hits: &HitBuffer,
    vis: &dyn visibility::Visibility,
    (mode, size, n): (Mode, u32, u32),
    runs: usize,
) -> Shading {
    let ((_, stats), seconds) = timed(runs, || shade(scene, hits, vis, n, 0, &NoProgress));
    let threads = rayon::current_num_threads();
    let mrays = stats.shadow_rays as f64 / seconds.max(1e-9) / 1e6;
    let per_ray = |n: u64| n as f64 / stats.shadow_rays.max(1) as f64;
    Shading {
        mode,
        refined: false,
        size,
        shadow_rays: n,
        threads,
        seconds,
        rays: stats.shadow_rays,
        triangle_tests_per_ray: per_ray(stats.triangle_tests),
        blocker_tests_per_ray: per_ray(stats.blocker_tests),
        own_leaf_tests_per_ray: per_ray(stats.own_leaf_tests),
        mrays_per_second: mrays,
        mrays_per_second_per_core: mrays / threads as f64,
    }
}

/// Break-even at the plan's break-even setting for lie and grid, unrefined and refined, against
/// octree and bvh. Costs: octree mode = octree build; bvh = BVH build; lie/grid = octree build +
/// P-LIE build (thesis / with grids; refined: the refined constructions).
fn break_even(
    plan: &Plan,
    shading: &[Shading],
    (octree_s, bvh_s): (f64, f64),
    builds: [(f64, f64); 2],
) -> Vec<BreakEven> {
    let (size, n) = plan.break_even_setting();
    let t = |m: Mode, refined: bool| {
        let row = shading.iter().find(|r| r.mode == m && r.refined == refined && r.size == size && r.shadow_rays == n);
        row.map(|r| r.seconds)
    };
    let mut out = Vec::new();
    for (refined, (lie_s, grid_s)) in [false, true].into_iter().zip(builds) {
        for (mode, build) in [(Mode::Lie, octree_s + lie_s), (Mode::Grid, octree_s + grid_s)] {
            for (against, other_build) in [(Mode::Octree, octree_s), (Mode::Bvh, bvh_s)] {
                let (Some(tm), Some(ta)) = (t(mode, refined), t(against, false)) else { continue };
                let images = images_to_break_even(build, tm, other_build, ta);
                out.push(BreakEven { mode, refined, against, images });
            }
        }
    }
    out
}

/// Smallest number of images `k` with `build + k * t <= other_build + k * other_t`; None if never.
pub fn images_to_break_even(build: f64, t: f64, other_build: f64, other_t: f64) -> Option<u64> {
    if build <= other_build && t <= other_t {
        return Some(0);
    }
    if t >= other_t {
        return None;
    }
    Some(((build - other_build) / (other_t - t)).ceil().max(0.0) as u64)
}
