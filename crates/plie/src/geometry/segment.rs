//! Segments prepared for slab tests against boxes: the conservative culling step shared by octree
//! traversal (SPEC §3) and the P-LIE's candidate lists (SPEC §5). An axis whose inverse direction is
//! not finite (a zero or tiny direction component) is tested as the interval of coordinates the
//! segment covers, since `0 * inf = NaN` would otherwise decide the answer.

use glam::Vec3;

use super::Aabb;

/// A segment `origin + t * dir`, `t` in `[t_min, t_max]`, prepared for slab tests.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    /// Start.
    pub origin: Vec3,
    inv_dir: Vec3,
    t_min: f32,
    t_max: f32,
    /// Bit k set: axis k is treated as parallel (the inverse direction is not finite).
    parallel: u32,
    /// For parallel axes: the range of coordinates the segment covers.
    span_lo: Vec3,
    span_hi: Vec3,
}

impl Segment {
    /// Prepares the segment `origin + t * dir`, `t` in `[t_min, t_max]`.
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Segment {
        let inv_dir = dir.recip();
        let mut parallel = 0;
        let mut span_lo = origin;
        let mut span_hi = origin;
        for k in 0..3 {
            if !inv_dir[k].is_finite() {
                parallel |= 1 << k;
                if dir[k] != 0.0 {
                    // Tiny but non-zero: the coordinate still moves a little along the segment.
                    let a = origin[k] + dir[k] * t_min;
                    let b = origin[k] + dir[k] * t_max;
                    span_lo[k] = a.min(b).min(origin[k]);
                    span_hi[k] = a.max(b).max(origin[k]);
                }
            }
        }
        Segment { origin, inv_dir, t_min, t_max, parallel, span_lo, span_hi }
    }

    /// The parameter interval in which the segment lies in the closed box `b`, if any.
    #[inline]
    pub fn clip(&self, b: &Aabb) -> Option<(f32, f32)> {
        let mut t0 = self.t_min;
        let mut t1 = self.t_max;
        for k in 0..3 {
            if self.parallel & (1 << k) != 0 {
                if self.span_hi[k] < b.min[k] || self.span_lo[k] > b.max[k] {
                    return None;
                }
            } else {
                let a = (b.min[k] - self.origin[k]) * self.inv_dir[k];
                let c = (b.max[k] - self.origin[k]) * self.inv_dir[k];
                t0 = t0.max(a.min(c));
                t1 = t1.min(a.max(c));
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }
}
