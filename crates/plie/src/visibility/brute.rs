//! The reference visibility: test the segment against every triangle of the scene.

use super::{blocks, QueryCtx, ShadowRay, Visibility};
use crate::scene::{Scene, TriId};

/// Brute force: every triangle, in index order.
pub struct Brute<'a> {
    scene: &'a Scene,
}

impl<'a> Brute<'a> {
    /// Brute-force visibility in `scene`.
    pub fn new(scene: &'a Scene) -> Brute<'a> {
        Brute { scene }
    }
}

impl Visibility for Brute<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        (0..self.scene.triangles.len() as u32).any(|t| blocks(self.scene, ray, TriId(t), ctx))
    }
}
