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
//!
//! All the samples of one light from one point (the per-light query, issue 21) are answered together
//! in `light.rs`: from the light's footprints on the leaf's faces where they decide it, else from
//! the triangles in the shaft of the point's piece of surface (`shafts.rs`) or by the scene BVH
//! walked by all the samples at once.

mod light;
mod shafts;
mod whole;

use super::bvh::{segment_occluded, Bvh, Cut};
use super::leaf_voxels::LeafVoxels;
use super::list_boxes::{Chunked, ListBoxes, ListVisitor};
use super::pyramid::{self, Pyramid, PyramidBasis};
use super::{blocks, Answer, LightRays, Mode, OctreeVisibility, QueryCtx, ShadowRay, Visibility};
use glam::Vec3;

use crate::geometry::{Aabb, Segment};
use crate::lie::frame::{in_triangles, FaceFrame};
use crate::lie::grid;
use crate::lie::{Cell, Plie, RecordKind};
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{LightId, Scene, TriId};
use std::sync::OnceLock;

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
    /// Per leaf, its own triangles in Morton order (`(start, len)` into `own_tris`), with chunk
    /// boxes: the per-light query culls them by chunk against its pyramid.
    own: Vec<(u32, u32)>,
    own_tris: Vec<TriId>,
    own_boxes: ListBoxes,
    /// In `grid`: per record, where its grid's tables start in `sat` (`u32::MAX`: no grid).
    sat_start: Vec<u32>,
    /// Summed-area tables of each face grid, `(res + 1)^2` triples each: the number of cells that
    /// are not lit (umbra, scene or a non-empty list), of cells that are not umbra, and of cells
    /// without a list (umbra or scene), in the cells `[0, i) x [0, j)`. A footprint's cells are then
    /// counted in four lookups.
    sat: Vec<[u32; 3]>,
    /// Per (leaf, light), `leaf * lights + light`: where the scene BVH's walk starts for a light
    /// answered by the scene ([`Bvh::cut_of`] the leaf and the light), computed on first use. Empty
    /// when the table would take too much memory: the walks then start at the root.
    cuts: Vec<OnceLock<Box<Cut>>>,
    /// The scene tolerance the cuts' hulls are grown by.
    pad: f32,
    /// The lists of the pieces of shaded triangles toward lights ([`shafts`]), built on use.
    shafts: shafts::Shafts,
    /// Per light, its corners in lanes for the pyramid ([`PyramidBasis`]; `None` beyond four).
    bases: Vec<Option<PyramidBasis>>,
    /// The margin of every pyramid ([`pyramid::margin_of`]).
    pyramid_margin: f32,
}

impl<'a> LieVisibility<'a> {
    /// Mode `mode` (one of `Lie`, `Umbra`, `Penumbra`, `Grid`; others answer as `Lie`) over a P-LIE
    /// built for `scene` and `octree`. Without regions or grids in the P-LIE, the modes that use them
    /// test the blockers instead (still exact).
    pub fn new(scene: &'a Scene, bvh: &'a Bvh, octree: &'a Octree, plie: &'a Plie, mode: Mode) -> LieVisibility<'a> {
        let pad = scene.tolerance();
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
        let (sat_start, sat) = if mode == Mode::Grid { whole::grid_tables(plie) } else { (Vec::new(), Vec::new()) };
        let cuts = cut_table(scene, octree);
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
            own,
            own_tris,
            own_boxes,
            sat_start,
            sat,
            cuts,
            pad,
            shafts: shafts::Shafts::default(),
            bases: scene.lights.iter().map(PyramidBasis::of).collect(),
            pyramid_margin: pyramid::margin_of(scene),
        }
    }

    /// Sets `pyramid` to the one from `x` over light `light` ([`Pyramid::set_in`]), from the
    /// light's precomputed basis where it has one.
    #[inline]
    fn set_pyramid(&self, pyramid: &mut Pyramid, x: Vec3, light: LightId) -> bool {
        match &self.bases[light.idx()] {
            Some(basis) => pyramid.set_from(x, basis, self.pyramid_margin),
            None => pyramid.set_in(self.scene, x, light),
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

/// The empty table of the cuts of the scene BVH, one slot per (leaf, light) at
/// `leaf * lights + light` ([`LieVisibility::cut`]), or no table (every walk starts at the root) when
/// its slots would take more than [`CUTS_MAX_BYTES`].
fn cut_table(scene: &Scene, octree: &Octree) -> Vec<OnceLock<Box<Cut>>> {
    let pairs = octree.leaf_count() as u64 * scene.lights.len() as u64;
    if pairs.saturating_mul(std::mem::size_of::<OnceLock<Box<Cut>>>() as u64) > CUTS_MAX_BYTES {
        return Vec::new();
    }
    (0..pairs).map(|_| OnceLock::new()).collect()
}

/// Most bytes the slots of the cut table may take (16 a (leaf, light) pair; a cut computed takes
/// about 300 more): 256 MiB.
const CUTS_MAX_BYTES: u64 = 256 << 20;

impl LieVisibility<'_> {
    /// The cut of the scene BVH for `leaf` and `light`: the children whose boxes meet the hull of
    /// the leaf's box and the light's bounding box (grown by the scene tolerance), which holds every
    /// segment from a point of the leaf to a point of the light. Computed on first use (any thread
    /// computes the same cut); `None` without a cut table.
    #[inline]
    fn cut(&self, leaf: LeafId, light: LightId) -> Option<&Cut> {
        let slot = self.cuts.get(leaf.idx() * self.scene.lights.len() + light.idx())?;
        Some(slot.get_or_init(|| {
            let b = self.octree.leaf_bounds(leaf);
            Box::new(self.bvh.cut_of(&b, &self.scene.lights[light.idx()].vertices, self.pad))
        }))
    }
}

/// [`exit_face`] for the box `b` and the segment `o + t d`, `t < t_max`.
#[inline]
fn exit_face_of(b: &Aabb, o: Vec3, d: Vec3, t_max: f32) -> Option<(Dir, f32)> {
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

    fn occluded_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        self.answer_light(rays, out, ctx);
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
                assert!(l.boxes.is_empty());
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
