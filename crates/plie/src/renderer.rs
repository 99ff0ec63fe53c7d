//! Rendering in one call (SPEC §2, §8 point 6): a [`Renderer`] holds the image settings, the camera
//! and the integrator (direct light, or the path tracer), and renders a scene with a visibility mode
//! ([`Renderer::render`]) or with any [`Visibility`] ([`Renderer::render_with`]).

use std::path::Path;

use glam::Vec3;

use crate::environment::Environment;
use crate::error::{Error, Result};
use crate::octree::Octree;
use crate::progress::{NoProgress, Progress};
use crate::render::path::{render_path, PathSettings, PathStats};
use crate::render::{render as render_direct, RenderSettings};
use crate::scene::{Camera, Scene};
use crate::visibility::bvh::Bvh;
use crate::visibility::{Mode, QueryStats, Shadows, Visibility};

/// Which estimator renders the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Integrator {
    /// Direct light only (SPEC §2): K x K regular eye rays per pixel, N shadow rays per light each.
    Direct,
    /// Path tracing (global illumination) with next-event estimation through the visibility mode.
    Path(PathSettings),
}

/// Rendering settings, built up by methods, then [`Renderer::render`].
///
/// ```
/// # fn main() -> plie::Result<()> {
/// let scene = plie::scene::builtin::load("cornell-cube-1")?;
/// let image = plie::Renderer::new().size(16, 12).shadow_rays(4).render(&scene, plie::Mode::Bvh, None)?;
/// assert_eq!(image.pixels.len(), 16 * 12);
/// # Ok(()) }
/// ```
#[derive(Clone, Copy)]
pub struct Renderer<'p> {
    settings: RenderSettings,
    camera: Option<Camera>,
    integrator: Integrator,
    progress: &'p dyn Progress,
}

impl Default for Renderer<'_> {
    fn default() -> Self {
        Renderer::new()
    }
}

/// Timings of a rendered image, by integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Timing {
    /// Direct light.
    Direct {
        /// Seconds spent on the hit buffer (pass 1).
        hit_buffer_seconds: f64,
        /// Seconds spent shading (pass 2), the figure the thesis reports.
        shading_seconds: f64,
        /// CPU seconds of the process during shading, all threads (`None` where the platform does
        /// not say).
        shading_cpu_seconds: Option<f64>,
    },
    /// The path tracer.
    Path {
        /// Wall-clock seconds of the whole render.
        seconds: f64,
        /// Rays by kind and timings.
        path: PathStats,
    },
}

/// A rendered image: linear radiance with its counters and timings.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear radiance per pixel, row-major, top row first.
    pub pixels: Vec<Vec3>,
    /// Visibility counters (shadow rays).
    pub stats: QueryStats,
    /// Timings.
    pub timing: Timing,
}

impl Image {
    /// Writes the image; the extension picks the format (`.png` tone-mapped sRGB, `.exr` and `.pfm`
    /// linear radiance). Atomic.
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::io::save_image(path, self.width, self.height, &self.pixels)
    }
}

impl<'p> Renderer<'p> {
    /// The thesis' image settings ([`RenderSettings::default`]: 398 x 398, 2 x 2 eye rays, 25 shadow
    /// rays per light), direct light, the scene's camera.
    pub fn new() -> Renderer<'static> {
        Renderer {
            settings: RenderSettings::default(),
            camera: None,
            integrator: Integrator::Direct,
            progress: &NoProgress,
        }
    }

    /// All image settings at once.
    pub fn settings(mut self, settings: RenderSettings) -> Self {
        self.settings = settings;
        self
    }

    /// Image size in pixels.
    pub fn size(mut self, width: u32, height: u32) -> Self {
        (self.settings.width, self.settings.height) = (width, height);
        self
    }

    /// Direct light: K x K regular eye rays per pixel.
    pub fn eye_rays(mut self, k: u32) -> Self {
        self.settings.eye_rays = k;
        self
    }

    /// N-rooks shadow rays per light per eye ray (per path vertex for the path tracer).
    pub fn shadow_rays(mut self, n: u32) -> Self {
        self.settings.shadow_rays = n;
        self
    }

    /// Seed of the random streams: the same seed gives the same image in every exact mode.
    pub fn seed(mut self, seed: u64) -> Self {
        self.settings.seed = seed;
        self
    }

    /// The camera (default: the scene's, or one framing the whole scene).
    pub fn camera(mut self, camera: Camera) -> Self {
        self.camera = Some(camera);
        self
    }

    /// The estimator (default: [`Integrator::Direct`]).
    pub fn integrator(mut self, integrator: Integrator) -> Self {
        self.integrator = integrator;
        self
    }

    /// Reports progress to `progress`.
    pub fn progress<'q>(self, progress: &'q dyn Progress) -> Renderer<'q> {
        Renderer { settings: self.settings, camera: self.camera, integrator: self.integrator, progress }
    }

    /// The image settings.
    pub fn image_settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// Checks the settings (sizes, counts, the path tracer's depth) without rendering.
    pub fn validate(&self) -> Result<()> {
        self.settings.validate()?;
        if let Integrator::Path(p) = &self.integrator {
            p.validate()?;
        }
        Ok(())
    }

    /// Renders `scene` with visibility `mode`. The P-LIE modes answer from `env` (which must be
    /// given and belong to `scene`); the other modes build what they need (the BVH, the octree).
    pub fn render(&self, scene: &Scene, mode: Mode, env: Option<&Environment>) -> Result<Image> {
        self.validate()?;
        match env {
            Some(env) => {
                let vis = env.visibility(mode, scene)?;
                self.render_with(scene, env.bvh(scene), Some(env.octree()).filter(|_| mode.needs_plie()), vis.as_ref())
            }
            None if mode.needs_plie() => Err(Error::InvalidParameter(format!(
                "mode {mode} answers from a P-LIE: build or load an Environment and pass it"
            ))),
            None => {
                let shadows = Shadows::new(scene);
                let vis = shadows.visibility(mode)?;
                self.render_with(scene, shadows.bvh(), None, vis.as_ref())
            }
        }
    }

    /// Renders `scene` with the visibility `vis` (any [`Visibility`], a P-LIE's or your own). `bvh`
    /// finds the eye rays' and bounce rays' closest hits; `octree`, when given, locates each shaded
    /// point's leaf ([`crate::visibility::ShadowRay::leaf`]), which the P-LIE modes need.
    pub fn render_with(
        &self,
        scene: &Scene,
        bvh: &Bvh,
        octree: Option<&Octree>,
        vis: &dyn Visibility,
    ) -> Result<Image> {
        let camera = self.camera.unwrap_or_else(|| scene.camera_or_default());
        let (width, height) = (self.settings.width, self.settings.height);
        match &self.integrator {
            Integrator::Direct => {
                let r = render_direct(scene, &camera, &self.settings, bvh, octree, vis, self.progress)?;
                let timing = Timing::Direct {
                    hit_buffer_seconds: r.hit_buffer_seconds,
                    shading_seconds: r.shading_seconds,
                    shading_cpu_seconds: r.shading_cpu_seconds,
                };
                Ok(Image { width, height, pixels: r.pixels, stats: r.stats, timing })
            }
            Integrator::Path(p) => {
                let r = render_path(scene, &camera, &self.settings, p, bvh, octree, vis, self.progress)?;
                let timing = Timing::Path { seconds: r.seconds, path: r.path };
                Ok(Image { width, height, pixels: r.pixels, stats: r.stats, timing })
            }
        }
    }
}
