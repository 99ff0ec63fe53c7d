//! `--max-triangles`, `--max-depth`, `--no-grids`, `--no-regions` and `--no-propagation`: the P-LIE build parameters
//! (SPEC §4.9) shared by `plie build` and `plie render`.

use anyhow::Result;
use plie::lie::PlieParams;
use plie::octree::OctreeParams;

/// Options that set the octree and P-LIE parameters.
#[derive(clap::Args, Clone, Debug)]
pub struct PlieArgs {
    /// Octree: split leaves holding more triangles than this.
    #[arg(long, default_value_t = 200, value_name = "N")]
    pub max_triangles: usize,
    /// Octree: maximum depth.
    #[arg(long, default_value_t = OctreeParams::default().max_depth, value_name = "D")]
    pub max_depth: u32,
    /// P-LIE: skip the face grids (per-cell blocker lists used by `--visibility grid`).
    #[arg(long)]
    pub no_grids: bool,
    /// P-LIE: skip umbra and penumbra (SPEC §4.5) and the removal of fully dark records (§4.6), as
    /// in the thesis' Table 8.4. Modes `umbra` and `penumbra` need them.
    #[arg(long)]
    pub no_regions: bool,
    /// P-LIE: do not propagate umbra to neighbouring cells (SPEC §4.7); every record's blockers are
    /// computed. Same records except fully dark ones; only construction time changes.
    #[arg(long)]
    pub no_propagation: bool,
}

impl PlieArgs {
    /// The validated parameters; face grids only if `want_grids` and not `--no-grids`.
    pub fn params(&self, want_grids: bool) -> Result<PlieParams> {
        let p = PlieParams {
            max_triangles: self.max_triangles,
            max_depth: self.max_depth,
            grids: want_grids && !self.no_grids,
            regions: !self.no_regions,
            propagation: !self.no_propagation,
        };
        p.octree().validate()?;
        Ok(p)
    }
}
