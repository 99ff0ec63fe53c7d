//! The propagation rules of SPEC §4.7 (thesis chapter 6) on hand-built configurations: one, two and
//! three lit faces with every sub-case of which are dark, the general rule, recursion and inner-node
//! neighbours, and configurations where a rule must not fire.
//!
//! The octree is a regular grid of tiny triangles (no real blockers): the test marks the source cell's
//! faces dark by hand, runs the propagator, and checks which faces it deletes. An independent oracle
//! checks every deletion: each sampled segment from a deleted face to the light must cross one of the
//! faces marked dark by hand.

use glam::{Vec2, Vec3};
use plie::geometry::Aabb;
use plie::internals::construct::propagation::{FaceState, FaceStates, Propagated, Propagator, Rule, Tolerances};
use plie::octree::{Dir, LeafId, Octree, OctreeParams};
use plie::{LightId, Scene, SceneBuilder};

/// Half-size of the box the corner triangles fix: the root is about `[-8, 8]³`, depth-3 cells about 2.
const R: f32 = 8.0;
const L0: LightId = LightId(0);

/// A hand-built configuration: the scene, its octree, and the source leaf `c`.
struct Config {
    scene: Scene,
    octree: Octree,
    c: LeafId,
}

/// Tiny triangles: one at each corner of `[-R, R]³` and one in the middle of every grid cell, depth 3
/// (8 per axis) everywhere, or depth 2 (4 per axis) above `y = 0` when `coarse_top`.
fn grid_triangles(b: &mut SceneBuilder, coarse_top: bool) {
    let m = b.diffuse("grey", Vec3::splat(0.5));
    let mut tiny = |p: Vec3| {
        b.triangle(p, p + Vec3::new(0.01, 0.0, 0.0), p + Vec3::new(0.0, 0.01, 0.005), m);
    };
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { -R } else { R },
            if i & 2 == 0 { -R } else { R },
            if i & 4 == 0 { -R } else { R },
        );
        tiny(c * 0.999);
    }
    for n in [8, 4] {
        let w = 2.0 * R / n as f32;
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let p = Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * w - Vec3::splat(R);
                    if (n == 8) != (coarse_top && p.y > 0.0) {
                        tiny(p);
                    }
                }
            }
        }
    }
}

fn params() -> OctreeParams {
    OctreeParams { max_triangles: 3, max_depth: 3 }
}

/// The leaf containing the cell-centre of grid index `idx` (depth 3: 8 per axis).
fn leaf_at(o: &Octree, idx: [i32; 3]) -> LeafId {
    let w = 2.0 * R / 8.0;
    o.locate(Vec3::new(idx[0] as f32 + 0.5, idx[1] as f32 + 0.5, idx[2] as f32 + 0.5) * w - Vec3::splat(R)).unwrap()
}

/// A configuration whose source leaf has grid index `c` and whose light is the horizontal square,
/// facing down, `x, z` in `[x0, x1] x [z0, z1]` at height `y`, all in units of the source cell from its
/// minimum corner.
fn config(coarse_top: bool, c: [i32; 3], x: (f32, f32), y: f32, z: (f32, f32)) -> Config {
    let mut b = SceneBuilder::new("grid");
    grid_triangles(&mut b, coarse_top);
    // A scene needs a light: a tiny one in the bottom corner cell, where the grid is at its deepest.
    let q = |x: f32, z: f32| Vec3::new(x, -0.99 * R, z) - Vec3::new(0.99 * R, 0.0, 0.99 * R);
    b.light("probe", &[q(0.0, 0.0), q(0.0, 0.1), q(0.1, 0.1), q(0.1, 0.0)], Vec3::ONE);
    let bare = b.build().unwrap();
    let o = Octree::build(&bare, params()).expect("valid octree parameters");
    let cell = o.leaf_bounds(leaf_at(&o, c));
    let s = cell.size().x;
    let p = |u: f32, v: f32, w: f32| cell.min + Vec3::new(u, v, w) * s;
    let mut b = SceneBuilder::new("grid");
    grid_triangles(&mut b, coarse_top);
    // Counter-clockwise seen from below: emits down.
    b.light("l", &[p(x.0, y, z.0), p(x.1, y, z.0), p(x.1, y, z.1), p(x.0, y, z.1)], Vec3::ONE);
    let scene = b.build().unwrap();
    let octree = Octree::build(&scene, params()).expect("valid octree parameters");
    assert_eq!(octree.leaf_count(), o.leaf_count(), "the light must not change the grid");
    let c = leaf_at(&octree, c);
    assert_eq!(octree.leaf_bounds(c), cell);
    Config { scene, octree, c }
}

fn tolerances(cfg: &Config) -> (f32, Tolerances) {
    let root = cfg.octree.root_bounds();
    let tol = cfg.scene.scale().max(root.size().max_element()) * plie::internals::construct::TOLERANCE_REL;
    (tol, Tolerances::new(tol, root.min.abs().max(root.max.abs()).max_element()))
}

/// The faces of leaf `l` that see the light.
fn lit(cfg: &Config, states: &FaceStates, l: LeafId) -> Vec<Dir> {
    let _ = cfg;
    Dir::ALL.into_iter().filter(|&f| states.get(l, f, L0) != FaceState::NoLight).collect()
}

/// Marks faces of the source dark (with a budget far beyond the scene) or kept, propagates from the
/// source, checks every deletion with the oracle, and returns the deletions.
fn run(cfg: &Config, dark: &[Dir], kept: &[Dir], budget: f64) -> (FaceStates, Vec<Propagated>) {
    let (tol, t) = tolerances(cfg);
    let mut states = FaceStates::new(&cfg.scene, &cfg.octree, tol);
    let mut want_lit: Vec<Dir> = dark.iter().chain(kept).copied().collect();
    want_lit.sort();
    assert_eq!(lit(cfg, &states, cfg.c), want_lit, "lit faces of the source");
    for &f in dark {
        states.set(cfg.c, f, L0, FaceState::Dark { budget });
    }
    for &f in kept {
        states.set(cfg.c, f, L0, FaceState::Kept);
    }
    let mut p = Propagator::new(&cfg.scene, &cfg.octree, t);
    p.run(&mut states, L0, &[cfg.octree.leaf_node(cfg.c)]);
    let seeded: Vec<(LeafId, Dir)> = dark.iter().map(|&f| (cfg.c, f)).collect();
    for d in &p.log {
        oracle(cfg, &seeded, d);
    }
    (states, p.log)
}

/// True if the segment `g -> y` crosses face `f` of box `b` outward (edges included, with slack).
fn crosses(g: Vec3, y: Vec3, b: &Aabb, f: Dir) -> bool {
    let k = f.axis();
    let w = if f.is_positive() { b.max[k] } else { b.min[k] };
    let d = y[k] - g[k];
    if d == 0.0 || (d > 0.0) != f.is_positive() {
        return false;
    }
    let t = (w - g[k]) / d;
    if !(0.0..=1.0).contains(&t) {
        return false;
    }
    let p = g + (y - g) * t;
    let slack = 1e-4 * b.size().x;
    (0..3).filter(|&a| a != k).all(|a| p[a] >= b.min[a] - slack && p[a] <= b.max[a] + slack)
}

/// Every sampled segment from the deleted face toward the light that a shadow ray could follow (it
/// leaves through the face, from in front of the light) crosses a face marked dark by hand.
fn oracle(cfg: &Config, seeded: &[(LeafId, Dir)], d: &Propagated) {
    let light = &cfg.scene.lights[0];
    let q = d.face.face_corners(&cfg.octree.leaf_bounds(d.leaf));
    let mut checked = 0;
    for i in 0..400u32 {
        let (a, b) = ((i % 20) as f32 / 19.0, (i / 20) as f32 / 19.0);
        let g = q[0] + (q[1] - q[0]) * a + (q[3] - q[0]) * b;
        let u = Vec2::new(((i * 7 + 3) % 17) as f32 / 16.0, ((i * 11 + 5) % 13) as f32 / 12.0);
        let y = light.sample(u);
        if (y - g).dot(d.face.normal()) <= 0.0 || (g - y).dot(light.normal) <= 0.0 {
            continue;
        }
        checked += 1;
        let ok = seeded.iter().any(|&(l, f)| crosses(g, y, &cfg.octree.leaf_bounds(l), f));
        assert!(ok, "{d:?}: segment {g} -> {y} crosses no dark face");
    }
    assert!(checked > 0, "{d:?}: nothing to check");
}

fn deleted(states: &FaceStates, l: LeafId, f: Dir) -> bool {
    matches!(states.get(l, f, L0), FaceState::Propagated { .. })
}

fn rule_of(log: &[Propagated], l: LeafId, f: Dir) -> Option<Rule> {
    log.iter().find(|d| d.leaf == l && d.face == f).map(|d| d.rule)
}

const BIG: f64 = 1e9;
const C: [i32; 3] = [3, 3, 3];

fn at(cfg: &Config, d: [i32; 3]) -> LeafId {
    leaf_at(&cfg.octree, [C[0] + d[0], C[1] + d[1], C[2] + d[2]])
}

#[test]
fn one_lit_face_propagates_down_the_column() {
    // Light straight above the cell, inside its slab: only Up sees it.
    let cfg = config(false, C, (0.3, 0.7), 2.5, (0.3, 0.7));
    let (states, log) = run(&cfg, &[Dir::Up], &[], BIG);
    for j in 1..=3 {
        let n = at(&cfg, [0, -j, 0]);
        assert!(deleted(&states, n, Dir::Up), "cell {j} below");
        assert_eq!(rule_of(&log, n, Dir::Up), Some(Rule::OneFace));
    }
    assert_eq!(log.len(), 3, "{log:?}");
}

#[test]
fn one_lit_face_must_not_fire_when_not_dark_or_out_of_budget() {
    let cfg = config(false, C, (0.3, 0.7), 2.5, (0.3, 0.7));
    let (_, log) = run(&cfg, &[], &[Dir::Up], BIG);
    assert!(log.is_empty(), "a kept face proves nothing: {log:?}");
    // Rays from the cell below to the light are about 6 long: a budget of 3 vouches for none.
    let (_, log) = run(&cfg, &[Dir::Up], &[], 3.0);
    assert!(log.is_empty(), "budget too short: {log:?}");
    // A dark face that cannot vouch (budget 0: its umbra does not bound grazing rays).
    let (_, log) = run(&cfg, &[Dir::Up], &[], 0.0);
    assert!(log.is_empty(), "{log:?}");
}

#[test]
fn one_lit_face_must_not_fire_when_the_light_reaches_into_the_cell() {
    // A light inside the source cell, reaching out through its Right face only: rays from the left
    // neighbour end inside the cell.
    let cfg = config(false, C, (0.6, 1.4), 0.5, (0.3, 0.7));
    let (_, log) = run(&cfg, &[Dir::Right], &[], BIG);
    assert!(log.is_empty(), "{log:?}");
}

#[test]
fn inner_node_neighbour_loses_the_faces_of_all_its_leaves() {
    // Depth-2 leaves above y = 0, depth-3 below: the source (depth 2, just above y = 0) has an inner
    // node below it whose 8 leaves all lose their Up face, and so do the 8 of the next node down.
    let cfg = config(true, [4, 4, 4], (0.1, 0.4), 1.5, (0.1, 0.4));
    assert_eq!(cfg.octree.leaf_depth(cfg.c), 2);
    let (states, log) = run(&cfg, &[Dir::Up], &[], BIG);
    let node = cfg.octree.leaf_node(cfg.c);
    let mut below = Vec::new();
    for steps in 1..=2 {
        let plie::octree::Neighbour::Equal(mut n) = cfg.octree.neighbour(node, &[Dir::Down]) else { panic!() };
        if steps == 2 {
            let plie::octree::Neighbour::Equal(m) = cfg.octree.neighbour(n, &[Dir::Down]) else { panic!() };
            n = m;
        }
        assert!(cfg.octree.node_leaf(n).is_none(), "an inner node");
        let mut leaves = Vec::new();
        cfg.octree.leaves_under(n, &mut leaves);
        assert_eq!(leaves.len(), 8);
        below.extend(leaves);
    }
    for &l in &below {
        assert!(deleted(&states, l, Dir::Up), "{l:?}");
    }
    assert!(log.len() >= 16, "{log:?}");
    assert!(log.iter().all(|d| d.rule == Rule::OneFace), "{log:?}");
}

#[test]
fn two_lit_faces_one_dark_fires_only_between_45_degree_limits() {
    // Light above and to the right: Up and Right see it. Only Up is dark.
    let cfg = config(false, C, (1.8, 2.2), 2.5, (0.3, 0.7));
    let (states, log) = run(&cfg, &[Dir::Up], &[Dir::Right], BIG);
    for j in 1..=3 {
        let n = at(&cfg, [-j, -j, 0]);
        assert!(deleted(&states, n, Dir::Up), "diagonal neighbour {j}");
        assert_eq!(rule_of(&log, n, Dir::Up), Some(Rule::TwoFacesOneDark));
    }
    assert!(!deleted(&states, at(&cfg, [-1, -1, 0]), Dir::Right));
    // Too shallow: rays from the diagonal neighbour leave through Right, which is not dark...
    let cfg = config(false, C, (2.8, 3.2), 2.5, (0.3, 0.7));
    let (_, log) = run(&cfg, &[Dir::Up], &[Dir::Right], BIG);
    assert!(log.is_empty(), "{log:?}");
    // ... and once it is, the face is proven.
    let (states, _) = run(&cfg, &[Dir::Up, Dir::Right], &[], BIG);
    assert!(deleted(&states, at(&cfg, [-1, -1, 0]), Dir::Up));
    // Too steep: rays from the diagonal neighbour pass beside the cell.
    let cfg = config(false, C, (1.1, 1.3), 4.5, (0.3, 0.7));
    let (_, log) = run(&cfg, &[Dir::Up], &[Dir::Right], BIG);
    assert!(log.is_empty(), "{log:?}");
}

#[test]
fn two_lit_faces_both_dark_and_the_general_rule() {
    let cfg = config(false, C, (1.8, 2.2), 2.5, (0.3, 0.7));
    let (states, log) = run(&cfg, &[Dir::Up, Dir::Right], &[], BIG);
    let n = at(&cfg, [-1, -1, 0]);
    for f in [Dir::Up, Dir::Right] {
        assert!(deleted(&states, n, f), "{f:?}");
        assert_eq!(rule_of(&log, n, f), Some(Rule::TwoFacesBothDark));
    }
    // The general rule: the faces shared with the source.
    assert_eq!(rule_of(&log, at(&cfg, [0, -1, 0]), Dir::Up), Some(Rule::General));
    assert_eq!(rule_of(&log, at(&cfg, [-1, 0, 0]), Dir::Right), Some(Rule::General));
    // Too steep: the diagonal neighbour's Up face is not behind the source.
    let cfg = config(false, C, (1.1, 1.3), 4.5, (0.3, 0.7));
    let (states, _) = run(&cfg, &[Dir::Up, Dir::Right], &[], BIG);
    assert!(!deleted(&states, at(&cfg, [-1, -1, 0]), Dir::Up));
    assert!(deleted(&states, at(&cfg, [0, -1, 0]), Dir::Up), "the general rule still holds");
}

#[test]
fn general_rule_must_not_fire_beyond_the_budget() {
    let cfg = config(false, C, (1.8, 2.2), 2.5, (0.3, 0.7));
    let (_, log) = run(&cfg, &[Dir::Up, Dir::Right], &[], 4.0);
    assert!(log.is_empty(), "rays from the neighbours are longer than 4: {log:?}");
}

#[test]
fn three_lit_faces_all_dark() {
    // Light above, right and in front: Up, Right and Front see it.
    let cfg = config(false, C, (1.8, 2.2), 2.5, (1.8, 2.2));
    let (states, log) = run(&cfg, &[Dir::Up, Dir::Right, Dir::Front], &[], BIG);
    for j in 1..=3 {
        let n = at(&cfg, [-j, -j, -j]);
        for f in [Dir::Up, Dir::Right, Dir::Front] {
            assert!(deleted(&states, n, f), "corner neighbour {j}, {f:?}");
            assert_eq!(rule_of(&log, n, f), Some(Rule::ThreeFacesAllDark));
        }
    }
    // Too steep: rays from the corner neighbour's Up face pass beside the cell.
    let cfg = config(false, C, (1.1, 1.3), 4.5, (1.1, 1.3));
    let (states, _) = run(&cfg, &[Dir::Up, Dir::Right, Dir::Front], &[], BIG);
    assert!(!deleted(&states, at(&cfg, [-1, -1, -1]), Dir::Up));
}

#[test]
fn three_lit_faces_two_dark() {
    // Up and Right dark, Front kept: rays from the corner neighbour's Up face leave through Up before
    // reaching Front; from its Right face some leave through Front, so it must stay.
    let cfg = config(false, C, (1.8, 2.2), 2.5, (1.7, 2.0));
    let (states, log) = run(&cfg, &[Dir::Up, Dir::Right], &[Dir::Front], BIG);
    let n = at(&cfg, [-1, -1, -1]);
    assert!(deleted(&states, n, Dir::Up));
    assert_eq!(rule_of(&log, n, Dir::Up), Some(Rule::ThreeFacesTwoDark));
    assert!(!deleted(&states, n, Dir::Right), "rays from it reach the kept Front face");
    assert!(!deleted(&states, n, Dir::Front), "not proposed");
    // Light farther in front: some rays leave through Front first...
    let cfg = config(false, C, (2.1, 2.3), 2.5, (2.6, 2.9));
    let (states, _) = run(&cfg, &[Dir::Up, Dir::Right], &[Dir::Front], BIG);
    assert!(!deleted(&states, at(&cfg, [-1, -1, -1]), Dir::Up));
    // ... which, dark too, proves it.
    let (states, _) = run(&cfg, &[Dir::Up, Dir::Right, Dir::Front], &[], BIG);
    assert!(deleted(&states, at(&cfg, [-1, -1, -1]), Dir::Up));
}

#[test]
fn three_lit_faces_one_dark() {
    let cfg = config(false, C, (1.6, 2.0), 2.5, (1.6, 2.0));
    let (states, log) = run(&cfg, &[Dir::Up], &[Dir::Right, Dir::Front], BIG);
    let n = at(&cfg, [-1, -1, -1]);
    assert!(deleted(&states, n, Dir::Up));
    assert_eq!(rule_of(&log, n, Dir::Up), Some(Rule::ThreeFacesOneDark));
    // Shallower toward x: some rays leave through the kept Right face...
    let cfg = config(false, C, (2.6, 2.8), 2.5, (1.9, 2.2));
    let (states, _) = run(&cfg, &[Dir::Up], &[Dir::Right, Dir::Front], BIG);
    assert!(!deleted(&states, at(&cfg, [-1, -1, -1]), Dir::Up));
    // ... which, dark too, proves it (two of three dark).
    let (states, log) = run(&cfg, &[Dir::Up, Dir::Right], &[Dir::Front], BIG);
    assert_eq!(rule_of(&log, at(&cfg, [-1, -1, -1]), Dir::Up), Some(Rule::ThreeFacesTwoDark));
    assert!(deleted(&states, at(&cfg, [-1, -1, -1]), Dir::Up));
}
