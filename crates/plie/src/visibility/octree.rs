//! SPEC §5 mode (a) (work in progress).

/// Mode (a).
pub struct OctreeVisibility;
