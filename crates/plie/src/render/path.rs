//! Global illumination (SPEC §8 point 6, the thesis' future work §9.2.5): a unidirectional path tracer
//! whose next-event estimation asks the chosen visibility mode, so the P-LIE answers shadow rays from
//! points anywhere in the scene, not only from the eye rays' hits.
//!
//! The estimator, with Lambertian surfaces (`f_r = albedo / pi`):
//! - paths start at a uniformly jittered point of the pixel; bounce directions are cosine-weighted
//!   (`pdf = cos / pi`), so the throughput is multiplied by the albedo at every bounce;
//! - at every vertex, next-event estimation: `N` N-rooks samples on every light ([`Nee::All`], the
//!   estimator of direct mode) or on one light chosen with probability proportional to its power
//!   ([`Nee::Power`], the CLI's default: as noisy per path on two-light scenes, with half the shadow
//!   rays); shadow rays go through [`Visibility::occluded_light`];
//! - multiple importance sampling with the power heuristic between the light samples and the bounce
//!   rays that hit a light's front: with `N` light samples of density `p_l` (solid angle, times the
//!   light's selection probability) and one bounce of density `p_b`, the weights are
//!   `(N p_l)^2 / ((N p_l)^2 + p_b^2)` and `p_b^2 / ((N p_l)^2 + p_b^2)`;
//! - emission seen directly (by the eye ray) is counted once, with weight 1;
//! - `max_depth` counts as Mitsuba 3's: 1 is emission seen directly, 2 direct light, 3 adds one
//!   bounce, -1 unbounded; Russian roulette from `rr_depth` on (survival `min(max throughput, 0.95)`).
//!
//! Bounce rays find their closest hit with the BVH, whatever the visibility mode. Random streams are
//! keyed by (seed, pixel, sample, bounce, purpose), and the floating-point operations depend only on
//! them and the visibility answers, so exact modes give bit-identical images for any thread count.

use std::f32::consts::{FRAC_1_PI, PI};
use std::time::Instant;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::hit_buffer::Hit;
use super::sampler::{n_rooks, Rng};
use super::{Progress, RenderSettings};
use crate::error::{Error, Result};
use crate::octree::Octree;
use crate::scene::{Camera, LightId, Scene, TriId};
use crate::visibility::bvh::Bvh;
use crate::visibility::{LightRays, QueryCtx, QueryStats, Visibility};

/// Which lights next-event estimation samples at a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Nee {
    /// `N` samples on every light (as direct mode).
    All,
    /// `N` samples on one light, chosen with probability proportional to its power (area times the
    /// mean of its RGB radiance).
    Power,
}

/// The path tracer's settings (the image settings are [`RenderSettings`]; its `eye_rays` is unused).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PathSettings {
    /// Paths per pixel.
    pub spp: u32,
    /// Longest path, counted as Mitsuba 3's `max_depth` (1: emission seen directly, 2: direct light,
    /// -1: unbounded).
    pub max_depth: i32,
    /// Russian roulette from this many bounces on (`None`: never).
    pub rr_depth: Option<u32>,
    /// Light selection of next-event estimation.
    pub nee: Nee,
}

impl PathSettings {
    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(m));
        if self.spp == 0 || self.spp > 1 << 20 {
            return bad(format!("samples per pixel {} must be between 1 and 1048576", self.spp));
        }
        if self.max_depth == 0 || self.max_depth < -1 {
            return bad(format!("max depth {} must be -1 (unbounded) or at least 1", self.max_depth));
        }
        Ok(())
    }
}

/// Counters of a path-traced image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PathStats {
    /// Eye rays traced (one per path).
    pub camera_rays: u64,
    /// Bounce rays traced (closest hit with the BVH).
    pub bounce_rays: u64,
    /// Octree point locations of path vertices (only when an octree is given).
    pub locates: u64,
    /// Seconds inside [`Visibility::occluded_light`], summed over threads (timed per call).
    pub shadow_seconds: f64,
    /// Seconds in [`Octree::locate`], summed over threads (timed per call).
    pub locate_seconds: f64,
    /// Seconds of path tracing, summed over threads (timed per image row).
    pub thread_seconds: f64,
}

impl std::ops::AddAssign for PathStats {
    fn add_assign(&mut self, o: PathStats) {
        self.camera_rays += o.camera_rays;
        self.bounce_rays += o.bounce_rays;
        self.locates += o.locates;
        self.shadow_seconds += o.shadow_seconds;
        self.locate_seconds += o.locate_seconds;
        self.thread_seconds += o.thread_seconds;
    }
}

/// A path-traced image with its counters.
#[derive(Clone, Debug)]
pub struct PathRendered {
    /// Linear radiance per pixel, row-major, top row first.
    pub pixels: Vec<Vec3>,
    /// Wall-clock seconds of the whole render.
    pub seconds: f64,
    /// Visibility counters (shadow rays).
    pub stats: QueryStats,
    /// Rays by kind and timings.
    pub path: PathStats,
}

/// What a random stream is for; with the bounce, the stream's third key.
#[derive(Clone, Copy)]
enum Purpose {
    Pixel = 1,
    Light = 2,
    Select = 3,
    Bounce = 4,
    Roulette = 5,
}

#[inline]
fn key(bounce: u32, purpose: Purpose, light: u32) -> u64 {
    ((bounce as u64) << 32) | ((purpose as u64) << 24) | light as u64
}

/// The power heuristic's weight of strategy `a` against `b` (densities times sample counts).
#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// A unit vector about `n` (unit) with density `cos / pi`, from `u` in the unit square, and its cosine.
fn cosine_sample(n: Vec3, u: Vec2) -> (Vec3, f32) {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let z = (1.0 - u.x).max(0.0).sqrt();
    // Duff et al. 2017, an orthonormal basis without branches on the normal's direction.
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    let d = t * (r * phi.cos()) + bt * (r * phi.sin()) + n * z;
    (d.normalize(), z)
}

/// Per-thread scratch space.
struct Scratch {
    ctx: QueryCtx,
    samples: Vec<Vec2>,
    targets: Vec<Vec3>,
    weights: Vec<f32>,
    occluded: Vec<bool>,
    stats: PathStats,
}

/// Everything a path needs that does not change per path.
struct Tracer<'a> {
    scene: &'a Scene,
    bvh: &'a Bvh,
    octree: Option<&'a Octree>,
    vis: &'a dyn Visibility,
    settings: &'a PathSettings,
    seed: u64,
    n: u32,
    /// Selection probability of each light under [`Nee::Power`] (all 1 under [`Nee::All`]).
    select: Vec<f32>,
    /// Cumulative `select`, for choosing under [`Nee::Power`].
    select_cdf: Vec<f32>,
    t_min: f32,
}

impl Tracer<'_> {
    /// Next-event estimation at `hit` (albedo `albedo`): the light's contribution, MIS-weighted
    /// against a bounce of density `cos / pi`.
    fn next_event(&self, hit: &Hit, albedo: Vec3, stream: (u64, u64, u32), s: &mut Scratch) -> Vec3 {
        let (pixel, sample, bounce) = stream;
        let chosen = match self.settings.nee {
            Nee::All => None,
            Nee::Power => {
                let mut rng = Rng::stream(self.seed, pixel, sample, key(bounce, Purpose::Select, 0));
                let u = rng.next_f32();
                Some(self.select_cdf.partition_point(|&c| c <= u).min(self.select.len() - 1))
            }
        };
        let mut l = Vec3::ZERO;
        let n = self.n as f32;
        for (i, light) in self.scene.lights.iter().enumerate() {
            if chosen.is_some_and(|c| c != i) {
                continue;
            }
            let p_select = self.select[i];
            if p_select <= 0.0 {
                // A light too faint to be chosen by power, picked by the rounding of the last step.
                continue;
            }
            let mut rng = Rng::stream(self.seed, pixel, sample, key(bounce, Purpose::Light, i as u32));
            n_rooks(&mut rng, &mut s.samples);
            s.targets.clear();
            s.weights.clear();
            for &u in &s.samples {
                let y = light.sample(u);
                let d = y - hit.point;
                let dist2 = d.length_squared();
                if dist2.is_nan() || dist2 <= 0.0 {
                    continue;
                }
                let inv_len = dist2.sqrt().recip();
                let cos_x = hit.normal.dot(d) * inv_len;
                let cos_y = -light.normal.dot(d) * inv_len;
                if cos_x <= 0.0 || cos_y <= 0.0 {
                    continue;
                }
                let p_light = p_select * dist2 / (cos_y * light.area);
                let w = power_heuristic(n * p_light, cos_x * FRAC_1_PI);
                s.targets.push(y);
                s.weights.push(w * cos_x * cos_y / dist2);
            }
            let m = s.targets.len();
            if m == 0 {
                continue;
            }
            let rays = LightRays {
                origin: hit.point,
                origin_tri: hit.tri,
                leaf: hit.leaf,
                light: LightId(i as u32),
                targets: &s.targets,
            };
            let occluded = &mut s.occluded[..m];
            let t = Instant::now();
            self.vis.occluded_light(&rays, occluded, &mut s.ctx);
            s.stats.shadow_seconds += t.elapsed().as_secs_f64();
            let sum = super::shade::unoccluded_sum(&s.weights, occluded, &mut s.ctx.stats);
            l += light.radiance * albedo * FRAC_1_PI * (light.area / (n * p_select) * sum);
        }
        l
    }

    /// The closest hit of a ray, as a [`Hit`] (leaf located if an octree is given).
    fn intersect(&self, o: Vec3, d: Vec3, from: Option<TriId>, s: &mut Scratch) -> Option<Hit> {
        let t_min = if from.is_some() { self.t_min } else { 0.0 };
        let (tri, t) = self.bvh.closest_hit_from(self.scene, o, d, t_min, from)?;
        let point = o + d * t;
        let n = self.scene.triangles[tri.idx()].normal();
        let front = n.dot(d) < 0.0;
        let leaf = self.octree.and_then(|oc| {
            let t0 = Instant::now();
            let leaf = oc.locate(point);
            s.stats.locate_seconds += t0.elapsed().as_secs_f64();
            s.stats.locates += 1;
            leaf
        });
        Some(Hit { point, normal: if front { n } else { -n }, dir: d, tri, front, leaf })
    }

    /// The radiance of one path through the image point `(o, d)`.
    fn trace(&self, mut o: Vec3, mut d: Vec3, pixel: u64, sample: u64, s: &mut Scratch) -> Vec3 {
        let scene = self.scene;
        let max_depth = self.settings.max_depth;
        let mut l = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        let mut from: Option<TriId> = None;
        // Density (solid angle) of the bounce that made the current ray.
        let mut bounce_pdf = 0.0f32;
        let mut depth: u32 = 0;
        while let Some(hit) = self.intersect(o, d, from, s) {
            let material = scene.material_of(hit.tri);
            if hit.front && material.is_emissive() {
                let w = match (from, scene.tri_light[hit.tri.idx()]) {
                    (Some(_), Some(li)) => {
                        let light = &scene.lights[li.idx()];
                        let dist2 = (hit.point - o).length_squared();
                        let cos_y = light.normal.dot(-d).max(1e-12);
                        let p_light = self.select[li.idx()] * dist2 / (cos_y * light.area);
                        power_heuristic(bounce_pdf, self.n as f32 * p_light)
                    }
                    _ => 1.0,
                };
                l += throughput * material.emission * w;
            }
            if max_depth >= 0 && depth as i64 + 1 >= max_depth as i64 {
                break;
            }
            let albedo = scene.albedo_at(hit.tri, hit.point);
            if albedo == Vec3::ZERO {
                break;
            }
            l += throughput * self.next_event(&hit, albedo, (pixel, sample, depth), s);
            let mut rng = Rng::stream(self.seed, pixel, sample, key(depth, Purpose::Bounce, 0));
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let (dir, cos) = cosine_sample(hit.normal, u);
            throughput *= albedo;
            depth += 1;
            if self.settings.rr_depth.is_some_and(|k| depth >= k) {
                let q = throughput.max_element().min(0.95);
                let mut rng = Rng::stream(self.seed, pixel, sample, key(depth, Purpose::Roulette, 0));
                if rng.next_f32() >= q {
                    break;
                }
                throughput /= q;
            }
            if throughput.max_element() <= 0.0 || cos <= 0.0 {
                break;
            }
            s.stats.bounce_rays += 1;
            o = hit.point;
            d = dir;
            from = Some(hit.tri);
            bounce_pdf = cos * FRAC_1_PI;
        }
        l
    }
}

/// Path-traces `scene` from `camera`: `path.spp` paths per pixel, `settings.shadow_rays` light samples
/// per light at every vertex, shadow rays answered by `vis`. `octree`, when given, locates every path
/// vertex's leaf (the P-LIE modes need it).
#[allow(clippy::too_many_arguments)]
pub fn render_path(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    path: &PathSettings,
    bvh: &Bvh,
    octree: Option<&Octree>,
    vis: &dyn Visibility,
    progress: &dyn Progress,
) -> Result<PathRendered> {
    settings.validate()?;
    path.validate()?;
    // The pixels twice (the image and its output).
    let (w, h) = (settings.width, settings.height);
    super::memory::check(u128::from(w) * u128::from(h) * 2 * 12, (w, h, settings.eye_rays))?;
    camera.validate()?;
    let t0 = Instant::now();
    // In f64: a light's power may be below f32's range (a faint light), or their sum above it.
    let power: Vec<f64> =
        scene.lights.iter().map(|l| f64::from(l.area) * f64::from(l.radiance.element_sum()) / 3.0).collect();
    let total: f64 = power.iter().sum();
    let select: Vec<f32> = match path.nee {
        Nee::Power if total > 0.0 && total.is_finite() => power.iter().map(|p| (p / total) as f32).collect(),
        // No light with power to speak of: each as likely (what they add is as good as nothing).
        Nee::Power => vec![1.0 / scene.lights.len() as f32; scene.lights.len()],
        Nee::All => vec![1.0; scene.lights.len()],
    };
    let mut acc = 0.0;
    let select_cdf = select
        .iter()
        .map(|p| {
            acc += p;
            acc
        })
        .collect();
    let tracer = Tracer {
        scene,
        bvh,
        octree,
        vis,
        settings: path,
        seed: settings.seed,
        n: settings.shadow_rays,
        select,
        select_cdf,
        t_min: 1e-6 * scene.scale(),
    };
    let (w, h) = (settings.width as usize, settings.height as usize);
    let frame = camera.frame(settings.width, settings.height);
    let n = settings.shadow_rays as usize;
    let mut image = vec![Vec3::ZERO; w * h];
    progress.start("path tracing", h as u64);
    let (stats, path_stats) = image
        .par_chunks_mut(w)
        .enumerate()
        .map_init(
            || Scratch {
                ctx: QueryCtx::new(scene.triangles.len()),
                samples: vec![Vec2::ZERO; n],
                targets: Vec::with_capacity(n),
                weights: Vec::with_capacity(n),
                occluded: vec![false; n],
                stats: PathStats::default(),
            },
            |s, (py, row)| {
                let t = Instant::now();
                for (px, out) in row.iter_mut().enumerate() {
                    let pixel = (py * w + px) as u64;
                    let mut sum = Vec3::ZERO;
                    for j in 0..path.spp as u64 {
                        let mut rng = Rng::stream(settings.seed, pixel, j, key(0, Purpose::Pixel, 0));
                        let (x, y) = (px as f32 + rng.next_f32(), py as f32 + rng.next_f32());
                        let (o, d) = frame.ray(x, y);
                        s.stats.camera_rays += 1;
                        sum += tracer.trace(o, d, pixel, j, s);
                    }
                    *out = sum / path.spp as f32;
                }
                s.stats.thread_seconds += t.elapsed().as_secs_f64();
                progress.advance(1);
                (std::mem::take(&mut s.ctx.stats), std::mem::take(&mut s.stats))
            },
        )
        .reduce(
            || (QueryStats::default(), PathStats::default()),
            |mut a, b| {
                a.0 += b.0;
                a.1 += b.1;
                a
            },
        );
    progress.finish();
    Ok(PathRendered { pixels: image, seconds: t0.elapsed().as_secs_f64(), stats, path: path_stats })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_samples_lie_about_the_normal() {
        let mut rng = Rng::stream(1, 2, 3, 4);
        for n in [Vec3::Y, -Vec3::Z, Vec3::new(0.3, -0.4, 0.866).normalize(), Vec3::new(0.0, 0.0, -1.0)] {
            let mut mean_cos = 0.0;
            for _ in 0..4000 {
                let (d, cos) = cosine_sample(n, Vec2::new(rng.next_f32(), rng.next_f32()));
                assert!((d.length() - 1.0).abs() < 1e-4);
                assert!((d.dot(n) - cos).abs() < 1e-4, "{d} {n} {cos}");
                mean_cos += cos / 4000.0;
            }
            // E[cos] under the density cos / pi is 2/3.
            assert!((mean_cos - 2.0 / 3.0).abs() < 0.02, "{mean_cos}");
        }
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 2.0), (0.3, 0.0), (5.0, 5.0)] {
            assert!((power_heuristic(a, b) + power_heuristic(b, a) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn bad_settings_are_refused() {
        let ok = PathSettings { spp: 4, max_depth: 3, rr_depth: None, nee: Nee::All };
        assert!(ok.validate().is_ok());
        assert!(PathSettings { spp: 0, ..ok }.validate().is_err());
        assert!(PathSettings { max_depth: 0, ..ok }.validate().is_err());
        assert!(PathSettings { max_depth: -2, ..ok }.validate().is_err());
        assert!(PathSettings { max_depth: -1, ..ok }.validate().is_ok());
    }
}
