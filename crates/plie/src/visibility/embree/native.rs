//! `--visibility embree`: native Intel Embree 3, the peer a user would compare against (SPEC §5's
//! comparison with a modern ray tracer). **Not exact**: Embree's triangle test decides, so a few
//! shadow-ray answers may differ from `brute` (see `compare.rs`).
//!
//! The scene's triangles are Embree triangle geometry (`RTC_GEOMETRY_TYPE_TRIANGLE`) over shared
//! vertex and index buffers, built with `RTC_SCENE_FLAG_ROBUST` and `RTC_BUILD_QUALITY_HIGH`. A shadow
//! ray is Embree's ray `x + t (y - x)` with `t` in `[SEGMENT_EPS, 1 - SEGMENT_EPS]`, our segment range.
//! The target light's own triangles never block a ray to it, and the ray's origin triangle never
//! blocks it; see [`Exclusion`] for how. The samples of one light from one point are answered in
//! packets ([`Packet`]).
//!
//! **Measured** (this machine: an Intel Xeon with AVX-512, for which Debian's Embree 3.13.5 lists
//! AVX512 as a supported, compiled-in target, its widest, in `rtcNewDevice("verbose=1")`; 254x254, 1 eye ray, seed 1, one thread,
//! least process CPU seconds of 3 interleaved runs, 10 ms ticks, on a heavily shared machine), with
//! `cargo run --release -p plie --features embree --example embree_packets -- SCENE RAYS 3`:
//!
//! | scene, rays | none | bvh | 1 | 4 | 8 | 16 | 1M coherent | 8, masks |
//! |---|---|---|---|---|---|---|---|---|
//! | cornell-bunny, 64 | 0.08 | 0.40 | 0.28 | 0.21 | **0.17** | 0.18 | 0.19 | 0.16 |
//! | conference-lit, 64 | 0.18 | 1.16 | 0.76 | 0.58 | 0.43 | 0.43 | **0.38** | 0.42 |
//! | cornell-dragon-100k, 64 | 0.17 | 0.75 | 0.51 | 0.39 | **0.30** | **0.30** | 0.32 | 0.29 |
//! | cornell-bunny, 16 | 0.02 | 0.10 | 0.08 | 0.05 | **0.04** | 0.05 | 0.06 | 0.04 |
//! | conference-lit, 16 | 0.04 | 0.30 | 0.20 | 0.15 | 0.12 | 0.12 | **0.11** | 0.11 |
//! | sum | | | 1.83 | 1.38 | **1.06** | 1.08 | **1.06** | 1.02 |
//!
//! Packets of 8 (`rtcOccluded8`) and coherent streams tie on CPU time; packets of 8 have the least
//! wall time summed over the five (3.17 s against 3.28 s for 16 and 3.34 s for streams), so
//! [`NativeEmbree::new`] uses `rtcOccluded8` with the filter. Masks save at most one tick per scene
//! but leave the origin triangle to the segment range, and that lets it block: on cornell-bunny at
//! 64 rays masks answer 417,412 rays occluded where brute force (and the filter) say 416,522. The
//! filter runs only on Embree's hits, so it costs about nothing; it is the default.

use std::ffi::c_int;
use std::ptr;

use glam::Vec3;

use super::{check, ffi, Device};
use crate::scene::{LightId, Scene, TriId};
use crate::visibility::query::SEGMENT_EPS;
use crate::visibility::{LightRays, QueryCtx, ShadowRay, Visibility};
use crate::{Error, Result};

/// How a light's samples from one point are handed to Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Packet {
    /// `rtcOccluded1`, one ray at a time.
    One,
    /// `rtcOccluded4`, packets of 4.
    Four,
    /// `rtcOccluded8`, packets of 8.
    Eight,
    /// `rtcOccluded16`, packets of 16.
    Sixteen,
    /// `rtcOccluded1M` with `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`, streams of up to [`STREAM`] rays.
    Stream,
}

/// Rays per `rtcOccluded1M` call with [`Packet::Stream`].
pub const STREAM: usize = 64;

/// How the ray's own triangles (its origin triangle, the target light's triangles) are kept from
/// blocking it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exclusion {
    /// One geometry of every triangle (`primID` = [`TriId`]) with an occlusion filter that rejects a
    /// hit on the origin triangle or on a triangle of the target light.
    Filter,
    /// The triangles of light `l` are a geometry of their own with mask bit `2 << l`, the others a
    /// geometry with mask `1`; a ray to light `l` carries every bit but `2 << l`, so other lights'
    /// triangles block it. No filter: the origin triangle is left out by the segment range alone
    /// (it meets the ray's line at `t = 0`, up to rounding). Needs ray masks and at most 31 lights.
    Masks,
}

/// One Embree geometry: its first triangle in the shared index buffer, its triangle count, its mask.
type Geometry = (usize, usize, u32);

/// Native Embree over a [`Scene`]'s triangles.
pub struct NativeEmbree<'a> {
    scene: &'a Scene,
    packet: Packet,
    exclusion: Exclusion,
    // Field order is drop order: the Embree scene is released before its device, and both before the
    // buffers Embree shares.
    rtc: RtcScene,
    device: Device,
    /// Three vertices per triangle, padded to 16 bytes (Embree reads a vertex as 16 bytes).
    vertices: Vec<[f32; 4]>,
    /// Indices into `vertices`, grouped by geometry (see [`Exclusion`]).
    indices: Vec<[u32; 3]>,
}

// SAFETY: after construction the handles are only used through `&self` for occlusion queries on a
// committed scene, which Embree 3 documents as thread-safe; the shared buffers are never written.
unsafe impl Send for NativeEmbree<'_> {}
unsafe impl Sync for NativeEmbree<'_> {}

/// A committed Embree scene, released on drop.
struct RtcScene(ffi::RTCScene);

impl Drop for RtcScene {
    fn drop(&mut self) {
        if !self.0.is_null() {
            // SAFETY: the scene was created by `NativeEmbree::with` and is released once.
            unsafe { ffi::rtcReleaseScene(self.0) };
        }
    }
}

/// The intersection context of one query: Embree's context first, then what the filter needs.
#[repr(C)]
struct Own<'a> {
    base: ffi::RTCIntersectContext,
    origin_tri: TriId,
    light: LightId,
    scene: &'a Scene,
}

/// Occlusion filter of [`Exclusion::Filter`]: rejects hits on the ray's own triangles.
unsafe extern "C" fn reject_own(args: *const ffi::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments with the context given to the query, which is the `base`
    // of a live `Own`; the hit packet is SOA with `N` lanes, `primID` being component 5.
    unsafe {
        let a = &*args;
        let n = a.N as usize;
        let q = &*a.context.cast::<Own>();
        let prim = a.hit.cast::<u32>().add(5 * n);
        for i in 0..n {
            let valid = a.valid.add(i);
            if *valid == 0 {
                continue;
            }
            let t = TriId(*prim.add(i));
            if t == q.origin_tri || q.scene.tri_light[t.idx()] == Some(q.light) {
                *valid = 0;
            }
        }
    }
}

impl<'a> NativeEmbree<'a> {
    /// Native Embree over `scene` with the measured best: packets of 8 and the filter (module doc).
    pub fn new(scene: &'a Scene) -> Result<NativeEmbree<'a>> {
        NativeEmbree::with(scene, Packet::Eight, Exclusion::Filter)
    }

    /// Native Embree over `scene` with the given packets and exclusion. [`Exclusion::Masks`] falls
    /// back to [`Exclusion::Filter`] where Embree lacks ray masks or the scene has over 31 lights.
    pub fn with(scene: &'a Scene, packet: Packet, exclusion: Exclusion) -> Result<NativeEmbree<'a>> {
        let device = Device::new()?;
        let exclusion = match exclusion {
            Exclusion::Masks
                if scene.lights.len() > 31 || !device.supports(ffi::RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) =>
            {
                Exclusion::Filter
            }
            e => e,
        };
        if exclusion == Exclusion::Filter && !device.supports(ffi::RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED) {
            return Err(Error::Embree("this Embree was built without intersection filters".into()));
        }
        let n = scene.triangles.len();
        if u32::try_from(3 * n).is_err() {
            return Err(Error::Embree(format!("{n} triangles are too many")));
        }
        let vertices: Vec<[f32; 4]> = scene.triangles.iter().flat_map(|t| t.v.map(|p| [p.x, p.y, p.z, 0.0])).collect();
        let tri = |t: usize| [3 * t as u32, 3 * t as u32 + 1, 3 * t as u32 + 2];
        let (indices, geometries): (Vec<[u32; 3]>, Vec<Geometry>) = match exclusion {
            Exclusion::Filter => ((0..n).map(tri).collect(), vec![(0, n, u32::MAX)]),
            Exclusion::Masks => {
                let mut indices = Vec::with_capacity(n);
                let mut geometries = Vec::new();
                for group in std::iter::once(None).chain((0..scene.lights.len()).map(|l| Some(LightId(l as u32)))) {
                    let first = indices.len();
                    indices.extend((0..n).filter(|&t| scene.tri_light[t] == group).map(tri));
                    let mask = group.map_or(1, |l| 2 << l.0);
                    geometries.push((first, indices.len() - first, mask));
                }
                (indices, geometries)
            }
        };
        let mut e =
            NativeEmbree { scene, packet, exclusion, rtc: RtcScene(ptr::null_mut()), device, vertices, indices };
        let device = e.device.0;
        // SAFETY: plain Embree API calls on handles created here; `Drop` releases whatever was made if
        // a later step fails. The shared buffers are the heap buffers of `vertices` and `indices`,
        // which live (and do not move) as long as `e`; the vertex buffer has 16-byte items, so its
        // last vertex is readable as 16 bytes as Embree requires.
        unsafe {
            e.rtc.0 = ffi::rtcNewScene(device);
            check(device, "rtcNewScene")?;
            ffi::rtcSetSceneFlags(e.rtc.0, ffi::RTC_SCENE_FLAG_ROBUST);
            ffi::rtcSetSceneBuildQuality(e.rtc.0, ffi::RTC_BUILD_QUALITY_HIGH);
            for (first, count, mask) in geometries.into_iter().filter(|g| g.1 > 0) {
                let geom = ffi::rtcNewGeometry(device, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
                check(device, "rtcNewGeometry")?;
                ffi::rtcSetGeometryBuildQuality(geom, ffi::RTC_BUILD_QUALITY_HIGH);
                ffi::rtcSetSharedGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_VERTEX,
                    0,
                    ffi::RTC_FORMAT_FLOAT3,
                    e.vertices.as_ptr().cast(),
                    0,
                    16,
                    e.vertices.len(),
                );
                ffi::rtcSetSharedGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_INDEX,
                    0,
                    ffi::RTC_FORMAT_UINT3,
                    e.indices.as_ptr().cast(),
                    first * 12,
                    12,
                    count,
                );
                ffi::rtcSetGeometryMask(geom, mask);
                if exclusion == Exclusion::Filter {
                    ffi::rtcSetGeometryOccludedFilterFunction(geom, Some(reject_own));
                }
                ffi::rtcCommitGeometry(geom);
                ffi::rtcAttachGeometry(e.rtc.0, geom);
                // The scene keeps its own reference to the geometry.
                ffi::rtcReleaseGeometry(geom);
                check(device, "building a triangle geometry")?;
            }
            ffi::rtcCommitScene(e.rtc.0);
            check(device, "rtcCommitScene")?;
        }
        Ok(e)
    }

    /// The packets and exclusion in use.
    pub fn config(&self) -> (Packet, Exclusion) {
        (self.packet, self.exclusion)
    }

    /// The ray mask of a ray to `light`.
    fn mask(&self, light: LightId) -> u32 {
        match self.exclusion {
            Exclusion::Filter => u32::MAX,
            Exclusion::Masks => !(2 << light.0),
        }
    }

    /// The context of a query from a point on `origin_tri` to `light`.
    fn context(&self, origin_tri: TriId, light: LightId, coherent: bool) -> Own<'a> {
        let mut base = ffi::RTCIntersectContext::new();
        if coherent {
            base.flags = ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        }
        Own { base, origin_tri, light, scene: self.scene }
    }

    /// One ray from `x` along `d` (to `x + d`) with `mask`, over our segment range.
    fn ray(x: Vec3, d: Vec3, mask: u32) -> ffi::RTCRay {
        ffi::RTCRay {
            org_x: x.x,
            org_y: x.y,
            org_z: x.z,
            tnear: SEGMENT_EPS,
            dir_x: d.x,
            dir_y: d.y,
            dir_z: d.z,
            time: 0.0,
            tfar: 1.0 - SEGMENT_EPS,
            mask,
            id: 0,
            flags: 0,
        }
    }

    /// Answers `rays` in packets of `P::N`.
    fn packets<P: Lanes>(&self, rays: &LightRays, out: &mut [bool]) {
        let mut q = self.context(rays.origin_tri, rays.light, false);
        let qp: *mut Own = &mut q;
        let mut p = P::new(rays.origin, self.mask(rays.light));
        for (targets, out) in rays.targets.chunks(P::N).zip(out.chunks_mut(P::N)) {
            let mut valid = ValidMask([0; 16]);
            for (i, &y) in targets.iter().enumerate() {
                p.set(i, y - rays.origin);
                valid.0[i] = -1;
            }
            // SAFETY: the scene is committed; `Own` is repr(C) and starts with its
            // `RTCIntersectContext`, so `qp` is a valid context for the filter, and lives for the call.
            unsafe { p.occluded(valid.0.as_ptr(), self.rtc.0, qp.cast()) };
            for (i, o) in out.iter_mut().enumerate() {
                *o = p.blocked(i);
            }
        }
    }

    /// Answers `rays` in coherent streams of up to [`STREAM`] rays.
    fn stream(&self, rays: &LightRays, out: &mut [bool]) {
        let mut q = self.context(rays.origin_tri, rays.light, true);
        let qp: *mut Own = &mut q;
        let mask = self.mask(rays.light);
        let mut buf = [NativeEmbree::ray(Vec3::ZERO, Vec3::ZERO, 0); STREAM];
        for (targets, out) in rays.targets.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
            for (r, &y) in buf.iter_mut().zip(targets) {
                *r = NativeEmbree::ray(rays.origin, y - rays.origin, mask);
            }
            // SAFETY: as in `packets`; `buf` holds at least `targets.len()` rays of stride 48 bytes.
            unsafe {
                ffi::rtcOccluded1M(
                    self.rtc.0,
                    qp.cast(),
                    buf.as_mut_ptr(),
                    targets.len() as u32,
                    size_of::<ffi::RTCRay>(),
                );
            }
            for (o, r) in out.iter_mut().zip(&buf) {
                *o = r.tfar == f32::NEG_INFINITY;
            }
        }
    }
}

impl Visibility for NativeEmbree<'_> {
    fn occluded(&self, ray: &ShadowRay, _ctx: &mut QueryCtx) -> bool {
        let mut q = self.context(ray.origin_tri, ray.light, false);
        let qp: *mut Own = &mut q;
        let mut r = NativeEmbree::ray(ray.test.origin, ray.test.dir, self.mask(ray.light));
        // SAFETY: as in `packets`.
        unsafe { ffi::rtcOccluded1(self.rtc.0, qp.cast(), &mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    fn occluded_light(&self, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        debug_assert_eq!(out.len(), rays.targets.len());
        match self.packet {
            Packet::One => {
                for (k, o) in out.iter_mut().enumerate() {
                    *o = self.occluded(&rays.ray(k), ctx);
                }
            }
            Packet::Four => self.packets::<ffi::RTCRay4>(rays, out),
            Packet::Eight => self.packets::<ffi::RTCRay8>(rays, out),
            Packet::Sixteen => self.packets::<ffi::RTCRay16>(rays, out),
            Packet::Stream => self.stream(rays, out),
        }
    }
}

/// The valid mask of a packet (`-1`: lane valid), aligned as Embree loads it for 16 lanes.
#[repr(C, align(64))]
struct ValidMask([c_int; 16]);

/// An SOA ray packet of `N` rays sharing their origin and mask.
trait Lanes {
    const N: usize;
    /// A packet of rays from `x` with `mask`, over our segment range.
    fn new(x: Vec3, mask: u32) -> Self;
    /// Lane `i` goes along `d` (to `x + d`), with its range reset.
    fn set(&mut self, i: usize, d: Vec3);
    /// Runs Embree's occlusion query on the lanes where `valid` is `-1`.
    ///
    /// # Safety
    /// `scene` is committed and `ctx` is a live context for it; `valid` points to `N` ints.
    unsafe fn occluded(&mut self, valid: *const c_int, scene: ffi::RTCScene, ctx: *mut ffi::RTCIntersectContext);
    /// True if lane `i` was found occluded.
    fn blocked(&self, i: usize) -> bool;
}

macro_rules! lanes {
    ($t:ty, $n:literal, $f:ident) => {
        impl Lanes for $t {
            const N: usize = $n;
            fn new(x: Vec3, mask: u32) -> Self {
                Self {
                    org_x: [x.x; $n],
                    org_y: [x.y; $n],
                    org_z: [x.z; $n],
                    tnear: [SEGMENT_EPS; $n],
                    dir_x: [0.0; $n],
                    dir_y: [0.0; $n],
                    dir_z: [0.0; $n],
                    time: [0.0; $n],
                    tfar: [1.0 - SEGMENT_EPS; $n],
                    mask: [mask; $n],
                    id: [0; $n],
                    flags: [0; $n],
                }
            }
            #[inline]
            fn set(&mut self, i: usize, d: Vec3) {
                self.dir_x[i] = d.x;
                self.dir_y[i] = d.y;
                self.dir_z[i] = d.z;
                self.tfar[i] = 1.0 - SEGMENT_EPS;
            }
            unsafe fn occluded(
                &mut self,
                valid: *const c_int,
                scene: ffi::RTCScene,
                ctx: *mut ffi::RTCIntersectContext,
            ) {
                // SAFETY: forwarded from the caller.
                unsafe { ffi::$f(valid, scene, ctx, self) }
            }
            #[inline]
            fn blocked(&self, i: usize) -> bool {
                self.tfar[i] == f32::NEG_INFINITY
            }
        }
    };
}
lanes!(ffi::RTCRay4, 4, rtcOccluded4);
lanes!(ffi::RTCRay8, 8, rtcOccluded8);
lanes!(ffi::RTCRay16, 16, rtcOccluded16);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visibility::Brute;

    const PACKETS: [Packet; 5] = [Packet::One, Packet::Four, Packet::Eight, Packet::Sixteen, Packet::Stream];

    #[test]
    fn a_wall_blocks_and_a_gap_does_not_in_every_configuration() {
        let (s, floor) = crate::visibility::wall_scene();
        let mut ctx = QueryCtx::new(s.triangle_count());
        let x = [Vec3::new(0.0, -1.0, -0.5), Vec3::new(0.0, -1.0, 0.5)];
        let targets: Vec<Vec3> = (0..37).map(|k| Vec3::new(-0.2 + 0.01 * k as f32, 1.0, 0.2)).collect();
        for exclusion in [Exclusion::Filter, Exclusion::Masks] {
            for packet in PACKETS {
                let vis = NativeEmbree::with(&s, packet, exclusion).expect("Embree device");
                assert_eq!(vis.config(), (packet, exclusion));
                for (x, want) in x.into_iter().zip([true, false]) {
                    let rays =
                        LightRays { origin: x, origin_tri: floor, leaf: None, light: LightId(0), targets: &targets };
                    let mut out = vec![!want; targets.len()];
                    vis.occluded_light(&rays, &mut out, &mut ctx);
                    assert!(out.iter().all(|&o| o == want), "{packet:?} {exclusion:?} from {x}: {out:?}");
                    assert_eq!(vis.occluded(&rays.ray(3), &mut ctx), want);
                }
            }
        }
    }

    /// Two lights facing each other over a floor: a light's triangles never block rays to it, but
    /// block rays to the other light.
    #[test]
    fn a_light_blocks_rays_to_other_lights_only() {
        let mut b = crate::SceneBuilder::new("two lights");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        let floor = b.triangle(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 0.0, 5.0), Vec3::new(5.0, 0.0, -5.0), m);
        // Light 0 at y = 1 facing up; light 1 at y = 2 facing down, right above it.
        b.light("low", &[Vec3::new(-1.0, 1.0, -1.0), Vec3::new(-1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 0.0)], Vec3::ONE);
        b.light("high", &[Vec3::new(-1.0, 2.0, -1.0), Vec3::new(1.0, 2.0, 0.0), Vec3::new(-1.0, 2.0, 1.0)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let brute = Brute::new(&s);
        let mut ctx = QueryCtx::new(s.triangle_count());
        let x = Vec3::new(-0.5, 0.0, 0.0);
        for exclusion in [Exclusion::Filter, Exclusion::Masks] {
            let vis = NativeEmbree::with(&s, Packet::Sixteen, exclusion).expect("Embree device");
            for (light, y, want) in [(0, Vec3::new(-0.5, 1.0, 0.0), false), (1, Vec3::new(-0.5, 2.0, 0.0), true)] {
                let ray = ShadowRay::new(x, y, LightId(light), floor, None);
                assert_eq!(brute.occluded(&ray, &mut ctx), want);
                assert_eq!(vis.occluded(&ray, &mut ctx), want, "light {light} {exclusion:?}");
            }
        }
    }
}
