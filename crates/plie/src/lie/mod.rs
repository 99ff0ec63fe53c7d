//! The P-LIE itself (SPEC §0, §4): for every octree leaf, face and light, an optional data object
//! (record) holding the blockers between that face and that light. "No record" means no light from
//! that light enters the cell through that face (SPEC §4.1).
//!
//! Layout: one `u32` per (leaf, face, light) in `record_index` (O(1) lookup, `NO_RECORD` where there is
//! none), the records in one flat array, and all blocker lists concatenated in `blockers`. Parallel to
//! the records: their umbra/penumbra triangles (§4.5, in the face's integer units, see
//! [`frame::FaceFrame`]) and their face grids. Long blocker lists are stored in
//! Morton order ([`CHUNKED_MIN`]).
//!
//! Bounded storage (issue 15): a record whose shaft holds more than [`PlieParams::blocker_cap`]
//! blockers, or that would exceed the construction's memory budget, stores no list
//! ([`RecordKind::Scene`]): shadow rays through its face are answered by the scene BVH, which is exact.
//! Its umbra, computed from a subset of its blockers, is a subset of the true umbra and still answers
//! "occluded"; its penumbra and its lit cells are unknown, so it stores none.

pub mod frame;
pub mod grid;
pub mod order;
pub mod params;
mod validate;

use serde::{Deserialize, Serialize};

pub use frame::Tri2;
pub use params::{Criterion, Grids, MaxBlockers, PlieParams, Propagation, RefineParams, Regions, DEFAULT_BLOCKER_CAP};

use crate::octree::{Dir, LeafId};
use crate::scene::{LightId, TriId};

/// Blocker lists (of records and of face-grid cells) with at least this many triangles are stored in
/// Morton order ([`order::sort_spatially`]); shorter ones by ascending id.
pub const CHUNKED_MIN: usize = 4 * CHUNK;

/// Triangles per chunk when a shadow ray walks a long list: it tests a box around each chunk (and
/// around each group of `CHUNK` chunks) first (the P-LIE modes, `visibility::lie`).
pub const CHUNK: usize = 8;

/// `record_index` entry for "no data object".
pub const NO_RECORD: u32 = u32::MAX;

/// Limits of one construction that are not part of the P-LIE's parameters (issue 15). The P-LIE
/// keeps them ([`Plie::limits`]) and its file stores them, so that a rebuild (`plie verify --full`)
/// makes the same P-LIE.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Limits {
    /// Bytes the blocker lists of the records and grid cells may take. A listed record that would
    /// pass it is stored as [`RecordKind::Scene`] instead (degrading, never aborting); the decision
    /// is made at the record's commit, in task order, so it does not depend on the thread count.
    /// `None`: no limit.
    pub list_bytes: Option<usize>,
    /// Candidate clips the construction may spend gathering the records over the blocker cap again
    /// with a cap up to 16 times larger (the lift, `construct::lift`); in a fixed order, so the
    /// result does not depend on the thread count. `None`: no lifting (every record over the cap
    /// stays a scene record).
    pub lift_clips: Option<usize>,
    /// Candidate clips the construction may spend gathering the cells of the records still over the
    /// cap after the lift, each cell with a small cap (`construct::scene_cells`); in a fixed order,
    /// so the result does not depend on the thread count. `None`: none (their cells outside the
    /// umbra stay answered by the scene BVH).
    pub cell_clips: Option<usize>,
}

/// How a record answers the rays through its face beyond its umbra.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum RecordKind {
    /// By its blocker list (and its face grid): the thesis' record.
    #[default]
    Listed,
    /// By the scene BVH ([`crate::visibility::bvh`], exact): its shaft holds more than
    /// [`PlieParams::blocker_cap`] blockers, or its list did not fit the memory budget. It stores no
    /// blocker list and no penumbra; its umbra (from a subset of its blockers) and its grid's umbra
    /// cells still answer "occluded".
    Scene,
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
    /// Whether the list holds every blocker ([`RecordKind::Listed`]) or none ([`RecordKind::Scene`]).
    pub kind: RecordKind,
}

/// A record's umbra and penumbra triangles: ranges into [`Plie::region_tris`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RecordRegions {
    /// First umbra triangle.
    pub umbra_start: u32,
    /// Umbra triangles.
    pub umbra_len: u32,
    /// First penumbra triangle.
    pub penumbra_start: u32,
    /// Penumbra triangles.
    pub penumbra_len: u32,
}

/// `(start, len)` of a grid cell fully in umbra (no blocker list needed).
pub const UMBRA_CELL: (u32, u32) = (u32::MAX, u32::MAX);

/// `(start, len)` of a grid cell of a [`RecordKind::Scene`] record outside its umbra.
pub const SCENE_CELL: (u32, u32) = (u32::MAX, u32::MAX - 1);

/// What a face-grid cell says about rays crossing the face inside it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cell<'a> {
    /// Fully in umbra: every ray through it is blocked.
    Umbra,
    /// Its record stores no list ([`RecordKind::Scene`]): ask the scene BVH.
    Scene,
    /// Test these blockers (none: fully lit by the blockers).
    Blockers(&'a [TriId]),
}

/// A record's face grid (see [`crate::construct::grid`]): `res x res` cells whose blocker lists are
/// `cells[cells_start .. cells_start + res * res]`. `res == 0`: no grid, use the record's list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FaceGrid {
    /// Cells per side (0: no grid).
    pub res: u32,
    /// First cell in [`Plie::cells`].
    pub cells_start: u32,
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
    /// The face grid of each record (parallel to `records`).
    pub grids: Vec<FaceGrid>,
    /// Grid cells: `(start, len)` into `cell_blockers`.
    pub cells: Vec<(u32, u32)>,
    /// All cell blocker lists, concatenated.
    pub cell_blockers: Vec<TriId>,
    /// The umbra/penumbra triangles of each record (parallel to `records`; all empty without
    /// regions).
    pub regions: Vec<RecordRegions>,
    /// All region triangles, concatenated.
    pub region_tris: Vec<Tri2>,
    /// The refinement (SPEC §4.8): per round, the nodes of the leaves split, in order (see
    /// [`crate::octree::Octree::split_nodes`]). Empty without refinement.
    pub splits: Vec<Vec<u32>>,
    /// The limits it was built within.
    pub limits: Limits,
}

impl Plie {
    /// The slot of (leaf, face, light) in [`Plie::record_index`].
    #[inline]
    pub fn slot(&self, leaf: LeafId, face: Dir, light: LightId) -> usize {
        (leaf.idx() * 6 + face.index()) * self.lights as usize + light.idx()
    }

    /// The record of (leaf, face, light), if the face sees the light.
    #[inline]
    pub fn record(&self, leaf: LeafId, face: Dir, light: LightId) -> Option<&Record> {
        self.record_id(leaf, face, light).map(|r| &self.records[r])
    }

    /// The index of the record of (leaf, face, light) in [`Plie::records`], if any.
    #[inline]
    pub fn record_id(&self, leaf: LeafId, face: Dir, light: LightId) -> Option<usize> {
        match self.record_index[self.slot(leaf, face, light)] {
            NO_RECORD => None,
            r => Some(r as usize),
        }
    }

    /// A record's blockers.
    #[inline]
    pub fn blockers_of(&self, r: &Record) -> &[TriId] {
        &self.blockers[r.blockers_start as usize..(r.blockers_start + r.blockers_len) as usize]
    }

    /// Cell `c` of record `r`'s grid.
    #[inline]
    pub fn cell(&self, grid: &FaceGrid, c: usize) -> Cell<'_> {
        match self.cells[grid.cells_start as usize + c] {
            UMBRA_CELL => Cell::Umbra,
            SCENE_CELL => Cell::Scene,
            (s, n) => Cell::Blockers(&self.cell_blockers[s as usize..(s + n) as usize]),
        }
    }

    /// The umbra triangles of record `r`.
    #[inline]
    pub fn umbra_of(&self, r: usize) -> &[Tri2] {
        let g = &self.regions[r];
        &self.region_tris[g.umbra_start as usize..(g.umbra_start + g.umbra_len) as usize]
    }

    /// The penumbra triangles of record `r`.
    #[inline]
    pub fn penumbra_of(&self, r: usize) -> &[Tri2] {
        let g = &self.regions[r];
        &self.region_tris[g.penumbra_start as usize..(g.penumbra_start + g.penumbra_len) as usize]
    }

    /// Bytes held in memory by the P-LIE's arrays.
    pub fn memory_bytes(&self) -> usize {
        self.record_index.len() * 4
            + self.records.len() * std::mem::size_of::<Record>()
            + self.blockers.len() * std::mem::size_of::<TriId>()
            + self.grids.len() * std::mem::size_of::<FaceGrid>()
            + self.cells.len() * 8
            + self.cell_blockers.len() * std::mem::size_of::<TriId>()
            + self.regions.len() * std::mem::size_of::<RecordRegions>()
            + self.region_tris.len() * std::mem::size_of::<Tri2>()
    }

    /// Records answered by the scene BVH ([`RecordKind::Scene`]).
    pub fn scene_records(&self) -> usize {
        self.records.iter().filter(|r| r.kind == RecordKind::Scene).count()
    }

    /// Mean and maximum blockers per record.
    pub fn blocker_stats(&self) -> (f64, u32) {
        let max = self.records.iter().map(|r| r.blockers_len).max().unwrap_or(0);
        let mean = if self.records.is_empty() { 0.0 } else { self.blockers.len() as f64 / self.records.len() as f64 };
        (mean, max)
    }
}
