//! The octree of SPEC §3 (placeholder on main until the octree branch lands).

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Index of an octree leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct LeafId(pub u32);

/// The octree.
pub struct Octree;

impl Octree {
    /// Leaf containing `p`.
    pub fn locate(&self, _p: Vec3) -> Option<LeafId> {
        None
    }
}
