//! `plie render`: hit buffer + shading (SPEC §2) with a chosen visibility mode, written to PNG (tone-mapped
//! sRGB), EXR or PFM (linear radiance).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use plie::octree::Octree;
use plie::visibility::{Answer, QueryStats};
use plie::{Camera, Mode, Renderer, Shadows, Timing};
use serde_json::json;

use crate::image_args::ImageArgs;
use crate::path_args::{Integrator, PathArgs};
use crate::plie_args::{build, load_file, PlieArgs};
use crate::progress::Bar;
use crate::render_path;
use crate::scene_arg::{CameraArgs, SceneArgs};
use crate::walkthrough::{FrameRange, Plan};

/// Options of `plie render`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    camera: CameraArgs,
    /// Output image; the extension picks the format: .png, .exr, .pfm. With --camera-path, a pattern
    /// whose run of # is replaced by the frame number, zero-padded (out/frame_####.png).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: PathBuf,
    /// Render a walkthrough: one image per frame of this camera path (JSON keyframes, interpolation
    /// `linear` or `catmull-rom`; see the README), all from one scene and P-LIE.
    #[arg(long, value_name = "PATH.json", conflicts_with_all = ["eye", "target", "up", "fov", "stats"])]
    camera_path: Option<PathBuf>,
    /// With --camera-path: the frames to render, `A..B` (both included) or `N` (default: all).
    #[arg(long, value_name = "A..B", requires = "camera_path")]
    frames: Option<FrameRange>,
    /// With --camera-path: skip frames whose output file exists.
    #[arg(long, requires = "camera_path")]
    resume: bool,
    #[command(flatten)]
    image: ImageArgs,
    #[command(flatten)]
    path: PathArgs,
    /// How shadow rays are answered. Every mode but `none` and `embree` gives the same image, bit for
    /// bit; they differ in speed. `brute`: test every triangle (the reference; slow). `octree`: walk the
    /// octree's cells along the ray. `bvh`: a bounding volume hierarchy, the fastest without
    /// preprocessing. `lie`: a P-LIE (built first, or read with --plie) lists, per cell face and light,
    /// the triangles that can block the light; test only those. `umbra`: as `lie`, and a ray crossing
    /// the face in the region the light cannot reach at all is dark without a test. `penumbra`: as
    /// `umbra`, and a ray crossing the face where nothing blocks the light is lit without a test.
    /// `grid`: a grid on each face says dark, lit, or which few blockers to test (the fastest P-LIE
    /// mode). `embree-exact`: Embree's BVH proposing candidates to plie's own triangle test (exact).
    /// References, NOT exact: `none` (no shadow test: every light sample counts as visible; a lower
    /// bound on shading time) and `embree` (native Intel Embree 3 with its own triangle test: a few
    /// shadow rays may differ from `brute`). The two Embree modes need a plie built with `--features
    /// embree`. Default: `bvh`; with --plie, the fastest mode the file supports.
    #[arg(long, value_name = "MODE")]
    visibility: Option<Mode>,
    #[command(flatten)]
    threads: crate::threads_arg::ThreadsArg,
    #[command(flatten)]
    params: PlieArgs,
    /// Use this P-LIE file (from `plie build`) instead of building one; only the P-LIE modes (`lie`,
    /// `umbra`, `penumbra`, `grid`) use it. Its build parameters come from the file: build options
    /// can be left out, and one given that contradicts the file is an error.
    #[arg(long, value_name = "FILE.plie")]
    plie: Option<PathBuf>,
    /// Print human-readable figures on stderr (times, shadow rays, and how a P-LIE answered them).
    #[arg(long)]
    stats: bool,
    /// Print one JSON object with the figures on stdout.
    #[arg(long)]
    json: bool,
    /// No progress bar, no warnings, no `wrote FILE` line.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(a: &Args, matches: &clap::ArgMatches) -> Result<()> {
    a.threads.install()?;
    plie::io::ImageFormat::from_path(&a.output)?;
    let inputs: Vec<&std::path::Path> =
        a.scene.file().into_iter().chain(a.plie.as_deref()).chain(a.camera_path.as_deref()).collect();
    let walk = a.camera_path.as_deref().map(|p| Plan::new(p, a.frames, &a.output, a.resume)).transpose()?;
    let outputs: Vec<PathBuf> = match &walk {
        Some(w) => w.existing_files().collect(),
        None => vec![a.output.clone()],
    };
    for output in &outputs {
        crate::checks::output_is_not_input(output, &inputs)?;
    }
    let mut settings = a.image.settings()?;
    if a.path.integrator == Integrator::Direct {
        settings.eye_rays = a.path.eye_rays(settings.eye_rays)?;
        settings.validate()?;
    } else {
        a.path.settings(settings.eye_rays)?;
    }
    let t = Instant::now();
    let scene = a.scene.load()?;
    crate::checks::outputs_are_not_sources(&outputs, &scene.sources)?;
    let load_seconds = t.elapsed().as_secs_f64();
    if !a.quiet {
        crate::scene_arg::warn_about(&scene);
    }
    let camera = a.camera.camera(&scene)?;
    a.image.size_for(&mut settings, &scene)?;

    let bar = Bar::new(a.quiet || a.json);
    let asked = a.visibility.unwrap_or(Mode::Bvh);
    let plie_file = if a.visibility.is_none_or(Mode::needs_plie) { a.plie.as_deref() } else { None };
    if !a.quiet {
        for w in ignored_options(a, asked, matches) {
            eprintln!("warning: {w}");
        }
    }
    // Face grids only serve mode `grid`: other modes skip building them.
    let params = a.params.params(asked == Mode::Grid)?;
    let t = Instant::now();
    // The P-LIE modes answer from an environment (loaded or built), the others from `Shadows`.
    let loaded = if asked.needs_plie() || plie_file.is_some() {
        Some(match plie_file {
            Some(file) => load_file(&scene, file, &a.params, matches)?,
            None => build(&scene, params, &a.params, &bar)?,
        })
    } else {
        None
    };
    let shadows = Shadows::with_octree_params(&scene, params.octree())?;
    let env = loaded.as_ref().map(|l| &l.env);
    let (plie_seconds, load_plie_seconds) = loaded.as_ref().map_or((None, None), |l| (l.build_seconds, l.load_seconds));
    // The octree of mode `octree` or of the P-LIE; the other modes build none.
    let octree = match env {
        Some(env) => Some(env.octree()),
        None => (asked == Mode::Octree).then(|| shadows.octree()),
    };
    let octree_seconds = t.elapsed().as_secs_f64() - plie_seconds.unwrap_or(0.0);
    let t = Instant::now();
    let bvh = env.map_or_else(|| shadows.bvh(), |e| e.bvh(&scene));
    let bvh_seconds = t.elapsed().as_secs_f64();
    let (mode, vis) = match env {
        Some(env) => {
            let mode = a.visibility.unwrap_or_else(|| env.best_mode());
            (mode, env.visibility(mode, &scene)?)
        }
        None => (asked, shadows.visibility(asked)?),
    };
    // Only the P-LIE modes locate shaded points in the octree (the others do not use the leaf).
    let leaves = octree.filter(|_| mode.needs_plie());
    let integrator = match a.path.integrator {
        Integrator::Path => plie::Integrator::Path(a.path.settings(settings.eye_rays)?),
        Integrator::Direct => plie::Integrator::Direct,
    };
    let renderer = Renderer::new().settings(settings).integrator(integrator).progress(&bar);
    let render = |camera: &Camera| renderer.camera(*camera).render_with(&scene, bvh, leaves, vis.as_ref());
    if let Some(walk) = walk {
        let render_frame = |camera: &Camera| -> Result<Vec<glam::Vec3>> { Ok(render(camera)?.pixels) };
        let save = |file: &std::path::Path, pixels| render_path::save(file, &settings, a.image.exposure, pixels);
        return walk.run(a.quiet, a.json, render_frame, save);
    }
    let out = render(&camera)?;
    if a.path.integrator == Integrator::Path {
        let traced = render_path::Traced::of(&out);
        let shadow_rays = out.stats.shadow_rays;
        let seconds = traced.seconds;
        if a.json {
            let mut v = render_path::json_fields(&traced, &a.path, settings.eye_rays)?;
            v["scene"] = json!(scene.name);
            v["triangles"] = json!(scene.triangle_count());
            v["lights"] = json!(scene.lights.len());
            v["visibility"] = json!(mode.name());
            v["width"] = json!(settings.width);
            v["height"] = json!(settings.height);
            v["shadow_rays_per_light"] = json!(settings.shadow_rays);
            v["seed"] = json!(settings.seed);
            v["threads"] = json!(rayon::current_num_threads());
            v["load_seconds"] = json!(load_seconds);
            v["build_seconds"] = json!(plie_seconds);
            v["plie_load_seconds"] = json!(load_plie_seconds);
            v["output"] = json!(a.output.display().to_string());
            println!("{v}");
        }
        if a.stats {
            eprintln!(
                "scene            {} ({} triangles, {})",
                scene.name,
                scene.triangle_count(),
                crate::scenes::count(scene.lights.len(), "light")
            );
            eprintln!("visibility       {}", mode);
            render_path::print_stats(&traced);
            print_answers(&out.stats);
        }
        render_path::save(&a.output, &settings, a.image.exposure, out.pixels)?;
        if !a.quiet && !a.json && !a.stats {
            eprintln!("wrote {} ({seconds:.2} s path tracing, {shadow_rays} shadow rays)", a.output.display());
        }
        return Ok(());
    }
    let Timing::Direct { hit_buffer_seconds, shading_seconds, shading_cpu_seconds } = out.timing else {
        bail!("direct light rendered without its timings");
    };
    let pixels = match plie::io::ImageFormat::from_path(&a.output)? {
        plie::io::ImageFormat::Png if a.image.exposure != 0.0 => {
            let k = a.image.exposure.exp2();
            out.pixels.iter().map(|p| *p * k).collect()
        }
        _ => out.pixels,
    };
    plie::io::save_image(&a.output, settings.width, settings.height, &pixels)
        .with_context(|| format!("cannot write {}", a.output.display()))?;

    let s = out.stats;
    let per_ray = if s.shadow_rays > 0 { s.triangle_tests as f64 / s.shadow_rays as f64 } else { 0.0 };
    let rays_per_second = s.shadow_rays as f64 / shading_seconds.max(1e-9);
    if a.json {
        let v = json!({
            "scene": scene.name,
            "triangles": scene.triangle_count(),
            "lights": scene.lights.len(),
            "visibility": mode.name(),
            "width": settings.width,
            "height": settings.height,
            "integrator": "direct",
            "eye_rays": settings.eye_rays,
            "shadow_rays_per_light": a.image.shadow_rays,
            "seed": a.image.seed,
            "threads": rayon::current_num_threads(),
            "load_seconds": load_seconds,
            "bvh_build_seconds": bvh_seconds,
            "octree_build_seconds": octree.map(|_| octree_seconds),
            "octree_leaves": octree.map(Octree::leaf_count),
            "octree_depth": octree.map(Octree::depth),
            "build_seconds": plie_seconds,
            "plie_load_seconds": load_plie_seconds,
            "hit_buffer_seconds": hit_buffer_seconds,
            "shading_seconds": shading_seconds,
            "shading_cpu_seconds": shading_cpu_seconds,
            "shadow_rays": s.shadow_rays,
            "occluded": s.occluded,
            "triangle_tests": s.triangle_tests,
            "triangle_tests_per_shadow_ray": per_ray,
            "lane_tests": s.lane_tests,
            "box_tests": s.box_tests,
            "box_tests_per_shadow_ray": s.box_tests as f64 / s.shadow_rays.max(1) as f64,
            "blocker_tests": s.blocker_tests,
            "blocker_tests_per_shadow_ray": s.blocker_tests as f64 / s.shadow_rays.max(1) as f64,
            "own_leaf_tests": s.own_leaf_tests,
            "own_leaf_tests_per_shadow_ray": s.own_leaf_tests as f64 / s.shadow_rays.max(1) as f64,
            "answers": s.answers,
            "light_queries": s.lights,
            "shadow_rays_per_second": rays_per_second,
            "output": a.output.display().to_string(),
        });
        println!("{v}");
    }
    if a.stats {
        eprintln!(
            "scene            {} ({} triangles, {})",
            scene.name,
            scene.triangle_count(),
            crate::scenes::count(scene.lights.len(), "light")
        );
        eprintln!("visibility       {mode}");
        eprintln!(
            "image            {}x{}, {}x{} eye rays/pixel, {} shadow rays/light",
            settings.width, settings.height, settings.eye_rays, settings.eye_rays, a.image.shadow_rays
        );
        eprintln!("threads          {}", rayon::current_num_threads());
        eprintln!("load             {load_seconds:.3} s");
        eprintln!("bvh build        {bvh_seconds:.3} s");
        match octree {
            Some(o) => {
                eprintln!("octree build     {octree_seconds:.3} s ({} leaves, depth {})", o.leaf_count(), o.depth())
            }
            None => eprintln!("octree build     none (--visibility {mode} uses no octree)"),
        }
        if let Some(s) = plie_seconds {
            eprintln!("p-lie build      {s:.3} s");
        }
        if let Some(s) = load_plie_seconds {
            eprintln!("p-lie load       {s:.3} s");
        }
        eprintln!("hit buffer       {:.3} s", hit_buffer_seconds);
        eprintln!("shading          {:.3} s", shading_seconds);
        eprintln!(
            "shadow rays      {} ({:.1}% occluded, {:.2} M/s)",
            s.shadow_rays,
            100.0 * s.occluded as f64 / s.shadow_rays.max(1) as f64,
            rays_per_second / 1e6
        );
        eprintln!("triangle tests   {} ({per_ray:.2} per shadow ray)", s.triangle_tests);
        if s.lane_tests > 0 {
            let lanes = s.lane_tests as f64 / s.shadow_rays.max(1) as f64;
            eprintln!("fan lane tests   {} ({lanes:.2} per shadow ray)", s.lane_tests);
        }
        print_answers(&s);
    }
    if !a.quiet && !a.json {
        eprintln!("wrote {} ({:.2} s shading, {} shadow rays)", a.output.display(), shading_seconds, s.shadow_rays);
    }
    Ok(())
}

/// The answer paths of a P-LIE mode (nothing for the other modes, which count none): rays and share of
/// the shadow rays per path, and the triangle tests per shadow ray split into blockers and own leaf.
fn print_answers(s: &QueryStats) {
    if s.answers.total() == 0 {
        return;
    }
    let per_ray = |n: u64| n as f64 / s.shadow_rays.max(1) as f64;
    eprintln!(
        "p-lie tests      {:.2} blocker and {:.2} own-leaf triangle tests per shadow ray",
        per_ray(s.blocker_tests),
        per_ray(s.own_leaf_tests)
    );
    eprintln!("answered by      {:>12} {:>7}", "rays", "share");
    for a in Answer::ALL {
        let n = s.answers.get(a);
        eprintln!("  {:<14} {n:>12} {:>6.1}%", a.name(), 100.0 * per_ray(n));
    }
    let l = &s.lights;
    if l.queries > 0 {
        let share = |n: u64| 100.0 * n as f64 / l.queries as f64;
        eprintln!("(point, light)   {:>12} {:>7}", "pairs", "share");
        for (name, n) in [
            ("whole umbra", l.whole_umbra),
            ("whole lit", l.whole_lit),
            ("gathered", l.gathered),
            ("shaft", l.shaft),
            ("last blockers", l.last_blockers),
            ("scene BVH", l.scene),
        ] {
            eprintln!("  {name:<14} {n:>12} {:>6.1}%", share(n));
        }
        eprintln!(
            "  of all pairs, {} ({:.1}%) did not look for footprints (their leaf's footprints had decided nothing lately); they are among shaft, last blockers and scene BVH",
            l.unsought,
            share(l.unsought)
        );
    }
}

/// Options given on the command line (`matches`) that the chosen mode, integrator or output does not
/// use, as warnings.
fn ignored_options(a: &Args, mode: Mode, matches: &clap::ArgMatches) -> Vec<String> {
    let given = |id: &str| matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine);
    let mut out = Vec::new();
    let p = &a.params;
    let uses_plie = a.visibility.is_none_or(Mode::needs_plie) && (mode.needs_plie() || a.plie.is_some());
    if let (Some(file), false) = (&a.plie, uses_plie) {
        out.push(format!(
            "--plie {} is ignored: --visibility {mode} does not use a P-LIE (lie, umbra, penumbra and grid do)",
            file.display()
        ));
    }
    if !uses_plie {
        // --max-blockers without --refine blockers is an error (below), not a warning.
        let max_blockers = p.max_blockers.is_some() && p.refine.contains(&crate::plie_args::RefineCriterion::Blockers);
        for (id, name) in [
            ("refine", "--refine"),
            ("max_split_depth", "--max-split-depth"),
            ("no_regions", "--no-regions"),
            ("no_propagation", "--no-propagation"),
            ("no_grids", "--no-grids"),
            ("blocker_cap", "--blocker-cap"),
            ("lift_clips", "--lift-clips"),
            ("cell_clips", "--cell-clips"),
        ] {
            if given(id) {
                out.push(format!(
                    "{name} is ignored: --visibility {mode} builds no P-LIE (lie, umbra, penumbra and grid do)"
                ));
            }
        }
        if max_blockers {
            out.push(format!(
                "--max-blockers is ignored: --visibility {mode} builds no P-LIE (lie, umbra, penumbra and grid do)"
            ));
        }
        if mode != Mode::Octree {
            for (id, name) in [("max_triangles", "--max-triangles"), ("max_depth", "--max-depth")] {
                if given(id) {
                    out.push(format!(
                        "{name} is ignored: --visibility {mode} builds no octree (octree and the P-LIE modes do)"
                    ));
                }
            }
        }
    } else if p.no_grids && a.visibility.is_some_and(|m| m != Mode::Grid) {
        out.push(format!("--no-grids is ignored: only --visibility grid uses face grids, not {mode}"));
    }
    if a.path.integrator == Integrator::Direct {
        for (id, name) in [("nee", "--nee"), ("max_path_depth", "--max-path-depth"), ("rr_depth", "--rr-depth")] {
            if given(id) {
                out.push(format!("{name} is ignored: it sets the path tracer (--integrator path), not direct light"));
            }
        }
    }
    let linear = |p: &std::path::Path| {
        p.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("pfm") || e.eq_ignore_ascii_case("exr"))
    };
    if given("exposure") && linear(&a.output) {
        out.push("--exposure is ignored: .exr and .pfm images store linear radiance (it scales PNG output)".into());
    }
    out
}
