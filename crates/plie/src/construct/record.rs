//! Stages 2-5 for one (leaf, face, light) (SPEC §4.2-§4.5, §4.6 removal): its shaft, its blockers,
//! its umbra and penumbra and its face grid, as a record not yet flattened into the P-LIE.

use std::time::Instant;

use super::blockers::{gather_blockers, GatherScratch};
use super::propagation::{self, FaceState, Tolerances};
use super::shaft::Shaft;
use super::{grid, regions};
use crate::lie::{PlieParams, RecordKind};
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{LightId, Scene, TriId};

/// One record before flattening.
pub(super) struct PendingRecord {
    pub(super) blockers: Vec<TriId>,
    pub(super) regions: Option<regions::FaceRegions>,
    pub(super) grid: Option<grid::PendingGrid>,
    pub(super) kind: RecordKind,
    /// A scene record because its gather passed the blocker cap: [`super::lift`] may gather it again
    /// with a larger cap.
    pub(super) liftable: bool,
}

impl PendingRecord {
    /// A [`RecordKind::Scene`] record: no list and no penumbra; its umbra (from a subset of the
    /// blockers) is kept, with a grid of umbra cells when there is some umbra and grids are on.
    pub(super) fn scene(regions: Option<regions::FaceRegions>, grids: bool) -> PendingRecord {
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
        PendingRecord { blockers: Vec::new(), regions, grid, kind: RecordKind::Scene, liftable: false }
    }

    /// Bytes its blocker lists (record and grid cells) will take in the P-LIE.
    pub(super) fn list_bytes(&self) -> usize {
        self.blockers.len() * std::mem::size_of::<TriId>() + self.grid.as_ref().map_or(0, grid::PendingGrid::list_bytes)
    }

    /// Turns a listed record into a [`RecordKind::Scene`] one (over the memory budget).
    pub(super) fn into_scene(self, grids: bool) -> PendingRecord {
        PendingRecord::scene(self.regions, grids)
    }
}

/// What stages 2-5 made of one (leaf, face, light).
pub(super) struct FaceOut {
    pub(super) record: Option<PendingRecord>,
    pub(super) state: FaceState,
    pub(super) candidates: usize,
    pub(super) seconds: f64,
}

/// Stages 2-5 for one (leaf, face, light) that is still `Pending`.
#[allow(clippy::too_many_arguments)]
pub(super) fn face_record(
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
    // Capped: `blockers` is a subset, whose umbra is a subset of the true umbra (still sound); only
    // what can fill a cell of the record's grid (or the face) is computed, its penumbra not at all.
    let regions = params.has_regions().then(|| {
        if gathered.capped {
            let cell = crate::lie::frame::UNITS / grid::UMBRA_MIN_RES as f64;
            regions::face_umbra_cover(scene, face, &b, light, &blockers, &shaft, (tol, abs_scale), cell)
        } else {
            regions::face_regions(scene, face, &b, light, &blockers, &shaft, tol, abs_scale)
        }
    });
    let (record, state) = if let Some(reg) = regions.as_ref().filter(|r| r.full_umbra) {
        (None, FaceState::Dark { budget: propagation::dark_budget(face, &b, light, reg, tols) })
    } else if gathered.capped {
        (Some(PendingRecord { liftable: true, ..PendingRecord::scene(regions, params.has_grids()) }), FaceState::Kept)
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
                crate::lie::order::sort_spatially(scene, list);
            }
        }
        (Some(PendingRecord { blockers, regions, grid, kind: RecordKind::Listed, liftable: false }), FaceState::Kept)
    };
    let candidates = gathered.candidates;
    FaceOut { record, state, candidates, seconds: t0.elapsed().as_secs_f64() }
}
