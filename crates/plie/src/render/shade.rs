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
use crate::scene::{Light, LightId, Scene};
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

/// The sample points of `light` for the unit-square samples `us` into `points`, and into `terms`
/// the geometry term `cos_x cos_y / |x - y|^2` of each point `y`, seen from `x` with normal `n`;
/// `NaN` where either cosine is not positive (or `y = x`): no shadow ray is shot there.
///
/// For a parallelogram the terms are computed from `us` directly (`y - x` as `(v0 - x) + e1 u.x +
/// e3 u.y`), lane by lane, so that it vectorises; where the CPU has AVX2, in a copy compiled for
/// it. Division is correctly rounded in every lane, so the values are those of the scalar formula.
fn points_and_terms(x: Vec3, n: Vec3, light: &Light, us: &[Vec2], points: &mut Vec<Vec3>, terms: &mut Vec<f32>) {
    let nl = light.normal;
    match light.parallelogram_edges() {
        Some(edges) => {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: AVX2 is available (checked above).
                return unsafe { parallelogram_terms_avx(x, edges, n, nl, us, points, terms) };
            }
            parallelogram_terms(x, edges, n, nl, us, points, terms)
        }
        None => {
            points.clear();
            light.sample_into(us, points);
            terms.clear();
            terms.extend(points.iter().map(|&y| geometry_term(y - x, n, nl)));
        }
    }
}

/// [`parallelogram_terms`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
unsafe fn parallelogram_terms_avx(
    x: Vec3,
    edges: (Vec3, Vec3, Vec3),
    n: Vec3,
    nl: Vec3,
    us: &[Vec2],
    points: &mut Vec<Vec3>,
    terms: &mut Vec<f32>,
) {
    parallelogram_terms(x, edges, n, nl, us, points, terms)
}

/// [`points_and_terms`] for a parallelogram `(v0, e1, e3)`
/// ([`Light::parallelogram_edges`]): the points as [`Light::sample_into`] computes them.
#[inline(always)]
fn parallelogram_terms(
    x: Vec3,
    (o, e1, e3): (Vec3, Vec3, Vec3),
    n: Vec3,
    nl: Vec3,
    us: &[Vec2],
    points: &mut Vec<Vec3>,
    terms: &mut Vec<f32>,
) {
    // Plain loops over slices (not `extend`), so that they inline into the AVX2 copy.
    points.resize(us.len(), Vec3::ZERO);
    for (p, u) in points.iter_mut().zip(us) {
        *p = o + e1 * u.x + e3 * u.y;
    }
    let a = o - x;
    terms.resize(us.len(), 0.0);
    for (t, u) in terms.iter_mut().zip(us) {
        *t = geometry_term(a + e1 * u.x + e3 * u.y, n, nl);
    }
}

/// The geometry term of a point at `d` from the shaded point (see [`points_and_terms`]):
/// `cos_x cos_y / |d|^2 = (n.d / |d|^2) (-nl.d / |d|^2)`, without a square root.
#[inline(always)]
fn geometry_term(d: Vec3, n: Vec3, nl: Vec3) -> f32 {
    let dist2 = d.length_squared();
    let inv = dist2.recip();
    let (a, b) = (n.dot(d), -nl.dot(d));
    if dist2 > 0.0 && a > 0.0 && b > 0.0 {
        a * inv * (b * inv)
    } else {
        f32::NAN
    }
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
        points_and_terms(x, hit.normal, light, &s.samples, &mut s.points, &mut s.terms);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Rng;

    /// The points are `Light::sample`'s, bit for bit (they are the shadow rays' targets), and the
    /// terms the textbook `cos_x cos_y / |x - y|^2` up to rounding, NaN exactly where a cosine is not
    /// positive: for a parallelogram (the lane path) and a triangle.
    #[test]
    fn points_and_terms_match_the_formula() {
        // A skewed parallelogram (not axis-aligned, so that the order of the sums matters) and a
        // triangle, both at about y = 2 and within x, z in [0, 1.3].
        let (o, e1, e3) = (Vec3::new(0.13, 2.0, 0.07), Vec3::new(0.31, 0.02, 0.97), Vec3::new(0.93, -0.01, -0.29));
        let square = vec![o, o + e1, o + e1 + e3, o + e3];
        let tri = vec![o, o + e1, o + e1 + e3];
        let mut rng = Rng::stream(5, 0, 0, 0);
        for vertices in [square, tri] {
            // Facing down, toward the first two points.
            let mut light = Light::new(vertices.clone(), Vec3::ONE, vec![]).expect("valid light");
            if light.normal.y > 0.0 {
                light = Light::new(vertices.into_iter().rev().collect(), Vec3::ONE, vec![]).expect("valid light");
            }
            assert!(light.normal.y < 0.0);
            let us: Vec<Vec2> = (0..37).map(|_| Vec2::new(rng.next_f32(), rng.next_f32())).collect();
            for (x, n) in [
                (Vec3::new(0.3, 0.0, 0.4), Vec3::Y),
                (Vec3::new(-2.0, 1.5, 0.5), Vec3::new(1.0, 0.2, 0.0).normalize()),
                (Vec3::new(1.5, 1.95, 0.5), Vec3::X),
            ] {
                let (mut points, mut terms) = (Vec::new(), Vec::new());
                points_and_terms(x, n, &light, &us, &mut points, &mut terms);
                assert_eq!(points.len(), us.len());
                assert_eq!(terms.len(), us.len());
                let mut facing = 0;
                for ((&u, &p), &t) in us.iter().zip(&points).zip(&terms) {
                    let y = light.sample(u);
                    assert_eq!(p, y);
                    let d = y - x;
                    let (cx, cy) = (n.dot(d.normalize()), -light.normal.dot(d.normalize()));
                    if cx > 1e-4 && cy > 1e-4 {
                        let want = cx * cy / d.length_squared();
                        assert!((t - want).abs() <= 1e-5 * want, "{t} against {want}");
                        facing += 1;
                    } else if cx < -1e-4 || cy < -1e-4 {
                        assert!(t.is_nan());
                    }
                }
                // The first two points see the light, the last one (beside it, facing +x) does not.
                assert_eq!(facing > 0, x.x < 1.0, "{x}");
                assert!(light.parallelogram_edges().is_some() == (light.vertices.len() == 4));
            }
        }
    }
}
