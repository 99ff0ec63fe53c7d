//! `embree-exact` (cargo feature `embree`): Intel Embree 3's BVH proposes candidate triangles, the
//! shared [`blocks`] predicate decides them, so answers equal brute force (SPEC §5, exactness).
//!
//! Embree's own triangle test is not our watertight test, so Embree never decides a hit. Every
//! triangle is a primitive of one *user* geometry (`RTC_GEOMETRY_TYPE_USER`) whose bounds are the
//! triangle's box grown by a tolerance (`pad`). The occluded callback reaches the [`ShadowRay`] and
//! the thread's [`QueryCtx`] through `Query`, a struct that extends `RTCIntersectContext` (the
//! pattern Embree 3 documents for passing data to callbacks), calls [`blocks`] and, on a hit, sets
//! `tfar = -inf` as Embree 3 requires for occlusion. Embree is given the whole segment from `x`
//! (`tnear = 0`) to `y` (`tfar = 1`), a range containing our open `t` range, and the scene is built
//! with `RTC_SCENE_FLAG_ROBUST` (conservative traversal) and `RTC_BUILD_QUALITY_HIGH`.
//!
//! This is not the peer a user compares against (that is native Embree, [`super::native`]); it is
//! kept as the exact mode that pairs Embree's traversal with our predicate (see the module doc of
//! [`super`] for why).

use std::ffi::{c_int, c_void};
use std::ptr;

use super::{check, ffi, Device};
use crate::scene::{Scene, TriId};
use crate::visibility::{blocks, QueryCtx, ShadowRay, Visibility};
use crate::{Error, Result};

/// An Embree device and a committed scene over a [`Scene`]'s triangles (as padded boxes).
pub struct ExactEmbree {
    // Field order is drop order: the scene is released before its device.
    scene: ffi::RTCScene,
    device: Device,
    /// The padded triangle boxes; Embree holds a pointer to them (the bounds callback's user data).
    boxes: Vec<ffi::RTCBounds>,
}

// SAFETY: the handles are only used through `&self` for queries (`rtcOccluded1`) once the scene is
// committed, which Embree 3 documents as thread-safe; building and releasing need `&mut`/ownership.
// The boxes are never written after construction.
unsafe impl Send for ExactEmbree {}
unsafe impl Sync for ExactEmbree {}

/// How far every triangle box is grown: `1e-5` of the scene size, plus a few ulps of the largest
/// coordinate so scenes far from the origin are padded too.
fn pad(scene: &Scene) -> f32 {
    scene.scale() * 1e-5 + scene.bounds.largest_abs() * 4.0 * f32::EPSILON
}

impl ExactEmbree {
    /// Builds the Embree scene for `scene`. Fails with [`Error::Embree`] if the device cannot be
    /// created (e.g. an unsupported CPU) or the build fails.
    pub fn build(scene: &Scene) -> Result<ExactEmbree> {
        let pad = pad(scene);
        let boxes = scene
            .triangles
            .iter()
            .map(|t| {
                let b = t.aabb();
                let (lo, hi) = (b.min - pad, b.max + pad);
                ffi::RTCBounds {
                    lower_x: lo.x,
                    lower_y: lo.y,
                    lower_z: lo.z,
                    upper_x: hi.x,
                    upper_y: hi.y,
                    upper_z: hi.z,
                    ..Default::default()
                }
            })
            .collect::<Vec<_>>();
        let count =
            u32::try_from(boxes.len()).map_err(|_| Error::Embree(format!("{} triangles are too many", boxes.len())))?;
        // SAFETY: plain Embree API calls on handles created here; `Drop` releases whatever was made
        // if a later step fails. The bounds callback reads `boxes`, whose heap buffer lives (and does
        // not move) as long as `self`.
        unsafe {
            let device = Device::new()?;
            let mut e = ExactEmbree { scene: ptr::null_mut(), device, boxes };
            let device = e.device.0;
            e.scene = ffi::rtcNewScene(device);
            check(device, "rtcNewScene")?;
            ffi::rtcSetSceneFlags(e.scene, ffi::RTC_SCENE_FLAG_ROBUST);
            ffi::rtcSetSceneBuildQuality(e.scene, ffi::RTC_BUILD_QUALITY_HIGH);
            let geom = ffi::rtcNewGeometry(device, ffi::RTC_GEOMETRY_TYPE_USER);
            check(device, "rtcNewGeometry")?;
            ffi::rtcSetGeometryBuildQuality(geom, ffi::RTC_BUILD_QUALITY_HIGH);
            ffi::rtcSetGeometryUserPrimitiveCount(geom, count);
            // Embree 3.13 hands the geometry's user data (not the bounds function's pointer) to the
            // bounds callback as `geometryUserPtr`: set both.
            let boxes = e.boxes.as_mut_ptr().cast::<c_void>();
            ffi::rtcSetGeometryUserData(geom, boxes);
            ffi::rtcSetGeometryBoundsFunction(geom, Some(bounds), boxes);
            ffi::rtcSetGeometryOccludedFunction(geom, Some(occluded));
            ffi::rtcCommitGeometry(geom);
            ffi::rtcAttachGeometry(e.scene, geom);
            // The scene keeps its own reference to the geometry.
            ffi::rtcReleaseGeometry(geom);
            check(device, "building the geometry")?;
            ffi::rtcCommitScene(e.scene);
            check(device, "rtcCommitScene")?;
            Ok(e)
        }
    }

    /// Triangles in the Embree scene.
    pub fn triangle_count(&self) -> usize {
        self.boxes.len()
    }

    /// True if a triangle of `scene` (the one this was built from) blocks `ray`, decided by [`blocks`].
    pub fn occluded(&self, scene: &Scene, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        debug_assert_eq!(scene.triangles.len(), self.boxes.len(), "Embree built for another scene");
        let (x, d) = (ray.test.origin, ray.test.dir);
        let mut r = ffi::RTCRay {
            org_x: x.x,
            org_y: x.y,
            org_z: x.z,
            tnear: 0.0,
            dir_x: d.x,
            dir_y: d.y,
            dir_z: d.z,
            time: 0.0,
            tfar: 1.0,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        };
        let mut q = Query { base: ffi::RTCIntersectContext::new(), scene, ray, ctx };
        let qp: *mut Query = &mut q;
        // SAFETY: the scene is committed; `Query` is repr(C) and starts with its `RTCIntersectContext`,
        // so `qp` is a valid context pointer to the whole `Query`, which lives for the whole call,
        // during which only the callback touches it.
        unsafe { ffi::rtcOccluded1(self.scene, qp.cast::<ffi::RTCIntersectContext>(), &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

impl Drop for ExactEmbree {
    fn drop(&mut self) {
        if !self.scene.is_null() {
            // SAFETY: the scene was created by `build` and is released once, before its device.
            unsafe { ffi::rtcReleaseScene(self.scene) };
        }
    }
}

/// The intersection context of one query: Embree's context first, then what the callback needs.
#[repr(C)]
struct Query<'a> {
    base: ffi::RTCIntersectContext,
    scene: &'a Scene,
    ray: &'a ShadowRay,
    ctx: &'a mut QueryCtx,
}

/// Bounds callback: the padded box of triangle `primID`.
unsafe extern "C" fn bounds(args: *const ffi::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid arguments; the user pointer is `Embree::boxes` and `primID` is below
    // the primitive count, which is its length.
    unsafe {
        let a = &*args;
        *a.bounds_o = *a.geometryUserPtr.cast::<ffi::RTCBounds>().add(a.primID as usize);
    }
}

/// Occluded callback: triangle `primID` is a candidate; [`blocks`] decides. On a hit, `tfar = -inf`
/// for every valid ray of the packet (`rtcOccluded1` sends packets of one, all of them our ray).
unsafe extern "C" fn occluded(args: *const ffi::RTCOccludedFunctionNArguments) {
    // SAFETY: Embree passes valid arguments with the context given to `rtcOccluded1`, which is the
    // `base` of a live `Query`; the ray packet is SOA with `N` lanes, `tfar` being component 8.
    unsafe {
        let a = &*args;
        let n = a.N as usize;
        let valid = std::slice::from_raw_parts(a.valid as *const c_int, n);
        if valid.iter().all(|&v| v == 0) {
            return;
        }
        let q = &mut *a.context.cast::<Query>();
        if blocks(q.scene, q.ray, TriId(a.primID), q.ctx) {
            let tfar = a.ray.cast::<f32>().add(8 * n);
            for (i, _) in valid.iter().enumerate().filter(|(_, &v)| v != 0) {
                *tfar.add(i) = f32::NEG_INFINITY;
            }
        }
    }
}

/// `embree-exact`: owns its [`ExactEmbree`] built over `scene`.
pub struct ExactEmbreeVisibility<'a> {
    scene: &'a Scene,
    embree: ExactEmbree,
}

impl<'a> ExactEmbreeVisibility<'a> {
    /// Builds Embree over `scene`.
    pub fn new(scene: &'a Scene) -> Result<ExactEmbreeVisibility<'a>> {
        Ok(ExactEmbreeVisibility { scene, embree: ExactEmbree::build(scene)? })
    }
}

impl Visibility for ExactEmbreeVisibility<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        self.embree.occluded(self.scene, ray, ctx)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::visibility::Brute;
    use crate::LightId;

    /// splitmix64, for a fixed-seed random test.
    fn rng(state: &mut u64) -> f32 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn a_wall_blocks_and_a_gap_does_not() {
        let (s, floor) = crate::visibility::wall_scene();
        let vis = ExactEmbreeVisibility::new(&s).expect("Embree device");
        assert_eq!(vis.embree.triangle_count(), s.triangle_count());
        let mut ctx = QueryCtx::new(s.triangle_count());
        let y = Vec3::new(0.0, 1.0, 0.2);
        let blocked = ShadowRay::new(Vec3::new(0.0, -1.0, -0.5), y, LightId(0), floor, None);
        let open = ShadowRay::new(Vec3::new(0.0, -1.0, 0.5), y, LightId(0), floor, None);
        assert!(vis.occluded(&blocked, &mut ctx));
        assert!(!vis.occluded(&open, &mut ctx));
        assert!(ctx.stats.triangle_tests > 0, "candidates are decided by `blocks`");
    }

    #[test]
    fn random_segments_match_brute_force() {
        let s = crate::scene::builtin::load("cornell-cube-2").unwrap();
        let (vis, brute) = (ExactEmbreeVisibility::new(&s).expect("Embree device"), Brute::new(&s));
        let mut ctx = QueryCtx::new(s.triangle_count());
        let (lo, size) = (s.bounds.min, s.bounds.size());
        let mut state = 42;
        let point = |st: &mut u64| lo + size * Vec3::new(rng(st), rng(st), rng(st));
        let mut blocked = 0;
        for _ in 0..20_000 {
            let (x, y) = (point(&mut state), point(&mut state));
            let ray = ShadowRay::new(x, y, LightId(0), TriId(u32::MAX), None);
            let want = brute.occluded(&ray, &mut ctx);
            assert_eq!(vis.occluded(&ray, &mut ctx), want, "{ray:?}");
            blocked += want as usize;
        }
        assert!(blocked > 1000 && blocked < 19_000, "both answers occur ({blocked} blocked)");
    }
}
