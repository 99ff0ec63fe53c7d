//! `plie bench --path`: the path-tracing table (global illumination, SPEC §8 point 6). Per scene, at
//! max depth 3 and 5 with 16 paths per pixel: per visibility mode, the whole render's time, the time in
//! shadow tests (summed over threads, timed per `occluded_light` call), shadow rays per second, and
//! the cost of locating path vertices in the octree (P-LIE modes). Mode `none` (no shadow test) is
//! always measured too: paths do not depend on the shadow answers, so it traces the same camera and
//! bounce rays, and a mode's total minus `none`'s is a second measure of its shadow-test time, free of
//! per-call timer overhead. Written to `path.md` and
//! `path.json` in the output directory. Native Embree joins as a column where the `embree` mode is
//! available and asked for (`--path-modes`).

use anyhow::{Context, Result};
use plie::visibility::Mode;
use plie::PlieParams;
use plie::{Camera, Environment, Integrator, Renderer, Shadows, Timing};
use plie::{Nee, PathSettings};
use plie::{Progress, RenderSettings};
use serde::Serialize;

use crate::out_dir::OutDir;
use crate::progress::Bar;
use crate::scene_arg::{CameraArgs, SceneArgs};

/// What the path table measures.
pub struct PathPlan {
    pub scenes: Vec<String>,
    pub size: u32,
    pub spp: u32,
    pub shadow_rays: u32,
    pub depths: Vec<i32>,
    pub modes: Vec<Mode>,
    pub runs: usize,
}

/// One render of the path table (median of the runs by total time).
#[derive(Serialize)]
pub struct PathRow {
    pub scene: String,
    pub triangles: usize,
    pub mode: Mode,
    pub max_depth: i32,
    pub total_seconds: f64,
    pub thread_seconds: f64,
    pub shadow_seconds: f64,
    pub shadow_share: f64,
    pub shadow_rays: u64,
    pub mrays_per_second: f64,
    pub bounce_rays: u64,
    pub locates: u64,
    pub locate_ns: f64,
    pub plie_build_seconds: Option<f64>,
}

/// The conference room's camera (../shared/scenes/README.md); other scenes use their own.
fn camera_for(name: &str) -> (Option<glam::Vec3>, Option<glam::Vec3>, Option<f32>) {
    if name.ends_with("conference-lit.obj") {
        (Some(glam::Vec3::new(1550.0, 380.0, 550.0)), Some(glam::Vec3::new(400.0, 150.0, -150.0)), Some(60.0))
    } else {
        (None, None, None)
    }
}

/// Runs the path table and writes `path.md` and `path.json` into `out`.
pub fn run(plan: &PathPlan, out: &mut OutDir, bar: &Bar) -> Result<()> {
    let mut modes = plan.modes.clone();
    if !modes.contains(&Mode::None) {
        modes.push(Mode::None);
    }
    bar.start("path bench", (plan.scenes.len() * plan.depths.len() * modes.len()) as u64);
    let mut rows = Vec::new();
    for name in &plan.scenes {
        let (eye, target, fov) = camera_for(name);
        let args = SceneArgs { scene: name.clone(), allow_outside_paths: false };
        let scene = args.load().with_context(|| format!("scene {name}"))?;
        let camera: Camera = CameraArgs { eye, target, up: None, fov }.camera(&scene)?;
        let params = PlieParams::default();
        let shadows = Shadows::with_octree_params(&scene, params.octree())?;
        let t = std::time::Instant::now();
        let env = modes.iter().any(|m| m.needs_plie()).then(|| Environment::build(&scene, &params)).transpose()?;
        let build_seconds = env.as_ref().map(|_| t.elapsed().as_secs_f64());
        let oc = env.as_ref().map_or_else(|| shadows.octree(), |(e, _)| e.octree());
        let bvh = shadows.bvh();
        for &depth in &plan.depths {
            for &mode in &modes {
                let vis = match &env {
                    Some((e, _)) if mode.needs_plie() => e.visibility(mode, &scene)?,
                    _ => shadows.visibility(mode)?,
                };
                let settings = RenderSettings {
                    width: plan.size,
                    height: plan.size,
                    eye_rays: 1,
                    shadow_rays: plan.shadow_rays,
                    seed: 0,
                };
                let path = PathSettings { spp: plan.spp, max_depth: depth, rr_depth: None, nee: Nee::Power };
                let located = mode.needs_plie().then_some(oc);
                let renderer = Renderer::new().settings(settings).camera(camera).integrator(Integrator::Path(path));
                let mut runs = Vec::new();
                for _ in 0..plan.runs {
                    let image = renderer.render_with(&scene, bvh, located, vis.as_ref())?;
                    let Timing::Path { seconds, path } = image.timing else {
                        anyhow::bail!("the path tracer rendered without its timings");
                    };
                    runs.push((seconds, path, image.stats));
                }
                runs.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (seconds, p, stats) = &runs[runs.len() / 2];
                rows.push(PathRow {
                    scene: scene.name.clone(),
                    triangles: scene.triangle_count(),
                    mode,
                    max_depth: depth,
                    total_seconds: *seconds,
                    thread_seconds: p.thread_seconds,
                    shadow_seconds: p.shadow_seconds,
                    shadow_share: p.shadow_seconds / p.thread_seconds.max(1e-9),
                    shadow_rays: stats.shadow_rays,
                    mrays_per_second: stats.shadow_rays as f64 / p.shadow_seconds.max(1e-9) / 1e6,
                    bounce_rays: p.bounce_rays,
                    locates: p.locates,
                    locate_ns: 1e9 * p.locate_seconds / p.locates.max(1) as f64,
                    plie_build_seconds: build_seconds.filter(|_| mode.needs_plie()),
                });
                bar.advance(1);
            }
        }
    }
    bar.finish();
    let md = markdown(plan, &rows);
    out.write("path.md", &md)?;
    out.write("path.json", &(serde_json::to_string_pretty(&rows)? + "\n"))?;
    Ok(())
}

/// The Markdown table: one row per scene, depth and mode.
fn markdown(plan: &PathPlan, rows: &[PathRow]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Path tracing: {0}x{0}, {1} paths per pixel, {2} shadow rays at every vertex on a light chosen by power, \
         no Russian roulette, {3} threads, median of {4} runs. Shadow time: summed over threads, timed around each \
         `occluded_light` call; total - none: the total minus that of mode `none` (same rays, no shadow test); \
         shadow share: of the summed path-tracing time. More modes (`embree`, the P-LIE modes): \
         `--path-modes`.\n",
        plan.size,
        plan.spp,
        plan.shadow_rays,
        rayon::current_num_threads(),
        plan.runs
    );
    let _ = writeln!(
        s,
        "| scene | depth | mode | total s | shadow s | total - none s | shadow share | shadow Mrays/s | vs bvh shadow s | locate ns |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.mode != Mode::None) {
        let find = |m: Mode| rows.iter().find(|b| b.scene == r.scene && b.max_depth == r.max_depth && b.mode == m);
        let bvh = find(Mode::Bvh);
        let none = find(Mode::None).map(|n| format!("{:.3}", r.total_seconds - n.total_seconds)).unwrap_or_default();
        let vs = bvh.map(|b| format!("{:.2}x", r.shadow_seconds / b.shadow_seconds.max(1e-9))).unwrap_or_default();
        let loc = if r.locates > 0 { format!("{:.0}", r.locate_ns) } else { "-".into() };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.3} | {:.3} | {none} | {:.0}% | {:.2} | {vs} | {loc} |",
            r.scene,
            r.max_depth,
            r.mode,
            r.total_seconds,
            r.shadow_seconds,
            100.0 * r.shadow_share,
            r.mrays_per_second
        );
    }
    s
}
