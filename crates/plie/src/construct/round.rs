//! One construction round (SPEC §4.1-§4.7): stages 1-6 for every (leaf, light) task of the octree,
//! run in parallel and committed in a fixed order ([`super::schedule`]); propagation and the memory
//! budget are applied at the commits, so the result does not depend on the thread count. Each worker
//! thread owns one gather scratch for all its tasks.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use super::blockers::GatherScratch;
use super::propagation::{self, FaceState, FaceStates, Propagated, Propagator, Tolerances};
use super::record::{face_record, FaceOut, PendingRecord};
use super::stats::RoundStats;
use super::{abs_scale, schedule, tolerance, Interrupted, Limits};
use crate::lie::{PlieParams, RecordKind};
use crate::octree::{Dir, LeafId, Octree};
use crate::progress::Progress;
use crate::scene::{LightId, Scene};

/// What was computed for one (leaf, light): a record per face, counters. There is one per (leaf,
/// light), most without a record (a face that cannot see the light), so the records are boxed: with
/// many lights the build's memory is that of the records it keeps, not of the (leaf, light) pairs.
#[derive(Default)]
pub(super) struct TaskRecords {
    pub(super) records: [Option<Box<PendingRecord>>; 6],
    /// Faces whose record was computed (kept or removed in umbra).
    pub(super) computed: u8,
    pub(super) candidates: usize,
    pub(super) removed_umbra: usize,
    pub(super) seconds: f64,
}
// One per (leaf, light): kept small whatever a record holds.
const _: () = assert!(std::mem::size_of::<TaskRecords>() <= 80);

/// What one round computed: every (leaf, light) task's records, every face's state, and what
/// propagation did.
pub(super) struct Round {
    pub(super) tasks: Vec<TaskRecords>,
    pub(super) states: FaceStates,
    pub(super) propagator_log: Vec<Propagated>,
    pub(super) tests: usize,
    pub(super) wasted: usize,
    pub(super) seconds: f64,
    /// Records stored as [`RecordKind::Scene`] because their lists did not fit the budget.
    pub(super) over_budget: usize,
}

impl Round {
    /// The round's figures, `t0` being the start of the construction.
    pub(super) fn summary(&self, octree: &Octree, t0: Instant) -> RoundStats {
        let records = self.tasks.iter().flat_map(|t| t.records.iter().flatten());
        RoundStats {
            leaves: octree.leaf_count(),
            records: records.clone().count(),
            blockers_total: records.map(|r| r.blockers.len()).sum(),
            seconds: t0.elapsed().as_secs_f64(),
        }
    }
}

/// Bytes the blocker lists of `tasks`' records take ([`PendingRecord::list_bytes`]): what the memory
/// budget has spent on them.
pub(super) fn list_bytes(tasks: &[TaskRecords]) -> usize {
    tasks.iter().flat_map(|t| t.records.iter().flatten()).map(|r| r.list_bytes()).sum()
}

/// The previous round and, for each leaf of the refined octree, the leaf of the previous one it is
/// (`None` for a new child).
pub(super) struct Prior {
    pub(super) round: Round,
    pub(super) origin: Vec<Option<LeafId>>,
}

/// Stages 1-6 for every (leaf, light) of `octree`; with `prior`, the tasks of leaves that were not
/// split are taken from it instead of computed again (their records do not depend on other leaves).
pub(super) fn run_round(
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
    // Set where a face is pending at the start and cleared at the commit that deletes it: workers skip
    // a face whose flag is clear (a face deleted later is computed anyway, and its result discarded at
    // its own commit). One byte per (leaf, face, light), where a copy of the states took sixteen.
    let todo: Vec<AtomicBool> =
        (0..states.len()).map(|i| AtomicBool::new(states.at(i) == FaceState::Pending)).collect();
    // The budget counts the lists of the records carried over from the previous round too.
    let used = list_bytes(&tasks);
    let budget = Budget { limit: limits.list_bytes, used, over: 0, grids: params.has_grids() };
    let mut commits = Commits { states, propagator, tasks, lights, propagate, seconds: 0.0, wasted: 0, budget };
    let cancelled = AtomicBool::new(false);
    progress.start(stage, order.len() as u64);
    schedule::run_ordered_init(
        order.len(),
        // One gather scratch per worker thread, for all the tasks it takes.
        || GatherScratch::new(scene.triangles.len()),
        // Stages 2-5 for the task's faces that are pending and not deleted yet.
        |scratch, k| {
            let (leaf, light) = order[k];
            if cancelled.load(Ordering::Relaxed) || progress.cancelled() {
                cancelled.store(true, Ordering::Relaxed);
                return None;
            }
            let out: [Option<FaceOut>; 6] = std::array::from_fn(|f| {
                let face = Dir::from_index(f);
                let todo = todo[FaceStates::index_of(lights, leaf, face, light)].load(Ordering::Acquire);
                todo.then(|| face_record(scene, octree, (leaf, light), face, &tols, abs_scale, params, scratch))
            });
            progress.advance(1);
            // Boxed, and only where a face was computed: the schedule holds a slot per task.
            Some(out.iter().any(Option::is_some).then(|| Box::new(out)))
        },
        |k, out| {
            if let Some(out) = out {
                commits.commit(order[k], out.map_or_else(|| std::array::from_fn(|_| None), |o| *o), &todo);
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
pub(super) struct Budget {
    limit: Option<usize>,
    used: usize,
    /// Records turned into [`RecordKind::Scene`] because they did not fit.
    over: usize,
    grids: bool,
}

impl Budget {
    /// `rec` if its lists fit the budget (spending it), else `rec` as a [`RecordKind::Scene`] record.
    pub(super) fn spend(&mut self, rec: PendingRecord) -> PendingRecord {
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
pub(super) struct Commits<'a> {
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
    /// propagation from the task's leaf (stage 6); what it deletes is cleared in `todo` for the
    /// workers.
    pub(super) fn commit(&mut self, (leaf, light): (LeafId, LightId), out: [Option<FaceOut>; 6], todo: &[AtomicBool]) {
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
            t.records[face.index()] = fo.record.map(|r| Box::new(self.budget.spend(r)));
            t.computed += 1;
            t.candidates += fo.candidates;
            t.removed_umbra += matches!(fo.state, FaceState::Dark { .. }) as usize;
            t.seconds += fo.seconds;
        }
        if self.propagate {
            let t0 = Instant::now();
            let before = self.propagator.log.len();
            self.propagator.after_commit(&mut self.states, leaf, light);
            for d in &self.propagator.log[before..] {
                todo[self.states.index(d.leaf, d.face, d.light)].store(false, Ordering::Release);
            }
            self.seconds += t0.elapsed().as_secs_f64();
        }
    }
}
