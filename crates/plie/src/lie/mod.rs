//! The P-LIE itself (SPEC §0, §4): for every octree leaf, face and light, an optional data object
//! (record) holding the blockers between that face and that light. "No record" means no light from
//! that light enters the cell through that face (SPEC §4.1).
//!
//! Layout: one `u32` per (leaf, face, light) in `record_index` (O(1) lookup, `NO_RECORD` where there is
//! none), the records in one flat array, and all blocker lists concatenated in `blockers`. Parallel to
//! the records: their umbra/penumbra triangles (§4.5, in the face's integer units, see
//! [`crate::construct::regions::FaceFrame`]) and their face grids. Long blocker lists are stored in
//! Morton order ([`CHUNKED_MIN`]).
//!
//! Bounded storage (issue 15): a record whose shaft holds more than [`PlieParams::blocker_cap`]
//! blockers, or that would exceed the construction's memory budget, stores no list
//! ([`RecordKind::Scene`]): shadow rays through its face are answered by the scene BVH, which is exact.
//! Its umbra, computed from a subset of its blockers, is a subset of the true umbra and still answers
//! "occluded"; its penumbra and its lit cells are unknown, so it stores none.

mod validate;

use serde::{Deserialize, Serialize};

use crate::construct::refine::RefineParams;
use crate::construct::regions::Tri2;
use crate::octree::{Dir, LeafId};
use crate::scene::{LightId, TriId};

/// Blocker lists (of records and of face-grid cells) with at least this many triangles are stored in
/// Morton order ([`crate::geometry::morton::sort_spatially`]); shorter ones by ascending id.
pub const CHUNKED_MIN: usize = 4 * CHUNK;

/// Triangles per chunk when a shadow ray walks a long list: it tests a box around each chunk (and
/// around each group of `CHUNK` chunks) first ([`crate::visibility::lie`]).
pub const CHUNK: usize = 8;

/// The cap `plie build`, `render`, `inspect` and `bench` use unless told otherwise
/// ([`PlieParams::blocker_cap`]); chosen by the measurements of issue 15 in docs/results.md (64 built
/// fastest and smallest of 64, 256 and 1024 on every larger scene, without slowing `grid` shading).
pub const DEFAULT_BLOCKER_CAP: u32 = 64;

/// `record_index` entry for "no data object".
pub const NO_RECORD: u32 = u32::MAX;

/// Parameters of the P-LIE construction (SPEC §4.9).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlieParams {
    /// Octree: split leaves holding more triangles than this (thesis: 200).
    pub max_triangles: usize,
    /// Octree: maximum depth.
    pub max_depth: u32,
    /// Whether to build face grids (per-cell blocker lists, our addition; used by mode `grid`).
    pub grids: Grids,
    /// Whether to compute umbra and penumbra (SPEC §4.5) and remove fully dark records (§4.6). The
    /// thesis' Table 8.4 measured construction without them.
    pub regions: Regions,
    /// Whether to propagate umbra to neighbouring cells (SPEC §4.7, thesis chapter 6): delete the
    /// records of faces proven dark by a fully dark neighbour without computing their blockers. Only
    /// speeds up construction; needs regions (without them no face is known to be dark).
    pub propagation: Propagation,
    /// Refinement of the octree after the records are known (SPEC §4.8); off by default, as in the
    /// thesis' test 1.
    pub refine: RefineParams,
    /// Most blockers a record stores (issue 15): a record with more becomes [`RecordKind::Scene`],
    /// and gathering its blockers stops there, so construction time and storage per record are
    /// bounded. `None`: no cap (every record lists all its blockers, as in the thesis; the library's
    /// [`PlieParams::thesis`] and default). [`PlieParams::bounded`] sets [`DEFAULT_BLOCKER_CAP`].
    pub blocker_cap: Option<u32>,
}

impl PlieParams {
    /// The thesis' test 1: 200 triangles per leaf, umbra and penumbra, no refinement, nothing the
    /// thesis did not have. Propagation is on: the thesis' construction always removes data by
    /// umbra and propagates it (§5.7, chapter 6); test 1 only turned refinement off (§8.2.1).
    pub fn thesis() -> PlieParams {
        let o = crate::octree::OctreeParams::thesis();
        PlieParams {
            max_triangles: o.max_triangles,
            max_depth: o.max_depth,
            grids: Grids::Skip,
            regions: Regions::Compute,
            propagation: Propagation::On,
            refine: RefineParams::none(),
            blocker_cap: None,
        }
    }

    /// These parameters with the default blocker cap ([`DEFAULT_BLOCKER_CAP`], issue 15): what the
    /// command-line tool builds unless told otherwise.
    pub fn bounded(self) -> PlieParams {
        PlieParams { blocker_cap: Some(DEFAULT_BLOCKER_CAP), ..self }
    }

    /// Checks the parameters: the octree's ([`crate::octree::OctreeParams::validate`]) and the
    /// refinement's, which must agree with the rest (refining by umbra needs regions).
    pub fn validate(&self) -> crate::Result<()> {
        self.octree().validate()?;
        self.refine.validate(self.has_regions())
    }

    /// True if face grids are built ([`Grids::Build`]).
    pub fn has_grids(&self) -> bool {
        self.grids == Grids::Build
    }

    /// True if umbra and penumbra are computed ([`Regions::Compute`]).
    pub fn has_regions(&self) -> bool {
        self.regions == Regions::Compute
    }

    /// True if umbra is propagated: [`Propagation::On`] and regions computed.
    pub fn propagates(&self) -> bool {
        self.propagation == Propagation::On && self.has_regions()
    }

    /// The octree part of the parameters.
    pub fn octree(&self) -> crate::octree::OctreeParams {
        crate::octree::OctreeParams { max_triangles: self.max_triangles, max_depth: self.max_depth }
    }
}

impl Default for PlieParams {
    /// The thesis' parameters (with umbra and penumbra) plus face grids.
    fn default() -> PlieParams {
        PlieParams { grids: Grids::Build, ..PlieParams::thesis() }
    }
}

/// Whether the construction builds face grids ([`PlieParams::grids`]). Stored in `.plie` files as
/// the boolean it replaced (`Skip` = 0, `Build` = 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Grids {
    /// No face grids: mode `grid` answers as `penumbra` (or `lie`).
    Skip,
    /// A face grid per record.
    Build,
}

/// Whether the construction computes umbra and penumbra ([`PlieParams::regions`]). Stored as the
/// boolean it replaced (`Skip` = 0, `Compute` = 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Regions {
    /// Blocker lists only (modes `umbra` and `penumbra` refuse such a P-LIE).
    Skip,
    /// Umbra and penumbra per record, and removal of fully dark records.
    Compute,
}

/// Whether the construction propagates umbra ([`PlieParams::propagation`]). Stored as the boolean
/// it replaced (`Off` = 0, `On` = 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Propagation {
    /// Every face's blockers are computed.
    Off,
    /// Faces proven dark by a dark neighbour lose their record without being computed.
    On,
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
