//! Shadow rays without a P-LIE (SPEC §5 mode a, the BVH, brute force): [`Shadows`] holds a scene and
//! builds the structure a mode answers from the first time it is asked for. The P-LIE modes answer
//! from a [`crate::Environment`].

use std::sync::OnceLock;

use super::bvh::Bvh;
use super::{Mode, Visibility};
use crate::error::{Error, Result};
use crate::octree::{Octree, OctreeParams};
use crate::scene::Scene;

/// The visibility modes that need no P-LIE, over one scene: `brute`, `octree`, `bvh`, `none` (and
/// the Embree modes with feature `embree`). The scene BVH and the octree are built on first use.
pub struct Shadows<'s> {
    scene: &'s Scene,
    octree_params: OctreeParams,
    bvh: OnceLock<Bvh>,
    octree: OnceLock<Octree>,
}

impl<'s> Shadows<'s> {
    /// Shadow rays in `scene`; mode `octree` uses the thesis' octree parameters.
    pub fn new(scene: &'s Scene) -> Shadows<'s> {
        Shadows { scene, octree_params: OctreeParams::thesis(), bvh: OnceLock::new(), octree: OnceLock::new() }
    }

    /// [`Shadows::new`] with other octree parameters for mode `octree`; fails if they are invalid.
    pub fn with_octree_params(scene: &'s Scene, params: OctreeParams) -> Result<Shadows<'s>> {
        params.validate()?;
        Ok(Shadows { octree_params: params, ..Shadows::new(scene) })
    }

    /// The visibility `mode`. Fails for the P-LIE modes (use [`crate::Environment::visibility`]).
    pub fn visibility(&self, mode: Mode) -> Result<Box<dyn Visibility + '_>> {
        if mode.needs_plie() {
            return Err(Error::InvalidParameter(format!(
                "mode {mode} answers from a P-LIE: build or load an Environment and ask it"
            )));
        }
        super::make(mode, self.scene, || self.bvh(), || self.octree(), None)
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The scene BVH (built on first use).
    pub fn bvh(&self) -> &Bvh {
        self.bvh.get_or_init(|| Bvh::build(self.scene))
    }

    /// The octree of mode `octree` (built on first use).
    pub fn octree(&self) -> &Octree {
        self.octree.get_or_init(|| Octree::build_valid(self.scene, self.octree_params))
    }
}
