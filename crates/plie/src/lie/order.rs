//! The spatial order of long blocker lists (SPEC §8 point 4).
//!
//! The construction stores every blocker list of at least [`super::CHUNKED_MIN`] triangles in the
//! Morton order of its triangles' box centres, quantised within the list's own bounding box, so
//! consecutive triangles lie close together; the visibility then puts a box around every chunk of
//! [`super::CHUNK`] of them (and every group of chunks) and a shadow ray skips the chunks it misses.
//! The order never changes an answer: a list is a set of candidates.

use crate::geometry::morton::morton3;
use crate::geometry::Aabb;
use crate::scene::{Scene, TriId};

/// Sorts `list` (triangles of `scene`) by the Morton code of their box centres within the list's
/// bounding box; ties by id, so the order is a function of the set.
pub fn sort_spatially(scene: &Scene, list: &mut [TriId]) {
    let Some(bounds) = list.iter().map(|t| scene.triangles[t.idx()].aabb()).reduce(Aabb::union) else {
        return;
    };
    list.sort_by_cached_key(|t| (morton3(&bounds, scene.triangles[t.idx()].aabb().center()), *t));
}
