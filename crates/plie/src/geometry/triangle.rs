//! Triangles as stored by the scene: three vertices, counter-clockwise around the front normal.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::Aabb;

/// A triangle by its three vertices. The front side is the one the counter-clockwise winding faces.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Triangle {
    /// The vertices, counter-clockwise seen from the front.
    pub v: [Vec3; 3],
}

impl Triangle {
    /// A triangle from its vertices.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Triangle {
        Triangle { v: [a, b, c] }
    }

    /// `(b - a) x (c - a)`: twice the area, along the front normal.
    pub fn cross(&self) -> Vec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }

    /// Unit front normal (zero for a degenerate triangle).
    pub fn normal(&self) -> Vec3 {
        self.cross().normalize_or_zero()
    }

    /// Area.
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    /// Bounding box.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.v)
    }

    /// Centroid.
    pub fn centroid(&self) -> Vec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }

    /// True if the triangle has (numerically) no area: it cannot block anything.
    pub fn is_degenerate(&self) -> bool {
        let e = (self.v[1] - self.v[0]).length().max((self.v[2] - self.v[0]).length());
        let c = self.cross().length();
        c.is_nan() || c <= 1e-12 * e * e || !c.is_finite()
    }

    /// The point with barycentric coordinates `(1 - u - v, u, v)`.
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        self.v[0] + (self.v[1] - self.v[0]) * u + (self.v[2] - self.v[0]) * v
    }
}
