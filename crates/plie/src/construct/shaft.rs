//! The shaft between a cell face and a light (SPEC §4.2, §4.3): the bounding volume (the box around
//! face and light) and the supporting planes of `S = conv(face ∪ light)`.
//!
//! The thesis builds four planes, each through one face edge and one light vertex chosen by angle.
//! We take SPEC §4.3's exact alternative: every supporting plane of the convex hull of the at most
//! `4 + k` points, found by testing each triple of points (all points must lie on one side). A flat
//! hull (light in the face's plane) simply yields fewer planes, i.e. a larger set — never a smaller
//! one. Each plane is moved outward by a tolerance, so the kept set contains `S` grown by it: clipping
//! can only err toward keeping a blocker.

use glam::{DVec3, Vec3};

use crate::geometry::Aabb;

/// Most points a shaft's planes are chosen from (4 face corners + light vertices): each passes through
/// three of the first `MAX_POINTS` points, and is kept only if every point, the rest included, lies
/// on its inner side. A longer light polygon can only get fewer planes (a larger shaft).
pub const MAX_POINTS: usize = 16;

/// Vertices of the stack buffers [`Shaft::clips_triangle`] clips in when the shaft has at most
/// `SMALL_CLIP - 3` planes.
const SMALL_CLIP: usize = 48;

/// A closed half-space `n . p <= d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Outward unit normal.
    pub n: DVec3,
    /// Offset.
    pub d: f64,
}

impl Plane {
    /// Signed distance of `p` beyond the plane (positive: outside).
    #[inline]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.n.dot(p) - self.d
    }
}

/// The shaft from a face to a light: bounding volume and supporting planes, both grown by `tol`.
#[derive(Clone, Debug)]
pub struct Shaft {
    /// Box around face and light, grown by the tolerance.
    pub bounds: Aabb,
    /// The hull's supporting planes, each moved outward by the tolerance, followed by the six planes of
    /// `bounds`.
    pub planes: Vec<Plane>,
}

impl Shaft {
    /// The shaft of `conv(face ∪ light)`, grown by `tol`.
    pub fn new(face: &[Vec3; 4], light: &[Vec3], tol: f32) -> Shaft {
        Shaft::of_points(face, light, tol)
    }

    /// The shaft of `conv(near ∪ light)` for any points `near`, grown by `tol`. Its planes are those
    /// through three of the first [`MAX_POINTS`] points that have every point (all of them) on one
    /// side.
    pub fn of_points(near: &[Vec3], light: &[Vec3], tol: f32) -> Shaft {
        let bounds = Aabb::from_points(near.iter().chain(light)).expanded(tol);
        let pts: Vec<DVec3> = near.iter().chain(light).map(|p| p.as_dvec3()).collect();
        Shaft::hull(pts, bounds, tol)
    }

    /// The shaft of `conv(a ∪ b)` for two boxes, grown by `tol` (the shafts of the cuts of the scene
    /// BVH, [`crate::visibility::bvh::Cut`]: a leaf's box and a light's). A facet of that hull whose
    /// normal has three non-zero components would meet each box in one corner only, so every facet
    /// is a face of the boxes' bounds or parallel to an axis. Those parallel to axis `e` are the
    /// lines of the hull of the two rectangles the boxes project to along `e`: through a corner of
    /// each, with all eight corners on one side. Such a line that is not along an axis has an
    /// outward normal with two non-zero components, and each rectangle's one corner farthest along
    /// it is of the same kind (least or greatest in each coordinate, by the normal's signs): so it
    /// passes through the two rectangles' corners of one kind. So this is [`Shaft::of_points`] of
    /// the sixteen corners, from 3 x 4 candidate lines instead of 560 triples.
    pub fn of_boxes(a: &Aabb, b: &Aabb, tol: f32) -> Shaft {
        let bounds = a.union(*b).expanded(tol);
        let mut planes: Vec<Plane> = Vec::with_capacity(12);
        for e in 0..3 {
            let (u, v) = ((e + 1) % 3, (e + 2) % 3);
            let rect = |r: &Aabb| {
                let (lo, hi) = (r.min.as_dvec3(), r.max.as_dvec3());
                [[lo[u], lo[v]], [hi[u], lo[v]], [lo[u], hi[v]], [hi[u], hi[v]]]
            };
            let (ra, rb) = (rect(a), rect(b));
            let all = [ra[0], ra[1], ra[2], ra[3], rb[0], rb[1], rb[2], rb[3]];
            // Corners of one kind.
            for (p, q) in ra.into_iter().zip(rb) {
                let (du, dv) = (q[0] - p[0], q[1] - p[1]);
                // A line along an axis (or no line) is a face of the bounds, planes already.
                if du == 0.0 || dv == 0.0 {
                    continue;
                }
                // Which side of the line through `p` and `q` each corner lies on: all on one.
                let (mut below, mut above) = (false, false);
                for x in all {
                    let s = dv * (x[0] - p[0]) - du * (x[1] - p[1]);
                    below |= s < 0.0;
                    above |= s > 0.0;
                }
                if below && above {
                    continue;
                }
                let sign = if above { -1.0 } else { 1.0 };
                let mut n = DVec3::ZERO;
                (n[u], n[v]) = (sign * dv, -sign * du);
                let n = n / n.length();
                // Through `p` (and `q`): every corner inside, but for rounding far below `tol`.
                let plane = Plane { n, d: n[u] * p[0] + n[v] * p[1] };
                // Corners that project to one point give the same line more than once.
                if !planes.contains(&plane) {
                    planes.push(plane);
                }
            }
        }
        Shaft::with_planes(planes, bounds, tol)
    }

    /// The supporting planes through three of the first [`MAX_POINTS`] of `pts` with all of `pts`
    /// on one side, moved out by `tol`, and the planes of `bounds`.
    fn hull(pts: Vec<DVec3>, bounds: Aabb, tol: f32) -> Shaft {
        let mut planes: Vec<Plane> = Vec::new();
        let found = HullPoints::new(&pts);
        let n = pts.len().min(MAX_POINTS);
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    found.try_plane(i, j, k, &mut planes);
                }
            }
        }
        Shaft::with_planes(planes, bounds, tol)
    }

    /// The shaft of the supporting planes `planes`, moved out by `tol`, and the planes of `bounds`.
    fn with_planes(mut planes: Vec<Plane>, bounds: Aabb, tol: f32) -> Shaft {
        for p in &mut planes {
            p.d += tol as f64;
        }
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = 1.0;
            planes.push(Plane { n: e, d: bounds.max[k] as f64 });
            planes.push(Plane { n: -e, d: -(bounds.min[k] as f64) });
        }
        Shaft { bounds, planes }
    }

    /// False if the box lies entirely outside one of the planes (then nothing in it touches the shaft).
    pub fn may_overlap_box(&self, b: &Aabb) -> bool {
        let c = b.center().as_dvec3();
        let h = (b.size() * 0.5).as_dvec3();
        self.planes.iter().all(|p| p.distance(c) - h.dot(p.n.abs()) <= 0.0)
    }

    /// True if the triangle has a non-empty intersection with the (grown) shaft: Sutherland-Hodgman
    /// clipping of the triangle by every plane (SPEC §4.4 step 3).
    pub fn clips_triangle(&self, tri: &[Vec3; 3]) -> bool {
        // Quick answers first: all vertices beyond one plane (outside), or one vertex inside all.
        let v = tri.map(|p| p.as_dvec3());
        let mut inside = [true; 3];
        for p in &self.planes {
            let d = v.map(|q| p.distance(q));
            if d.iter().all(|&x| x > 0.0) {
                return false;
            }
            for (ins, x) in inside.iter_mut().zip(d) {
                *ins &= x <= 0.0;
            }
        }
        if inside.iter().any(|&i| i) {
            return true;
        }
        // Clipping a convex polygon by a plane adds at most one vertex: a small buffer (cheap to
        // clear) holds every polygon when the shaft has few planes, as it always has in practice.
        if 3 + self.planes.len() <= SMALL_CLIP {
            self.clip_nonempty(tri, &mut [DVec3::ZERO; SMALL_CLIP], &mut [DVec3::ZERO; SMALL_CLIP])
        } else {
            let big = 3 + 2 * MAX_POINTS * MAX_POINTS;
            self.clip_nonempty(tri, &mut vec![DVec3::ZERO; big], &mut vec![DVec3::ZERO; big])
        }
    }

    /// True if `tri` clipped by every plane keeps a point, clipping in the buffers `buf_a`, `buf_b`.
    fn clip_nonempty(&self, tri: &[Vec3; 3], buf_a: &mut [DVec3], buf_b: &mut [DVec3]) -> bool {
        let mut len = 3;
        for (o, v) in buf_a.iter_mut().zip(tri) {
            *o = v.as_dvec3();
        }
        let (mut cur, mut next) = (buf_a, buf_b);
        for p in &self.planes {
            let mut out = 0;
            for i in 0..len {
                let a = cur[i];
                let b = cur[(i + 1) % len];
                let (da, db) = (p.distance(a), p.distance(b));
                // The buffer is full (never for a convex polygon): keep the triangle, conservatively.
                if out + 2 > next.len() {
                    return true;
                }
                if da <= 0.0 {
                    next[out] = a;
                    out += 1;
                }
                if (da <= 0.0) != (db <= 0.0) {
                    let t = da / (da - db);
                    next[out] = a + (b - a) * t;
                    out += 1;
                }
            }
            if out == 0 {
                return false;
            }
            std::mem::swap(&mut cur, &mut next);
            len = out;
        }
        true
    }
}

/// The points of a hull and their scale, for trying candidate planes through three of them.
struct HullPoints<'a> {
    pts: &'a [DVec3],
    scale: f64,
}

impl<'a> HullPoints<'a> {
    fn new(pts: &'a [DVec3]) -> HullPoints<'a> {
        let scale = pts.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element())).max(1e-30);
        HullPoints { pts, scale }
    }

    /// Adds the plane through points `i`, `j`, `k` to `planes`, facing away from the points, if
    /// every point lies on one side of it (within a relative slack, by which it is moved out) and
    /// no plane of `planes` is the same.
    #[inline(always)]
    fn try_plane(&self, i: usize, j: usize, k: usize, planes: &mut Vec<Plane>) {
        let (pts, scale) = (self.pts, self.scale);
        let normal = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
        let len = normal.length();
        if len.is_nan() || len <= 1e-12 * scale * scale {
            return;
        }
        let nn = normal / len;
        let d = nn.dot(pts[i]);
        let slack = 1e-9 * scale;
        let (lo, hi) = pts.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
            let s = nn.dot(*p) - d;
            (lo.min(s), hi.max(s))
        });
        let cand = if hi <= slack {
            Plane { n: nn, d: d + hi.max(0.0) }
        } else if lo >= -slack {
            Plane { n: -nn, d: -d - lo.min(0.0) }
        } else {
            return;
        };
        if !planes.iter().any(|p| p.n.dot(cand.n) > 1.0 - 1e-12 && (p.d - cand.d).abs() <= slack) {
            planes.push(cand);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_face() -> [Vec3; 4] {
        [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 0.0)]
    }

    #[test]
    fn shaft_contains_segments_from_face_to_light_and_excludes_far_points() {
        let light = [Vec3::new(2.0, 5.0, 2.0), Vec3::new(3.0, 5.0, 2.0), Vec3::new(3.0, 5.0, 3.0)];
        let s = Shaft::new(&unit_face(), &light, 1e-5);
        // Segment points from face points to light points are inside every plane.
        for (f, l) in [(unit_face()[0], light[0]), (unit_face()[2], light[1]), (Vec3::new(0.5, 1.0, 0.5), light[2])] {
            for i in 0..=10 {
                let p = (f + (l - f) * (i as f32 / 10.0)).as_dvec3();
                assert!(s.planes.iter().all(|pl| pl.distance(p) <= 1e-9), "{p}");
            }
        }
        // A small triangle far off the shaft is not a blocker; one across it is.
        let off = [Vec3::new(-3.0, 3.0, 3.0), Vec3::new(-2.9, 3.0, 3.0), Vec3::new(-3.0, 3.0, 3.1)];
        assert!(!s.clips_triangle(&off));
        let across = [Vec3::new(-10.0, 3.0, -10.0), Vec3::new(10.0, 3.0, -10.0), Vec3::new(0.0, 3.0, 10.0)];
        assert!(s.clips_triangle(&across));
    }

    #[test]
    fn coplanar_light_gives_a_conservative_flat_shaft() {
        let light = [Vec3::new(3.0, 1.0, 0.0), Vec3::new(4.0, 1.0, 0.0), Vec3::new(4.0, 1.0, 1.0)];
        let s = Shaft::new(&unit_face(), &light, 1e-5);
        let on = [Vec3::new(2.0, 0.5, 0.5), Vec3::new(2.0, 1.5, 0.5), Vec3::new(2.0, 1.0, 0.7)];
        assert!(s.clips_triangle(&on));
    }

    /// A light of 24 vertices (more than `MAX_POINTS` with the face): every vertex, the ones past
    /// the first sixteen points included, lies inside every plane, and so do the segments to them.
    #[test]
    fn a_light_with_many_vertices_stays_inside_its_shaft() {
        let light: Vec<Vec3> = (0..24)
            .map(|k| {
                let a = k as f32 / 24.0 * std::f32::consts::TAU;
                Vec3::new(2.5 + 1.5 * a.cos(), 5.0, 2.5 + 1.5 * a.sin())
            })
            .collect();
        let s = Shaft::new(&unit_face(), &light, 1e-5);
        for f in unit_face() {
            for &l in &light {
                for i in 0..=10 {
                    let p = (f + (l - f) * (i as f32 / 10.0)).as_dvec3();
                    assert!(s.planes.iter().all(|pl| pl.distance(p) <= 1e-5), "{p}");
                }
            }
        }
        // A small blocker on the segment from a face corner to the last vertex is kept.
        let p = unit_face()[0] + (light[23] - unit_face()[0]) * 0.98;
        let near = [p, p + Vec3::new(0.001, 0.0, 0.0), p + Vec3::new(0.0, 0.0, 0.001)];
        assert!(s.clips_triangle(&near));
    }

    /// The two-box shaft has the planes of the general one over the sixteen corners (the same
    /// supporting planes, up to rounding), on random boxes, flat ones among them.
    #[test]
    fn two_box_shaft_has_the_hull_planes() {
        let mut state = 9u64;
        let mut rnd = || {
            state = crate::render::sampler::mix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut boxes = |flat: bool| {
            let p = Vec3::new(rnd(), rnd(), rnd()) * 20.0 - 5.0;
            let mut size = Vec3::new(rnd(), rnd(), rnd()) * 3.0 + 0.01;
            if flat {
                size[(rnd() * 3.0) as usize % 3] = 0.0;
            }
            Aabb { min: p, max: p + size }
        };
        let mut planes = 0;
        for case in 0..500 {
            let (a, b) = (boxes(false), boxes(case % 2 == 0));
            let corners: Vec<Vec3> = a.corners().into_iter().chain(b.corners()).collect();
            let general = Shaft::of_points(&corners[..8], &corners[8..], 1e-4);
            let fast = Shaft::of_boxes(&a, &b, 1e-4);
            let has =
                |s: &Shaft, q: &Plane| s.planes.iter().any(|p| p.n.dot(q.n) > 1.0 - 1e-6 && (p.d - q.d).abs() < 1e-3);
            for q in &general.planes {
                assert!(has(&fast, q), "case {case}: {q:?} missing");
            }
            for q in &fast.planes {
                assert!(has(&general, q), "case {case}: {q:?} extra");
            }
            // Every corner inside every plane (moved out by the tolerance, and no further).
            assert!(corners.iter().all(|c| fast.planes.iter().all(|p| p.distance(c.as_dvec3()) <= 1e-4)));
            planes += fast.planes.len() - 6;
        }
        // Most hulls have slanted facets (else the test would check only the bounds).
        assert!(planes > 1000, "{planes} slanted planes in 500 hulls");
    }
}
