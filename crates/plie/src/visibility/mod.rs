//! Visibility: does anything block the segment from a shaded point `x` to a light sample `y`?
//! (SPEC §5.) Every mode implements [`Visibility`]; all of them must answer exactly as [`Brute`] does,
//! which they do by testing candidates with the one shared [`blocks`] predicate and pruning only
//! conservatively.

pub mod answer;
pub mod brute;
pub mod bvh;
#[cfg(feature = "embree")]
pub mod embree;
pub(crate) mod fan;
pub(crate) mod footprint;
pub(crate) mod leaf_voxels;
pub(crate) mod lie;
pub(crate) mod list_boxes;
pub mod mode;
pub mod octree;
pub(crate) mod pyramid;
pub mod query;
pub mod shadows;
pub(crate) mod simd;
pub(crate) mod verdicts;

pub use answer::{Answer, Answers};
pub use brute::Brute;
pub use bvh::BvhVisibility;
#[cfg(feature = "embree")]
pub use embree::{exact::ExactEmbreeVisibility, native::NativeEmbree};
pub(crate) use lie::LieVisibility;
pub use mode::Mode;
pub use octree::OctreeVisibility;
pub use query::{blocks, LightAnswers, LightRays, QueryCtx, QueryStats, ShadowRay};
pub use shadows::Shadows;

/// Test fixture shared by the modes' unit tests: a floor, a wall half above it, and a light above
/// both. Returns the scene and the floor triangle.
#[cfg(test)]
pub(crate) fn wall_scene() -> (crate::Scene, crate::TriId) {
    use glam::Vec3;
    let mut b = crate::SceneBuilder::new("wall");
    let m = b.diffuse("grey", Vec3::splat(0.5));
    b.quad(
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(-1.0, 0.0, 0.0),
        m,
    );
    let floor = b.triangle(Vec3::new(-2.0, -1.0, -2.0), Vec3::new(2.0, -1.0, 2.0), Vec3::new(2.0, -1.0, -2.0), m);
    b.light("l", &[Vec3::new(-0.5, 1.0, -0.5), Vec3::new(-0.5, 1.0, 0.5), Vec3::new(0.5, 1.0, 0.5)], Vec3::ONE);
    (b.build().expect("valid scene"), floor)
}

/// Fewer samples of a light facing the point than this are asked ray by ray by the per-light
/// queries (the `bvh` and P-LIE modes); from this many on, the light is answered as a fan.
/// Measured (callgrind inside `occluded_light`, 254x254, 4 rays, docs/results.md issue 21 session
/// 24), 8 (before) against 2: `grid` on conference-lit 1,444.5 -> 635.1 M instructions, huis-c
/// 1,451.6 -> 541.1, cornell-dragon-100k 707.7 -> 402.0, cornell-bunny 382.2 -> 244.5 (1 instead of
/// 2: up to 0.8% more); `bvh` 832.7 -> 772.0, 748.6 -> 690.3, 518.4 -> 498.8 and 257.1 -> 281.0 M
/// (-4.9% in sum). At 16 rays, where only lights partly behind the point have fewer than 8 samples,
/// 2 saved `grid` 1.2% in sum.
pub(crate) const FAN_MIN: usize = 2;

/// A visibility method: answers shadow-ray queries exactly (but for the reference modes that say
/// otherwise: [`Mode::None`] and native Embree, [`Mode::is_exact`]).
pub trait Visibility: Sync {
    /// True if some triangle other than the ray's own (its origin triangle and the target light's
    /// triangles) intersects the open segment. `ctx` is the calling thread's scratch space and counters.
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool;

    /// Answers all the shadow rays of one light from one point at once: `out[k]` is set to
    /// [`Visibility::occluded`] of [`LightRays::ray`]`(k)`, and must equal it exactly.
    /// `out.len() == rays.targets.len()`. The default asks each ray in turn; modes override it to share
    /// work between rays that share their origin.
    fn occluded_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        debug_assert_eq!(out.len(), rays.targets.len());
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.occluded(&rays.ray(k), ctx);
        }
    }
}

/// `--visibility none`: every shadow ray unoccluded. Not exact; it measures shading alone.
pub struct NoVisibility;

impl Visibility for NoVisibility {
    fn occluded(&self, _ray: &ShadowRay, _ctx: &mut QueryCtx) -> bool {
        false
    }

    fn occluded_light(&self, _rays: &LightRays, out: &mut [bool], _ctx: &mut QueryCtx) {
        out.fill(false);
    }
}

/// The visibility method for `mode`; `bvh` and `octree` are asked for only by the modes that use
/// them. Fails if `mode` needs a P-LIE and none is given, or needs regions the P-LIE lacks.
pub(crate) fn make<'a>(
    mode: Mode,
    scene: &'a crate::Scene,
    bvh: impl FnOnce() -> &'a bvh::Bvh,
    octree: impl FnOnce() -> &'a crate::octree::Octree,
    plie: Option<&'a crate::lie::Plie>,
) -> crate::Result<Box<dyn Visibility + 'a>> {
    Ok(match mode {
        Mode::Brute => Box::new(Brute::new(scene)),
        Mode::Octree => Box::new(OctreeVisibility::new(scene, octree())),
        Mode::Bvh => Box::new(BvhVisibility::new(scene, bvh())),
        Mode::Lie | Mode::Umbra | Mode::Penumbra | Mode::Grid => {
            let plie = plie.ok_or_else(|| crate::Error::InvalidParameter(format!("mode {mode} needs a P-LIE")))?;
            if mode.needs_regions() && !plie.params.has_regions() {
                return Err(crate::Error::InvalidParameter(format!(
                    "mode {mode} needs umbra and penumbra, but the P-LIE was built without them (--no-regions)"
                )));
            }
            Box::new(LieVisibility::new(scene, bvh(), octree(), plie, mode))
        }
        #[cfg(feature = "embree")]
        Mode::Embree => Box::new(NativeEmbree::new(scene)?),
        #[cfg(feature = "embree")]
        Mode::EmbreeExact => Box::new(ExactEmbreeVisibility::new(scene)?),
        Mode::None => Box::new(NoVisibility),
    })
}
