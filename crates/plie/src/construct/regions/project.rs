//! One blocker's umbra and shadow region on the face (SPEC §4.5): the blocker shrunk and cut to the
//! slab the ray's range allows, projected from each light vertex and intersected (umbra); its
//! projections' hull, dilated by the error bound (shadow region), or the fallback grid's cells.

use glam::{DVec2, DVec3};
use i_overlay::i_shape::int::shape::IntContour;

use super::crossing::contains_square;
use super::polygon::{snap, square_f};
use super::{Scratch, Setup, CORE_EXTRA, MIN_COS};
use crate::geometry::clip::{clip2, clip3, hull2, signed_area2};
use crate::lie::frame::UNITS;

/// One blocker's umbra, its core, and the height range of the blocker part casting it.
pub(super) type Umbra = (IntContour<i32>, Option<IntContour<i32>>, (f64, f64));

/// A blocker's shadow region.
pub(super) enum Shadow {
    /// The blocker lies outside the shaft.
    None,
    /// Projections are unbounded: the whole face.
    Whole,
    /// A convex polygon (units), left in the scratch buffer `a`.
    Polygon,
    /// The fallback grid's cells whose sub-shafts the blocker meets (when projections from the
    /// light's vertices do not bound it).
    Cells(Vec<(u32, u32)>),
}

/// Cells per side of the grid used when a blocker's shadow cannot be bounded by projections.
pub(super) const FALLBACK_RES: u32 = 8;

impl Setup<'_> {
    /// The umbra of one blocker and its core (both eroded, snapped, counter-clockwise), if any, with
    /// the lowest and highest height of the part of the blocker that casts it.
    pub(super) fn umbra_of(&self, tri: &[DVec3], s: &mut Scratch) -> Option<Umbra> {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).try_normalize()?;
        if self.min_h <= 2.0 * self.guard {
            return None;
        }
        s.poly.clear();
        s.poly.extend_from_slice(tri);
        let (na, da) = self.frame.above(self.guard);
        clip3(&mut s.poly, na, da, &mut s.tmp3);
        let (nb, db) = self.frame.below(self.min_h - self.guard);
        clip3(&mut s.poly, nb, db, &mut s.tmp3);
        // Every direction from the blocker to the light (the convex hull of vertex differences) must
        // cross the blocker's plane at a cosine of at least MIN_COS.
        let mut cos = f64::INFINITY;
        let mut sign = 0.0;
        for &(v, _) in &self.light {
            for p in &s.poly {
                let dot = n.dot((v - *p).normalize_or_zero());
                if sign == 0.0 {
                    sign = dot.signum();
                }
                if dot * sign <= 0.0 {
                    return None;
                }
                cos = cos.min(dot.abs());
            }
        }
        if cos < MIN_COS {
            return None;
        }
        let inset = self.r / cos + self.r;
        let k = tri.len();
        for i in 0..k {
            let (a, b, c) = (tri[i], tri[(i + 1) % k], tri[(i + 2) % k]);
            let mut d = n.cross(b - a).normalize();
            if d.dot(c - a) < 0.0 {
                d = -d;
            }
            clip3(&mut s.poly, -d, -d.dot(a) - inset, &mut s.tmp3);
        }
        if s.poly.len() < 3 {
            return None;
        }
        let heights = s.poly.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| {
            let h = self.frame.height(p);
            (lo.min(h), hi.max(h))
        });
        let lo = DVec2::splat(-3.0 * self.margin);
        let hi = DVec2::splat(UNITS + 3.0 * self.margin);
        s.a.clear();
        s.a.extend_from_slice(&square_f(lo, hi));
        s.b.clear();
        s.b.extend_from_slice(&s.a);
        for &(v, hv) in &self.light {
            s.pts.clear();
            s.pts.extend(s.poly.iter().map(|&p| self.frame.project(v, hv, p)));
            let a2 = signed_area2(&s.pts);
            if a2.abs() < 2.0 {
                return None;
            }
            if a2 < 0.0 {
                s.pts.reverse();
            }
            let m = s.pts.len();
            for i in 0..m {
                let (a, b) = (s.pts[i], s.pts[(i + 1) % m]);
                let e = b - a;
                let len = e.length();
                let nrm = DVec2::new(e.y, -e.x);
                clip2(&mut s.a, nrm, nrm.dot(a) - self.margin * len, &mut s.tmp2);
                clip2(&mut s.b, nrm, nrm.dot(a) - (self.margin + CORE_EXTRA) * len, &mut s.tmp2);
            }
            if s.a.len() < 3 {
                return None;
            }
        }
        let umbra = snap(&s.a)?;
        Some((umbra, snap(&s.b), heights))
    }

    /// False if the umbra of the convex polygon `poly` alone cannot contain a face square of `side`
    /// units grown by the margin: the intersection of the boxes of its projections from the light's
    /// vertices (which holds its umbra) is narrower than that. True when a point of `poly` is as high
    /// as a light vertex (no cheap bound).
    pub(super) fn may_cover(&self, poly: &[DVec3], side: f64) -> bool {
        // The umbra lies in every projection; a convex polygon containing a square of side `a`
        // contains its inscribed disc, and a convex polygon's inradius is at most twice its area over
        // its perimeter.
        let need = side + 2.0 * self.margin - 1.0;
        let (mut lo, mut hi) = (DVec2::splat(f64::NEG_INFINITY), DVec2::splat(f64::INFINITY));
        let mut q = [DVec2::ZERO; 8];
        if poly.len() > q.len() {
            return true;
        }
        for &(v, hv) in &self.light {
            let (mut a, mut b) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for (k, &p) in poly.iter().enumerate() {
                if self.frame.height(p) >= hv {
                    return true;
                }
                q[k] = self.frame.project(v, hv, p);
                (a, b) = (a.min(q[k]), b.max(q[k]));
            }
            (lo, hi) = (lo.max(a), hi.min(b));
            let q = &q[..poly.len()];
            let perimeter: f64 = (0..q.len()).map(|k| (q[(k + 1) % q.len()] - q[k]).length()).sum();
            if signed_area2(q).abs() < 0.5 * need * perimeter {
                return false;
            }
        }
        (hi - lo).cmpge(DVec2::splat(need)).all()
    }

    /// The shadow region of one blocker (dilated, snapped, counter-clockwise).
    pub(super) fn shadow_of(&self, tri: &[DVec3; 3], s: &mut Scratch) -> Shadow {
        s.poly.clear();
        s.poly.extend_from_slice(tri);
        // A hit from inside the cell lies in the shaft and (t < 1 - SEGMENT_EPS) below `max_hit_h`.
        let (nb, db) = self.frame.below(self.max_hit_h);
        for (n, d) in self.shaft.planes.iter().map(|p| (p.n, p.d)).chain([(nb, db)]) {
            clip3(&mut s.poly, n, d, &mut s.tmp3);
            if s.poly.is_empty() {
                return Shadow::None;
            }
        }
        let h_max = s.poly.iter().map(|&p| self.frame.height(p)).fold(f64::NEG_INFINITY, f64::max);
        let gap = self.min_h - h_max;
        if gap <= 2.0 * self.r {
            return self.cells_shadow(tri);
        }
        // How far an `r` move of a blocker point or of the light point can move a projection.
        let mut dilate = 0.0f64;
        s.pts.clear();
        for &(v, hv) in &self.light {
            let lambda = hv / (hv - h_max).max(gap);
            dilate = dilate.max(3f64.sqrt() * self.r * lambda.max(1.0) * (1.0 + self.diag / (hv - h_max).max(gap)));
            s.pts.extend(s.poly.iter().map(|&p| self.frame.project(v, hv, p)));
        }
        if dilate * self.frame.scale() > UNITS / FALLBACK_RES as f64 {
            return self.cells_shadow(tri);
        }
        hull2(&mut s.pts, &mut s.hull);
        let d = dilate * self.frame.scale() + self.margin;
        s.pts.clear();
        for &p in &s.hull {
            s.pts.extend([DVec2::new(-d, -d), DVec2::new(d, -d), DVec2::new(d, d), DVec2::new(-d, d)].map(|o| p + o));
        }
        hull2(&mut s.pts, &mut s.a);
        if contains_square(&s.a, -self.margin, UNITS + self.margin) {
            return Shadow::Whole;
        }
        let lo = -2.0 * self.margin;
        let hi = UNITS + 2.0 * self.margin;
        for (n, dd) in [(DVec2::X, hi), (DVec2::NEG_X, -lo), (DVec2::Y, hi), (DVec2::NEG_Y, -lo)] {
            clip2(&mut s.a, n, dd, &mut s.tmp2);
        }
        if s.a.is_empty() {
            Shadow::None
        } else {
            Shadow::Polygon
        }
    }
}
