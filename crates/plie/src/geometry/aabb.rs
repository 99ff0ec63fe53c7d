//! Axis-aligned boxes: octree cells, BVH bounds, scene bounds.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// An axis-aligned box, `min <= max` componentwise unless empty.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: extending it by a point gives that point.
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// A box from its corners.
    pub fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    /// The cube with the given center and half-size.
    pub fn cube(center: Vec3, half: f32) -> Aabb {
        Aabb { min: center - Vec3::splat(half), max: center + Vec3::splat(half) }
    }

    /// The smallest box around the points.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.extended(*p))
    }

    /// True if no point lies in the box.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// The box grown to contain `p`.
    pub fn extended(self, p: Vec3) -> Aabb {
        Aabb { min: self.min.min(p), max: self.max.max(p) }
    }

    /// The smallest box containing both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// The box grown by `d` on every side.
    pub fn expanded(self, d: f32) -> Aabb {
        Aabb { min: self.min - Vec3::splat(d), max: self.max + Vec3::splat(d) }
    }

    /// The eight corners (bit 0 of the index picks `max.x`, bit 1 `max.y`, bit 2 `max.z`).
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|k| Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), self.max, self.min))
    }

    /// Center point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Edge lengths.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f32 {
        self.size().length()
    }

    /// The largest absolute coordinate of the box: how far it reaches from the origin along an
    /// axis, the scale of the `f32` rounding of points in it.
    pub fn largest_abs(&self) -> f32 {
        self.min.abs().max(self.max.abs()).max_element()
    }

    /// Closed-box containment.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Closed-box overlap.
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// The parameter interval `[t0, t1]` within `[t_min, t_max]` where `origin + t * dir` lies in the
    /// box, or `None`. Slab test; callers that must be conservative pass an expanded box.
    pub fn clip_ray(&self, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let a = (self.min - origin) * inv_dir;
        let b = (self.max - origin) * inv_dir;
        // NaN (0 * inf, a ray in a slab plane) must not shrink the interval: max/min ignore NaN.
        let lo = a.min(b);
        let hi = a.max(b);
        let t0 = t_min.max(lo.x).max(lo.y).max(lo.z);
        let t1 = t_max.min(hi.x).min(hi.y).min(hi.z);
        (t0 <= t1).then_some((t0, t1))
    }
}
