//! Propagation of umbra to neighbouring cells (SPEC §4.7, thesis chapter 6): when faces of a cell are
//! fully in umbra for a light, faces of its neighbours can be proven dark too, and their records are
//! deleted **without** computing blockers or regions. It only speeds up construction: a record is
//! deleted only where "no record ⇒ occluded" gives exactly the brute-force answer.
//!
//! # The principle, tested directly
//!
//! A face `G` of a leaf `X` may be deleted for light `L` if every segment from `G` to `L` passes through
//! a source cell `C` and leaves it through a face known to be dark ([`principle`]). The thesis' rules
//! ([`rules`]) only choose *which* neighbour and faces to try; each candidate must pass that test. We
//! checked the rules against the principle:
//!
//! - **General rule (§6.2)** — every lit face of `C` dark, so face `F` of `neighbour(F.inv)` (the face
//!   shared with `C`) is dark — holds when the light does not reach into `C`: a segment from the shared
//!   face enters `C` and leaves it through a face whose plane its light point lies beyond and that is
//!   in front of the light (every point of a shadow ray but its end is), i.e. a face that sees the
//!   light by SPEC §4.1, and those are all dark. The test confirms it case by case, and refuses it
//!   when the light reaches into the cell, when a dark face cannot vouch for rays that graze it, or
//!   when the rays are too long for the umbra's guard (see *Tolerances*).
//! - **One lit face (§6.3)**: for the face shared with `C` it is the general rule. For the other faces
//!   of `neighbour(F.inv)` we have no proof with the exact, one-sided §4.1 condition (the thesis
//!   argues with equal cubes and a light facing the face), so each goes through the test; in our
//!   configurations they either cannot see the light or pass it.
//! - **Two and three lit faces (§6.4, §6.5)**: the 45° conditions on the angles of the thesis' four
//!   shaft planes are stated for equal cubes and planes we do not build (our shafts are the exact
//!   supporting planes of conv(face ∪ light)); they are replaced by the test, which decides exactly
//!   when the diagonal neighbour's faces lie behind `C` as seen from the light (tests/
//!   propagation_rules.rs has a light too steep and one too shallow for each sub-case).
//! - **Recursion** "along the same direction" and **inner-node neighbours**: a neighbour that is an
//!   inner node has all its leaves tried, and every neighbour that lost records becomes a source in
//!   turn (a work list, until nothing changes). We go one step further than the thesis, which stops
//!   at a larger leaf: the parent of a source with a dark face is a source too (an inner node's face is
//!   dark when every leaf on it is), so the larger leaf can be its equal neighbour.
//!
//! # Tolerances
//!
//! The renderer decides in `f32` through which face a shadow ray leaves its leaf
//! ([`crate::visibility::lie::exit_face`]); where the ray leaves near an edge the true exit can lie on
//! the neighbouring face, within a rounding distance of the chosen face, and the light sample is
//! rounded too. So a deleted face must cover every ray passing within `delta` of it toward the light
//! grown by `delta`: `delta = r / 16`, with `r` the regions' error bound
//! ([`crate::construct::regions::error_bound`], at least 10^-5 of the largest coordinate, while the
//! rounding is a few `f32` ulps of it). The test works on the face and on the source cell grown by
//! `delta`. A ray leaving the grown cell is `delta` off the dark face's plane, so it is covered only if
//! it meets the face plane within the umbra's margin, which bounds its angle to the face
//! ([`state::dark_budget`]). The umbra blocks a ray between known heights; a long ray from a far
//! neighbour could put that hit inside the `SEGMENT_EPS` ends of the watertight test, so every dark
//! face carries a *budget* (the longest ray it vouches for) and the test checks the rays from the
//! target leaf against it; a propagated face passes on the smallest budget it relied on.
//!
//! # Order and determinism
//!
//! Propagation needs an order: a face can only be deleted before it is computed. The (leaf, light)
//! tasks are sorted by the distance from the leaf's centre to the light's centre (ties by leaf, then
//! light: [`task_order`]) and run by [`crate::construct::schedule::run_ordered`]: in parallel, but
//! *committed* strictly in that order. At its commit a task's faces get their outcome (computed, or
//! deleted by an earlier commit) and its leaf propagates ([`Propagator`]), which only turns faces of
//! tasks not yet committed (`Pending`) into `Propagated`. So the P-LIE is the one a single thread would
//! build in that order, whatever the thread count. Workers skip faces already deleted when they reach
//! them; a face deleted by a commit that comes after its worker started is computed for nothing (the
//! timing-dependent `propagation_wasted` of [`crate::construct::BuildStats`]). Dark faces lie behind
//! blockers as seen from the light and the faces they prove lie farther on, so they are usually still
//! ahead of the workers. There is no barrier: a slow task delays commits, never the other workers.

pub mod principle;
pub mod rules;
pub mod state;

use rayon::slice::ParallelSliceMut;
use std::collections::VecDeque;

pub use principle::{Exit, LightHull, Source};
pub use rules::Rule;
pub use state::{dark_budget, FaceState, FaceStates};

use crate::octree::{Dir, LeafId, Neighbour, NodeId, Octree};
use crate::scene::{LightId, Scene};

/// The tolerances of propagation: the construction tolerance `tol` and the distance `delta` within
/// which a shadow ray's exit face is decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Construction tolerance (world units, see [`crate::construct::TOLERANCE_REL`]).
    pub tol: f32,
    /// Rounding distance of the exit face and of light samples (world units):
    /// `error_bound(tol, abs_scale) / 16`.
    pub delta: f64,
}

impl Tolerances {
    /// From the construction tolerance and the largest absolute coordinate of the scene.
    pub fn new(tol: f32, abs_scale: f32) -> Tolerances {
        Tolerances { tol, delta: crate::construct::regions::error_bound(tol, abs_scale) / 16.0 }
    }
}

/// One record deleted by propagation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Propagated {
    /// The leaf.
    pub leaf: LeafId,
    /// Its face.
    pub face: Dir,
    /// The light.
    pub light: LightId,
    /// The rule that proposed it.
    pub rule: Rule,
    /// The source cell whose dark faces prove it.
    pub source: NodeId,
}

/// The (leaf, light) construction tasks in the order they are committed: with `propagate` false in
/// (leaf, light) order; else sorted by the distance from the leaf's centre to the light's centre, ties
/// by leaf then light.
pub fn task_order(scene: &Scene, octree: &Octree, propagate: bool) -> Vec<(LeafId, LightId)> {
    let lights = scene.lights.len() as u32;
    let tasks = octree.leaves().flat_map(|l| (0..lights).map(move |i| (l, LightId(i))));
    if !propagate {
        return tasks.collect();
    }
    // Each distance computed once; a distance is not negative, so its bits order as it does, and the
    // keys are distinct, so an unstable sort gives the one order.
    let dist = |l: LeafId, i: LightId| octree.leaf_bounds(l).center().distance(scene.lights[i.idx()].center());
    let mut keyed: Vec<(u32, LeafId, LightId)> = tasks.map(|(l, i)| (dist(l, i).to_bits(), l, i)).collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, l, i)| (l, i)).collect()
}

/// Runs the rules from source cells until nothing changes, recording what it deletes.
pub struct Propagator<'a> {
    octree: &'a Octree,
    t: Tolerances,
    hulls: Vec<LightHull<'a>>,
    queued: Vec<bool>,
    leaves: Vec<LeafId>,
    face_leaves: Vec<LeafId>,
    /// Every deletion so far, in order.
    pub log: Vec<Propagated>,
    /// Principle tests run (candidates that were still pending).
    pub tests: usize,
}

impl<'a> Propagator<'a> {
    /// A propagator for `scene` over `octree`.
    pub fn new(scene: &'a Scene, octree: &'a Octree, t: Tolerances) -> Propagator<'a> {
        Propagator {
            octree,
            t,
            hulls: scene.lights.iter().map(|l| LightHull::new(l, &t)).collect(),
            queued: vec![false; octree.node_count()],
            leaves: Vec::new(),
            face_leaves: Vec::new(),
            log: Vec::new(),
            tests: 0,
        }
    }

    /// After the commit of the (leaf, light) task: propagates for that light from the leaf if one of
    /// its faces is known dark. Only the task's light: the cost of a commit does not grow with the
    /// scene's lights.
    pub fn after_commit(&mut self, states: &mut FaceStates, leaf: LeafId, light: LightId) {
        if Dir::ALL.iter().any(|&f| states.get(leaf, f, light).vouches().is_some()) {
            self.run(states, light, &[self.octree.leaf_node(leaf)]);
        }
    }

    /// Propagates for `light` from `sources`, then from every neighbour that lost records and from
    /// the parent of every source with a dark face (an inner node is a source too: its face is dark
    /// when every leaf on it is), until nothing changes. Returns how many records it deleted.
    pub fn run(&mut self, states: &mut FaceStates, light: LightId, sources: &[NodeId]) -> usize {
        let before = self.log.len();
        let mut queue: VecDeque<NodeId> = VecDeque::new();
        for &s in sources {
            if !std::mem::replace(&mut self.queued[s.idx()], true) {
                queue.push_back(s);
            }
        }
        let octree = self.octree;
        while let Some(node) = queue.pop_front() {
            self.queued[node.idx()] = false;
            let hull = &self.hulls[light.idx()];
            let Some(src) = Source::new(octree, states, node, light, hull, &self.t, &mut self.face_leaves) else {
                continue;
            };
            let mut next = Vec::new();
            if src.any_dark() {
                next.extend(octree.node_parent(node).filter(|&p| p != NodeId::ROOT));
            }
            for cand in rules::candidates(&src) {
                let Neighbour::Equal(n) = octree.neighbour(node, &cand.dirs[..cand.n]) else { continue };
                self.leaves.clear();
                octree.leaves_under(n, &mut self.leaves);
                let mut changed = false;
                for &leaf in &self.leaves {
                    let b = octree.leaf_bounds(leaf);
                    for face in Dir::ALL.into_iter().filter(|f| cand.faces & (1 << f.index()) != 0) {
                        if states.get(leaf, face, light) != FaceState::Pending {
                            continue;
                        }
                        self.tests += 1;
                        if let Some(budget) = src.vouches_for(&b, face, hull, &self.t) {
                            states.set(leaf, face, light, FaceState::Propagated { budget });
                            self.log.push(Propagated { leaf, face, light, rule: cand.rule, source: node });
                            changed = true;
                        }
                    }
                }
                if changed {
                    next.push(n);
                }
            }
            for n in next {
                if !std::mem::replace(&mut self.queued[n.idx()], true) {
                    queue.push_back(n);
                }
            }
        }
        self.log.len() - before
    }
}
