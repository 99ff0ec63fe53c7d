//! The triangles of the scene BVH inside a shaft (issue 21): a walk from a cut ([`super::cut`]) that
//! keeps the children whose boxes may meet every plane of a convex region, and hands their
//! triangles to the caller. The per-light query of the P-LIE modes gathers with it, once, the
//! triangles that may block any segment from a piece of a shaded triangle to a light
//! ([`crate::visibility::lie`]'s shafts).

use super::crowd::{Prims, Single};
use super::cut::{Child, Cut, LocalPlane};
use super::Bvh;
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
        let planes: Vec<LocalPlane> = planes.iter().map(|p| self.local_plane(p)).collect();
        let keep = |lo, hi| LocalPlane::all_may_meet(&planes, lo, hi);
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
