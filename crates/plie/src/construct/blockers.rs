//! Blockers of one data object (SPEC §4.4): gather the triangles of the leaves overlapping the
//! bounding volume (once each, skipping the light's own triangles), and keep those whose clip against
//! the shaft planes is non-empty. The original triangles are stored, sorted by id.
//!
//! With a cap (issue 15, [`crate::lie::PlieParams::blocker_cap`]) the gather stops as soon as it has
//! found more blockers than the cap, or clipped [`CANDIDATES_PER_BLOCKER`] times the cap candidates:
//! the record is then answered by the scene BVH, and its work and storage are bounded whatever the
//! scene.

use super::shaft::Shaft;
use crate::octree::Octree;
use crate::scene::{LightId, Scene, TriId};

/// A capped gather also stops after clipping this many candidates per blocker of the cap (most
/// candidates of a dense scene's shaft box are outside the shaft itself).
pub const CANDIDATES_PER_BLOCKER: usize = 16;

/// What one gather found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Gathered {
    /// Candidate triangles clipped.
    pub candidates: usize,
    /// The cap was exceeded: the gather stopped early and the list holds only some blockers (a
    /// subset, usable for umbra only).
    pub capped: bool,
}

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

/// Appends the blockers of `shaft` toward `light` to `out` (sorted by id) and says how many candidate
/// triangles were clipped. With `cap`, stops once more than `cap` blockers are found (or
/// [`CANDIDATES_PER_BLOCKER`] times `cap` candidates clipped) and says it was capped.
pub fn gather_blockers(
    scene: &Scene,
    octree: &Octree,
    shaft: &Shaft,
    light: LightId,
    cap: Option<usize>,
    s: &mut GatherScratch,
    out: &mut Vec<TriId>,
) -> Gathered {
    s.stamp = s.stamp.wrapping_add(1);
    if s.stamp == 0 {
        s.stamps.fill(0);
        s.stamp = 1;
    }
    let start = out.len();
    let mut candidates = 0;
    let (max_found, max_candidates) = match cap {
        Some(c) => (c, c.saturating_mul(CANDIDATES_PER_BLOCKER).max(1)),
        None => (usize::MAX, usize::MAX),
    };
    let mut capped = false;
    octree.for_each_leaf_overlapping(&shaft.bounds, |leaf| {
        if capped || !shaft.may_overlap_box(&octree.leaf_bounds(leaf)) {
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
            if out.len() - start > max_found || candidates >= max_candidates {
                capped = true;
                break;
            }
        }
    });
    out[start..].sort_unstable();
    Gathered { candidates, capped }
}
