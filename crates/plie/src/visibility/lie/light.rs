//! The per-light query of the P-LIE modes (issue 21): all `N` samples of one light from one shaded
//! point at once ([`Visibility::occluded_light`](super::super::Visibility::occluded_light)). The light's
//! footprints on the leaf's faces ([`super::whole`]) answer the whole light where they lie in lit
//! cells or in umbra, or gather the short lists of the cells under them, tested as a fan
//! ([`super::super::fan`]) with the leaf's own triangles. Any other light (footprints over penumbra
//! and umbra alike, long lists, records that store no list, a leaf crowded with triangles of its
//! own) is answered from the few triangles in the shaft of the point's piece of surface where that
//! piece, asked often and not in a crowded leaf, has them ([`super::shafts`]), else by the scene
//! BVH, all samples at once,
//! starting from the cut of the leaf and the light (`Bvh::fan_occluded`,
//! [`crate::visibility::bvh::Cut`]): measured, that beat
//! finding each sample's exit face, record and cell and testing its own list on every scene tried
//! (docs/results.md, session 8). Before that walk, the blockers of the light's last walk that found
//! every ray occluded are tested: in shadow that the footprints cannot decide, a neighbouring
//! pixel's blockers often close every ray, and the walk is not needed. Where a leaf's footprints
//! toward a light decided nothing the last few times, they are not sought
//! ([`crate::visibility::verdicts`]), and the light goes straight to its shaft or the scene BVH.

use super::super::fan::{Fan, LightScratch, Pyramid};
use super::super::list_boxes::{Chunked, ListVisitor};
use super::super::{Answer, LightRays, QueryCtx, Visibility, FAN_MIN};
use super::shafts::Found;
use super::whole::{Whole, CELL_KEY};
use super::LieVisibility;
use crate::geometry::Aabb;
use crate::octree::LeafId;
use crate::scene::TriId;
use crate::visibility::simd::Avx2;

impl LieVisibility<'_> {
    /// [`Whole::Lists`]: every sample against every gathered list, then the leaf's own triangles,
    /// as a fan culled by the pyramid.
    fn lists_only(&self, leaf: LeafId, rays: &LightRays, sc: &mut LightScratch, out: &mut [bool], ctx: &mut QueryCtx) {
        out.fill(false);
        let tests_before = fan_tests(ctx);
        sc.fan.set(rays);
        self.set_pyramid(&mut sc.fan.pyramid, rays.origin, rays.light);
        ctx.begin_query();
        let before = ctx.stats.triangle_tests;
        for &key in &sc.lists {
            self.fan_list(rays, self.list_of(key), true, &mut sc.fan, out, ctx);
        }
        ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
        let list_hits = out.iter().filter(|&&o| o).count();
        // The rays the lists hit are closed already, so the leaf's own triangles are tested
        // against the others only.
        let before = ctx.stats.triangle_tests;
        let (start, len) = self.own[leaf.idx()];
        let own = self.own_boxes.of(leaf.idx(), &self.own_tris[start as usize..(start + len) as usize]);
        self.fan_list(rays, own, false, &mut sc.fan, out, ctx);
        ctx.stats.own_leaf_tests += ctx.stats.triangle_tests - before;
        let hits = out.iter().filter(|&&o| o).count();
        let answers = &mut ctx.stats.answers;
        answers.count_n(Answer::BlockersHit, list_hits);
        answers.count_n(Answer::OwnLeaf, hits - list_hits);
        answers.count_n(Answer::BlockersMiss, out.len() - hits);
        count_lit_or_gathered(ctx, tests_before);
    }

    /// All samples of one light from one point (issue 21), by the footprints' verdict
    /// ([`Whole`]): all occluded; lit but for the leaf's own triangles; the gathered lists and the
    /// leaf's own triangles as a fan (for a leaf of at most [`OWN_MAX`] triangles); or the scene
    /// BVH. Every candidate set holds each ray's true
    /// blockers, and each triangle is decided by the watertight test, so every answer is the per-ray
    /// answer.
    pub(super) fn answer_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        let leaf = rays.leaf.or_else(|| self.octree.locate(rays.origin));
        let Some(leaf) = leaf.filter(|_| rays.targets.len() >= FAN_MIN) else {
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.occluded(&rays.ray(k), ctx);
            }
            return;
        };
        ctx.with_light(|sc, ctx| {
            let bounds = self.octree.leaf_bounds(leaf);
            sc.lists.clear();
            sc.ranges.clear();
            ctx.stats.lights.queries += 1;
            // A leaf with many triangles of its own: the BVH culls them better than the fan does,
            // so only umbra can spare its lights the walk, and the footprints look for nothing else
            // (its lights come back as umbra or mixed, never lit or listed).
            let crowded = self.own[leaf.idx()].1 as usize > OWN_MAX;
            // Where this leaf's footprints toward the light decided nothing the last few times,
            // they are not sought ([`crate::visibility::verdicts`]): the light goes where an
            // undecided one goes (its shaft or the scene BVH).
            let whole = match sc.verdicts.ask(leaf, rays.light) {
                Some(slot) => {
                    let poly = &self.scene.lights[rays.light.idx()].vertices;
                    let whole = self.whole_light(leaf, &bounds, rays, poly, crowded, sc);
                    sc.verdicts.found(slot, whole != Whole::Mixed);
                    whole
                }
                None => {
                    ctx.stats.lights.unsought += 1;
                    Whole::Mixed
                }
            };
            match whole {
                Whole::Umbra => {
                    out.fill(true);
                    ctx.stats.lights.whole_umbra += 1;
                    ctx.stats.answers.count_n(Answer::Umbra, out.len());
                }
                Whole::Lit => self.own_only(leaf, rays, sc, out, ctx),
                Whole::Lists => self.lists_only(leaf, rays, sc, out, ctx),
                Whole::Mixed => self.by_scene(leaf, crowded, rays, sc, out, ctx),
            }
        });
    }

    /// [`Whole::Mixed`]: outside `crowded` leaves, the triangles in the shaft of the point's piece
    /// when it has a list ([`super::shafts`]); else every sample down the scene BVH at once, for
    /// the whole segment, from the cut of the leaf and the light ([`crate::visibility::bvh::Cut`]).
    fn by_scene(
        &self,
        leaf: LeafId,
        crowded: bool,
        rays: &LightRays,
        sc: &mut LightScratch,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        out.fill(false);
        self.set_pyramid(&mut sc.fan.pyramid, rays.origin, rays.light);
        if !crowded {
            if let Found::List = self.shaft_list(leaf, rays, &sc.fan.pyramid, &mut sc.shaft, ctx) {
                return self.by_shaft(rays, sc, out, ctx);
            }
        }
        sc.fan.set(rays);
        let before = ctx.stats.triangle_tests;
        // Where the walk for this light from an earlier point found every ray occluded, its
        // blockers likely block this point's rays too (a neighbouring pixel): tested first, they
        // spare the walk where they close every ray.
        sc.test_last_blockers(self.scene, rays, out, ctx);
        if sc.fan.live() == 0 {
            ctx.stats.lights.last_blockers += 1;
        } else {
            ctx.stats.lights.scene += 1;
            // The cut holds every triangle a segment from the leaf to the light can meet.
            debug_assert!(self.octree.leaf_bounds(leaf).expanded(self.scene.tolerance()).contains(rays.origin));
            let cut = self.cut(leaf, rays.light);
            self.bvh.fan_occluded(cut, rays, &mut sc.fan, &mut sc.walk, out, ctx);
        }
        sc.keep_blockers(rays);
        ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
        ctx.stats.answers.count_n(Answer::SceneBvh, out.len());
    }
}

impl LieVisibility<'_> {
    /// A light answered by its piece's shaft ([`super::shafts`]): the triangles in `sc.shaft`
    /// (those of the shaft that the light's pyramid does not cull) are all that can block,
    /// tested as a fan; where there are none, every ray is lit without one.
    fn by_shaft(&self, rays: &LightRays, sc: &mut LightScratch, out: &mut [bool], ctx: &mut QueryCtx) {
        ctx.stats.lights.shaft += 1;
        let before = ctx.stats.triangle_tests;
        if !sc.shaft.is_empty() {
            sc.fan.set(rays);
            self.fan_shaft(rays, &sc.shaft, &mut sc.fan, out, ctx);
        }
        ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
        let hits = out.iter().filter(|&&o| o).count();
        ctx.stats.answers.count_n(Answer::BlockersHit, hits);
        ctx.stats.answers.count_n(Answer::BlockersMiss, out.len() - hits);
    }

    /// [`Self::fan_tris`] over a shaft's list, compiled for AVX2 where the CPU has it.
    fn fan_shaft(&self, rays: &LightRays, tris: &[TriId], fan: &mut Fan, out: &mut [bool], ctx: &mut QueryCtx) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = Avx2::detect() {
            // SAFETY: AVX2, POPCNT and BMI1 are available (the proof).
            return unsafe { self.fan_shaft_avx(rays, tris, fan, out, ctx, simd) };
        }
        self.fan_shaft_in(rays, tris, fan, out, ctx, None)
    }

    /// The body of [`Self::fan_shaft`]: each triangle against the open rays.
    #[inline(always)]
    fn fan_shaft_in(
        &self,
        rays: &LightRays,
        tris: &[TriId],
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        for &t in tris {
            if fan.live() == 0 {
                return;
            }
            fan.test(self.scene, rays, t, out, ctx, simd);
        }
    }

    /// [`Self::fan_shaft`] compiled for AVX2: the same operations, so the same answers.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,popcnt,bmi1")]
    unsafe fn fan_shaft_avx(
        &self,
        rays: &LightRays,
        tris: &[TriId],
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Avx2,
    ) {
        self.fan_shaft_in(rays, tris, fan, out, ctx, Some(simd))
    }

    /// The blocker list of `key` with its chunk boxes.
    #[inline]
    fn list_of(&self, key: u32) -> Chunked<'_> {
        if key & CELL_KEY != 0 {
            let c = (key & !CELL_KEY) as usize;
            let (start, len) = self.plie.cells[c];
            self.cell_boxes.of(c, &self.plie.cell_blockers[start as usize..(start + len) as usize])
        } else {
            let ri = key as usize;
            self.record_boxes.of(ri, self.plie.blockers_of(&self.plie.records[ri]))
        }
    }

    /// A light whose footprints lie in lit cells only: every sample is lit unless a triangle of the
    /// leaf itself blocks it. Those meeting the pyramid (usually none) are tested as a fan.
    fn own_only(&self, leaf: LeafId, rays: &LightRays, sc: &mut LightScratch, out: &mut [bool], ctx: &mut QueryCtx) {
        out.fill(false);
        self.set_pyramid(&mut sc.fan.pyramid, rays.origin, rays.light);
        let (start, len) = self.own[leaf.idx()];
        let own = self.own_boxes.of(leaf.idx(), &self.own_tris[start as usize..(start + len) as usize]);
        let before = ctx.stats.triangle_tests;
        let tests_before = fan_tests(ctx);
        if self.any_in_pyramid(rays, own, &sc.fan.pyramid, ctx) {
            sc.fan.set(rays);
            self.fan_list(rays, own, false, &mut sc.fan, out, ctx);
        }
        ctx.stats.own_leaf_tests += ctx.stats.triangle_tests - before;
        let hits = out.iter().filter(|&&o| o).count();
        ctx.stats.answers.count_n(Answer::OwnLeaf, hits);
        ctx.stats.answers.count_n(Answer::Lit, out.len() - hits);
        count_lit_or_gathered(ctx, tests_before);
    }

    /// True if a triangle of `list` (other than the rays' own) is not culled by `pyramid`.
    fn any_in_pyramid(&self, rays: &LightRays, list: Chunked, pyramid: &Pyramid, ctx: &mut QueryCtx) -> bool {
        /// The pyramid down the hierarchy.
        struct Cull<'v, 'a, 'c> {
            vis: &'v LieVisibility<'a>,
            rays: &'v LightRays<'v>,
            pyramid: &'v Pyramid,
            ctx: &'c mut QueryCtx,
        }
        impl ListVisitor for Cull<'_, '_, '_> {
            #[inline]
            fn enter(&mut self, b: &Aabb, _: usize) -> bool {
                self.ctx.stats.box_tests += 1;
                !self.pyramid.culls_box(b)
            }
            #[inline]
            fn chunk(&mut self, tris: &[TriId], _: usize) -> bool {
                let (vis, rays) = (self.vis, self.rays);
                tris.iter().any(|&t| {
                    if rays.own(vis.scene, t) {
                        return false;
                    }
                    self.ctx.stats.box_tests += 1;
                    !self.pyramid.culls(&vis.scene.triangles[t.idx()])
                })
            }
        }
        list.walk(&mut Cull { vis: self, rays, pyramid, ctx })
    }

    /// Tests the triangles `tris` that the pyramid does not cull against the fan's open rays,
    /// marking those hit in `out`; with `once`, only those not met before in the query.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn fan_tris(
        &self,
        rays: &LightRays,
        tris: &[TriId],
        once: bool,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        for &t in tris {
            if fan.live() == 0 {
                return;
            }
            if rays.own(self.scene, t) || (once && !ctx.first_visit(t)) {
                continue;
            }
            ctx.stats.box_tests += 1;
            if fan.pyramid.culls(&self.scene.triangles[t.idx()]) {
                continue;
            }
            fan.test(self.scene, rays, t, out, ctx, simd);
        }
    }

    /// [`Self::fan_tris`] over a blocker list, skipping the boxes of its hierarchy that the
    /// pyramid culls. Where the CPU has AVX2, as one copy compiled for it (as the scene BVH's walk
    /// is), so that the fan's lane kernels inline into it.
    fn fan_list(
        &self,
        rays: &LightRays,
        list: Chunked,
        once: bool,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = Avx2::detect() {
            // SAFETY: AVX2, POPCNT and BMI1 are available (the proof).
            return unsafe { self.fan_list_avx(rays, list, once, fan, out, ctx, simd) };
        }
        self.fan_list_in(rays, list, once, fan, out, ctx, None)
    }

    /// [`Self::fan_list`] compiled for AVX2: the same operations, so the same answers.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,popcnt,bmi1")]
    #[allow(clippy::too_many_arguments)]
    unsafe fn fan_list_avx(
        &self,
        rays: &LightRays,
        list: Chunked,
        once: bool,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Avx2,
    ) {
        self.fan_list_in(rays, list, once, fan, out, ctx, Some(simd))
    }

    /// The body of [`Self::fan_list`].
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn fan_list_in(
        &self,
        rays: &LightRays,
        list: Chunked,
        once: bool,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        /// The pyramid down the hierarchy, then the fan at its chunks.
        struct Tris<'v, 'a, 'c> {
            vis: &'v LieVisibility<'a>,
            rays: &'v LightRays<'v>,
            once: bool,
            fan: &'c mut Fan,
            out: &'c mut [bool],
            ctx: &'c mut QueryCtx,
            simd: Option<Avx2>,
        }
        impl ListVisitor for Tris<'_, '_, '_> {
            #[inline(always)]
            fn enter(&mut self, b: &Aabb, _: usize) -> bool {
                self.ctx.stats.box_tests += 1;
                self.fan.live() > 0 && !self.fan.pyramid.culls_box(b)
            }
            #[inline(always)]
            fn chunk(&mut self, tris: &[TriId], _: usize) -> bool {
                self.vis.fan_tris(self.rays, tris, self.once, self.fan, self.out, self.ctx, self.simd);
                self.fan.live() == 0
            }
        }
        if fan.live() > 0 {
            list.walk(&mut Tris { vis: self, rays, once, fan, out, ctx, simd });
        }
    }
}

/// The fan's tests run so far: in lanes, or by the watertight test (to which up to `DIRECT_MAX`
/// rays go directly).
fn fan_tests(ctx: &QueryCtx) -> u64 {
    ctx.stats.lane_tests + ctx.stats.triangle_tests
}

/// Counts a light answered without the scene BVH: whole lit if its fan ran no test since
/// `tests_before` ([`fan_tests`]), else gathered.
fn count_lit_or_gathered(ctx: &mut QueryCtx, tests_before: u64) {
    if fan_tests(ctx) == tests_before {
        ctx.stats.lights.whole_lit += 1;
    } else {
        ctx.stats.lights.gathered += 1;
    }
}

/// Most triangles of its own a leaf may hold for its lit or gathered lights to be tested as a fan;
/// with more, the scene BVH answers. Measured (callgrind of the query at 64 rays on cornell-cube-2,
/// huis-c, dragon, cornell-bunny and conference-lit, docs/results.md session 8): 32 needed the fewest
/// instructions in all of 16, 32, 64, 128 and no limit.
const OWN_MAX: usize = 32;
