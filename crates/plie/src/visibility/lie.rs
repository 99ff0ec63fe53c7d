//! SPEC §5 mode (b), LIE / blockers: the segment from `x` (in leaf `c`) to the light sample leaves `c`
//! through one face `F`. No record for (F, light): occluded. Otherwise test the record's blockers
//! (they cover the part of the segment beyond `F`, which lies in conv(F ∪ light)), then the triangles
//! of `c` itself (the part inside `c`). A segment that never leaves `c` only needs `c`'s triangles.

use super::{blocks, OctreeVisibility, QueryCtx, ShadowRay, Visibility};
use crate::lie::Plie;
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::Scene;

/// Mode (b): the P-LIE's blocker lists.
pub struct LieVisibility<'a> {
    scene: &'a Scene,
    octree: &'a Octree,
    plie: &'a Plie,
}

impl<'a> LieVisibility<'a> {
    /// Mode (b) over a P-LIE built for `scene` and `octree`.
    pub fn new(scene: &'a Scene, octree: &'a Octree, plie: &'a Plie) -> LieVisibility<'a> {
        LieVisibility { scene, octree, plie }
    }
}

/// The face through which the segment `ray` leaves the box of `leaf`, or `None` if it stays inside
/// for its whole open range.
#[inline]
pub fn exit_face(octree: &Octree, leaf: LeafId, ray: &ShadowRay) -> Option<Dir> {
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
    best.1
}

impl Visibility for LieVisibility<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        let Some(leaf) = ray.leaf.or_else(|| self.octree.locate(ray.origin())) else {
            // Outside the octree: no environment to consult.
            return OctreeVisibility::new(self.scene, self.octree).occluded(ray, ctx);
        };
        if let Some(face) = exit_face(self.octree, leaf, ray) {
            let Some(record) = self.plie.record(leaf, face, ray.light) else {
                return true;
            };
            for &t in self.plie.blockers_of(record) {
                if blocks(self.scene, ray, t, ctx) {
                    return true;
                }
            }
        }
        self.octree.leaf_triangles(leaf).iter().any(|&t| blocks(self.scene, ray, t, ctx))
    }
}
