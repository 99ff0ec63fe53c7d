//! Exact triangle/box overlap by the separating axis theorem (Akenine-Möller, "Fast 3D Triangle-Box
//! Overlap Testing", 2001). SPEC §3 **Correction**: the thesis assigned a triangle to a cell only when a
//! vertex lay in it or an edge crossed it, which misses a large triangle whose interior crosses a small
//! cell. Here all 13 axes are tested (3 box normals, the triangle normal, 9 edge cross products).
//!
//! Computed in f64 on a box that the caller may grow by a tolerance, so the answer errs toward overlap.

use glam::{DVec3, Vec3};

use super::{Aabb, Triangle};

/// True if `tri` overlaps the closed box `b` (touching counts).
pub fn triangle_overlaps_box(tri: &Triangle, b: &Aabb) -> bool {
    let c = b.center().as_dvec3();
    let h = (b.size() * 0.5).as_dvec3();
    let v: [DVec3; 3] = tri.v.map(|p: Vec3| p.as_dvec3() - c);
    // Box normals: the triangle's bounding box against the box.
    for k in 0..3 {
        let lo = v[0][k].min(v[1][k]).min(v[2][k]);
        let hi = v[0][k].max(v[1][k]).max(v[2][k]);
        if lo > h[k] || hi < -h[k] {
            return false;
        }
    }
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // Triangle normal.
    let n = e[0].cross(e[1]);
    if separated(n, &v, h) {
        return false;
    }
    // Edge x box-axis cross products.
    for edge in &e {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            if separated(edge.cross(axis), &v, h) {
                return false;
            }
        }
    }
    true
}

/// True if `axis` separates the triangle `v` from the box of half-size `h` centered at the origin.
fn separated(axis: DVec3, v: &[DVec3; 3], h: DVec3) -> bool {
    if axis == DVec3::ZERO {
        return false;
    }
    let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
    let r = h.dot(axis.abs());
    let lo = p[0].min(p[1]).min(p[2]);
    let hi = p[0].max(p[1]).max(p[2]);
    lo > r || hi < -r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_triangle_through_small_box_overlaps() {
        // No vertex in the box and no edge through it: the thesis' test would miss this one.
        let t = Triangle::new(Vec3::new(-10.0, -10.0, 0.5), Vec3::new(10.0, -10.0, 0.5), Vec3::new(0.0, 10.0, 0.5));
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert!(triangle_overlaps_box(&t, &b));
    }

    #[test]
    fn separated_by_normal_and_by_edge_axes() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let t = Triangle::new(Vec3::new(-10.0, -10.0, 1.5), Vec3::new(10.0, -10.0, 1.5), Vec3::new(0.0, 10.0, 1.5));
        assert!(!triangle_overlaps_box(&t, &b));
        // Slanted triangle passing by a corner: only an edge cross product separates it.
        let t = Triangle::new(Vec3::new(1.6, -1.0, 0.5), Vec3::new(1.6, 3.0, 0.5), Vec3::new(-1.0, 1.6, 0.5));
        let t2 = Triangle::new(Vec3::new(1.2, 2.0, 0.5), Vec3::new(2.0, 1.2, 0.5), Vec3::new(3.0, 3.0, 0.5));
        assert!(triangle_overlaps_box(&t, &b));
        assert!(!triangle_overlaps_box(&t2, &b));
    }

    #[test]
    fn touching_counts() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let t = Triangle::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        assert!(triangle_overlaps_box(&t, &b));
    }
}
