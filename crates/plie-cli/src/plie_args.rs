//! `--max-triangles`, `--max-depth`, `--no-grids`, `--no-regions`, `--no-propagation`, `--refine`,
//! `--max-split-depth`, `--max-blockers` and `--blocker-cap`: the P-LIE build parameters (SPEC §4.9,
//! issue 15) shared by `plie build`, `plie render` and `plie inspect`.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use plie::construct::refine::{MaxBlockers, RefineParams};
use plie::lie::Plie;
use plie::lie::{Grids, PlieParams, Propagation, Regions};
use plie::octree::{Octree, OctreeParams};
use plie::Scene;

use crate::progress::Bar;

/// The default of `--max-split-depth` (the thesis' test 2).
pub const DEFAULT_MAX_SPLIT_DEPTH: u32 = 2;

/// Options that set the octree and P-LIE parameters.
#[derive(clap::Args, Clone, Debug)]
pub struct PlieArgs {
    /// Octree: split leaves holding more triangles than this.
    #[arg(long, default_value_t = 200, value_name = "N")]
    pub max_triangles: usize,
    /// Octree: maximum depth.
    #[arg(long, default_value_t = OctreeParams::default().max_depth, value_name = "D")]
    pub max_depth: u32,
    /// P-LIE: skip the face grids (the per-face grids of `--visibility grid`).
    #[arg(long)]
    pub no_grids: bool,
    /// P-LIE: skip computing umbra and penumbra (where a face sees none or part of the light) and
    /// the removal of faces fully in shadow; keep only blocker lists. Modes `umbra`, `penumbra` need
    /// them.
    #[arg(long)]
    pub no_regions: bool,
    /// P-LIE: do not carry full shadow over to neighbouring cells (which lets the build skip their
    /// blockers); every face's blockers are computed. Same answers; only the build time changes.
    #[arg(long)]
    pub no_propagation: bool,
    /// P-LIE: split octree cells further once their shadows are known, by a comma-separated list of
    /// criteria: `umbra-full` (split where a smaller cell's face would lie fully in shadow),
    /// `umbra-free` (where a smaller cell's face would need no blockers), `umbra` (both),
    /// `blockers` (where a face has more than --max-blockers blockers for a light). Same answers;
    /// more cells, usually faster shading.
    #[arg(long, value_name = "CRITERIA", value_delimiter = ',')]
    pub refine: Vec<RefineCriterion>,
    /// Refinement: how many times a leaf may be split (bounds a chain of criteria that would split
    /// without end).
    #[arg(long, default_value_t = DEFAULT_MAX_SPLIT_DEPTH, value_name = "K")]
    pub max_split_depth: u32,
    /// Refinement by `blockers`: split when one face and light has more blockers than N, or
    /// `adaptive` (the scene's triangle count over twice the cell's depth in the octree).
    #[arg(long, value_name = "N|adaptive", value_parser = parse_max_blockers)]
    pub max_blockers: Option<MaxBlockers>,
    /// P-LIE: most blockers a record stores, or `none`; a record with more stores no list and its
    /// rays are answered by the scene BVH (exact either way). Bounds construction time and memory.
    #[arg(long, value_name = "N|none", default_value_t = BlockerCap(Some(plie::lie::DEFAULT_BLOCKER_CAP)), value_parser = parse_blocker_cap)]
    pub blocker_cap: BlockerCap,
}

/// A value of `--blocker-cap`: a number, or `None` for `none`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockerCap(pub Option<u32>);

impl std::fmt::Display for BlockerCap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(n) => write!(f, "{n}"),
            None => f.write_str("none"),
        }
    }
}

fn parse_blocker_cap(s: &str) -> std::result::Result<BlockerCap, String> {
    if s == "none" {
        return Ok(BlockerCap(None));
    }
    s.parse::<u32>()
        .map(|n| BlockerCap(Some(n)))
        .map_err(|_| format!("expected a number of blockers or `none`, not `{s}`"))
}

/// A value of `--refine`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefineCriterion {
    /// Both umbra criteria.
    Umbra,
    /// A smaller cell's face would lie fully in shadow.
    UmbraFull,
    /// A smaller cell's face would need no blockers.
    UmbraFree,
    /// More than --max-blockers blockers on one face for one light.
    Blockers,
}

fn parse_max_blockers(s: &str) -> std::result::Result<MaxBlockers, String> {
    if s == "adaptive" {
        return Ok(MaxBlockers::Adaptive);
    }
    s.parse::<u32>()
        .map(MaxBlockers::Fixed)
        .map_err(|_| format!("expected a number of blockers or `adaptive`, not `{s}`"))
}

impl PlieArgs {
    /// The validated parameters; face grids only if `want_grids` and not `--no-grids`.
    pub fn params(&self, want_grids: bool) -> Result<PlieParams> {
        let p = PlieParams {
            max_triangles: self.max_triangles,
            max_depth: self.max_depth,
            grids: if want_grids && !self.no_grids { Grids::Build } else { Grids::Skip },
            regions: if self.no_regions { Regions::Skip } else { Regions::Compute },
            propagation: if self.no_propagation { Propagation::Off } else { Propagation::On },
            refine: self.refine_params()?,
            blocker_cap: self.blocker_cap.0,
        };
        p.octree().validate()?;
        p.refine.validate(p.has_regions())?;
        Ok(p)
    }

    /// The refinement asked for.
    fn refine_params(&self) -> Result<RefineParams> {
        let has = |c| self.refine.contains(&c);
        let umbra = has(RefineCriterion::Umbra);
        let blockers = has(RefineCriterion::Blockers);
        if blockers && self.max_blockers.is_none() {
            bail!("--refine blockers needs --max-blockers N or --max-blockers adaptive");
        }
        if !blockers && self.max_blockers.is_some() {
            bail!("--max-blockers only applies to --refine blockers");
        }
        Ok(RefineParams {
            umbra_full: umbra || has(RefineCriterion::UmbraFull),
            umbra_free: umbra || has(RefineCriterion::UmbraFree),
            blockers: self.max_blockers.filter(|_| blockers),
            max_split_depth: self.max_split_depth,
        })
    }
}

/// An octree and its P-LIE, loaded from a file or built.
pub struct Loaded {
    /// The octree (refined if the P-LIE was).
    pub octree: Octree,
    /// The P-LIE.
    pub plie: Plie,
    /// Seconds building the P-LIE (octree excluded), when built.
    pub build_seconds: Option<f64>,
    /// Seconds loading the file (octree rebuilt included), when loaded.
    pub load_seconds: Option<f64>,
}

/// Loads the P-LIE file `path` (checking it was built for `scene` with `params`), or builds the
/// octree and the P-LIE (refined if `params` asks) when there is no file.
pub fn load_or_build(scene: &Scene, params: PlieParams, path: Option<&Path>, bar: &Bar) -> Result<Loaded> {
    let t = Instant::now();
    if let Some(path) = path {
        let (octree, plie) = plie::io::plie_file::load_plie(path, scene, Some(params))
            .with_context(|| format!("cannot use P-LIE file {}", path.display()))?;
        return Ok(Loaded { octree, plie, build_seconds: None, load_seconds: Some(t.elapsed().as_secs_f64()) });
    }
    let octree = Octree::build(scene, params.octree())?;
    let t = Instant::now();
    let limits =
        plie::construct::Limits { list_bytes: Some(crate::budget::list_bytes(crate::budget::default_bytes(), scene)) };
    let built = plie::construct::build_bounded(scene, octree, params, limits, bar)?;
    crate::budget::warn_over(&built.stats, bar);
    Ok(Loaded {
        octree: built.octree,
        plie: built.plie,
        build_seconds: Some(t.elapsed().as_secs_f64()),
        load_seconds: None,
    })
}
