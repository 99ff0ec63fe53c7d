//! The BVH peer: a compressed wide BVH8 (obvhs: PLOC build with reinsertion, SIMD traversal), used for
//! the `bvh` visibility mode and for the eye rays of the hit buffer.
//!
//! obvhs' node test is a float slab test with two shortcuts that could lose a blocker: node intervals
//! start at a fixed `t = 1e-4`, and direction components below `f32::EPSILON` get a clamped inverse.
//! To stay exact we (1) build in a normalised space where the scene spans 1000 units, (2) pad every
//! triangle box by [`PAD`] there, and (3) scale shadow rays so the segment runs over `t` in
//! `[0, SEGMENT_T]`. Then the first `t` a blocker can have (`SEGMENT_EPS * SEGMENT_T = 1`) is far past
//! `1e-4`, and a clamped inverse still keeps every point at least `PAD` inside a padded box within
//! `PAD / EPSILON > SEGMENT_T` of the interval; rounding in the slab test is far below `PAD`. Candidates
//! are then decided by the shared [`blocks`] predicate, so answers equal brute force.

use std::time::Duration;

use glam::{UVec2, Vec3, Vec3A};
use obvhs::aabb::Aabb as BAabb;
use obvhs::cwbvh::{builder::build_cwbvh, CwBvh};
use obvhs::ray::Ray;
use obvhs::BvhBuildParams;

use super::{blocks, QueryCtx, ShadowRay, Visibility};
use crate::geometry::RayTest;
use crate::scene::{Scene, TriId};

/// Size of the scene in the BVH's normalised space.
const NORMALISED_SIZE: f32 = 1000.0;
/// Padding of every primitive box in normalised units (1e-5 of the scene size).
const PAD: f32 = 1e-2;
/// The `t` at which a shadow ray reaches its light sample in BVH space.
const SEGMENT_T: f32 = 1e4;

/// A BVH over the scene's triangles.
pub struct Bvh {
    cw: CwBvh,
    origin: Vec3,
    scale: f32,
}

impl Bvh {
    /// Builds the BVH (in parallel).
    pub fn build(scene: &Scene) -> Bvh {
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
        let cw = build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut Duration::default());
        Bvh { cw, origin, scale }
    }

    /// Bytes used by the nodes and index array.
    pub fn memory_bytes(&self) -> usize {
        self.cw.nodes.len() * std::mem::size_of_val(&self.cw.nodes[0]) + self.cw.primitive_indices.len() * 4
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
        let test = RayTest::new(origin, dir, t_min, f32::INFINITY);
        // Unit direction in normalised space: t_local = t_world * scale.
        let ray = Ray::new(self.to_local(origin), Vec3A::from(dir), 0.0, f32::INFINITY);
        let mut best: Option<(TriId, f32)> = None;
        let mut state = self.cw.new_traversal(ray.direction);
        let mut node;
        let mut r = ray;
        obvhs::traverse!(self.cw, node, state, node.intersect_ray(&r, state.oct_inv4), {
            let tri = self.cw.primitive_indices[state.primitive_id as usize];
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
}

/// Whether a triangle of `scene` blocks the whole shadow ray `ray`, found by traversing `bvh` and
/// deciding candidates with the shared [`blocks`] predicate: brute force's answer. The `bvh` mode, and
/// the P-LIE modes for records that store no list ([`crate::lie::RecordKind::Scene`]), use it.
pub(crate) fn segment_occluded(scene: &Scene, bvh: &Bvh, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
    let dir = Vec3A::from(ray.test.dir * (bvh.scale / SEGMENT_T));
    let r = Ray::new(bvh.to_local(ray.test.origin), dir, 0.0, SEGMENT_T * (1.0 + 1e-6));
    let mut state = bvh.cw.new_traversal(r.direction);
    let mut node;
    let mut hit = false;
    'outer: {
        obvhs::traverse!(bvh.cw, node, state, node.intersect_ray(&r, state.oct_inv4), {
            let tri = TriId(bvh.cw.primitive_indices[state.primitive_id as usize]);
            if blocks(scene, ray, tri, ctx) {
                hit = true;
                break 'outer;
            }
        });
    }
    hit
}
