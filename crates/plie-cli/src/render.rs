//! `plie render`: hit buffer + shading (SPEC §2) with a chosen visibility mode, written to PNG (tone-mapped
//! sRGB), EXR or PFM (linear radiance).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use plie::octree::Octree;

use plie::render::render;
use plie::visibility::bvh::Bvh;
use plie::visibility::{self, Answer, Mode, QueryStats};
use serde_json::json;

use crate::image_args::ImageArgs;
use crate::plie_args::{load_or_build, PlieArgs};
use crate::progress::Bar;
use crate::scene_arg::SceneArgs;

/// Options of `plie render`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output image; the extension picks the format: .png, .exr, .pfm.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: PathBuf,
    #[command(flatten)]
    image: ImageArgs,
    /// Visibility method. Exact (all give the same image): brute (every triangle), octree (SPEC mode
    /// a), bvh (modern BVH), lie (P-LIE blockers, SPEC mode b), umbra (mode c), penumbra (mode d), grid
    /// (P-LIE face grids, ours), embree-exact (Embree's BVH, our triangle test; embree feature).
    /// References, NOT exact: embree (native Intel Embree 3, its own triangle test: a few shadow rays
    /// may differ from brute; embree feature), none (no shadow test: every light sample counts as
    /// visible; measures shading alone).
    #[arg(long, default_value = "bvh", value_name = "MODE")]
    visibility: Mode,
    /// Worker threads (default: all cores). Images do not depend on it.
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    #[command(flatten)]
    params: PlieArgs,
    /// Use this P-LIE file (from `plie build`) instead of building one (modes that need a P-LIE).
    #[arg(long, value_name = "FILE.plie")]
    plie: Option<PathBuf>,
    /// Print human-readable figures on stderr.
    #[arg(long)]
    stats: bool,
    /// Print one JSON object with the figures on stdout.
    #[arg(long)]
    json: bool,
    /// No progress bar, no warnings.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(a: &Args) -> Result<()> {
    crate::scenes::set_threads(a.threads)?;
    let settings = a.image.settings()?;
    let t = Instant::now();
    let scene = a.scene.load()?;
    let load_seconds = t.elapsed().as_secs_f64();
    if scene.degenerate_skipped > 0 && !a.quiet {
        eprintln!("warning: skipped {} degenerate (zero-area) triangles", scene.degenerate_skipped);
    }
    let camera = a.scene.camera(&scene)?;
    plie::io::check_image_path(&a.output)?;

    let t = Instant::now();
    let bvh = Bvh::build(&scene);
    let bvh_seconds = t.elapsed().as_secs_f64();
    let bar = Bar::new(a.quiet || a.json);
    // Face grids only serve mode `grid`: other modes skip building them.
    let params = a.params.params(a.visibility == Mode::Grid)?;
    let t = Instant::now();
    let (octree, plie, plie_seconds, load_plie_seconds) = if a.visibility.needs_plie() {
        let got = load_or_build(&scene, params, a.plie.as_deref(), &bar)?;
        (got.octree, Some(got.plie), got.build_seconds, got.load_seconds)
    } else {
        (Octree::build(&scene, params.octree()), None, None, None)
    };
    let octree_seconds = t.elapsed().as_secs_f64() - plie_seconds.unwrap_or(0.0);
    let vis = visibility::for_mode(a.visibility, &scene, &bvh, &octree, plie.as_ref())?;
    let out = render(&scene, &camera, &settings, &bvh, Some(&octree), vis.as_ref(), &bar)?;
    let pixels = match plie::io::ImageFormat::from_path(&a.output)? {
        plie::io::ImageFormat::Png if a.image.exposure != 0.0 => {
            let k = a.image.exposure.exp2();
            out.pixels.iter().map(|p| *p * k).collect()
        }
        _ => out.pixels,
    };
    plie::io::save_image(&a.output, a.image.width, a.image.height, &pixels)
        .with_context(|| format!("cannot write {}", a.output.display()))?;

    let s = out.stats;
    let per_ray = if s.shadow_rays > 0 { s.triangle_tests as f64 / s.shadow_rays as f64 } else { 0.0 };
    let rays_per_second = s.shadow_rays as f64 / out.shading_seconds.max(1e-9);
    if a.json {
        let v = json!({
            "scene": scene.name,
            "triangles": scene.triangle_count(),
            "lights": scene.lights.len(),
            "visibility": a.visibility.name(),
            "width": a.image.width,
            "height": a.image.height,
            "eye_rays": a.image.eye_rays,
            "shadow_rays_per_light": a.image.shadow_rays,
            "seed": a.image.seed,
            "threads": rayon::current_num_threads(),
            "load_seconds": load_seconds,
            "bvh_build_seconds": bvh_seconds,
            "octree_build_seconds": octree_seconds,
            "octree_leaves": octree.leaf_count(),
            "octree_depth": octree.depth(),
            "build_seconds": plie_seconds,
            "plie_load_seconds": load_plie_seconds,
            "hit_buffer_seconds": out.hit_buffer_seconds,
            "shading_seconds": out.shading_seconds,
            "shadow_rays": s.shadow_rays,
            "occluded": s.occluded,
            "triangle_tests": s.triangle_tests,
            "triangle_tests_per_shadow_ray": per_ray,
            "box_tests": s.box_tests,
            "box_tests_per_shadow_ray": s.box_tests as f64 / s.shadow_rays.max(1) as f64,
            "blocker_tests": s.blocker_tests,
            "blocker_tests_per_shadow_ray": s.blocker_tests as f64 / s.shadow_rays.max(1) as f64,
            "own_leaf_tests": s.own_leaf_tests,
            "own_leaf_tests_per_shadow_ray": s.own_leaf_tests as f64 / s.shadow_rays.max(1) as f64,
            "answers": s.answers,
            "shadow_rays_per_second": rays_per_second,
            "output": a.output.display().to_string(),
        });
        println!("{v}");
    }
    if a.stats {
        eprintln!(
            "scene            {} ({} triangles, {} lights)",
            scene.name,
            scene.triangle_count(),
            scene.lights.len()
        );
        eprintln!("visibility       {}", a.visibility);
        eprintln!(
            "image            {}x{}, {}x{} eye rays/pixel, {} shadow rays/light",
            a.image.width, a.image.height, a.image.eye_rays, a.image.eye_rays, a.image.shadow_rays
        );
        eprintln!("threads          {}", rayon::current_num_threads());
        eprintln!("load             {load_seconds:.3} s");
        eprintln!("bvh build        {bvh_seconds:.3} s");
        eprintln!("octree build     {octree_seconds:.3} s ({} leaves, depth {})", octree.leaf_count(), octree.depth());
        if let Some(s) = plie_seconds {
            eprintln!("p-lie build      {s:.3} s");
        }
        if let Some(s) = load_plie_seconds {
            eprintln!("p-lie load       {s:.3} s");
        }
        eprintln!("hit buffer       {:.3} s", out.hit_buffer_seconds);
        eprintln!("shading          {:.3} s", out.shading_seconds);
        eprintln!(
            "shadow rays      {} ({:.1}% occluded, {:.2} M/s)",
            s.shadow_rays,
            100.0 * s.occluded as f64 / s.shadow_rays.max(1) as f64,
            rays_per_second / 1e6
        );
        eprintln!("triangle tests   {} ({per_ray:.2} per shadow ray)", s.triangle_tests);
        print_answers(&s);
    }
    if !a.quiet && !a.json && !a.stats {
        eprintln!("wrote {} ({:.2} s shading, {} shadow rays)", a.output.display(), out.shading_seconds, s.shadow_rays);
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
        "  of which       {:.2} blockers, {:.2} own leaf per shadow ray",
        per_ray(s.blocker_tests),
        per_ray(s.own_leaf_tests)
    );
    eprintln!("answered by      {:>12} {:>7}", "rays", "share");
    for a in Answer::ALL {
        let n = s.answers.get(a);
        eprintln!("  {:<14} {n:>12} {:>6.1}%", a.name(), 100.0 * per_ray(n));
    }
}
