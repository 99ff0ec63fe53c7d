//! `plie render --integrator path`: the path tracer (global illumination, SPEC §8 point 6) with
//! next-event estimation through the chosen visibility mode; writes the image and prints its figures
//! (rays by kind, time in shadow tests, shadow rays per second, the cost of locating path vertices).

use anyhow::{Context, Result};
use plie::visibility::QueryStats;
use plie::PathStats;
use plie::RenderSettings;
use plie::{Image, Timing};
use serde_json::json;

use crate::path_args::PathArgs;

/// The figures of a path-traced image: wall-clock seconds, rays by kind, shadow-ray counters.
pub struct Traced<'a> {
    pub seconds: f64,
    pub path: PathStats,
    pub stats: &'a QueryStats,
}

impl<'a> Traced<'a> {
    /// The figures of `image`, rendered with the path tracer (zero timings for a direct-light image).
    pub fn of(image: &'a Image) -> Traced<'a> {
        let (seconds, path) = match image.timing {
            Timing::Path { seconds, path } => (seconds, path),
            Timing::Direct { .. } => (0.0, PathStats::default()),
        };
        Traced { seconds, path, stats: &image.stats }
    }
}

/// The figures of a path-traced image as JSON fields.
pub fn json_fields(out: &Traced, args: &PathArgs, k: u32) -> Result<serde_json::Value> {
    let path = args.settings(k)?;
    let p = &out.path;
    let s = out.stats;
    Ok(json!({
        "integrator": "path",
        "spp": path.spp,
        "max_path_depth": path.max_depth,
        "rr_depth": path.rr_depth,
        "nee": path.nee,
        "render_seconds": out.seconds,
        "thread_seconds": p.thread_seconds,
        "shadow_test_seconds": p.shadow_seconds,
        "locate_seconds": p.locate_seconds,
        "locates": p.locates,
        "camera_rays": p.camera_rays,
        "bounce_rays": p.bounce_rays,
        "shadow_rays": s.shadow_rays,
        "occluded": s.occluded,
        "triangle_tests": s.triangle_tests,
        "lane_tests": s.lane_tests,
        "box_tests": s.box_tests,
        "blocker_tests": s.blocker_tests,
        "own_leaf_tests": s.own_leaf_tests,
        "answers": s.answers,
        "shadow_rays_per_second": s.shadow_rays as f64 / p.shadow_seconds.max(1e-9),
    }))
}

/// Prints the figures of a path-traced image on stderr.
pub fn print_stats(out: &Traced) {
    let p = &out.path;
    let s = out.stats;
    eprintln!("render           {:.3} s ({:.3} s summed over threads)", out.seconds, p.thread_seconds);
    eprintln!(
        "rays             {} camera, {} bounce, {} shadow ({:.1}% occluded)",
        p.camera_rays,
        p.bounce_rays,
        s.shadow_rays,
        100.0 * s.occluded as f64 / s.shadow_rays.max(1) as f64
    );
    eprintln!(
        "shadow tests     {:.3} s summed over threads ({:.1}% of it), {:.2} M shadow rays/s",
        p.shadow_seconds,
        100.0 * p.shadow_seconds / p.thread_seconds.max(1e-9),
        s.shadow_rays as f64 / p.shadow_seconds.max(1e-9) / 1e6
    );
    if p.locates > 0 {
        eprintln!(
            "locate leaves    {} vertices, {:.3} s summed over threads ({:.0} ns each)",
            p.locates,
            p.locate_seconds,
            1e9 * p.locate_seconds / p.locates as f64
        );
    }
}

/// Writes the image (PNG scaled by 2^`exposure`).
pub fn save(path: &std::path::Path, settings: &RenderSettings, exposure: f32, pixels: Vec<glam::Vec3>) -> Result<()> {
    let pixels = match plie::io::ImageFormat::from_path(path)? {
        plie::io::ImageFormat::Png if exposure != 0.0 => {
            let k = exposure.exp2();
            pixels.iter().map(|p| *p * k).collect()
        }
        _ => pixels,
    };
    plie::io::save_image(path, settings.width, settings.height, &pixels)
        .with_context(|| format!("cannot write {}", path.display()))
}
