//! BVH visibility (work in progress).

/// BVH.
pub struct BvhVisibility;
