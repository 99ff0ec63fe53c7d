//! The figures of one construction (SPEC §4): what each stage kept and removed, and how long it took.
//! One struct per phase; [`BuildStats`] holds them, serialises to one JSON object (the phases'
//! fields at the top level, but propagation's and refinement's, which are objects of their own) and
//! prints one line or two per phase ([`std::fmt::Display`]). A new counter is a field of its phase:
//! the JSON follows, and the text where it says so.

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;

/// Named counters and stage times of one construction, by phase.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BuildStats {
    /// The octree (SPEC §3).
    #[serde(flatten)]
    pub octree: OctreeStats,
    /// Data objects, shafts and blockers (§4.1-§4.4).
    #[serde(flatten)]
    pub blockers: BlockerStats,
    /// Bounded storage (issue 15): records answered by the scene BVH.
    #[serde(flatten)]
    pub bounded: BoundedStats,
    /// Umbra and penumbra (§4.5), removal of dark records (§4.6).
    #[serde(flatten)]
    pub regions: RegionStats,
    /// Propagation of umbra (§4.7).
    pub propagation: PropagationStats,
    /// Refinement (§4.8).
    pub refinement: RefinementStats,
    /// Face grids (SPEC §8 points 2-4).
    #[serde(flatten)]
    pub grids: GridStats,
}

/// The octree the P-LIE is built on (refined if refinement split leaves).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct OctreeStats {
    /// Leaves.
    pub leaves: usize,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// Seconds building the octree (before refinement).
    pub octree_seconds: f64,
    /// True if the node cap ([`crate::octree::max_nodes`]) kept the build from splitting a level.
    pub capped: bool,
}

/// Which (leaf, face, light) get a record, and their blockers.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BlockerStats {
    /// (leaf, face, light) triples considered.
    pub faces_considered: usize,
    /// Records kept (data objects).
    pub records: usize,
    /// Triples without a record because the face cannot see the light (§4.1).
    pub records_removed_face_cannot_see_light: usize,
    /// Candidate triangles clipped against shafts.
    pub candidates_clipped: usize,
    /// Blocker references stored.
    pub blockers_total: usize,
    /// Mean blockers per record.
    pub blockers_mean: f64,
    /// Most blockers on one record.
    pub blockers_max: u32,
    /// Seconds computing data objects, shafts, blockers, regions and grids, propagation and
    /// refinement included: the construction without the octree.
    pub blockers_seconds: f64,
}

/// Records answered by the scene BVH (records of kind `Scene`, issue 15).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BoundedStats {
    /// The cap on blockers per record ([`crate::PlieParams::blocker_cap`]).
    pub blocker_cap: Option<u32>,
    /// Bytes the blocker lists could take ([`crate::BuildOptions::list_bytes`]); `None`: no limit.
    pub list_budget: Option<usize>,
    /// Records answered by the scene BVH: more blockers than the cap, or over the list budget.
    pub records_scene: usize,
    /// Of those, the records whose lists did not fit the list budget.
    pub records_over_budget: usize,
    /// Candidate clips the construction could spend lifting the cap ([`crate::BuildOptions::lift_clips`],
    /// per scene triangle); `None`: no lifting.
    pub lift_clips: Option<usize>,
    /// Records over the cap gathered again with a lifted cap (`construct::lift`).
    pub records_lift_tried: usize,
    /// Of those, the records that fit it: they hold their full lists (or were removed in umbra).
    pub records_lifted: usize,
    /// Candidate clips the construction could spend on the cells of the records still over the cap
    /// ([`crate::BuildOptions::cell_clips`], per scene triangle); `None`: none.
    pub cell_clips: Option<usize>,
    /// Records over the cap whose grid cells gathered their own blockers (`construct::scene_cells`).
    pub records_scene_cells: usize,
    /// Of their cells, those under the cells' cap: they hold their full lists (empty: fully lit).
    pub scene_cells_listed: usize,
    /// Bytes of the blocker lists stored (records and grid cells).
    pub list_bytes: usize,
}

/// Umbra and penumbra on the faces, and the records removed for lying fully in umbra.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RegionStats {
    /// Whether regions were computed ([`crate::Regions::Compute`]).
    pub regions: bool,
    /// Records removed because their face lies fully in umbra (§4.6).
    pub records_removed_umbra: usize,
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
}

/// Propagation of umbra to neighbouring faces (§4.7).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PropagationStats {
    /// Whether propagation was asked for ([`crate::Propagation::On`]; it runs only with regions).
    pub enabled: bool,
    /// Records deleted by propagation without computing their blockers.
    pub records_removed: usize,
    /// Of those, how many each rule proposed (`construct::propagation::Rule::name`).
    pub by_rule: BTreeMap<&'static str, usize>,
    /// Principle tests run (pending candidates proposed by the rules).
    pub tests: usize,
    /// Records computed before an earlier task's commit deleted them, their result discarded (depends
    /// on timing, unlike everything else here).
    pub wasted: usize,
    /// Seconds spent propagating (at the commits, one at a time).
    pub seconds: f64,
    /// Mean thread-seconds to compute one record (blockers, regions, grid), fully dark ones included.
    pub record_seconds_mean: f64,
    /// Estimated wall seconds propagation saved: the records it deleted times the mean record time,
    /// over the threads, minus the propagation time. An estimate; measure with and without
    /// propagation for the real figure (`plie bench`).
    pub seconds_saved_estimate: f64,
}

/// Refinement of the octree (§4.8).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RefinementStats {
    /// The criteria asked for, in chain order ([`crate::Criterion::name`]).
    pub criteria: Vec<&'static str>,
    /// Most times one leaf of the first octree may be split.
    pub max_split_depth: u32,
    /// The blocker criterion's threshold ([`crate::MaxBlockers`], in its `Debug` form), if asked for.
    pub max_blockers: Option<String>,
    /// Rounds that split some leaf.
    pub rounds: usize,
    /// Leaves split, by the criterion that asked; each split adds 7 leaves.
    pub splits_by_criterion: BTreeMap<&'static str, usize>,
    /// Leaves added by the splits.
    pub leaves_added: usize,
    /// True if refinement ended because the next round's splits would pass the octree's node cap
    /// ([`crate::octree::max_nodes`]).
    pub stopped_at_node_cap: bool,
    /// With refinement: the first round's figures, i.e. the P-LIE without refinement.
    pub unrefined: Option<RoundStats>,
}

/// The figures of one construction round (see [`RefinementStats::unrefined`]).
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

/// The face grids of the records.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GridStats {
    /// Whether face grids were built ([`crate::Grids::Build`]; not in the JSON).
    #[serde(skip)]
    pub enabled: bool,
    /// Records with a face grid.
    pub grids: usize,
    /// Grid cells in all.
    pub grid_cells: usize,
    /// Grid cells with no blocker at all (fully lit).
    pub grid_cells_lit: usize,
    /// Grid cells fully in umbra.
    pub grid_cells_umbra: usize,
    /// Blocker references stored in the cells.
    pub grid_blockers_total: usize,
}

impl fmt::Display for BuildStats {
    /// The figures as lines of text, a line or two per phase (what `plie build` prints between the
    /// scene and the file).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let o = &self.octree;
        let capped =
            if o.capped { "; the node cap stopped its splits, raise --max-triangles or lower --max-depth" } else { "" };
        writeln!(f, "octree          {} leaves, depth {} ({:.3} s{capped})", o.leaves, o.depth, o.octree_seconds)?;
        write!(f, "{}{}{}", self.blockers, self.bounded, self.regions)?;
        // Propagation needs regions: without them it says nothing.
        if self.regions.regions {
            write!(f, "{}", self.propagation)?;
        }
        write!(f, "{}{}", self.refinement_text(), self.grids)
    }
}

impl BuildStats {
    /// Refinement's lines, which compare with the unrefined round.
    fn refinement_text(&self) -> RefinementText<'_> {
        RefinementText(self)
    }
}

impl fmt::Display for BlockerStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "data objects    {} of {} (leaf, face, light); {} without: the face cannot see the light",
            self.records, self.faces_considered, self.records_removed_face_cannot_see_light
        )?;
        writeln!(
            f,
            "blockers        {} in all, {:.1} per record (max {}), {} candidates clipped ({:.3} s)",
            self.blockers_total, self.blockers_mean, self.blockers_max, self.candidates_clipped, self.blockers_seconds
        )
    }
}

impl fmt::Display for BoundedStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let cap = self.blocker_cap.map_or("no cap".to_string(), |c| c.to_string());
        let budget = self.list_budget.map_or("no".to_string(), |b| format!("{b}-byte"));
        writeln!(
            f,
            "scene records   {} answered by the scene BVH ({} with more than {cap} blockers, {} over the {budget} budget of the blocker lists)",
            self.records_scene,
            self.records_scene - self.records_over_budget,
            self.records_over_budget
        )?;
        match self.lift_clips {
            None => writeln!(f, "lifted cap      none"),
            Some(b) => writeln!(
                f,
                "lifted cap      {} records over the cap gathered again with a larger cap, {} of them now hold their full lists ({b} clips per triangle)",
                self.records_lift_tried, self.records_lifted
            ),
        }?;
        match self.cell_clips {
            None => writeln!(f, "scene cells     none"),
            Some(b) => writeln!(
                f,
                "scene cells     {} records over the cap gathered their cells: {} cells hold their full lists ({b} clips per triangle)",
                self.records_scene_cells, self.scene_cells_listed
            ),
        }
    }
}

impl fmt::Display for RegionStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.regions {
            return writeln!(f, "regions         none (--no-regions)");
        }
        writeln!(
            f,
            "regions         {} records removed (fully in umbra); of those kept, {} with umbra, {} with penumbra",
            self.records_removed_umbra, self.records_with_umbra, self.records_with_penumbra
        )?;
        writeln!(
            f,
            "                mean umbra {:.1}% and penumbra {:.1}% of a face; {} polygon vertices, {} triangles ({} bytes)",
            100.0 * self.umbra_fraction_mean,
            100.0 * self.penumbra_fraction_mean,
            self.region_polygon_vertices,
            self.region_triangles,
            self.region_bytes
        )
    }
}

impl fmt::Display for PropagationStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.enabled {
            return writeln!(f, "propagation     none (--no-propagation)");
        }
        writeln!(
            f,
            "propagation     {} records removed without computing their blockers ({} of {} candidates proven; {} computed before being removed; {:.3} s propagating)",
            self.records_removed, self.records_removed, self.tests, self.wasted, self.seconds
        )?;
        if self.records_removed > 0 {
            let rules: Vec<String> = self.by_rule.iter().map(|(r, n)| format!("{n} {r}")).collect();
            writeln!(f, "                by rule: {}", rules.join(", "))?;
        }
        writeln!(
            f,
            "                {} (estimate: {:.2} ms per record computed, over the threads, minus propagation)",
            time_saved(self.seconds_saved_estimate),
            1e3 * self.record_seconds_mean
        )
    }
}

/// [`RefinementStats`] as text, beside the figures it changed.
struct RefinementText<'a>(&'a BuildStats);

impl fmt::Display for RefinementText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.0;
        let r = &s.refinement;
        let Some(u) = r.unrefined else {
            return writeln!(f, "refinement      none (--refine to enable)");
        };
        let by: Vec<String> =
            // The criteria as `--refine` spells them (`umbra-free`; the JSON keys keep `umbra_free`).
            r.splits_by_criterion
                .iter()
                .map(|(c, n)| format!("{} {n} splits (+{} leaves)", c.replace('_', "-"), 7 * n))
                .collect();
        writeln!(
            f,
            "refinement      +{} leaves in {} rounds (max split depth {}{}){}{}",
            r.leaves_added,
            r.rounds,
            r.max_split_depth,
            if r.stopped_at_node_cap { "; stopped at the octree's node cap" } else { "" },
            if by.is_empty() { "" } else { ": " },
            by.join(", ")
        )?;
        writeln!(
            f,
            "                leaves {} -> {}, records {} -> {}, blockers {} -> {}, construction {:.3} s -> {:.3} s",
            u.leaves,
            s.octree.leaves,
            u.records,
            s.blockers.records,
            u.blockers_total,
            s.blockers.blockers_total,
            u.seconds,
            s.blockers.blockers_seconds
        )
    }
}

impl fmt::Display for GridStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.enabled {
            return writeln!(f, "face grids      none (--no-grids)");
        }
        writeln!(
            f,
            "face grids      {} records with a grid, {} cells ({} fully lit, {} umbra), {} cell blocker references",
            self.grids, self.grid_cells, self.grid_cells_lit, self.grid_cells_umbra, self.grid_blockers_total
        )
    }
}

/// The estimated construction time propagation saved, in words: a loss is said as one, and less than
/// half a millisecond either way as under a millisecond (never "-0.000 s").
fn time_saved(seconds: f64) -> String {
    if seconds >= 0.0005 {
        format!("time saved ≈ {seconds:.3} s")
    } else if seconds <= -0.0005 {
        format!("time lost ≈ {:.3} s (propagating cost more than it saved)", -seconds)
    } else {
        "time saved under a millisecond".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_saved_never_reads_minus_zero() {
        assert_eq!(time_saved(0.0123), "time saved ≈ 0.012 s");
        assert_eq!(time_saved(-0.0000004), "time saved under a millisecond");
        assert_eq!(time_saved(0.0004), "time saved under a millisecond");
        assert_eq!(time_saved(-0.25), "time lost ≈ 0.250 s (propagating cost more than it saved)");
    }

    /// The JSON keeps the names `plie build --json` printed before the phases (scripts read them):
    /// the phases' fields at the top level, propagation's and refinement's in their own objects.
    #[test]
    fn json_names_are_the_cli_names() {
        let v = serde_json::to_value(BuildStats::default()).unwrap();
        for key in [
            "leaves",
            "depth",
            "octree_seconds",
            "records",
            "records_removed_face_cannot_see_light",
            "blockers_total",
            "blockers_seconds",
            "blocker_cap",
            "records_scene",
            "records_over_budget",
            "records_lifted",
            "records_scene_cells",
            "scene_cells_listed",
            "list_bytes",
            "regions",
            "records_removed_umbra",
            "grids",
            "grid_cells",
            "grid_blockers_total",
        ] {
            assert!(v.get(key).is_some(), "{key} missing: {v}");
        }
        for key in ["enabled", "records_removed", "tests", "by_rule", "seconds", "seconds_saved_estimate"] {
            assert!(v["propagation"].get(key).is_some(), "propagation.{key} missing: {v}");
        }
        for key in ["criteria", "rounds", "splits_by_criterion", "leaves_added", "unrefined", "max_blockers"] {
            assert!(v["refinement"].get(key).is_some(), "refinement.{key} missing: {v}");
        }
    }

    #[test]
    fn each_phase_prints_its_lines() {
        let mut s = BuildStats::default();
        let text = s.to_string();
        for start in [
            "octree ",
            "data objects ",
            "blockers ",
            "scene records ",
            "lifted cap      none",
            "scene cells     none",
            "regions         none",
            "refinement      none",
        ] {
            assert!(text.lines().any(|l| l.starts_with(start)), "{start}: {text}");
        }
        s.regions.regions = true;
        s.propagation.enabled = true;
        s.propagation.records_removed = 3;
        s.propagation.by_rule.insert("corner", 3);
        let text = s.to_string();
        assert!(text.contains("3 records removed without computing") && text.contains("by rule: 3 corner"), "{text}");
    }
}
