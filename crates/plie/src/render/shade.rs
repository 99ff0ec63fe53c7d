//! Pass 2 of SPEC §2, the one the thesis times: direct lighting at every hit-buffer point,
//!
//! `L(x -> eye) = L_e(x) + sum_i (A_i / N) sum_k L_e,i f_r(x) G(x, y_k) V(x, y_k)`,
//!
//! with `f_r = albedo / pi`, `G = cos(theta_x) cos(theta_y) / |x - y|^2` (zero when either cosine is
//! not positive, and then no shadow ray is shot), and `N` N-rooks samples `y_k` per light. The order
//! of floating-point operations depends only on the scene, the seed and the visibility *answers*, so
//! exact visibility modes give bit-identical images.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::hit_buffer::{Hit, HitBuffer};
use super::sampler::{n_rooks, Rng};
use super::Progress;
use crate::scene::{LightId, Scene};
use crate::visibility::{LightRays, QueryCtx, QueryStats, Visibility};

/// Per-thread scratch space for shading.
pub struct ShadeScratch {
    /// Visibility query context.
    pub ctx: QueryCtx,
    samples: Vec<Vec2>,
    /// The current light's sample points, and per sample its geometry term (`NaN`: it does not
    /// face the point).
    points: Vec<Vec3>,
    terms: Vec<f32>,
    /// The samples that face the point, their geometry terms, and their visibility.
    targets: Vec<Vec3>,
    weights: Vec<f32>,
    occluded: Vec<bool>,
}

impl ShadeScratch {
    /// Scratch space for `scene` with `n` samples per light.
    pub fn new(scene: &Scene, n: u32) -> ShadeScratch {
        let n = n as usize;
        ShadeScratch {
            ctx: QueryCtx::new(scene.triangles.len()),
            samples: vec![Vec2::ZERO; n],
            points: Vec::with_capacity(n),
            terms: Vec::with_capacity(n),
            targets: Vec::with_capacity(n),
            weights: Vec::with_capacity(n),
            occluded: vec![false; n],
        }
    }
}

/// The geometry term `cos_x cos_y / |x - y|^2` of each sample point `y` of a light with normal
/// `nl`, seen from `x` with normal `n`, into `terms`; `NaN` where either cosine is not positive
/// (or `y = x`): no shadow ray is shot there. Written lane by lane so that it vectorises; division
/// is correctly rounded in every lane, so the values are those of the scalar formula.
fn geometry_terms(x: Vec3, n: Vec3, nl: Vec3, points: &[Vec3], terms: &mut Vec<f32>) {
    terms.clear();
    terms.extend(points.iter().map(|&y| {
        let d = y - x;
        let dist2 = d.length_squared();
        // cos_x cos_y / |d|^2 = (n.d / |d|^2) (-nl.d / |d|^2), without a square root.
        let inv = dist2.recip();
        let (a, b) = (n.dot(d), -nl.dot(d));
        if dist2 > 0.0 && a > 0.0 && b > 0.0 {
            a * inv * (b * inv)
        } else {
            f32::NAN
        }
    }));
}

/// The sum, in sample order, of the `weights` of the rays not `occluded`; counts the rays and the
/// occluded ones in `stats`. Shared by direct light and the path tracer's next-event estimation.
pub(crate) fn unoccluded_sum(weights: &[f32], occluded: &[bool], stats: &mut QueryStats) -> f32 {
    stats.shadow_rays += occluded.len() as u64;
    let mut sum = 0.0f32;
    for (w, &o) in weights.iter().zip(occluded) {
        if o {
            stats.occluded += 1;
        } else {
            sum += w;
        }
    }
    sum
}

/// Radiance toward the eye at one hit: emission (front side only) plus direct lighting from every
/// light. `stream` identifies the eye ray (pixel and sub-ray index) for the random streams.
///
/// The samples of a light that face the point (both cosines positive) are asked of the visibility
/// together ([`Visibility::occluded_light`]); the unoccluded ones are summed in sample order.
pub fn shade_hit(
    scene: &Scene,
    vis: &dyn Visibility,
    hit: &Hit,
    seed: u64,
    stream: (u64, u64),
    s: &mut ShadeScratch,
) -> Vec3 {
    let material = scene.material_of(hit.tri);
    let mut l = if hit.front { material.emission } else { Vec3::ZERO };
    let f_r = scene.albedo_at(hit.tri, hit.point) * FRAC_1_PI;
    if f_r == Vec3::ZERO {
        return l;
    }
    let x = hit.point;
    let n_samples = s.samples.len();
    for (i, light) in scene.lights.iter().enumerate() {
        let mut rng = Rng::stream(seed, stream.0, stream.1, i as u64);
        n_rooks(&mut rng, &mut s.samples);
        s.points.clear();
        light.sample_into(&s.samples, &mut s.points);
        geometry_terms(x, hit.normal, light.normal, &s.points, &mut s.terms);
        // Usually every sample faces the point, and the points are the targets as they are.
        let facing = s.terms.iter().filter(|w| !w.is_nan()).count();
        if facing == 0 {
            continue;
        }
        let (targets, weights) = if facing == s.terms.len() {
            (&s.points[..], &s.terms[..])
        } else {
            s.targets.clear();
            s.weights.clear();
            for (&y, &w) in s.points.iter().zip(&s.terms) {
                if !w.is_nan() {
                    s.targets.push(y);
                    s.weights.push(w);
                }
            }
            (&s.targets[..], &s.weights[..])
        };
        let rays = LightRays { origin: x, origin_tri: hit.tri, leaf: hit.leaf, light: LightId(i as u32), targets };
        let occluded = &mut s.occluded[..facing];
        vis.occluded_light(&rays, occluded, &mut s.ctx);
        let sum = unoccluded_sum(weights, occluded, &mut s.ctx.stats);
        l += light.radiance * f_r * (light.area / n_samples as f32 * sum);
    }
    l
}

/// Shades the whole hit buffer: one radiance per pixel (the mean of its eye rays), row-major, top row
/// first; and the summed query counters.
pub fn shade(
    scene: &Scene,
    hits: &HitBuffer,
    vis: &dyn Visibility,
    shadow_rays: u32,
    seed: u64,
    progress: &dyn Progress,
) -> (Vec<Vec3>, QueryStats) {
    let w = hits.width as usize;
    let per_pixel = (hits.k * hits.k) as usize;
    let mut image = vec![Vec3::ZERO; w * hits.height as usize];
    progress.start("shading", hits.height as u64);
    let stats = image
        .par_chunks_mut(w)
        .enumerate()
        .map_init(
            || ShadeScratch::new(scene, shadow_rays),
            |s, (py, row)| {
                for (px, out) in row.iter_mut().enumerate() {
                    let pixel = py * w + px;
                    let mut sum = Vec3::ZERO;
                    for (j, hit) in hits.hits[pixel * per_pixel..(pixel + 1) * per_pixel].iter().enumerate() {
                        if let Some(hit) = hit {
                            sum += shade_hit(scene, vis, hit, seed, (pixel as u64, j as u64), s);
                        }
                    }
                    *out = sum / per_pixel as f32;
                }
                progress.advance(1);
                // This row's counters; the scratch starts the next row from zero.
                std::mem::take(&mut s.ctx.stats)
            },
        )
        .reduce(QueryStats::default, |mut a, b| {
            a += b;
            a
        });
    progress.finish();
    (image, stats)
}
