//! Comparing a visibility mode's shadow-ray answers with a reference's, ray by ray, over the shadow
//! rays a render shoots (SPEC §2's pass 2, §5's exactness): how far a non-exact mode (native Embree)
//! is from `brute`. The bench reports the fraction; the tests bound it.

use std::sync::atomic::{AtomicU64, Ordering};

use serde::Serialize;

use crate::render::shade::shade;
use crate::render::{HitBuffer, NoProgress};
use crate::scene::Scene;
use crate::visibility::{LightRays, QueryCtx, ShadowRay, Visibility};

/// How many shadow-ray answers two modes gave, and in how many they differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct AnswerDiff {
    /// Shadow rays answered by both.
    pub rays: u64,
    /// Of `rays`, those answered differently.
    pub differing: u64,
}

impl AnswerDiff {
    /// `differing / rays` (0 when no ray was shot).
    pub fn fraction(&self) -> f64 {
        if self.rays == 0 {
            0.0
        } else {
            self.differing as f64 / self.rays as f64
        }
    }
}

/// Answers with `vis` and asks `reference` the same rays, counting the rays where they differ.
struct Both<'v> {
    vis: &'v dyn Visibility,
    reference: &'v dyn Visibility,
    rays: AtomicU64,
    differing: AtomicU64,
}

impl Visibility for Both<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        let got = self.vis.occluded(ray, ctx);
        let want = self.reference.occluded(ray, ctx);
        self.rays.fetch_add(1, Ordering::Relaxed);
        self.differing.fetch_add(u64::from(got != want), Ordering::Relaxed);
        got
    }

    fn occluded_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        self.vis.occluded_light(rays, out, ctx);
        let mut want = vec![false; out.len()];
        self.reference.occluded_light(rays, &mut want, ctx);
        let differing = out.iter().zip(&want).filter(|(a, b)| a != b).count();
        self.rays.fetch_add(out.len() as u64, Ordering::Relaxed);
        self.differing.fetch_add(differing as u64, Ordering::Relaxed);
    }
}

/// Shades `hits` (as [`shade`] does, with `shadow_rays` samples per light and `seed`) and compares,
/// ray by ray, the answers of `vis` with those of `reference` (e.g. native Embree with `brute` or
/// `bvh`): the shadow rays are exactly those a render with these settings shoots.
pub fn answer_diff(
    scene: &Scene,
    hits: &HitBuffer,
    vis: &dyn Visibility,
    reference: &dyn Visibility,
    shadow_rays: u32,
    seed: u64,
) -> AnswerDiff {
    let both = Both { vis, reference, rays: AtomicU64::new(0), differing: AtomicU64::new(0) };
    shade(scene, hits, &both, shadow_rays, seed, &NoProgress);
    AnswerDiff { rays: both.rays.into_inner(), differing: both.differing.into_inner() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visibility::{Brute, NoVisibility};

    #[test]
    fn none_differs_from_brute_exactly_where_brute_is_blocked() {
        let scene = crate::scene::builtin::load("cornell-cube-1").unwrap();
        let bvh = crate::visibility::bvh::Bvh::build(&scene);
        let hits = HitBuffer::build(&scene, &scene.camera_or_default(), (24, 24, 1), &bvh, None);
        let brute = Brute::new(&scene);
        let same = answer_diff(&scene, &hits, &brute, &brute, 4, 3);
        assert!(same.rays > 0);
        assert_eq!(same.differing, 0);
        let none = answer_diff(&scene, &hits, &NoVisibility, &brute, 4, 3);
        let (_, stats) = shade(&scene, &hits, &brute, 4, 3, &NoProgress);
        assert_eq!(none.rays, stats.shadow_rays);
        assert_eq!(none.differing, stats.occluded);
        assert!(none.differing > 0 && none.fraction() < 1.0, "{none:?}");
    }
}
