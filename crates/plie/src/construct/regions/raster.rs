//! The raster that unites the shadow regions of a record's blockers (SPEC §4.5): a 64 x 64 grid
//! of the face, every cell a shadow region meets marked, turned into rectangles for the penumbra.
//! A superset of the union, which is all the "lit" answer needs, far cheaper than exact booleans.

use glam::DVec2;
use i_overlay::i_shape::int::shape::IntShapes;

use super::polygon::square;
use super::project::FALLBACK_RES;
use crate::geometry::clip::clip2;
use crate::lie::frame::UNITS;

/// Cells per side of the raster that unites the shadow regions.
pub(super) const RASTER: usize = 64;

/// The union of the shadow regions as a `RASTER x RASTER` bitmap of face cells, each set when a
/// shadow region meets it: a superset of the union, which is all "lit" needs (a point outside every
/// set cell is outside every shadow region), and far cheaper than exact booleans of thousands of
/// overlapping regions. The outermost cells stand for everything beyond the face's edges too.
#[derive(Default)]
pub(super) struct Raster {
    rows: Vec<u64>,
    set: usize,
}

impl Raster {
    pub(super) fn ensure(&mut self) {
        if self.rows.is_empty() {
            self.rows = vec![0; RASTER];
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.set == 0
    }

    pub(super) fn full(&self) -> bool {
        self.set == RASTER * RASTER
    }

    pub(super) fn mark(&mut self, j: usize, i0: usize, i1: usize) {
        self.ensure();
        let bits = if i1 - i0 + 1 == 64 { u64::MAX } else { ((1u64 << (i1 - i0 + 1)) - 1) << i0 };
        self.set += (bits & !self.rows[j]).count_ones() as usize;
        self.rows[j] |= bits;
    }

    pub(super) fn mark_all(&mut self) {
        for j in 0..RASTER {
            self.mark(j, 0, RASTER - 1);
        }
    }

    /// Marks the cells of fallback-grid cell `(i, j)`.
    pub(super) fn mark_fallback_cell(&mut self, i: u32, j: u32) {
        let k = RASTER / FALLBACK_RES as usize;
        for row in j as usize * k..(j as usize + 1) * k {
            self.mark(row, i as usize * k, (i as usize + 1) * k - 1);
        }
    }

    /// Marks every cell the convex polygon `poly` (units) meets: per row, the polygon clipped to the
    /// row's slab gives the range of columns.
    pub(super) fn mark_polygon(&mut self, poly: &[DVec2], tmp: &mut Vec<DVec2>, row: &mut Vec<DVec2>) {
        let w = UNITS / RASTER as f64;
        let cell = |x: f64| ((x / w).floor().max(0.0) as usize).min(RASTER - 1);
        let (y_lo, y_hi) = poly.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.y), b.max(p.y)));
        if poly.is_empty() {
            return;
        }
        for j in cell(y_lo)..=cell(y_hi) {
            row.clear();
            row.extend_from_slice(poly);
            if j > 0 {
                clip2(row, DVec2::NEG_Y, -(j as f64 * w), tmp);
            }
            if j + 1 < RASTER {
                clip2(row, DVec2::Y, (j + 1) as f64 * w, tmp);
            }
            if row.is_empty() {
                continue;
            }
            let (x_lo, x_hi) =
                row.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.x), b.max(p.x)));
            self.mark(j, cell(x_lo), cell(x_hi));
        }
    }

    /// The set cells as rectangles (runs of each row), the outermost grown by `2 * margin` beyond the
    /// face's edges.
    pub(super) fn rectangles(&self, margin: f64) -> IntShapes<i32> {
        let w = UNITS / RASTER as f64;
        let edge = |k: usize| match k {
            0 => -2.0 * margin,
            RASTER => UNITS + 2.0 * margin,
            _ => k as f64 * w,
        };
        let mut out = Vec::new();
        for (j, &bits) in self.rows.iter().enumerate() {
            let mut i = 0;
            while i < RASTER {
                if bits >> i & 1 == 0 {
                    i += 1;
                    continue;
                }
                let start = i;
                while i < RASTER && bits >> i & 1 == 1 {
                    i += 1;
                }
                out.push(vec![square(DVec2::new(edge(start), edge(j)), DVec2::new(edge(i), edge(j + 1)))]);
            }
        }
        out
    }
}
