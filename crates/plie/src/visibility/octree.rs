//! SPEC §5 mode (a), OCTREE: ignore the P-LIE, walk the octree leaves along the shadow segment front
//! to back and test their triangles, stopping at the first blocker.
//!
//! Exactness: a triangle that [`blocks`] the segment meets it at a point `q` (up to `f32` rounding,
//! far below [`Octree::eps`]). `q` lies in some leaf; the traversal visits every leaf whose box grown
//! by `eps` the segment touches, and that leaf lists every triangle overlapping its box grown by
//! `eps`, so the blocker is among the candidates. Candidates are tested with the shared predicate,
//! once per query thanks to the [`QueryCtx`] stamps, so the answer equals [`super::Brute`]'s.

use super::{blocks, QueryCtx, ShadowRay, Visibility};
use crate::octree::Octree;
use crate::scene::Scene;

/// Mode (a): the leaves along the segment.
#[derive(Clone, Copy, Debug)]
pub struct OctreeVisibility<'a> {
    scene: &'a Scene,
    octree: &'a Octree,
}

impl<'a> OctreeVisibility<'a> {
    /// Octree visibility in `scene`, whose octree is `octree`.
    pub fn new(scene: &'a Scene, octree: &'a Octree) -> OctreeVisibility<'a> {
        debug_assert_eq!(scene.triangles.len(), octree.scene_triangle_count(), "octree of another scene");
        OctreeVisibility { scene, octree }
    }
}

impl Visibility for OctreeVisibility<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        ctx.begin_query();
        let r = &ray.test;
        let mut hit = false;
        self.octree.for_each_leaf_on_segment(r.origin, r.dir, r.t_min, r.t_max, |leaf| {
            for &t in self.octree.leaf_triangles(leaf) {
                if ctx.first_visit(t) && blocks(self.scene, ray, t, ctx) {
                    hit = true;
                    return false;
                }
            }
            true
        });
        hit
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::octree::OctreeParams;
    use crate::visibility::Brute;
    use crate::{LightId, TriId};

    #[test]
    fn a_wall_blocks_and_a_gap_does_not() {
        let (s, floor) = crate::visibility::wall_scene();
        let o = Octree::build(&s, OctreeParams::default()).expect("valid octree parameters");
        let (oct, brute) = (OctreeVisibility::new(&s, &o), Brute::new(&s));
        let mut ctx = QueryCtx::new(s.triangle_count());
        let y = Vec3::new(0.0, 1.0, 0.2);
        let blocked = ShadowRay::new(Vec3::new(0.0, -1.0, -0.5), y, LightId(0), floor, None);
        let open = ShadowRay::new(Vec3::new(0.0, -1.0, 0.5), y, LightId(0), floor, None);
        assert!(oct.occluded(&blocked, &mut ctx) && brute.occluded(&blocked, &mut ctx));
        assert!(!oct.occluded(&open, &mut ctx) && !brute.occluded(&open, &mut ctx));
        // The ray's own triangle never blocks it.
        let own = ShadowRay::new(Vec3::new(0.0, 1.0, -0.5), Vec3::new(0.0, -2.0, -0.5), LightId(0), TriId(0), None);
        assert_eq!(oct.occluded(&own, &mut ctx), brute.occluded(&own, &mut ctx));
    }
}
