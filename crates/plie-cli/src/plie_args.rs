//! `--max-triangles`, `--max-depth`, `--no-grids`, `--no-regions`, `--no-propagation`, `--refine`,
//! `--max-split-depth`, `--max-blockers` and `--blocker-cap`: the P-LIE build parameters (SPEC §4.9,
//! issue 15) shared by `plie build`, `plie render` and `plie inspect`.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::parser::ValueSource;
use clap::ArgMatches;
use plie::octree::OctreeParams;
use plie::Scene;
use plie::{BuildOptions, Environment};
use plie::{Grids, PlieParams, Propagation, Regions};
use plie::{MaxBlockers, RefineParams};

use crate::progress::Bar;

/// The default of `--max-split-depth` (the thesis' test 2).
pub const DEFAULT_MAX_SPLIT_DEPTH: u32 = 2;

/// Options that set the octree and P-LIE parameters.
#[derive(clap::Args, Clone, Debug)]
pub struct PlieArgs {
    /// Octree: split leaves holding more triangles than this. Exact copies of a triangle count once,
    /// and so do the triangles around a vertex that more than N triangles share (splitting cannot
    /// separate either).
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
    #[arg(long, value_name = "N|none", default_value_t = BlockerCap(Some(plie::DEFAULT_BLOCKER_CAP)), value_parser = parse_blocker_cap)]
    pub blocker_cap: BlockerCap,
    /// P-LIE: candidate triangles per scene triangle the build may clip to give records over
    /// --blocker-cap their full lists anyway (with a cap up to 16 times larger), spent in a fixed
    /// order; or `none`. Where few records pass the cap (an open room) nearly all get their lists;
    /// where most do (dense clutter) the budget bounds the extra time. Exact either way.
    #[arg(long, value_name = "N|none", default_value_t = BlockerCap(Some(plie::DEFAULT_LIFT_CLIPS as u32)), value_parser = parse_lift_clips)]
    pub lift_clips: BlockerCap,
    /// P-LIE: candidate triangles per scene triangle the build may clip to give the records still
    /// over the cap (after --lift-clips) face grids of their own (up to 32x32 cells): squares of
    /// cells, from the face's quarters down, gather their blockers with a cap of 16, and a cell under
    /// it keeps its list (empty: fully lit) instead of leaving its rays to the scene BVH; spent in a
    /// fixed order; or `none`. Exact either way.
    #[arg(long, value_name = "N|none", default_value_t = BlockerCap(Some(plie::DEFAULT_CELL_CLIPS as u32)), value_parser = parse_lift_clips)]
    pub cell_clips: BlockerCap,
}

/// A value of `--blocker-cap`, `--lift-clips` or `--cell-clips`: a number, or `None` for `none`.
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

/// A number of `what`, or `none`.
fn parse_number_or_none(s: &str, what: &str) -> std::result::Result<BlockerCap, String> {
    if s == "none" {
        return Ok(BlockerCap(None));
    }
    s.parse::<u32>()
        .map(|n| BlockerCap(Some(n)))
        .map_err(|_| format!("expected a number of {what} or `none`, not `{s}`"))
}

fn parse_blocker_cap(s: &str) -> std::result::Result<BlockerCap, String> {
    parse_number_or_none(s, "blockers")
}

fn parse_lift_clips(s: &str) -> std::result::Result<BlockerCap, String> {
    parse_number_or_none(s, "clips")
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

    /// `--lift-clips`: candidate clips per scene triangle ([`BuildOptions::lift_clips`]).
    pub fn lift_clips(&self) -> Option<usize> {
        self.lift_clips.0.map(|n| n as usize)
    }

    /// `--cell-clips`: candidate clips per scene triangle ([`BuildOptions::cell_clips`]).
    pub fn cell_clips(&self) -> Option<usize> {
        self.cell_clips.0.map(|n| n as usize)
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

/// The spelling of the refinement criteria on the command line (`none` when off).
fn refine_words(r: &RefineParams) -> String {
    let mut words = Vec::new();
    match (r.umbra_full, r.umbra_free) {
        (true, true) => words.push("umbra"),
        (true, false) => words.push("umbra-full"),
        (false, true) => words.push("umbra-free"),
        (false, false) => {}
    }
    if r.blockers.is_some() {
        words.push("blockers");
    }
    if words.is_empty() {
        "none".into()
    } else {
        words.join(",")
    }
}

fn max_blockers_word(m: Option<MaxBlockers>) -> String {
    match m {
        None => "none".into(),
        Some(MaxBlockers::Fixed(n)) => n.to_string(),
        Some(MaxBlockers::Adaptive) => "adaptive".into(),
    }
}

impl PlieArgs {
    /// Checks the options given explicitly on the command line (`matches`: the subcommand's) against
    /// the parameters a `.plie` file was built with (issue 18: the file describes itself, so options
    /// left at their defaults take the file's values). A contradiction is an error naming the option,
    /// the value given and the file's value.
    pub fn check_file_params(&self, env: &Environment, scene: &Scene, matches: &ArgMatches, path: &Path) -> Result<()> {
        let file = env.params();
        let given = |id: &str| matches.value_source(id) == Some(ValueSource::CommandLine);
        // The file stores the build's clip budgets in clips, the options count them per triangle.
        let triangles = scene.triangles.len().max(1);
        let per_triangle = |c: Option<usize>| BlockerCap(c.map(|c| (c / triangles).min(u32::MAX as usize) as u32));
        let limits = env.plie().limits;
        // (argument id, option, the value given, the file's value)
        let mut checks: Vec<(&str, &str, String, String)> = vec![
            ("max_triangles", "--max-triangles", self.max_triangles.to_string(), file.max_triangles.to_string()),
            ("max_depth", "--max-depth", self.max_depth.to_string(), file.max_depth.to_string()),
            (
                "max_split_depth",
                "--max-split-depth",
                self.max_split_depth.to_string(),
                file.refine.max_split_depth.to_string(),
            ),
            (
                "max_blockers",
                "--max-blockers",
                max_blockers_word(self.max_blockers),
                max_blockers_word(file.refine.blockers),
            ),
            ("blocker_cap", "--blocker-cap", self.blocker_cap.to_string(), BlockerCap(file.blocker_cap).to_string()),
            ("lift_clips", "--lift-clips", self.lift_clips.to_string(), per_triangle(limits.lift_clips).to_string()),
            ("cell_clips", "--cell-clips", self.cell_clips.to_string(), per_triangle(limits.cell_clips).to_string()),
        ];
        if given("refine") {
            let asked = RefineParams {
                umbra_full: self
                    .refine
                    .iter()
                    .any(|c| matches!(c, RefineCriterion::Umbra | RefineCriterion::UmbraFull)),
                umbra_free: self
                    .refine
                    .iter()
                    .any(|c| matches!(c, RefineCriterion::Umbra | RefineCriterion::UmbraFree)),
                blockers: self.refine.contains(&RefineCriterion::Blockers).then_some(MaxBlockers::Adaptive),
                max_split_depth: 0,
            };
            checks.push(("refine", "--refine", refine_words(&asked), refine_words(&file.refine)));
        }
        for (id, option, given_flag, file_has) in [
            ("no_grids", "--no-grids", self.no_grids, file.has_grids()),
            ("no_regions", "--no-regions", self.no_regions, file.has_regions()),
            ("no_propagation", "--no-propagation", self.no_propagation, file.propagates()),
        ] {
            if given(id) && given_flag && file_has {
                bail!(
                    "{option} contradicts the P-LIE file {}, which was built without {option} \
                     (leave the option out to use the file)",
                    path.display()
                );
            }
        }
        for (id, option, mine, theirs) in checks {
            if given(id) && mine != theirs {
                bail!(
                    "{option} {mine} contradicts the P-LIE file {}, which was built with {option} {theirs} \
                     (leave the option out to use the file's value)",
                    path.display()
                );
            }
        }
        Ok(())
    }
}

/// Loads the P-LIE file `path` for `scene` (its fingerprint must match) with the parameters it was
/// built with, after checking them against the options given explicitly ([`PlieArgs::check_file_params`]).
pub fn load_file(scene: &Scene, path: &Path, args: &PlieArgs, matches: &ArgMatches) -> Result<Loaded> {
    let t = Instant::now();
    let env =
        Environment::load(path, scene, None).with_context(|| format!("cannot use P-LIE file {}", path.display()))?;
    args.check_file_params(&env, scene, matches, path)?;
    Ok(Loaded { env, build_seconds: None, load_seconds: Some(t.elapsed().as_secs_f64()) })
}

/// A P-LIE environment (octree and P-LIE), loaded from a file or built.
pub struct Loaded {
    /// The octree (refined if the P-LIE was) and the P-LIE.
    pub env: Environment,
    /// Seconds building the P-LIE (octree excluded), when built.
    pub build_seconds: Option<f64>,
    /// Seconds loading the file (octree rebuilt included), when loaded.
    pub load_seconds: Option<f64>,
}

/// Builds the octree and the P-LIE of `scene` (refined if `params` asks) within the default memory
/// budget, lifting the cap as `args` says.
pub fn build(scene: &Scene, params: PlieParams, args: &PlieArgs, bar: &Bar) -> Result<Loaded> {
    let list_bytes = Some(crate::budget::list_bytes(crate::budget::default_bytes(), scene));
    let options =
        BuildOptions { list_bytes, lift_clips: args.lift_clips(), cell_clips: args.cell_clips(), progress: bar };
    let (env, stats) = Environment::build_with(scene, &params, options)?;
    crate::budget::warn_over(&stats, bar);
    Ok(Loaded { env, build_seconds: Some(stats.blockers.blockers_seconds), load_seconds: None })
}
