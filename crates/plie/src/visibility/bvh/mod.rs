//! The BVH peer: a compressed wide BVH8 (obvhs: PLOC build with reinsertion, SIMD traversal), used for
//! the `bvh` visibility mode and for the eye rays of the hit buffer.
//!
//! obvhs' node test is a float slab test with two shortcuts that could lose a blocker: node intervals
//! start at a fixed `t = 1e-4`, and direction components below `f32::EPSILON` get a clamped inverse.
//! To stay exact we (1) build in a normalised space where the scene spans 1000 units, (2) pad every
//! triangle box by `PAD` there, and (3) scale shadow rays so the segment runs over `t` in
//! `[0, SEGMENT_T]`. Then the first `t` a blocker can have (`SEGMENT_EPS * SEGMENT_T = 1`) is far past
//! `1e-4`, and a clamped inverse still keeps every point at least `PAD` inside a padded box within
//! `PAD / EPSILON > SEGMENT_T` of the interval; rounding in the slab test is far below `PAD`. Candidates
//! are then decided by the shared [`blocks`] predicate, so answers equal brute force.
//!
//! obvhs' traversal keeps the groups still to visit on a fixed 32-entry stack that, when full,
//! overwrites its top entry: a BVH deeper than 31 inner levels (hundreds of coincident triangles, whose
//! identical boxes PLOC pairs into a chain) would silently skip nodes. [`Bvh::build`] measures the
//! depth, and traversals of a deeper BVH use a growable stack instead (`Walk`); the common, shallow
//! case keeps obvhs' fixed stack. Boxes with one centre (exact copies, instances with one transform,
//! triangles nested around a point) also made PLOC's build quadratic (5,000 copies of a triangle:
//! 1.5 s and a depth of 713; 20,000 glTF instances: 70 s): PLOC orders boxes by the Morton code of
//! their centres and cannot order equal codes. So more than [`CROWD_LIMIT`] boxes whose centres share
//! a Morton cell become one primitive listing their triangles (`crowd.rs`); ordinary scenes have no
//! such crowd and keep one primitive per triangle. Boxes along which PLOC's merge costs change
//! steadily (a fan of triangles around one centre across the scene: 100,000 took 15 s) stall it too;
//! where its first choices pair up too few boxes, the BVH is split top-down instead (`top_down.rs`).
//!
//! The fans' walks (`fan_walk.rs`) read a leaf's triangles from a copy laid out in the order of the
//! leaves (`LeafTris`: 48 bytes a triangle with its id and light), so that they lie side by side in
//! memory rather than wherever the scene lists them (measured, issue 21 session 26: 1-6% of `grid`'s
//! shading time at 16-64 rays, 4-15% of `bvh`'s at 16).

use glam::{UVec2, Vec3, Vec3A};
use obvhs::aabb::Aabb as BAabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::{bvh2_to_cwbvh::bvh2_to_cwbvh, CwBvh};
use obvhs::faststack::{FastStack, StackStack};
use obvhs::ploc::PlocBuilder;
use obvhs::ray::Ray;
use obvhs::BvhBuildParams;

use super::{blocks, LightRays, QueryCtx, ShadowRay, Visibility};
use crate::geometry::{RayTest, Triangle};
use crate::scene::{LightId, Scene, TriId};
pub use crowd::CROWD_LIMIT;
use crowd::{group_crowded_centres, Groups, Prims, Single};

mod collect;
mod crowd;
mod cut;
mod fan_walk;
mod top_down;

pub(crate) use cut::Cut;

/// Size of the scene in the BVH's normalised space.
const NORMALISED_SIZE: f32 = 1000.0;
/// Padding of every primitive box in normalised units (1e-5 of the scene size).
const PAD: f32 = 1e-2;
/// The `t` at which a shadow ray reaches its light sample in BVH space.
const SEGMENT_T: f32 = 1e4;
/// Entries of obvhs' fixed traversal stack (`TRAVERSAL_STACK_SIZE`, private there). Its `push` on a
/// full stack overwrites the top entry, so it holds `FIXED_STACK - 1` entries without loss.
const FIXED_STACK: usize = 32;

/// A BVH over the scene's triangles.
pub struct Bvh {
    cw: CwBvh,
    origin: Vec3,
    scale: f32,
    /// Depth of the deepest inner node (the root is 0): the most entries a traversal stack holds.
    depth: u32,
    /// The triangles of each primitive when some centres were crowded ([`CROWD_LIMIT`]); else every
    /// primitive is the triangle of the same index.
    groups: Option<Groups>,
    /// The triangles in the order of the leaves, for the fans' walks.
    leaf_tris: LeafTris,
}

/// A copy of the scene's triangles in the order the BVH's leaves list them (the primitives of the
/// primitive index array, each one's triangles in turn), with their ids and lights: a leaf's
/// triangles lie side by side in memory, as the fans' walks read them ([`Prims::span`]).
#[derive(Default)]
struct LeafTris {
    tris: Vec<Triangle>,
    ids: Vec<TriId>,
    lights: Vec<Option<LightId>>,
}

impl LeafTris {
    fn of<P: Prims>(scene: &Scene, primitive_indices: &[u32], prims: &P) -> LeafTris {
        let mut out = LeafTris::default();
        for p in primitive_indices {
            for &t in prims.of(p) {
                out.tris.push(scene.triangles[t as usize]);
                out.ids.push(TriId(t));
                out.lights.push(scene.tri_light[t as usize]);
            }
        }
        out
    }

    fn memory_bytes(&self) -> usize {
        self.tris.len() * std::mem::size_of::<Triangle>()
            + self.ids.len() * std::mem::size_of::<TriId>()
            + self.lights.len() * std::mem::size_of::<Option<LightId>>()
    }
}

/// Calls `$f($stack, $prims, args...)` with the traversal stack and primitive kind `$bvh` needs.
macro_rules! dispatch {
    ($bvh:expr, $f:expr $(, $arg:expr)*) => {{
        let deep = || Vec::with_capacity($bvh.depth as usize + 1);
        match (&$bvh.groups, $bvh.fixed_stack_fits()) {
            (None, true) => $f(&mut StackStack::<UVec2, FIXED_STACK>::default(), &Single, $($arg),*),
            (None, false) => $f(&mut deep(), &Single, $($arg),*),
            (Some(g), true) => $f(&mut StackStack::<UVec2, FIXED_STACK>::default(), g, $($arg),*),
            (Some(g), false) => $f(&mut deep(), g, $($arg),*),
        }
    }};
}

impl Bvh {
    /// Builds the BVH (in parallel).
    pub fn build(scene: &Scene) -> Bvh {
        Bvh::build_with(scene, true)
    }

    /// As [`Bvh::build`], one primitive per triangle even where centres crowd (for tests of deep BVHs).
    #[cfg(test)]
    fn build_ungrouped(scene: &Scene) -> Bvh {
        Bvh::build_with(scene, false)
    }

    fn build_with(scene: &Scene, group: bool) -> Bvh {
        let origin = scene.bounds.min;
        let scale = NORMALISED_SIZE / scene.scale().max(f32::MIN_POSITIVE);
        let boxes: Vec<BAabb> = scene
            .triangles
            .iter()
            .map(|t| {
                let b = t.aabb();
                let lo = Vec3A::from((b.min - origin) * scale) - Vec3A::splat(PAD);
                let hi = Vec3A::from((b.max - origin) * scale) + Vec3A::splat(PAD);
                BAabb::new(lo, hi)
            })
            .collect();
        let (cw, groups) = match group.then(|| group_crowded_centres(&boxes, NORMALISED_SIZE, PAD)).flatten() {
            None => (build_cwbvh(boxes, BvhBuildParams::medium_build()), None),
            Some((prim_boxes, mut groups)) => {
                drop(boxes);
                let cw = build_cwbvh(prim_boxes, BvhBuildParams::medium_build());
                groups.place(&cw.primitive_indices);
                (cw, Some(groups))
            }
        };
        let leaf_tris = match &groups {
            None => LeafTris::of(scene, &cw.primitive_indices, &Single),
            Some(g) => LeafTris::of(scene, &cw.primitive_indices, g),
        };
        let depth = inner_depth(&cw);
        Bvh { cw, origin, scale, depth, groups, leaf_tris }
    }

    /// Number of BVH primitives (triangles, or groups of triangles with crowded centres).
    pub fn primitive_count(&self) -> usize {
        self.cw.primitive_indices.len()
    }

    /// Depth of the deepest inner node (the root is 0). Above 31, traversals use a growable stack.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Whether obvhs' fixed stack holds every entry a traversal of this BVH pushes: at most one per
    /// inner level above the node visited, so at most [`Bvh::depth`].
    fn fixed_stack_fits(&self) -> bool {
        (self.depth as usize) < FIXED_STACK
    }

    /// Bytes used by the nodes, the index array, the crowds' groups and the leaf-ordered triangles.
    pub fn memory_bytes(&self) -> usize {
        let groups = self.groups.as_ref().map_or(0, Groups::memory_bytes);
        self.cw.nodes.len() * std::mem::size_of_val(&self.cw.nodes[0])
            + self.cw.primitive_indices.len() * 4
            + groups
            + self.leaf_tris.memory_bytes()
    }

    fn to_local(&self, p: Vec3) -> Vec3A {
        Vec3A::from((p - self.origin) * self.scale)
    }

    /// The nearest triangle hit by the ray `origin + t * dir` (`dir` unit length) with `t > 0`, and its
    /// `t`. Ties go to the first found, which is deterministic for a given BVH.
    pub fn closest_hit(&self, scene: &Scene, origin: Vec3, dir: Vec3) -> Option<(TriId, f32)> {
        self.closest_hit_from(scene, origin, dir, 0.0, None)
    }

    /// As [`Bvh::closest_hit`], for a ray leaving a surface (the bounce rays of the path tracer): only
    /// hits with `t > t_min`, and never the triangle `skip` the ray starts on.
    pub fn closest_hit_from(
        &self,
        scene: &Scene,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        skip: Option<TriId>,
    ) -> Option<(TriId, f32)> {
        dispatch!(self, |st, pr| self.closest_hit_with(st, pr, scene, origin, dir, t_min, skip))
    }

    /// [`Bvh::closest_hit_from`] with `stack` as the traversal stack.
    #[allow(clippy::too_many_arguments)]
    fn closest_hit_with<S: FastStack<UVec2>, P: Prims>(
        &self,
        stack: &mut S,
        prims: &P,
        scene: &Scene,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        skip: Option<TriId>,
    ) -> Option<(TriId, f32)> {
        let test = RayTest::new(origin, dir, t_min, f32::INFINITY);
        // Unit direction in normalised space: t_local = t_world * scale.
        let ray = Ray::new(self.to_local(origin), Vec3A::from(dir), 0.0, f32::INFINITY);
        let mut best: Option<(TriId, f32)> = None;
        let mut state = Walk::new(&self.cw, ray.direction, stack);
        let mut node;
        let mut r = ray;
        obvhs::traverse!(self.cw, node, state, node.intersect_ray(&r, state.oct_inv4), {
            for &tri in prims.of(&self.cw.primitive_indices[state.primitive_id as usize]) {
                if skip == Some(TriId(tri)) {
                    continue;
                }
                if let Some(t) = test.hit(&scene.triangles[tri as usize]) {
                    let tl = t * self.scale;
                    if tl < r.tmax {
                        r.tmax = tl;
                        best = Some((TriId(tri), t));
                    }
                }
            }
        });
        best
    }
}

/// Visibility by the BVH.
pub struct BvhVisibility<'a> {
    scene: &'a Scene,
    bvh: &'a Bvh,
}

impl<'a> BvhVisibility<'a> {
    /// BVH visibility in `scene`.
    pub fn new(scene: &'a Scene, bvh: &'a Bvh) -> BvhVisibility<'a> {
        BvhVisibility { scene, bvh }
    }
}

impl Visibility for BvhVisibility<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        segment_occluded(self.scene, self.bvh, ray, ctx)
    }

    /// All samples of the light down the BVH at once (`Bvh::fan_occluded`), as a packet; fewer
    /// than `visibility::FAN_MIN` samples ray by ray. As the P-LIE modes do before their walks,
    /// the blockers of the light's last walk that found every ray occluded are tested first
    /// (`LightScratch::test_last_blockers`): coherence between pixels
    /// that any renderer can keep, so the peer keeps it too.
    fn occluded_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        if rays.targets.len() < crate::visibility::FAN_MIN {
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.occluded(&rays.ray(k), ctx);
            }
            return;
        }
        ctx.with_light(|sc, ctx| {
            out.fill(false);
            sc.fan.set(rays);
            sc.fan.pyramid.set_in(self.scene, rays.origin, rays.light);
            sc.test_last_blockers(self.scene, rays, out, ctx);
            if sc.fan.live() > 0 {
                self.bvh.fan_occluded(None, rays, &mut sc.fan, &mut sc.walk, out, ctx);
            }
            sc.keep_blockers(rays);
        });
    }
}

/// Whether a triangle of `scene` blocks the whole shadow ray `ray`, found by traversing `bvh` and
/// deciding candidates with the shared [`blocks`] predicate: brute force's answer. The `bvh` mode, and
/// the P-LIE modes for records that store no list ([`crate::lie::RecordKind::Scene`]), use it.
pub(crate) fn segment_occluded(scene: &Scene, bvh: &Bvh, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
    dispatch!(bvh, segment_occluded_with, scene, bvh, ray, ctx)
}

/// [`segment_occluded`] with `stack` as the traversal stack.
fn segment_occluded_with<S: FastStack<UVec2>, P: Prims>(
    stack: &mut S,
    prims: &P,
    scene: &Scene,
    bvh: &Bvh,
    ray: &ShadowRay,
    ctx: &mut QueryCtx,
) -> bool {
    let dir = Vec3A::from(ray.test.dir * (bvh.scale / SEGMENT_T));
    let r = Ray::new(bvh.to_local(ray.test.origin), dir, 0.0, SEGMENT_T * (1.0 + 1e-6));
    let mut state = Walk::new(&bvh.cw, r.direction, stack);
    let mut node;
    let mut hit = false;
    'outer: {
        obvhs::traverse!(bvh.cw, node, state, node.intersect_ray(&r, state.oct_inv4), {
            for &tri in prims.of(&bvh.cw.primitive_indices[state.primitive_id as usize]) {
                if blocks(scene, ray, TriId(tri), ctx) {
                    hit = true;
                    break 'outer;
                }
            }
        });
    }
    hit
}

/// obvhs' `build_cwbvh` (PLOC, reinsertion, conversion to BVH8) without its debug-build `validate`,
/// which asserts that the depth fits obvhs' fixed stack: here a deeper BVH is valid ([`Walk`]). Where
/// PLOC would stall ([`top_down::ploc_would_stall`]), a top-down build takes its place.
///
/// The boxes are dropped once the binary BVH holds them, before the conversion, which is the build's
/// peak of memory; the BVH8's arrays keep only what they hold (obvhs reserves a node per primitive).
fn build_cwbvh(boxes: Vec<BAabb>, config: BvhBuildParams) -> CwBvh {
    let mut bvh2 = if top_down::ploc_would_stall(&boxes) {
        top_down::build(&boxes)
    } else {
        let indices = (0..boxes.len() as u32).collect::<Vec<_>>();
        PlocBuilder::with_capacity(boxes.len()).build(
            config.ploc_search_distance,
            &boxes,
            indices,
            config.sort_precision,
            config.search_depth_threshold,
        )
    };
    drop(boxes);
    ReinsertionOptimizer::default().run(&mut bvh2, config.reinsertion_batch_ratio, None);
    let mut cw = bvh2_to_cwbvh(&bvh2, config.max_prims_per_leaf.clamp(1, 3), true, false);
    drop(bvh2);
    cw.nodes.shrink_to_fit();
    cw.primitive_indices.shrink_to_fit();
    cw
}

/// Depth of the deepest inner node of `cw` (the root is 0; 0 for an empty BVH). The inner children of
/// a node are the `imask.count_ones()` nodes from its `child_base_idx` on.
fn inner_depth(cw: &CwBvh) -> u32 {
    let mut deepest = 0;
    let mut todo = if cw.nodes.is_empty() { vec![] } else { vec![(0u32, 0u32)] };
    while let Some((n, d)) = todo.pop() {
        deepest = deepest.max(d);
        let node = &cw.nodes[n as usize];
        todo.extend((0..node.imask.count_ones()).map(|k| (node.child_base_idx + k, d + 1)));
    }
    deepest
}

/// The traversal state `obvhs::traverse!` works on (the fields of obvhs' `Traversal`), with a stack of
/// our choosing: obvhs' fixed one or a growable `Vec`.
struct Walk<S> {
    stack: S,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl<'a, S: FastStack<UVec2>> Walk<&'a mut S> {
    /// The state at the root of `cw` for rays in direction `dir`, with `stack` emptied.
    fn new(cw: &CwBvh, dir: Vec3A, stack: &'a mut S) -> Walk<&'a mut S> {
        stack.clear();
        let t = cw.new_traversal(dir);
        Walk {
            stack,
            current_group: t.current_group,
            primitive_group: t.primitive_group,
            oct_inv4: t.oct_inv4,
            primitive_id: t.primitive_id,
            hitmask: t.hitmask,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{LightId, SceneBuilder};
    use crate::visibility::Brute;

    /// A 20 x 20 grid of floor quads, `copies` copies of a triangle at height 1 above part of it, the
    /// `k`-th `1 + k * grow` times as wide (the same box centre), 60 small distinct blockers between
    /// them and the light (a quad at height 3).
    fn scene_with_copies(copies: usize, grow: f32) -> Scene {
        let mut b = SceneBuilder::new("copies");
        let m = b.diffuse("white", Vec3::splat(0.5));
        for i in 0..20 {
            for j in 0..20 {
                let (x, z) = (i as f32 * 0.2 - 2.0, j as f32 * 0.2 - 2.0);
                let p = |dx: f32, dz: f32| Vec3::new(x + dx, 0.0, z + dz);
                b.quad(p(0.0, 0.0), p(0.0, 0.2), p(0.2, 0.2), p(0.2, 0.0), m);
            }
        }
        for k in 0..copies {
            let r = 1.0 + k as f32 * grow;
            b.triangle(Vec3::new(-r, 1.0, -r), Vec3::new(-r, 1.0, r), Vec3::new(r, 1.0, 0.0), m);
        }
        for k in 0..60 {
            let a = k as f32 * 0.61;
            let c = Vec3::new(1.6 * a.cos() * (k as f32 / 60.0), 1.5 + 0.01 * k as f32, 1.6 * a.sin());
            b.triangle(c, c + Vec3::new(0.0, 0.0, 0.3), c + Vec3::new(0.3, 0.02, 0.0), m);
        }
        let l = |x: f32, z: f32| Vec3::new(x, 3.0, z);
        b.light("light", &[l(-1.5, -1.5), l(1.5, -1.5), l(1.5, 1.5), l(-1.5, 1.5)], Vec3::ONE);
        b.build().unwrap()
    }

    /// Shadow rays from every floor triangle's centre to a 5 x 5 grid of light samples.
    fn shadow_rays(scene: &Scene) -> Vec<ShadowRay> {
        let mut rays = Vec::new();
        for (t, tri) in scene.triangles.iter().enumerate().filter(|(_, tri)| tri.v.iter().all(|v| v.y == 0.0)) {
            let x = (tri.v[0] + tri.v[1] + tri.v[2]) / 3.0;
            for i in 0..5 {
                for j in 0..5 {
                    let y = Vec3::new(i as f32 * 0.7 - 1.4, 3.0, j as f32 * 0.7 - 1.4);
                    rays.push(ShadowRay::new(x, y, LightId(0), TriId(t as u32), None));
                }
            }
        }
        rays
    }

    /// Brute force's nearest hit of `origin + t dir`, `t > 0`.
    fn nearest(scene: &Scene, origin: Vec3, dir: Vec3) -> Option<f32> {
        let test = RayTest::new(origin, dir, 0.0, f32::INFINITY);
        scene.triangles.iter().filter_map(|t| test.hit(t)).reduce(f32::min)
    }

    /// A growable stack that records the most entries it held.
    #[derive(Default)]
    struct PeakStack {
        items: Vec<UVec2>,
        peak: usize,
    }

    impl FastStack<UVec2> for PeakStack {
        fn push(&mut self, v: UVec2) {
            self.items.push(v);
            self.peak = self.peak.max(self.items.len());
        }
        fn pop_fast(&mut self) -> UVec2 {
            self.items.pop().unwrap()
        }
        fn pop(&mut self) -> Option<UVec2> {
            self.items.pop()
        }
        fn len(&self) -> usize {
            self.items.len()
        }
        fn is_empty(&self) -> bool {
            self.items.is_empty()
        }
        fn clear(&mut self) {
            self.items.clear()
        }
    }

    /// Checks every shadow ray and a fan of eye rays of `scene` against brute force; returns the most
    /// entries a traversal stack held.
    fn check_against_brute(scene: &Scene, bvh: &Bvh) -> usize {
        let brute = Brute::new(scene);
        let mut ctx = QueryCtx::new(scene.triangles.len());
        let mut peak = PeakStack::default();
        let mut occluded = 0;
        let rays = shadow_rays(scene);
        for (i, ray) in rays.iter().enumerate() {
            let expected = brute.occluded(ray, &mut ctx);
            assert_eq!(segment_occluded(scene, bvh, ray, &mut ctx), expected, "shadow ray {i}: {ray:?}");
            let got = match &bvh.groups {
                None => segment_occluded_with(&mut peak, &Single, scene, bvh, ray, &mut ctx),
                Some(g) => segment_occluded_with(&mut peak, g, scene, bvh, ray, &mut ctx),
            };
            assert_eq!(got, expected, "shadow ray {i}");
            occluded += expected as usize;
        }
        // Both answers occur, so a traversal that found nothing or everything would fail.
        assert!(occluded > rays.len() / 10 && occluded < rays.len() * 9 / 10, "{occluded} of {}", rays.len());
        for i in 0..40 {
            for j in 0..40 {
                let origin = Vec3::new(0.3, 5.0, -0.2);
                let dir = (Vec3::new(i as f32 * 0.11 - 2.2, 0.0, j as f32 * 0.11 - 2.2) - origin).normalize();
                let expected = nearest(scene, origin, dir);
                let got = bvh.closest_hit(scene, origin, dir).map(|(_, t)| t);
                assert_eq!(got, expected, "eye ray {i},{j}");
                let got = match &bvh.groups {
                    None => bvh.closest_hit_with(&mut peak, &Single, scene, origin, dir, 0.0, None),
                    Some(g) => bvh.closest_hit_with(&mut peak, g, scene, origin, dir, 0.0, None),
                };
                let got = got.map(|(_, t)| t);
                assert_eq!(got, expected, "eye ray {i},{j}");
            }
        }
        peak.peak
    }

    /// 2,000 copies of a triangle, each 1e-4 wider than the last: distinct boxes around one centre,
    /// which PLOC stacks into a BVH deeper than obvhs' fixed stack holds. (Built without grouping
    /// crowded centres, which would make them one primitive.)
    #[test]
    fn deep_bvh_answers_every_ray_as_brute_force() {
        let scene = scene_with_copies(2000, 1e-4);
        let bvh = Bvh::build_ungrouped(&scene);
        // Deeper than obvhs' fixed stack holds: the growable stack is the one used.
        assert!(bvh.depth() as usize >= FIXED_STACK, "depth {}", bvh.depth());
        assert!(!bvh.fixed_stack_fits());
        let peak = check_against_brute(&scene, &bvh);
        eprintln!("deep BVH: depth {}, at most {peak} stack entries", bvh.depth());
        // The bound the choice of stack relies on.
        assert!(peak <= bvh.depth() as usize, "peak {peak} > depth {}", bvh.depth());
    }

    /// 400 exact copies (the 1,200-index face), and 2,000 triangles nested around one centre:
    /// one primitive lists them all, and the BVH is shallow (without the grouping it was deeper than
    /// the fixed stack, and PLOC's build quadratic).
    #[test]
    fn crowded_centres_are_one_primitive() {
        for (copies, grow) in [(400, 0.0), (2000, 1e-4)] {
            let scene = scene_with_copies(copies, grow);
            let bvh = Bvh::build(&scene);
            // The copies' centres fall in one cell, or a few where rounding straddles a cell's side.
            let others = scene.triangles.len() - copies;
            let prims = bvh.primitive_count();
            assert!(prims > others && prims <= others + 4, "{copies} copies: {prims} primitives");
            assert!(bvh.fixed_stack_fits(), "{copies} copies: depth {}", bvh.depth());
            let peak = check_against_brute(&scene, &bvh);
            assert!(peak <= bvh.depth() as usize, "peak {peak} > depth {}", bvh.depth());
        }
    }

    /// The fans' leaf-ordered copy of the triangles: the primitives at positions `start..start +
    /// len` of the primitive index array span exactly their triangles, each with its id and light,
    /// with and without crowded centres, and every triangle is there once.
    #[test]
    fn leaf_ordered_triangles_are_the_leaves_own() {
        fn check<P: Prims>(scene: &Scene, bvh: &Bvh, prims: &P) {
            let LeafTris { tris, ids, lights } = &bvh.leaf_tris;
            assert_eq!((tris.len(), ids.len(), lights.len()), (scene.triangles.len(), tris.len(), tris.len()));
            let mut seen = vec![false; scene.triangles.len()];
            let pis = &bvh.cw.primitive_indices;
            for (p, pi) in pis.iter().enumerate() {
                let span = prims.span(p as u32, 1);
                let want = prims.of(pi);
                assert_eq!(span.len(), want.len(), "position {p}");
                for (i, &t) in span.zip(want) {
                    assert_eq!(ids[i], TriId(t));
                    assert_eq!(tris[i].v, scene.triangles[t as usize].v);
                    assert_eq!(lights[i], scene.tri_light[t as usize]);
                    assert!(!std::mem::replace(&mut seen[t as usize], true), "triangle {t} twice");
                }
            }
            // A run of positions spans the runs of its positions.
            let n = pis.len() as u32;
            for start in [0, n / 3, n / 2] {
                let len = (n - start).min(5);
                assert_eq!(prims.span(start, len), prims.span(start, 1).start..prims.span(start + len - 1, 1).end);
            }
            assert!(seen.iter().all(|&s| s));
        }
        for copies in [0, 400] {
            let scene = scene_with_copies(copies, 0.0);
            let bvh = Bvh::build(&scene);
            assert!(scene.tri_light.iter().any(Option::is_some));
            match &bvh.groups {
                None => check(&scene, &bvh, &Single),
                Some(g) => check(&scene, &bvh, g),
            }
            assert_eq!(bvh.groups.is_some(), copies > 0);
        }
    }

    /// Up to [`CROWD_LIMIT`] triangles sharing a box stay one primitive each.
    #[test]
    fn a_few_copies_stay_apart() {
        let scene = scene_with_copies(CROWD_LIMIT, 0.0);
        let bvh = Bvh::build(&scene);
        assert_eq!(bvh.primitive_count(), scene.triangles.len());
        check_against_brute(&scene, &bvh);
    }

    #[test]
    fn shallow_bvh_keeps_the_fixed_stack() {
        let scene = scene_with_copies(1, 0.0);
        let bvh = Bvh::build(&scene);
        assert!(bvh.fixed_stack_fits(), "depth {}", bvh.depth());
        let peak = check_against_brute(&scene, &bvh);
        assert!(peak <= bvh.depth() as usize, "peak {peak} > depth {}", bvh.depth());
    }

    #[test]
    fn depth_of_an_empty_and_a_one_box_bvh() {
        assert_eq!(inner_depth(&CwBvh::default()), 0);
        let one = build_cwbvh(vec![BAabb::new(Vec3A::ZERO, Vec3A::ONE)], BvhBuildParams::medium_build());
        assert_eq!(inner_depth(&one), 0);
    }
}
