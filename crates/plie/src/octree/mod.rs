//! The octree of SPEC §3 (work in progress: being written).

use serde::{Deserialize, Serialize};

/// Index of an octree leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct LeafId(pub u32);

/// The octree.
pub struct Octree;
