//! P-LIE construction (SPEC §4), built once for every leaf, face and light, independent of any camera.
//! This file only runs the stages in order; each stage is its own module:
//!
//! 1. [`data_objects`]: which (leaf, face, light) need a record (§4.1, exact condition).
//! 2. [`shaft`]: bounding volume and supporting planes of conv(face ∪ light) (§4.2, §4.3).
//! 3. [`blockers`]: gather candidates from the overlapping leaves, de-duplicate, clip (§4.4).
//! 4. [`regions`]: umbra and penumbra on the face (§4.5); a record fully in umbra is removed (§4.6).
//! 5. [`grid`]: per record, a face grid of per-cell blocker lists with its umbra cells marked (our
//!    addition, SPEC §8 points 2-4).
//!
//! Propagation (§4.7) and refinement (§4.8) come later.
//! Leaves are processed in parallel with rayon; the result does not depend on the thread count.

pub mod blockers;
pub mod data_objects;
pub mod grid;
pub mod regions;
pub mod shaft;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::lie::{FaceGrid, Plie, PlieParams, Record, RecordRegions, NO_RECORD, UMBRA_CELL};
use crate::octree::{Dir, LeafId, Octree};
use crate::render::Progress;
use crate::scene::{LightId, Scene, TriId};
use blockers::{gather_blockers, GatherScratch};
use shaft::Shaft;

/// Relative tolerance of the construction (times the scene size): every test errs toward keeping.
pub const TOLERANCE_REL: f32 = 1e-5;

/// The absolute tolerance of the construction for `scene` over `octree`: [`TOLERANCE_REL`] times the
/// larger of the scene's size and the octree's root cube. Every test that must agree with the builder
/// (e.g. `plie inspect` telling a removed record from a face that cannot see the light) uses this.
pub fn tolerance(scene: &Scene, octree: &Octree) -> f32 {
    scene.scale().max(octree.root_bounds().size().max_element()) * TOLERANCE_REL
}

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
    /// Records with a face grid.
    pub grids: usize,
    /// Grid cells with no blocker at all (fully lit).
    pub grid_cells_lit: usize,
    /// Grid cells fully in umbra.
    pub grid_cells_umbra: usize,
    /// Grid cells in all.
    pub grid_cells: usize,
    /// Seconds building the octree.
    pub octree_seconds: f64,
    /// Seconds computing data objects, shafts, blockers, regions and grids.
    pub blockers_seconds: f64,
}

/// One record before flattening.
struct PendingRecord {
    face: Dir,
    light: LightId,
    blockers: Vec<TriId>,
    regions: Option<regions::FaceRegions>,
    grid: Option<grid::PendingGrid>,
}

/// The records of one leaf before flattening, and its counters.
#[derive(Default)]
struct LeafRecords {
    records: Vec<PendingRecord>,
    candidates: usize,
    removed_umbra: usize,
}

/// Builds the P-LIE of `scene` over `octree` (stages 1-3).
pub fn build(scene: &Scene, octree: &Octree, params: PlieParams, progress: &dyn Progress) -> (Plie, BuildStats) {
    let t0 = Instant::now();
    let tol = tolerance(scene, octree);
    let lights = scene.lights.len();
    progress.start("blockers", octree.leaf_count() as u64);
    let abs_scale = octree.root_bounds().min.abs().max(octree.root_bounds().max.abs()).max_element();
    let per_leaf: Vec<LeafRecords> = (0..octree.leaf_count() as u32)
        .into_par_iter()
        .map_init(
            || GatherScratch::new(scene.triangles.len()),
            |scratch, l| {
                let r = leaf_records(scene, octree, LeafId(l), tol, abs_scale, params, scratch);
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
        regions: Vec::new(),
        region_tris: Vec::new(),
    };
    let (mut umbra_sum, mut penumbra_sum) = (0.0, 0.0);
    for (l, leaf) in per_leaf.into_iter().enumerate() {
        stats.candidates_clipped += leaf.candidates;
        stats.records_removed_umbra += leaf.removed_umbra;
        for rec in leaf.records {
            let fg = flatten_grid(rec.grid, &mut plie, &mut stats);
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
            let i = plie.slot(LeafId(l as u32), rec.face, rec.light);
            plie.record_index[i] = plie.records.len() as u32;
            plie.records.push(Record {
                leaf: LeafId(l as u32),
                face: rec.face,
                light: rec.light,
                blockers_start: plie.blockers.len() as u32,
                blockers_len: rec.blockers.len() as u32,
            });
            plie.blockers.extend(rec.blockers);
        }
    }
    stats.records = plie.records.len();
    stats.no_record_face_cannot_see_light = stats.faces_considered - stats.records - stats.records_removed_umbra;
    stats.region_triangles = plie.region_tris.len();
    stats.region_bytes = plie.region_tris.len() * std::mem::size_of::<regions::Tri2>()
        + plie.regions.len() * std::mem::size_of::<RecordRegions>();
    if params.regions && stats.records > 0 {
        stats.umbra_fraction_mean = umbra_sum / stats.records as f64;
        stats.penumbra_fraction_mean = penumbra_sum / stats.records as f64;
    }
    stats.blockers_total = plie.blockers.len();
    (stats.blockers_mean, stats.blockers_max) = plie.blocker_stats();
    stats.blockers_seconds = t0.elapsed().as_secs_f64();
    (plie, stats)
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
    for (i, c) in pg.cell_list.into_iter().enumerate() {
        stats.grid_cells += 1;
        if pg.umbra.get(i).copied().unwrap_or(false) {
            stats.grid_cells_umbra += 1;
            plie.cells.push(UMBRA_CELL);
        } else {
            let r = ranges[c as usize];
            stats.grid_cells_lit += (r.1 == 0) as usize;
            plie.cells.push(r);
        }
    }
    fg
}

/// Every stage for one leaf: every face and light.
fn leaf_records(
    scene: &Scene,
    octree: &Octree,
    leaf: LeafId,
    tol: f32,
    abs_scale: f32,
    params: PlieParams,
    scratch: &mut GatherScratch,
) -> LeafRecords {
    let b = octree.leaf_bounds(leaf);
    let mut out = LeafRecords::default();
    for face in Dir::ALL {
        let corners = face.face_corners(&b);
        for (li, light) in scene.lights.iter().enumerate() {
            if !data_objects::face_sees_light(&corners, face.normal(), light, tol) {
                continue;
            }
            let shaft = Shaft::new(&corners, &light.vertices, tol);
            let mut blockers = Vec::new();
            let light_id = LightId(li as u32);
            out.candidates += gather_blockers(scene, octree, &shaft, light_id, scratch, &mut blockers);
            let regions = params
                .regions
                .then(|| regions::face_regions(scene, face, &b, light, &blockers, &shaft, tol, abs_scale));
            if regions.as_ref().is_some_and(|r| r.full_umbra) {
                out.removed_umbra += 1;
                continue;
            }
            let has_umbra = regions.as_ref().is_some_and(|r| !r.umbra.is_empty());
            let mut grid = if params.grids {
                let min_res = if has_umbra { grid::UMBRA_MIN_RES } else { 0 };
                grid::face_grid(scene, face, &b, light, &blockers, tol, min_res)
            } else {
                None
            };
            if let (Some(g), Some(reg)) = (grid.as_mut(), regions.as_ref().filter(|_| has_umbra)) {
                g.umbra = grid::umbra_cells(g.g, reg);
            }
            out.records.push(PendingRecord { face, light: light_id, blockers, regions, grid });
        }
    }
    out
}
