//! The whole light at once (issue 21): the footprints of a light (or part of it) on the faces of the
//! shaded point's leaf ([`super::super::footprint`]), read through summed-area tables of the face
//! grids' cells, decide all its samples at once where they lie in umbra or in lit cells, or gather the
//! short lists of the cells they cover so that the samples are tested against those without looking
//! up their own cells (SPEC §5, our `grid`). Any other light goes to the scene BVH.

use glam::Vec3;

use super::super::fan::LightScratch;
use super::super::footprint::footprints;
use super::super::query::SEGMENT_EPS;
use super::super::{LightRays, Mode};
use super::LieVisibility;
use crate::geometry::Aabb;
use crate::lie::{Cell, Plie, RecordKind};
use crate::octree::LeafId;

/// Summed-area tables of the face grids of `plie` (see the field `sat` of `LieVisibility`).
pub(super) fn grid_tables(plie: &Plie) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut start = Vec::with_capacity(plie.grids.len());
    let mut sat = Vec::new();
    for grid in &plie.grids {
        if grid.res == 0 {
            start.push(u32::MAX);
            continue;
        }
        start.push(sat.len() as u32);
        let g = grid.res as usize;
        let base = sat.len();
        sat.resize(base + (g + 1) * (g + 1), [0, 0, 0]);
        for j in 0..g {
            for i in 0..g {
                let counts = match plie.cell(grid, j * g + i) {
                    Cell::Umbra => [1, 0, 1],
                    Cell::Scene => [1, 1, 1],
                    Cell::Blockers(l) => [u32::from(!l.is_empty()), 1, 0],
                };
                let at = |i: usize, j: usize| base + j * (g + 1) + i;
                let (a, b, c) = (sat[at(i, j + 1)], sat[at(i + 1, j)], sat[at(i, j)]);
                sat[at(i + 1, j + 1)] = std::array::from_fn(|w| a[w] + b[w] - c[w] + counts[w]);
            }
        }
    }
    (start, sat)
}

/// What the footprints of a light on the faces of a point's leaf decide ([`LieVisibility::whole_light`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Whole {
    /// Every sample's ray is occluded: each leaves the leaf through a face without a record or
    /// through umbra cells.
    Umbra,
    /// No blocker list can hit any sample (every footprint lies in lit cells, or on records with
    /// empty lists): only the leaf's own triangles remain to test.
    Lit,
    /// Every footprint lies in cells (or on records without a grid) whose distinct lists hold at
    /// most [`gather_max`] triangles in all, and their keys are gathered: each sample's own list is
    /// one of them, so testing every sample against all of them (and the leaf's own triangles) finds
    /// exactly its blockers.
    Lists,
    /// None of the above: the scene answers.
    Mixed,
}

impl LieVisibility<'_> {
    /// The samples of the light polygon `poly` (the light of `rays` or a part of it) at once, from
    /// its footprints on the faces of `leaf` ([`footprints`]), if they decide them ([`Whole`]); with
    /// `only_umbra`, [`Whole::Umbra`] or [`Whole::Mixed`] only. For [`Whole::Lists`], the keys of
    /// the lists (see [`CELL_KEY`]) are added to `sc.lists`, each distinct list once (other outcomes
    /// may have added some too).
    pub(super) fn whole_light(
        &self,
        leaf: LeafId,
        bounds: &Aabb,
        rays: &LightRays,
        poly: &[Vec3],
        only_umbra: bool,
        sc: &mut LightScratch,
    ) -> Whole {
        // `umbra`: every footprint so far lies in umbra cells or on a face without a record (the
        // samples' rays must also all leave the leaf). With `only_umbra` (a leaf whose lit and
        // listed lights go to the scene BVH anyway), the other two verdicts are not sought: the
        // footprints stop at the first that is not in umbra, and no list is gathered.
        let (mut lit, mut umbra, mut listed) = (!only_umbra, true, self.mode == Mode::Grid && !only_umbra);
        // Triangles in the distinct lists gathered so far, and how many may be.
        let mut gathered = 0;
        let max = gather_max(rays.targets.len());
        // Each footprint as it is found; once none of the verdicts can hold, the rest are not
        // computed.
        let all_exit = footprints(bounds, rays.origin, poly, SEGMENT_EPS, |fp| {
            let Some(ri) = self.plie.record_id(leaf, fp.face, rays.light) else {
                lit = false;
                listed = false;
                return umbra;
            };
            let record = &self.plie.records[ri];
            match self.sat_start.get(ri).copied().filter(|&s| s != u32::MAX) {
                Some(start) => {
                    let g = self.plie.grids[ri].res as usize;
                    let k = fp.face.axis();
                    let (u, v) = crate::lie::frame::face_axes(k);
                    let cell = |x: f64, axis: usize| {
                        let (lo, hi) = (bounds.min[axis] as f64, bounds.max[axis] as f64);
                        (((x - lo) / (hi - lo) * g as f64).max(0.0) as usize).min(g - 1)
                    };
                    let (i0, i1) = (cell(fp.rect[0], u), cell(fp.rect[1], u));
                    let (j0, j1) = (cell(fp.rect[2], v), cell(fp.rect[3], v));
                    // The table's four corners of the cells `[i0, i1] x [j0, j1]`.
                    let row = g + 1;
                    let sat = &self.sat[start as usize..start as usize + row * row];
                    let (first, last) = (&sat[j0 * row..(j0 + 1) * row], &sat[(j1 + 1) * row..(j1 + 2) * row]);
                    let (a, b, c, d) = (first[i0], first[i1 + 1], last[i0], last[i1 + 1]);
                    let count = |w: usize| d[w] + a[w] - c[w] - b[w];
                    lit &= count(0) == 0;
                    umbra &= count(1) == 0;
                    listed &= count(2) == 0;
                    if listed && count(0) > 0 {
                        listed = self.gather_cells(ri, g, (i0, i1), (j0, j1), (&mut gathered, max), sc);
                    }
                }
                None => {
                    let empty = record.kind == RecordKind::Listed && record.blockers_len == 0;
                    lit &= empty;
                    umbra = false;
                    if listed && !empty {
                        gathered += record.blockers_len as usize;
                        listed = record.kind == RecordKind::Listed && gathered <= max;
                        sc.lists.push(ri as u32);
                    }
                }
            }
            lit || umbra || listed
        });
        let Some(all_exit) = all_exit else {
            return Whole::Mixed;
        };
        let umbra = umbra && all_exit;
        if umbra {
            Whole::Umbra
        } else if lit {
            Whole::Lit
        } else if listed {
            Whole::Lists
        } else {
            Whole::Mixed
        }
    }

    /// Adds the distinct non-empty lists of the cells `[i0, i1] x [j0, j1]` of record `ri`'s grid
    /// (`g` cells a side, none of them umbra or scene) to `sc.lists`, and their lengths to
    /// `gathered`; false once that exceeds `max` ([`gather_max`]).
    fn gather_cells(
        &self,
        ri: usize,
        g: usize,
        (i0, i1): (usize, usize),
        (j0, j1): (usize, usize),
        (gathered, max): (&mut usize, usize),
        sc: &mut LightScratch,
    ) -> bool {
        let first = self.plie.grids[ri].cells_start as usize;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let c = first + j * g + i;
                let range = self.plie.cells[c];
                if range.1 == 0 || sc.ranges.contains(&range) {
                    continue;
                }
                *gathered += range.1 as usize;
                if *gathered > max {
                    return false;
                }
                sc.ranges.push(range);
                sc.lists.push(c as u32 | CELL_KEY);
            }
        }
        true
    }
}

/// Most triangles, in all, of the distinct lists the footprints of a light of `samples` samples
/// gather ([`Whole::Lists`]): a quarter of the samples, from 4 to 16; a light over more is answered
/// by the scene BVH. The gathered lists cost a test per triangle and sample, the walk far less per
/// sample, so the fewer the samples the shorter the lists that pay. Measured (callgrind of the query
/// on conference-lit, cornell-dragon-100k, cornell-bunny and huis-c, docs/results.md issue 21
/// session 19), in all four scenes' instructions: at 16 samples 4 needed 1.4% fewer than 16 (8:
/// 1.0%), at 32 samples 8 needed 0.3% fewer than 16, at 64 samples 32 needed 0.03% fewer (but 0.5%
/// more on huis-c) and 48 or 64 more.
/// (Sessions 8 and 13 chose one limit for every sample count: 32, then 16.)
#[inline]
pub(super) fn gather_max(samples: usize) -> usize {
    (samples / 4).clamp(4, 16)
}

/// A blocker list key of a per-light query: a record's index, or a face-grid cell's index with the
/// top bit set.
pub(super) const CELL_KEY: u32 = 1 << 31;
