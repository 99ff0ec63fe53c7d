//! SPEC §5 mode (b), LIE / blockers: the segment from `x` (in leaf `c`) to the light sample leaves `c`
//! through one face `F`. No record for (F, light): occluded. Otherwise test the record's blockers
//! (they cover the part of the segment beyond `F`, which lies in conv(F ∪ light)), then the triangles
//! of `c` itself (the part inside `c`). A segment that never leaves `c` only needs `c`'s triangles.
//!
//! Each ray is counted on the [`Answer`] path that decided it, and its triangle tests are split into
//! blocker tests and own-leaf tests (`plie render --stats`).

use super::{blocks, Answer, OctreeVisibility, QueryCtx, ShadowRay, Visibility};
use crate::construct::grid;
use crate::geometry::{Aabb, Segment};
use crate::lie::Plie;
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{Scene, TriId};

/// Mode (b): the P-LIE's blocker lists.
///
/// Before a candidate gets the watertight test, its bounding box (grown by the construction tolerance)
/// is tested against the segment: a conservative cull (SPEC §8 point 4) that never changes an answer.
pub struct LieVisibility<'a> {
    scene: &'a Scene,
    octree: &'a Octree,
    plie: &'a Plie,
    /// Grown bounding box of every triangle.
    tri_boxes: Vec<Aabb>,
    /// Use the records' face grids (mode `grid`) instead of their whole lists (mode `lie`).
    use_grids: bool,
}

impl<'a> LieVisibility<'a> {
    /// Mode (b) over a P-LIE built for `scene` and `octree`.
    pub fn new(scene: &'a Scene, octree: &'a Octree, plie: &'a Plie) -> LieVisibility<'a> {
        let pad = scene.scale() * crate::construct::TOLERANCE_REL;
        let tri_boxes = scene.triangles.iter().map(|t| t.aabb().expanded(pad)).collect();
        LieVisibility { scene, octree, plie, tri_boxes, use_grids: false }
    }

    /// Mode `grid`: as mode (b), but a ray tests only the blockers of the face-grid cell where it
    /// crosses the face (see [`crate::construct::grid`]).
    pub fn with_grids(scene: &'a Scene, octree: &'a Octree, plie: &'a Plie) -> LieVisibility<'a> {
        LieVisibility { use_grids: true, ..LieVisibility::new(scene, octree, plie) }
    }

    /// The box cull, then the shared predicate.
    #[inline]
    fn test(&self, seg: &Segment, ray: &ShadowRay, t: TriId, ctx: &mut QueryCtx) -> bool {
        ctx.stats.box_tests += 1;
        seg.clip(&self.tri_boxes[t.idx()]).is_some() && blocks(self.scene, ray, t, ctx)
    }

    /// True if a triangle of `list` blocks the ray (tested in order, stopping at the first), and the
    /// number of triangle tests that took.
    #[inline]
    fn any_blocks(&self, seg: &Segment, ray: &ShadowRay, list: &[TriId], ctx: &mut QueryCtx) -> (bool, u64) {
        let before = ctx.stats.triangle_tests;
        let hit = list.iter().any(|&t| self.test(seg, ray, t, ctx));
        (hit, ctx.stats.triangle_tests - before)
    }
}

/// The face through which the segment `ray` leaves the box of `leaf` and the segment parameter where
/// it does, or `None` if it stays inside for its whole open range.
#[inline]
pub fn exit_face(octree: &Octree, leaf: LeafId, ray: &ShadowRay) -> Option<(Dir, f32)> {
    let b = octree.leaf_bounds(leaf);
    let (o, d) = (ray.test.origin, ray.test.dir);
    let mut best = (ray.test.t_max, None);
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
        // The path the ray takes if the leaf's own triangles miss it.
        let through = match exit_face(self.octree, leaf, ray) {
            None => Answer::InsideLeaf,
            Some((face, t_exit)) => {
                let Some(ri) = self.plie.record_id(leaf, face, ray.light) else {
                    return ctx.stats.answered(Answer::NoRecord, true);
                };
                let grid = &self.plie.grids[ri];
                let list = if self.use_grids && grid.res > 0 {
                    let f = ray.test.origin + ray.test.dir * t_exit;
                    let c = grid::cell_of(face, &self.octree.leaf_bounds(leaf), grid.res, f);
                    self.plie.cell_blockers_of(grid, c)
                } else {
                    self.plie.blockers_of(&self.plie.records[ri])
                };
                if list.is_empty() {
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
        let (hit, tests) = self.any_blocks(&seg, ray, self.octree.leaf_triangles(leaf), ctx);
        ctx.stats.own_leaf_tests += tests;
        if hit {
            ctx.stats.answered(Answer::OwnLeaf, true)
        } else {
            ctx.stats.answered(through, false)
        }
    }
}
