//! The shadow-ray query shared by all modes, the per-thread query context (counters and the
//! de-duplication stamps of SPEC §3), and [`blocks`], the one predicate that decides whether a triangle
//! blocks a shadow ray.

use glam::Vec3;

use super::{Answer, Answers};
use crate::geometry::RayTest;
use crate::octree::LeafId;
use crate::scene::{LightId, Scene, TriId};

pub use crate::geometry::SEGMENT_EPS;

/// A shadow ray from a shaded point to a sample on a light.
#[derive(Clone, Copy, Debug)]
pub struct ShadowRay {
    /// The segment, prepared for the watertight test; `t` runs from 0 at `x` to 1 at `y`.
    pub test: RayTest,
    /// The light sampled.
    pub light: LightId,
    /// The triangle `x` lies on (never counts as a blocker). `x` must lie on it, up to rounding, as a
    /// shaded point does; a point on no triangle passes an id no triangle has (e.g. `TriId(u32::MAX)`).
    pub origin_tri: TriId,
    /// The octree leaf containing `x`, when known (from the hit buffer).
    pub leaf: Option<LeafId>,
}

impl ShadowRay {
    /// The segment from `x` on `origin_tri` to `y` on `light`.
    pub fn new(x: Vec3, y: Vec3, light: LightId, origin_tri: TriId, leaf: Option<LeafId>) -> ShadowRay {
        ShadowRay { test: RayTest::new(x, y - x, SEGMENT_EPS, 1.0 - SEGMENT_EPS), light, origin_tri, leaf }
    }

    /// Start point `x`.
    pub fn origin(&self) -> Vec3 {
        self.test.origin
    }

    /// End point `y`.
    pub fn end(&self) -> Vec3 {
        self.test.origin + self.test.dir
    }
}

/// The shadow rays of one light from one shaded point `x`: segments from `x` to each of `targets`.
/// They share their origin, so a mode can answer them together
/// ([`super::Visibility::occluded_light`]).
#[derive(Clone, Copy, Debug)]
pub struct LightRays<'a> {
    /// The shaded point `x`.
    pub origin: Vec3,
    /// The triangle `x` lies on (as [`ShadowRay::origin_tri`]).
    pub origin_tri: TriId,
    /// The octree leaf containing `x`, when known.
    pub leaf: Option<LeafId>,
    /// The light sampled.
    pub light: LightId,
    /// The light samples `y_k`.
    pub targets: &'a [Vec3],
}

impl LightRays<'_> {
    /// True for the rays' own triangles, which never block them (as in [`blocks`]): the one the
    /// point lies on and the light's.
    #[inline(always)]
    pub fn own(&self, scene: &Scene, t: TriId) -> bool {
        self.own_with(t, scene.tri_light[t.idx()])
    }

    /// [`LightRays::own`] for triangle `t` of light `light` (the scene's `tri_light[t]`).
    #[inline(always)]
    pub fn own_with(&self, t: TriId, light: Option<LightId>) -> bool {
        t == self.origin_tri || light == Some(self.light)
    }

    /// The `k`-th shadow ray.
    #[inline]
    pub fn ray(&self, k: usize) -> ShadowRay {
        ShadowRay::new(self.origin, self.targets[k], self.light, self.origin_tri, self.leaf)
    }
}

/// Counters of one thread's queries, summed over threads at the end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct QueryStats {
    /// Shadow rays answered.
    pub shadow_rays: u64,
    /// Shadow rays found occluded.
    pub occluded: u64,
    /// Watertight triangle tests run.
    pub triangle_tests: u64,
    /// Candidate bounding-box tests run before triangle tests (P-LIE modes; in the per-light queries,
    /// the pyramid culls of triangles and of their chunks).
    pub box_tests: u64,
    /// (triangle, ray) pairs decided by the fan's fast test (per-light queries of the P-LIE modes):
    /// sure misses, and the rays it sent on to the watertight test.
    pub lane_tests: u64,
    /// Of `triangle_tests`, those of a record's (or grid cell's) blockers (P-LIE modes).
    pub blocker_tests: u64,
    /// Of `triangle_tests`, those of the triangles of the ray's own leaf (P-LIE modes).
    pub own_leaf_tests: u64,
    /// How the shadow rays were answered (P-LIE modes; zero in the others).
    pub answers: Answers,
    /// How the (point, light) queries of [`super::Visibility::occluded_light`] were answered (P-LIE
    /// modes; zero in the others).
    pub lights: LightAnswers,
}

/// How the P-LIE modes answered the (point, light) pairs of the per-light query.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LightAnswers {
    /// Pairs asked.
    pub queries: u64,
    /// Pairs whose every ray was occluded without a triangle test (no record or umbra).
    pub whole_umbra: u64,
    /// Pairs whose every ray was answered without a triangle test, some of them lit (no blocker in
    /// their cell and no triangle of the leaf in the pyramid to the light).
    pub whole_lit: u64,
    /// Pairs whose rays were all tested against the short lists of every cell under the light's
    /// footprints (without finding each ray's own cell) and the leaf's own triangles.
    pub gathered: u64,
    /// Pairs answered by the scene BVH, all rays at once: their footprints cover cells of different
    /// kinds, long lists, or records that store no list.
    pub scene: u64,
    /// Pairs the footprints left to the scene BVH whose rays were all occluded by the blockers of
    /// the light's last walk that found every ray occluded (so without a walk).
    pub last_blockers: u64,
    /// Pairs whose rays were all tested against the few triangles that meet the shaft from the
    /// piece of the point's triangle in its leaf to the light (pairs the footprints left to the
    /// scene BVH, from a piece asked before).
    pub shaft: u64,
    /// Pairs whose footprints were not found, because those of their (leaf, light) had decided
    /// nothing the last few times (`visibility::verdicts`); counted again among `shaft`,
    /// `last_blockers` and `scene`.
    pub unsought: u64,
}

impl std::ops::AddAssign for LightAnswers {
    fn add_assign(&mut self, o: LightAnswers) {
        self.queries += o.queries;
        self.whole_umbra += o.whole_umbra;
        self.whole_lit += o.whole_lit;
        self.gathered += o.gathered;
        self.scene += o.scene;
        self.last_blockers += o.last_blockers;
        self.shaft += o.shaft;
        self.unsought += o.unsought;
    }
}

impl QueryStats {
    /// Counts a ray decided by path `a` and returns its answer, `occluded`, so a mode can write
    /// `return ctx.stats.answered(Answer::NoRecord, true)`.
    #[inline]
    pub fn answered(&mut self, a: Answer, occluded: bool) -> bool {
        debug_assert!(a.occluded().is_none_or(|o| o == occluded), "{a:?} cannot answer {occluded}");
        self.answers.count(a);
        occluded
    }
}

impl std::ops::AddAssign for QueryStats {
    fn add_assign(&mut self, o: QueryStats) {
        self.shadow_rays += o.shadow_rays;
        self.occluded += o.occluded;
        self.triangle_tests += o.triangle_tests;
        self.box_tests += o.box_tests;
        self.lane_tests += o.lane_tests;
        self.blocker_tests += o.blocker_tests;
        self.own_leaf_tests += o.own_leaf_tests;
        self.answers += o.answers;
        self.lights += o.lights;
    }
}

/// Per-thread scratch space for queries: counters and the stamp array that makes sure a triangle met
/// in several leaves is tested once per query.
#[derive(Clone, Debug, Default)]
pub struct QueryCtx {
    /// Counters.
    pub stats: QueryStats,
    /// Scratch of the per-light queries, taken out while one runs (moving a pointer, not the
    /// scratch itself; `None` until the first).
    pub(crate) light: Option<Box<super::fan::LightScratch>>,
    stamps: Vec<u32>,
    stamp: u32,
}

impl QueryCtx {
    /// A context for a scene with `triangles` triangles.
    pub fn new(triangles: usize) -> QueryCtx {
        QueryCtx { stats: QueryStats::default(), light: None, stamps: vec![0; triangles], stamp: 0 }
    }

    /// Runs `f` with the per-light scratch, taken out of the context (a pointer moved) so that `f`
    /// can use both, and put back after.
    #[inline]
    pub(crate) fn with_light<R>(&mut self, f: impl FnOnce(&mut super::fan::LightScratch, &mut QueryCtx) -> R) -> R {
        let mut sc = self.light.take().unwrap_or_default();
        let r = f(&mut sc, self);
        self.light = Some(sc);
        r
    }

    /// Starts a new query: every triangle counts as unvisited again.
    #[inline]
    pub fn begin_query(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.fill(0);
            self.stamp = 1;
        }
    }

    /// True the first time `t` is seen in the current query.
    #[inline]
    pub fn first_visit(&mut self, t: TriId) -> bool {
        let s = &mut self.stamps[t.idx()];
        if *s == self.stamp {
            false
        } else {
            *s = self.stamp;
            true
        }
    }
}

/// The one blocker predicate: true if triangle `t` blocks `ray`. The ray's origin triangle and the
/// target light's own triangles never block it. Counts a triangle test.
#[inline]
pub fn blocks(scene: &Scene, ray: &ShadowRay, t: TriId, ctx: &mut QueryCtx) -> bool {
    if t == ray.origin_tri || scene.tri_light[t.idx()] == Some(ray.light) {
        return false;
    }
    ctx.stats.triangle_tests += 1;
    ray.test.hit(&scene.triangles[t.idx()]).is_some()
}
