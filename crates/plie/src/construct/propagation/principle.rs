//! The principle of SPEC §4.7 as a direct geometric test: a face `G` of a leaf `X` may be deleted for a
//! light `L` if every segment from `G` to `L` passes through the source cell `C` and leaves it through
//! a face known to be dark.
//!
//! The test is exact up to conservative tolerances (the parent module says why each is there). `G+`
//! is the face grown by `delta` on every axis, `C+` the cell grown by `delta`, and `L+` the light's
//! sampling domain ([`Light::sample_domain`]) grown by `delta` on every axis (the sample points the
//! renderer computes in `f32` lie in it).
//!
//! 1. `L+` is separated from `C` grown by `2 delta` by a plane of the cell's faces or lies in front of
//!    it, so every segment that enters `C+` leaves it again before reaching the light.
//! 2. Every segment from `G+` to `L+` meets `C+`. For a fixed end, the start points whose segment meets
//!    a convex box form a convex set, and so do the ends for a fixed start: checking the 8 corners of
//!    `G+` against the corners of `L+` proves it for all of `G+` and `L+`.
//! 3. Every face of `C+` that such a segment can leave through is dark. A segment can only leave
//!    through a face whose plane some point of `L+` lies beyond, and it only matters if the face is
//!    not entirely behind the light (the shaded point is in front of the one-sided light, so is every
//!    point of its ray but the end). Of the remaining faces, those that the shaft conv(`G+` ∪ `L`)
//!    (supporting planes, grown) does not touch cannot be left through either; every other one must
//!    be dark: every leaf on it computed dark or deleted by propagation with a budget, or behind the
//!    light.
//! 4. Every ray from the target leaf to the light is shorter than the smallest budget of the faces of
//!    step 3 (see [`super::state::dark_budget`]).

use glam::{DVec3, Vec3};

use super::state::{FaceState, FaceStates};
use super::Tolerances;
use crate::construct::data_objects::face_sees_light;
use crate::construct::shaft::Shaft;
use crate::geometry::Aabb;
use crate::octree::{Dir, LeafId, NodeId, Octree};
use crate::scene::{Light, LightId};

/// A light as the principle test sees it: the corners of `L+` and the offset of its frontmost point
/// along the normal.
#[derive(Clone, Debug)]
pub struct LightHull<'a> {
    /// The light.
    pub light: &'a Light,
    /// Corners of the sampling domain grown by `delta` on every axis.
    pub points: Vec<DVec3>,
    /// A point of the light's plane.
    origin: DVec3,
    /// The light's normal.
    normal: DVec3,
    /// Smallest `(p - origin) . normal` over `L+`: a point at most this far along the normal is behind
    /// (or on) the plane of every light point.
    front_min: f64,
}

impl<'a> LightHull<'a> {
    /// The hull of `light` for tolerances `t`.
    pub fn new(light: &'a Light, t: &Tolerances) -> LightHull<'a> {
        let points: Vec<DVec3> = light
            .sample_domain()
            .iter()
            .flat_map(|v| corners(v.as_dvec3() - t.delta, v.as_dvec3() + t.delta))
            .collect();
        let (origin, normal) = (light.vertices[0].as_dvec3(), light.normal.as_dvec3());
        let front_min = points.iter().map(|&p| (p - origin).dot(normal)).fold(f64::INFINITY, f64::min);
        LightHull { light, points, origin, normal, front_min }
    }

    /// True if every point of the box `(lo, hi)` lies at least `margin` behind the planes through every
    /// light point (parallel to the light).
    fn behind(&self, lo: DVec3, hi: DVec3, margin: f64) -> bool {
        corners(lo, hi).iter().all(|&c| (c - self.origin).dot(self.normal) <= self.front_min - margin)
    }
}

/// Whether shadow rays can leave a source cell through one of its faces, and what that face vouches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exit {
    /// No ray that matters leaves through it: no light point beyond it, or it lies behind the light.
    Never,
    /// Dark (every leaf on it): rays shorter than this budget that leave through it are blocked.
    Dark(f64),
    /// Not known to be dark: a target whose shaft touches it cannot be deleted.
    Open,
}

/// A source cell for one light: its box, which faces see the light, and its [`Exit`]s.
#[derive(Clone, Debug)]
pub struct Source {
    /// The node (leaf or inner).
    pub node: NodeId,
    /// Its box.
    pub cell: Aabb,
    /// Faces that see the light (SPEC §4.1 test on the node's face).
    pub lit: [bool; 6],
    /// Per face.
    pub exits: [Exit; 6],
}

/// `b` grown by `d` on every side, in `f64`.
fn grown(b: &Aabb, d: f64) -> (DVec3, DVec3) {
    (b.min.as_dvec3() - d, b.max.as_dvec3() + d)
}

/// The 8 corners of the box `(lo, hi)`.
fn corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// The box of face `face` of `(lo, hi)`: the face square, flat along its axis.
fn face_box(lo: DVec3, hi: DVec3, face: Dir) -> (DVec3, DVec3) {
    let k = face.axis();
    let (mut a, mut b) = (lo, hi);
    let w = if face.is_positive() { hi[k] } else { lo[k] };
    a[k] = w;
    b[k] = w;
    (a, b)
}

/// True if the segment `a -> b` meets the closed box `(lo, hi)` (slab test in `f64`).
pub fn segment_meets_box(a: DVec3, b: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (ta, tb) = ((lo[k] - a[k]) / d, (hi[k] - a[k]) / d);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
        if t0 > t1 {
            return false;
        }
    }
    true
}

impl Source {
    /// The source `node` for a light, or `None` when the light is not separated from the node's box
    /// (step 1: then a segment may end inside the cell).
    pub fn new(
        octree: &Octree,
        states: &FaceStates,
        node: NodeId,
        light_id: LightId,
        hull: &LightHull,
        t: &Tolerances,
        leaves: &mut Vec<LeafId>,
    ) -> Option<Source> {
        let cell = octree.node_bounds(node);
        let half_tol = 0.5 * t.tol as f64;
        let (lo2, hi2) = grown(&cell, 2.0 * t.delta);
        let pts = &hull.points;
        let separated = (0..3).any(|k| pts.iter().all(|v| v[k] > hi2[k]) || pts.iter().all(|v| v[k] < lo2[k]))
            || hull.behind(lo2, hi2, half_tol);
        if !separated {
            return None;
        }
        let (lo, hi) = grown(&cell, t.delta);
        let mut lit = [false; 6];
        let mut exits = [Exit::Never; 6];
        for face in Dir::ALL {
            let f = face.index();
            lit[f] = face_sees_light(&face.face_corners(&cell), face.normal(), hull.light, t.tol);
            let k = face.axis();
            let beyond = |v: &DVec3| if face.is_positive() { v[k] > hi[k] } else { v[k] < lo[k] };
            let (flo, fhi) = face_box(lo, hi, face);
            if !pts.iter().any(beyond) || hull.behind(flo, fhi, half_tol) {
                continue;
            }
            leaves.clear();
            octree.leaves_on_face(node, face, leaves);
            let mut budget = f64::INFINITY;
            for &leaf in leaves.iter() {
                let state = states.get(leaf, face, light_id);
                let leaf_budget = match state.vouches() {
                    Some(b) => b,
                    // Cannot see the light: then no ray that matters crosses it if it lies behind it.
                    None if state == FaceState::NoLight => {
                        let (a, b) = grown(&octree.leaf_bounds(leaf), t.delta);
                        let (a, b) = face_box(a, b, face);
                        if hull.behind(a - t.delta, b + t.delta, half_tol) {
                            f64::INFINITY
                        } else {
                            -1.0
                        }
                    }
                    None => -1.0,
                };
                budget = budget.min(leaf_budget);
                if budget <= 0.0 {
                    break;
                }
            }
            exits[f] = if budget > 0.0 { Exit::Dark(budget) } else { Exit::Open };
        }
        Some(Source { node, cell, lit, exits })
    }

    /// True if face `f` sees the light and is known to be dark (or never left through).
    pub fn dark(&self, f: Dir) -> bool {
        self.lit[f.index()] && self.exits[f.index()] != Exit::Open
    }

    /// True if some face that sees the light is dark: the parent may have a dark face too.
    pub fn any_dark(&self) -> bool {
        Dir::ALL.into_iter().any(|f| self.lit[f.index()] && matches!(self.exits[f.index()], Exit::Dark(_)))
    }

    /// The principle test (steps 2-4 of the module doc) for face `face` of the leaf box `target`:
    /// `Some(budget)` if every shadow ray from the target leaf that passes within `delta` of that face
    /// toward the light is blocked (the rays are shorter than `budget`, which is what the deleted face
    /// vouches for in turn).
    pub fn vouches_for(&self, target: &Aabb, face: Dir, hull: &LightHull, t: &Tolerances) -> Option<f64> {
        let delta = t.delta;
        // Step 2: every segment from G+ to L+ meets C+.
        let (tlo, thi) = (target.min.as_dvec3(), target.max.as_dvec3());
        let (glo, ghi) = face_box(tlo, thi, face);
        let g_corners = corners(glo - delta, ghi + delta);
        let (lo, hi) = grown(&self.cell, delta);
        if !g_corners.iter().all(|&p| hull.points.iter().all(|&v| segment_meets_box(p, v, lo, hi))) {
            return None;
        }
        // Step 3: the faces of C+ the shaft conv(G+ ∪ L+) touches must be dark.
        let k = face.axis();
        let mut g_face = *target;
        for a in (0..3).filter(|&a| a != k) {
            g_face.min[a] -= 2.0 * delta as f32;
            g_face.max[a] += 2.0 * delta as f32;
        }
        let shaft = Shaft::new(&face.face_corners(&g_face), &hull.light.sample_domain(), t.tol + 4.0 * delta as f32);
        let c_plus = Aabb::new(lo.as_vec3(), hi.as_vec3());
        let mut budget = f64::INFINITY;
        for f in Dir::ALL {
            let b = match self.exits[f.index()] {
                Exit::Never => continue,
                Exit::Dark(b) => Some(b),
                Exit::Open => None,
            };
            let q: [Vec3; 4] = f.face_corners(&c_plus);
            if !shaft.clips_triangle(&[q[0], q[1], q[2]]) && !shaft.clips_triangle(&[q[0], q[2], q[3]]) {
                continue;
            }
            budget = budget.min(b?);
        }
        // Step 4: every ray from the target leaf to the light is shorter than the budget.
        let reach = corners(tlo - delta, thi + delta)
            .iter()
            .flat_map(|&x| hull.points.iter().map(move |&v| (v - x).length()))
            .fold(0.0f64, f64::max);
        (reach < budget).then_some(budget)
    }
}
