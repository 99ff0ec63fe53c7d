//! The last step of the construction: the rounds' records flattened into the P-LIE's arrays (by
//! leaf, face, light), and the statistics of what was kept.

use std::time::Instant;

use super::refine::Refiner;
use super::round::{Round, TaskRecords};
use super::stats::{BuildStats, RoundStats};
use super::{grid, Built};
use crate::lie::{FaceGrid, Plie, PlieParams, Record, RecordKind, RecordRegions, NO_RECORD, SCENE_CELL, UMBRA_CELL};
use crate::octree::{Dir, Octree};
use crate::scene::{LightId, Scene, TriId};

/// Propagation figures summed over the rounds, and the first round's summary.
#[derive(Default)]
pub(super) struct Totals {
    tests: usize,
    wasted: usize,
    seconds: f64,
    /// With refinement: the first round's figures.
    pub(super) unrefined: Option<RoundStats>,
}

impl Totals {
    /// Adds `round`'s propagation figures.
    pub(super) fn add(&mut self, round: &Round) {
        self.tests += round.tests;
        self.wasted += round.wasted;
        self.seconds += round.seconds;
    }
}

/// The last round flattened into the P-LIE, with the construction's statistics; `t0` is its start.
pub(super) fn finish(
    scene: &Scene,
    octree: Octree,
    params: PlieParams,
    round: Round,
    refiner: Refiner,
    totals: Totals,
    t0: Instant,
) -> Built {
    let Round { tasks, propagator_log: propagated, states, over_budget, .. } = round;
    let lights = scene.lights.len();
    let mut stats = BuildStats {
        leaves: octree.leaf_count(),
        faces_considered: octree.leaf_count() * 6 * lights,
        propagation_wasted: totals.wasted,
        propagation_seconds: totals.seconds,
        refine_rounds: refiner.splits.len(),
        refine_splits: refiner.by_criterion,
        unrefined: totals.unrefined,
        ..Default::default()
    };
    stats.records_over_budget = over_budget;
    let mut plie = flatten(&octree, params, lights, tasks, &mut stats);
    plie.splits = refiner.splits;
    stats.propagation_tests = totals.tests;
    stats.records_removed_propagation = propagated.len();
    debug_assert_eq!(propagated.len(), states.propagated());
    for p in &propagated {
        *stats.propagation_by_rule.entry(p.rule.name()).or_default() += 1;
    }
    stats.no_record_face_cannot_see_light =
        stats.faces_considered - stats.records - stats.records_removed_umbra - stats.records_removed_propagation;
    let threads = rayon::current_num_threads().max(1) as f64;
    stats.propagation_seconds_saved_estimate =
        stats.records_removed_propagation as f64 * stats.record_seconds_mean / threads - totals.seconds;
    stats.blockers_seconds = t0.elapsed().as_secs_f64();
    Built { octree, plie, stats, propagated }
}

/// The tasks' records flattened into the P-LIE (by leaf, face, light), with their statistics.
pub(super) fn flatten(
    octree: &Octree,
    params: PlieParams,
    lights: usize,
    mut tasks: Vec<TaskRecords>,
    stats: &mut BuildStats,
) -> Plie {
    let mut plie = Plie {
        params,
        leaves: octree.leaf_count() as u32,
        lights: lights as u32,
        record_index: vec![NO_RECORD; octree.leaf_count() * 6 * lights],
        records: Vec::new(),
        blockers: Vec::new(),
        grids: Vec::new(),
        cells: Vec::new(),
        cell_blockers: Vec::new(),
        regions: Vec::new(),
        region_tris: Vec::new(),
        splits: Vec::new(),
    };
    let (mut task_seconds, mut computed) = (0.0, 0);
    for t in &tasks {
        stats.candidates_clipped += t.candidates;
        stats.records_removed_umbra += t.removed_umbra;
        task_seconds += t.seconds;
        computed += t.computed.iter().flatten().count();
    }
    stats.record_seconds_mean = if computed > 0 { task_seconds / computed as f64 } else { 0.0 };
    let (mut umbra_sum, mut penumbra_sum) = (0.0, 0.0);
    for leaf in octree.leaves() {
        for face in Dir::ALL {
            for li in 0..lights {
                let Some(rec) = tasks[leaf.idx() * lights + li].records[face.index()].take() else { continue };
                let fg = flatten_grid(rec.grid, &mut plie, stats);
                plie.grids.push(fg);
                let mut rr = RecordRegions::default();
                if let Some(reg) = rec.regions {
                    stats.records_with_umbra += !reg.umbra.is_empty() as usize;
                    stats.records_with_penumbra += !reg.penumbra.is_empty() as usize;
                    stats.region_polygon_vertices += reg.polygon_vertices;
                    umbra_sum += reg.umbra_fraction;
                    penumbra_sum += reg.penumbra_fraction;
                    rr.umbra_start = plie.region_tris.len() as u32;
                    rr.umbra_len = reg.umbra.len() as u32;
                    plie.region_tris.extend(reg.umbra);
                    rr.penumbra_start = plie.region_tris.len() as u32;
                    rr.penumbra_len = reg.penumbra.len() as u32;
                    plie.region_tris.extend(reg.penumbra);
                }
                plie.regions.push(rr);
                let light = LightId(li as u32);
                let i = plie.slot(leaf, face, light);
                plie.record_index[i] = plie.records.len() as u32;
                plie.records.push(Record {
                    leaf,
                    face,
                    light,
                    blockers_start: plie.blockers.len() as u32,
                    blockers_len: rec.blockers.len() as u32,
                    kind: rec.kind,
                });
                stats.records_scene += (rec.kind == RecordKind::Scene) as usize;
                plie.blockers.extend(rec.blockers);
            }
        }
    }
    stats.records = plie.records.len();
    stats.region_triangles = plie.region_tris.len();
    stats.region_bytes = plie.region_tris.len() * std::mem::size_of::<crate::lie::Tri2>()
        + plie.regions.len() * std::mem::size_of::<RecordRegions>();
    if params.has_regions() && stats.records > 0 {
        stats.umbra_fraction_mean = umbra_sum / stats.records as f64;
        stats.penumbra_fraction_mean = penumbra_sum / stats.records as f64;
    }
    stats.blockers_total = plie.blockers.len();
    stats.list_bytes = (plie.blockers.len() + plie.cell_blockers.len()) * std::mem::size_of::<TriId>();
    (stats.blockers_mean, stats.blockers_max) = plie.blocker_stats();
    plie
}

/// A record's grid, flattened into `plie.cells` and `plie.cell_blockers`.
pub(super) fn flatten_grid(grid: Option<grid::PendingGrid>, plie: &mut Plie, stats: &mut BuildStats) -> FaceGrid {
    let Some(pg) = grid else {
        return FaceGrid::default();
    };
    let fg = FaceGrid { res: pg.g, cells_start: plie.cells.len() as u32 };
    stats.grids += 1;
    let mut ranges = Vec::with_capacity(pg.lists.len());
    for l in pg.lists {
        ranges.push((plie.cell_blockers.len() as u32, l.len() as u32));
        plie.cell_blockers.extend(l);
    }
    let cells = (pg.g * pg.g) as usize;
    for i in 0..cells {
        stats.grid_cells += 1;
        if pg.umbra.get(i).copied().unwrap_or(false) {
            stats.grid_cells_umbra += 1;
            plie.cells.push(UMBRA_CELL);
        } else if pg.scene {
            plie.cells.push(SCENE_CELL);
        } else {
            let r = ranges[pg.cell_list[i] as usize];
            stats.grid_cells_lit += (r.1 == 0) as usize;
            plie.cells.push(r);
        }
    }
    fg
}
