//! The P-LIE itself (SPEC §0, §4): for every octree leaf, face and light, an optional data object
//! (record) holding the blockers between that face and that light. "No record" means no light from
//! that light enters the cell through that face (SPEC §4.1).
//!
//! Layout: one `u32` per (leaf, face, light) in `record_index` (O(1) lookup, `NO_RECORD` where there is
//! none), the records in one flat array, and all blocker lists concatenated in `blockers`.

use serde::{Deserialize, Serialize};

use crate::octree::{Dir, LeafId};
use crate::scene::{LightId, TriId};

/// `record_index` entry for "no data object".
pub const NO_RECORD: u32 = u32::MAX;

/// Parameters of the P-LIE construction (SPEC §4.9).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlieParams {
    /// Octree: split leaves holding more triangles than this (thesis: 200).
    pub max_triangles: usize,
    /// Octree: maximum depth.
    pub max_depth: u32,
}

impl PlieParams {
    /// The thesis' test 1: 200 triangles per leaf, no refinement.
    pub fn thesis() -> PlieParams {
        let o = crate::octree::OctreeParams::thesis();
        PlieParams { max_triangles: o.max_triangles, max_depth: o.max_depth }
    }

    /// The octree part of the parameters.
    pub fn octree(&self) -> crate::octree::OctreeParams {
        crate::octree::OctreeParams { max_triangles: self.max_triangles, max_depth: self.max_depth }
    }
}

impl Default for PlieParams {
    fn default() -> PlieParams {
        PlieParams::thesis()
    }
}

/// One data object: a (leaf, face, light) and its blockers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Record {
    /// The leaf.
    pub leaf: LeafId,
    /// The face.
    pub face: Dir,
    /// The light.
    pub light: LightId,
    /// Start of the blocker list in [`Plie::blockers`].
    pub blockers_start: u32,
    /// Length of the blocker list.
    pub blockers_len: u32,
}

/// The preprocessed local illumination environments of every leaf.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plie {
    /// The parameters it was built with.
    pub params: PlieParams,
    /// Number of leaves of the octree it belongs to.
    pub leaves: u32,
    /// Number of lights of the scene.
    pub lights: u32,
    /// Record per (leaf, face, light): `((leaf * 6) + face) * lights + light`.
    pub record_index: Vec<u32>,
    /// The records.
    pub records: Vec<Record>,
    /// All blocker lists, concatenated.
    pub blockers: Vec<TriId>,
}

impl Plie {
    /// The record of (leaf, face, light), if the face sees the light.
    #[inline]
    pub fn record(&self, leaf: LeafId, face: Dir, light: LightId) -> Option<&Record> {
        let i = (leaf.idx() * 6 + face.index()) * self.lights as usize + light.idx();
        match self.record_index[i] {
            NO_RECORD => None,
            r => Some(&self.records[r as usize]),
        }
    }

    /// A record's blockers.
    #[inline]
    pub fn blockers_of(&self, r: &Record) -> &[TriId] {
        &self.blockers[r.blockers_start as usize..(r.blockers_start + r.blockers_len) as usize]
    }

    /// Bytes held in memory by the P-LIE's arrays.
    pub fn memory_bytes(&self) -> usize {
        self.record_index.len() * 4
            + self.records.len() * std::mem::size_of::<Record>()
            + self.blockers.len() * std::mem::size_of::<TriId>()
    }

    /// Mean and maximum blockers per record.
    pub fn blocker_stats(&self) -> (f64, u32) {
        let max = self.records.iter().map(|r| r.blockers_len).max().unwrap_or(0);
        let mean = if self.records.is_empty() { 0.0 } else { self.blockers.len() as f64 / self.records.len() as f64 };
        (mean, max)
    }
}
