//! P-LIE construction (SPEC §4), built once for every leaf, face and light, independent of any camera.
//! This file only runs the stages in order; each stage is its own module:
//!
//! 1. [`data_objects`]: which (leaf, face, light) need a record (§4.1, exact condition).
//! 2. [`shaft`]: bounding volume and supporting planes of conv(face ∪ light) (§4.2, §4.3).
//! 3. [`blockers`]: gather candidates from the overlapping leaves, de-duplicate, clip (§4.4).
//! 4. [`grid`]: per record, a face grid of per-cell blocker lists (our addition, SPEC §8).
//!
//! Umbra/penumbra (§4.5), removal (§4.6), propagation (§4.7) and refinement (§4.8) come later.
//! Leaves are processed in parallel with rayon; the result does not depend on the thread count.

pub mod blockers;
pub mod data_objects;
pub mod grid;
pub mod shaft;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::lie::{FaceGrid, Plie, PlieParams, Record, NO_RECORD};
use crate::octree::{Dir, LeafId, Octree};
use crate::render::Progress;
use crate::scene::{LightId, Scene, TriId};
use blockers::{gather_blockers, GatherScratch};
use shaft::Shaft;

/// Relative tolerance of the construction (times the scene size): every test errs toward keeping.
pub const TOLERANCE_REL: f32 = 1e-5;

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
    /// Records with a face grid.
    pub grids: usize,
    /// Grid cells with no blocker at all (fully lit).
    pub grid_cells_lit: usize,
    /// Seconds building the octree.
    pub octree_seconds: f64,
    /// Seconds computing data objects, shafts and blockers.
    pub blockers_seconds: f64,
}

/// One record before flattening: face, light, blockers and the optional face grid.
type PendingRecord = (Dir, LightId, Vec<TriId>, Option<grid::PendingGrid>);
/// The records of one leaf before flattening.
type LeafRecords = Vec<PendingRecord>;

/// Builds the P-LIE of `scene` over `octree` (stages 1-3).
pub fn build(scene: &Scene, octree: &Octree, params: PlieParams, progress: &dyn Progress) -> (Plie, BuildStats) {
    let t0 = Instant::now();
    let tol = scene.scale().max(octree.root_bounds().size().max_element()) * TOLERANCE_REL;
    let lights = scene.lights.len();
    progress.start("blockers", octree.leaf_count() as u64);
    let per_leaf: Vec<(LeafRecords, usize)> = (0..octree.leaf_count() as u32)
        .into_par_iter()
        .map_init(
            || GatherScratch::new(scene.triangles.len()),
            |scratch, l| {
                let r = leaf_records(scene, octree, LeafId(l), tol, params.grids, scratch);
                progress.advance(1);
                r
            },
        )
        .collect();
    progress.finish();

    let mut stats = BuildStats {
        leaves: octree.leaf_count(),
        faces_considered: octree.leaf_count() * 6 * lights,
        ..Default::default()
    };
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
    };
    for (l, (records, candidates)) in per_leaf.into_iter().enumerate() {
        stats.candidates_clipped += candidates;
        for (face, light, blockers, grid) in records {
            let mut fg = FaceGrid::default();
            if let Some(pg) = grid {
                fg = FaceGrid { res: pg.g, cells_start: plie.cells.len() as u32 };
                stats.grids += 1;
                let mut ranges = Vec::with_capacity(pg.lists.len());
                for l in pg.lists {
                    ranges.push((plie.cell_blockers.len() as u32, l.len() as u32));
                    plie.cell_blockers.extend(l);
                }
                for c in pg.cell_list {
                    let r = ranges[c as usize];
                    stats.grid_cells_lit += (r.1 == 0) as usize;
                    plie.cells.push(r);
                }
            }
            plie.grids.push(fg);
            let i = plie.slot(LeafId(l as u32), face, light);
            plie.record_index[i] = plie.records.len() as u32;
            plie.records.push(Record {
                leaf: LeafId(l as u32),
                face,
                light,
                blockers_start: plie.blockers.len() as u32,
                blockers_len: blockers.len() as u32,
            });
            plie.blockers.extend(blockers);
        }
    }
    stats.records = plie.records.len();
    stats.no_record_face_cannot_see_light = stats.faces_considered - stats.records;
    stats.blockers_total = plie.blockers.len();
    (stats.blockers_mean, stats.blockers_max) = plie.blocker_stats();
    stats.blockers_seconds = t0.elapsed().as_secs_f64();
    (plie, stats)
}

/// Stages 1-3 for one leaf: every face and light.
fn leaf_records(
    scene: &Scene,
    octree: &Octree,
    leaf: LeafId,
    tol: f32,
    grids: bool,
    scratch: &mut GatherScratch,
) -> (LeafRecords, usize) {
    let b = octree.leaf_bounds(leaf);
    let mut out = Vec::new();
    let mut candidates = 0;
    for face in Dir::ALL {
        let corners = face.face_corners(&b);
        for (li, light) in scene.lights.iter().enumerate() {
            if !data_objects::face_sees_light(&corners, face.normal(), light, tol) {
                continue;
            }
            let shaft = Shaft::new(&corners, &light.vertices, tol);
            let mut blockers = Vec::new();
            candidates += gather_blockers(scene, octree, &shaft, LightId(li as u32), scratch, &mut blockers);
            let grid = if grids { grid::face_grid(scene, face, &b, light, &blockers, tol) } else { None };
            out.push((face, LightId(li as u32), blockers, grid));
        }
    }
    (out, candidates)
}
