//! Camera paths for walkthroughs (issue 20): keyframed cameras interpolated per frame, so that one
//! P-LIE serves every frame of an animation (a P-LIE does not depend on the camera, SPEC §4).
//!
//! A path is a JSON file:
//!
//! ```json
//! {
//!   "interpolation": "catmull-rom",
//!   "keyframes": [
//!     { "frame": 0,  "eye": [1550, 380, 550], "target": [400, 150, -150], "up": [0, 1, 0], "fov": 60 },
//!     { "frame": 10, "eye": [1200, 380, 700], "target": [400, 150, -150], "up": [0, 1, 0], "fov": 60 },
//!     { "frame": 19, "eye": [900, 300, 800],  "target": [300, 150, -100], "up": [0, 1, 0], "fov": 55 }
//!   ]
//! }
//! ```
//!
//! `interpolation` is `linear` (straight segments between keyframes) or `catmull-rom` (the uniform
//! Catmull-Rom spline through the keyframes, the end keyframes repeated as their own outer
//! neighbours). Eye, target, up and field of view are each interpolated that way between the two
//! keyframes around a frame, by the frame's fraction of the way between them. Keyframe frames are
//! integers, strictly increasing; the path covers frames `first..=last`, and a frame that is a
//! keyframe gets that keyframe's camera exactly. Every frame's camera is validated like any camera.

use glam::Vec3;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::scene::Camera;

/// How cameras between keyframes are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Interpolation {
    /// Straight segments between keyframes.
    Linear,
    /// The uniform Catmull-Rom spline through the keyframes.
    CatmullRom,
}

/// One keyframe: the camera at `frame`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Frame number.
    pub frame: u32,
    /// Eye position.
    pub eye: [f32; 3],
    /// Point looked at.
    pub target: [f32; 3],
    /// Up direction.
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov: f32,
}

/// A validated camera path: keyframes in increasing frame order, each a valid camera.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraPath {
    /// How frames between keyframes are interpolated.
    pub interpolation: Interpolation,
    /// The keyframes, at least one, frames strictly increasing.
    pub keyframes: Vec<Keyframe>,
}

impl Keyframe {
    fn camera(&self) -> Camera {
        Camera { eye: self.eye.into(), target: self.target.into(), up: self.up.into(), fov_deg: self.fov }
    }
}

impl CameraPath {
    /// Parses and validates a camera path from its JSON text; errors name what is wrong (with line and
    /// column for malformed JSON).
    pub fn from_json(text: &str) -> Result<CameraPath> {
        let path: CameraPath =
            serde_json::from_str(text).map_err(|e| Error::InvalidParameter(format!("camera path: {e}")))?;
        path.validate()?;
        Ok(path)
    }

    /// Reads a camera path file ([`CameraPath::from_json`]); errors name the file.
    pub fn load(file: &std::path::Path) -> Result<CameraPath> {
        let bytes = super::input::read_bounded(file, 1 << 26)?;
        let bad = |message: String| Error::Parse { path: file.to_path_buf(), line: None, message };
        let text = String::from_utf8(bytes).map_err(|_| bad("camera path: not UTF-8 text".into()))?;
        CameraPath::from_json(&text).map_err(|e| match e {
            Error::InvalidParameter(m) => bad(m),
            e => e,
        })
    }

    /// Checks: at least one keyframe, frames strictly increasing, every keyframe a valid camera.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(format!("camera path: {m}")));
        if self.keyframes.is_empty() {
            return bad("no keyframes".into());
        }
        for (i, k) in self.keyframes.iter().enumerate() {
            if i > 0 && k.frame <= self.keyframes[i - 1].frame {
                return bad(format!(
                    "keyframe {i}: frame {} does not come after frame {}",
                    k.frame,
                    self.keyframes[i - 1].frame
                ));
            }
            if let Err(e) = k.camera().validate() {
                return bad(format!("keyframe {i} (frame {}): {e}", k.frame));
            }
        }
        Ok(())
    }

    /// The first and last frame of the path (both included).
    pub fn frames(&self) -> (u32, u32) {
        let k = &self.keyframes;
        (k[0].frame, k[k.len() - 1].frame)
    }

    /// The camera at `frame`; an error if the frame is outside the path or its interpolated camera is
    /// not valid (e.g. eye and target meeting, a Catmull-Rom overshoot of the field of view).
    pub fn camera(&self, frame: u32) -> Result<Camera> {
        let (first, last) = self.frames();
        if frame < first || frame > last {
            return Err(Error::InvalidParameter(format!(
                "camera path: frame {frame} is outside the path's frames {first}..{last}"
            )));
        }
        let k = &self.keyframes;
        // The segment [k[i], k[i + 1]] holding the frame (or the keyframe itself).
        let i = k.partition_point(|kf| kf.frame <= frame) - 1;
        if k[i].frame == frame {
            return Ok(k[i].camera());
        }
        let t = (frame - k[i].frame) as f32 / (k[i + 1].frame - k[i].frame) as f32;
        let p0 = &k[i.saturating_sub(1)];
        let (p1, p2) = (&k[i], &k[i + 1]);
        let p3 = &k[(i + 2).min(k.len() - 1)];
        let v = |f: fn(&Keyframe) -> [f32; 3]| -> Vec3 {
            let [a, b, c, d] = [f(p0), f(p1), f(p2), f(p3)].map(Vec3::from);
            match self.interpolation {
                Interpolation::Linear => b + (c - b) * t,
                Interpolation::CatmullRom => catmull_rom(a, b, c, d, t),
            }
        };
        let fov = match self.interpolation {
            Interpolation::Linear => p1.fov + (p2.fov - p1.fov) * t,
            Interpolation::CatmullRom => {
                catmull_rom(Vec3::splat(p0.fov), Vec3::splat(p1.fov), Vec3::splat(p2.fov), Vec3::splat(p3.fov), t).x
            }
        };
        let c = Camera { eye: v(|k| k.eye), target: v(|k| k.target), up: v(|k| k.up), fov_deg: fov };
        c.validate().map_err(|e| Error::InvalidParameter(format!("camera path: frame {frame}: {e}")))?;
        Ok(c)
    }
}

/// The uniform Catmull-Rom spline between `b` (t = 0) and `c` (t = 1), `a` and `d` their outer
/// neighbours.
fn catmull_rom(a: Vec3, b: Vec3, c: Vec3, d: Vec3, t: f32) -> Vec3 {
    let (t2, t3) = (t * t, t * t * t);
    0.5 * (2.0 * b + (c - a) * t + (2.0 * a - 5.0 * b + 4.0 * c - d) * t2 + (3.0 * b - a - 3.0 * c + d) * t3)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(interp: &str) -> CameraPath {
        CameraPath::from_json(&format!(
            r#"{{"interpolation": "{interp}", "keyframes": [
                {{"frame": 0, "eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40}},
                {{"frame": 4, "eye": [4, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 60}},
                {{"frame": 8, "eye": [4, 4, 10], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 60}}
            ]}}"#
        ))
        .unwrap()
    }

    #[test]
    fn keyframes_are_hit_exactly_and_linear_is_halfway() {
        for interp in ["linear", "catmull-rom"] {
            let p = path(interp);
            assert_eq!(p.frames(), (0, 8));
            assert_eq!(p.camera(4).unwrap().eye, Vec3::new(4.0, 0.0, 10.0));
            assert_eq!(p.camera(8).unwrap().fov_deg, 60.0);
        }
        let c = path("linear").camera(2).unwrap();
        assert_eq!(c.eye, Vec3::new(2.0, 0.0, 10.0));
        assert_eq!(c.fov_deg, 50.0);
    }

    #[test]
    fn catmull_rom_curves_where_linear_does_not() {
        // Halfway between keyframes 1 and 2, the spline bends away from the straight segment (its
        // neighbour keyframe 0 pulls it), and stays continuous at the keyframe.
        let lin = path("linear").camera(6).unwrap().eye;
        let cr = path("catmull-rom").camera(6).unwrap().eye;
        assert_eq!(lin, Vec3::new(4.0, 2.0, 10.0));
        assert!(cr.x > 4.0, "{cr}");
        let near = path("catmull-rom").camera(5).unwrap().eye;
        assert!((near - Vec3::new(4.0, 0.0, 10.0)).length() < 1.5, "{near}");
    }

    #[test]
    fn bad_paths_are_errors_that_say_why() {
        let err = |s: &str| CameraPath::from_json(s).unwrap_err().to_string();
        assert!(err("{").contains("camera path"), "{}", err("{"));
        assert!(err(r#"{"interpolation": "cubic", "keyframes": []}"#).contains("unknown variant"));
        assert!(err(r#"{"interpolation": "linear", "keyframes": []}"#).contains("no keyframes"));
        let k = r#"{"frame": 3, "eye": [0, 0, 1], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40}"#;
        assert!(
            err(&format!(r#"{{"interpolation": "linear", "keyframes": [{k}, {k}]}}"#)).contains("does not come after")
        );
        let same = r#"{"frame": 0, "eye": [0, 0, 0], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40}"#;
        assert!(err(&format!(r#"{{"interpolation": "linear", "keyframes": [{same}]}}"#)).contains("coincide"));
        assert!(path("linear").camera(9).unwrap_err().to_string().contains("outside"));
    }
}
