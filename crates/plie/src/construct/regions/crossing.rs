//! The crossing test (SPEC §4.5): umbra that no single blocker casts but a set of blockers does,
//! found square by square on the face (a blocker crossing a square's whole sub-shaft blocks it).

use glam::{DVec2, DVec3};
use i_overlay::i_shape::int::shape::IntContour;

use super::polygon::square;
use super::project::Shadow;
use super::project::FALLBACK_RES;
use super::{Setup, CORE_EXTRA, MIN_COS};
use crate::construct::shaft::Shaft;
use crate::geometry::Aabb;

/// True if the convex counter-clockwise polygon contains the square `[lo, hi]²`.
pub(super) fn contains_square(poly: &[DVec2], lo: f64, hi: f64) -> bool {
    let m = poly.len();
    m >= 3
        && [DVec2::splat(lo), DVec2::new(hi, lo), DVec2::splat(hi), DVec2::new(lo, hi)]
            .iter()
            .all(|&c| (0..m).all(|i| (poly[(i + 1) % m] - poly[i]).perp_dot(c - poly[i]) >= 0.0))
}

impl Setup<'_> {
    /// A blocker's shadow as the squares (grown by the margin) of the fallback grid's cells whose
    /// sub-shafts, conv(cell ∪ light) grown by the tolerance, it meets: a ray crossing the face in
    /// another cell lies in that cell's sub-shaft and cannot meet the blocker.
    pub(super) fn cells_shadow(&self, tri: &[DVec3; 3]) -> Shadow {
        let cells = self.cell_shafts.get_or_init(|| {
            let g = FALLBACK_RES;
            let mut out = Vec::with_capacity((g * g) as usize);
            for j in 0..g {
                for i in 0..g {
                    let b = crate::construct::grid::cell_box(self.face, self.cell, g, i, j);
                    let shaft = Shaft::new(&self.face.face_corners(&b), self.light_pts, self.tol);
                    out.push((shaft, (i, j)));
                }
            }
            out
        });
        let t = tri.map(|p| p.as_vec3());
        let bounds = Aabb::from_points(t.iter());
        let hit: Vec<(u32, u32)> = cells
            .iter()
            .filter(|(sh, _)| sh.bounds.overlaps(&bounds) && sh.clips_triangle(&t))
            .map(|&(_, ij)| ij)
            .collect();
        if hit.len() == cells.len() {
            Shadow::Whole
        } else if hit.is_empty() {
            Shadow::None
        } else {
            Shadow::Cells(hit)
        }
    }
}

/// Depth of the quadtree of face squares tried by the crossing test.
pub(super) const CROSSING_DEPTH: u32 = 3;

impl Setup<'_> {
    /// Adds to the umbra (and its core) the squares of the face, from the whole face down to
    /// `CROSSING_DEPTH` levels of quarters, that one blocker polygon certifies by
    /// [`Setup::crossing_blocks`].
    pub(super) fn crossing_squares(
        &self,
        polys: &[Flat],
        lo: DVec2,
        size: f64,
        depth: u32,
        umbra: &mut Vec<IntContour<i32>>,
        core: &mut Vec<IntContour<i32>>,
    ) {
        let grown = [lo, lo + DVec2::new(size, 0.0), lo + size, lo + DVec2::new(0.0, size)];
        // Certify the square grown by twice the margin; add it grown by one margin.
        let m = DVec2::splat(2.0 * self.margin);
        let corners = [grown[0] - m, grown[1] + DVec2::new(m.x, -m.y), grown[2] + m, grown[3] + DVec2::new(-m.x, m.y)]
            .map(|c| self.frame.point(c));
        if polys.iter().any(|p| self.crossing_blocks(p, &corners)) {
            umbra.push(square(lo - self.margin, lo + size + self.margin));
            let c = self.margin - CORE_EXTRA;
            core.push(square(lo - c, lo + size + c));
            return;
        }
        if depth < CROSSING_DEPTH {
            let h = size / 2.0;
            for d in [DVec2::ZERO, DVec2::new(h, 0.0), DVec2::new(0.0, h), DVec2::splat(h)] {
                self.crossing_squares(polys, lo + d, h, depth + 1, umbra, core);
            }
        }
    }

    /// A flat convex blocker prepared for [`Setup::crossing_blocks`]: `None` if degenerate or if the
    /// light is not entirely at least `guard` in front of its plane.
    pub(super) fn flat(&self, poly: Vec<DVec3>) -> Option<Flat> {
        let mut n = (poly[1] - poly[0]).cross(poly[2] - poly[0]).try_normalize()?;
        let o = poly[0];
        if n.dot(self.light[0].0 - o) < 0.0 {
            n = -n;
        }
        if self.light.iter().any(|&(v, _)| n.dot(v - o) < self.guard) {
            return None;
        }
        let k = poly.len();
        let centre = poly.iter().copied().sum::<DVec3>() / k as f64;
        let edges = (0..k)
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % k]);
                let mut e = n.cross(b - a).normalize();
                if e.dot(centre - a) < 0.0 {
                    e = -e;
                }
                (e, e.dot(a))
            })
            .collect();
        Some(Flat { n, o, edges })
    }

    /// True if every segment from the face square with corners `sq` to the light crosses the flat
    /// convex blocker `f` well inside it: square and light lie on opposite sides of its plane, at
    /// least `guard` away, and the crossings of the segments between their corners (whose convex
    /// hull holds every crossing) lie in the blocker shrunk by `r / cos + r`.
    pub(super) fn crossing_blocks(&self, f: &Flat, sq: &[DVec3; 4]) -> bool {
        let d = |p: DVec3| f.n.dot(p - f.o);
        if sq.iter().any(|&c| d(c) > -self.guard) {
            return false;
        }
        let crossing = |c: DVec3, v: DVec3| c + (v - c) * (d(c) / (d(c) - d(v)));
        let inside = |g: DVec3, inset: f64| f.edges.iter().all(|&(e, ea)| e.dot(g) - ea >= inset);
        // Cheap rejection first: one crossing, no inset.
        if !inside(crossing(sq[0], self.light[0].0), 0.0) {
            return false;
        }
        let mut cos = f64::INFINITY;
        for &(v, _) in &self.light {
            for &c in sq {
                cos = cos.min(f.n.dot((v - c).normalize()));
            }
        }
        if cos < MIN_COS {
            return false;
        }
        let inset = self.r / cos + self.r;
        self.light.iter().all(|&(v, _)| sq.iter().all(|&c| inside(crossing(c, v), inset)))
    }
}

/// A flat convex blocker: plane normal `n` (toward the light) through `o`, and per edge the inward
/// in-plane normal `e` with `e . a` for a point `a` of the edge.
pub(super) struct Flat {
    n: DVec3,
    o: DVec3,
    edges: Vec<(DVec3, f64)>,
}
