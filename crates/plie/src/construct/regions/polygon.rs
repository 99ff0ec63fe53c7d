//! Integer polygons on the face (SPEC §4.5): snapping to the face's units, squares, and the
//! booleans (union, difference), areas and triangulation of i_overlay shapes.

use glam::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay::{Overlay, ShapeType};
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::{IntContour, IntShapes};
use i_triangle::int::triangulator::IntTriangulator;

use crate::lie::frame::Tri2;

/// The axis-aligned square `[lo, hi]` as a counter-clockwise `f64` polygon.
pub(super) fn square_f(lo: DVec2, hi: DVec2) -> [DVec2; 4] {
    [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
}

/// The square `[lo, hi]` snapped outward to units, counter-clockwise.
pub(super) fn square(lo: DVec2, hi: DVec2) -> IntContour<i32> {
    let (x0, y0) = (lo.x.floor() as i32, lo.y.floor() as i32);
    let (x1, y1) = (hi.x.ceil() as i32, hi.y.ceil() as i32);
    vec![IntPoint::new(x0, y0), IntPoint::new(x1, y0), IntPoint::new(x1, y1), IntPoint::new(x0, y1)]
}

/// A convex counter-clockwise polygon rounded to units, or `None` if it collapses.
pub(super) fn snap(poly: &[DVec2]) -> Option<IntContour<i32>> {
    let mut out: IntContour<i32> = Vec::with_capacity(poly.len());
    for p in poly {
        let q = IntPoint::new(p.x.round() as i32, p.y.round() as i32);
        if out.last() != Some(&q) {
            out.push(q);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    (out.len() >= 3 && contour_area2(&out) > 0).then_some(out)
}

/// Twice the signed area of an integer contour.
pub(super) fn contour_area2(c: &[IntPoint<i32>]) -> i64 {
    let n = c.len();
    (0..n)
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % n]);
            a.x as i64 * b.y as i64 - b.x as i64 * a.y as i64
        })
        .sum()
}

/// The union of convex contours, merged pairwise: each overlay then only meets the boundaries of two
/// partial unions, not every edge crossing inside the final union (umbra regions overlap a lot).
pub(super) fn union(contours: Vec<IntContour<i32>>) -> IntShapes<i32> {
    let mut parts: Vec<IntShapes<i32>> = contours.into_iter().map(|c| vec![vec![c]]).collect();
    while parts.len() > 1 {
        let mut next = Vec::with_capacity(parts.len().div_ceil(2));
        let mut it = parts.into_iter();
        while let Some(a) = it.next() {
            match it.next() {
                Some(b) => {
                    let mut o = Overlay::new(vertex_count(&a) + vertex_count(&b));
                    o.add_source(&a, ShapeType::Subject);
                    o.add_source(&b, ShapeType::Clip);
                    next.push(o.overlay(OverlayRule::Union, FillRule::NonZero));
                }
                None => next.push(a),
            }
        }
        parts = next;
    }
    parts.pop().unwrap_or_default()
}

/// `a` minus `b`.
pub(super) fn difference(a: &IntShapes<i32>, b: &IntShapes<i32>) -> IntShapes<i32> {
    if a.is_empty() || b.is_empty() {
        return a.clone();
    }
    let mut o = Overlay::new(vertex_count(a) + vertex_count(b));
    o.add_source(a, ShapeType::Subject);
    o.add_source(b, ShapeType::Clip);
    o.overlay(OverlayRule::Difference, FillRule::NonZero)
}

/// Area of shapes (holes subtract), in units².
pub(super) fn area(shapes: &IntShapes<i32>) -> f64 {
    shapes.iter().flatten().map(|c| contour_area2(c) as f64 * 0.5).sum::<f64>().abs()
}

/// Vertices of shapes.
pub(super) fn vertex_count(shapes: &IntShapes<i32>) -> usize {
    shapes.iter().flatten().map(Vec::len).sum()
}

/// Triangles of shapes.
pub(super) fn triangulate(shapes: &IntShapes<i32>) -> Vec<Tri2> {
    if shapes.is_empty() {
        return Vec::new();
    }
    let t = IntTriangulator::<i32, u32>::default().triangulate_shapes(shapes);
    let p = |k: u32| {
        let q = t.points[k as usize];
        [q.x, q.y]
    };
    t.indices.chunks_exact(3).map(|i| [p(i[0]), p(i[1]), p(i[2])]).collect()
}
