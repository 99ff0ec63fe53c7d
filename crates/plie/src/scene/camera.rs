//! The pinhole camera (SPEC §1): eye, look-at target, up vector and vertical field of view. Image right
//! is `forward x up`, image up is `right x forward`; pixel (0, 0) is the top-left corner.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geometry::Aabb;

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

/// The camera's orthonormal frame and image-plane scale, computed once per image.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half: f32,
    aspect: f32,
    width: f32,
    height: f32,
}

impl Camera {
    /// A validated camera: finite values, eye distinct from target, up not parallel to the view, field
    /// of view strictly between 0 and 180 degrees.
    pub fn new(eye: Vec3, target: Vec3, up: Vec3, fov_deg: f32) -> Result<Camera> {
        let c = Camera { eye, target, up, fov_deg };
        c.validate()?;
        Ok(c)
    }

    /// Checks the camera (see [`Camera::new`]).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(Error::InvalidParameter(format!("camera: {m}")));
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite() && self.fov_deg.is_finite()) {
            return bad("non-finite value");
        }
        let f = self.target - self.eye;
        if f.length() <= 0.0 {
            return bad("eye and target coincide");
        }
        if f.normalize().cross(self.up.normalize_or_zero()).length() < 1e-6 {
            return bad("up vector is zero or parallel to the view direction");
        }
        if !(self.fov_deg > 0.0 && self.fov_deg < 180.0) {
            return bad("field of view must be between 0 and 180 degrees");
        }
        Ok(())
    }

    /// The default for scene files that carry no camera, like the "frame all" of other tools: a camera
    /// looking at the box's center along the horizontal axis nearest to `from` (±x or ±z; -z if
    /// `from` has no horizontal part), on the side `from` points to, y up, as close as it can be with
    /// the whole box in view: the box's near face fills the vertical field of view with a 5% margin
    /// (and the horizontal one too in square or wider images), centred in the picture.
    pub fn framing(bounds: &Aabb, fov_deg: f32, from: Vec3) -> Camera {
        let center = bounds.center();
        let half = (bounds.size() * 0.5).max(Vec3::splat(1e-6));
        let axis = if from.x.abs() > from.z.abs() {
            Vec3::new(from.x.signum(), 0.0, 0.0)
        } else if from.z != 0.0 {
            Vec3::new(0.0, 0.0, from.z.signum())
        } else {
            -Vec3::Z
        };
        // Half the near face's width across the view, and half the box's depth along it.
        let (across, depth) = if axis.x != 0.0 { (half.z, half.x) } else { (half.x, half.z) };
        let tan_half = (fov_deg.to_radians() * 0.5).tan();
        let dist = depth + 1.05 * across.max(half.y) / tan_half;
        Camera { eye: center + axis * dist, target: center, up: Vec3::Y, fov_deg }
    }

    /// The frame for an image of `width` x `height` pixels.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        CameraFrame {
            eye: self.eye,
            forward,
            right,
            up,
            tan_half: (self.fov_deg.to_radians() * 0.5).tan(),
            aspect: width as f32 / height as f32,
            width: width as f32,
            height: height as f32,
        }
    }
}

impl CameraFrame {
    /// Origin and unit direction of the eye ray through the continuous image point `(x, y)`, in pixels
    /// from the top-left corner.
    pub fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        let sx = (2.0 * x / self.width - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.tan_half;
        (self.eye, (self.forward + self.right * sx + self.up * sy).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_is_forward_cross_up() {
        // The classic Cornell camera looks +z with y up: image right is -x (red wall at x = 550 on the left).
        let c = Camera::new(Vec3::new(278.0, 273.0, -800.0), Vec3::new(278.0, 273.0, 0.0), Vec3::Y, 39.3).unwrap();
        let f = c.frame(100, 100);
        let (_, d) = f.ray(99.0, 50.0);
        assert!(d.x < 0.0);
        let (_, d) = f.ray(50.0, 0.0);
        assert!(d.y > 0.0, "top row looks up");
    }

    /// The default camera frames a box: its center in the middle of the picture, every corner in
    /// view, and the box filling the view (not a small part of it), whatever side it looks from.
    #[test]
    fn framing_centres_the_box_and_fills_the_view() {
        // CornellBox-Original's bounds, and a flat wide box.
        let boxes = [
            Aabb::new(Vec3::new(-1.02, 0.0, -1.04), Vec3::new(1.0, 1.99, 0.99)),
            Aabb::new(Vec3::new(10.0, -1.0, 3.0), Vec3::new(50.0, 2.0, 5.0)),
        ];
        let froms = [Vec3::Z, -Vec3::Z, Vec3::new(0.9, 0.3, 0.2), Vec3::new(-0.1, 0.0, -0.05), Vec3::Y];
        for b in boxes {
            for from in froms {
                let c = Camera::framing(&b, 40.0, from);
                c.validate().unwrap();
                let f = c.frame(100, 100);
                let ndc = |p: Vec3| {
                    let d = p - f.eye;
                    let z = d.dot(f.forward);
                    assert!(z > 0.0, "{p} behind the camera");
                    (d.dot(f.right) / (z * f.tan_half), d.dot(f.up) / (z * f.tan_half))
                };
                let (cx, cy) = ndc(b.center());
                assert!(cx.abs() < 1e-5 && cy.abs() < 1e-5, "{b:?} from {from}: center at {cx}, {cy}");
                let mut widest = 0.0f32;
                for i in 0..8 {
                    let p = Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), b.max, b.min);
                    let (x, y) = ndc(p);
                    assert!(x.abs() <= 1.0 && y.abs() <= 1.0, "{b:?} from {from}: corner {p} out of view");
                    widest = widest.max(x.abs()).max(y.abs());
                }
                assert!(widest > 0.9, "{b:?} from {from}: the box fills only {widest} of the view");
            }
        }
    }

    #[test]
    fn rejects_bad_cameras() {
        assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, f32::NAN).is_err());
    }
}
