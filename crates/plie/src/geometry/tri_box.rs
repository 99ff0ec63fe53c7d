//! Exact triangle/box overlap by the separating axis theorem (Akenine-Möller, "Fast 3D Triangle-Box
//! Overlap Testing", 2001). SPEC §3 **Correction**: the thesis assigned a triangle to a cell only when a
//! vertex lay in it or an edge crossed it, which misses a large triangle whose interior crosses a small
//! cell. Here all 13 axes are tested (3 box normals, the triangle normal, 9 edge cross products).
//!
//! Computed in f64 on a box that the caller may grow by a tolerance, so the answer errs toward overlap.
//!
//! A triangle with a corner inside the box (shrunk by a relative `1e-9`) overlaps it, and no axis of
//! the 13 can come out separating: the corner's projection on any axis `a` is at most
//! `(1 + 4u)(1 - 1e-9) sum |a_k| h_k` in magnitude, the box's radius at least `(1 - 4u) sum |a_k| h_k`
//! (`u` = 2^-53, f64 rounding of three-term dot products). So that case returns `true` before the
//! edge axes, with the full test's answer; in a fine octree cell most triangles have such a corner.

use glam::{DVec3, Vec3};

use super::{Aabb, Triangle};

/// True if `tri` overlaps the closed box `b` (touching counts).
pub fn triangle_overlaps_box(tri: &Triangle, b: &Aabb) -> bool {
    overlaps(tri, b, true)
}

/// [`triangle_overlaps_box`], with or without the corner shortcut (the tests compare both).
fn overlaps(tri: &Triangle, b: &Aabb, corners_first: bool) -> bool {
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
    if corners_first && v.iter().any(|p| corner_inside(*p, h)) {
        return true;
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

/// True if the corner `p` lies in the box of half-size `h` centered at the origin, shrunk by a relative
/// `1e-9`: far more room than the rounding of any axis' projection and radius (module doc).
fn corner_inside(p: DVec3, h: DVec3) -> bool {
    p.abs().cmple(h * (1.0 - 1e-9)).all()
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

    /// The corner shortcut gives the 13 axes' answer: random boxes and triangles, with corners drawn
    /// inside, outside and a few ulps from the box's faces (where rounding could matter).
    #[test]
    fn the_corner_shortcut_keeps_every_answer() {
        use proptest::prelude::*;
        let coord = prop_oneof![
            -4.0f32..4.0,
            Just(0.0f32),
            Just(1.0f32),
            (0u32..4).prop_map(|k| f32::from_bits(1.0f32.to_bits() - k)),
            (0u32..4).prop_map(|k| f32::from_bits(1.0f32.to_bits() + k)),
            (0u32..4).prop_map(f32::from_bits),
            (0u32..4).prop_map(|k| -f32::from_bits(k)),
        ];
        let corner = [coord.clone(), coord.clone(), coord].prop_map(|[x, y, z]| Vec3::new(x, y, z));
        let mut runner = proptest::test_runner::TestRunner::new(proptest::test_runner::Config {
            cases: 20_000,
            ..Default::default()
        });
        let (mut inside, mut overlapping) = (0u32, 0u32);
        runner
            .run(&([corner.clone(), corner.clone(), corner], prop_oneof![Just(0.0f32), 0.0f32..1e-3]), |(v, grow)| {
                let t = Triangle::new(v[0], v[1], v[2]);
                let b = Aabb::new(Vec3::ZERO, Vec3::ONE).expanded(grow);
                let full = overlaps(&t, &b, false);
                prop_assert_eq!(triangle_overlaps_box(&t, &b), full);
                Ok(())
            })
            .expect("same answers");
        // The cases exercise both ways: corners inside (the shortcut) and overlaps found by the axes.
        let mut state = 1u64;
        let mut f = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((state >> 40) % 600) as f32 / 200.0 - 1.0
        };
        for _ in 0..2_000 {
            let mut corner = || Vec3::new(f(), f(), f());
            let t = Triangle::new(corner(), corner(), corner());
            let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
            let (vs, h) = (t.v.map(|p| p.as_dvec3() - DVec3::splat(0.5)), DVec3::splat(0.5));
            inside += u32::from(vs.iter().any(|p| corner_inside(*p, h)));
            let full = overlaps(&t, &b, false);
            overlapping += u32::from(full);
            assert_eq!(triangle_overlaps_box(&t, &b), full);
        }
        assert!(inside > 100 && overlapping > inside, "{inside} with a corner inside, {overlapping} overlapping");
    }

    #[test]
    fn touching_counts() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let t = Triangle::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        assert!(triangle_overlaps_box(&t, &b));
    }
}
