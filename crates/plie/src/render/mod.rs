//! Rendering, SPEC §2: the hit buffer (pass 1), then shading (pass 2) with a chosen visibility method.

pub mod cpu_time;
pub mod hit_buffer;
pub mod memory;
pub mod path;
pub mod sampler;
pub mod shade;

use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::octree::Octree;
pub use crate::progress::{NoProgress, Progress};
use crate::scene::{Camera, Scene};
use crate::visibility::bvh::Bvh;
use crate::visibility::{QueryStats, Visibility};
pub use hit_buffer::{Hit, HitBuffer};

/// Image settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RenderSettings {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// K: K x K regular eye rays per pixel.
    pub eye_rays: u32,
    /// N: N-rooks shadow rays per light per eye ray.
    pub shadow_rays: u32,
    /// Seed of the random streams.
    pub seed: u64,
}

impl Default for RenderSettings {
    /// The thesis' image settings (SPEC §6): 398 x 398, 2 x 2 eye rays, 25 shadow rays per light.
    fn default() -> RenderSettings {
        RenderSettings { width: 398, height: 398, eye_rays: 2, shadow_rays: 25, seed: 0 }
    }
}

impl RenderSettings {
    /// Checks the settings: sizes and counts positive and not absurd.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(m));
        if self.width == 0 || self.height == 0 || self.width > 32768 || self.height > 32768 {
            return bad(format!("image size {}x{} must be between 1 and 32768", self.width, self.height));
        }
        if self.eye_rays == 0 || self.eye_rays > 64 {
            return bad(format!("eye rays per pixel axis {} must be between 1 and 64", self.eye_rays));
        }
        if self.shadow_rays == 0 || self.shadow_rays > 4096 {
            return bad(format!("shadow rays per light {} must be between 1 and 4096", self.shadow_rays));
        }
        Ok(())
    }
}

/// A rendered image with its timings and counters.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Linear radiance per pixel, row-major, top row first.
    pub pixels: Vec<Vec3>,
    /// Seconds spent on the hit buffer (pass 1).
    pub hit_buffer_seconds: f64,
    /// Seconds spent shading (pass 2), the figure the thesis reports.
    pub shading_seconds: f64,
    /// CPU seconds the process used during shading, all threads together (`None` where the
    /// platform does not say): less disturbed by other load on the machine than the wall time.
    pub shading_cpu_seconds: Option<f64>,
    /// Visibility counters of pass 2.
    pub stats: QueryStats,
}

/// Renders `scene` from `camera`: hit buffer with `bvh` (and leaves from `octree` if given), then shading
/// with `vis`.
pub(crate) fn render(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    bvh: &Bvh,
    octree: Option<&Octree>,
    vis: &dyn Visibility,
    progress: &dyn Progress,
) -> Result<Rendered> {
    settings.validate()?;
    camera.validate()?;
    // The hits of the eye rays, and the pixels twice (the image and its output).
    let (w, h, k) = (settings.width, settings.height, settings.eye_rays);
    let per_pixel = u128::from(k * k) * std::mem::size_of::<Option<Hit>>() as u128 + 2 * 12;
    memory::check(u128::from(w) * u128::from(h) * per_pixel, (w, h, k))?;
    let t0 = Instant::now();
    let hits = HitBuffer::build(scene, camera, (settings.width, settings.height, settings.eye_rays), bvh, octree);
    let hit_buffer_seconds = t0.elapsed().as_secs_f64();
    let (t1, c1) = (Instant::now(), cpu_time::process_cpu_seconds());
    let (pixels, stats) = shade::shade(scene, &hits, vis, settings.shadow_rays, settings.seed, progress);
    let shading_seconds = t1.elapsed().as_secs_f64();
    let shading_cpu_seconds = c1.zip(cpu_time::process_cpu_seconds()).map(|(a, b)| b - a);
    Ok(Rendered { pixels, hit_buffer_seconds, shading_seconds, shading_cpu_seconds, stats })
}
