//! Sutherland-Hodgman clipping of a convex polygon by one half-space, in 3D (SPEC §4.4 step 3, §4.5)
//! and in 2D (§4.5: projections and umbra polygons on a face). `f64` throughout: these run at
//! construction time, where exactness margins matter more than speed.

use glam::{DVec2, DVec3};

/// Keeps the part of the convex polygon `poly` where `dist(p) <= 0`, for an affine `dist` (the signed
/// distance to a plane or line), using `tmp` as scratch.
fn clip_by<P>(poly: &mut Vec<P>, dist: impl Fn(P) -> f64, tmp: &mut Vec<P>)
where
    P: Copy + std::ops::Add<Output = P> + std::ops::Sub<Output = P> + std::ops::Mul<f64, Output = P>,
{
    tmp.clear();
    let len = poly.len();
    for i in 0..len {
        let (a, b) = (poly[i], poly[(i + 1) % len]);
        let (da, db) = (dist(a), dist(b));
        if da <= 0.0 {
            tmp.push(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            tmp.push(a + (b - a) * (da / (da - db)));
        }
    }
    std::mem::swap(poly, tmp);
}

/// Keeps the part of the convex polygon `poly` with `n . p <= d`, using `tmp` as scratch.
pub fn clip3(poly: &mut Vec<DVec3>, n: DVec3, d: f64, tmp: &mut Vec<DVec3>) {
    clip_by(poly, |p| n.dot(p) - d, tmp);
}

/// Keeps the part of the convex polygon `poly` with `n . p <= d`, using `tmp` as scratch.
pub fn clip2(poly: &mut Vec<DVec2>, n: DVec2, d: f64, tmp: &mut Vec<DVec2>) {
    clip_by(poly, |p| n.dot(p) - d, tmp);
}

/// Twice the signed area of a 2D polygon (positive: counter-clockwise).
pub fn signed_area2(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum()
}

/// The convex hull of `pts`, counter-clockwise, without collinear points (Andrew's monotone chain).
/// Sorts `pts` in place.
pub fn hull2(pts: &mut [DVec2], out: &mut Vec<DVec2>) {
    out.clear();
    pts.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    if pts.len() < 3 {
        out.extend_from_slice(pts);
        return;
    }
    let turn = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    for &p in pts.iter() {
        while out.len() >= 2 && turn(out[out.len() - 2], out[out.len() - 1], p) <= 0.0 {
            out.pop();
        }
        out.push(p);
    }
    let lower = out.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while out.len() >= lower && turn(out[out.len() - 2], out[out.len() - 1], p) <= 0.0 {
            out.pop();
        }
        out.push(p);
    }
    out.pop();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_a_square_by_a_diagonal_keeps_a_triangle() {
        let mut sq = vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)];
        let mut tmp = Vec::new();
        clip2(&mut sq, DVec2::new(1.0, 1.0), 1.0, &mut tmp);
        assert_eq!(sq.len(), 3);
        assert!((signed_area2(&sq) - 1.0).abs() < 1e-12);
        let mut tri = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let mut tmp3 = Vec::new();
        clip3(&mut tri, DVec3::X, -0.5, &mut tmp3);
        assert!(tri.is_empty());
    }

    #[test]
    fn hull_of_a_square_with_inner_and_edge_points() {
        let mut pts: Vec<DVec2> = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0), (1.0, 1.0), (1.0, 0.0), (0.5, 1.5)]
            .iter()
            .map(|&(x, y)| DVec2::new(x, y))
            .collect();
        let mut out = Vec::new();
        hull2(&mut pts, &mut out);
        assert_eq!(out.len(), 4);
        assert!((signed_area2(&out) - 8.0).abs() < 1e-12, "counter-clockwise, area 4");
    }
}
