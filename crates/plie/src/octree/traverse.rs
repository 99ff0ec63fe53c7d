//! Octree traversal (SPEC §3 queries, SPEC §5 mode (a)): the leaves along a segment, front to back,
//! and the leaves overlapping a box.
//!
//! Both queries are **conservative**: they work on cell boxes grown by [`Octree::eps`], the same
//! tolerance the triangle assignment uses. A segment therefore visits every leaf whose closed box it
//! touches, including segments lying in a cell's face plane, running along an edge, starting on a
//! corner or having zero direction components; leaves it passes within `eps` of are visited too.
//!
//! The slab test is [`Segment::clip`], which treats axes with a non-finite inverse direction as
//! coordinate intervals. Rounding in the slab test is a few `f32` ulps of the coordinates, far below
//! `eps` (see [`super::build::tolerance`]).
//!
//! Both walks use a fixed-size stack on the call stack; nothing is allocated.

use glam::Vec3;

use super::{LeafId, NodeKind, Octree, MAX_DEPTH_LIMIT};
use crate::geometry::{Aabb, Segment};

/// Stack capacity: each inner level leaves at most 7 siblings behind, plus the 8 of the deepest level.
const STACK: usize = 8 * (MAX_DEPTH_LIMIT as usize + 1);

impl Octree {
    /// Visits, front to back, every leaf whose box grown by [`Octree::eps`] the segment
    /// `origin + t * dir`, `t` in `[t_min, t_max]`, touches; stops as soon as `f` returns `false`.
    ///
    /// Order: the children of a cell are visited by increasing entry parameter (ties by child index),
    /// depth first, so leaves come in the order the segment enters them, up to the `eps` overlap of
    /// neighbouring grown boxes. Nothing is visited if `t_min > t_max` or either is NaN. A zero `dir`
    /// visits the leaves around the point `origin`.
    pub fn for_each_leaf_on_segment(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        mut f: impl FnMut(LeafId) -> bool,
    ) {
        if t_min.is_nan() || t_max.is_nan() || t_min > t_max {
            return;
        }
        let seg = Segment::new(origin, dir, t_min, t_max);
        let eps = self.eps;
        if seg.clip(&self.node_bounds[0].expanded(eps)).is_none() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = stack[sp] as usize;
            match self.nodes[node].kind() {
                NodeKind::Leaf(l) => {
                    if !f(l) {
                        return;
                    }
                }
                NodeKind::Inner(first) => {
                    // Children touched, kept sorted by decreasing entry parameter.
                    let mut hit = [(0.0f32, 0u32); 8];
                    let mut n = 0;
                    for c in first..first + 8 {
                        if let Some((t0, _)) = seg.clip(&self.node_bounds[c as usize].expanded(eps)) {
                            let mut j = n;
                            while j > 0 && hit[j - 1].0 < t0 {
                                hit[j] = hit[j - 1];
                                j -= 1;
                            }
                            hit[j] = (t0, c);
                            n += 1;
                        }
                    }
                    // Pushed in decreasing order: the nearest child ends on top.
                    for &(_, c) in &hit[..n] {
                        stack[sp] = c;
                        sp += 1;
                    }
                }
            }
        }
    }

    /// Visits every leaf whose box grown by [`Octree::eps`] overlaps the closed box `b` (touching
    /// counts), depth first in child order.
    pub fn for_each_leaf_overlapping(&self, b: &Aabb, mut f: impl FnMut(LeafId)) {
        let eps = self.eps;
        if !self.node_bounds[0].expanded(eps).overlaps(b) {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = stack[sp] as usize;
            match self.nodes[node].kind() {
                NodeKind::Leaf(l) => f(l),
                NodeKind::Inner(first) => {
                    for c in (first..first + 8).rev() {
                        if self.node_bounds[c as usize].expanded(eps).overlaps(b) {
                            stack[sp] = c;
                            sp += 1;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};

    use super::*;
    use crate::octree::OctreeParams;
    use crate::{Scene, SceneBuilder};

    /// A scene whose octree is several levels deep around the origin's corner of the room.
    fn scene() -> Scene {
        let mut b = SceneBuilder::new("grid");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        for i in 0..12 {
            for j in 0..12 {
                let p = Vec3::new(i as f32 * 0.1, j as f32 * 0.1, 0.05 * (i + j) as f32 % 0.3);
                b.triangle(p, p + Vec3::new(0.08, 0.0, 0.0), p + Vec3::new(0.0, 0.08, 0.02), m);
            }
        }
        b.quad(
            Vec3::new(-4.0, -4.0, -4.0),
            Vec3::new(4.0, -4.0, -4.0),
            Vec3::new(4.0, 4.0, -4.0),
            Vec3::new(-4.0, 4.0, -4.0),
            m,
        );
        b.light("l", &[Vec3::new(0.0, 4.0, 0.0), Vec3::new(0.5, 4.0, 0.0), Vec3::new(0.5, 4.0, 0.5)], Vec3::ONE);
        b.build().expect("valid scene")
    }

    /// Reference in f64: does the segment touch the closed box? Zero components handled explicitly.
    fn touches(o: Vec3, d: Vec3, t0: f32, t1: f32, b: &Aabb) -> bool {
        let (o, d) = (o.as_dvec3(), d.as_dvec3());
        let (mut lo, mut hi) = (t0 as f64, t1 as f64);
        let (bmin, bmax): (DVec3, DVec3) = (b.min.as_dvec3(), b.max.as_dvec3());
        for k in 0..3 {
            if d[k] == 0.0 {
                if o[k] < bmin[k] || o[k] > bmax[k] {
                    return false;
                }
            } else {
                let a = (bmin[k] - o[k]) / d[k];
                let c = (bmax[k] - o[k]) / d[k];
                lo = lo.max(a.min(c));
                hi = hi.min(a.max(c));
            }
        }
        lo <= hi
    }

    fn check(o: &Octree, p: Vec3, d: Vec3, t0: f32, t1: f32) {
        let mut seen = Vec::new();
        o.for_each_leaf_on_segment(p, d, t0, t1, |l| {
            seen.push(l);
            true
        });
        let mut sorted = seen.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), seen.len(), "a leaf visited twice");
        for l in o.leaves() {
            let b = o.leaf_bounds(l);
            if touches(p, d, t0, t1, &b) {
                assert!(seen.contains(&l), "segment {p} + t {d} misses leaf {l:?} {b:?}");
            }
            if seen.contains(&l) {
                assert!(touches(p, d, t0, t1, &b.expanded(2.0 * o.eps())), "leaf {l:?} visited needlessly");
            }
        }
    }

    #[test]
    fn degenerate_directions_and_boundaries() {
        let s = scene();
        let o = Octree::build(&s, OctreeParams { max_triangles: 4, max_depth: 6 }).expect("valid octree parameters");
        assert!(o.depth() >= 4);
        for l in o.leaves().step_by(7) {
            let b = o.leaf_bounds(l);
            let (lo, hi) = (b.min, b.max);
            // In a face plane, along an edge, from a corner, axis-parallel, diagonal, zero length.
            check(&o, lo, Vec3::new(hi.x - lo.x, hi.y - lo.y, 0.0) * 3.0, 0.0, 1.0);
            check(&o, lo, Vec3::new(1.0, 0.0, 0.0), -2.0, 2.0);
            check(&o, lo, Vec3::new(0.0, 0.0, -1.0), 0.0, 5.0);
            check(&o, hi, lo - hi, 0.0, 1.0);
            check(&o, hi, (lo - hi) * Vec3::new(1.0, 1.0, 0.0), 0.0, 10.0);
            check(&o, b.center(), Vec3::ZERO, 0.0, 1.0);
            check(&o, lo, Vec3::ZERO, 0.0, 1.0);
            check(&o, lo, Vec3::new(1e-40, 1.0, 0.0), -1.0, 1.0);
        }
    }

    #[test]
    fn segment_in_the_plane_of_a_box_face_touches_it() {
        // Origin exactly on the face plane and a zero component: the slab formula gives 0 * inf = NaN.
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        for (o, d) in [
            (Vec3::new(0.0, -1.0, 0.5), Vec3::new(0.0, 1.0, 0.0)),
            (Vec3::new(1.0, 0.5, 0.5), Vec3::new(0.0, 0.0, -1.0)),
            (Vec3::new(1.0, 1.0, -2.0), Vec3::new(0.0, 0.0, 1.0)),
            (Vec3::new(0.0, 0.0, 0.0), Vec3::ZERO),
        ] {
            assert!(Segment::new(o, d, 0.0, 4.0).clip(&b).is_some(), "{o} + t {d}");
        }
        assert!(Segment::new(Vec3::new(-1e-3, -1.0, 0.5), Vec3::Y, 0.0, 4.0).clip(&b).is_none());
        assert!(Segment::new(Vec3::new(1.0, 1.0 + 1e-3, 0.5), Vec3::Z, -4.0, 4.0).clip(&b).is_none());
        // The same through the octree: a segment in the plane of a grown leaf box visits that leaf.
        let s = scene();
        let o = Octree::build(&s, OctreeParams { max_triangles: 4, max_depth: 6 }).expect("valid octree parameters");
        for l in o.leaves() {
            let g = o.leaf_bounds(l).expanded(o.eps());
            let p = Vec3::new(g.min.x, g.center().y, g.max.z);
            let mut found = false;
            o.for_each_leaf_on_segment(p, Vec3::Y, -1.0, 1.0, |m| {
                found |= m == l;
                !found
            });
            assert!(found, "leaf {l:?}");
        }
    }

    #[test]
    fn outside_and_empty_ranges() {
        let s = scene();
        let o = Octree::build(&s, OctreeParams::default()).expect("valid octree parameters");
        let r = o.root_bounds();
        let mut n = 0;
        o.for_each_leaf_on_segment(r.max + Vec3::ONE, Vec3::ONE, 0.0, 1.0, |_| {
            n += 1;
            true
        });
        o.for_each_leaf_on_segment(r.center(), Vec3::ONE, 1.0, 0.0, |_| {
            n += 1;
            true
        });
        o.for_each_leaf_on_segment(r.center(), Vec3::ONE, f32::NAN, 1.0, |_| {
            n += 1;
            true
        });
        assert_eq!(n, 0);
        // Stopping early.
        o.for_each_leaf_on_segment(r.min, r.size(), 0.0, 1.0, |_| {
            n += 1;
            false
        });
        assert_eq!(n, 1);
    }

    #[test]
    fn overlapping_box_matches_brute_force() {
        let s = scene();
        let o = Octree::build(&s, OctreeParams { max_triangles: 4, max_depth: 6 }).expect("valid octree parameters");
        for l in o.leaves().step_by(5) {
            let q = o.leaf_bounds(l);
            let q = Aabb::new(q.min, q.min + q.size() * 1.7);
            let mut got = Vec::new();
            o.for_each_leaf_overlapping(&q, |m| got.push(m));
            got.sort();
            let want: Vec<_> = o.leaves().filter(|&m| o.leaf_bounds(m).expanded(o.eps()).overlaps(&q)).collect();
            assert_eq!(got, want);
        }
    }
}
