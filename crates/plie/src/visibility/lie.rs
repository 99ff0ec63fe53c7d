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
use super::fan::Fan;
use super::leaf_voxels::LeafVoxels;
use super::query::SEGMENT_EPS;
use super::{blocks, Answer, LightRays, Mode, OctreeVisibility, QueryCtx, ShadowRay, Visibility};
use crate::geometry::{Aabb, Segment};
use crate::lie::frame::{in_triangles, FaceFrame};
use crate::lie::grid;
use crate::lie::{Cell, Plie, RecordKind, CHUNK, CHUNKED_MIN};
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{Scene, TriId};

/// The boxes of consecutive chunks of [`CHUNK`] blockers of every long list, and of groups of
/// [`CHUNK`] chunks (SPEC §8 point 4): a ray tests a group's box, then its chunks' boxes, before the
/// boxes of their blockers, so it skips most of a long list whose triangles lie away from it. Long
/// lists are stored in Morton order ([`crate::geometry::morton`]), so chunks are compact. Built when
/// the visibility is made; conservative culls, so answers do not change.
#[derive(Default)]
struct ListBoxes {
    /// Per list: the index of its first chunk box in `boxes`, or `u32::MAX` for a short list.
    first: Vec<u32>,
    /// Chunk boxes (unions of the grown triangle boxes).
    boxes: Vec<Aabb>,
    /// Per list: the index of its first group box in `groups` (`u32::MAX` for a short list).
    first_group: Vec<u32>,
    /// Boxes of groups of [`CHUNK`] consecutive chunks.
    groups: Vec<Aabb>,
}

impl ListBoxes {
    /// Chunk and group boxes of the lists `ranges` (start, len) of `refs`. Ranges may repeat (grid
    /// cells share lists): a repeated range shares its boxes.
    fn new(ranges: impl Iterator<Item = (u32, u32)>, refs: &[TriId], tri_boxes: &[Aabb]) -> ListBoxes {
        let mut out = ListBoxes::default();
        let mut seen: std::collections::HashMap<u32, (u32, u32)> = std::collections::HashMap::new();
        for (start, len) in ranges {
            if (len as usize) < CHUNKED_MIN || start == u32::MAX {
                out.first.push(u32::MAX);
                out.first_group.push(u32::MAX);
                continue;
            }
            let (f, g) = *seen.entry(start).or_insert_with(|| {
                let (f, g) = (out.boxes.len(), out.groups.len());
                let union = |it: &mut dyn Iterator<Item = Aabb>| it.reduce(Aabb::union).expect("not empty");
                for chunk in refs[start as usize..(start + len) as usize].chunks(CHUNK) {
                    out.boxes.push(union(&mut chunk.iter().map(|t| tri_boxes[t.idx()])));
                }
                for group in out.boxes[f..].chunks(CHUNK) {
                    out.groups.push(union(&mut group.iter().copied()));
                }
                (f as u32, g as u32)
            });
            out.first.push(f);
            out.first_group.push(g);
        }
        out
    }

    /// List `i` (stored at `list`) with its chunk and group boxes if it is long.
    #[inline]
    fn of<'s>(&'s self, i: usize, list: &'s [TriId]) -> Chunked<'s> {
        match self.first[i] {
            u32::MAX => Chunked { list, chunks: &[], groups: &[] },
            f => {
                let (f, g) = (f as usize, self.first_group[i] as usize);
                let n = list.len().div_ceil(CHUNK);
                Chunked { list, chunks: &self.boxes[f..f + n], groups: &self.groups[g..g + n.div_ceil(CHUNK)] }
            }
        }
    }
}

/// A blocker list with, if long, the boxes of its chunks and of its groups of chunks.
#[derive(Clone, Copy)]
struct Chunked<'a> {
    list: &'a [TriId],
    chunks: &'a [Aabb],
    groups: &'a [Aabb],
}

impl Chunked<'_> {
    const EMPTY: Chunked<'static> = Chunked { list: &[], chunks: &[], groups: &[] };
}

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
        let before = ctx.stats.triangle_tests;
        let meets = |b: &Aabb, ctx: &mut QueryCtx| {
            ctx.stats.box_tests += 1;
            seg.clip(b).is_some()
        };
        // The chunks of `tris` whose boxes (`boxes`) the segment meets.
        let scan = |tris: &[TriId], boxes: &[Aabb], ctx: &mut QueryCtx| {
            tris.chunks(CHUNK)
                .zip(boxes)
                .any(|(chunk, b)| meets(b, ctx) && chunk.iter().any(|&t| self.test(seg, ray, t, ctx)))
        };
        let hit = if l.chunks.is_empty() {
            l.list.iter().any(|&t| self.test(seg, ray, t, ctx))
        } else if l.groups.len() == 1 {
            // One group: its box would only repeat the chunks' tests.
            scan(l.list, l.chunks, ctx)
        } else {
            let per_group = CHUNK * CHUNK;
            l.groups.iter().enumerate().any(|(gi, g)| {
                meets(g, ctx) && {
                    let tris = &l.list[gi * per_group..l.list.len().min((gi + 1) * per_group)];
                    scan(tris, &l.chunks[gi * CHUNK..l.chunks.len().min((gi + 1) * CHUNK)], ctx)
                }
            })
        };
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
        sc.fan.set(rays);
        sc.path.clear();
        sc.path.resize(n, path::LIT);
        sc.list.clear();
        sc.list.resize(n, u32::MAX);
        sc.lists.clear();
        out.fill(false);
        let bounds = self.octree.leaf_bounds(leaf);
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
            // (with chunk boxes) are walked ray by ray as `occluded` does: a thin segment culls their
            // chunks far better than the pyramid does.
            let before = ctx.stats.triangle_tests;
            let long = |key: u32| !self.list_of(key).chunks.is_empty();
            for k in 0..n {
                if sc.list[k] != u32::MAX && long(sc.lists[sc.list[k] as usize]) {
                    let ray = rays.ray(k);
                    let seg = Segment::new(ray.test.origin, ray.test.dir, ray.test.t_min, ray.test.t_max);
                    out[k] = self.any_blocks(&seg, &ray, self.list_of(sc.lists[sc.list[k] as usize]), ctx).0;
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

    /// [`Self::fan_tris`] over a blocker list, skipping the groups and chunks whose boxes the
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
        if list.chunks.is_empty() {
            return self.fan_tris(rays, list.list, once, fan, out, ctx);
        }
        let per_group = CHUNK * CHUNK;
        for (gi, group) in list.list.chunks(per_group).enumerate() {
            if fan.live() == 0 {
                return;
            }
            if list.groups.len() > 1 {
                ctx.stats.box_tests += 1;
                if fan.pyramid.culls_box(&list.groups[gi]) {
                    continue;
                }
            }
            for (ci, chunk) in group.chunks(CHUNK).enumerate() {
                ctx.stats.box_tests += 1;
                if !fan.pyramid.culls_box(&list.chunks[gi * CHUNK + ci]) {
                    self.fan_tris(rays, chunk, once, fan, out, ctx);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::construct::build;
    use crate::lie::{Grids, PlieParams};
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
                assert!(l.chunks.is_empty() && l.groups.is_empty());
                continue;
            }
            long += 1;
            for (k, chunk) in l.list.chunks(CHUNK).enumerate() {
                assert!(chunk.iter().all(|t| inside(&vis.tri_boxes[t.idx()], &l.chunks[k])));
                assert!(inside(&l.chunks[k], &l.groups[k / CHUNK]));
                let vol = |b: Aabb| b.size().as_dvec3().element_product();
                volume_sorted += vol(l.chunks[k]);
                let mut ids = l.list.to_vec();
                ids.sort_unstable();
                let by_id = ids[k * CHUNK..(k * CHUNK + CHUNK).min(ids.len())].iter().map(|t| vis.tri_boxes[t.idx()]);
                volume_ids += vol(by_id.reduce(Aabb::union).unwrap());
            }
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
