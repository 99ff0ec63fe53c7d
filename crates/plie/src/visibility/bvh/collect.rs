//! The triangles of the scene BVH inside a shaft (issue 21): a walk from a cut ([`super::cut`]) that
//! keeps the children whose boxes may meet every plane of a convex region, and hands their
//! triangles to the caller. The per-light query of the P-LIE modes gathers with it, once, the
//! triangles that may block any segment from a piece of a shaded triangle to a light
//! ([`crate::visibility::lie`]'s shafts).

use glam::DVec3;

use super::crowd::{Prims, Single};
use super::cut::{Child, Cut};
use super::{Bvh, PAD};
use crate::construct::shaft::Plane;
use crate::scene::TriId;

impl Bvh {
    /// Calls `f` with every triangle under `cut` (or under the root) whose BVH boxes meet the
    /// half-spaces `n . p <= d` of all of `planes` (world units), until `f` returns false. Returns
    /// false if `f` stopped it. Boxes are kept if, grown by twice the BVH's padding, they are not
    /// wholly beyond a plane, so every triangle that meets the region is handed to `f` (some that do
    /// not may be too: the caller decides each).
    pub(crate) fn collect_in(&self, cut: Option<&Cut>, planes: &[Plane], f: impl FnMut(TriId) -> bool) -> bool {
        match &self.groups {
            None => self.collect_with(&Single, cut, planes, f),
            Some(g) => self.collect_with(g, cut, planes, f),
        }
    }

    fn collect_with<P: Prims>(
        &self,
        prims: &P,
        cut: Option<&Cut>,
        planes: &[Plane],
        mut f: impl FnMut(TriId) -> bool,
    ) -> bool {
        if self.cw.nodes.is_empty() {
            return true;
        }
        // As `cut_of`: a box of centre `c` and half-size `h` (normalised units), grown by twice the
        // padding, may meet `n . p <= d` if `n . c - |n| . h + k <= 0`.
        let (origin, scale) = (self.origin.as_dvec3(), f64::from(self.scale));
        let planes: Vec<(DVec3, DVec3, f64)> = planes
            .iter()
            .map(|p| (p.n, p.n.abs(), (p.n.dot(origin) - p.d) * scale - 2.0 * f64::from(PAD) * p.n.abs().element_sum()))
            .collect();
        let keep = |lo: glam::Vec3, hi: glam::Vec3| {
            let (c, h) = (((lo + hi) * 0.5).as_dvec3(), ((hi - lo) * 0.5).as_dvec3());
            planes.iter().all(|(n, a, k)| n.dot(c) - a.dot(h) + k <= 0.0)
        };
        let mut todo: Vec<Child> = Vec::new();
        match cut {
            None => todo.push(Child::Node(0)),
            Some(cut) => {
                for e in 0..cut.len as usize {
                    let lo = glam::Vec3::new(cut.lo[0][e], cut.lo[1][e], cut.lo[2][e]);
                    let hi = glam::Vec3::new(cut.hi[0][e], cut.hi[1][e], cut.hi[2][e]);
                    if keep(lo, hi) {
                        todo.push(cut.child[e]);
                    }
                }
            }
        }
        while let Some(c) = todo.pop() {
            match c {
                Child::None => {}
                Child::Leaf(start, len) => {
                    for p in start..start + len {
                        for &t in prims.of(&self.cw.primitive_indices[p as usize]) {
                            if !f(TriId(t)) {
                                return false;
                            }
                        }
                    }
                }
                Child::Node(n) => {
                    let node = &self.cw.nodes[n as usize];
                    for k in 0..8 {
                        if node.child_meta[k] == 0 {
                            continue;
                        }
                        let (lo, hi) = self.child_box(n, k);
                        if keep(lo, hi) {
                            todo.push(Child::of(node, k));
                        }
                    }
                }
            }
        }
        true
    }
}
