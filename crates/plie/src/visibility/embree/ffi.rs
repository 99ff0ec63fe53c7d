//! Thin bindings to the part of Intel Embree 3 (3.13, `libembree3`) that the Embree visibility modes
//! use: a device, a scene of triangle geometries (native, `embree`) or of one user geometry
//! (`embree-exact`), an occlusion filter, and the occlusion queries `rtcOccluded1/4/8/16/1M`. Layouts follow
//! `embree3/rtcore_*.h` of Embree 3.13 as built by Debian (`RTC_MAX_INSTANCE_LEVEL_COUNT` = 1,
//! `RTC_MIN_WIDTH` = 0); the tests at the end check sizes and offsets.
//!
//! No crate on crates.io covers user geometries and filters with a context struct extending
//! `RTCIntersectContext`, so these few declarations are written by hand.

#![allow(non_camel_case_types, non_snake_case, missing_docs)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// Opaque handle types (`typedef struct RTCDeviceTy* RTCDevice;` etc.).
#[repr(C)]
pub struct RTCDeviceTy {
    _private: [u8; 0],
}
#[repr(C)]
pub struct RTCSceneTy {
    _private: [u8; 0],
}
#[repr(C)]
pub struct RTCGeometryTy {
    _private: [u8; 0],
}
pub type RTCDevice = *mut RTCDeviceTy;
pub type RTCScene = *mut RTCSceneTy;
pub type RTCGeometry = *mut RTCGeometryTy;

/// `enum RTCError`.
pub type RTCError = c_int;
pub const RTC_ERROR_NONE: RTCError = 0;

/// `enum RTCGeometryType`.
pub type RTCGeometryType = c_int;
pub const RTC_GEOMETRY_TYPE_TRIANGLE: RTCGeometryType = 0;
pub const RTC_GEOMETRY_TYPE_USER: RTCGeometryType = 120;

/// `enum RTCBufferType`.
pub type RTCBufferType = c_int;
pub const RTC_BUFFER_TYPE_INDEX: RTCBufferType = 0;
pub const RTC_BUFFER_TYPE_VERTEX: RTCBufferType = 1;

/// `enum RTCFormat`.
pub type RTCFormat = c_int;
pub const RTC_FORMAT_UINT3: RTCFormat = 0x5003;
pub const RTC_FORMAT_FLOAT3: RTCFormat = 0x9003;

/// `enum RTCDeviceProperty`.
pub type RTCDeviceProperty = c_int;
pub const RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED: RTCDeviceProperty = 64;
pub const RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED: RTCDeviceProperty = 66;

/// `enum RTCSceneFlags`.
pub type RTCSceneFlags = c_int;
pub const RTC_SCENE_FLAG_ROBUST: RTCSceneFlags = 1 << 2;

/// `enum RTCBuildQuality`.
pub type RTCBuildQuality = c_int;
pub const RTC_BUILD_QUALITY_HIGH: RTCBuildQuality = 2;

/// `enum RTCIntersectContextFlags`.
pub type RTCIntersectContextFlags = c_int;
pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: RTCIntersectContextFlags = 0;
pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: RTCIntersectContextFlags = 1;

pub const RTC_INVALID_GEOMETRY_ID: c_uint = u32::MAX;

/// `struct RTCRay` (16-byte aligned).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}

/// `struct RTCBounds` (16-byte aligned).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCBounds {
    pub lower_x: f32,
    pub lower_y: f32,
    pub lower_z: f32,
    pub align0: f32,
    pub upper_x: f32,
    pub upper_y: f32,
    pub upper_z: f32,
    pub align1: f32,
}

/// `struct RTCRayN`: an opaque SOA packet of `N` rays; component `k` of ray `i` is float `k * N + i`.
#[repr(C)]
pub struct RTCRayN {
    _private: [u8; 0],
}

/// `struct RTCHitN`: an opaque SOA packet of `N` hits; `primID` of hit `i` is `u32` number `5 * N + i`.
#[repr(C)]
pub struct RTCHitN {
    _private: [u8; 0],
}

/// `struct RTCFilterFunctionNArguments`.
#[repr(C)]
pub struct RTCFilterFunctionNArguments {
    pub valid: *mut c_int,
    pub geometryUserPtr: *mut c_void,
    pub context: *mut RTCIntersectContext,
    pub ray: *mut RTCRayN,
    pub hit: *mut RTCHitN,
    pub N: c_uint,
}
pub type RTCFilterFunctionN = Option<unsafe extern "C" fn(args: *const RTCFilterFunctionNArguments)>;

/// `struct RTCIntersectContext` with one instance level and no minimum width.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCIntersectContext {
    pub flags: RTCIntersectContextFlags,
    pub filter: RTCFilterFunctionN,
    pub instID: [c_uint; 1],
}

impl RTCIntersectContext {
    /// What the header's inline `rtcInitIntersectContext` sets.
    pub fn new() -> RTCIntersectContext {
        RTCIntersectContext {
            flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
            filter: None,
            instID: [RTC_INVALID_GEOMETRY_ID],
        }
    }
}

/// `struct RTCBoundsFunctionArguments`.
#[repr(C)]
pub struct RTCBoundsFunctionArguments {
    pub geometryUserPtr: *mut c_void,
    pub primID: c_uint,
    pub timeStep: c_uint,
    pub bounds_o: *mut RTCBounds,
}
pub type RTCBoundsFunction = Option<unsafe extern "C" fn(args: *const RTCBoundsFunctionArguments)>;

/// `struct RTCOccludedFunctionNArguments`.
#[repr(C)]
pub struct RTCOccludedFunctionNArguments {
    pub valid: *mut c_int,
    pub geometryUserPtr: *mut c_void,
    pub primID: c_uint,
    pub context: *mut RTCIntersectContext,
    pub ray: *mut RTCRayN,
    pub N: c_uint,
    pub geomID: c_uint,
}
pub type RTCOccludedFunctionN = Option<unsafe extern "C" fn(args: *const RTCOccludedFunctionNArguments)>;

/// `struct RTCRay4/8/16`: `N` rays in SOA layout, aligned to `N` floats (at least 16 bytes).
macro_rules! ray_packet {
    ($name:ident, $n:literal, $align:literal) => {
        #[repr(C, align($align))]
        #[derive(Clone, Copy, Debug)]
        pub struct $name {
            pub org_x: [f32; $n],
            pub org_y: [f32; $n],
            pub org_z: [f32; $n],
            pub tnear: [f32; $n],
            pub dir_x: [f32; $n],
            pub dir_y: [f32; $n],
            pub dir_z: [f32; $n],
            pub time: [f32; $n],
            pub tfar: [f32; $n],
            pub mask: [c_uint; $n],
            pub id: [c_uint; $n],
            pub flags: [c_uint; $n],
        }
    };
}
ray_packet!(RTCRay4, 4, 16);
ray_packet!(RTCRay8, 8, 32);
ray_packet!(RTCRay16, 16, 64);

#[link(name = "embree3")]
extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceError(device: RTCDevice) -> RTCError;
    pub fn rtcGetDeviceProperty(device: RTCDevice, prop: RTCDeviceProperty) -> isize;

    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcSetSceneFlags(scene: RTCScene, flags: RTCSceneFlags);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: RTCBuildQuality);
    pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    pub fn rtcCommitScene(scene: RTCScene);
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcOccluded4(valid: *const c_int, scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay4);
    pub fn rtcOccluded8(valid: *const c_int, scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay8);
    pub fn rtcOccluded16(valid: *const c_int, scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay16);
    pub fn rtcOccluded1M(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        ray: *mut RTCRay,
        m: c_uint,
        byte_stride: usize,
    );

    pub fn rtcNewGeometry(device: RTCDevice, kind: RTCGeometryType) -> RTCGeometry;
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: RTCBuildQuality);
    pub fn rtcSetGeometryUserPrimitiveCount(geometry: RTCGeometry, count: c_uint);
    pub fn rtcSetGeometryUserData(geometry: RTCGeometry, user: *mut c_void);
    pub fn rtcSetGeometryBoundsFunction(geometry: RTCGeometry, bounds: RTCBoundsFunction, user: *mut c_void);
    pub fn rtcSetGeometryOccludedFunction(geometry: RTCGeometry, occluded: RTCOccludedFunctionN);
    pub fn rtcSetSharedGeometryBuffer(
        geometry: RTCGeometry,
        kind: RTCBufferType,
        slot: c_uint,
        format: RTCFormat,
        ptr: *const c_void,
        byte_offset: usize,
        byte_stride: usize,
        item_count: usize,
    );
    pub fn rtcSetGeometryMask(geometry: RTCGeometry, mask: c_uint);
    pub fn rtcSetGeometryOccludedFilterFunction(geometry: RTCGeometry, filter: RTCFilterFunctionN);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
}

/// Human-readable name of an error code (`enum RTCError`).
pub fn error_name(e: RTCError) -> &'static str {
    match e {
        0 => "RTC_ERROR_NONE",
        1 => "RTC_ERROR_UNKNOWN",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU",
        6 => "RTC_ERROR_CANCELLED",
        _ => "unknown RTCError",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, offset_of, size_of};

    #[test]
    fn layouts_match_embree_3_headers() {
        assert_eq!((size_of::<RTCRay>(), align_of::<RTCRay>()), (48, 16));
        assert_eq!(offset_of!(RTCRay, tnear), 12);
        assert_eq!(offset_of!(RTCRay, tfar), 32);
        assert_eq!(offset_of!(RTCRay, flags), 44);
        assert_eq!((size_of::<RTCBounds>(), align_of::<RTCBounds>()), (32, 16));
        assert_eq!(offset_of!(RTCBounds, upper_x), 16);
        assert_eq!(size_of::<RTCIntersectContext>(), 24);
        assert_eq!(offset_of!(RTCIntersectContext, filter), 8);
        assert_eq!(offset_of!(RTCIntersectContext, instID), 16);
        assert_eq!(offset_of!(RTCBoundsFunctionArguments, bounds_o), 16);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, primID), 16);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, context), 24);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, ray), 32);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, N), 40);
        assert_eq!(offset_of!(RTCOccludedFunctionNArguments, geomID), 44);
        assert_eq!(offset_of!(RTCFilterFunctionNArguments, hit), 32);
        assert_eq!(offset_of!(RTCFilterFunctionNArguments, N), 40);
        assert_eq!((size_of::<RTCRay4>(), align_of::<RTCRay4>()), (192, 16));
        assert_eq!((size_of::<RTCRay8>(), align_of::<RTCRay8>()), (384, 32));
        assert_eq!((size_of::<RTCRay16>(), align_of::<RTCRay16>()), (768, 64));
        assert_eq!(offset_of!(RTCRay16, tfar), 8 * 64);
    }
}
