//! The last step of the construction: the rounds' records flattened into the P-LIE's arrays (by
//! leaf, face, light), and the statistics of what was kept.

use std::time::Instant;

use super::lift::Lift;
use super::refine::Refiner;
use super::round::{Round, TaskRecords};
use super::scene_cells::Cells;
use super::stats::{BuildStats, RoundStats};
use super::{grid, Built};
use crate::lie::{
    FaceGrid, Limits, Plie, PlieParams, Record, RecordKind, RecordRegions, NO_RECORD, SCENE_CELL, UMBRA_CELL,
};
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
    /// The lifting budget left and what lifting did.
    pub(super) lift: Lift,
    /// The cell budget left and what it paid for.
    pub(super) cells: Cells,
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
    let mut stats = BuildStats::default();
    stats.octree.leaves = octree.leaf_count();
    stats.octree.depth = octree.depth();
    stats.octree.capped = octree.capped;
    stats.blockers.faces_considered = octree.leaf_count() * 6 * lights;
    stats.bounded.blocker_cap = params.blocker_cap;
    stats.bounded.records_over_budget = over_budget;
    (stats.bounded.records_lift_tried, stats.bounded.records_lifted) = (totals.lift.tried, totals.lift.lifted);
    (stats.bounded.records_scene_cells, stats.bounded.scene_cells_listed) = (totals.cells.records, totals.cells.listed);
    stats.regions.regions = params.has_regions();
    let p = &mut stats.propagation;
    p.enabled = params.propagation == crate::lie::Propagation::On;
    (p.wasted, p.seconds, p.tests) = (totals.wasted, totals.seconds, totals.tests);
    let r = &mut stats.refinement;
    r.criteria = params.refine.chain().iter().map(|c| c.name()).collect();
    r.max_split_depth = params.refine.max_split_depth;
    r.max_blockers = params.refine.blockers.map(|m| format!("{m:?}"));
    r.rounds = refiner.splits.len();
    r.leaves_added = 7 * refiner.by_criterion.values().sum::<usize>();
    r.splits_by_criterion = refiner.by_criterion;
    r.stopped_at_node_cap = refiner.capped;
    r.unrefined = totals.unrefined;
    stats.grids.enabled = params.has_grids();
    let mut plie = flatten(&octree, params, lights, tasks, &mut stats);
    plie.splits = refiner.splits;
    stats.propagation.records_removed = propagated.len();
    debug_assert_eq!(propagated.len(), states.propagated());
    for p in &propagated {
        *stats.propagation.by_rule.entry(p.rule.name()).or_default() += 1;
    }
    let b = &mut stats.blockers;
    b.records_removed_face_cannot_see_light =
        b.faces_considered - b.records - stats.regions.records_removed_umbra - stats.propagation.records_removed;
    let threads = rayon::current_num_threads().max(1) as f64;
    let p = &mut stats.propagation;
    p.seconds_saved_estimate = p.records_removed as f64 * p.record_seconds_mean / threads - totals.seconds;
    stats.blockers.blockers_seconds = t0.elapsed().as_secs_f64();
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
        limits: Limits::default(),
    };
    let (mut task_seconds, mut computed) = (0.0, 0);
    for t in &tasks {
        stats.blockers.candidates_clipped += t.candidates;
        stats.regions.records_removed_umbra += t.removed_umbra;
        task_seconds += t.seconds;
        computed += usize::from(t.computed);
    }
    stats.propagation.record_seconds_mean = if computed > 0 { task_seconds / computed as f64 } else { 0.0 };
    let (mut umbra_sum, mut penumbra_sum) = (0.0, 0.0);
    for leaf in octree.leaves() {
        for face in Dir::ALL {
            for li in 0..lights {
                let Some(rec) = tasks[leaf.idx() * lights + li].records[face.index()].take() else { continue };
                let fg = flatten_grid(rec.grid, &mut plie, stats);
                plie.grids.push(fg);
                let mut rr = RecordRegions::default();
                if let Some(reg) = rec.regions {
                    stats.regions.records_with_umbra += !reg.umbra.is_empty() as usize;
                    stats.regions.records_with_penumbra += !reg.penumbra.is_empty() as usize;
                    stats.regions.region_polygon_vertices += reg.polygon_vertices;
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
                stats.bounded.records_scene += (rec.kind == RecordKind::Scene) as usize;
                plie.blockers.extend(rec.blockers);
            }
        }
    }
    let records = plie.records.len();
    stats.blockers.records = records;
    let r = &mut stats.regions;
    r.region_triangles = plie.region_tris.len();
    r.region_bytes = plie.region_tris.len() * std::mem::size_of::<crate::lie::Tri2>()
        + plie.regions.len() * std::mem::size_of::<RecordRegions>();
    if params.has_regions() && records > 0 {
        r.umbra_fraction_mean = umbra_sum / records as f64;
        r.penumbra_fraction_mean = penumbra_sum / records as f64;
    }
    stats.blockers.blockers_total = plie.blockers.len();
    stats.bounded.list_bytes = (plie.blockers.len() + plie.cell_blockers.len()) * std::mem::size_of::<TriId>();
    stats.grids.grid_blockers_total = plie.cell_blockers.len();
    (stats.blockers.blockers_mean, stats.blockers.blockers_max) = plie.blocker_stats();
    plie
}

/// A record's grid, flattened into `plie.cells` and `plie.cell_blockers`.
pub(super) fn flatten_grid(grid: Option<grid::PendingGrid>, plie: &mut Plie, stats: &mut BuildStats) -> FaceGrid {
    let Some(pg) = grid else {
        return FaceGrid::default();
    };
    let fg = FaceGrid { res: pg.g, cells_start: plie.cells.len() as u32 };
    stats.grids.grids += 1;
    let mut ranges = Vec::with_capacity(pg.lists.len());
    for l in pg.lists {
        ranges.push((plie.cell_blockers.len() as u32, l.len() as u32));
        plie.cell_blockers.extend(l);
    }
    let cells = (pg.g * pg.g) as usize;
    for i in 0..cells {
        stats.grids.grid_cells += 1;
        if pg.umbra.get(i).copied().unwrap_or(false) {
            stats.grids.grid_cells_umbra += 1;
            plie.cells.push(UMBRA_CELL);
        } else if pg.scene && pg.cell_list.get(i).is_none_or(|&l| l == grid::SCENE_LIST) {
            plie.cells.push(SCENE_CELL);
        } else {
            let r = ranges[pg.cell_list[i] as usize];
            stats.grids.grid_cells_lit += (r.1 == 0) as usize;
            plie.cells.push(r);
        }
    }
    fg
}
