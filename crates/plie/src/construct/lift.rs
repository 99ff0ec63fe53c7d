//! Lifting the blocker cap where the build can afford it (issue 15; SPEC §4.4 with the cap). After
//! a round, the records the cap turned into [`RecordKind::Scene`] records are gathered again (stages
//! 2-5, as the round computes them) with a larger cap, up to [`LIFT_FACTOR`] times the cap, while a
//! budget of candidate clips lasts ([`Limits::lift_clips`]). A record that fits the larger cap gets
//! its full list, regions and grid, as without a cap; one that does not keeps a scene record (with
//! the umbra of the larger subset). Every answer stays exact either way; only where the scene BVH
//! is walked changes.
//!
//! The budget is spent in a fixed order: the records of leaves holding triangles first (shading asks
//! the records of the leaves its points lie in, and its points lie on triangles; measured against
//! three other orders in docs/results.md), then by leaf, face and light. It goes in batches of up to
//! [`BATCH`] records: each batch's cap is what the budget left at its start can pay for all of them
//! at the most ([`CANDIDATES_PER_BLOCKER`] clips per blocker of the cap; the batch shrinks before the
//! cap does), its records are computed in parallel and committed in order, each paying the
//! candidates it clipped. So the work is bounded by the budget, and the result does not depend on
//! the thread count. Where few records are capped (an open room) nearly all are lifted; where most
//! are (dense clutter before a small light) the budget runs out early and the rest keep the cap.

use std::sync::Mutex;

use super::blockers::{GatherScratch, CANDIDATES_PER_BLOCKER};
use super::propagation::{FaceState, Tolerances};
use super::record::{face_record, FaceOut, PendingRecord};
use super::round::{list_bytes, Round};
use super::{abs_scale, schedule, tolerance, Interrupted, Limits};
use crate::lie::{PlieParams, RecordKind};
use crate::octree::{Dir, LeafId, Octree};
use crate::progress::Progress;
use crate::scene::{LightId, Scene};

/// The lifting budget `plie build`, `render`, `bench` and [`crate::BuildOptions::default`] use: candidate
/// clips per scene triangle ([`crate::BuildOptions::lift_clips`]); chosen by the measurements of issue
/// 15 in docs/results.md.
pub const DEFAULT_LIFT_CLIPS: usize = 16;

/// A lifted cap is at most this many times the blocker cap.
pub const LIFT_FACTOR: u32 = 16;
const _: () = assert!(LIFT_FACTOR == 16, "`plie build --help` and `BuildOptions::lift_clips` say 16 times");

/// Most records computed between two looks at the budget.
pub const BATCH: usize = 64;

/// The clips left in the budget and what lifting did, over all rounds of a construction.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Lift {
    /// Candidate clips left; `None`: no lifting.
    pub(super) clips_left: Option<usize>,
    /// Records gathered again with a lifted cap.
    pub(super) tried: usize,
    /// Of those, the records that fit it: they now hold their full list (or were removed in umbra).
    pub(super) lifted: usize,
}

impl Lift {
    /// A budget of `limits.lift_clips` candidate clips.
    pub(super) fn new(limits: &Limits) -> Lift {
        Lift { clips_left: limits.lift_clips, ..Lift::default() }
    }
}

/// Lifts the cap of `round`'s capped records in that order while `lift`'s budget lasts; the lists'
/// bytes stay within `limits.list_bytes`.
pub(super) fn lift_caps(
    scene: &Scene,
    octree: &Octree,
    params: PlieParams,
    limits: &Limits,
    progress: &dyn Progress,
    round: &mut Round,
    lift: &mut Lift,
) -> Result<(), Interrupted> {
    let (Some(cap), Some(_)) = (params.blocker_cap, lift.clips_left) else { return Ok(()) };
    if cap == 0 {
        // A cap of nothing lifted is still nothing: every record with a blocker stays a scene record.
        return Ok(());
    }
    let lights = scene.lights.len();
    let capped = in_lift_order(round, octree, lights, |r| r.liftable);
    let task = |t: usize| task_of(t, lights);
    if capped.is_empty() {
        return Ok(());
    }
    let tol = tolerance(scene, octree);
    let abs_scale = abs_scale(octree);
    let tols = Tolerances::new(tol, abs_scale);
    let mut used = list_bytes(&round.tasks);
    let scratches = worker_scratches(scene);
    progress.start("lifting the blocker cap", capped.len() as u64);
    let max_cap = cap.saturating_mul(LIFT_FACTOR) as usize;
    let mut next = 0;
    while next < capped.len() {
        // As many records as the budget left pays the whole lifted cap for (at least one), each
        // with the cap the budget pays for all of them.
        let left = lift.clips_left.unwrap_or(0);
        let n = (left / (CANDIDATES_PER_BLOCKER * max_cap)).clamp(1, BATCH).min(capped.len() - next);
        let lifted_cap = max_cap.min(left / (n * CANDIDATES_PER_BLOCKER));
        if lifted_cap <= cap as usize {
            break;
        }
        let batch = &capped[next..next + n];
        next += n;
        if progress.cancelled() {
            progress.finish();
            return Err(Interrupted);
        }
        let p = PlieParams { blocker_cap: Some(lifted_cap as u32), ..params };
        schedule::run_ordered(
            batch.len(),
            |k| {
                let (t, face) = batch[k];
                let worker = rayon::current_thread_index().unwrap_or(0) % scratches.len();
                let mut scratch = scratches[worker].lock().unwrap_or_else(|e| e.into_inner());
                face_record(scene, octree, task(t), face, &tols, abs_scale, p, &mut scratch)
            },
            |k, fo: FaceOut| {
                let (t, face) = batch[k];
                let left = lift.clips_left.get_or_insert(0);
                *left = left.saturating_sub(fo.candidates);
                lift.tried += 1;
                let slot = &mut round.tasks[t];
                slot.candidates += fo.candidates;
                slot.seconds += fo.seconds;
                let fits = |r: &PendingRecord| limits.list_bytes.is_none_or(|l| used + r.list_bytes() <= l);
                match fo.record {
                    // Still over the lifted cap (its umbra from a larger subset), or its lists would
                    // not fit the memory budget: a scene record, not tried again.
                    Some(r) if r.kind == RecordKind::Scene || !fits(&r) => {
                        let old = slot.records[face.index()].as_mut().expect("a capped record");
                        old.liftable = false;
                        if r.kind == RecordKind::Scene {
                            **old = PendingRecord { liftable: false, ..r };
                        }
                    }
                    Some(r) => {
                        used += r.list_bytes();
                        slot.records[face.index()] = Some(Box::new(r));
                        lift.lifted += 1;
                    }
                    // Its full regions show the face in umbra: removed (§4.6), as without the cap.
                    None => {
                        let (leaf, light) = task(t);
                        debug_assert!(matches!(fo.state, FaceState::Dark { .. }));
                        round.states.set(leaf, face, light, fo.state);
                        slot.records[face.index()] = None;
                        slot.removed_umbra += 1;
                        lift.lifted += 1;
                    }
                }
                progress.advance(1);
            },
        );
    }
    progress.finish();
    Ok(())
}

/// The records of `round` that `keep` accepts, as (task, face), in the lift's order: shading asks the
/// records of the leaves its points lie in, so leaves holding triangles first. The sort is stable and
/// tasks are numbered leaf by leaf, so the rest stays in leaf, face, light order. (The cells of
/// [`super::scene_cells`] follow it too.)
pub(super) fn in_lift_order(
    round: &Round,
    octree: &Octree,
    lights: usize,
    keep: impl Fn(&PendingRecord) -> bool,
) -> Vec<(usize, Dir)> {
    let mut out: Vec<(usize, Dir)> = Vec::new();
    for (t, task) in round.tasks.iter().enumerate() {
        for f in Dir::ALL {
            if task.records[f.index()].as_deref().is_some_and(&keep) {
                out.push((t, f));
            }
        }
    }
    out.sort_by_key(|&(t, _)| octree.leaf_triangles(task_of(t, lights).0).is_empty());
    out
}

/// The (leaf, light) of task `t` of a round over `lights` lights.
pub(super) fn task_of(t: usize, lights: usize) -> (LeafId, LightId) {
    (LeafId((t / lights) as u32), LightId((t % lights) as u32))
}

/// One gather scratch per worker thread, for all batches of a pass (each is a stamp per scene
/// triangle).
pub(super) fn worker_scratches(scene: &Scene) -> Vec<Mutex<GatherScratch>> {
    (0..rayon::current_num_threads().max(1)).map(|_| Mutex::new(GatherScratch::new(scene.triangles.len()))).collect()
}
