//! The Mitsuba sensor (issue 18): a `perspective` sensor's `fov` (or `focal_length`), `fov_axis` and
//! `to_world`, and its film's `width` and `height`, as plie's camera and image size.

use glam::Vec3;

use super::props::{find, float, integer, string, transform};
use super::xml::Elem;
use crate::error::Result;
use crate::io::input::short;
use crate::scene::Camera;

/// Checks the sensor's type: `perspective`, or `thinlens` rendered as a pinhole (noted).
pub(super) fn check_type(e: &Elem, notes: &mut Vec<String>) -> Result<()> {
    match e.need("type")? {
        "perspective" => Ok(()),
        "thinlens" => {
            notes.push(format!("sensor at line {}: thinlens is rendered as a pinhole (no depth of field)", e.line));
            Ok(())
        }
        t => Err(e.error(format!("sensor type '{}' is not supported (perspective is)", short(t)))),
    }
}

/// The sensor's camera and image size (width, height); a mirroring transform is noted.
pub(super) fn camera(e: &Elem, notes: &mut Vec<String>) -> Result<(Camera, (u32, u32))> {
    let (mut w, mut h) = (768i64, 576i64);
    if let Some(film) = e.children.iter().find(|c| c.tag == "film") {
        w = integer(film, "width", w)?;
        h = integer(film, "height", h)?;
        if !(1..=32768).contains(&w) || !(1..=32768).contains(&h) {
            return Err(film.error(format!("image size {w}x{h} must be between 1 and 32768")));
        }
    }
    let fov = match (find(e, "fov"), string(e, "focal_length")?) {
        (Some(_), _) => float(e, "fov", 0.0)?,
        (None, Some(f)) => {
            let mm: f32 = f
                .trim()
                .trim_end_matches("mm")
                .parse()
                .map_err(|_| e.error(format!("focal_length '{}' is not a length in mm", short(f))))?;
            2.0 * (18.0 / mm).atan().to_degrees()
        }
        (None, None) => 2.0 * (18.0f32 / 50.0).atan().to_degrees(),
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(e.error(format!("fov {fov} must be between 0 and 180 degrees")));
    }
    let (wf, hf) = (w as f32, h as f32);
    let half = (fov.to_radians() / 2.0).tan();
    let axis = string(e, "fov_axis")?.unwrap_or("x");
    let tan_v = match axis {
        "x" => half * hf / wf,
        "y" => half,
        "diagonal" => half * hf / (wf * wf + hf * hf).sqrt(),
        "smaller" if wf < hf => half * hf / wf,
        "smaller" => half,
        "larger" if wf > hf => half * hf / wf,
        "larger" => half,
        a => return Err(e.error(format!("fov_axis '{}' is not x, y, diagonal, smaller or larger", short(a)))),
    };
    let m = transform(e, "to_world")?;
    let eye = m.transform_point3(Vec3::ZERO);
    let forward = m.transform_vector3(Vec3::Z);
    let up = m.transform_vector3(Vec3::Y);
    let left = m.transform_vector3(Vec3::X);
    if forward.cross(up).dot(left) > 0.0 {
        notes.push(format!("sensor at line {}: its transform mirrors the image; plie renders it unmirrored", e.line));
    }
    let camera =
        Camera { eye, target: eye + forward.normalize_or_zero(), up, fov_deg: 2.0 * tan_v.atan().to_degrees() };
    camera.validate().map_err(|err| e.error(err.to_string()))?;
    Ok((camera, (w as u32, h as u32)))
}
