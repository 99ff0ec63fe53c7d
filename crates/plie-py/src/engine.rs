//! The glue between the Python API and the plie library, in plain Rust (no Python types): scenes,
//! environments (octree + P-LIE), rendering with the CLI's defaults and semantics, and shadow queries.
//! Everything the bindings need from the library goes through this module, so a change of the
//! library's API touches only this file.

use std::path::Path;
use std::sync::OnceLock;
use std::time::Instant;

use glam::Vec3;
pub use plie::io::camera_path::CameraPath;
use plie::octree::{Octree, OctreeParams};
use plie::visibility::bvh::Bvh;
use plie::visibility::{Brute, BvhVisibility, NoVisibility, OctreeVisibility, QueryCtx, QueryStats, ShadowRay};
pub use plie::Camera;
use plie::Visibility;
use plie::{Environment, Grids, Integrator, Mode, Nee, PathSettings, PlieParams, Propagation, Regions};
use plie::{LightId, Scene, TriId};
use plie::{MaxBlockers, RefineParams};
use plie::{RenderSettings, Renderer};
use rayon::prelude::*;

pub use plie::Error;
pub type Result<T> = plie::Result<T>;

fn invalid(m: String) -> Error {
    Error::InvalidParameter(m)
}

/// A loaded scene with what renders and queries without an environment share, built on first use:
/// the scene BVH and the octree (the CLI's default parameters).
pub struct LoadedScene {
    pub scene: Scene,
    bvh: OnceLock<Bvh>,
    octree: OnceLock<Octree>,
}

impl LoadedScene {
    /// A built-in scene by name, else a scene file (reads confined to its folder unless
    /// `allow_outside_paths`), as `plie render --scene`.
    pub fn load(name_or_path: &str, allow_outside_paths: bool) -> Result<LoadedScene> {
        let scene = if plie::scene::builtin::exists(name_or_path) {
            plie::scene::builtin::load(name_or_path)?
        } else {
            let path = Path::new(name_or_path);
            if !path.exists() && path.extension().is_none() {
                // Neither a built-in name nor a file: the error lists the built-in names.
                plie::scene::builtin::load(name_or_path)?
            } else {
                plie::io::load_scene_with(path, plie::io::LoadOptions { allow_outside_paths })?
            }
        };
        Ok(LoadedScene { scene, bvh: OnceLock::new(), octree: OnceLock::new() })
    }

    pub fn bvh(&self) -> &Bvh {
        self.bvh.get_or_init(|| Bvh::build(&self.scene))
    }

    /// The octree with the CLI's default parameters (for mode `octree` without an environment).
    fn octree(&self) -> Result<&Octree> {
        if let Some(o) = self.octree.get() {
            return Ok(o);
        }
        let o = Octree::build(&self.scene, BuildOptions::default().params(false)?.octree())?;
        Ok(self.octree.get_or_init(|| o))
    }

    /// The visibility `mode` without an environment, over the structures kept here (as
    /// [`plie::Shadows::visibility`], which borrows the scene and so cannot live beside it).
    fn visibility(&self, mode: Mode) -> Result<Box<dyn Visibility + '_>> {
        let s = &self.scene;
        Ok(match mode {
            Mode::Brute => Box::new(Brute::new(s)),
            Mode::Octree => Box::new(OctreeVisibility::new(s, self.octree()?)),
            Mode::Bvh => Box::new(BvhVisibility::new(s, self.bvh())),
            Mode::None => Box::new(NoVisibility),
            m => {
                return Err(invalid(format!("mode {m} answers from a P-LIE: build or load an Environment and pass it")))
            }
        })
    }
}

/// The P-LIE build parameters as the CLI's options (`plie build`), with the CLI's defaults.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    pub max_triangles: usize,
    pub max_depth: u32,
    pub no_grids: bool,
    pub no_regions: bool,
    pub no_propagation: bool,
    /// `umbra`, `umbra-full`, `umbra-free`, `blockers`.
    pub refine: Vec<String>,
    pub max_split_depth: u32,
    /// A number, or `adaptive`.
    pub max_blockers: Option<String>,
    /// A number, or `None` for no cap.
    pub blocker_cap: Option<u32>,
}

impl Default for BuildOptions {
    fn default() -> BuildOptions {
        BuildOptions {
            max_triangles: 200,
            max_depth: OctreeParams::default().max_depth,
            no_grids: false,
            no_regions: false,
            no_propagation: false,
            refine: Vec::new(),
            max_split_depth: 2,
            max_blockers: None,
            blocker_cap: Some(plie::DEFAULT_BLOCKER_CAP),
        }
    }
}

impl BuildOptions {
    /// The validated parameters (as `plie_args::PlieArgs::params` of the CLI).
    pub fn params(&self, want_grids: bool) -> Result<PlieParams> {
        let mut umbra_full = false;
        let mut umbra_free = false;
        let mut blockers = false;
        for r in &self.refine {
            match r.as_str() {
                "umbra" => (umbra_full, umbra_free) = (true, true),
                "umbra-full" => umbra_full = true,
                "umbra-free" => umbra_free = true,
                "blockers" => blockers = true,
                other => {
                    return Err(invalid(format!(
                        "refine: unknown criterion '{other}' (umbra, umbra-full, umbra-free, blockers)"
                    )))
                }
            }
        }
        let max_blockers = match self.max_blockers.as_deref() {
            None => None,
            Some("adaptive") => Some(MaxBlockers::Adaptive),
            Some(n) => Some(MaxBlockers::Fixed(n.parse::<u32>().map_err(|_| {
                invalid(format!("max_blockers: expected a number of blockers or 'adaptive', not '{n}'"))
            })?)),
        };
        if blockers && max_blockers.is_none() {
            return Err(invalid("refine 'blockers' needs max_blockers (a number or 'adaptive')".into()));
        }
        if !blockers && max_blockers.is_some() {
            return Err(invalid("max_blockers only applies to refine 'blockers'".into()));
        }
        let p = PlieParams {
            max_triangles: self.max_triangles,
            max_depth: self.max_depth,
            grids: if want_grids && !self.no_grids { Grids::Build } else { Grids::Skip },
            regions: if self.no_regions { Regions::Skip } else { Regions::Compute },
            propagation: if self.no_propagation { Propagation::Off } else { Propagation::On },
            refine: RefineParams {
                umbra_full,
                umbra_free,
                blockers: max_blockers.filter(|_| blockers),
                max_split_depth: self.max_split_depth,
            },
            blocker_cap: self.blocker_cap,
        };
        p.validate()?;
        Ok(p)
    }
}

/// An environment (octree + P-LIE, [`plie::Environment`]) with the figures of its build or load.
pub struct Env {
    pub env: Environment,
    /// Construction figures as JSON, when built here.
    pub stats_json: Option<String>,
    /// Seconds building or loading.
    pub seconds: f64,
}

impl Env {
    /// Builds the octree and the P-LIE (refined if the parameters ask), lifting the blocker cap with
    /// `lift_clips` clips per scene triangle ([`plie::BuildOptions::lift_clips`]) and gathering the
    /// cells of the records still over it with `cell_clips` ([`plie::BuildOptions::cell_clips`]).
    pub fn build(
        scene: &LoadedScene,
        params: PlieParams,
        lift_clips: Option<usize>,
        cell_clips: Option<usize>,
    ) -> Result<Env> {
        let t = Instant::now();
        let options = plie::BuildOptions { lift_clips, cell_clips, ..Default::default() };
        let (env, stats) = Environment::build_with(&scene.scene, &params, options)?;
        let stats_json = serde_json::to_string(&stats).ok();
        Ok(Env { env, stats_json, seconds: t.elapsed().as_secs_f64() })
    }

    /// Saves it as a `.plie` file (atomically); returns the bytes written.
    pub fn save(&self, scene: &LoadedScene, path: &Path) -> Result<u64> {
        self.env.save(path, &scene.scene)
    }

    /// Loads a `.plie` file built for `scene`.
    pub fn load(scene: &LoadedScene, path: &Path) -> Result<Env> {
        let t = Instant::now();
        let env = Environment::load(path, &scene.scene, None)?;
        Ok(Env { env, stats_json: None, seconds: t.elapsed().as_secs_f64() })
    }

    /// Loads a `.plie` file's bytes (e.g. from a distributed object store) built for `scene`.
    pub fn from_bytes(scene: &LoadedScene, bytes: &[u8]) -> Result<Env> {
        let t = Instant::now();
        let env = Environment::load_bytes(bytes, "<.plie bytes>", &scene.scene, None)?;
        Ok(Env { env, stats_json: None, seconds: t.elapsed().as_secs_f64() })
    }

    /// The fastest mode it supports (as `plie render --plie` without `--visibility`).
    pub fn best_mode(&self) -> Mode {
        self.env.best_mode()
    }

    /// Octree leaves.
    pub fn leaves(&self) -> usize {
        self.env.octree().leaf_count()
    }
}

/// The estimator options of `plie render`, with its defaults.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub eye_rays: u32,
    pub shadow_rays: u32,
    pub seed: u64,
    pub spp: Option<u32>,
    /// `direct` or `path`.
    pub integrator: String,
    pub max_path_depth: i32,
    pub rr_depth: Option<u32>,
    /// `power` or `all`.
    pub nee: String,
    pub threads: Option<usize>,
}

/// A rendered image and its figures.
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Linear radiance, row-major, top row first.
    pub pixels: Vec<Vec3>,
    pub stats: QueryStats,
    pub mode: Mode,
    pub seconds: f64,
}

/// Parses a visibility mode name.
pub fn mode(name: &str) -> Result<Mode> {
    name.parse::<Mode>().map_err(|e| invalid(format!("visibility: {e}")))
}

/// Renders as `plie render` does with the same options: the same image, bit for bit.
pub fn render(
    scene: &LoadedScene,
    camera: Option<Camera>,
    visibility: Option<&str>,
    env: Option<&Env>,
    o: &RenderOptions,
) -> Result<Image> {
    let mut settings = RenderSettings {
        width: o.width,
        height: o.height,
        eye_rays: o.eye_rays,
        shadow_rays: o.shadow_rays,
        seed: o.seed,
    };
    let path = match o.integrator.as_str() {
        "direct" => {
            if let Some(s) = o.spp {
                let r = (s as f64).sqrt().round() as u32;
                if r * r != s || s == 0 {
                    return Err(invalid(format!(
                        "spp {s}: direct light takes K x K eye rays per pixel, so spp must be a square (1, 4, 9, ...)"
                    )));
                }
                settings.eye_rays = r;
            }
            None
        }
        "path" => {
            let nee = match o.nee.as_str() {
                "power" => Nee::Power,
                "all" => Nee::All,
                n => return Err(invalid(format!("nee: '{n}' is neither 'power' nor 'all'"))),
            };
            let p = PathSettings {
                spp: o.spp.unwrap_or(o.eye_rays * o.eye_rays),
                max_depth: o.max_path_depth,
                rr_depth: o.rr_depth,
                nee,
            };
            p.validate()?;
            Some(p)
        }
        i => return Err(invalid(format!("integrator: '{i}' is neither 'direct' nor 'path'"))),
    };
    settings.validate()?;
    let camera = camera.unwrap_or_else(|| scene.scene.camera_or_default());
    camera.validate()?;
    let m = match (visibility.map(mode).transpose()?, env) {
        (Some(m), _) => m,
        (None, Some(e)) => e.best_mode(),
        (None, None) => Mode::Bvh,
    };
    let integrator = match path {
        None => Integrator::Direct,
        Some(p) => Integrator::Path(p),
    };
    let renderer = Renderer::new().settings(settings).camera(camera).integrator(integrator);
    let t = Instant::now();
    let img = with_threads(o.threads, || match env {
        Some(e) => renderer.render(&scene.scene, m, Some(&e.env)),
        // A P-LIE mode without an environment builds one with the CLI's defaults, as `plie render`.
        None if m.needs_plie() => {
            let built = Env::build(
                scene,
                BuildOptions::default().params(m == Mode::Grid)?,
                Some(plie::DEFAULT_LIFT_CLIPS),
                Some(plie::DEFAULT_CELL_CLIPS),
            )?;
            renderer.render(&scene.scene, m, Some(&built.env))
        }
        None => {
            let vis = scene.visibility(m)?;
            renderer.render_with(&scene.scene, scene.bvh(), None, vis.as_ref())
        }
    })?;
    Ok(Image {
        width: img.width,
        height: img.height,
        pixels: img.pixels,
        stats: img.stats,
        mode: m,
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// Runs `f` on a pool of `threads` workers (the global pool when `None`).
fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> Result<T> + Send) -> Result<T> {
    let Some(t) = threads else { return f() };
    if !(1..=1024).contains(&t) {
        return Err(invalid(format!("threads {t} must be between 1 and 1024")));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(t)
        .build()
        .map_err(|e| invalid(format!("threads {t}: cannot start the worker threads ({e})")))?;
    pool.install(f)
}

/// One shadow segment: from `x` (on triangle `origin_tri`, or on none) to `y` on light `light`.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    pub x: [f64; 3],
    pub y: [f64; 3],
    pub light: i64,
    pub origin_tri: Option<i64>,
}

/// Answers shadow segments with a visibility mode (`bvh` by default, the environment's best with one):
/// `true` where something other than the origin triangle and the light's own triangles blocks the open
/// segment. Every exact mode gives the same answers.
pub fn occluded(
    scene: &LoadedScene,
    segments: &[Segment],
    visibility: Option<&str>,
    env: Option<&Env>,
) -> Result<Vec<bool>> {
    let s = &scene.scene;
    let mut rays = Vec::with_capacity(segments.len());
    for (i, seg) in segments.iter().enumerate() {
        let bad = |m: String| invalid(format!("segment {i}: {m}"));
        if !(seg.x.iter().chain(&seg.y).all(|c| c.is_finite())) {
            return Err(bad("non-finite coordinate".into()));
        }
        if seg.light < 0 || seg.light as usize >= s.lights.len() {
            return Err(bad(format!("light {} does not exist (the scene has {})", seg.light, s.lights.len())));
        }
        let tri = match seg.origin_tri {
            None => TriId(u32::MAX),
            Some(t) if t >= 0 && (t as usize) < s.triangles.len() => TriId(t as u32),
            Some(t) => return Err(bad(format!("triangle {t} does not exist (the scene has {})", s.triangles.len()))),
        };
        let v = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
        rays.push(ShadowRay::new(v(seg.x), v(seg.y), LightId(seg.light as u32), tri, None));
    }
    let m = match (visibility.map(mode).transpose()?, env) {
        (Some(m), _) => m,
        (None, Some(e)) => e.best_mode(),
        (None, None) => Mode::Bvh,
    };
    let vis = match env {
        Some(e) => e.env.visibility(m, s)?,
        None => scene.visibility(m)?,
    };
    let n = s.triangles.len();
    Ok(rays.par_iter().map_init(|| QueryCtx::new(n), |ctx, r| vis.occluded(r, ctx)).collect())
}

/// A camera path ([`plie::io::camera_path::CameraPath`]) from JSON text or a file.
pub fn camera_path(text: Option<&str>, file: Option<&Path>) -> Result<CameraPath> {
    match (text, file) {
        (Some(t), _) => CameraPath::from_json(t),
        (None, Some(f)) => CameraPath::load(f),
        (None, None) => Err(invalid("camera path: give JSON text or a file".into())),
    }
}

/// Writes an image of linear radiance (row-major, top row first) as `plie render -o` does: the format
/// of the extension (PNG tone-mapped, radiance scaled by 2^`exposure` first; EXR and PFM linear),
/// atomically.
pub fn save_image(path: &Path, width: u32, height: u32, rgb: &[f32], exposure: f32) -> Result<()> {
    if !exposure.is_finite() {
        return Err(invalid("exposure must be a finite number".into()));
    }
    let png = plie::io::ImageFormat::from_path(path)? == plie::io::ImageFormat::Png;
    let k = if png && exposure != 0.0 { exposure.exp2() } else { 1.0 };
    let pixels: Vec<Vec3> = rgb.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2]) * k).collect();
    plie::io::save_image(path, width, height, &pixels)
}
