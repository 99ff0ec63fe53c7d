//! The octree of SPEC §3 (thesis §3.1.2, §5.1): a cube around the scene, split into 8 children at the
//! root and then wherever a cell holds more than `max_triangles` triangles, down to `max_depth`.
//!
//! Triangles are assigned with the exact separating-axis test against the cell box grown by
//! [`Octree::eps`] (SPEC §3 **Correction**: the thesis' vertex/edge test misses large triangles), so a
//! triangle may sit in many leaves and every gathering query must de-duplicate.
//!
//! Layout (flat arrays, `u32` indices, nothing allocated per node):
//! - `nodes[0]` is the root; an inner node stores the index of its first child, and its 8 children are
//!   consecutive. Child `i` of a cell is the octant with bit 0 = upper half in x, bit 1 = upper half in
//!   y, bit 2 = upper half in z (see [`child_box`]). A leaf node stores its [`LeafId`]. Nodes are
//!   addressed by [`NodeId`].
//! - Children are allocated 8 at a time after the root, so the blocks start at `1 + 8 m`: node `n > 0`
//!   is child `(n - 1) % 8` of `parents[(n - 1) / 8]` (one parent link per block, for the climbing
//!   neighbour queries of [`neighbour`]).
//! - `node_bounds[n]` is the box of node `n`; every box is computed from its parent's by [`child_box`],
//!   so neighbouring cells share their faces bit for bit.
//! - `leaves[l]` holds the leaf's node, depth and a range into `leaf_tris`, the concatenation of all
//!   leaf triangle lists. Each list is sorted by ascending [`TriId`]. Leaves are numbered breadth-first
//!   (after [`refine`], the children of split leaves follow the others).
//!
//! Stages: [`build`] (construction, with `hubs` saying when a split can separate triangles),
//! [`locate`] (point location), [`traverse`] (segments and boxes), [`neighbour`] (face, edge and
//! corner neighbours), [`refine`] (splitting chosen leaves, §4.8), [`validate`] (invariant report).

pub mod build;
mod hubs;
pub mod locate;
pub mod neighbour;
pub mod refine;
pub mod traverse;
pub mod validate;

pub use crate::geometry::Dir;
pub use neighbour::Neighbour;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geometry::Aabb;
use crate::scene::TriId;

pub use validate::{OctreeReport, Violation};

/// Index of an octree leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct LeafId(pub u32);

impl LeafId {
    /// The index as `usize`.
    #[inline]
    pub fn idx(self) -> usize {
        self.0 as usize
    }
}

/// Index of an octree node, inner or leaf (`NodeId(0)` is the root). See the module doc for the layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

impl NodeId {
    /// The root.
    pub const ROOT: NodeId = NodeId(0);

    /// The index as `usize`.
    #[inline]
    pub fn idx(self) -> usize {
        self.0 as usize
    }
}

/// The deepest `max_depth` accepted: cells are then `2^-16` of the root, far above `f32` resolution
/// and above the assignment tolerance.
pub const MAX_DEPTH_LIMIT: u32 = 16;

/// Most nodes an octree of a scene of `triangles` triangles may have: the build splits no cell of
/// a level whose splits would pass it, and refinement (SPEC §4.8) stops before it. Far above what
/// scenes need (an octree has fewer leaves than triangles at the defaults), it bounds the memory and
/// time of parameters that would split without end (`--max-triangles 1 --max-depth 16` around
/// triangles meeting at a point, or a long refinement chain).
pub fn max_nodes(triangles: usize) -> usize {
    (1 << 18).max(triangles.saturating_mul(4))
}

/// Octree build parameters (SPEC §3, §4.9).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct OctreeParams {
    /// A cell with more triangles than this is split (unless at `max_depth`), exact copies of a
    /// triangle counted once and the triangles around a vertex that more than this many share
    /// counted once (see `build`). Thesis default: 200.
    pub max_triangles: usize,
    /// Deepest leaf level; the root is level 0 and is always split, so leaves are at depth 1 or more.
    /// Must be in `1..=MAX_DEPTH_LIMIT`. Default: 10 (the thesis never saw depth > 8).
    pub max_depth: u32,
}

impl Default for OctreeParams {
    fn default() -> OctreeParams {
        OctreeParams::thesis()
    }
}

impl OctreeParams {
    /// The thesis' settings: at most 200 triangles per leaf, depth at most 10.
    pub fn thesis() -> OctreeParams {
        OctreeParams { max_triangles: 200, max_depth: 10 }
    }

    /// Checks the parameters: `max_triangles >= 1` and `1 <= max_depth <= MAX_DEPTH_LIMIT`.
    pub fn validate(&self) -> Result<()> {
        if self.max_triangles == 0 {
            return Err(Error::InvalidParameter("octree max_triangles must be at least 1".into()));
        }
        if !(1..=MAX_DEPTH_LIMIT).contains(&self.max_depth) {
            return Err(Error::InvalidParameter(format!(
                "octree max_depth {} must be between 1 and {MAX_DEPTH_LIMIT}",
                self.max_depth
            )));
        }
        Ok(())
    }
}

/// A node: an inner node (index of its first of 8 consecutive children) or a leaf, in one `u32`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Node(u32);

/// What a [`Node`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NodeKind {
    /// Inner node; its children are `first .. first + 8`.
    Inner(u32),
    /// Leaf node.
    Leaf(LeafId),
}

const LEAF_BIT: u32 = 1 << 31;

impl Node {
    /// Placeholder for a node not yet decided during the build.
    pub(crate) const UNSET: Node = Node(u32::MAX);

    pub(crate) fn inner(first_child: u32) -> Node {
        assert!(first_child < LEAF_BIT, "octree too large");
        Node(first_child)
    }

    pub(crate) fn leaf(l: LeafId) -> Node {
        assert!(l.0 < LEAF_BIT, "octree too large");
        Node(l.0 | LEAF_BIT)
    }

    #[inline]
    pub(crate) fn kind(self) -> NodeKind {
        if self.0 & LEAF_BIT != 0 {
            NodeKind::Leaf(LeafId(self.0 & !LEAF_BIT))
        } else {
            NodeKind::Inner(self.0)
        }
    }
}

/// A leaf: its node, its depth and its range in the flat triangle list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Leaf {
    pub(crate) node: u32,
    pub(crate) depth: u32,
    pub(crate) start: u32,
    pub(crate) end: u32,
}

/// The octree over a scene's triangles. See the module doc for the layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Octree {
    pub(crate) nodes: Vec<Node>,
    pub(crate) node_bounds: Vec<Aabb>,
    /// `parents[m]` is the parent of the 8 children `1 + 8 m ..= 8 + 8 m`.
    pub(crate) parents: Vec<u32>,
    pub(crate) leaves: Vec<Leaf>,
    pub(crate) leaf_tris: Vec<TriId>,
    pub(crate) eps: f32,
    pub(crate) params: OctreeParams,
    pub(crate) depth: u32,
    pub(crate) scene_triangles: usize,
    /// True if the node cap ([`max_nodes`]) kept the build from splitting a level: its leaves may
    /// hold more than `max_triangles` above `max_depth`.
    pub(crate) capped: bool,
    /// Nodes of the octree as [`Octree::build`] made it; refinement ([`refine`]) appends its nodes
    /// after these.
    pub(crate) built_nodes: u32,
}

/// Child `i` (bit 0: upper x, bit 1: upper y, bit 2: upper z) of the cell `b`. The split planes pass
/// through `b.center()`; a lower child's upper face and the upper child's lower face are the same
/// `f32` value, so cells tile their parent without gaps.
#[inline]
pub fn child_box(b: &Aabb, i: usize) -> Aabb {
    let c = b.center();
    let mut min = b.min;
    let mut max = c;
    for k in 0..3 {
        if i & (1 << k) != 0 {
            min[k] = c[k];
            max[k] = b.max[k];
        }
    }
    Aabb { min, max }
}

impl Octree {
    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    /// Number of nodes, inner and leaf.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// All leaf ids, in breadth-first order (refined leaves last, see [`refine`]).
    pub fn leaves(&self) -> impl ExactSizeIterator<Item = LeafId> + Clone {
        (0..self.leaves.len() as u32).map(LeafId)
    }

    /// All node ids, inner and leaf, root first.
    pub fn nodes(&self) -> impl ExactSizeIterator<Item = NodeId> + Clone {
        (0..self.nodes.len() as u32).map(NodeId)
    }

    /// The (unexpanded, closed) box of a node.
    #[inline]
    pub fn node_bounds(&self, n: NodeId) -> Aabb {
        self.node_bounds[n.idx()]
    }

    /// The leaf a node is, or `None` for an inner node.
    #[inline]
    pub fn node_leaf(&self, n: NodeId) -> Option<LeafId> {
        match self.nodes[n.idx()].kind() {
            NodeKind::Leaf(l) => Some(l),
            NodeKind::Inner(_) => None,
        }
    }

    /// The 8 children of an inner node, child `i` being octant `i` (see [`child_box`]); `None` for a leaf.
    #[inline]
    pub fn node_children(&self, n: NodeId) -> Option<[NodeId; 8]> {
        match self.nodes[n.idx()].kind() {
            NodeKind::Inner(first) => Some(std::array::from_fn(|i| NodeId(first + i as u32))),
            NodeKind::Leaf(_) => None,
        }
    }

    /// The parent of a node, `None` for the root.
    #[inline]
    pub fn node_parent(&self, n: NodeId) -> Option<NodeId> {
        (n.0 > 0).then(|| NodeId(self.parents[(n.idx() - 1) / 8]))
    }

    /// Which child of its parent a node is (0..8, see [`child_box`]); the root answers 0.
    #[inline]
    pub fn node_octant(&self, n: NodeId) -> usize {
        n.idx().saturating_sub(1) % 8
    }

    /// The node of a leaf.
    #[inline]
    pub fn leaf_node(&self, l: LeafId) -> NodeId {
        NodeId(self.leaves[l.idx()].node)
    }

    /// The (unexpanded, closed) box of a leaf.
    #[inline]
    pub fn leaf_bounds(&self, l: LeafId) -> Aabb {
        self.node_bounds[self.leaves[l.idx()].node as usize]
    }

    /// The triangles overlapping the leaf's box grown by [`Octree::eps`], by ascending id.
    #[inline]
    pub fn leaf_triangles(&self, l: LeafId) -> &[TriId] {
        let leaf = &self.leaves[l.idx()];
        &self.leaf_tris[leaf.start as usize..leaf.end as usize]
    }

    /// Depth of a leaf (the root is depth 0, so leaves are at depth 1 or more).
    pub fn leaf_depth(&self, l: LeafId) -> u32 {
        self.leaves[l.idx()].depth
    }

    /// The deepest leaf's depth.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// The root cube.
    pub fn root_bounds(&self) -> Aabb {
        self.node_bounds[0]
    }

    /// Tolerance by which cell boxes are grown for triangle assignment and traversal.
    pub fn eps(&self) -> f32 {
        self.eps
    }

    /// The parameters the octree was built with.
    pub fn params(&self) -> OctreeParams {
        self.params
    }

    /// Total number of (leaf, triangle) references.
    pub fn triangle_refs(&self) -> usize {
        self.leaf_tris.len()
    }

    /// Number of triangles of the scene the octree was built for.
    pub fn scene_triangle_count(&self) -> usize {
        self.scene_triangles
    }

    /// Heap and inline memory used, in bytes.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        size_of::<Octree>()
            + self.nodes.capacity() * size_of::<Node>()
            + self.node_bounds.capacity() * size_of::<Aabb>()
            + self.parents.capacity() * size_of::<u32>()
            + self.leaves.capacity() * size_of::<Leaf>()
            + self.leaf_tris.capacity() * size_of::<TriId>()
    }
}
