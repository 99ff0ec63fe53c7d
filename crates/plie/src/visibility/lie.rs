//! SPEC §5 modes (b)-(d) and our `grid`, all answered from the P-LIE. The segment from `x` (in leaf
//! `c`) to the light sample leaves `c` through one face `F`, crossing it at `f`. No record for
//! (F, light): occluded. Otherwise, by mode:
//!
//! - `lie` (b): test the record's blockers (they cover the part of the segment beyond `F`, which lies
//!   in conv(F ∪ light));
//! - `umbra` (c): `f` in the record's umbra triangles: occluded; else as (b);
//! - `penumbra` (d): as (c), and `f` outside both umbra and penumbra: no blocker can hit, skip them;
//! - `grid`: the face-grid cell of `f` says umbra (occluded) or which blockers to test.
//!
//! A record that stores no list ([`RecordKind::Scene`], issue 15) answers a ray outside its umbra (or
//! its grid's umbra cells) by the scene BVH, for the whole segment ([`Answer::SceneBvh`]).
//!
//! Then the triangles of `c` itself (the part of the segment inside `c`). A segment that never leaves
//! `c` only needs `c`'s triangles. Regions are conservative (see [`crate::construct::regions`]), so
//! every mode answers exactly as the blocker test would.
//!
//! Each ray is counted on the [`Answer`] path that decided it, and its triangle tests are split into
//! blocker tests and own-leaf tests (`plie render --stats`).

use super::bvh::{segment_occluded, Bvh};
use super::fan::{Fan, LightScratch, Pyramid};
use super::footprint::{footprints, FaceFootprint};
use super::leaf_voxels::LeafVoxels;
use super::list_boxes::{Chunked, ListBoxes, ListVisitor};
use super::query::SEGMENT_EPS;
use super::{blocks, Answer, LightRays, Mode, OctreeVisibility, QueryCtx, ShadowRay, Visibility};
use crate::geometry::{Aabb, Segment};
use crate::lie::frame::{in_triangles, FaceFrame};
use crate::lie::grid;
use crate::lie::{Cell, Plie, RecordKind};
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{Scene, TriId};

/// Modes (b)-(d) and `grid`: the P-LIE's blocker lists, regions and face grids.
///
/// Before a candidate gets the watertight test, its bounding box (grown by the construction tolerance)
/// is tested against the segment, and in a long list the box of its chunk first ([`ListBoxes`]):
/// conservative culls (SPEC §8 point 4) that never change an answer.
pub struct LieVisibility<'a> {
    scene: &'a Scene,
    octree: &'a Octree,
    plie: &'a Plie,
    /// The scene BVH, for the records that store no list.
    bvh: &'a Bvh,
    /// Grown bounding box of every triangle.
    tri_boxes: Vec<Aabb>,
    /// `Lie`, `Umbra`, `Penumbra` or `Grid`.
    mode: Mode,
    /// Voxel grids over the leaves' own triangles.
    voxels: LeafVoxels,
    /// Chunk boxes of the records' blocker lists.
    record_boxes: ListBoxes,
    /// Chunk boxes of the face-grid cells' lists.
    cell_boxes: ListBoxes,
    /// The construction tolerance (how far triangle boxes are grown).
    pad: f32,
    /// Per leaf, its own triangles in Morton order (`(start, len)` into `own_tris`), with chunk
    /// boxes: the per-light query culls them by chunk against its pyramid.
    own: Vec<(u32, u32)>,
    own_tris: Vec<TriId>,
    own_boxes: ListBoxes,
    /// In `grid`: per record, where its grid's tables start in `sat` (`u32::MAX`: no grid).
    sat_start: Vec<u32>,
    /// Summed-area tables of each face grid, `(res + 1)^2` pairs each: the number of cells that are
    /// not lit (umbra, scene or a non-empty list) and of cells that are not umbra, in the cells
    /// `[0, i) x [0, j)`. A footprint's cells are then counted in four lookups.
    sat: Vec<[u32; 2]>,
}

/// Summed-area tables of the face grids of `plie` (see [`LieVisibility::sat`]).
fn grid_tables(plie: &Plie) -> (Vec<u32>, Vec<[u32; 2]>) {
    let mut start = Vec::with_capacity(plie.grids.len());
    let mut sat = Vec::new();
    for grid in &plie.grids {
        if grid.res == 0 {
            start.push(u32::MAX);
            continue;
        }
        start.push(sat.len() as u32);
        let g = grid.res as usize;
        let base = sat.len();
        sat.resize(base + (g + 1) * (g + 1), [0, 0]);
        for j in 0..g {
            for i in 0..g {
                let (not_lit, not_umbra) = match plie.cell(grid, j * g + i) {
                    Cell::Umbra => (1, 0),
                    Cell::Scene => (1, 1),
                    Cell::Blockers(l) => (u32::from(!l.is_empty()), 1),
                };
                let at = |i: usize, j: usize| base + j * (g + 1) + i;
                let (a, b, c) = (sat[at(i, j + 1)], sat[at(i + 1, j)], sat[at(i, j)]);
                sat[at(i + 1, j + 1)] = [a[0] + b[0] - c[0] + not_lit, a[1] + b[1] - c[1] + not_umbra];
            }
        }
    }
    (start, sat)
}

impl<'a> LieVisibility<'a> {
    /// Mode `mode` (one of `Lie`, `Umbra`, `Penumbra`, `Grid`; others answer as `Lie`) over a P-LIE
    /// built for `scene` and `octree`. Without regions or grids in the P-LIE, the modes that use them
    /// test the blockers instead (still exact).
    pub fn new(scene: &'a Scene, bvh: &'a Bvh, octree: &'a Octree, plie: &'a Plie, mode: Mode) -> LieVisibility<'a> {
        let pad = scene.scale() * crate::geometry::TOLERANCE_REL;
        let tri_boxes: Vec<Aabb> = scene.triangles.iter().map(|t| t.aabb().expanded(pad)).collect();
        let voxels = LeafVoxels::new(octree, &tri_boxes, pad);
        let records = plie.records.iter().map(|r| (r.blockers_start, r.blockers_len));
        let record_boxes = ListBoxes::new(records, &plie.blockers, &tri_boxes);
        let cell_boxes = if mode == Mode::Grid {
            ListBoxes::new(plie.cells.iter().copied(), &plie.cell_blockers, &tri_boxes)
        } else {
            ListBoxes::default()
        };
        let mut own = Vec::with_capacity(octree.leaf_count());
        let mut own_tris = Vec::new();
        for leaf in octree.leaves() {
            let start = own_tris.len();
            own_tris.extend_from_slice(octree.leaf_triangles(leaf));
            crate::lie::order::sort_spatially(scene, &mut own_tris[start..]);
            own.push((start as u32, (own_tris.len() - start) as u32));
        }
        let own_boxes = ListBoxes::new(own.iter().copied(), &own_tris, &tri_boxes);
        let (sat_start, sat) = if mode == Mode::Grid { grid_tables(plie) } else { (Vec::new(), Vec::new()) };
        LieVisibility {
            scene,
            octree,
            plie,
            bvh,
            tri_boxes,
            voxels,
            mode,
            record_boxes,
            cell_boxes,
            pad,
            own,
            own_tris,
            own_boxes,
            sat_start,
            sat,
        }
    }

    /// The whole light at once, from its footprints on the faces of `leaf` ([`footprints`]), if
    /// they decide it: `Some(true)` if every sample's ray is occluded (each leaves the leaf through
    /// a face without a record or through umbra cells), `Some(false)` if no blocker list can hit
    /// any of them (every footprint lies in lit cells, or on records with empty lists) so that only
    /// the leaf's own triangles remain to test, `None` otherwise.
    fn whole_light(
        &self,
        leaf: LeafId,
        bounds: &Aabb,
        rays: &LightRays,
        feet: &mut Vec<FaceFootprint>,
    ) -> Option<bool> {
        let light = &self.scene.lights[rays.light.idx()];
        let all_exit = footprints(bounds, rays.origin, &light.vertices, SEGMENT_EPS, feet);
        let (mut lit, mut umbra) = (true, all_exit);
        for fp in feet.iter() {
            let Some(ri) = self.plie.record_id(leaf, fp.face, rays.light) else {
                lit = false;
                continue;
            };
            let record = &self.plie.records[ri];
            match self.sat_start.get(ri).copied().filter(|&s| s != u32::MAX) {
                Some(start) => {
                    let g = self.plie.grids[ri].res as usize;
                    let k = fp.face.axis();
                    let (u, v) = crate::lie::frame::face_axes(k);
                    let cell = |x: f64, axis: usize| {
                        let (lo, hi) = (bounds.min[axis] as f64, bounds.max[axis] as f64);
                        (((x - lo) / (hi - lo) * g as f64).max(0.0) as usize).min(g - 1)
                    };
                    let (i0, i1) = (cell(fp.rect[0], u), cell(fp.rect[1], u));
                    let (j0, j1) = (cell(fp.rect[2], v), cell(fp.rect[3], v));
                    let at = |i: usize, j: usize| self.sat[start as usize + j * (g + 1) + i];
                    let count =
                        |w: usize| at(i1 + 1, j1 + 1)[w] + at(i0, j0)[w] - at(i0, j1 + 1)[w] - at(i1 + 1, j0)[w];
                    lit &= count(0) == 0;
                    umbra &= count(1) == 0;
                }
                None => {
                    lit &= record.kind == RecordKind::Listed && record.blockers_len == 0;
                    umbra = false;
                }
            }
            if !lit && !umbra {
                return None;
            }
        }
        if umbra {
            Some(true)
        } else if lit {
            Some(false)
        } else {
            None
        }
    }

    /// The box cull, then the shared predicate.
    #[inline]
    fn test(&self, seg: &Segment, ray: &ShadowRay, t: TriId, ctx: &mut QueryCtx) -> bool {
        ctx.stats.box_tests += 1;
        seg.clip(&self.tri_boxes[t.idx()]).is_some() && blocks(self.scene, ray, t, ctx)
    }

    /// True if a triangle of `l` blocks the ray (stopping at the first; in a long list, only inside
    /// the groups and chunks whose box the segment meets), and the number of triangle tests that took.
    #[inline]
    fn any_blocks(&self, seg: &Segment, ray: &ShadowRay, l: Chunked, ctx: &mut QueryCtx) -> (bool, u64) {
        /// A ray down the hierarchy.
        struct Ray<'v, 'a, 'c> {
            vis: &'v LieVisibility<'a>,
            seg: &'v Segment,
            ray: &'v ShadowRay,
            ctx: &'c mut QueryCtx,
        }
        impl ListVisitor for Ray<'_, '_, '_> {
            #[inline]
            fn enter(&mut self, b: &Aabb, _: usize) -> bool {
                self.ctx.stats.box_tests += 1;
                self.seg.clip(b).is_some()
            }
            #[inline]
            fn chunk(&mut self, tris: &[TriId], _: usize) -> bool {
                tris.iter().any(|&t| self.vis.test(self.seg, self.ray, t, self.ctx))
            }
        }
        let before = ctx.stats.triangle_tests;
        let hit = l.walk(&mut Ray { vis: self, seg, ray, ctx });
        (hit, ctx.stats.triangle_tests - before)
    }
}

/// The face through which the segment `ray` leaves the box of `leaf` and the segment parameter where
/// it does, or `None` if it stays inside for its whole open range.
#[inline]
pub fn exit_face(octree: &Octree, leaf: LeafId, ray: &ShadowRay) -> Option<(Dir, f32)> {
    exit_face_of(&octree.leaf_bounds(leaf), ray.test.origin, ray.test.dir, ray.test.t_max)
}

/// [`exit_face`] for the box `b` and the segment `o + t d`, `t < t_max`.
#[inline]
fn exit_face_of(b: &Aabb, o: glam::Vec3, d: glam::Vec3, t_max: f32) -> Option<(Dir, f32)> {
    let mut best = (t_max, None);
    for k in 0..3 {
        let (t, positive) = if d[k] > 0.0 {
            ((b.max[k] - o[k]) / d[k], true)
        } else if d[k] < 0.0 {
            ((b.min[k] - o[k]) / d[k], false)
        } else {
            continue;
        };
        if t < best.0 {
            best = (t, Some(Dir::from_axis(k, positive)));
        }
    }
    best.1.map(|d| (d, best.0))
}

impl Visibility for LieVisibility<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        let Some(leaf) = ray.leaf.or_else(|| self.octree.locate(ray.origin())) else {
            // Outside the octree: no environment to consult.
            let hit = OctreeVisibility::new(self.scene, self.octree).occluded(ray, ctx);
            return ctx.stats.answered(Answer::OutsideOctree, hit);
        };
        let seg = Segment::new(ray.test.origin, ray.test.dir, ray.test.t_min, ray.test.t_max);
        let exit = exit_face(self.octree, leaf, ray);
        // The path the ray takes if the leaf's own triangles miss it.
        let through = match exit {
            None => Answer::InsideLeaf,
            Some((face, t_exit)) => {
                let Some(ri) = self.plie.record_id(leaf, face, ray.light) else {
                    return ctx.stats.answered(Answer::NoRecord, true);
                };
                let f = ray.test.origin + ray.test.dir * t_exit;
                let scene_record = self.plie.records[ri].kind == RecordKind::Scene;
                let record = || self.record_boxes.of(ri, self.plie.blockers_of(&self.plie.records[ri]));
                // `None`: the record stores no list; the scene answers.
                let list = match self.mode {
                    Mode::Umbra | Mode::Penumbra => {
                        let x = FaceFrame::new(face, &self.octree.leaf_bounds(leaf)).units(f.as_dvec3());
                        if in_triangles(self.plie.umbra_of(ri), x) {
                            return ctx.stats.answered(Answer::Umbra, true);
                        }
                        if scene_record {
                            None
                        } else if self.mode == Mode::Penumbra && !in_triangles(self.plie.penumbra_of(ri), x) {
                            Some(Chunked::EMPTY)
                        } else {
                            Some(record())
                        }
                    }
                    Mode::Grid if self.plie.grids[ri].res > 0 => {
                        let grid = &self.plie.grids[ri];
                        let c = grid::cell_of(face, &self.octree.leaf_bounds(leaf), grid.res, f);
                        match self.plie.cell(grid, c) {
                            Cell::Umbra => return ctx.stats.answered(Answer::Umbra, true),
                            Cell::Scene => None,
                            Cell::Blockers(list) => Some(self.cell_boxes.of(grid.cells_start as usize + c, list)),
                        }
                    }
                    _ => (!scene_record).then(record),
                };
                let Some(list) = list else {
                    // The whole segment, by the scene BVH; its triangle tests count as blocker tests.
                    let before = ctx.stats.triangle_tests;
                    let hit = segment_occluded(self.scene, self.bvh, ray, ctx);
                    ctx.stats.blocker_tests += ctx.stats.triangle_tests - before;
                    return ctx.stats.answered(Answer::SceneBvh, hit);
                };
                if list.list.is_empty() {
                    Answer::Lit
                } else {
                    let (hit, tests) = self.any_blocks(&seg, ray, list, ctx);
                    ctx.stats.blocker_tests += tests;
                    if hit {
                        return ctx.stats.answered(Answer::BlockersHit, true);
                    }
                    Answer::BlockersMiss
                }
            }
        };
        // The leaf's own triangles along the part of the segment inside the leaf.
        let (o, d) = (ray.test.origin, ray.test.dir);
        let t_end = exit.map_or(ray.test.t_max, |(_, t)| t.min(ray.test.t_max));
        let part = (o + d * ray.test.t_min, o + d * t_end);
        let before = ctx.stats.triangle_tests;
        ctx.begin_query();
        let hit = self.voxels.any(self.octree, leaf, &seg, part, ctx, |t, ctx| self.test(&seg, ray, t, ctx));
        ctx.stats.own_leaf_tests += ctx.stats.triangle_tests - before;
        if hit {
            ctx.stats.answered(Answer::OwnLeaf, true)
        } else {
            ctx.stats.answered(through, false)
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
    fn occluded_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
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
        match self.whole_light(leaf, &bounds, rays, &mut sc.feet) {
            Some(true) => {
                out.fill(true);
                ctx.stats.lights.queries += 1;
                ctx.stats.lights.whole_umbra += 1;
                for _ in 0..n {
                    ctx.stats.answered(Answer::Umbra, true);
                }
                ctx.light = scratch;
                return;
            }
            Some(false) => {
                self.own_only(leaf, rays, sc, out, ctx);
                ctx.light = scratch;
                return;
            }
            None => {}
        }
        sc.fan.set(rays);
        sc.path.clear();
        sc.path.resize(n, path::LIT);
        sc.list.clear();
        sc.list.resize(n, u32::MAX);
        sc.lists.clear();
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
                ctx.stats.lights.per_sample += 1;
            }
        } else {
            let lanes_before = ctx.stats.lane_tests;
            let margin = self.pad * 10.0;
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

/// A blocker list key of a per-light query: a record's index, or a face-grid cell's index with the
/// top bit set.
const CELL_KEY: u32 = 1 << 31;

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
            sc.fan.select(|_| true);
            self.fan_list(rays, own, false, &mut sc.fan, out, ctx);
        }
        ctx.stats.own_leaf_tests += ctx.stats.triangle_tests - before;
        for &o in out.iter() {
            ctx.stats.answered(if o { Answer::OwnLeaf } else { Answer::Lit }, o);
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::construct::build;
    use crate::lie::{Grids, PlieParams, CHUNK, CHUNKED_MIN};
    use crate::render::NoProgress;

    /// Every triangle of a long list lies in its chunk's box and that in its group's box; shared
    /// ranges share boxes; long lists are stored in Morton order, so chunks are tighter than in id
    /// order.
    #[test]
    fn chunk_boxes_cover_their_lists() {
        let scene = crate::scene::builtin::load("huis-a").unwrap();
        let params = PlieParams { grids: Grids::Build, ..PlieParams::thesis() };
        let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
        let (plie, _) = build(&scene, &octree, params, &NoProgress);
        let bvh = crate::visibility::bvh::Bvh::build(&scene);
        let vis = LieVisibility::new(&scene, &bvh, &octree, &plie, Mode::Grid);
        let inside = |a: &Aabb, b: &Aabb| b.min.cmple(a.min).all() && a.max.cmple(b.max).all();
        let (mut long, mut volume_sorted, mut volume_ids) = (0, 0.0f64, 0.0f64);
        for (ri, r) in plie.records.iter().enumerate() {
            let l = vis.record_boxes.of(ri, plie.blockers_of(r));
            if l.list.len() < CHUNKED_MIN {
                assert!(!l.is_long());
                continue;
            }
            long += 1;
            let chunks = l.level(0);
            assert_eq!(chunks.len(), l.list.len().div_ceil(CHUNK));
            for (k, chunk) in l.list.chunks(CHUNK).enumerate() {
                assert!(chunk.iter().all(|t| inside(&vis.tri_boxes[t.idx()], &chunks[k])));
                let vol = |b: Aabb| b.size().as_dvec3().element_product();
                volume_sorted += vol(chunks[k]);
                let mut ids = l.list.to_vec();
                ids.sort_unstable();
                let by_id = ids[k * CHUNK..(k * CHUNK + CHUNK).min(ids.len())].iter().map(|t| vis.tri_boxes[t.idx()]);
                volume_ids += vol(by_id.reduce(Aabb::union).unwrap());
            }
            // Each box lies in its parent's, up to a single box.
            let mut level = 0;
            while l.level(level).len() > 1 {
                let (below, above) = (l.level(level), l.level(level + 1));
                assert_eq!(above.len(), below.len().div_ceil(CHUNK));
                for (k, b) in below.iter().enumerate() {
                    assert!(inside(b, &above[k / CHUNK]));
                }
                level += 1;
            }
            assert_eq!(l.level(level).len(), 1);
        }
        assert!(long > 10, "{long} long lists");
        assert!(volume_sorted < volume_ids, "Morton chunks {volume_sorted} vs id chunks {volume_ids}");
        // Cells sharing a list share its boxes.
        let b = &vis.cell_boxes;
        for (c, &(start, len)) in plie.cells.iter().enumerate() {
            if b.first[c] == u32::MAX {
                continue;
            }
            let other = plie.cells.iter().position(|&x| x == (start, len)).unwrap();
            assert_eq!(b.first[c], b.first[other]);
        }
    }
}
