//! Mitsuba's built-in shapes tessellated into triangle meshes in their object space (issue 18):
//! `rectangle` (`[-1, 1]^2` at `z = 0`, facing `+z`), `cube` (`[-1, 1]^3`, facing out), `disk` (unit
//! radius at `z = 0`, facing `+z`, [`DISK_SEGMENTS`] segments) and `sphere` (unit radius, facing out,
//! [`SPHERE_RINGS`] x 2 [`SPHERE_RINGS`] quads; an inscribed polyhedron, so its area is slightly
//! smaller than the sphere's). Texture coordinates as Mitsuba 3 gives them: rectangle `(x, y) / 2 +
//! 1/2`, disk `(r, phi / 2 pi)`, sphere `(phi / 2 pi, theta / pi)`; the cube has none.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::io::tri_mesh::TriMesh;

/// Segments of a tessellated disk.
pub const DISK_SEGMENTS: u32 = 64;
/// Rings of a tessellated sphere (twice as many segments around).
pub const SPHERE_RINGS: u32 = 16;

/// The unit rectangle.
pub fn rectangle() -> TriMesh {
    let p = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    TriMesh {
        positions: p.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
        uvs: p.iter().map(|&(x, y)| Vec2::new(x * 0.5 + 0.5, y * 0.5 + 0.5)).collect(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// The cube `[-1, 1]^3`.
pub fn cube() -> TriMesh {
    let mut m = TriMesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let u = Vec3::AXES[(axis + 1) % 3];
            let v = n.cross(u);
            let base = m.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                m.positions.push(n + u * a + v * b);
            }
            m.triangles.push([base, base + 1, base + 2]);
            m.triangles.push([base, base + 2, base + 3]);
        }
    }
    m
}

/// The unit disk.
pub fn disk() -> TriMesh {
    let mut m = TriMesh { positions: vec![Vec3::ZERO], uvs: vec![Vec2::ZERO], triangles: Vec::new() };
    for i in 0..=DISK_SEGMENTS {
        let phi = TAU * i as f32 / DISK_SEGMENTS as f32;
        m.positions.push(Vec3::new(phi.cos(), phi.sin(), 0.0));
        m.uvs.push(Vec2::new(1.0, i as f32 / DISK_SEGMENTS as f32));
    }
    for i in 0..DISK_SEGMENTS {
        m.triangles.push([0, i + 1, i + 2]);
    }
    m
}

/// The unit sphere.
pub fn sphere() -> TriMesh {
    let (rings, segs) = (SPHERE_RINGS, 2 * SPHERE_RINGS);
    let mut m = TriMesh::default();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segs {
            let phi = TAU * s as f32 / segs as f32;
            m.positions.push(Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
            m.uvs.push(Vec2::new(s as f32 / segs as f32, r as f32 / rings as f32));
        }
    }
    let at = |r: u32, s: u32| r * (segs + 1) + s;
    for r in 0..rings {
        for s in 0..segs {
            let (a, b, c, d) = (at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s + 1));
            // Counter-clockwise seen from outside; the poles' degenerate halves are dropped.
            if r > 0 {
                m.triangles.push([a, b, d]);
            }
            if r + 1 < rings {
                m.triangles.push([b, c, d]);
            }
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle's normal points away from the origin (closed shapes) or along +z (flat ones).
    fn faces_out(m: &TriMesh, flat: bool) {
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.length() > 0.0, "degenerate triangle {t:?}");
            let out = if flat { n.z } else { n.dot(a + b + c) };
            assert!(out > 0.0, "triangle {t:?} faces inward");
        }
    }

    #[test]
    fn shapes_face_outward() {
        faces_out(&rectangle(), true);
        faces_out(&disk(), true);
        faces_out(&cube(), false);
        faces_out(&sphere(), false);
        assert_eq!(cube().triangles.len(), 12);
        assert_eq!(sphere().triangles.len() as u32, 2 * SPHERE_RINGS * (2 * SPHERE_RINGS) - 2 * 2 * SPHERE_RINGS);
    }
}
