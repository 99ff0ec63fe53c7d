//! Neighbour queries (SPEC §3, thesis §6.1), the foundation of umbra propagation (SPEC §4.7): the 6
//! face-, 12 edge- and 8 corner-neighbours of a node, `cell.neighbour(d)`, `cell.neighbour(d1, d2)`,
//! `cell.neighbour(d1, d2, d3)`, and the leaves under a node that touch one of its faces.
//!
//! A neighbour is the cell of the same size shifted by one cell along each given direction. The
//! answer is that node if the tree has it ([`Neighbour::Equal`], a leaf or an inner node), else the
//! larger leaf that covers it ([`Neighbour::Larger`]), or [`Neighbour::None`] when the shifted cell
//! lies outside the root.
//!
//! Method (Samet, "Neighbor finding in images represented by octrees", 1989, generalised to edge
//! and corner steps): climb through the parents while the step leaves the parent along some axis;
//! at each level the mirrored octant (the octant with the stepped axes flipped) is remembered, and
//! only the axes on which the step still leaves the parent go on climbing. Where no axis is left, the
//! remembered octants are followed back down; a leaf met on the way down is the larger neighbour.
//! `O(depth)`, usually far less, with integer work only: no box is compared and nothing allocated.
//!
//! Invalid direction sets (empty, more than three, two on one axis) are programming errors and panic,
//! as [`Octree::neighbour`] documents.

use super::{Dir, LeafId, NodeId, NodeKind, Octree, MAX_DEPTH_LIMIT};

/// The answer of [`Octree::neighbour`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Neighbour {
    /// The node of the same size, leaf or inner.
    Equal(NodeId),
    /// No node of the same size exists there: this larger leaf contains the would-be cell.
    Larger(LeafId),
    /// The would-be cell lies outside the root.
    None,
}

/// Stack capacity of the leaf walks: each inner level leaves at most 7 siblings behind, plus 8.
const STACK: usize = 8 * (MAX_DEPTH_LIMIT as usize + 1);

/// A validated direction set as octant bit masks: bit `k` of `axes` is set when axis `k` is stepped,
/// bit `k` of `positive` when that step goes to the upper side.
#[derive(Clone, Copy)]
struct Step {
    axes: usize,
    positive: usize,
}

impl Step {
    /// # Panics
    /// If `dirs` is empty, longer than 3 or names one axis twice.
    fn new(dirs: &[Dir]) -> Step {
        assert!((1..=3).contains(&dirs.len()), "Octree::neighbour: {} directions, need 1 to 3", dirs.len());
        let (mut axes, mut positive) = (0, 0);
        for d in dirs {
            let bit = 1 << d.axis();
            assert!(axes & bit == 0, "Octree::neighbour: two directions along one axis in {dirs:?}");
            axes |= bit;
            if d.is_positive() {
                positive |= bit;
            }
        }
        Step { axes, positive }
    }
}

impl Octree {
    /// The neighbour of `node` one cell along each direction of `dirs`: one direction for the 6 face
    /// neighbours, two on different axes for the 12 edge neighbours, three on the three axes for the
    /// 8 corner neighbours (the order of `dirs` does not matter). See [`Neighbour`] for the answers;
    /// the root has no neighbours.
    ///
    /// # Panics
    /// If `dirs` is empty, has more than 3 directions or two along one axis (a programming error: the
    /// direction sets of SPEC §4.7 are built from distinct cell faces).
    pub fn neighbour(&self, node: NodeId, dirs: &[Dir]) -> Neighbour {
        let step = Step::new(dirs);
        // Mirrored octants, deepest first: at most one per level below the root.
        let mut path = [0u8; MAX_DEPTH_LIMIT as usize];
        let mut len = 0;
        let mut cur = node;
        let mut axes = step.axes;
        while axes != 0 {
            let Some(parent) = self.node_parent(cur) else { return Neighbour::None };
            let octant = self.node_octant(cur);
            path[len] = (octant ^ axes) as u8;
            len += 1;
            // The step leaves the parent along axis k when the cell already is on that side.
            axes &= !(octant ^ step.positive);
            cur = parent;
        }
        // `cur` is the lowest ancestor holding both cells (an inner node): go back down.
        while len > 0 {
            len -= 1;
            match self.nodes[cur.idx()].kind() {
                NodeKind::Inner(first) => cur = NodeId(first + path[len] as u32),
                NodeKind::Leaf(l) => return Neighbour::Larger(l),
            }
        }
        Neighbour::Equal(cur)
    }

    /// Appends to `out` every leaf under `node` (the node itself if it is a leaf), depth first in
    /// child order.
    pub fn leaves_under(&self, node: NodeId, out: &mut Vec<LeafId>) {
        self.push_leaves(node, 0, 0, out);
    }

    /// Appends to `out` every leaf under `node` whose box touches the face `face` of the node's box
    /// (the node itself if it is a leaf), depth first in child order.
    pub fn leaves_on_face(&self, node: NodeId, face: Dir, out: &mut Vec<LeafId>) {
        let bit = 1 << face.axis();
        self.push_leaves(node, bit, if face.is_positive() { bit } else { 0 }, out);
    }

    /// The leaves under `node` reached through children whose octant `i` has `i & mask == want`.
    fn push_leaves(&self, node: NodeId, mask: u32, want: u32, out: &mut Vec<LeafId>) {
        let mut stack = [0u32; STACK];
        stack[0] = node.0;
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            match self.nodes[stack[sp] as usize].kind() {
                NodeKind::Leaf(l) => out.push(l),
                NodeKind::Inner(first) => {
                    for i in (0..8).rev().filter(|i| i & mask == want) {
                        stack[sp] = first + i;
                        sp += 1;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::octree::OctreeParams;
    use crate::{Scene, SceneBuilder};

    /// The 26 direction sets, as steps in {-1, 0, 1}^3 and as directions.
    fn direction_sets() -> Vec<([i32; 3], Vec<Dir>)> {
        let mut v = Vec::new();
        for s in 0..27 {
            let step = [s % 3 - 1, s / 3 % 3 - 1, s / 9 - 1];
            let dirs: Vec<Dir> = (0..3).filter(|&k| step[k] != 0).map(|k| Dir::from_axis(k, step[k] > 0)).collect();
            if !dirs.is_empty() {
                v.push((step, dirs));
            }
        }
        assert_eq!(v.len(), 26);
        v
    }

    /// The point around which the tree is deep: in root octant 6 (lower x, upper y, upper z), in a
    /// depth-5 cell touching the plane x = 0 (the root is about [-4, 4]^3, depth-5 cells 0.25 wide).
    const DEEP: Vec3 = Vec3::new(-0.1, 1.1, 2.1);

    /// A floor, a light, and a few tiny triangles around [`DEEP`]: with `max_triangles` 4 and
    /// `max_depth` 5 only the cells around `DEEP` split, so root octant 6 is 4 levels deeper than the
    /// other 7 root children, which are leaves.
    fn unbalanced() -> (Scene, Octree) {
        let mut b = SceneBuilder::new("unbalanced");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        b.quad(
            Vec3::new(-4.0, -4.0, -4.0),
            Vec3::new(-4.0, -4.0, 4.0),
            Vec3::new(4.0, -4.0, 4.0),
            Vec3::new(4.0, -4.0, -4.0),
            m,
        );
        for i in 0..6 {
            let p = DEEP + Vec3::new(0.003 * i as f32, 0.0, -0.002 * i as f32);
            b.triangle(p, p + Vec3::new(0.01, 0.0, 0.0), p + Vec3::new(0.0, 0.01, 0.005), m);
        }
        b.light("l", &[Vec3::new(0.0, 4.0, 0.0), Vec3::new(0.5, 4.0, 0.0), Vec3::new(0.5, 4.0, 0.5)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let o = Octree::build(&s, OctreeParams { max_triangles: 4, max_depth: 5 }).expect("valid octree parameters");
        (s, o)
    }

    #[test]
    fn root_children_see_each_other_and_nothing_beyond_the_root() {
        let (_, o) = unbalanced();
        let children = o.node_children(NodeId::ROOT).expect("the root is split");
        for (i, &c) in children.iter().enumerate() {
            assert_eq!(o.node_parent(c), Some(NodeId::ROOT));
            assert_eq!(o.node_octant(c), i);
            for (step, dirs) in direction_sets() {
                assert_eq!(o.neighbour(NodeId::ROOT, &dirs), Neighbour::None);
                let bits: Vec<i32> = (0..3).map(|k| (i >> k & 1) as i32 + step[k]).collect();
                let want = if bits.iter().all(|b| (0..2).contains(b)) {
                    Neighbour::Equal(children[(bits[0] + 2 * bits[1] + 4 * bits[2]) as usize])
                } else {
                    Neighbour::None
                };
                assert_eq!(o.neighbour(c, &dirs), want, "octant {i}, {dirs:?}");
            }
        }
    }

    #[test]
    fn unbalanced_tree_answers_larger_leaves() {
        let (s, o) = unbalanced();
        assert!(o.validate(&s).is_ok());
        assert_eq!(o.depth(), 5);
        assert_eq!(o.leaf_count(), 7 + 29, "7 root leaves, 7 leaves at depths 2 to 4 and 8 at depth 5");
        let root = o.node_children(NodeId::ROOT).expect("the root is split");
        let deep = o.locate(DEEP).expect("inside");
        let node = o.leaf_node(deep);
        assert_eq!((o.leaf_depth(deep), o.node_leaf(node)), (5, Some(deep)));
        assert_eq!(o.node_bounds(node).max.x, o.root_bounds().center().x, "the deep leaf touches x = 0");

        // Across x = 0: the depth-1 leaf of root octant 7; the other way: a sibling.
        let right = o.node_leaf(root[7]).expect("octant 7 is a leaf");
        assert_eq!(o.neighbour(node, &[Dir::Right]), Neighbour::Larger(right));
        let parent = o.node_parent(node).expect("not the root");
        let sibling = o.node_children(parent).expect("inner")[o.node_octant(node) ^ 1];
        assert_eq!(o.neighbour(node, &[Dir::Left]), Neighbour::Equal(sibling));
        assert!(o.node_leaf(sibling).is_some());
        // Coming back from the large leaf: the inner node of the same size.
        assert_eq!(o.neighbour(root[7], &[Dir::Left]), Neighbour::Equal(root[6]));
        assert_eq!(o.node_leaf(root[6]), None);
        assert_eq!(o.neighbour(root[7], &[Dir::Right]), Neighbour::None);
        assert_eq!(o.neighbour(parent, &[Dir::Right, Dir::Down]), Neighbour::Larger(right));
    }

    #[test]
    fn leaves_under_and_on_faces_of_an_unbalanced_node() {
        let (_, o) = unbalanced();
        let root = o.node_children(NodeId::ROOT).expect("the root is split");
        let mut all = Vec::new();
        o.leaves_under(NodeId::ROOT, &mut all);
        all.sort();
        assert_eq!(all, o.leaves().collect::<Vec<_>>());

        let deep = root[6];
        let b = o.node_bounds(deep);
        let mut under = Vec::new();
        o.leaves_under(deep, &mut under);
        assert_eq!(under.len(), 29);
        for face in Dir::ALL {
            let mut on = vec![LeafId(u32::MAX)]; // appended to, not cleared
            o.leaves_on_face(deep, face, &mut on);
            let want: Vec<LeafId> = under
                .iter()
                .copied()
                .filter(|&l| {
                    let lb = o.leaf_bounds(l);
                    let k = face.axis();
                    if face.is_positive() {
                        lb.max[k] == b.max[k]
                    } else {
                        lb.min[k] == b.min[k]
                    }
                })
                .collect();
            assert_eq!(on[0], LeafId(u32::MAX));
            assert_eq!(on[1..], want[..], "{face:?}");
        }
        let mut on = Vec::new();
        o.leaves_on_face(deep, Dir::Right, &mut on);
        assert_eq!(on.len(), 13, "3 leaves at depths 2 to 4 and 4 at depth 5 touch x = 0");
        let leaf = o.node_leaf(root[0]).expect("a leaf");
        on.clear();
        o.leaves_on_face(root[0], Dir::Up, &mut on);
        assert_eq!(on, vec![leaf]);
    }

    #[test]
    #[should_panic(expected = "two directions along one axis")]
    fn opposite_directions_panic() {
        let (_, o) = unbalanced();
        o.neighbour(NodeId(1), &[Dir::Left, Dir::Right]);
    }

    #[test]
    #[should_panic(expected = "two directions along one axis")]
    fn a_repeated_direction_panics() {
        let (_, o) = unbalanced();
        o.neighbour(NodeId(1), &[Dir::Up, Dir::Front, Dir::Up]);
    }

    #[test]
    #[should_panic(expected = "0 directions")]
    fn no_direction_panics() {
        let (_, o) = unbalanced();
        o.neighbour(NodeId(1), &[]);
    }

    #[test]
    #[should_panic(expected = "4 directions")]
    fn four_directions_panic() {
        let (_, o) = unbalanced();
        o.neighbour(NodeId(1), &[Dir::Left, Dir::Up, Dir::Front, Dir::Right]);
    }
}
