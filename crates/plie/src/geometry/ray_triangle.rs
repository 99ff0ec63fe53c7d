//! The one watertight ray/triangle test (Woop, Benthin & Wald, "Watertight Ray/Triangle Intersection",
//! JCGT 2013), used by every visibility mode and by eye rays (SPEC §5).
//!
//! The ray is sheared so that it runs along +z through the origin; the three 2D edge functions of the
//! transformed vertices decide the hit. A vertex transforms the same way whichever triangle it belongs
//! to, so two triangles sharing an edge compute the same edge function with opposite sign: a ray through
//! the edge hits at least one of them. Edge functions that come out exactly zero are recomputed in f64,
//! as the paper prescribes, so the sign is right where it matters most.
//!
//! Answers depend only on the ray and the triangle, never on the order of tests or on the caller, which
//! is what makes all visibility modes agree bit for bit.

use glam::Vec3;

use super::Triangle;

/// A ray `origin + t * dir` with `t` in the open interval `(t_min, t_max)`, prepared for the watertight
/// test.
#[derive(Clone, Copy, Debug)]
pub struct RayTest {
    /// Ray origin.
    pub origin: Vec3,
    /// Ray direction (not necessarily unit length; `t` is measured in multiples of it).
    pub dir: Vec3,
    /// Hits must have `t > t_min`.
    pub t_min: f32,
    /// Hits must have `t < t_max`.
    pub t_max: f32,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RayTest {
    /// Prepares the ray. `dir` must be non-zero and finite.
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> RayTest {
        debug_assert!(dir.is_finite() && dir != Vec3::ZERO, "bad ray direction {dir}");
        let kz = RayTest::major_axis(dir);
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        RayTest { origin, dir, t_min, t_max, kx, ky, kz, sx: dir[kx] * sz, sy: dir[ky] * sz, sz }
    }

    /// The axis the test shears along for direction `dir`: that of its largest component (the first
    /// of equal ones). Lane-wide copies of the test must choose as this does.
    #[inline]
    pub fn major_axis(dir: Vec3) -> usize {
        let a = dir.abs();
        if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        }
    }

    /// The shear of the test: `[sx, sy, sz]` and the axes `[kx, ky, kz]` (for lane-wide copies of
    /// [`RayTest::hit`] that must compute exactly what it computes).
    #[inline]
    pub fn shear(&self) -> ([f32; 3], [u32; 3]) {
        ([self.sx, self.sy, self.sz], [self.kx as u32, self.ky as u32, self.kz as u32])
    }

    /// The parameter `t` of the hit with `tri`, if the ray hits it strictly inside `(t_min, t_max)`.
    /// Both sides of the triangle count. Degenerate triangles are never hit.
    #[inline]
    pub fn hit(&self, tri: &Triangle) -> Option<f32> {
        let a = tri.v[0] - self.origin;
        let b = tri.v[1] - self.origin;
        let c = tri.v[2] - self.origin;
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        // Compare t = t_scaled / det against the interval without dividing, sign-corrected.
        let (ts, d) = if det < 0.0 { (-t_scaled, -det) } else { (t_scaled, det) };
        if ts <= self.t_min * d || ts >= self.t_max * d {
            return None;
        }
        Some(ts / d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0))
    }

    #[test]
    fn hits_inside_and_misses_outside() {
        let r = RayTest::new(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -2.0), 0.0, 1.0);
        let t = r.hit(&tri()).expect("hit");
        assert!((t - 0.5).abs() < 1e-6);
        let r = RayTest::new(Vec3::new(0.8, 0.8, 1.0), Vec3::new(0.0, 0.0, -2.0), 0.0, 1.0);
        assert!(r.hit(&tri()).is_none());
    }

    #[test]
    fn respects_open_interval_and_both_sides() {
        let r = RayTest::new(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -2.0), 0.0, 0.4);
        assert!(r.hit(&tri()).is_none());
        let r = RayTest::new(Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.0, 0.0, 2.0), 0.0, 1.0);
        assert!(r.hit(&tri()).is_some(), "back side counts");
        let r = RayTest::new(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, 2.0), 0.0, 1.0);
        assert!(r.hit(&tri()).is_none(), "behind the origin");
    }

    #[test]
    fn degenerate_triangle_is_never_hit() {
        let d = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        let r = RayTest::new(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.0, 0.0, -2.0), 0.0, 1.0);
        assert!(r.hit(&d).is_none());
    }
}
