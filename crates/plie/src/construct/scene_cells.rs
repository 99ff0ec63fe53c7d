//! Cells of the records over the blocker cap (issue 15; SPEC §8 points 3-4 with the cap). A
//! [`RecordKind::Scene`] record stores no list, so the per-light query could not tell its lit cells
//! from its penumbra: every light whose footprint touched it went to the scene BVH. After the lift
//! ([`super::lift`]), each scene record gets a face grid whose squares of cells, from the face's
//! quarters down to single cells and outside its umbra, gather the blockers of the shaft from the
//! square to the light with a small cap ([`grid::scene_cells`]): a cell under it keeps its full
//! list (empty: fully lit), as a listed record's cell does; one over it is still answered by the
//! scene BVH. Every answer stays exact.
//!
//! The work is bounded by a budget of candidate clips ([`Limits::cell_clips`]), spent as the lift's
//! is: in the lift's order (records of leaves holding triangles first, then leaf, face, light), in
//! batches of at most [`BATCH`] records, each batch with the finest grid (up to [`MAX_RES`] cells a
//! side) that the budget left pays for all of its records at the most; the records are computed in
//! parallel and committed in order, each paying the candidates it clipped. So the result does not
//! depend on the thread count, and the clips spent never pass the budget. [`DRY_RECORDS`] records in
//! a row without a cell under the cap end the pass (dense clutter, where the budget buys nothing). Measured
//! (docs/results.md, issue 15): finer grids recover more of the uncapped shading per clip, and the
//! first few hundred records in that order recover nearly all of it.

use super::lift::{in_lift_order, task_of, worker_scratches, BATCH};
use super::round::{list_bytes, Round};
use super::{grid, tolerance, Interrupted, Limits};
use crate::lie::{PlieParams, RecordKind};
use crate::octree::{Dir, Octree};
use crate::progress::Progress;
use crate::scene::Scene;

/// The cell budget `plie build`, `render`, `bench` and [`crate::BuildOptions::default`] use:
/// candidate clips per scene triangle ([`crate::BuildOptions::cell_clips`]); chosen by the
/// measurements of issue 15 in docs/results.md.
pub const DEFAULT_CELL_CLIPS: usize = 64;

/// Most cells a side of a scene record's grid: each batch takes the finest grid, up to this, that
/// the budget left pays for all of its records at the most ([`grid::scene_cells_clips`]).
pub const MAX_RES: u32 = 32;

/// The pass ends after this many records in a row without a cell under the cap (checked between
/// batches).
pub const DRY_RECORDS: usize = 32;

/// The clips left in the cell budget and what it paid for, over all rounds of a construction.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Cells {
    /// Candidate clips left; `None`: no cells for scene records.
    pub(super) clips_left: Option<usize>,
    /// Scene records whose cells were gathered.
    pub(super) records: usize,
    /// Of their cells, those that hold their full list (the others stay with the scene BVH).
    pub(super) listed: usize,
}

impl Cells {
    /// A budget of `limits.cell_clips` candidate clips.
    pub(super) fn new(limits: &Limits) -> Cells {
        Cells { clips_left: limits.cell_clips, ..Cells::default() }
    }
}

/// Gathers the cells of `round`'s scene records in the lift's order while `cells`' budget lasts; the
/// lists' bytes stay within `limits.list_bytes`.
pub(super) fn gather_scene_cells(
    scene: &Scene,
    octree: &Octree,
    params: PlieParams,
    limits: &Limits,
    progress: &dyn Progress,
    round: &mut Round,
    cells: &mut Cells,
) -> Result<(), Interrupted> {
    if cells.clips_left.is_none() || !params.has_grids() {
        return Ok(());
    }
    let lights = scene.lights.len();
    let todo = in_lift_order(round, octree, lights, |r| {
        r.kind == RecordKind::Scene && r.grid.as_ref().is_none_or(|g| g.cell_list.is_empty())
    });
    let task = |t: usize| task_of(t, lights);
    if todo.is_empty() {
        return Ok(());
    }
    let tol = tolerance(scene, octree);
    let mut used = list_bytes(&round.tasks);
    let scratches = worker_scratches(scene);
    progress.start("cells of the records over the cap", todo.len() as u64);
    let mut next = 0;
    // Records committed since the last one with a cell under the cap.
    let mut dry = 0;
    while next < todo.len() {
        // As many records as the budget left pays the finest grid for (at least one), each with
        // the finest grid the budget pays for all of them.
        let left = cells.clips_left.unwrap_or(0);
        let n = (left / grid::scene_cells_clips(MAX_RES)).clamp(1, BATCH).min(todo.len() - next);
        let Some(res) = (1..=MAX_RES.ilog2()).rev().map(|k| 1 << k).find(|&g| n * grid::scene_cells_clips(g) <= left)
        else {
            break;
        };
        let batch = &todo[next..next + n];
        next += n;
        if progress.cancelled() {
            progress.finish();
            return Err(Interrupted);
        }
        let round_ref = &*round;
        let jobs: Vec<(Vec<bool>, (usize, Dir))> = batch
            .iter()
            .map(|&(t, f)| {
                let r = round_ref.tasks[t].records[f.index()].as_ref().expect("a scene record");
                let umbra = r.regions.as_ref().filter(|x| !x.umbra.is_empty()).map(|x| grid::umbra_cells(res, x));
                (umbra.unwrap_or_default(), (t, f))
            })
            .collect();
        super::schedule::run_ordered(
            jobs.len(),
            |k| {
                let (umbra, (t, face)) = &jobs[k];
                let (leaf, light) = task(*t);
                let worker = rayon::current_thread_index().unwrap_or(0) % scratches.len();
                let mut scratch = scratches[worker].lock().unwrap_or_else(|e| e.into_inner());
                let b = octree.leaf_bounds(leaf);
                let l = &scene.lights[light.idx()];
                grid::scene_cells(scene, octree, (*face, &b), (l, light), tol, res, umbra.clone(), &mut scratch)
            },
            |k, (grid, clipped): (grid::PendingGrid, usize)| {
                let (t, face) = jobs[k].1;
                let left = cells.clips_left.get_or_insert(0);
                *left = left.saturating_sub(clipped);
                let slot = &mut round.tasks[t];
                slot.candidates += clipped;
                let bytes = grid.list_bytes();
                if limits.list_bytes.is_none_or(|l| used + bytes <= l) {
                    used += bytes;
                    cells.records += 1;
                    let umbra = |c: usize| grid.umbra.get(c).copied().unwrap_or(false);
                    let listed =
                        (0..grid.cell_list.len()).filter(|&c| grid.cell_list[c] != grid::SCENE_LIST && !umbra(c));
                    let listed = listed.count();
                    cells.listed += listed;
                    dry = if listed == 0 { dry + 1 } else { 0 };
                    let r = slot.records[face.index()].as_mut().expect("a scene record");
                    r.grid = Some(grid);
                }
                progress.advance(1);
            },
        );
        // The last records all without a cell under the cap: the scene is too dense behind these
        // faces for the cells to pay.
        if dry >= DRY_RECORDS {
            break;
        }
    }
    progress.finish();
    Ok(())
}
