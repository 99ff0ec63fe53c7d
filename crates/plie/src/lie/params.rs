//! The parameters of the P-LIE construction (SPEC §4.9): the octree's, which stages run, the
//! refinement's chain of criteria (§4.8), and the blocker cap (issue 15). Each checks itself
//! ([`PlieParams::validate`]); the construction and `.plie` files take them as they are.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The cap `plie build`, `render`, `inspect` and `bench` use unless told otherwise
/// ([`PlieParams::blocker_cap`]); chosen by the measurements of issue 15 in docs/results.md (64 built
/// fastest and smallest of 64, 256 and 1024 on every larger scene, without slowing `grid` shading).
pub const DEFAULT_BLOCKER_CAP: u32 = 64;

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
    /// Most blockers a record stores (issue 15): a record with more becomes [`crate::lie::RecordKind::Scene`],
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

/// The limit of the blockers criterion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MaxBlockers {
    /// Split when one (face, light) has more than this many blockers.
    Fixed(u32),
    /// The thesis' adaptive limit (§8.3.3): the scene's triangle count, divided by `2 * depth` for a
    /// leaf at depth `depth` (the thesis: "start at the triangle count, reduce by `1 / (2 level)`").
    Adaptive,
}

impl MaxBlockers {
    /// The limit for a leaf at `depth` in a scene of `triangles` triangles.
    pub fn limit(self, triangles: usize, depth: u32) -> usize {
        match self {
            MaxBlockers::Fixed(n) => n as usize,
            MaxBlockers::Adaptive => triangles / (2 * depth.max(1) as usize),
        }
    }
}

/// Which criteria refine the octree, and how far (SPEC §4.8, §4.9). The default refines nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RefineParams {
    /// Umbra rule 1 ([`Criterion::UmbraFull`]).
    pub umbra_full: bool,
    /// Umbra rule 2 ([`Criterion::UmbraFree`]).
    pub umbra_free: bool,
    /// Blockers per face ([`Criterion::Blockers`]) with this limit; `None`: off.
    pub blockers: Option<MaxBlockers>,
    /// How many times a leaf of the original octree may be split by refinement (thesis: 2).
    pub max_split_depth: u32,
}

impl Default for RefineParams {
    fn default() -> RefineParams {
        RefineParams::none()
    }
}

impl RefineParams {
    /// No refinement.
    pub fn none() -> RefineParams {
        RefineParams { umbra_full: false, umbra_free: false, blockers: None, max_split_depth: 2 }
    }

    /// The thesis' test 2: refined by umbra (rules 1 and 2), at most 2 splits.
    pub fn thesis_umbra() -> RefineParams {
        RefineParams { umbra_full: true, umbra_free: true, ..RefineParams::none() }
    }

    /// True if some criterion is on and a leaf may split at least once.
    pub fn enabled(&self) -> bool {
        !self.chain().is_empty() && self.max_split_depth > 0
    }

    /// The criteria that are on, in chain order.
    pub fn chain(&self) -> Vec<Criterion> {
        let mut c = Vec::new();
        if self.umbra_full {
            c.push(Criterion::UmbraFull);
        }
        if self.umbra_free {
            c.push(Criterion::UmbraFree);
        }
        if self.blockers.is_some() {
            c.push(Criterion::Blockers);
        }
        c
    }

    /// Checks the parameters against the rest of the construction: the umbra rules need regions.
    pub fn validate(&self, regions: bool) -> Result<()> {
        if (self.umbra_full || self.umbra_free) && !regions {
            return Err(Error::InvalidParameter("refinement by umbra needs umbra and penumbra regions".into()));
        }
        if self.max_split_depth > crate::octree::MAX_DEPTH_LIMIT {
            return Err(Error::InvalidParameter(format!(
                "max split depth {} is above the octree's depth limit {}",
                self.max_split_depth,
                crate::octree::MAX_DEPTH_LIMIT
            )));
        }
        Ok(())
    }
}

/// One link of the chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Criterion {
    /// Umbra rule 1: a quarter of a face lies fully in its umbra.
    UmbraFull,
    /// Umbra rule 2: a quarter of a face with blockers touches neither umbra nor penumbra.
    UmbraFree,
    /// More blockers on one (face, light) than the limit.
    Blockers,
}

impl Criterion {
    /// Every criterion, in chain order.
    pub const ALL: [Criterion; 3] = [Criterion::UmbraFull, Criterion::UmbraFree, Criterion::Blockers];

    /// Short name (statistics, CLI).
    pub fn name(self) -> &'static str {
        match self {
            Criterion::UmbraFull => "umbra_full",
            Criterion::UmbraFree => "umbra_free",
            Criterion::Blockers => "blockers",
        }
    }
}
