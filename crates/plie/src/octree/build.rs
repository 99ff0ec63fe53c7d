//! Octree construction (SPEC §3; thesis §3.1.2, §5.1).
//!
//! The root is a cube centred on the scene's bounding box whose half-size is the largest half-extent
//! grown by [`ROOT_MARGIN`] (plus a few `eps`), so no triangle lies on the root's boundary. The root is
//! always split; any other cell with more than `max_triangles` triangles is split until `max_depth`.
//! A triangle goes to every child whose box, grown by `eps`, it overlaps by the exact separating-axis
//! test ([`triangle_overlaps_box`]); a cheap bounding-box pre-filter with a `2 eps` slack only skips
//! children the exact test would reject too.
//!
//! Triangles no split can separate count once toward `max_triangles` (`hubs`): exact copies
//! of a triangle, and the triangles sharing a vertex of the cell that more than `max_triangles` of
//! them share (a hub). Otherwise a cell holding them would split to `max_depth`, and for a hub the
//! cells around it too.
//!
//! The build runs level by level. For one level, the cells to split are split in parallel (rayon,
//! and large triangle lists in parallel chunks); the results are then placed into the flat arrays by
//! one sequential pass in cell order. Every value is a pure function of the scene and the parameters,
//! and rayon's ordered `collect` keeps the chunk order, so the arrays are identical for any number of
//! threads.

use rayon::prelude::*;

use super::hubs::SplitCount;
use super::{child_box, Leaf, LeafId, Node, Octree, OctreeParams};
use crate::geometry::{triangle_overlaps_box, Aabb};
use crate::scene::{Scene, TriId};

/// Relative margin by which the root cube exceeds the scene's largest half-extent.
pub const ROOT_MARGIN: f32 = 1e-3;

/// Relative assignment tolerance: `eps = EPS_REL * max(scene.scale(), largest |coordinate|)`.
pub const EPS_REL: f32 = 1e-6;

/// Triangle lists longer than this are split in parallel chunks of this size.
const PAR_CHUNK: usize = 4096;

/// The assignment and traversal tolerance for a scene: `EPS_REL` times the larger of the scene's scale
/// and its largest absolute coordinate. For scenes near the origin this is `scene.scale() * 1e-6`;
/// for a scene far from the origin it stays several `f32` ulps of its coordinates wide, so rounding in
/// the traversal can never close the margin.
pub fn tolerance(scene: &Scene) -> f32 {
    EPS_REL * scene.scale().max(scene.bounds.largest_abs())
}

/// The root cube for a scene and tolerance.
pub fn root_cube(scene: &Scene, eps: f32) -> Aabb {
    let half = 0.5 * scene.bounds.size().max_element();
    Aabb::cube(scene.bounds.center(), half * (1.0 + ROOT_MARGIN) + 4.0 * eps)
}

/// A cell waiting for its split decision: its node, box, depth, triangles and the hubs in its box
/// grown by `eps` (`hubs`).
struct Pending {
    node: u32,
    bounds: Aabb,
    depth: u32,
    tris: Vec<TriId>,
    hubs: Vec<u32>,
}

/// The triangle lists of the 8 children of a cell.
type Split = [Vec<TriId>; 8];

impl Octree {
    /// Builds the octree of `scene`. Deterministic: the same scene and parameters give the same arrays
    /// for any number of rayon threads.
    /// Fails with [`crate::Error::InvalidParameter`] if `params` fails [`OctreeParams::validate`].
    pub fn build(scene: &Scene, params: OctreeParams) -> crate::Result<Octree> {
        params.validate()?;
        Ok(Octree::build_valid(scene, params))
    }

    /// [`Octree::build`] of parameters already validated.
    pub(crate) fn build_valid(scene: &Scene, params: OctreeParams) -> Octree {
        debug_assert!(params.validate().is_ok());
        let eps = tolerance(scene);
        let root = root_cube(scene, eps);
        let n = scene.triangles.len();
        assert!(n < u32::MAX as usize, "too many triangles for u32 ids");
        let mut tree = Octree {
            nodes: vec![Node::UNSET],
            node_bounds: vec![root],
            parents: Vec::new(),
            leaves: Vec::new(),
            leaf_tris: Vec::new(),
            eps,
            params,
            depth: 0,
            scene_triangles: n,
            capped: false,
            built_nodes: 0,
        };
        let count = SplitCount::new(scene, params.max_triangles);
        let all = (0..n as u32).map(TriId).collect();
        let mut frontier = vec![Pending { node: 0, bounds: root, depth: 0, tris: all, hubs: count.all_hubs() }];
        let max_nodes = super::max_nodes(n);
        while !frontier.is_empty() {
            let wants: Vec<bool> = frontier
                .par_iter()
                .map(|p| {
                    p.depth == 0
                        || (p.depth < params.max_depth
                            && p.tris.len() > params.max_triangles
                            && count.groups(scene, &p.tris, &p.hubs) > params.max_triangles)
                })
                .collect();
            // A level whose splits would pass the node cap splits nothing but the root (the same
            // for any number of threads: the count is of the whole level).
            let room = tree.nodes.len() + 8 * wants.iter().filter(|&&w| w).count() <= max_nodes;
            tree.capped |= !room && frontier.iter().zip(&wants).any(|(p, &w)| w && p.depth > 0);
            let splits: Vec<Option<Split>> = frontier
                .par_iter()
                .zip(&wants)
                .map(|(p, &want)| (want && (room || p.depth == 0)).then(|| split_cell(scene, &p.tris, &p.bounds, eps)))
                .collect();
            frontier = tree.place(frontier, splits, &count);
        }
        tree.built_nodes = tree.nodes.len() as u32;
        tree.nodes.shrink_to_fit();
        tree.node_bounds.shrink_to_fit();
        tree.parents.shrink_to_fit();
        tree.leaves.shrink_to_fit();
        tree.leaf_tris.shrink_to_fit();
        tree
    }

    /// Places one level: split cells become inner nodes with 8 new children (returned as the next
    /// level), the others become leaves.
    fn place(&mut self, frontier: Vec<Pending>, splits: Vec<Option<Split>>, count: &SplitCount) -> Vec<Pending> {
        let mut next = Vec::new();
        for (p, split) in frontier.into_iter().zip(splits) {
            match split {
                Some(children) => {
                    let first = self.push_children(p.node);
                    for (i, tris) in children.into_iter().enumerate() {
                        let node = first + i as u32;
                        let bounds = self.node_bounds[node as usize];
                        let hubs = count.hubs_in(&p.hubs, &bounds.expanded(self.eps));
                        next.push(Pending { node, bounds, depth: p.depth + 1, tris, hubs });
                    }
                }
                None => self.push_leaf(p.node, p.depth, &p.tris),
            }
        }
        next
    }
}

impl Octree {
    /// Makes `node` an inner node with a new block of 8 undecided children (boxes from
    /// [`child_box`]) at the end of the arrays; returns the first child's index.
    pub(super) fn push_children(&mut self, node: u32) -> u32 {
        let first = self.nodes.len() as u32;
        self.nodes[node as usize] = Node::inner(first);
        debug_assert_eq!(first as usize, 1 + 8 * self.parents.len(), "child blocks start at 1 + 8 m");
        self.parents.push(node);
        let bounds = self.node_bounds[node as usize];
        for i in 0..8 {
            self.nodes.push(Node::UNSET);
            self.node_bounds.push(child_box(&bounds, i));
        }
        first
    }

    /// Makes `node` the next leaf, at `depth`, with the triangle list `tris`.
    pub(super) fn push_leaf(&mut self, node: u32, depth: u32, tris: &[TriId]) {
        let id = LeafId(self.leaves.len() as u32);
        self.nodes[node as usize] = Node::leaf(id);
        let start = self.leaf_tris.len() as u32;
        self.leaf_tris.extend_from_slice(tris);
        assert!(self.leaf_tris.len() <= u32::MAX as usize, "too many leaf triangle references for u32 ranges");
        self.leaves.push(Leaf { node, depth, start, end: self.leaf_tris.len() as u32 });
        self.depth = self.depth.max(depth);
    }
}

/// Distributes a cell's triangles over its 8 children (each list keeps the parent's order).
pub(super) fn split_cell(scene: &Scene, tris: &[TriId], cell: &Aabb, eps: f32) -> Split {
    let grown: [Aabb; 8] = std::array::from_fn(|i| child_box(cell, i).expanded(eps));
    let center = cell.center();
    if tris.len() <= PAR_CHUNK {
        return split_chunk(scene, tris, &grown, center, eps);
    }
    let parts: Vec<Split> =
        tris.par_chunks(PAR_CHUNK).map(|chunk| split_chunk(scene, chunk, &grown, center, eps)).collect();
    std::array::from_fn(|i| {
        let mut v = Vec::with_capacity(parts.iter().map(|p| p[i].len()).sum());
        for p in &parts {
            v.extend_from_slice(&p[i]);
        }
        v
    })
}

/// Sequential part of [`split_cell`]: a bounding-box pre-filter against the split planes through
/// `center` (slack `2 eps`, wider than the grown boxes) picks the candidate children, the exact test
/// decides.
fn split_chunk(scene: &Scene, tris: &[TriId], grown: &[Aabb; 8], center: glam::Vec3, eps: f32) -> Split {
    let mut out: Split = Default::default();
    let lo_limit = center + glam::Vec3::splat(2.0 * eps);
    let hi_limit = center - glam::Vec3::splat(2.0 * eps);
    for &t in tris {
        let tri = scene.triangle(t);
        let bb = tri.aabb();
        // Bit k of `lower`/`upper`: the triangle may reach the lower/upper half along axis k.
        let lower = bb.min.cmple(lo_limit).bitmask();
        let upper = bb.max.cmpge(hi_limit).bitmask();
        for (i, child) in grown.iter().enumerate() {
            let i = i as u32;
            // Axis k needs the upper half if bit k of i is set, the lower half otherwise.
            let ok = (i & upper) | (!i & lower & 7);
            if ok == 7 && triangle_overlaps_box(tri, child) {
                out[i as usize].push(t);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::octree::NodeKind;
    use crate::SceneBuilder;

    fn two_triangle_scene() -> Scene {
        let mut b = SceneBuilder::new("two");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        b.triangle(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), m);
        b.light("light", &[Vec3::new(0.2, 2.0, 0.2), Vec3::new(0.4, 2.0, 0.2), Vec3::new(0.4, 2.0, 0.4)], Vec3::ONE);
        b.build().expect("valid scene")
    }

    #[test]
    fn root_is_split_even_when_small() {
        let s = two_triangle_scene();
        let o = Octree::build(&s, OctreeParams::default()).expect("valid octree parameters");
        assert!(matches!(o.nodes[0].kind(), NodeKind::Inner(1)));
        assert_eq!(o.leaf_count(), 8);
        assert_eq!(o.depth(), 1);
        let r = o.root_bounds();
        assert!(r.min.cmplt(s.bounds.min).all() && r.max.cmpgt(s.bounds.max).all(), "margin around the scene");
        let size = r.size();
        assert_eq!(size.x, size.y);
        assert_eq!(size.y, size.z);
    }

    /// Four triangles crossing each other, with leaves of one triangle down to depth 16, would split
    /// along the lines where they cross to over a million nodes; the node cap stops the build at a
    /// level, the same for any thread count, and the octree stays valid. (Along a shared edge the
    /// shared vertices would be hubs at this limit: `hubs`.)
    #[test]
    fn the_node_cap_bounds_an_octree_that_would_split_without_end() {
        let mut b = SceneBuilder::new("crossing");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        b.triangle(Vec3::new(-0.1, 0.0, -0.1), Vec3::new(0.3, 0.0, 1.1), Vec3::new(1.1, 0.0, 0.2), m);
        b.triangle(Vec3::new(0.1, -0.5, 0.13), Vec3::new(0.9, 0.4, 0.85), Vec3::new(0.95, -0.6, 0.9), m);
        b.triangle(Vec3::new(0.52, -0.7, -0.2), Vec3::new(0.52, 0.6, 0.3), Vec3::new(0.52, -0.3, 1.2), m);
        b.triangle(Vec3::new(-0.2, -0.6, 0.47), Vec3::new(1.2, -0.4, 0.47), Vec3::new(0.4, 0.7, 0.47), m);
        b.light("light", &[Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.1)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let params = OctreeParams { max_triangles: 1, max_depth: 16 };
        let o = Octree::build(&s, params).expect("valid octree parameters");
        assert!(o.capped && o.node_count() <= crate::octree::max_nodes(s.triangles.len()), "{}", o.node_count());
        assert!(o.node_count() > crate::octree::max_nodes(s.triangles.len()) / 8, "{}", o.node_count());
        assert!(o.depth() < 16);
        let report = o.validate(&s);
        assert!(report.is_ok(), "{report}");
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert!(one.install(|| Octree::build(&s, params).unwrap()) == o, "the cap depends on the thread count");
        // Below the cap nothing changes.
        let small = Octree::build(&s, OctreeParams { max_triangles: 4, max_depth: 5 }).unwrap();
        assert!(!small.capped);
    }

    /// 30 thin triangles sharing a vertex (they all meet in every cell around it) and a floor of
    /// `floor` x `floor` squares around them, far enough that some cells hold no hub.
    fn spokes(floor: usize) -> Scene {
        let mut b = SceneBuilder::new("fan");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        for i in 0..30 {
            let a = i as f32 * 0.2;
            b.triangle(Vec3::ZERO, Vec3::new(a.cos(), a.sin(), 0.1), Vec3::new(a.cos(), a.sin(), -0.1), m);
        }
        let p = |i: usize, j: usize| Vec3::new(1.5 + i as f32 * 0.3, -1.0, 1.5 + j as f32 * 0.3);
        for i in 0..floor {
            for j in 0..floor {
                b.quad(p(i, j), p(i, j + 1), p(i + 1, j + 1), p(i + 1, j), m);
            }
        }
        b.light("light", &[Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.1)], Vec3::ONE);
        b.build().expect("valid scene")
    }

    #[test]
    fn splits_until_limit_or_depth_but_not_around_a_hub() {
        let s = spokes(12);
        // The floor's vertices are shared by at most 6 triangles: no hubs at a limit of 6.
        let o = Octree::build(&s, OctreeParams { max_triangles: 6, max_depth: 5 }).expect("valid octree parameters");
        assert!(o.validate(&s).is_ok());
        assert_eq!(o.depth(), 5, "the floor splits to max_depth");
        let mut hub_leaves = 0;
        for l in o.leaves() {
            let grown = o.node_bounds[o.leaves[l.idx()].node as usize].expanded(o.eps);
            let tris = o.leaf_triangles(l);
            if grown.contains(Vec3::ZERO) {
                // The hub's 30 triangles and at most 5 others, in a cell no deeper than needed.
                hub_leaves += 1;
                assert!(
                    (30..=35).contains(&tris.len()) && o.leaf_depth(l) < 5,
                    "{} at {}",
                    tris.len(),
                    o.leaf_depth(l)
                );
            } else {
                assert!(tris.len() <= 6 || o.leaf_depth(l) == 5, "{} at {}", tris.len(), o.leaf_depth(l));
            }
        }
        assert!(hub_leaves > 0);
        // Refinement may split a hub's leaf: children without the hub may then hold more than the
        // limit, as their parent did, and the octree is still valid.
        let hub = o.locate(Vec3::ZERO).expect("the hub is in the octree");
        let (refined, _) = o.split_leaves(&s, &[hub]);
        let report = refined.validate(&s);
        assert!(report.is_ok(), "{report}");
    }

    /// A unit floor (two triangles) with `copies` more copies of its first triangle (vertices in
    /// rotated order too), a wall standing on it, and a light.
    fn coincident_floor(copies: usize) -> Scene {
        let mut b = SceneBuilder::new("coincident");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        let [p, q, r, s] = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z];
        for i in 0..=copies {
            if i % 2 == 0 {
                b.triangle(p, r, q, m);
            } else {
                b.triangle(r, q, p, m);
            }
        }
        b.triangle(p, s, r, m);
        b.triangle(Vec3::new(0.3, 0.0, 0.2), Vec3::new(0.7, 0.0, 0.6), Vec3::new(0.5, 0.5, 0.4), m);
        b.light("light", &[Vec3::new(0.4, 0.9, 0.4), Vec3::new(0.6, 0.9, 0.4), Vec3::new(0.6, 0.9, 0.6)], Vec3::ONE);
        b.build().expect("valid scene")
    }

    #[test]
    fn coincident_triangles_do_not_explode_the_octree() {
        // Issue 16: 201 coincident triangles split to depth 10 into 1,220,836 leaves.
        for copies in [200, 400] {
            let s = coincident_floor(copies);
            assert_eq!(s.triangles.len(), copies + 4);
            let o =
                Octree::build(&s, OctreeParams { max_triangles: 200, max_depth: 10 }).expect("valid octree parameters");
            assert_eq!((o.leaf_count(), o.depth()), (8, 1), "{copies} copies: only the root is split");
            // Every triangle is still in the leaves it overlaps: the rule only stops splitting.
            let mut seen = vec![false; s.triangles.len()];
            for l in o.leaves() {
                o.leaf_triangles(l).iter().for_each(|t| seen[t.idx()] = true);
            }
            assert!(seen.iter().all(|&x| x));
        }
        // With a lower limit the distinct triangles are still separated as before.
        let s = coincident_floor(200);
        let o = Octree::build(&s, OctreeParams { max_triangles: 2, max_depth: 10 }).expect("valid octree parameters");
        assert!(o.depth() > 1 && o.leaf_count() < 4096, "{} leaves, depth {}", o.leaf_count(), o.depth());
        for l in o.leaves() {
            let tris = o.leaf_triangles(l);
            let d = SplitCount::new(&s, 2).distinct(tris);
            assert!(d <= 2 || o.leaf_depth(l) == 10, "leaf with {d} distinct triangles above max_depth");
        }
    }

    #[test]
    fn rejects_zero_max_triangles() {
        let r = Octree::build(&two_triangle_scene(), OctreeParams { max_triangles: 0, max_depth: 3 });
        assert!(matches!(r, Err(crate::Error::InvalidParameter(m)) if m.contains("max_triangles")));
    }
}
