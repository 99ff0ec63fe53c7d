//! The Embree peers (cargo feature `embree`, SPEC §5's comparison with a modern ray tracer): Intel
//! Embree 3 as a user would run it, and Embree's traversal paired with our predicate.
//!
//! - [`native`] (`--visibility embree`): Embree's own triangles and triangle test, a light's samples
//!   from one point answered in packets. The reference a user compares against. **Not exact**: its
//!   triangle test is Embree's, not our watertight test, so a few shadow-ray answers differ from
//!   `brute` (tests bound the fraction; `compare.rs` measures it).
//! - [`exact`] (`--visibility embree-exact`): Embree's BVH over padded triangle boxes proposes
//!   candidates and [`super::blocks`] decides, so it answers exactly as brute force. Kept because it
//!   is the only exact mode whose traversal is not ours: the exactness suites then check our predicate
//!   under a second, independent BVH, and it measures what Embree's traversal alone is worth.
//!
//! Both own an Embree `Device`; `ffi.rs` holds the hand-written bindings.

pub mod exact;
mod ffi;
pub mod native;

use std::ptr;

use crate::{Error, Result};

/// The error Embree reports for `device` (the thread's last error where `device` is null), if any.
fn check(device: ffi::RTCDevice, what: &str) -> Result<()> {
    // SAFETY: `device` is null or a live device.
    let e = unsafe { ffi::rtcGetDeviceError(device) };
    if e == ffi::RTC_ERROR_NONE {
        Ok(())
    } else {
        Err(Error::Embree(format!("{what} failed: {}", ffi::error_name(e))))
    }
}

/// An Embree device, released on drop (after the scenes made on it: owners declare it last).
struct Device(ffi::RTCDevice);

impl Device {
    /// A new device with Embree's default configuration. Fails with [`Error::Embree`] if Embree cannot
    /// run here (e.g. an unsupported CPU).
    fn new() -> Result<Device> {
        // SAFETY: a plain API call; a null configuration string means the defaults.
        let device = unsafe { ffi::rtcNewDevice(ptr::null()) };
        if device.is_null() {
            check(device, "rtcNewDevice")?;
            return Err(Error::Embree("rtcNewDevice returned no device".into()));
        }
        Ok(Device(device))
    }

    /// True if the device's build supports `prop` (an `RTC_DEVICE_PROPERTY_*_SUPPORTED`).
    fn supports(&self, prop: ffi::RTCDeviceProperty) -> bool {
        // SAFETY: the device is live.
        unsafe { ffi::rtcGetDeviceProperty(self.0, prop) != 0 }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the device was created by `Device::new` and is released once.
        unsafe { ffi::rtcReleaseDevice(self.0) };
    }
}
