//! Face grids (SPEC §8 points 3-4, our improvement over the thesis; part of issue 4's `grid`): a
//! record's face is split into `g x g` cells, and each cell keeps only the blockers that meet the shaft
//! from that cell to the light. A shadow ray looks up the cell where it crosses the face in O(1) and
//! tests that list; an empty list means the cell is fully lit from the light (no blocker at all).
//!
//! Each cell's list is found exactly as a record's list is (SPEC §4.4): the supporting planes of
//! conv(cell ∪ light), moved outward by the tolerance, clip the record's blockers. Because of that
//! tolerance, a crossing point computed with rounding error near a cell border is still covered by the
//! cell it is assigned to. Cells inside the record's umbra (SPEC §4.5, [`super::regions`]) are
//! marked by the construction afterwards: a ray crossing there is blocked without a test.

use glam::DVec2;

use super::blockers::{gather_blockers, GatherScratch, CANDIDATES_PER_BLOCKER};
use super::regions::FaceRegions;
use super::shaft::Shaft;
use crate::geometry::Aabb;
use crate::lie::frame::UNITS;
pub use crate::lie::grid::{cell_box, cell_of};
use crate::octree::{Dir, Octree};
use crate::scene::{Light, LightId, Scene, TriId};

/// Records with fewer blockers than this keep no grid: their list is short already (unless they have
/// umbra to classify).
pub const MIN_BLOCKERS: usize = 8;

/// Fewest cells per side of the grid of a record with umbra.
pub const UMBRA_MIN_RES: u32 = 4;

/// Cells per side for a record with `n` blockers: a power of two near `sqrt(n) / 2`, from `min` (a
/// power of two) to 8.
pub fn resolution(n: usize, min: u32) -> u32 {
    let want = ((n as f64).sqrt() / 2.0).ceil().clamp(min as f64, 8.0) as u32;
    want.next_power_of_two().min(8)
}

/// A record's face grid before flattening: the distinct lists, and for each cell (`(i, j)` at
/// `j * g + i`) the index of its list. Cells of a square whose list barely shrinks share one list.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PendingGrid {
    /// Cells per side.
    pub g: u32,
    /// The distinct blocker lists.
    pub lists: Vec<Vec<TriId>>,
    /// List index of each cell.
    pub cell_list: Vec<u32>,
    /// Cells fully in umbra (empty until the regions have classified them).
    pub umbra: Vec<bool>,
    /// The grid of a [`crate::lie::RecordKind::Scene`] record: the cells not in umbra whose list
    /// is [`SCENE_LIST`] (all of them when `cell_list` is empty) are answered by the scene BVH.
    pub scene: bool,
}

impl PendingGrid {
    /// Bytes its distinct lists will take in the P-LIE.
    pub fn list_bytes(&self) -> usize {
        self.lists.iter().map(Vec::len).sum::<usize>() * std::mem::size_of::<TriId>()
    }
}

/// `cell_list` entry of a cell of a scene record's grid whose own gather passed its cap: the scene
/// BVH answers rays through it.
pub const SCENE_LIST: u32 = u32::MAX;

/// Most blockers of a square of cells of a [`crate::lie::RecordKind::Scene`] record's grid for it to
/// keep its list ([`scene_cells`]).
pub const SCENE_CELL_CAP: usize = 16;

/// Most candidate clips [`scene_cells`] spends on a grid of `g x g` cells (`g` a power of two, at
/// least 2): at most `(4 g^2 - 4) / 3` squares gather ([`CANDIDATES_PER_BLOCKER`] clips per blocker of
/// [`SCENE_CELL_CAP`] each) and at most as many filter a list of at most [`SCENE_CELL_CAP`].
pub const fn scene_cells_clips(g: u32) -> usize {
    let squares = (4 * (g as usize) * (g as usize) - 4) / 3;
    squares * (CANDIDATES_PER_BLOCKER * SCENE_CELL_CAP + SCENE_CELL_CAP)
}

/// The cells of a [`crate::lie::RecordKind::Scene`] record's `g x g` grid (issue 15; `g` a power of
/// two, at least 2), as a quadtree from the face's four quarters down: a square of cells not all in
/// the umbra (`umbra`, empty for none) gathers the blockers of the shaft from it to the light
/// ([`gather_blockers`], as the record's own gather does) with a cap of [`SCENE_CELL_CAP`]. Under the
/// cap, its cells get their lists from that one as a listed record's grid does ([`face_grid`]'s
/// filtering); over it, its quarters try in turn, and a single cell over it is left to the scene
/// BVH ([`SCENE_LIST`]). Every list is a cell's full list, so every answer stays exact. Returns the
/// grid and the candidates clipped (gathered and filtered), at most [`scene_cells_clips`].
#[allow(clippy::too_many_arguments)]
pub fn scene_cells(
    scene: &Scene,
    octree: &Octree,
    (face, cell): (Dir, &Aabb),
    (light, light_id): (&Light, LightId),
    tol: f32,
    g: u32,
    umbra: Vec<bool>,
    scratch: &mut GatherScratch,
) -> (PendingGrid, usize) {
    debug_assert!(g >= 2 && g.is_power_of_two());
    let mut out =
        PendingGrid { g, lists: Vec::new(), cell_list: vec![SCENE_LIST; (g * g) as usize], umbra, scene: true };
    let quad = Quad { scene, face, cell, light, tol, g, clipped: std::cell::Cell::new(0) };
    let mut gathered = 0;
    let mut list = Vec::new();
    let mut todo = vec![(0, 0, g / 2), (g / 2, 0, g / 2), (0, g / 2, g / 2), (g / 2, g / 2, g / 2)];
    while let Some((i, j, size)) = todo.pop() {
        let in_umbra = |c: u32, r: u32| out.umbra.get((r * g + c) as usize).copied().unwrap_or(false);
        if (j..j + size).all(|r| (i..i + size).all(|c| in_umbra(c, r))) {
            continue;
        }
        let corners = face.face_corners(&quad.square(i, j, size));
        let shaft = Shaft::new(&corners, &light.vertices, tol);
        list.clear();
        let got = gather_blockers(scene, octree, &shaft, light_id, Some(SCENE_CELL_CAP), scratch, &mut list);
        gathered += got.candidates;
        if !got.capped {
            if size == 1 {
                quad.share(i, j, 1, list.clone(), &mut out);
            } else {
                quad.split(i, j, size, &list, &mut out);
            }
        } else if size > 1 {
            let h = size / 2;
            todo.extend([(i, j, h), (i + h, j, h), (i, j + h, h), (i + h, j + h, h)]);
        }
    }
    (out, gathered + quad.clipped.get())
}

/// A square is split into four only if the four lists together hold at most this many times the
/// square's own list; otherwise its cells share its list. This skips splits that would barely
/// shorten the lists and bounds a grid's memory at `SPLIT_GROWTH^levels` times the record's list.
/// Measured (docs/results.md): 2.5 keeps most of the culling of unlimited splitting while the cell
/// lists of cornell-bunny.obj hold 1.5x the record lists (4.0: 35x).
const SPLIT_GROWTH: f64 = 2.5;

/// The grid of one record with at least `min_res` cells per side, or `None` when `min_res` is 0 and
/// the record has too few blockers to need one.
pub fn face_grid(
    scene: &Scene,
    face: Dir,
    cell: &Aabb,
    light: &Light,
    blockers: &[TriId],
    tol: f32,
    min_res: u32,
) -> Option<PendingGrid> {
    if blockers.len() < MIN_BLOCKERS && min_res == 0 {
        return None;
    }
    let g = resolution(blockers.len(), min_res.max(2));
    let mut out = PendingGrid {
        g,
        lists: Vec::new(),
        cell_list: vec![u32::MAX; (g * g) as usize],
        umbra: Vec::new(),
        scene: false,
    };
    let quad = Quad { scene, face, cell, light, tol, g, clipped: std::cell::Cell::new(0) };
    quad.split(0, 0, g, blockers, &mut out);
    debug_assert!(out.cell_list.iter().all(|&c| (c as usize) < out.lists.len()));
    Some(out)
}

/// The quadtree walk that fills a grid: each square of cells filters its parent's list, so deep
/// cells clip only the few blockers that reached them.
struct Quad<'a> {
    scene: &'a Scene,
    face: Dir,
    cell: &'a Aabb,
    light: &'a Light,
    tol: f32,
    g: u32,
    /// Blockers filtered so far (each one clip).
    clipped: std::cell::Cell<usize>,
}

impl Quad<'_> {
    /// The face rectangle of the square of `size` cells at `(i, j)`.
    fn square(&self, i: u32, j: u32, size: u32) -> Aabb {
        let lo = cell_box(self.face, self.cell, self.g, i, j);
        let hi = cell_box(self.face, self.cell, self.g, i + size - 1, j + size - 1);
        lo.union(hi)
    }

    /// The blockers of `parent` that meet the shaft from the square of `size` cells at `(i, j)`.
    fn filter(&self, i: u32, j: u32, size: u32, parent: &[TriId]) -> Vec<TriId> {
        let corners = self.face.face_corners(&self.square(i, j, size));
        let shaft = Shaft::new(&corners, &self.light.vertices, self.tol);
        self.clipped.set(self.clipped.get() + parent.len());
        parent
            .iter()
            .copied()
            .filter(|t| {
                let tri = &self.scene.triangles[t.idx()];
                shaft.bounds.overlaps(&tri.aabb()) && shaft.clips_triangle(&tri.v)
            })
            .collect()
    }

    /// The square of `size` cells at `(i, j)` with blocker list `list`: split into four quarters
    /// (recursing down to single cells) when that pays (see [`SPLIT_GROWTH`]), else one shared list.
    fn split(&self, i: u32, j: u32, size: u32, list: &[TriId], out: &mut PendingGrid) {
        let half = size / 2;
        let quarters = [(0, 0), (half, 0), (0, half), (half, half)];
        let subs: Vec<Vec<TriId>> = quarters.iter().map(|&(di, dj)| self.filter(i + di, j + dj, half, list)).collect();
        if subs.iter().map(Vec::len).sum::<usize>() as f64 > SPLIT_GROWTH * list.len() as f64 {
            self.share(i, j, size, list.to_vec(), out);
            return;
        }
        for (&(di, dj), sub) in quarters.iter().zip(subs) {
            if half > 1 && !sub.is_empty() {
                self.split(i + di, j + dj, half, &sub, out);
            } else {
                self.share(i + di, j + dj, half, sub, out);
            }
        }
    }

    /// Gives every cell of the square of `size` cells at `(i, j)` the one list `list`.
    fn share(&self, i: u32, j: u32, size: u32, list: Vec<TriId>, out: &mut PendingGrid) {
        let id = out.lists.len() as u32;
        out.lists.push(list);
        for cj in j..j + size {
            for ci in i..i + size {
                out.cell_list[(cj * self.g + ci) as usize] = id;
            }
        }
    }
}

/// Which cells of a `g x g` grid lie fully in the umbra of `regions`.
pub fn umbra_cells(g: u32, regions: &FaceRegions) -> Vec<bool> {
    let w = UNITS / g as f64;
    let mut out = Vec::with_capacity((g * g) as usize);
    for j in 0..g {
        for i in 0..g {
            let lo = DVec2::new(i as f64 * w, j as f64 * w);
            out.push(regions.square_in_umbra(lo, lo + w));
        }
    }
    out
}
