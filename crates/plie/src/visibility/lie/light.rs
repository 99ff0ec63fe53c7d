//! The per-light query of the P-LIE modes (issue 21): all `N` samples of one light from one shaded
//! point at once ([`Visibility::occluded_light`](super::super::Visibility::occluded_light)). The light's
//! footprints on the leaf's faces ([`super::whole`]) answer the whole light where they lie in lit
//! cells or in umbra, or gather the lists of the cells under them; otherwise each sample finds its
//! exit face, record and cell as the per-ray query does (SPEC §5). The candidates are tested as a
//! fan ([`super::super::fan`]).

use super::super::bvh::segment_occluded;
use super::super::fan::{Fan, LightScratch, Pyramid};
use super::super::list_boxes::{Chunked, ListVisitor};
use super::super::query::SEGMENT_EPS;
use super::super::{Answer, LightRays, Mode, QueryCtx, Visibility};
use super::whole::{Whole, CELL_KEY};
use super::{exit_face_of, LieVisibility};
use crate::geometry::Aabb;
use crate::lie::frame::{in_triangles, FaceFrame};
use crate::lie::grid;
use crate::lie::{Cell, RecordKind};
use crate::octree::LeafId;
use crate::scene::TriId;

impl LieVisibility<'_> {
    /// [`Whole::Lists`]: every sample against every gathered list, then the leaf's own triangles,
    /// as a fan culled by the pyramid.
    fn lists_only(&self, leaf: LeafId, rays: &LightRays, sc: &mut LightScratch, out: &mut [bool], ctx: &mut QueryCtx) {
        out.fill(false);
        ctx.stats.lights.queries += 1;
        let lanes_before = ctx.stats.lane_tests;
        sc.fan.set(rays);
        sc.fan.pyramid.set(rays.origin, &self.scene.lights[rays.light.idx()], self.pad * 10.0);
        sc.fan.select_all();
        ctx.begin_query();
        let before = ctx.stats.triangle_tests;
        for &key in &sc.lists {
            self.fan_list(rays, self.list_of(key), true, &mut sc.fan, out, ctx);
        }
        ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
        let list_hits = out.iter().filter(|&&o| o).count();
        // Every ray stays active: those the lists hit are closed already, so the leaf's own
        // triangles are tested against the others only.
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
        if ctx.stats.lane_tests == lanes_before {
            ctx.stats.lights.whole_lit += 1;
        } else {
            ctx.stats.lights.gathered += 1;
        }
    }

    /// All samples of one light from one point (issue 21): each ray finds its exit face, record and
    /// (in `grid`) its cell exactly as [`Visibility::occluded`] does, so no record and umbra answer
    /// rays without a test. The remaining rays are tested as a fan ([`Fan`]): each distinct blocker
    /// list once against the rays that need it, then the leaf's own triangles against every ray
    /// still open, every candidate first culled by the pyramid from the point to the light. Testing
    /// a ray against more triangles than its own list can only find true blockers, so every answer is
    /// the per-ray answer.
    #[allow(clippy::needless_range_loop)] // `k` indexes the rays' targets, paths, lists and answers alike
    pub(super) fn answer_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        let leaf = rays.leaf.or_else(|| self.octree.locate(rays.origin));
        let Some(leaf) = leaf.filter(|_| rays.targets.len() >= FAN_MIN) else {
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.occluded(&rays.ray(k), ctx);
            }
            return;
        };
        let n = rays.targets.len();
        let mut scratch = std::mem::take(&mut ctx.light);
        let sc = &mut scratch;
        let bounds = self.octree.leaf_bounds(leaf);
        sc.lists.clear();
        sc.ranges.clear();
        match self.whole_light(leaf, &bounds, rays, &self.scene.lights[rays.light.idx()].vertices, sc) {
            Whole::Umbra => {
                out.fill(true);
                ctx.stats.lights.queries += 1;
                ctx.stats.lights.whole_umbra += 1;
                ctx.stats.answers.count_n(Answer::Umbra, n);
                ctx.light = scratch;
                return;
            }
            Whole::Lit => {
                self.own_only(leaf, rays, sc, out, ctx);
                ctx.light = scratch;
                return;
            }
            Whole::Lists => {
                self.lists_only(leaf, rays, sc, out, ctx);
                ctx.light = scratch;
                return;
            }
            Whole::Mixed => {}
        }
        sc.lists.clear();
        sc.ranges.clear();
        sc.path.clear();
        sc.path.resize(n, path::LIT);
        sc.list.clear();
        sc.list.resize(n, u32::MAX);
        out.fill(false);
        let x = rays.origin;
        // Per face: the record (`None`: no record), looked up once.
        let mut records: [Option<Option<usize>>; 6] = [None; 6];
        for k in 0..n {
            let d = rays.targets[k] - x;
            let Some((face, t_exit)) = exit_face_of(&bounds, x, d, 1.0 - SEGMENT_EPS) else {
                sc.path[k] = path::INSIDE;
                continue;
            };
            let record = *records[face.index()].get_or_insert_with(|| self.plie.record_id(leaf, face, rays.light));
            let Some(ri) = record else {
                out[k] = ctx.stats.answered(Answer::NoRecord, true);
                sc.path[k] = path::DONE;
                continue;
            };
            let f = x + d * t_exit;
            let scene_record = self.plie.records[ri].kind == RecordKind::Scene;
            // `Some(None)`: no list to test (lit); `None`: the record stores no list, the scene answers.
            let key = match self.mode {
                Mode::Umbra | Mode::Penumbra => {
                    let p = FaceFrame::new(face, &bounds).units(f.as_dvec3());
                    if in_triangles(self.plie.umbra_of(ri), p) {
                        out[k] = ctx.stats.answered(Answer::Umbra, true);
                        sc.path[k] = path::DONE;
                        continue;
                    }
                    if scene_record {
                        None
                    } else if self.mode == Mode::Penumbra && !in_triangles(self.plie.penumbra_of(ri), p) {
                        Some(None)
                    } else {
                        Some(Some(ri as u32))
                    }
                }
                Mode::Grid if self.plie.grids[ri].res > 0 => {
                    let grid = &self.plie.grids[ri];
                    let c = grid::cell_of(face, &bounds, grid.res, f);
                    match self.plie.cell(grid, c) {
                        Cell::Umbra => {
                            out[k] = ctx.stats.answered(Answer::Umbra, true);
                            sc.path[k] = path::DONE;
                            continue;
                        }
                        Cell::Scene => None,
                        Cell::Blockers([]) => Some(None),
                        Cell::Blockers(_) => Some(Some((grid.cells_start as usize + c) as u32 | CELL_KEY)),
                    }
                }
                _ if scene_record => None,
                _ => Some(Some(ri as u32).filter(|_| self.plie.records[ri].blockers_len > 0)),
            };
            let Some(key) = key else {
                // The whole segment, by the scene BVH, as `occluded` does.
                let before = ctx.stats.triangle_tests;
                let hit = segment_occluded(self.scene, self.bvh, &rays.ray(k), ctx);
                ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
                out[k] = ctx.stats.answered(Answer::SceneBvh, hit);
                sc.path[k] = path::DONE;
                continue;
            };
            if let Some(key) = key {
                sc.path[k] = path::LIST;
                let i = match sc.lists.iter().position(|&l| l == key) {
                    Some(i) => i,
                    None => {
                        sc.lists.push(key);
                        sc.lists.len() - 1
                    }
                };
                sc.list[k] = i as u32;
            }
        }
        let open = sc.path.iter().filter(|&&p| p != path::DONE).count();
        ctx.stats.lights.queries += 1;
        if open == 0 {
            if out.iter().all(|&o| o) {
                ctx.stats.lights.whole_umbra += 1;
            } else {
                ctx.stats.lights.gathered += 1;
            }
        } else {
            let lanes_before = ctx.stats.lane_tests;
            let margin = self.pad * 10.0;
            sc.fan.set(rays);
            sc.fan.pyramid.set(x, &self.scene.lights[rays.light.idx()], margin);
            // Short lists: their triangles, each once, against every ray that has a short list (a
            // ray tested against another ray's blockers too can only find true blockers). Long lists
            // (with chunk boxes) are walked by the rays that have them, all at once, with the same
            // box tests as `occluded` does per ray: a thin segment culls their chunks far better
            // than the pyramid does.
            let before = ctx.stats.triangle_tests;
            let long = |key: u32| self.list_of(key).is_long();
            for (i, &key) in sc.lists.iter().enumerate() {
                if long(key) {
                    let list_of = &sc.list;
                    sc.fan.select(|k| list_of[k] == i as u32);
                    self.walk_list(rays, self.list_of(key), &mut sc.fan, out, ctx);
                }
            }
            let (lists, list_of) = (&sc.lists, &sc.list);
            sc.fan.select(|k| list_of[k] != u32::MAX && !long(lists[list_of[k] as usize]));
            ctx.begin_query();
            for &key in &sc.lists {
                if !long(key) {
                    self.fan_list(rays, self.list_of(key), true, &mut sc.fan, out, ctx);
                }
            }
            ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
            // The leaf's own triangles against every ray still open.
            for k in 0..n {
                if sc.path[k] == path::LIST && out[k] {
                    sc.path[k] = path::LIST_HIT;
                }
            }
            let paths = &sc.path;
            sc.fan.select(|k| paths[k] != path::DONE && !out[k]);
            let before = ctx.stats.triangle_tests;
            let (start, len) = self.own[leaf.idx()];
            let own = self.own_boxes.of(leaf.idx(), &self.own_tris[start as usize..(start + len) as usize]);
            self.fan_list(rays, own, false, &mut sc.fan, out, ctx);
            ctx.stats.own_leaf_tests += ctx.stats.triangle_tests - before;
            for k in 0..n {
                let a = match (sc.path[k], out[k]) {
                    (path::DONE, _) => continue,
                    (path::LIST_HIT, _) => Answer::BlockersHit,
                    (_, true) => Answer::OwnLeaf,
                    (path::LIT, false) => Answer::Lit,
                    (path::LIST, false) => Answer::BlockersMiss,
                    _ => Answer::InsideLeaf,
                };
                ctx.stats.answered(a, out[k]);
            }
            if ctx.stats.lane_tests == lanes_before {
                ctx.stats.lights.whole_lit += 1;
            } else {
                ctx.stats.lights.per_sample += 1;
            }
        }
        ctx.light = scratch;
    }
}

/// How a ray of a per-light query is answered if no candidate triangle hits it, and then whether
/// one did.
mod path {
    /// Already answered (occluded: no record, or umbra).
    pub const DONE: u8 = 0;
    /// No blocker to test: lit.
    pub const LIT: u8 = 1;
    /// Its blocker list is to be tested.
    pub const LIST: u8 = 2;
    /// It never leaves the leaf.
    pub const INSIDE: u8 = 3;
    /// Its blocker list hit it.
    pub const LIST_HIT: u8 = 4;
}

/// Fewer samples than this are asked ray by ray: with so few, sharing work does not pay (measured at
/// 4 samples per light, `plie bench --soft-shadows`).
const FAN_MIN: usize = 8;

impl LieVisibility<'_> {
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
        ctx.stats.lights.queries += 1;
        let margin = self.pad * 10.0;
        sc.fan.pyramid.set(rays.origin, &self.scene.lights[rays.light.idx()], margin);
        let (start, len) = self.own[leaf.idx()];
        let own = self.own_boxes.of(leaf.idx(), &self.own_tris[start as usize..(start + len) as usize]);
        let before = ctx.stats.triangle_tests;
        let lanes_before = ctx.stats.lane_tests;
        if self.any_in_pyramid(rays, own, &sc.fan.pyramid, ctx) {
            sc.fan.set(rays);
            sc.fan.select_all();
            self.fan_list(rays, own, false, &mut sc.fan, out, ctx);
        }
        ctx.stats.own_leaf_tests += ctx.stats.triangle_tests - before;
        let hits = out.iter().filter(|&&o| o).count();
        ctx.stats.answers.count_n(Answer::OwnLeaf, hits);
        ctx.stats.answers.count_n(Answer::Lit, out.len() - hits);
        if ctx.stats.lane_tests == lanes_before {
            ctx.stats.lights.whole_lit += 1;
        } else {
            ctx.stats.lights.per_sample += 1;
        }
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
                    if t == rays.origin_tri || vis.scene.tri_light[t.idx()] == Some(rays.light) {
                        return false;
                    }
                    self.ctx.stats.box_tests += 1;
                    !self.pyramid.culls(&vis.scene.triangles[t.idx()])
                })
            }
        }
        list.walk(&mut Cull { vis: self, rays, pyramid, ctx })
    }

    /// Tests the long list `list` against the fan's active rays as [`Self::any_blocks`] does ray by
    /// ray: its group boxes, then the chunk boxes inside the groups a ray meets, then the triangle
    /// boxes inside those chunks, and the watertight test for the triangles whose box a ray meets,
    /// until the ray is found occluded. All active rays go down the hierarchy together, eight per
    /// box test ([`Fan::narrow`]).
    fn walk_list(&self, rays: &LightRays, list: Chunked, fan: &mut Fan, out: &mut [bool], ctx: &mut QueryCtx) {
        /// The fan's active rays down the hierarchy.
        struct Rays<'v, 'a, 'c> {
            vis: &'v LieVisibility<'a>,
            rays: &'v LightRays<'v>,
            fan: &'c mut Fan,
            out: &'c mut [bool],
            ctx: &'c mut QueryCtx,
        }
        impl ListVisitor for Rays<'_, '_, '_> {
            #[inline]
            fn enter(&mut self, b: &Aabb, depth: usize) -> bool {
                self.fan.narrow(b, depth, self.ctx)
            }
            #[inline]
            fn chunk(&mut self, tris: &[TriId], depth: usize) -> bool {
                let (vis, rays) = (self.vis, self.rays);
                for &t in tris {
                    if t == rays.origin_tri || vis.scene.tri_light[t.idx()] == Some(rays.light) {
                        continue;
                    }
                    if self.fan.narrow(&vis.tri_boxes[t.idx()], depth + 1, self.ctx) {
                        self.fan.test_level(vis.scene, rays, t, depth + 1, self.out, self.ctx);
                    }
                }
                self.fan.live() == 0
            }
        }
        fan.narrow_to_open(0);
        list.walk(&mut Rays { vis: self, rays, fan, out, ctx });
    }

    /// Tests the triangles `tris` that the pyramid does not cull against the fan's open active rays,
    /// marking those hit in `out`; with `once`, only those not met before in the query.
    #[inline]
    fn fan_tris(
        &self,
        rays: &LightRays,
        tris: &[TriId],
        once: bool,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        for &t in tris {
            if fan.live() == 0 {
                return;
            }
            if t == rays.origin_tri
                || self.scene.tri_light[t.idx()] == Some(rays.light)
                || (once && !ctx.first_visit(t))
            {
                continue;
            }
            ctx.stats.box_tests += 1;
            if fan.pyramid.culls(&self.scene.triangles[t.idx()]) {
                continue;
            }
            fan.test(self.scene, rays, t, out, ctx);
        }
    }

    /// [`Self::fan_tris`] over a blocker list, skipping the boxes of its hierarchy that the
    /// pyramid culls.
    fn fan_list(
        &self,
        rays: &LightRays,
        list: Chunked,
        once: bool,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        /// The pyramid down the hierarchy, then the fan at its chunks.
        struct Tris<'v, 'a, 'c> {
            vis: &'v LieVisibility<'a>,
            rays: &'v LightRays<'v>,
            once: bool,
            fan: &'c mut Fan,
            out: &'c mut [bool],
            ctx: &'c mut QueryCtx,
        }
        impl ListVisitor for Tris<'_, '_, '_> {
            #[inline]
            fn enter(&mut self, b: &Aabb, _: usize) -> bool {
                self.ctx.stats.box_tests += 1;
                self.fan.live() > 0 && !self.fan.pyramid.culls_box(b)
            }
            #[inline]
            fn chunk(&mut self, tris: &[TriId], _: usize) -> bool {
                self.vis.fan_tris(self.rays, tris, self.once, self.fan, self.out, self.ctx);
                self.fan.live() == 0
            }
        }
        if fan.live() > 0 {
            list.walk(&mut Tris { vis: self, rays, once, fan, out, ctx });
        }
    }
}
