//! The figures of one construction (SPEC §4): what each stage kept and removed, and how long it took.

use std::collections::BTreeMap;

use serde::Serialize;

/// Named counters and stage times of one construction.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BuildStats {
    /// Leaves processed.
    pub leaves: usize,
    /// (leaf, face, light) triples considered.
    pub faces_considered: usize,
    /// Records created (data objects).
    pub records: usize,
    /// Triples without a record because the face cannot see the light (§4.1).
    pub no_record_face_cannot_see_light: usize,
    /// Candidate triangles clipped against shafts.
    pub candidates_clipped: usize,
    /// Blocker references stored.
    pub blockers_total: usize,
    /// Mean blockers per record.
    pub blockers_mean: f64,
    /// Most blockers on one record.
    pub blockers_max: u32,
    /// Records answered by the scene BVH ([`crate::lie::RecordKind::Scene`]): more blockers than the cap, or over
    /// the memory budget.
    pub records_scene: usize,
    /// Of those, the records whose lists did not fit [`super::Limits::list_bytes`].
    pub records_over_budget: usize,
    /// Bytes of the blocker lists stored (records and grid cells).
    pub list_bytes: usize,
    /// Records removed because their face lies fully in umbra (§4.6).
    pub records_removed_umbra: usize,
    /// Records deleted by propagation (§4.7) without computing their blockers.
    pub records_removed_propagation: usize,
    /// Of those, how many each rule proposed ([`super::propagation::Rule::name`]).
    pub propagation_by_rule: BTreeMap<&'static str, usize>,
    /// Principle tests run by propagation (pending candidates proposed by the rules).
    pub propagation_tests: usize,
    /// Records computed before an earlier task's commit deleted them, their result discarded (depends
    /// on timing, unlike everything else here).
    pub propagation_wasted: usize,
    /// Seconds spent propagating (at the commits, one at a time).
    pub propagation_seconds: f64,
    /// Mean thread-seconds to compute one record (blockers, regions, grid), fully dark ones included.
    pub record_seconds_mean: f64,
    /// Estimated wall seconds propagation saved: the records it deleted times the mean record time,
    /// over the threads, minus the propagation time. An estimate; measure with and without
    /// propagation for the real figure (`plie bench`).
    pub propagation_seconds_saved_estimate: f64,
    /// Records (kept) with some umbra.
    pub records_with_umbra: usize,
    /// Records (kept) with some penumbra.
    pub records_with_penumbra: usize,
    /// Vertices of the kept records' umbra and penumbra polygons.
    pub region_polygon_vertices: usize,
    /// Umbra and penumbra triangles stored.
    pub region_triangles: usize,
    /// Bytes of the stored region triangles.
    pub region_bytes: usize,
    /// Mean umbra area over kept records, as a fraction of the face.
    pub umbra_fraction_mean: f64,
    /// Mean penumbra area over kept records, as a fraction of the face.
    pub penumbra_fraction_mean: f64,
    /// Records with a face grid.
    pub grids: usize,
    /// Grid cells with no blocker at all (fully lit).
    pub grid_cells_lit: usize,
    /// Grid cells fully in umbra.
    pub grid_cells_umbra: usize,
    /// Grid cells in all.
    pub grid_cells: usize,
    /// Refinement rounds that split some leaf (§4.8).
    pub refine_rounds: usize,
    /// Leaves split by refinement, by the criterion that asked ([`crate::lie::Criterion::name`]); each
    /// split adds 7 leaves.
    pub refine_splits: BTreeMap<&'static str, usize>,
    /// With refinement: the first round's figures, i.e. the P-LIE without refinement.
    pub unrefined: Option<RoundStats>,
    /// Seconds building the octree.
    pub octree_seconds: f64,
    /// Seconds computing data objects, shafts, blockers, regions and grids, propagation included.
    pub blockers_seconds: f64,
}

/// The figures of one construction round (see [`BuildStats::unrefined`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RoundStats {
    /// Leaves of the octree.
    pub leaves: usize,
    /// Records kept.
    pub records: usize,
    /// Blocker references of the kept records.
    pub blockers_total: usize,
    /// Seconds from the start of the construction to the end of the round.
    pub seconds: f64,
}

impl std::fmt::Display for BuildStats {
    /// The figures as lines of text, one per stage (what `plie build` prints, without the file).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "leaves          {} ({:.3} s octree)", self.leaves, self.octree_seconds)?;
        writeln!(
            f,
            "data objects    {} of {} (leaf, face, light); {} without: the face cannot see the light",
            self.records, self.faces_considered, self.no_record_face_cannot_see_light
        )?;
        writeln!(
            f,
            "blockers        {} in all, {:.1} per record (max {}), {} candidates clipped ({:.3} s)",
            self.blockers_total, self.blockers_mean, self.blockers_max, self.candidates_clipped, self.blockers_seconds
        )?;
        writeln!(
            f,
            "scene records   {} answered by the scene BVH ({} over the memory budget)",
            self.records_scene, self.records_over_budget
        )?;
        writeln!(
            f,
            "regions         {} records removed (fully in umbra); of those kept, {} with umbra, {} with penumbra",
            self.records_removed_umbra, self.records_with_umbra, self.records_with_penumbra
        )?;
        writeln!(
            f,
            "propagation     {} records removed without computing their blockers ({} candidates tested, {:.3} s)",
            self.records_removed_propagation, self.propagation_tests, self.propagation_seconds
        )?;
        if let Some(u) = self.unrefined {
            writeln!(
                f,
                "refinement      {} rounds: leaves {} -> {}, records {} -> {}, blockers {} -> {}",
                self.refine_rounds,
                u.leaves,
                self.leaves,
                u.records,
                self.records,
                u.blockers_total,
                self.blockers_total
            )?;
        }
        writeln!(
            f,
            "face grids      {} records with a grid, {} cells ({} fully lit, {} umbra)",
            self.grids, self.grid_cells, self.grid_cells_lit, self.grid_cells_umbra
        )
    }
}
