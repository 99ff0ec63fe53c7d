//! Octree tests (SPEC §3 and SPEC §5 mode (a)) on generated scenes and on every built-in scene that
//! loads: triangle assignment against brute force, point location with its tie-break, conservative
//! front-to-back traversal against an f64 reference, `OctreeVisibility` against `Brute` on 10^5
//! segments per scene (many of them on cell faces, edges and corners), thread-count determinism, and
//! the neighbour queries of every node in all 26 directions, and its leaves on each face, against a
//! reference on integer cell coordinates.
//!
//! A hand-run timing is at the end: `cargo test -p plie --test octree hand_run_timing -- --ignored --nocapture`.

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use plie::geometry::{triangle_overlaps_box, Aabb};
use plie::octree::{Dir, LeafId, Neighbour, NodeId, Octree, OctreeParams, MAX_DEPTH_LIMIT};
use plie::visibility::{Brute, OctreeVisibility, QueryCtx, ShadowRay, Visibility};
use plie::{LightId, Scene, SceneBuilder, TriId};

// ---------------------------------------------------------------------------------------------------
// Fixtures

/// splitmix64: a tiny deterministic generator.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn in_box(&mut self, b: &Aabb) -> Vec3 {
        Vec3::new(self.range(b.min.x, b.max.x), self.range(b.min.y, b.max.y), self.range(b.min.z, b.max.z))
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

fn ceiling_light(b: &mut SceneBuilder, y: f32, x0: f32, x1: f32, z0: f32, z1: f32) {
    // Counter-clockwise seen from below: emits downwards.
    let p = [Vec3::new(x0, y, z0), Vec3::new(x1, y, z0), Vec3::new(x1, y, z1), Vec3::new(x0, y, z1)];
    b.light("light", &p, Vec3::splat(10.0));
}

/// A Cornell-like room: five walls as big quads, a short box, a light under the ceiling.
fn cornell() -> Scene {
    let mut b = SceneBuilder::new("cornell-like");
    let w = b.diffuse("white", Vec3::splat(0.75));
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * 5.5;
    b.quad(p(0.0, 0.0, 0.0), p(0.0, 0.0, 1.0), p(1.0, 0.0, 1.0), p(1.0, 0.0, 0.0), w); // floor
    b.quad(p(0.0, 1.0, 0.0), p(1.0, 1.0, 0.0), p(1.0, 1.0, 1.0), p(0.0, 1.0, 1.0), w); // ceiling
    b.quad(p(0.0, 0.0, 1.0), p(0.0, 1.0, 1.0), p(1.0, 1.0, 1.0), p(1.0, 0.0, 1.0), w); // back
    b.quad(p(0.0, 0.0, 0.0), p(0.0, 1.0, 0.0), p(0.0, 1.0, 1.0), p(0.0, 0.0, 1.0), w); // left
    b.quad(p(1.0, 0.0, 0.0), p(1.0, 0.0, 1.0), p(1.0, 1.0, 1.0), p(1.0, 1.0, 0.0), w); // right
                                                                                       // A short block, rotated a little, as 5 quads.
    let (c, h, r, a) = (Vec3::new(0.65, 0.0, 0.35), 0.3, 0.15, 0.3f32);
    let corner = |i: usize, y: f32| {
        let ang = a + i as f32 * std::f32::consts::FRAC_PI_2;
        (c + Vec3::new(ang.cos() * r, y, ang.sin() * r)) * 5.5
    };
    for i in 0..4 {
        let j = (i + 1) % 4;
        b.quad(corner(i, 0.0), corner(j, 0.0), corner(j, h), corner(i, h), w);
    }
    b.quad(corner(0, h), corner(1, h), corner(2, h), corner(3, h), w);
    ceiling_light(&mut b, 5.49, 2.2, 3.3, 2.2, 3.3);
    b.build().expect("valid scene")
}

/// A tessellated sphere (`2 * seg * (rings - 1)` triangles) over a floor, lit from above.
fn sphere(seg: usize, rings: usize) -> Scene {
    let mut b = SceneBuilder::new("sphere");
    let m = b.diffuse("grey", Vec3::splat(0.5));
    let (c, r) = (Vec3::new(0.1, 0.0, -0.2), 1.0);
    let v = |i: usize, j: usize| {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        let ph = std::f32::consts::TAU * (j % seg) as f32 / seg as f32;
        c + r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
    };
    for i in 0..rings {
        for j in 0..seg {
            if i > 0 {
                b.triangle(v(i, j), v(i, j + 1), v(i + 1, j + 1), m);
            }
            if i + 1 < rings {
                b.triangle(v(i, j), v(i + 1, j + 1), v(i + 1, j), m);
            }
        }
    }
    b.quad(
        Vec3::new(-3.0, -1.2, -3.0),
        Vec3::new(-3.0, -1.2, 3.0),
        Vec3::new(3.0, -1.2, 3.0),
        Vec3::new(3.0, -1.2, -3.0),
        m,
    );
    ceiling_light(&mut b, 2.0, -0.5, 0.5, -0.5, 0.5);
    b.build().expect("valid scene")
}

/// Many tiny triangles in a small cluster (deep cells there) and one big slanted triangle cutting
/// through the cluster and across the whole scene.
fn big_triangle() -> Scene {
    let mut b = SceneBuilder::new("big-triangle");
    let m = b.diffuse("grey", Vec3::splat(0.5));
    let mut rng = Rng::new(7);
    let cluster = Aabb::new(Vec3::splat(0.0), Vec3::splat(0.25));
    for _ in 0..1500 {
        let p = rng.in_box(&cluster);
        b.triangle(p, p + rng.unit() * 0.01, p + rng.unit() * 0.01, m);
    }
    b.triangle(Vec3::new(-1.0, -0.9, 1.1), Vec3::new(1.2, -0.6, -1.0), Vec3::new(0.2, 1.3, 0.1), m);
    ceiling_light(&mut b, 1.5, -0.3, 0.3, -0.3, 0.3);
    b.build().expect("valid scene")
}

/// Random triangles of random sizes.
fn random_triangles() -> Scene {
    let mut b = SceneBuilder::new("random");
    let m = b.diffuse("grey", Vec3::splat(0.5));
    let mut rng = Rng::new(11);
    let room = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
    for _ in 0..1500 {
        let p = rng.in_box(&room);
        let size = 0.01 * 40f32.powf(rng.f());
        b.triangle(p, p + rng.unit() * size, p + rng.unit() * size, m);
    }
    ceiling_light(&mut b, 1.2, -0.2, 0.2, -0.2, 0.2);
    b.build().expect("valid scene")
}

/// The generated scenes, then every built-in scene that loads.
fn scenes() -> Vec<Scene> {
    let mut v = vec![cornell(), sphere(40, 30), big_triangle(), random_triangles()];
    v.extend(plie::scene::builtin::NAMES.iter().filter_map(|n| plie::scene::builtin::load(n).ok()));
    v
}

const SMALL: OctreeParams = OctreeParams { max_triangles: 8, max_depth: 8 };

/// The default parameters, and for the small generated scenes also a small leaf limit (deep trees).
fn param_sets(s: &Scene) -> Vec<OctreeParams> {
    if s.triangle_count() <= 2500 {
        vec![OctreeParams::default(), SMALL]
    } else {
        vec![OctreeParams::default()]
    }
}

/// A point in, on a face of, on an edge of, or at a corner of a random leaf.
fn leaf_point(o: &Octree, rng: &mut Rng) -> (LeafId, Vec3) {
    let l = LeafId(rng.below(o.leaf_count()) as u32);
    let b = o.leaf_bounds(l);
    let mut p = rng.in_box(&b);
    let snapped = rng.below(4); // 0 = inside, 1 = face, 2 = edge, 3 = corner
    let first = rng.below(3);
    for k in 0..snapped {
        let axis = (first + k) % 3;
        p[axis] = if rng.below(2) == 0 { b.min[axis] } else { b.max[axis] };
    }
    (l, p)
}

/// A random point on a random triangle: inside, on an edge or at a vertex.
fn triangle_point(s: &Scene, rng: &mut Rng) -> (TriId, Vec3) {
    let t = TriId(rng.below(s.triangle_count()) as u32);
    let tri = s.triangle(t);
    let p = match rng.below(3) {
        0 => tri.v[rng.below(3)],
        1 => tri.v[0].lerp(tri.v[1 + rng.below(2)], rng.f()),
        _ => {
            let (u, v) = (rng.f(), rng.f());
            if u + v > 1.0 {
                tri.point(1.0 - u, 1.0 - v)
            } else {
                tri.point(u, v)
            }
        }
    };
    (t, p)
}

/// Segment number `i`: endpoints, origin triangle. Cycles through the kinds of segments that stress
/// the traversal.
fn segment(s: &Scene, o: &Octree, i: u64) -> (Vec3, Vec3, TriId) {
    let mut rng = Rng::new(i.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0xA5A5);
    let none = TriId(u32::MAX); // never a real triangle; `blocks` only compares with it
    let root = o.root_bounds();
    match i % 8 {
        0 => (rng.in_box(&root.expanded(0.1 * root.size().x)), rng.in_box(&root), none),
        1 => (leaf_point(o, &mut rng).1, leaf_point(o, &mut rng).1, none),
        2 => (leaf_point(o, &mut rng).1, triangle_point(s, &mut rng).1, none),
        3 => {
            // Axis-parallel, from a cell boundary.
            let p = leaf_point(o, &mut rng).1;
            let mut d = Vec3::ZERO;
            d[rng.below(3)] = rng.range(-0.7, 0.7) * root.size().x;
            (p, p + d, none)
        }
        4 => {
            // In a leaf's face plane: axis k always shared by both ends, each other axis sometimes (then
            // the segment runs along an edge line).
            let (l, mut p) = leaf_point(o, &mut rng);
            let b = o.leaf_bounds(l);
            let mut q = rng.in_box(&root);
            let k = rng.below(3);
            for j in 0..3 {
                if j == k || rng.below(3) == 0 {
                    let plane = if rng.below(2) == 0 { b.min[j] } else { b.max[j] };
                    p[j] = plane;
                    q[j] = plane;
                }
            }
            (p, q, none)
        }
        5 => {
            // Inside one leaf.
            let l = LeafId(rng.below(o.leaf_count()) as u32);
            let b = o.leaf_bounds(l);
            (rng.in_box(&b), rng.in_box(&b), none)
        }
        6 => {
            // Shading point to a light sample, as the renderer asks.
            let (t, x) = triangle_point(s, &mut rng);
            let light = &s.lights[0];
            let lt = s.triangle(light.triangles[rng.below(light.triangles.len())]);
            let (u, v) = (rng.f(), rng.f());
            let y = if u + v > 1.0 { lt.point(1.0 - u, 1.0 - v) } else { lt.point(u, v) };
            (x, y, t)
        }
        _ => (triangle_point(s, &mut rng).1, triangle_point(s, &mut rng).1, none),
    }
}

// ---------------------------------------------------------------------------------------------------
// Tests

#[test]
fn triangles_are_in_exactly_the_leaves_they_overlap() {
    for s in scenes() {
        for params in param_sets(&s) {
            let o = Octree::build(&s, params).expect("valid octree parameters");
            let report = o.validate(&s);
            assert!(report.is_ok(), "{}: {report}", s.name);
            let eps = o.eps();
            let wrong: Vec<LeafId> = o
                .leaves()
                .collect::<Vec<_>>()
                .into_par_iter()
                .filter(|&l| {
                    let b = o.leaf_bounds(l).expanded(eps);
                    let want: Vec<TriId> = (0..s.triangle_count() as u32)
                        .map(TriId)
                        .filter(|&t| triangle_overlaps_box(s.triangle(t), &b))
                        .collect();
                    want != o.leaf_triangles(l)
                })
                .collect();
            assert!(wrong.is_empty(), "{} {params:?}: leaves {wrong:?} have wrong lists", s.name);
            // Full leaves are at the maximum depth, or hold a hub (a vertex more than
            // `max_triangles` triangles share, `octree/hubs.rs`) whose triangles count once.
            let key = |v: Vec3| v.to_array().map(f32::to_bits);
            let mut valence: HashMap<[u32; 3], usize> = HashMap::new();
            for t in 0..s.triangle_count() as u32 {
                for v in s.triangle(TriId(t)).v {
                    *valence.entry(key(v)).or_default() += 1;
                }
            }
            let hubs: Vec<[u32; 3]> =
                valence.into_iter().filter(|&(_, n)| n > params.max_triangles).map(|(k, _)| k).collect();
            for l in o.leaves() {
                let tris = o.leaf_triangles(l);
                let b = o.leaf_bounds(l).expanded(eps);
                let inside: Vec<_> =
                    hubs.iter().filter(|h| b.contains(Vec3::from_array(h.map(f32::from_bits)))).collect();
                let n = match inside[..] {
                    [&h] => tris.iter().filter(|&&t| !s.triangle(t).v.iter().any(|&v| key(v) == h)).count() + 1,
                    _ => tris.len(),
                };
                assert!(n <= params.max_triangles || o.leaf_depth(l) == params.max_depth, "{}: leaf {l:?}", s.name);
            }
            // The leaves tile the root.
            let vol = |b: Aabb| (b.max.as_dvec3() - b.min.as_dvec3()).element_product();
            let sum: f64 = o.leaves().map(|l| vol(o.leaf_bounds(l))).sum();
            assert!((sum / vol(o.root_bounds()) - 1.0).abs() < 1e-9, "{}: leaves do not tile the root", s.name);
        }
    }
}

#[test]
fn generated_scenes_are_deep_where_they_should_be() {
    let s = sphere(40, 30);
    assert!(s.triangle_count() > 2000);
    assert!(Octree::build(&s, OctreeParams::default()).expect("valid octree parameters").depth() >= 3);
    assert!(Octree::build(&s, SMALL).expect("valid octree parameters").depth() >= 5);
    let s = big_triangle();
    let o = Octree::build(&s, SMALL).expect("valid octree parameters");
    let big = TriId(s.triangle_count() as u32 - 3); // before the two light triangles
    let holding = o.leaves().filter(|&l| o.leaf_triangles(l).contains(&big)).count();
    assert!(o.depth() >= 5 && holding >= 100, "depth {}, big triangle in {holding} leaves", o.depth());
}

#[test]
fn octree_visibility_matches_brute_force() {
    const SEGMENTS: u64 = 100_000;
    for s in scenes() {
        let trees: Vec<Octree> =
            param_sets(&s).into_iter().map(|p| Octree::build(&s, p).expect("valid octree parameters")).collect();
        let brute = Brute::new(&s);
        let modes: Vec<OctreeVisibility> = trees.iter().map(|o| OctreeVisibility::new(&s, o)).collect();
        let (occluded, mismatches) = (0..SEGMENTS)
            .into_par_iter()
            .fold(
                || (QueryCtx::new(s.triangle_count()), 0u64, Vec::new()),
                |(mut ctx, mut occ, mut bad), i| {
                    let (x, y, origin_tri) = segment(&s, &trees[(i / 8) as usize % trees.len()], i);
                    if x == y {
                        return (ctx, occ, bad);
                    }
                    let ray = ShadowRay::new(x, y, LightId(0), origin_tri, None);
                    let want = brute.occluded(&ray, &mut ctx);
                    occ += want as u64;
                    for (m, mode) in modes.iter().enumerate() {
                        if mode.occluded(&ray, &mut ctx) != want {
                            bad.push((i, m, x, y, want));
                        }
                    }
                    (ctx, occ, bad)
                },
            )
            .map(|(_, occ, bad)| (occ, bad))
            .reduce(|| (0, Vec::new()), |a, b| (a.0 + b.0, [a.1, b.1].concat()));
        let first: Vec<_> = mismatches.iter().take(5).collect();
        assert!(mismatches.is_empty(), "{}: {} mismatches, e.g. {first:?}", s.name, mismatches.len());
        let frac = occluded as f64 / SEGMENTS as f64;
        assert!(frac > 0.02 && frac < 0.98, "{}: {frac} occluded, the test says little", s.name);
    }
}

/// f64 reference: the parameter interval where the segment is in the closed box.
fn clip64(o: Vec3, d: Vec3, b: &Aabb) -> Option<(f64, f64)> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let (bmin, bmax): (DVec3, DVec3) = (b.min.as_dvec3(), b.max.as_dvec3());
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < bmin[k] || o[k] > bmax[k] {
                return None;
            }
        } else {
            let (a, c) = ((bmin[k] - o[k]) / d[k], (bmax[k] - o[k]) / d[k]);
            lo = lo.max(a.min(c));
            hi = hi.min(a.max(c));
        }
    }
    (lo <= hi).then_some((lo, hi))
}

#[test]
fn traversal_is_conservative_tight_and_front_to_back() {
    for s in [cornell(), sphere(40, 30), big_triangle(), random_triangles()] {
        let o = Octree::build(&s, SMALL).expect("valid octree parameters");
        let eps = o.eps();
        for i in 0..1500u64 {
            let (x, y, _) = segment(&s, &o, i);
            let d = y - x;
            let mut seen = Vec::new();
            o.for_each_leaf_on_segment(x, d, 0.0, 1.0, |l| {
                seen.push(l);
                true
            });
            let mut set = seen.clone();
            set.sort();
            set.dedup();
            assert_eq!(set.len(), seen.len(), "{}: segment {i} visits a leaf twice", s.name);
            for l in o.leaves() {
                let b = o.leaf_bounds(l);
                let visited = set.binary_search(&l).is_ok();
                assert!(clip64(x, d, &b).is_none() || visited, "{}: segment {i} skips leaf {l:?}", s.name);
                assert!(!visited || clip64(x, d, &b.expanded(2.0 * eps)).is_some(), "{}: {i} visits {l:?}", s.name);
            }
            if i % 8 == 0 {
                // Generic segments: entry parameters (of the grown boxes) never go back by more than the
                // eps overlap of neighbouring cells.
                let tol = 4.0 * eps as f64 / d.abs().min_element().max(1e-30) as f64 + 1e-6;
                let entry = |l: &LeafId| clip64(x, d, &o.leaf_bounds(*l).expanded(eps)).map_or(0.0, |c| c.0);
                for w in seen.windows(2) {
                    assert!(entry(&w[1]) >= entry(&w[0]) - tol, "{}: segment {i} out of order", s.name);
                }
            }
        }
    }
}

#[test]
fn overlapping_boxes_match_brute_force() {
    let s = big_triangle();
    let o = Octree::build(&s, SMALL).expect("valid octree parameters");
    let mut rng = Rng::new(3);
    for _ in 0..300 {
        let (a, b) = (leaf_point(&o, &mut rng).1, rng.in_box(&o.root_bounds().expanded(0.2)));
        let q = Aabb::from_points(&[a, a + (b - a) * rng.f()]);
        let mut got = Vec::new();
        o.for_each_leaf_overlapping(&q, |l| got.push(l));
        got.sort();
        let want: Vec<LeafId> = o.leaves().filter(|&l| o.leaf_bounds(l).expanded(o.eps()).overlaps(&q)).collect();
        assert_eq!(got, want);
    }
}

#[test]
fn locate_finds_the_leaf_and_breaks_ties_upwards() {
    for s in scenes() {
        let o = Octree::build(&s, SMALL).expect("valid octree parameters");
        let root = o.root_bounds();
        // Every leaf's lower corner belongs to it (ties go up), and so does its center.
        for l in o.leaves() {
            let b = o.leaf_bounds(l);
            assert_eq!(o.locate(b.min), Some(l), "{}: lower corner of {l:?}", s.name);
            assert_eq!(o.locate(b.center()), Some(l), "{}: center of {l:?}", s.name);
        }
        let mut rng = Rng::new(5);
        for i in 0..20_000 {
            let p = if i % 2 == 0 { rng.in_box(&root) } else { leaf_point(&o, &mut rng).1 };
            let l = o.locate(p).expect("inside the root");
            let b = o.leaf_bounds(l);
            assert!(b.contains(p), "{}: {p} not in {b:?}", s.name);
            for k in 0..3 {
                assert!(p[k] < b.max[k] || b.max[k] == root.max[k], "{}: {p} on an upper face of {b:?}", s.name);
            }
        }
        assert!(o.locate(root.max).is_some());
        for p in [root.min - Vec3::splat(1e-3), root.max + Vec3::new(0.0, 0.0, 1e-3), Vec3::NAN] {
            assert_eq!(o.locate(p), None, "{}: {p} is outside", s.name);
        }
    }
}

#[test]
fn build_is_deterministic_across_thread_counts() {
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("thread pool");
    let (one, two) = (pool(1), pool(2));
    // The big sphere has lists longer than the parallel chunk size.
    for s in [sphere(160, 60), random_triangles()] {
        for params in [OctreeParams::default(), SMALL] {
            let a = one.install(|| Octree::build(&s, params).expect("valid octree parameters"));
            let b = two.install(|| Octree::build(&s, params).expect("valid octree parameters"));
            let c = two.install(|| Octree::build(&s, params).expect("valid octree parameters"));
            assert!(a == b && b == c, "{}: builds differ", s.name);
        }
    }
}

/// A cell in integer coordinates of the finest possible grid over the root: lower corner and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Cell {
    min: [i64; 3],
    size: i64,
}

/// Converts boxes to [`Cell`]s, independently of how the octree computes its boxes.
struct Grid {
    min: DVec3,
    size: f64,
}

impl Grid {
    const RES: i64 = 1 << MAX_DEPTH_LIMIT;

    fn new(o: &Octree) -> Grid {
        let r = o.root_bounds();
        Grid { min: r.min.as_dvec3(), size: r.size().x as f64 }
    }

    fn snap(&self, x: f64) -> i64 {
        let q = x / self.size * Grid::RES as f64;
        assert!((q - q.round()).abs() < 0.05, "{q} is not on the grid");
        q.round() as i64
    }

    fn cell(&self, b: &Aabb) -> Cell {
        let min = (b.min.as_dvec3() - self.min).to_array().map(|x| self.snap(x));
        Cell { min, size: self.snap(b.max.x as f64 - b.min.x as f64) }
    }

    /// The centre of a cell.
    fn center(&self, c: &Cell) -> Vec3 {
        let q = DVec3::from_array(c.min.map(|m| m as f64)) + DVec3::splat(c.size as f64 / 2.0);
        (self.min + q / Grid::RES as f64 * self.size).as_vec3()
    }
}

/// The 26 direction sets: steps in {-1, 0, 1}^3 and the directions they name.
fn direction_sets() -> Vec<([i64; 3], Vec<Dir>)> {
    (0..27)
        .map(|s| [s % 3 - 1, s / 3 % 3 - 1, s / 9 - 1])
        .filter(|step| *step != [0; 3])
        .map(|step| (step, (0..3).filter(|&k| step[k] != 0).map(|k| Dir::from_axis(k, step[k] > 0)).collect()))
        .collect()
}

/// The reference answer: the node with exactly the shifted cell, else the (larger) leaf holding its
/// centre, else nothing when the shifted cell leaves the root.
fn reference_neighbour(o: &Octree, grid: &Grid, cells: &HashMap<Cell, NodeId>, c: Cell, step: [i64; 3]) -> Neighbour {
    let shifted = Cell { min: std::array::from_fn(|k| c.min[k] + step[k] * c.size), size: c.size };
    if shifted.min.iter().any(|&m| m < 0 || m + c.size > Grid::RES) {
        return Neighbour::None;
    }
    if let Some(&n) = cells.get(&shifted) {
        return Neighbour::Equal(n);
    }
    let l = o.locate(grid.center(&shifted)).expect("inside the root");
    let lc = grid.cell(&o.leaf_bounds(l));
    let inside = (0..3).all(|k| lc.min[k] <= shifted.min[k] && shifted.min[k] + c.size <= lc.min[k] + lc.size);
    assert!(inside && lc.size > c.size, "leaf {l:?} {lc:?} does not cover the missing cell {shifted:?}");
    Neighbour::Larger(l)
}

#[test]
fn neighbours_match_the_integer_reference_in_all_26_directions() {
    let sets = direction_sets();
    let mut kinds = [0usize; 3];
    for s in scenes() {
        for params in param_sets(&s) {
            let o = Octree::build(&s, params).expect("valid octree parameters");
            let grid = Grid::new(&o);
            let cells: HashMap<Cell, NodeId> = o.nodes().map(|n| (grid.cell(&o.node_bounds(n)), n)).collect();
            assert_eq!(cells.len(), o.node_count(), "{}: two nodes with one box", s.name);
            let counts = o
                .nodes()
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|n| {
                    let c = grid.cell(&o.node_bounds(n));
                    let mut kinds = [0usize; 3];
                    for (step, dirs) in &sets {
                        let want = reference_neighbour(&o, &grid, &cells, c, *step);
                        let got = o.neighbour(n, dirs);
                        assert_eq!(got, want, "{}: node {n:?} {c:?}, {dirs:?}", s.name);
                        let mut reversed = dirs.clone();
                        reversed.reverse();
                        assert_eq!(o.neighbour(n, &reversed), got, "{}: order of {dirs:?}", s.name);
                        kinds[match got {
                            Neighbour::Equal(_) => 0,
                            Neighbour::Larger(_) => 1,
                            Neighbour::None => 2,
                        }] += 1;
                    }
                    kinds
                })
                .reduce(|| [0; 3], |a, b| std::array::from_fn(|i| a[i] + b[i]));
            (0..3).for_each(|i| kinds[i] += counts[i]);
        }
    }
    assert!(kinds.iter().all(|&k| k > 1000), "equal / larger / none answers: {kinds:?}");
}

#[test]
fn leaves_on_faces_match_the_integer_reference() {
    for s in scenes() {
        for params in param_sets(&s) {
            let o = Octree::build(&s, params).expect("valid octree parameters");
            let grid = Grid::new(&o);
            let cells: HashMap<Cell, NodeId> = o.nodes().map(|n| (grid.cell(&o.node_bounds(n)), n)).collect();
            // want[node][face]: every leaf under the node touching that face, by ascending id; index 6
            // holds all the leaves under the node. Ancestors are found by rounding the leaf's cell down
            // to coarser sizes, not through the tree's links.
            let mut want = vec![[(); 7].map(|_| Vec::new()); o.node_count()];
            for l in o.leaves() {
                let lc = grid.cell(&o.leaf_bounds(l));
                let mut size = lc.size;
                while size <= Grid::RES {
                    let a = Cell { min: lc.min.map(|m| m - m.rem_euclid(size)), size };
                    if let Some(&n) = cells.get(&a) {
                        want[n.idx()][6].push(l);
                        for face in Dir::ALL {
                            let k = face.axis();
                            let touches = if face.is_positive() {
                                lc.min[k] + lc.size == a.min[k] + size
                            } else {
                                lc.min[k] == a.min[k]
                            };
                            if touches {
                                want[n.idx()][face.index()].push(l);
                            }
                        }
                    }
                    size *= 2;
                }
            }
            let mut got = Vec::new();
            for n in o.nodes() {
                for face in Dir::ALL {
                    got.clear();
                    o.leaves_on_face(n, face, &mut got);
                    got.sort();
                    assert_eq!(got, want[n.idx()][face.index()], "{}: node {n:?}, {face:?}", s.name);
                }
                got.clear();
                o.leaves_under(n, &mut got);
                got.sort();
                assert_eq!(got, want[n.idx()][6], "{}: node {n:?}", s.name);
                if let Some(l) = o.node_leaf(n) {
                    assert_eq!(o.leaf_node(l), n);
                }
            }
            assert_eq!(want[0][6].len(), o.leaf_count(), "{}: every leaf is under the root", s.name);
        }
    }
}

/// Hand-run timing, no asserts on time (the exhaustive tier skips it: `--skip hand_run_`).
#[test]
#[ignore = "hand-run timing, not a check: cargo test -p plie --test octree hand_run_timing -- --ignored --nocapture"]
fn hand_run_timing() {
    use std::time::Instant;
    let s = if std::env::var("SMALL_SPHERE").is_ok() { sphere(40, 30) } else { sphere(1000, 300) };
    let t = Instant::now();
    let o = Octree::build(&s, OctreeParams::default()).expect("valid octree parameters");
    let build = t.elapsed();
    let t = Instant::now();
    let report = o.validate(&s);
    println!("{} triangles: build {build:?}, validate {:?}\n{report}", s.triangle_count(), t.elapsed());
    let (oct, brute) = (OctreeVisibility::new(&s, &o), Brute::new(&s));
    let mut ctx = QueryCtx::new(s.triangle_count());
    for (name, vis, n) in [("octree", &oct as &dyn Visibility, 200_000u64), ("brute", &brute, 200)] {
        let t = Instant::now();
        let mut occ = 0;
        for i in 0..n {
            let (x, y, tri) = segment(&s, &o, i * 8 + 6);
            occ += vis.occluded(&ShadowRay::new(x, y, LightId(0), tri, None), &mut ctx) as u64;
        }
        let per = t.elapsed() / n as u32;
        println!("{name}: {n} shadow rays, {occ} occluded, {per:?} per ray");
    }
}
