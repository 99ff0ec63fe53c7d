//! Blockers of one data object (SPEC §4.4): gather the triangles of the leaves overlapping the
//! bounding volume (once each, skipping the light's own triangles), and keep those whose clip against
//! the shaft planes is non-empty. The original triangles are stored, sorted by id.

use super::shaft::Shaft;
use crate::octree::Octree;
use crate::scene::{LightId, Scene, TriId};

/// Per-thread scratch: a stamp per triangle for de-duplication.
pub struct GatherScratch {
    stamps: Vec<u32>,
    stamp: u32,
}

impl GatherScratch {
    /// Scratch for a scene of `triangles` triangles.
    pub fn new(triangles: usize) -> GatherScratch {
        GatherScratch { stamps: vec![0; triangles], stamp: 0 }
    }
}

/// Appends the blockers of `shaft` toward `light` to `out` (sorted by id) and returns how many
/// candidate triangles were clipped.
pub fn gather_blockers(
    scene: &Scene,
    octree: &Octree,
    shaft: &Shaft,
    light: LightId,
    s: &mut GatherScratch,
    out: &mut Vec<TriId>,
) -> usize {
    s.stamp = s.stamp.wrapping_add(1);
    if s.stamp == 0 {
        s.stamps.fill(0);
        s.stamp = 1;
    }
    let start = out.len();
    let mut candidates = 0;
    octree.for_each_leaf_overlapping(&shaft.bounds, |leaf| {
        if !shaft.may_overlap_box(&octree.leaf_bounds(leaf)) {
            return;
        }
        for &t in octree.leaf_triangles(leaf) {
            let st = &mut s.stamps[t.idx()];
            if *st == s.stamp {
                continue;
            }
            *st = s.stamp;
            if scene.tri_light[t.idx()] == Some(light) {
                continue;
            }
            let tri = &scene.triangles[t.idx()];
            if !shaft.bounds.overlaps(&tri.aabb()) {
                continue;
            }
            candidates += 1;
            if shaft.clips_triangle(&tri.v) {
                out.push(t);
            }
        }
    });
    out[start..].sort_unstable();
    candidates
}
