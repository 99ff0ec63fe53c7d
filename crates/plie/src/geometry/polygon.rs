//! Planar polygons (SPEC §1: a light is a planar convex polygon): Newell's normal, the one sum every
//! light's normal and area come from, whether given as a polygon or grouped from a file's emissive
//! triangles.

use glam::{DVec3, Vec3};

/// Newell's normal of the polygon `p` (at least one corner): twice its area times its unit normal,
/// counter-clockwise around it. Summed relative to the first corner and in f64: from the origin,
/// the terms of a small polygon far away would be as large as its distance squared and cancel to
/// rounding noise.
pub fn newell(p: &[Vec3]) -> DVec3 {
    let p0 = p[0].as_dvec3();
    let mut n = DVec3::ZERO;
    for (i, a) in p.iter().enumerate() {
        n += (a.as_dvec3() - p0).cross(p[(i + 1) % p.len()].as_dvec3() - p0);
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square far from the origin: its area and normal, exactly.
    #[test]
    fn square_far_from_the_origin() {
        let f = Vec3::new(432.5, -740.75, -874.5);
        let n = newell(&[f, f + Vec3::X, f + Vec3::X + Vec3::Y, f + Vec3::Y]);
        assert_eq!(n, DVec3::new(0.0, 0.0, 2.0));
    }
}
