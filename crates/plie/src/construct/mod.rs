//! P-LIE construction (SPEC §4), built once for every leaf, face and light, independent of any camera.
//! This file only runs the stages in order; each stage is its own module:
//!
//! 1. [`data_objects`]: which (leaf, face, light) need a record (§4.1, exact condition).
//! 2. [`shaft`]: bounding volume and supporting planes of conv(face ∪ light) (§4.2, §4.3).
//! 3. [`blockers`]: gather candidates from the overlapping leaves, de-duplicate, clip (§4.4).
//! 4. [`regions`]: umbra and penumbra on the face (§4.5); a record fully in umbra is removed (§4.6).
//! 5. [`grid`]: per record, a face grid of per-cell blocker lists with its umbra cells marked (our
//!    addition, SPEC §8 points 2-4).
//! 6. [`propagation`]: faces proven dark by a dark neighbour lose their record before stages 2-5 run
//!    for them (§4.7).
//!
//! 7. [`refine`]: a chain of criteria picks leaves to split (§4.8); the next round computes the new
//!    leaves' records with stages 1-6 and reuses every other record (they do not depend on how other
//!    leaves are split), until no leaf asks or the maximum split depth is reached.
//!
//! The (leaf, light) tasks of a round run in parallel in a fixed order and are committed in that
//! order ([`schedule`]); propagation runs at each commit, so the result does not depend on the thread
//! count.

pub mod blockers;
pub mod data_objects;
pub mod grid;
pub mod propagation;
pub mod refine;
pub mod regions;
pub mod schedule;
pub mod shaft;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use serde::Serialize;

use crate::lie::{FaceGrid, Plie, PlieParams, Record, RecordKind, RecordRegions, NO_RECORD, SCENE_CELL, UMBRA_CELL};
use crate::octree::{Dir, LeafId, Octree};
use crate::render::Progress;
use crate::scene::{LightId, Scene, TriId};
use blockers::{gather_blockers, GatherScratch};
use propagation::{FaceState, FaceStates, Propagated, Propagator, Tolerances};
use shaft::Shaft;

/// Relative tolerance of the construction (times the scene size): every test errs toward keeping.
pub const TOLERANCE_REL: f32 = 1e-5;

/// The absolute tolerance of the construction for `scene` over `octree`: [`TOLERANCE_REL`] times the
/// larger of the scene's size and the octree's root cube. Every test that must agree with the builder
/// (e.g. `plie inspect` telling a removed record from a face that cannot see the light) uses this.
pub fn tolerance(scene: &Scene, octree: &Octree) -> f32 {
    scene.scale().max(octree.root_bounds().size().max_element()) * TOLERANCE_REL
}

/// The largest absolute coordinate of `octree`'s root cube: the scale of the `f32` rounding the
/// regions and propagation allow for.
pub(crate) fn abs_scale(octree: &Octree) -> f32 {
    octree.root_bounds().min.abs().max(octree.root_bounds().max.abs()).max_element()
}

/// Limits of one construction that are not part of the P-LIE's parameters (issue 15).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Limits {
    /// Bytes the blocker lists of the records and grid cells may take. A listed record that would
    /// pass it is stored as [`RecordKind::Scene`] instead (degrading, never aborting); the decision is
    /// made at the record's commit, in task order, so it does not depend on the thread count. `None`:
    /// no limit.
    pub list_bytes: Option<usize>,
}

/// The construction was interrupted ([`Progress::cancelled`]); nothing was built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("interrupted")]
pub struct Interrupted;

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
    /// Records answered by the scene BVH ([`RecordKind::Scene`]): more blockers than the cap, or over
    /// the memory budget.
    pub records_scene: usize,
    /// Of those, the records whose lists did not fit [`Limits::list_bytes`].
    pub records_over_budget: usize,
    /// Bytes of the blocker lists stored (records and grid cells).
    pub list_bytes: usize,
    /// Records removed because their face lies fully in umbra (§4.6).
    pub records_removed_umbra: usize,
    /// Records deleted by propagation (§4.7) without computing their blockers.
    pub records_removed_propagation: usize,
    /// Of those, how many each rule proposed ([`propagation::Rule::name`]).
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
    /// Leaves split by refinement, by the criterion that asked ([`refine::Criterion::name`]); each
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

/// One record before flattening.
struct PendingRecord {
    blockers: Vec<TriId>,
    regions: Option<regions::FaceRegions>,
    grid: Option<grid::PendingGrid>,
    kind: RecordKind,
}

impl PendingRecord {
    /// A [`RecordKind::Scene`] record: no list and no penumbra; its umbra (from a subset of the
    /// blockers) is kept, with a grid of umbra cells when there is some umbra and grids are on.
    fn scene(regions: Option<regions::FaceRegions>, grids: bool) -> PendingRecord {
        let regions = regions.map(|mut r| {
            r.penumbra = Vec::new();
            r.penumbra_fraction = 0.0;
            r
        });
        let grid = regions.as_ref().filter(|r| grids && !r.umbra.is_empty()).map(|r| grid::PendingGrid {
            g: grid::UMBRA_MIN_RES,
            lists: Vec::new(),
            cell_list: Vec::new(),
            umbra: grid::umbra_cells(grid::UMBRA_MIN_RES, r),
            scene: true,
        });
        PendingRecord { blockers: Vec::new(), regions, grid, kind: RecordKind::Scene }
    }

    /// Bytes its blocker lists (record and grid cells) will take in the P-LIE.
    fn list_bytes(&self) -> usize {
        let cells: usize = self.grid.iter().flat_map(|g| &g.lists).map(Vec::len).sum();
        (self.blockers.len() + cells) * std::mem::size_of::<TriId>()
    }

    /// Turns a listed record into a [`RecordKind::Scene`] one (over the memory budget).
    fn into_scene(self, grids: bool) -> PendingRecord {
        PendingRecord::scene(self.regions, grids)
    }
}

/// What was computed for one (leaf, light): a record per face, the faces' new states, counters.
#[derive(Default)]
struct TaskRecords {
    records: [Option<PendingRecord>; 6],
    computed: [Option<FaceState>; 6],
    candidates: usize,
    removed_umbra: usize,
    seconds: f64,
}

/// The P-LIE, the octree it belongs to, its statistics, and the records propagation deleted.
pub struct Built {
    /// The octree (refined if refinement split any leaf).
    pub octree: Octree,
    /// The P-LIE.
    pub plie: Plie,
    /// Its statistics.
    pub stats: BuildStats,
    /// The records deleted by propagation (leaves of [`Built::octree`]), in the order they were.
    pub propagated: Vec<Propagated>,
}

/// Builds the P-LIE of `scene` over `octree` (stages 1-6), without refinement.
///
/// # Panics
/// If `params.refine` asks for refinement, which changes the octree: use [`build_refined`].
pub fn build(scene: &Scene, octree: &Octree, params: PlieParams, progress: &dyn Progress) -> (Plie, BuildStats) {
    let b = build_traced(scene, octree, params, progress);
    (b.plie, b.stats)
}

/// [`build`], also returning which records propagation deleted (for tests and reports).
///
/// # Panics
/// If `params.refine` asks for refinement: use [`build_refined`].
pub fn build_traced(scene: &Scene, octree: &Octree, params: PlieParams, progress: &dyn Progress) -> Built {
    assert!(!params.refine.enabled(), "construct::build does not refine the octree: use construct::build_refined");
    build_refined(scene, octree.clone(), params, progress)
}

/// Builds the P-LIE of `scene` over `octree` (stages 1-6) and refines the octree as `params.refine`
/// asks (stage 7), returning the refined octree with it.
pub fn build_refined(scene: &Scene, octree: Octree, params: PlieParams, progress: &dyn Progress) -> Built {
    build_bounded(scene, octree, params, Limits::default(), progress)
        .expect("construction interrupted: use build_bounded with a progress that can cancel")
}

/// [`build_refined`] within `limits`; returns [`Interrupted`] as soon as `progress` says
/// [`Progress::cancelled`].
pub fn build_bounded(
    scene: &Scene,
    octree: Octree,
    params: PlieParams,
    limits: Limits,
    progress: &dyn Progress,
) -> Result<Built, Interrupted> {
    let t0 = Instant::now();
    let triangles = scene.triangles.len();
    let max_split = params.refine.max_split_depth;
    let mut octree = octree;
    // Times each leaf's region of the original octree has been split.
    let mut level = vec![0u32; octree.leaf_count()];
    let mut splits: Vec<Vec<u32>> = Vec::new();
    let mut by_criterion: BTreeMap<&'static str, usize> = BTreeMap::new();
    let mut prior = None;
    let mut unrefined = None;
    // Propagation figures summed over the rounds.
    let (mut tests, mut wasted, mut propagation_seconds) = (0, 0, 0.0);
    let round = loop {
        let stage = if splits.is_empty() { "blockers".to_string() } else { format!("refine {}", splits.len()) };
        let round = run_round(scene, &octree, params, limits, progress, &stage, prior.take())?;
        tests += round.tests;
        wasted += round.wasted;
        propagation_seconds += round.seconds;
        if unrefined.is_none() && params.refine.enabled() {
            unrefined = Some(round.summary(&octree, t0));
        }
        if !params.refine.enabled() {
            break round;
        }
        let lights = scene.lights.len();
        let candidates: Vec<LeafId> =
            octree.leaves().filter(|&l| level[l.idx()] < max_split && octree.can_split(l)).collect();
        let decisions: Vec<Option<refine::Criterion>> = candidates
            .par_iter()
            .map(|&l| {
                let faces: Vec<refine::FaceView> = (0..lights)
                    .flat_map(|i| round.tasks[l.idx() * lights + i].records.iter().flatten())
                    .map(|r| match r.kind {
                        RecordKind::Listed => {
                            refine::FaceView { blockers: r.blockers.len(), regions: r.regions.as_ref() }
                        }
                        // More blockers than the cap; its regions lack the penumbra.
                        RecordKind::Scene => refine::FaceView { blockers: usize::MAX, regions: None },
                    })
                    .collect();
                refine::decide(&faces, &params.refine, triangles, octree.leaf_depth(l))
            })
            .collect();
        let split: Vec<LeafId> =
            candidates.iter().zip(&decisions).filter(|(_, d)| d.is_some()).map(|(&l, _)| l).collect();
        if split.is_empty() {
            break round;
        }
        for d in decisions.iter().flatten() {
            *by_criterion.entry(d.name()).or_default() += 1;
        }
        splits.push(split.iter().map(|&l| octree.leaf_node(l).0).collect());
        let (refined, origin) = octree.split_leaves(scene, &split);
        let kept = origin.iter().filter(|o| o.is_some()).count();
        level = origin
            .iter()
            .enumerate()
            .map(|(i, o)| match o {
                Some(old) => level[old.idx()],
                None => level[split[(i - kept) / 8].idx()] + 1,
            })
            .collect();
        prior = Some(Prior { round, origin });
        octree = refined;
    };
    let Round { tasks, propagator_log: propagated, states, over_budget, .. } = round;
    let lights = scene.lights.len();
    let mut stats = BuildStats {
        leaves: octree.leaf_count(),
        faces_considered: octree.leaf_count() * 6 * lights,
        propagation_wasted: wasted,
        propagation_seconds,
        refine_rounds: splits.len(),
        refine_splits: by_criterion,
        unrefined,
        ..Default::default()
    };
    stats.records_over_budget = over_budget;
    let mut plie = flatten(&octree, params, lights, tasks, &mut stats);
    plie.splits = splits;
    stats.propagation_tests = tests;
    stats.records_removed_propagation = propagated.len();
    debug_assert_eq!(propagated.len(), states.propagated());
    for p in &propagated {
        *stats.propagation_by_rule.entry(p.rule.name()).or_default() += 1;
    }
    stats.no_record_face_cannot_see_light =
        stats.faces_considered - stats.records - stats.records_removed_umbra - stats.records_removed_propagation;
    let threads = rayon::current_num_threads().max(1) as f64;
    stats.propagation_seconds_saved_estimate =
        stats.records_removed_propagation as f64 * stats.record_seconds_mean / threads - propagation_seconds;
    stats.blockers_seconds = t0.elapsed().as_secs_f64();
    Ok(Built { octree, plie, stats, propagated })
}

/// What one round computed: every (leaf, light) task's records, every face's state, and what
/// propagation did.
struct Round {
    tasks: Vec<TaskRecords>,
    states: FaceStates,
    propagator_log: Vec<Propagated>,
    tests: usize,
    wasted: usize,
    seconds: f64,
    /// Records stored as [`RecordKind::Scene`] because their lists did not fit the budget.
    over_budget: usize,
}

impl Round {
    /// The round's figures, `t0` being the start of the construction.
    fn summary(&self, octree: &Octree, t0: Instant) -> RoundStats {
        let records = self.tasks.iter().flat_map(|t| t.records.iter().flatten());
        RoundStats {
            leaves: octree.leaf_count(),
            records: records.clone().count(),
            blockers_total: records.map(|r| r.blockers.len()).sum(),
            seconds: t0.elapsed().as_secs_f64(),
        }
    }
}

/// The previous round and, for each leaf of the refined octree, the leaf of the previous one it is
/// (`None` for a new child).
struct Prior {
    round: Round,
    origin: Vec<Option<LeafId>>,
}

/// Stages 1-6 for every (leaf, light) of `octree`; with `prior`, the tasks of leaves that were not
/// split are taken from it instead of computed again (their records do not depend on other leaves).
fn run_round(
    scene: &Scene,
    octree: &Octree,
    params: PlieParams,
    limits: Limits,
    progress: &dyn Progress,
    stage: &str,
    prior: Option<Prior>,
) -> Result<Round, Interrupted> {
    let tol = tolerance(scene, octree);
    let lights = scene.lights.len();
    let abs_scale = abs_scale(octree);
    let tols = Tolerances::new(tol, abs_scale);
    let propagate = params.propagates();
    let order = propagation::task_order(scene, octree, propagate);
    let mut states = FaceStates::new(scene, octree, tol);
    let mut propagator = Propagator::new(scene, octree, tols);
    let mut tasks: Vec<TaskRecords> = (0..octree.leaf_count() * lights).map(|_| TaskRecords::default()).collect();
    if let Some(Prior { round, origin }) = prior {
        // Kept leaves start with their final states and records; their propagated faces stay logged.
        let Round { tasks: mut old_tasks, states: old_states, propagator_log, .. } = round;
        let mut new_of = vec![None; old_tasks.len() / lights.max(1)];
        for (new, old) in origin.iter().enumerate() {
            let Some(old) = *old else { continue };
            let new = LeafId(new as u32);
            new_of[old.idx()] = Some(new);
            for i in 0..lights {
                tasks[new.idx() * lights + i] = std::mem::take(&mut old_tasks[old.idx() * lights + i]);
                for face in Dir::ALL {
                    let light = LightId(i as u32);
                    states.set(new, face, light, old_states.get(old, face, light));
                }
            }
        }
        propagator.log =
            propagator_log.iter().filter_map(|p| new_of[p.leaf.idx()].map(|leaf| Propagated { leaf, ..*p })).collect();
    }
    let initial = states.clone();
    // Set at the commit that deletes a face: workers skip it (a face deleted later is computed anyway,
    // and its result discarded at its own commit).
    let deleted: Vec<AtomicBool> = (0..states.len()).map(|_| AtomicBool::new(false)).collect();
    // The budget counts the lists of the records carried over from the previous round too.
    let used = tasks.iter().flat_map(|t| t.records.iter().flatten()).map(PendingRecord::list_bytes).sum();
    let budget = Budget { limit: limits.list_bytes, used, over: 0, grids: params.has_grids() };
    let mut commits = Commits { states, propagator, tasks, lights, propagate, seconds: 0.0, wasted: 0, budget };
    let cancelled = AtomicBool::new(false);
    let scratches: Vec<Mutex<GatherScratch>> = (0..rayon::current_num_threads().max(1))
        .map(|_| Mutex::new(GatherScratch::new(scene.triangles.len())))
        .collect();
    progress.start(stage, order.len() as u64);
    schedule::run_ordered(
        order.len(),
        // Stages 2-5 for the task's faces that are pending and not deleted yet.
        |k| {
            let (leaf, light) = order[k];
            if cancelled.load(Ordering::Relaxed) || progress.cancelled() {
                cancelled.store(true, Ordering::Relaxed);
                return None;
            }
            // One scratch per worker thread (a task never waits for another).
            let slot = &scratches[rayon::current_thread_index().unwrap_or(0) % scratches.len()];
            let mut scratch = slot.lock().unwrap_or_else(|e| e.into_inner());
            let out: [Option<FaceOut>; 6] = std::array::from_fn(|f| {
                let face = Dir::from_index(f);
                let pending = initial.get(leaf, face, light) == FaceState::Pending;
                let todo = pending && !deleted[initial.index(leaf, face, light)].load(Ordering::Acquire);
                todo.then(|| face_record(scene, octree, (leaf, light), face, &tols, abs_scale, params, &mut scratch))
            });
            progress.advance(1);
            Some(out)
        },
        |k, out| {
            if let Some(out) = out {
                commits.commit(order[k], out, &deleted);
            }
        },
    );
    progress.finish();
    if cancelled.load(Ordering::Relaxed) {
        return Err(Interrupted);
    }
    let Commits { states, propagator, tasks, seconds, wasted, budget, .. } = commits;
    let over_budget = budget.over;
    Ok(Round { tasks, states, propagator_log: propagator.log, tests: propagator.tests, wasted, seconds, over_budget })
}

/// The memory budget of the blocker lists, spent at the commits in task order.
struct Budget {
    limit: Option<usize>,
    used: usize,
    /// Records turned into [`RecordKind::Scene`] because they did not fit.
    over: usize,
    grids: bool,
}

impl Budget {
    /// `rec` if its lists fit the budget (spending it), else `rec` as a [`RecordKind::Scene`] record.
    fn spend(&mut self, rec: PendingRecord) -> PendingRecord {
        let bytes = rec.list_bytes();
        if self.limit.is_some_and(|l| self.used + bytes > l) && rec.kind == RecordKind::Listed {
            self.over += 1;
            return rec.into_scene(self.grids);
        }
        self.used += bytes;
        rec
    }
}

/// What the commits own, in task order: the faces' states, the propagator and the results.
struct Commits<'a> {
    states: FaceStates,
    propagator: Propagator<'a>,
    tasks: Vec<TaskRecords>,
    lights: usize,
    propagate: bool,
    /// Seconds spent propagating.
    seconds: f64,
    /// Faces computed, then found deleted at their commit.
    wasted: usize,
    budget: Budget,
}

impl Commits<'_> {
    /// Commits one task: each face's outcome (computed, or deleted by an earlier commit), then
    /// propagation from the task's leaf (stage 6); what it deletes is marked in `deleted` for the
    /// workers.
    fn commit(&mut self, (leaf, light): (LeafId, LightId), out: [Option<FaceOut>; 6], deleted: &[AtomicBool]) {
        let t = &mut self.tasks[leaf.idx() * self.lights + light.idx()];
        for (face, fo) in Dir::ALL.into_iter().zip(out) {
            match self.states.get(leaf, face, light) {
                FaceState::Pending => {}
                FaceState::Propagated { .. } => {
                    self.wasted += fo.is_some() as usize;
                    continue;
                }
                _ => continue,
            }
            let fo = fo.expect("a face pending at its task's commit was computed");
            self.states.set(leaf, face, light, fo.state);
            t.records[face.index()] = fo.record.map(|r| self.budget.spend(r));
            t.computed[face.index()] = Some(fo.state);
            t.candidates += fo.candidates;
            t.removed_umbra += matches!(fo.state, FaceState::Dark { .. }) as usize;
            t.seconds += fo.seconds;
        }
        if self.propagate {
            let t0 = Instant::now();
            let before = self.propagator.log.len();
            self.propagator.after_commit(&mut self.states, &[(leaf, light)]);
            for d in &self.propagator.log[before..] {
                deleted[self.states.index(d.leaf, d.face, d.light)].store(true, Ordering::Release);
            }
            self.seconds += t0.elapsed().as_secs_f64();
        }
    }
}

/// The tasks' records flattened into the P-LIE (by leaf, face, light), with their statistics.
fn flatten(
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
    stats.region_bytes = plie.region_tris.len() * std::mem::size_of::<regions::Tri2>()
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
fn flatten_grid(grid: Option<grid::PendingGrid>, plie: &mut Plie, stats: &mut BuildStats) -> FaceGrid {
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

/// What stages 2-5 made of one (leaf, face, light).
struct FaceOut {
    record: Option<PendingRecord>,
    state: FaceState,
    candidates: usize,
    seconds: f64,
}

/// Stages 2-5 for one (leaf, face, light) that is still `Pending`.
#[allow(clippy::too_many_arguments)]
fn face_record(
    scene: &Scene,
    octree: &Octree,
    (leaf, light_id): (LeafId, LightId),
    face: Dir,
    tols: &Tolerances,
    abs_scale: f32,
    params: PlieParams,
    scratch: &mut GatherScratch,
) -> FaceOut {
    let t0 = Instant::now();
    let tol = tols.tol;
    let b = octree.leaf_bounds(leaf);
    let light = &scene.lights[light_id.idx()];
    let corners = face.face_corners(&b);
    let shaft = Shaft::new(&corners, &light.vertices, tol);
    let mut blockers = Vec::new();
    let cap = params.blocker_cap.map(|c| c as usize);
    let gathered = gather_blockers(scene, octree, &shaft, light_id, cap, scratch, &mut blockers);
    // Capped: `blockers` is a subset, whose umbra is a subset of the true umbra (still sound); its
    // penumbra is not needed.
    let regions = params.has_regions().then(|| {
        let f = if gathered.capped { regions::face_umbra } else { regions::face_regions };
        f(scene, face, &b, light, &blockers, &shaft, tol, abs_scale)
    });
    let (record, state) = if let Some(reg) = regions.as_ref().filter(|r| r.full_umbra) {
        (None, FaceState::Dark { budget: propagation::dark_budget(face, &b, light, reg, tols) })
    } else if gathered.capped {
        (Some(PendingRecord::scene(regions, params.has_grids())), FaceState::Kept)
    } else {
        let has_umbra = regions.as_ref().is_some_and(|r| !r.umbra.is_empty());
        let mut grid = if params.has_grids() {
            let min_res = if has_umbra { grid::UMBRA_MIN_RES } else { 0 };
            grid::face_grid(scene, face, &b, light, &blockers, tol, min_res)
        } else {
            None
        };
        if let (Some(g), Some(reg)) = (grid.as_mut(), regions.as_ref().filter(|_| has_umbra)) {
            g.umbra = grid::umbra_cells(g.g, reg);
        }
        // Long lists in Morton order, for the visibility's chunk boxes (answers do not depend on it).
        let mut blockers = blockers;
        for list in std::iter::once(&mut blockers).chain(grid.iter_mut().flat_map(|g| g.lists.iter_mut())) {
            if list.len() >= crate::lie::CHUNKED_MIN {
                crate::geometry::morton::sort_spatially(scene, list);
            }
        }
        (Some(PendingRecord { blockers, regions, grid, kind: RecordKind::Listed }), FaceState::Kept)
    };
    let candidates = gathered.candidates;
    FaceOut { record, state, candidates, seconds: t0.elapsed().as_secs_f64() }
}
