//! Refinement of the octree after the records are known (SPEC §4.8, thesis §5.8-5.9).
//!
//! After a construction round, every leaf that may still split is passed along a **chain of
//! criteria** (the thesis' Chain of Responsibility); the first criterion that asks for a split takes
//! the credit, and the leaf is split into 8 children ([`crate::octree::Octree::split_leaves`]). The
//! next round computes the children's records; the records of every other leaf do not depend on how
//! other leaves are split, so they are reused as they are. Rounds stop when no leaf asks, or when
//! every leaf that asks has split `max_split_depth` times already: that bound is what stops a chain
//! that would split without end (an umbra edge crossing every child again).
//!
//! The criteria look at the faces of the leaf that lie on its boundary: each such face is the union
//! of four child faces (its quarters), and a child face sees the light through a sub-shaft of the
//! parent face's shaft, so what the parent's regions say about a quarter holds for the child's face:
//! - **umbra rule 1** ([`Criterion::UmbraFull`]): some quarter of a face lies fully in that face's
//!   umbra (grown by the margin, as for removal, §4.6), so after the split a child face would be fully
//!   dark and lose its record;
//! - **umbra rule 2** ([`Criterion::UmbraFree`]): a face whose blockers cast some shadow on it has a
//!   quarter that touches neither its umbra nor its penumbra, so after the split a child face would
//!   need no blocker tests;
//! - **blockers per face** ([`Criterion::Blockers`]): some (face, light) has more than
//!   [`MaxBlockers`] blockers (a fixed limit, or the thesis' adaptive limit).
//!
//! A fully dark face (removed already) asks nothing: its children could not gain. The criteria only
//! choose where to split; exactness never depends on them, since every round computes the new leaves'
//! records from scratch, exactly as for an unrefined octree.

use std::collections::BTreeMap;

use glam::DVec2;
use rayon::prelude::*;

use super::regions::FaceRegions;
use super::round::Round;
use crate::lie::frame::{Tri2, UNITS};
use crate::lie::RecordKind;
use crate::octree::{LeafId, Octree};
use crate::scene::Scene;

pub use crate::lie::params::{Criterion, MaxBlockers, RefineParams};

/// What a criterion sees of one kept record of the leaf: its blocker count and its regions.
#[derive(Clone, Copy, Debug)]
pub struct FaceView<'a> {
    /// Blockers of the record.
    pub blockers: usize,
    /// Its umbra and penumbra, if computed.
    pub regions: Option<&'a FaceRegions>,
}

/// The four quarters of a face, in its units: the faces of the four children on it.
pub fn quarters() -> [(DVec2, DVec2); 4] {
    let h = 0.5 * UNITS;
    std::array::from_fn(|i| {
        let lo = DVec2::new(if i & 1 != 0 { h } else { 0.0 }, if i & 2 != 0 { h } else { 0.0 });
        (lo, lo + DVec2::splat(h))
    })
}

impl Criterion {
    /// True if this criterion asks to split a leaf at `depth` (scene of `triangles` triangles) whose
    /// kept records are `faces`.
    pub fn asks(self, faces: &[FaceView], p: &RefineParams, triangles: usize, depth: u32) -> bool {
        match self {
            Criterion::UmbraFull => faces.iter().filter_map(|f| f.regions).any(quarter_in_umbra),
            Criterion::UmbraFree => faces.iter().filter(|f| f.blockers > 0).filter_map(|f| f.regions).any(quarter_free),
            Criterion::Blockers => {
                let limit = p.blockers.map_or(usize::MAX, |m| m.limit(triangles, depth));
                faces.iter().any(|f| f.blockers > limit)
            }
        }
    }
}

/// The first criterion of `p`'s chain that asks to split the leaf, if any (see [`Criterion::asks`]).
pub fn decide(faces: &[FaceView], p: &RefineParams, triangles: usize, depth: u32) -> Option<Criterion> {
    p.chain().into_iter().find(|c| c.asks(faces, p, triangles, depth))
}

/// Rule 1 on one face: some quarter lies in the umbra.
fn quarter_in_umbra(r: &FaceRegions) -> bool {
    !r.umbra.is_empty() && quarters().iter().any(|&(lo, hi)| r.square_in_umbra(lo, hi))
}

/// Rule 2 on one face with some shadow: some quarter, grown by the margin, meets no umbra or penumbra
/// triangle. A face whose blockers cast no shadow at all is skipped: its children cannot gain.
fn quarter_free(r: &FaceRegions) -> bool {
    if r.umbra.is_empty() && r.penumbra.is_empty() {
        return false;
    }
    let m = r.margin_units();
    quarters().iter().any(|&(lo, hi)| {
        let (lo, hi) = (lo - DVec2::splat(m), hi + DVec2::splat(m));
        !r.umbra.iter().chain(&r.penumbra).any(|t| triangle_meets_square(t, lo, hi))
    })
}

/// True if the triangle `t` and the square `[lo, hi]` overlap (boundaries included): separating-axis
/// test on the square's two axes and the triangle's three edge normals.
pub fn triangle_meets_square(t: &Tri2, lo: DVec2, hi: DVec2) -> bool {
    let p = t.map(|v| DVec2::new(v[0] as f64, v[1] as f64));
    let (tmin, tmax) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
    if tmax.x < lo.x || tmin.x > hi.x || tmax.y < lo.y || tmin.y > hi.y {
        return false;
    }
    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    (0..3).all(|i| {
        let n = (p[(i + 1) % 3] - p[i]).perp();
        let tri = p.map(|q| n.dot(q));
        let (a, b) = (tri.iter().copied().fold(f64::MAX, f64::min), tri.iter().copied().fold(f64::MIN, f64::max));
        let sq = corners.map(|q| n.dot(q));
        let (c, d) = (sq.iter().copied().fold(f64::MAX, f64::min), sq.iter().copied().fold(f64::MIN, f64::max));
        b >= c && d >= a
    })
}

/// The refinement's bookkeeping across rounds (stage 7): how often each leaf's region of the first
/// octree has been split, the split nodes per round (stored in the P-LIE, replayed on load), and the
/// splits each criterion asked for.
pub(super) struct Refiner {
    /// Per leaf of the current octree: times its region of the first octree has been split.
    level: Vec<u32>,
    /// Per round: the nodes of the leaves split, in order.
    pub(super) splits: Vec<Vec<u32>>,
    /// Leaves split, by the criterion that asked.
    pub(super) by_criterion: BTreeMap<&'static str, usize>,
    /// True if refinement ended at the octree's node cap ([`crate::octree::max_nodes`]).
    pub(super) capped: bool,
}

impl Refiner {
    /// Nothing split yet on `octree`.
    pub(super) fn new(octree: &Octree) -> Refiner {
        Refiner {
            level: vec![0; octree.leaf_count()],
            splits: Vec::new(),
            by_criterion: BTreeMap::new(),
            capped: false,
        }
    }

    /// The progress stage name of the next round.
    pub(super) fn stage(&self) -> String {
        if self.splits.is_empty() {
            "blockers".to_string()
        } else {
            format!("refine {}", self.splits.len())
        }
    }

    /// The leaves the chain of criteria splits after `round`, in leaf order (none: refinement ends).
    pub(super) fn choose(&mut self, scene: &Scene, octree: &Octree, round: &Round, p: &RefineParams) -> Vec<LeafId> {
        let lights = scene.lights.len();
        let triangles = scene.triangles.len();
        let candidates: Vec<LeafId> =
            octree.leaves().filter(|&l| self.level[l.idx()] < p.max_split_depth && octree.can_split(l)).collect();
        let decisions: Vec<Option<Criterion>> = candidates
            .par_iter()
            .map(|&l| {
                let faces: Vec<FaceView> = (0..lights)
                    .flat_map(|i| round.tasks[l.idx() * lights + i].records.iter().flatten())
                    .map(|r| match r.kind {
                        RecordKind::Listed => FaceView { blockers: r.blockers.len(), regions: r.regions.as_ref() },
                        // More blockers than the cap; its regions lack the penumbra.
                        RecordKind::Scene => FaceView { blockers: usize::MAX, regions: None },
                    })
                    .collect();
                decide(&faces, p, triangles, octree.leaf_depth(l))
            })
            .collect();
        let split: Vec<LeafId> =
            candidates.iter().zip(&decisions).filter(|(_, d)| d.is_some()).map(|(&l, _)| l).collect();
        // Refinement ends before the octree would pass its node cap.
        if octree.node_count() + 8 * split.len() > crate::octree::max_nodes(triangles) {
            self.capped = true;
            return Vec::new();
        }
        if !split.is_empty() {
            for d in decisions.iter().flatten() {
                *self.by_criterion.entry(d.name()).or_default() += 1;
            }
        }
        split
    }

    /// Splits `split` (from [`Refiner::choose`]): the refined octree and, per new leaf, the leaf of
    /// `octree` it is (`None` for a new child).
    pub(super) fn split(&mut self, scene: &Scene, octree: &Octree, split: &[LeafId]) -> (Octree, Vec<Option<LeafId>>) {
        self.splits.push(split.iter().map(|&l| octree.leaf_node(l).0).collect());
        let (refined, origin) = octree.split_leaves(scene, split);
        let kept = origin.iter().filter(|o| o.is_some()).count();
        self.level = origin
            .iter()
            .enumerate()
            .map(|(i, o)| match o {
                Some(old) => self.level[old.idx()],
                None => self.level[split[(i - kept) / 8].idx()] + 1,
            })
            .collect();
        (refined, origin)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::construct::blockers::GatherScratch;
    use crate::construct::propagation::Tolerances;
    use crate::construct::record::face_record;
    use crate::construct::tolerance;
    use crate::lie::PlieParams;
    use crate::octree::{Dir, Octree, OctreeParams};
    use crate::scene::{LightId, Scene, SceneBuilder};

    /// A floor `[-1, 1]^2` at `y = 0`, a light `[0.4, 0.6]^2` at `y = 2` facing down, and `blockers`
    /// (`[x0, x1] x [z0, z1]` rectangles at `y = 1.5`). The root cube is centred at `(0, 1, 0)`, so
    /// the lower `+x +z` leaf's top face is `[0, 1]^2` at `y = 1`; it is the leaf's only face that
    /// sees the light. The plates hang halfway between it and the light: from a light vertex `a`, a
    /// plate point `p` projects to `2 p - a`.
    fn plate_scene(blockers: &[[f32; 4]]) -> Scene {
        let mut b = SceneBuilder::new("plates");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        let v = Vec3::new;
        b.quad(v(-1.0, 0.0, -1.0), v(-1.0, 0.0, 1.0), v(1.0, 0.0, 1.0), v(1.0, 0.0, -1.0), m);
        for &[x0, x1, z0, z1] in blockers {
            b.quad(v(x0, 1.5, z0), v(x0, 1.5, z1), v(x1, 1.5, z1), v(x1, 1.5, z0), m);
        }
        let (a, c) = (0.4, 0.6);
        b.light("light", &[v(a, 2.0, a), v(c, 2.0, a), v(c, 2.0, c), v(a, 2.0, c)], Vec3::ONE);
        b.build().unwrap()
    }

    /// What the chain sees of the lower `+x +z` leaf: its kept records, computed as the builder does.
    fn decide_leaf(blockers: &[[f32; 4]], p: &RefineParams) -> Option<Criterion> {
        let scene = plate_scene(blockers);
        let octree = Octree::build(&scene, OctreeParams::thesis()).expect("valid octree parameters");
        let leaf = octree.locate(Vec3::new(0.5, 0.5, 0.5)).unwrap();
        let top = octree.leaf_bounds(leaf);
        assert!((top.max.y - 1.0).abs() < 1e-2 && top.min.x.abs() < 1e-2 && (top.max.x - 1.0).abs() < 1e-2);
        let tol = tolerance(&scene, &octree);
        let abs = crate::construct::abs_scale(&octree);
        let tols = Tolerances::new(tol, abs);
        let mut scratch = GatherScratch::new(scene.triangles.len());
        let params = PlieParams { refine: *p, ..PlieParams::thesis() };
        let records: Vec<_> = Dir::ALL
            .into_iter()
            .filter_map(|f| {
                let corners = f.face_corners(&top);
                let sees = crate::construct::data_objects::face_sees_light(&corners, f.normal(), &scene.lights[0], tol);
                sees.then(|| face_record(&scene, &octree, (leaf, LightId(0)), f, &tols, abs, params, &mut scratch))
            })
            .filter_map(|o| o.record)
            .collect();
        assert!(records.len() <= 1, "only the top face sees the light");
        let faces: Vec<FaceView> =
            records.iter().map(|r| FaceView { blockers: r.blockers.len(), regions: r.regions.as_ref() }).collect();
        decide(&faces, p, scene.triangles.len(), octree.leaf_depth(leaf))
    }

    const RULE_1: RefineParams =
        RefineParams { umbra_full: true, umbra_free: false, blockers: None, max_split_depth: 2 };
    const RULE_2: RefineParams =
        RefineParams { umbra_full: false, umbra_free: true, blockers: None, max_split_depth: 2 };

    #[test]
    fn rule_1_fires_when_a_quarter_is_in_umbra() {
        // Plate [0.4, 0.95]^2: umbra [0.4, 1]^2 of the top face, its upper quarter included.
        let big = [[0.4, 0.95, 0.4, 0.95]];
        assert_eq!(decide_leaf(&big, &RULE_1), Some(Criterion::UmbraFull));
        // Its penumbra reaches every quarter: rule 2 must not fire.
        assert_eq!(decide_leaf(&big, &RULE_2), None);
    }

    #[test]
    fn rule_2_fires_when_a_quarter_is_free() {
        // Plate [0.7, 0.8]^2: no umbra (its projections only touch), shadow only in [0.8, 1]^2.
        let small = [[0.7, 0.8, 0.7, 0.8]];
        assert_eq!(decide_leaf(&small, &RULE_1), None);
        assert_eq!(decide_leaf(&small, &RULE_2), Some(Criterion::UmbraFree));
        // Both on: the chain credits the first that asks.
        assert_eq!(decide_leaf(&small, &RefineParams::thesis_umbra()), Some(Criterion::UmbraFree));
        assert_eq!(decide_leaf(&[[0.4, 0.95, 0.4, 0.95]], &RefineParams::thesis_umbra()), Some(Criterion::UmbraFull));
    }

    #[test]
    fn neither_rule_fires_on_a_penumbra_band_through_every_quarter() {
        // A bar across the face at z in [0.45, 0.55]: penumbra z in [0.3, 0.7] crosses all four
        // quarters, and its umbra is a line (nothing after erosion).
        let bar = [[-1.0, 1.0, 0.45, 0.55]];
        assert_eq!(decide_leaf(&bar, &RULE_1), None);
        assert_eq!(decide_leaf(&bar, &RULE_2), None);
        // The bar is 2 triangles: the blockers criterion compares strictly with its limit.
        let by = |n| RefineParams { blockers: Some(MaxBlockers::Fixed(n)), ..RefineParams::none() };
        assert_eq!(decide_leaf(&bar, &by(1)), Some(Criterion::Blockers));
        assert_eq!(decide_leaf(&bar, &by(2)), None);
    }

    #[test]
    fn a_fully_dark_face_asks_nothing() {
        // A plate over everything: the top face is fully dark and removed; its children cannot gain.
        let all = [[-1.0, 1.0, -1.0, 1.0]];
        assert_eq!(decide_leaf(&all, &RefineParams::thesis_umbra()), None);
        let by0 = RefineParams { blockers: Some(MaxBlockers::Fixed(0)), ..RefineParams::none() };
        assert_eq!(decide_leaf(&all, &by0), None, "no kept record, so no blockers to count");
    }

    #[test]
    fn square_triangle_overlap() {
        let t: Tri2 = [[0, 0], [10, 0], [0, 10]];
        let sq = |a: f64, b: f64, c: f64, d: f64| (DVec2::new(a, b), DVec2::new(c, d));
        let meets = |(lo, hi)| triangle_meets_square(&t, lo, hi);
        assert!(meets(sq(1.0, 1.0, 2.0, 2.0)), "inside");
        assert!(meets(sq(-5.0, -5.0, 20.0, 20.0)), "contains");
        assert!(meets(sq(5.0, 5.0, 8.0, 8.0)), "touches the hypotenuse at (5, 5)");
        assert!(!meets(sq(6.0, 6.0, 8.0, 8.0)), "beyond the hypotenuse, inside the bounding box");
        assert!(!meets(sq(11.0, 0.0, 12.0, 1.0)), "right of it");
    }

    #[test]
    fn adaptive_limit_decreases_with_depth() {
        let a = MaxBlockers::Adaptive;
        assert_eq!(a.limit(2766, 1), 1383);
        assert_eq!(a.limit(2766, 3), 461);
        assert!(a.limit(2766, 4) < a.limit(2766, 3));
        assert_eq!(MaxBlockers::Fixed(700).limit(2766, 9), 700);
    }

    #[test]
    fn chain_order_and_validation() {
        let p = RefineParams { blockers: Some(MaxBlockers::Fixed(0)), ..RefineParams::thesis_umbra() };
        assert_eq!(p.chain(), Criterion::ALL.to_vec());
        assert!(p.enabled());
        assert!(!RefineParams::none().enabled());
        assert!(!RefineParams { max_split_depth: 0, ..p }.enabled());
        assert!(p.validate(false).is_err(), "umbra rules without regions");
        assert!(RefineParams { blockers: Some(MaxBlockers::Adaptive), ..RefineParams::none() }.validate(false).is_ok());
        // The blockers criterion compares strictly: a face at the limit does not split.
        let f = [FaceView { blockers: 5, regions: None }];
        let q = RefineParams { blockers: Some(MaxBlockers::Fixed(5)), ..RefineParams::none() };
        assert_eq!(decide(&f, &q, 100, 1), None);
        let q = RefineParams { blockers: Some(MaxBlockers::Fixed(4)), ..q };
        assert_eq!(decide(&f, &q, 100, 1), Some(Criterion::Blockers));
    }
}
