//! `plie bench --soft-shadows`: soft shadows at the sample counts people use (issue 21). For each
//! scene (the ten built-in ones and the shared `cornell-bunny.obj`, `cornell-dragon-100k.obj` and
//! `conference-lit.obj`, with the cameras of ../shared/scenes/README.md), one 254x254 hit buffer
//! (1 eye ray per pixel), then the shading pass (timed alone, median of the runs, seed 1) at 4, 16
//! and 64 shadow rays per light with every mode: `none` (no shadow test: the floor), the exact modes
//! but `brute` and `octree`, `embree` where built with it, the P-LIE modes on the refined P-LIE
//! (`grid+u`), and `grid` asked ray by ray (`grid/ray`: the per-ray query as before the per-light
//! query). The modes' runs are interleaved (every mode's first run, then every mode's second, ...),
//! so that a noisy spell of the shared machine falls on all of them alike. Written to
//! `soft-shadows.md` and `soft-shadows.json`.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use plie::internals::render::cpu_time::process_cpu_seconds;
use plie::internals::render::shade::shade;
use plie::internals::render::{HitBuffer, NoProgress};
use plie::scene::builtin;
use plie::visibility::{LightAnswers, Mode, QueryCtx, ShadowRay, Visibility};
use plie::PlieParams;
use plie::RefineParams;
use plie::{Camera, Environment, Scene, Shadows};
use serde::Serialize;

use crate::out_dir::OutDir;

/// Image size (width = height) of the table.
const SIZE: u32 = 254;
/// Shadow rays per light of the table.
const SHADOW_RAYS: [u32; 3] = [4, 16, 64];
/// The shared scenes of the table, with their cameras (eye, target, vertical fov; up is +y).
const SHARED: [(&str, [f32; 3], [f32; 3], f32); 3] = [
    ("cornell-bunny.obj", [278.0, 273.0, -800.0], [278.0, 273.0, 0.0], 39.3),
    ("cornell-dragon-100k.obj", [278.0, 273.0, -800.0], [278.0, 273.0, 0.0], 39.3),
    ("conference-lit.obj", [1550.0, 380.0, 550.0], [400.0, 150.0, -150.0], 60.0),
];

/// One shading measurement.
#[derive(Serialize)]
pub struct Row {
    pub scene: String,
    pub mode: String,
    pub shadow_rays: u32,
    /// Median wall seconds of the shading pass.
    pub seconds: f64,
    /// Median CPU seconds of the process during the pass (all threads).
    pub cpu_seconds: Option<f64>,
    pub rays: u64,
    pub occluded: u64,
    /// How the (point, light) pairs were answered (P-LIE modes).
    pub lights: LightAnswers,
    /// For the modes that are not exact (`embree`): the shadow rays whose answer differs from
    /// `bvh`'s (exact), ray by ray.
    pub differing: Option<u64>,
}

/// Everything measured.
#[derive(Serialize)]
pub struct SoftResults {
    pub command: String,
    pub date: String,
    pub cpu: Option<String>,
    pub threads: usize,
    pub runs: usize,
    pub size: u32,
    pub rows: Vec<Row>,
}

/// A mode of the table: a visibility mode, on the refined P-LIE (`+u`) or asked ray by ray.
#[derive(Clone, Copy, PartialEq)]
enum Column {
    Mode(Mode),
    Refined(Mode),
    PerRay(Mode),
}

impl Column {
    fn name(self) -> String {
        match self {
            Column::Mode(m) => m.name().to_string(),
            Column::Refined(m) => format!("{m}+u"),
            Column::PerRay(m) => format!("{m}/ray"),
        }
    }
}

/// The columns of the table, in order.
fn columns() -> Vec<Column> {
    let mut c = vec![Column::Mode(Mode::None), Column::Mode(Mode::Bvh)];
    #[cfg(feature = "embree")]
    c.push(Column::Mode(Mode::Embree));
    c.extend([Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid].map(Column::Mode));
    c.push(Column::Refined(Mode::Grid));
    c.push(Column::PerRay(Mode::Grid));
    c
}

/// A column's visibility at one shadow-ray count, with its timings (wall and CPU seconds per run)
/// and the counters of its last run.
struct Timed<'a> {
    col: Column,
    vis: Box<dyn Visibility + 'a>,
    hits: &'a HitBuffer,
    walls: Vec<f64>,
    cpus: Vec<f64>,
    stats: Option<plie::visibility::QueryStats>,
}

/// A visibility answered ray by ray: the per-light query falls back to the trait's loop.
struct PerRay<'a>(Box<dyn Visibility + 'a>);

impl Visibility for PerRay<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        self.0.occluded(ray, ctx)
    }
}

/// The default scenes: the ten built-in ones, then the shared ones found in `shared`. Each shared
/// scene not found is named on stderr (even with `--quiet`: the table is then not the documented one).
pub fn default_scenes(shared: &Path) -> Vec<String> {
    let mut s: Vec<String> = builtin::NAMES.iter().map(|n| n.to_string()).collect();
    for (f, ..) in SHARED {
        let p = shared.join(f);
        if p.exists() {
            s.push(p.display().to_string());
        } else {
            eprintln!("notice: {} not found: the soft-shadow table leaves it out (see --shared)", p.display());
        }
    }
    s
}

/// Loads a scene with the table's camera: the README's for the shared files, else the scene's own.
fn load(name: &str) -> Result<(Scene, Camera)> {
    let args = crate::scene_arg::SceneArgs { scene: name.to_string(), allow_outside_paths: false };
    let scene = args.load()?;
    let file = Path::new(name).file_name().and_then(|f| f.to_str()).unwrap_or("");
    let camera = match SHARED.iter().find(|(f, ..)| *f == file) {
        Some((_, eye, target, fov)) => Camera::new((*eye).into(), (*target).into(), glam::Vec3::Y, *fov)?,
        None => scene.camera_or_default(),
    };
    Ok((scene, camera))
}

/// Measures every column at every shadow-ray count on `scenes` and writes the report into `out`.
pub fn run(scenes: &[String], out: &mut OutDir, runs: usize, quiet: bool) -> Result<()> {
    let mut rows = Vec::new();
    for name in scenes {
        let (scene, camera) = load(name).with_context(|| format!("scene {name}"))?;
        let label = Path::new(name).file_name().and_then(|f| f.to_str()).unwrap_or(name).to_string();
        if !quiet {
            eprintln!("soft shadows: {label} ({} triangles)", scene.triangle_count());
        }
        let params = PlieParams::default();
        let (env, _) = Environment::build(&scene, &params)?;
        let refine = RefineParams { umbra_full: true, umbra_free: true, ..RefineParams::none() };
        let (refined, _) = Environment::build(&scene, &PlieParams { refine, ..params })?;
        let shadows = Shadows::new(&scene);
        let bvh = shadows.bvh();
        let hits = HitBuffer::build(&scene, &camera, (SIZE, SIZE, 1), bvh, Some(env.octree()));
        let r_hits = HitBuffer::build(&scene, &camera, (SIZE, SIZE, 1), bvh, Some(refined.octree()));
        for n in SHADOW_RAYS {
            let mut cols = Vec::new();
            for col in columns() {
                let (vis, hits): (Box<dyn Visibility + '_>, _) = match col {
                    Column::Mode(m) if !m.needs_plie() => (shadows.visibility(m)?, &hits),
                    Column::Mode(m) => (env.visibility(m, &scene)?, &hits),
                    Column::Refined(m) => (refined.visibility(m, &scene)?, &r_hits),
                    Column::PerRay(m) => (Box::new(PerRay(env.visibility(m, &scene)?)), &hits),
                };
                cols.push(Timed { col, vis, hits, walls: Vec::new(), cpus: Vec::new(), stats: None });
            }
            // The modes' runs interleaved (every mode's first run, then every mode's second, ...),
            // so that a noisy spell of the machine falls on all of them alike.
            for _ in 0..runs {
                for c in &mut cols {
                    let (t, cpu) = (Instant::now(), process_cpu_seconds());
                    c.stats = Some(shade(&scene, c.hits, c.vis.as_ref(), n, 1, &NoProgress).1);
                    c.walls.push(t.elapsed().as_secs_f64());
                    if let Some((a, b)) = cpu.zip(process_cpu_seconds()) {
                        c.cpus.push(b - a);
                    }
                }
            }
            for Timed { col, vis, hits, mut walls, mut cpus, stats } in cols {
                let stats = stats.expect("one run");
                let differing = match col {
                    Column::Mode(m) if m != Mode::None && !m.is_exact() => {
                        let bvh_vis = shadows.visibility(Mode::Bvh)?;
                        Some(
                            plie::internals::compare::answer_diff(&scene, hits, vis.as_ref(), bvh_vis.as_ref(), n, 1)
                                .differing,
                        )
                    }
                    _ => None,
                };
                rows.push(Row {
                    scene: label.clone(),
                    mode: col.name(),
                    shadow_rays: n,
                    seconds: crate::bench_data::median(&mut walls),
                    cpu_seconds: (!cpus.is_empty()).then(|| crate::bench_data::median(&mut cpus)),
                    rays: stats.shadow_rays,
                    occluded: stats.occluded,
                    lights: stats.lights,
                    differing,
                });
            }
        }
    }
    let results = SoftResults {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        date: crate::bench_report::utc_now(),
        cpu: crate::bench_report::cpu_model(),
        threads: rayon::current_num_threads(),
        runs,
        size: SIZE,
        rows,
    };
    out.write("soft-shadows.json", &(serde_json::to_string_pretty(&results)? + "\n"))?;
    out.write("soft-shadows.md", &report(&results))?;
    if !quiet {
        eprintln!("wrote {}/{{soft-shadows.md, soft-shadows.json}}", out.path().display());
    }
    Ok(())
}

/// The report: per shadow-ray count, a table of shading seconds per scene and mode, the overhead above
/// `none`, the ratio to `embree`, the share of (point, light) pairs answered whole, and the goals.
pub fn report(r: &SoftResults) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "# Soft shadows: shading seconds at {0}x{0}, 1 eye ray per pixel, seed 1\n", r.size);
    let _ = writeln!(
        s,
        "Command `{}`, {}, {} threads, median of {} runs (the modes' runs interleaved), CPU: {}.\n",
        r.command,
        r.date,
        r.threads,
        r.runs,
        r.cpu.as_deref().unwrap_or("unknown")
    );
    let _ = writeln!(
        s,
        "`none` tests no shadow ray (the floor; not exact). `embree` is native Embree 3 where plie was built \
         with the `embree` feature (not exact: see its help). `+u`: on the P-LIE refined by umbra. `/ray`: \
         the same mode asked ray by ray (the per-ray query, as before the per-light query). Overhead: \
         seconds above `none`.\n"
    );
    let mut scenes: Vec<&str> = Vec::new();
    let mut modes: Vec<&str> = Vec::new();
    for row in &r.rows {
        if !scenes.contains(&row.scene.as_str()) {
            scenes.push(&row.scene);
        }
        if !modes.contains(&row.mode.as_str()) {
            modes.push(&row.mode);
        }
    }
    let get = |scene: &str, mode: &str, n: u32| {
        r.rows.iter().find(|x| x.scene == scene && x.mode == mode && x.shadow_rays == n).map(|x| x.seconds)
    };
    let sum = |mode: &str, n: u32| scenes.iter().map(|sc| get(sc, mode, n)).sum::<Option<f64>>();
    for n in SHADOW_RAYS {
        let _ = writeln!(s, "## {n} shadow rays per light\n");
        let _ = writeln!(s, "| scene | {} |", modes.join(" | "));
        let _ = writeln!(s, "|---|{}", "---|".repeat(modes.len()));
        for sc in &scenes {
            let cells: Vec<String> =
                modes.iter().map(|m| get(sc, m, n).map_or("-".into(), |t| format!("{t:.3}"))).collect();
            let _ = writeln!(s, "| {sc} | {} |", cells.join(" | "));
        }
        let sums: Vec<String> = modes.iter().map(|m| sum(m, n).map_or("-".into(), |t| format!("{t:.3}"))).collect();
        let _ = writeln!(s, "| **sum** | {} |", sums.join(" | "));
        if let Some(none) = sum("none", n) {
            let over: Vec<String> =
                modes.iter().map(|m| sum(m, n).map_or("-".into(), |t| format!("{:.3}", t - none))).collect();
            let _ = writeln!(s, "| overhead above none | {} |", over.join(" | "));
        }
        if let Some(e) = sum("embree", n) {
            let ratio: Vec<String> =
                modes.iter().map(|m| sum(m, n).map_or("-".into(), |t| format!("{:.2}", t / e))).collect();
            let _ = writeln!(s, "| ratio to embree | {} |", ratio.join(" | "));
        }
        for row in r.rows.iter().filter(|x| x.shadow_rays == n) {
            if let Some(d) = row.differing {
                let _ = writeln!(
                    s,
                    "- `{}` on {}: {d} of {} shadow rays answered otherwise than `bvh` (exact): {:.2e}.",
                    row.mode,
                    row.scene,
                    row.rays,
                    d as f64 / row.rays.max(1) as f64
                );
            }
        }
        let _ = writeln!(s);
        // Whole answers of the P-LIE modes.
        let _ = writeln!(s, "(point, light) pairs answered whole (umbra / lit), by the short lists gathered under the light's footprints, by the triangles in the shaft of the point's piece of surface, by the light's last blockers (all rays occluded by the blockers of its last walk that found every ray occluded), or by the scene BVH, `grid`; and the pairs whose footprints were not sought because they had decided nothing in the last queries of their leaf and light (those go to the shaft, last blockers or scene BVH):\n");
        let _ = writeln!(
            s,
            "| scene | pairs | whole umbra | whole lit | gathered | shaft | last blockers | scene BVH | not sought |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        for sc in &scenes {
            if let Some(row) = r.rows.iter().find(|x| x.scene == *sc && x.mode == "grid" && x.shadow_rays == n) {
                let l = row.lights;
                let pct = |k: u64| 100.0 * k as f64 / l.queries.max(1) as f64;
                let _ = writeln!(
                    s,
                    "| {sc} | {} | {:.1}% | {:.1}% | {:.1}% | {:.1}% | {:.1}% | {:.1}% | {:.1}% |",
                    l.queries,
                    pct(l.whole_umbra),
                    pct(l.whole_lit),
                    pct(l.gathered),
                    pct(l.shaft),
                    pct(l.last_blockers),
                    pct(l.scene),
                    pct(l.unsought)
                );
            }
        }
        let _ = writeln!(s);
    }
    // The goals of issue 21.
    let best = |n: u32| {
        ["lie", "umbra", "penumbra", "grid", "grid+u"]
            .iter()
            .filter_map(|m| sum(m, n).map(|t| (t, *m)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    };
    let _ = writeln!(s, "## Goals\n");
    let verdict = |ok: bool| if ok { "met" } else { "not met" };
    if let (Some((b64, m64)), Some(none64)) = (best(64), sum("none", 64)) {
        if let Some(e64) = sum("embree", 64) {
            let _ = writeln!(
                s,
                "- 64 rays: best exact P-LIE mode `{m64}` {b64:.3} s against embree {e64:.3} s: {:.2}x (goal <= 0.5): {}.",
                b64 / e64,
                verdict(b64 <= 0.5 * e64)
            );
        }
        let _ = writeln!(
            s,
            "- 64 rays: its overhead above none {:.3} s against none {none64:.3} s: {:.2}x (goal <= 0.5): {}.",
            b64 - none64,
            (b64 - none64) / none64,
            verdict(b64 - none64 <= 0.5 * none64)
        );
    }
    if let (Some((b16, m16)), Some(e16)) = (best(16), sum("embree", 16)) {
        let _ = writeln!(
            s,
            "- 16 rays: best `{m16}` {b16:.3} s against embree {e16:.3} s: {:.2}x (goal <= 0.75): {}.",
            b16 / e16,
            verdict(b16 <= 0.75 * e16)
        );
    }
    if let (Some(g4), Some(r4)) = (sum("grid", 4), sum("grid/ray", 4)) {
        let _ = writeln!(
            s,
            "- 4 rays: `grid` {g4:.3} s against `grid` ray by ray {r4:.3} s (goal: no slower): {}.",
            verdict(g4 <= r4)
        );
    }
    s
}
