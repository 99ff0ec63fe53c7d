//! The pyramid from a shaded point `x` over a light polygon (issue 21): it contains every shadow ray
//! from `x` to the light, so a triangle or box beyond one of its planes (grown by a margin) meets
//! none of them. The per-light query culls its candidates with it before the fan's lane tests
//! ([`super::fan`]).

use glam::Vec3;

use crate::geometry::{Aabb, Triangle};
use crate::scene::Light;

/// The pyramid conv(`x` ∪ light polygon), as planes with inward unit normals through `x` (one per
/// light edge) and the light's own plane, each grown outward by `margin`.
#[derive(Clone, Debug, Default)]
pub struct Pyramid {
    /// Inward unit normals of the side planes (through the apex).
    sides: Vec<Vec3>,
    /// Unit normal of the light plane pointing toward the apex, and the plane's offset.
    cap: (Vec3, f32),
    apex: Vec3,
    margin: f32,
}

impl Pyramid {
    /// The pyramid from `x` over `light`'s sample domain, grown by `margin` (a length). Returns false
    /// (and leaves an empty pyramid, which culls nothing) if `x` lies too close to the light's plane
    /// for the side planes to be well defined.
    pub fn set(&mut self, x: Vec3, light: &Light, margin: f32) -> bool {
        self.sides.clear();
        self.apex = x;
        self.margin = margin;
        let n = light.normal;
        let v = &light.vertices;
        let h = n.dot(x - v[0]);
        self.cap = (n, n.dot(v[0]));
        if h.is_nan() || h <= 4.0 * margin {
            return false;
        }
        // The sample domain's hull is the polygon (plus, for a parallelogram, its fourth corner
        // recomputed, within rounding of the vertex): the polygon's edges, grown by the margin.
        for i in 0..v.len() {
            let (p, q) = (v[i] - x, v[(i + 1) % v.len()] - x);
            // The plane through the apex and the edge (p, q), its normal turned toward the centre.
            let s = p.cross(q);
            let len = s.length();
            if len.is_nan() || len <= 0.0 || len.is_infinite() {
                self.sides.clear();
                return false;
            }
            let mut s = s / len;
            if s.dot(light.center() - x) < 0.0 {
                s = -s;
            }
            self.sides.push(s);
        }
        true
    }

    /// True if no segment from the apex to a point of the light (within the margin) can meet
    /// `tri`: all its vertices lie beyond one plane.
    #[inline]
    pub fn culls(&self, tri: &Triangle) -> bool {
        let x = self.apex;
        let m = self.margin;
        let (a, b, c) = (tri.v[0] - x, tri.v[1] - x, tri.v[2] - x);
        for s in &self.sides {
            if s.dot(a) < -m && s.dot(b) < -m && s.dot(c) < -m {
                return true;
            }
        }
        if self.sides.is_empty() {
            return false;
        }
        let (n, off) = self.cap;
        n.dot(tri.v[0]) - off < -m && n.dot(tri.v[1]) - off < -m && n.dot(tri.v[2]) - off < -m
    }

    /// True if no segment of the pyramid can meet anything in the box `b`.
    #[inline]
    pub fn culls_box(&self, b: &Aabb) -> bool {
        if self.sides.is_empty() {
            return false;
        }
        let x = self.apex;
        let m = self.margin;
        // The box corner farthest along the normal.
        let far = |s: Vec3| Vec3::select(s.cmpge(Vec3::ZERO), b.max, b.min);
        for s in &self.sides {
            if s.dot(far(*s) - x) < -m {
                return true;
            }
        }
        let (n, off) = self.cap;
        n.dot(far(n)) - off < -m
    }
}
