//! Splitting chosen leaves of a built octree (SPEC §4.8: refinement, thesis §5.8).
//!
//! [`Octree::split_leaves`] turns each chosen leaf into an inner node with 8 new leaf children whose
//! triangles are assigned exactly as [`Octree::build`] assigns them, so the refined tree obeys every
//! invariant of the module doc ([`Octree::validate`] checks them). The new child blocks are appended
//! after the existing nodes, so every existing [`NodeId`] keeps its meaning and the refinement of a
//! tree is reproduced from the list of split nodes alone ([`Octree::split_nodes`], used when a `.plie`
//! file is loaded).
//!
//! Leaves are renumbered: the leaves that stay keep their relative order, the children of the split
//! leaves follow (by split order, then octant). The returned map tells, for every new leaf, the old
//! leaf it is (`None` for a new child), so the P-LIE construction reuses the records of kept leaves.

use rayon::prelude::*;

use super::build::split_cell;
use super::{LeafId, NodeId, Octree, MAX_DEPTH_LIMIT};
use crate::error::{Error, Result};
use crate::scene::Scene;

impl Octree {
    /// True if `l` may be split once more: its children would be at depth `<= MAX_DEPTH_LIMIT`.
    pub fn can_split(&self, l: LeafId) -> bool {
        self.leaf_depth(l) < MAX_DEPTH_LIMIT
    }

    /// The octree with each leaf of `split` (distinct, ascending, each [`Octree::can_split`]) split into
    /// 8 children, and for every leaf of the new tree the leaf of `self` it is (`None` for the new
    /// children). Deterministic for any number of threads.
    ///
    /// # Panics
    /// If `split` is not ascending and distinct, or names a leaf that cannot be split (callers choose
    /// the leaves themselves; [`Octree::split_nodes`] checks file input first).
    pub fn split_leaves(&self, scene: &Scene, split: &[LeafId]) -> (Octree, Vec<Option<LeafId>>) {
        assert!(split.windows(2).all(|w| w[0] < w[1]), "split_leaves: leaves must be ascending and distinct");
        assert!(split.iter().all(|&l| self.can_split(l)), "split_leaves: a leaf is at the depth limit");
        let parts: Vec<_> = split
            .par_iter()
            .map(|&l| split_cell(scene, self.leaf_triangles(l), &self.leaf_bounds(l), self.eps))
            .collect();
        let mut t = Octree {
            nodes: self.nodes.clone(),
            node_bounds: self.node_bounds.clone(),
            parents: self.parents.clone(),
            leaves: Vec::with_capacity(self.leaves.len() + 7 * split.len()),
            leaf_tris: Vec::with_capacity(self.leaf_tris.len()),
            eps: self.eps,
            params: self.params,
            depth: 0,
            scene_triangles: self.scene_triangles,
            capped: self.capped,
            built_nodes: self.built_nodes,
        };
        let mut origin = Vec::with_capacity(t.leaves.capacity());
        let mut next = split.iter().peekable();
        for l in self.leaves() {
            if next.peek() == Some(&&l) {
                next.next();
                continue;
            }
            let old = &self.leaves[l.idx()];
            t.push_leaf(old.node, old.depth, self.leaf_triangles(l));
            origin.push(Some(l));
        }
        for (&l, children) in split.iter().zip(parts) {
            let old = self.leaves[l.idx()];
            let first = t.push_children(old.node);
            for (i, tris) in children.iter().enumerate() {
                t.push_leaf(first + i as u32, old.depth + 1, tris);
                origin.push(None);
            }
        }
        (t, origin)
    }

    /// Splits the leaves at the nodes `nodes` (as [`Octree::split_leaves`], in the given order), checking
    /// that each is a leaf that can be split: the refinement stored in a `.plie` file is replayed with
    /// this, so a bad list is an error, not a panic.
    pub fn split_nodes(&self, scene: &Scene, nodes: &[u32]) -> Result<Octree> {
        let mut leaves = Vec::with_capacity(nodes.len());
        for &n in nodes {
            let leaf = (n < self.nodes.len() as u32)
                .then(|| self.node_leaf(NodeId(n)))
                .flatten()
                .filter(|&l| self.can_split(l))
                .ok_or_else(|| {
                    Error::InvalidParameter(format!("refinement splits node {n}, not a leaf that can be split"))
                })?;
            leaves.push(leaf);
        }
        if !leaves.windows(2).all(|w| w[0] < w[1]) {
            return Err(Error::InvalidParameter("refinement split list is not in leaf order".into()));
        }
        Ok(self.split_leaves(scene, &leaves).0)
    }
}

#[cfg(test)]
mod tests {
    use crate::octree::{Octree, OctreeParams};
    use crate::scene::builtin;

    #[test]
    fn split_keeps_invariants_and_maps_leaves() {
        let s = builtin::load("cornell-cube-2").unwrap();
        let o = Octree::build(&s, OctreeParams::thesis()).expect("valid octree parameters");
        let split: Vec<_> = o.leaves().filter(|l| l.0 % 3 == 0).collect();
        let (r, origin) = o.split_leaves(&s, &split);
        assert_eq!(r.leaf_count(), o.leaf_count() + 7 * split.len());
        assert!(r.validate(&s).violations.is_empty(), "{:?}", r.validate(&s).violations);
        for (i, from) in origin.iter().enumerate() {
            let l = crate::octree::LeafId(i as u32);
            match from {
                Some(old) => {
                    assert_eq!(r.leaf_bounds(l), o.leaf_bounds(*old));
                    assert_eq!(r.leaf_triangles(l), o.leaf_triangles(*old));
                    assert!(!split.contains(old));
                }
                None => assert_eq!(r.leaf_depth(l), 2),
            }
        }
        // Replaying from node ids gives the same tree.
        let nodes: Vec<u32> = split.iter().map(|&l| o.leaf_node(l).0).collect();
        assert_eq!(o.split_nodes(&s, &nodes).unwrap(), r);
        // A node that is not a leaf any more is refused.
        assert!(r.split_nodes(&s, &nodes[..1]).is_err());
        assert!(r.split_nodes(&s, &[u32::MAX]).is_err());
    }
}
