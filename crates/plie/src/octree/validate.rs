//! The octree's invariant report (SPEC §3; STYLE: `validate()` returns counts and violations that
//! tests run after every stage and `plie inspect` can print).
//!
//! Checked, independently of the build code:
//! - structure: node links in range, parent links matching them, every node and leaf reached exactly
//!   once from the root, root split, stored boxes equal to the boxes recomputed top-down, stored depths right;
//! - ranges: every leaf's range lies in the flat list, ranges are disjoint and cover it, triangle ids
//!   exist and each list is strictly ascending;
//! - size: no leaf over `max_triangles` unless at `max_depth` (or the node cap stopped the build), exact
//!   copies and the triangles around a hub counted once as the build counts them (`hubs`), and a
//!   leaf of refinement judged as the build's leaf it lies in;
//! - assignment: for every triangle, the leaves it is listed in are exactly the leaves whose box grown
//!   by `eps` it overlaps by [`triangle_overlaps_box`]. Candidates come from
//!   [`Octree::for_each_leaf_overlapping`] on the triangle's bounding box, so the check costs about
//!   one octree descent per triangle (parallel over triangles), not leaves x triangles.

use std::fmt;

use rayon::prelude::*;

use super::hubs::SplitCount;
use super::{child_box, LeafId, NodeKind, Octree};
use crate::geometry::triangle_overlaps_box;
use crate::scene::{Scene, TriId};

/// At most this many violations are listed (the count is always complete).
pub const MAX_LISTED_VIOLATIONS: usize = 1000;

/// One broken invariant.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Violation {
    /// A leaf holds more than `max_triangles` triangles but is not at `max_depth`.
    Overfull {
        /// The leaf.
        leaf: LeafId,
        /// Its triangle count.
        triangles: usize,
        /// Its depth.
        depth: u32,
    },
    /// A triangle overlaps the leaf's grown box but is not in its list.
    MissingTriangle {
        /// The leaf.
        leaf: LeafId,
        /// The triangle.
        tri: TriId,
    },
    /// A triangle is in the leaf's list but does not overlap its grown box.
    ExtraTriangle {
        /// The leaf.
        leaf: LeafId,
        /// The triangle.
        tri: TriId,
    },
    /// A leaf's triangle range is out of bounds, overlaps another or leaves a gap.
    BadRange {
        /// The leaf.
        leaf: LeafId,
        /// Range start.
        start: u32,
        /// Range end.
        end: u32,
    },
    /// A leaf's list has an unknown triangle id or is not strictly ascending.
    BadList {
        /// The leaf.
        leaf: LeafId,
    },
    /// The node/leaf structure is broken (links, boxes, depths).
    Structure(String),
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Violation::Overfull { leaf, triangles, depth } => {
                write!(f, "leaf {} has {triangles} triangles at depth {depth} (below max depth)", leaf.0)
            }
            Violation::MissingTriangle { leaf, tri } => {
                write!(f, "triangle {} overlaps leaf {} but is not listed", tri.0, leaf.0)
            }
            Violation::ExtraTriangle { leaf, tri } => {
                write!(f, "triangle {} is listed in leaf {} but does not overlap it", tri.0, leaf.0)
            }
            Violation::BadRange { leaf, start, end } => write!(f, "leaf {} has bad range {start}..{end}", leaf.0),
            Violation::BadList { leaf } => write!(f, "leaf {} has an unknown or unsorted triangle list", leaf.0),
            Violation::Structure(m) => write!(f, "structure: {m}"),
        }
    }
}

/// Counts and violations of an octree.
#[derive(Clone, Debug, PartialEq)]
pub struct OctreeReport {
    /// Number of leaves.
    pub leaves: usize,
    /// Number of nodes (inner and leaf).
    pub nodes: usize,
    /// Deepest leaf.
    pub depth: u32,
    /// Total (leaf, triangle) references.
    pub triangle_refs: usize,
    /// Largest leaf list.
    pub max_triangles_per_leaf: usize,
    /// Mean leaf list length.
    pub mean_triangles_per_leaf: f64,
    /// Leaves with no triangles.
    pub empty_leaves: usize,
    /// Bytes used.
    pub memory_bytes: usize,
    /// Total number of violations found.
    pub violation_count: usize,
    /// The first [`MAX_LISTED_VIOLATIONS`] violations.
    pub violations: Vec<Violation>,
}

impl OctreeReport {
    /// True if no invariant is broken.
    pub fn is_ok(&self) -> bool {
        self.violation_count == 0
    }
}

impl fmt::Display for OctreeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "octree: {} leaves, {} nodes, depth {}, {} triangle refs, max {} / mean {:.1} per leaf, {} empty, {} bytes",
            self.leaves,
            self.nodes,
            self.depth,
            self.triangle_refs,
            self.max_triangles_per_leaf,
            self.mean_triangles_per_leaf,
            self.empty_leaves,
            self.memory_bytes
        )?;
        writeln!(f, "{} violations", self.violation_count)?;
        for v in &self.violations {
            writeln!(f, "  {v}")?;
        }
        Ok(())
    }
}

impl Octree {
    /// Checks every invariant listed in the module doc against `scene` (the scene the octree was
    /// built from) and returns counts and violations.
    pub fn validate(&self, scene: &Scene) -> OctreeReport {
        let mut v = Vec::new();
        if scene.triangles.len() != self.scene_triangles {
            v.push(Violation::Structure(format!(
                "built for {} triangles, scene has {}",
                self.scene_triangles,
                scene.triangles.len()
            )));
        }
        self.check_structure(&mut v);
        self.check_ranges(scene, &mut v);
        // The assignment and size checks need sound lists and links.
        if v.is_empty() {
            v.extend(self.check_assignment(scene));
            self.check_sizes(scene, &mut v);
        }
        // From the ranges alone: they may be broken.
        let sizes = self.leaves.iter().map(|l| l.end.saturating_sub(l.start) as usize);
        let violation_count = v.len();
        v.truncate(MAX_LISTED_VIOLATIONS);
        OctreeReport {
            leaves: self.leaf_count(),
            nodes: self.node_count(),
            depth: self.depth,
            triangle_refs: self.leaf_tris.len(),
            max_triangles_per_leaf: sizes.clone().max().unwrap_or(0),
            mean_triangles_per_leaf: self.leaf_tris.len() as f64 / self.leaf_count().max(1) as f64,
            empty_leaves: sizes.filter(|&n| n == 0).count(),
            memory_bytes: self.memory_bytes(),
            violation_count,
            violations: v,
        }
    }

    /// Walks the nodes from the root, recomputing boxes and depths.
    fn check_structure(&self, v: &mut Vec<Violation>) {
        let mut bad = |m: String| v.push(Violation::Structure(m));
        if self.nodes.len() != self.node_bounds.len() {
            bad(format!("{} nodes but {} node boxes", self.nodes.len(), self.node_bounds.len()));
            return;
        }
        if self.parents.len() != self.nodes.len().saturating_sub(1) / 8 {
            bad(format!("{} nodes but {} parent links", self.nodes.len(), self.parents.len()));
            return;
        }
        if !matches!(self.nodes.first().map(|n| n.kind()), Some(NodeKind::Inner(_))) {
            bad("the root is not split".into());
            return;
        }
        let mut node_seen = vec![false; self.nodes.len()];
        let mut leaf_seen = vec![false; self.leaves.len()];
        let mut stack = vec![(0usize, self.node_bounds[0], 0u32)];
        let mut max_depth = 0;
        while let Some((n, b, depth)) = stack.pop() {
            if std::mem::replace(&mut node_seen[n], true) {
                bad(format!("node {n} reached twice"));
                continue;
            }
            if self.node_bounds[n] != b {
                bad(format!("node {n} has box {:?}, expected {b:?}", self.node_bounds[n]));
            }
            match self.nodes[n].kind() {
                NodeKind::Inner(first) if first as usize + 8 <= self.nodes.len() && first as usize > n => {
                    let block = (first as usize - 1) / 8;
                    if (first - 1) % 8 != 0 || self.parents[block] as usize != n {
                        bad(format!("node {n}: children {first}.. not a block whose parent link is {n}"));
                    }
                    for i in 0..8 {
                        stack.push((first as usize + i, child_box(&b, i), depth + 1));
                    }
                }
                NodeKind::Inner(first) => bad(format!("node {n} links to children {first}.. out of order or range")),
                NodeKind::Leaf(l) => match self.leaves.get(l.idx()) {
                    None => bad(format!("node {n} links to missing leaf {}", l.0)),
                    Some(leaf) => {
                        if std::mem::replace(&mut leaf_seen[l.idx()], true) {
                            bad(format!("leaf {} reached twice", l.0));
                        }
                        if leaf.node as usize != n || leaf.depth != depth {
                            bad(format!(
                                "leaf {} says node {} depth {}, is node {n} depth {depth}",
                                l.0, leaf.node, leaf.depth
                            ));
                        }
                        max_depth = max_depth.max(depth);
                    }
                },
            }
        }
        if let Some(n) = node_seen.iter().position(|&s| !s) {
            bad(format!("node {n} is unreachable"));
        }
        if let Some(l) = leaf_seen.iter().position(|&s| !s) {
            bad(format!("leaf {l} is unreachable"));
        }
        if max_depth != self.depth {
            bad(format!("depth is {} but the deepest leaf is at {max_depth}", self.depth));
        }
    }

    /// Ranges tile `leaf_tris` in leaf order; lists are strictly ascending and name real triangles.
    fn check_ranges(&self, scene: &Scene, v: &mut Vec<Violation>) {
        let mut ok = true;
        let mut expect = 0u32;
        for (i, leaf) in self.leaves.iter().enumerate() {
            let id = LeafId(i as u32);
            if leaf.start != expect || leaf.end < leaf.start || leaf.end as usize > self.leaf_tris.len() {
                v.push(Violation::BadRange { leaf: id, start: leaf.start, end: leaf.end });
                ok = false;
                continue;
            }
            expect = leaf.end;
            let list = &self.leaf_tris[leaf.start as usize..leaf.end as usize];
            let known = list.iter().all(|t| t.idx() < scene.triangles.len());
            if !known || !list.windows(2).all(|w| w[0] < w[1]) {
                v.push(Violation::BadList { leaf: id });
                ok = false;
            }
        }
        if expect as usize != self.leaf_tris.len() && ok {
            v.push(Violation::Structure(format!("ranges end at {expect} of {}", self.leaf_tris.len())));
        }
    }

    /// Sizes need sound ranges: called only when they are. A leaf that refinement made is judged as
    /// the leaf of the build it lies in (its ancestor among the build's nodes) was: its triangles are
    /// some of that leaf's, so they fit where that leaf's did (around a hub of that leaf's box, say).
    fn check_sizes(&self, scene: &Scene, v: &mut Vec<Violation>) {
        let mut count = None;
        for (i, leaf) in self.leaves.iter().enumerate() {
            let n = leaf.end.saturating_sub(leaf.start) as usize;
            let (mut node, mut depth) = (leaf.node, leaf.depth);
            while node >= self.built_nodes && node > 0 {
                node = self.parents[(node as usize - 1) / 8];
                depth -= 1;
            }
            if n > self.params.max_triangles && depth < self.params.max_depth && !self.capped {
                // Copies and hubs count once (`hubs`): such a leaf is full only if the rest is.
                let (count, all) = count.get_or_insert_with(|| {
                    let count = SplitCount::new(scene, self.params.max_triangles);
                    let all = count.all_hubs();
                    (count, all)
                });
                let list = &self.leaf_tris[leaf.start as usize..leaf.end as usize];
                let grown = self.node_bounds[node as usize].expanded(self.eps);
                let hubs = count.hubs_in(all, &grown);
                if count.groups(scene, list, &hubs) > self.params.max_triangles {
                    v.push(Violation::Overfull { leaf: LeafId(i as u32), triangles: n, depth: leaf.depth });
                }
            }
        }
    }

    /// For each triangle, compares the leaves listing it with the leaves it overlaps.
    fn check_assignment(&self, scene: &Scene) -> Vec<Violation> {
        // Leaves of each triangle (CSR, ascending leaf order since leaves are scanned in order).
        let n = scene.triangles.len();
        let mut start = vec![0u32; n + 1];
        for t in &self.leaf_tris {
            start[t.idx() + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut listed = vec![LeafId(0); self.leaf_tris.len()];
        for l in self.leaves() {
            for t in self.leaf_triangles(l) {
                listed[fill[t.idx()] as usize] = l;
                fill[t.idx()] += 1;
            }
        }
        (0..n)
            .into_par_iter()
            .flat_map_iter(|t| {
                let tri = scene.triangles[t];
                let mut overlapped = Vec::new();
                self.for_each_leaf_overlapping(&tri.aabb().expanded(self.eps), |l| {
                    if triangle_overlaps_box(&tri, &self.leaf_bounds(l).expanded(self.eps)) {
                        overlapped.push(l);
                    }
                });
                overlapped.sort_unstable();
                let have = &listed[start[t] as usize..start[t + 1] as usize];
                diff(TriId(t as u32), have, &overlapped)
            })
            .collect()
    }
}

/// Violations between the sorted leaf lists `have` (listed) and `want` (overlapped) of triangle `tri`.
fn diff(tri: TriId, have: &[LeafId], want: &[LeafId]) -> Vec<Violation> {
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < have.len() || j < want.len() {
        match (have.get(i), want.get(j)) {
            (Some(a), Some(b)) if a == b => {
                i += 1;
                j += 1;
            }
            (Some(&a), Some(&b)) if a < b => {
                out.push(Violation::ExtraTriangle { leaf: a, tri });
                i += 1;
            }
            (Some(&a), None) => {
                out.push(Violation::ExtraTriangle { leaf: a, tri });
                i += 1;
            }
            (_, Some(&b)) => {
                out.push(Violation::MissingTriangle { leaf: b, tri });
                j += 1;
            }
            (None, None) => unreachable!(),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::octree::OctreeParams;
    use crate::SceneBuilder;

    fn scene() -> Scene {
        let mut b = SceneBuilder::new("strip");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        for i in 0..40 {
            let x = i as f32 * 0.05;
            b.triangle(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 0.04, 0.0, 0.0), Vec3::new(x, 0.3, 0.1), m);
        }
        b.light("l", &[Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, 1.0, 0.5)], Vec3::ONE);
        b.build().expect("valid scene")
    }

    #[test]
    fn a_fresh_octree_is_valid() {
        let s = scene();
        let o = Octree::build(&s, OctreeParams { max_triangles: 3, max_depth: 6 }).expect("valid octree parameters");
        let r = o.validate(&s);
        assert!(r.is_ok(), "{r}");
        assert_eq!(r.leaves, o.leaf_count());
        assert!(r.max_triangles_per_leaf > 0 && r.empty_leaves > 0);
    }

    #[test]
    fn broken_octrees_are_reported() {
        let s = scene();
        let good = Octree::build(&s, OctreeParams { max_triangles: 3, max_depth: 6 }).expect("valid octree parameters");
        let busy = good.leaves().find(|&l| good.leaf_triangles(l).len() >= 2).expect("a leaf with triangles");

        // A triangle dropped from a leaf (the list shrinks, ranges after it shift).
        let mut o = good.clone();
        let leaf = o.leaves[busy.idx()];
        let dropped = o.leaf_tris.remove(leaf.start as usize);
        o.leaves[busy.idx()].end -= 1;
        for l in &mut o.leaves[busy.idx() + 1..] {
            l.start -= 1;
            l.end -= 1;
        }
        let r = o.validate(&s);
        assert_eq!(r.violations, vec![Violation::MissingTriangle { leaf: busy, tri: dropped }]);

        // A triangle listed where it does not belong.
        let mut o = good.clone();
        let far = o.leaves().find(|&l| o.leaf_triangles(l).is_empty()).expect("an empty leaf");
        o.leaf_tris.insert(o.leaves[far.idx()].start as usize, TriId(0));
        o.leaves[far.idx()].end += 1;
        for l in &mut o.leaves[far.idx() + 1..] {
            l.start += 1;
            l.end += 1;
        }
        let r = o.validate(&s);
        assert!(r.violations.contains(&Violation::ExtraTriangle { leaf: far, tri: TriId(0) }), "{r}");

        // Over-full leaf, bad range, bad box.
        let mut o = good.clone();
        o.params.max_triangles = 1;
        assert!(o.validate(&s).violations.iter().any(|v| matches!(v, Violation::Overfull { .. })));
        let mut o = good.clone();
        o.leaves[busy.idx()].end = o.leaf_tris.len() as u32 + 5;
        assert!(o.validate(&s).violations.iter().any(|v| matches!(v, Violation::BadRange { .. })));
        let mut o = good.clone();
        o.node_bounds[3].max.x += 1.0;
        assert!(o.validate(&s).violations.iter().any(|v| matches!(v, Violation::Structure(_))));
        let mut o = good.clone();
        o.parents[0] = 1;
        assert!(o.validate(&s).violations.iter().any(|v| matches!(v, Violation::Structure(_))));
    }
}
