//! Typed properties of Mitsuba elements (issue 18): `<float>`, `<integer>`, `<boolean>`, `<string>`,
//! `<point>`/`<vector>`, colours (`<rgb>`, `<srgb>`, `<spectrum>`, a plain `<float>`) and
//! `<transform>` with its `matrix`, `translate`, `rotate`, `scale` and `lookat` steps, in both the 0.6
//! and 3.x spellings (`x`/`y`/`z` attributes or one `value`).

use glam::{Mat4, Vec3, Vec4};

use super::xml::Elem;
use crate::error::Result;
use crate::io::input::short;
use crate::scene::texture::srgb_to_linear;

/// The child property named `name`.
pub fn find<'a>(e: &'a Elem, name: &str) -> Option<&'a Elem> {
    e.children.iter().find(|c| c.attr("name") == Some(name))
}

/// Numbers separated by commas and/or white space.
pub fn numbers(e: &Elem, s: &str) -> Result<Vec<f32>> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| match t.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(e.error(format!("'{}' is not a finite number", short(t)))),
        })
        .collect()
}

/// One number from attribute `attr`.
pub fn number_attr(e: &Elem, attr: &str) -> Result<Option<f32>> {
    match e.attr(attr) {
        None => Ok(None),
        Some(s) => match numbers(e, s)?.as_slice() {
            [v] => Ok(Some(*v)),
            _ => Err(e.error(format!("'{attr}' must be one number, not '{}'", short(s)))),
        },
    }
}

/// `<float name=... value=...>` (or `<integer>`), or `default`.
pub fn float(e: &Elem, name: &str, default: f32) -> Result<f32> {
    match find(e, name) {
        None => Ok(default),
        Some(p) if p.tag == "float" || p.tag == "integer" => {
            number_attr(p, "value")?.ok_or_else(|| p.error("has no value".into()))
        }
        Some(p) => Err(p.error(format!("'{name}' must be a <float>"))),
    }
}

/// `<integer name=... value=...>`, or `default`.
pub fn integer(e: &Elem, name: &str, default: i64) -> Result<i64> {
    match find(e, name) {
        None => Ok(default),
        Some(p) => {
            let v = p.need("value")?;
            v.trim().parse().map_err(|_| p.error(format!("'{}' is not an integer", short(v))))
        }
    }
}

/// `<boolean name=... value="true|false">`, or `default`.
pub fn boolean(e: &Elem, name: &str, default: bool) -> Result<bool> {
    match find(e, name) {
        None => Ok(default),
        Some(p) => match p.need("value")?.trim() {
            "true" | "1" => Ok(true),
            "false" | "0" => Ok(false),
            v => Err(p.error(format!("'{}' is not true or false", short(v)))),
        },
    }
}

/// `<string name=... value=...>`.
pub fn string<'a>(e: &'a Elem, name: &str) -> Result<Option<&'a str>> {
    find(e, name).map(|p| p.need("value")).transpose()
}

/// A 3-vector from `x`, `y`, `z` attributes (missing ones `default`) or a `value` of one or three
/// numbers (one: all three the same when `splat`).
pub fn vec3_of(e: &Elem, default: f32, splat: bool) -> Result<Vec3> {
    if let Some(s) = e.attr("value") {
        return match numbers(e, s)?.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            [v] if splat => Ok(Vec3::splat(*v)),
            _ => Err(e.error(format!("'value' must be three numbers, not '{}'", short(s)))),
        };
    }
    let c = |a| number_attr(e, a).map(|v| v.unwrap_or(default));
    Ok(Vec3::new(c("x")?, c("y")?, c("z")?))
}

/// `<point name=...>`, or `default`.
pub fn point(e: &Elem, name: &str, default: Vec3) -> Result<Vec3> {
    find(e, name).map_or(Ok(default), |p| vec3_of(p, 0.0, false))
}

/// A colour element (`rgb`, `srgb`, `spectrum`, `float`) as linear RGB; `spectral` is set when a
/// spectrum of wavelength:value pairs was averaged to grey.
pub fn colour(p: &Elem, spectral: &mut bool) -> Result<Vec3> {
    let s = p.need("value")?;
    match p.tag.as_str() {
        "float" => Ok(Vec3::splat(number_attr(p, "value")?.unwrap_or(0.0))),
        "rgb" | "color" => match numbers(p, s)?.as_slice() {
            [v] => Ok(Vec3::splat(*v)),
            [r, g, b] => Ok(Vec3::new(*r, *g, *b)),
            _ => Err(p.error(format!("expects one or three numbers, not '{}'", short(s)))),
        },
        "srgb" => {
            let v = if let Some(hex) = s.trim().strip_prefix('#') {
                let x = u32::from_str_radix(hex, 16).map_err(|_| p.error(format!("'{}' is not a colour", short(s))))?;
                Vec3::new((x >> 16 & 255) as f32, (x >> 8 & 255) as f32, (x & 255) as f32) / 255.0
            } else {
                match numbers(p, s)?.as_slice() {
                    [v] => Vec3::splat(*v),
                    [r, g, b] => Vec3::new(*r, *g, *b),
                    _ => return Err(p.error(format!("expects one or three numbers, not '{}'", short(s)))),
                }
            };
            Ok(Vec3::new(srgb_to_linear(v.x), srgb_to_linear(v.y), srgb_to_linear(v.z)))
        }
        "spectrum" => {
            if s.contains(':') {
                let mut sum = 0.0;
                let mut n = 0;
                for pair in s.split(',') {
                    let vals = numbers(p, &pair.replace(':', " "))?;
                    let [_, v] = vals.as_slice() else {
                        return Err(p.error(format!("'{}' is not a wavelength:value pair", short(pair))));
                    };
                    sum += v;
                    n += 1;
                }
                *spectral = true;
                return Ok(Vec3::splat(sum / n.max(1) as f32));
            }
            match numbers(p, s)?.as_slice() {
                [v] => Ok(Vec3::splat(*v)),
                _ => Err(p.error("a spectrum needs one value or wavelength:value pairs".into())),
            }
        }
        t => Err(p.error(format!("<{t}> is not a colour (rgb, srgb, spectrum or float)"))),
    }
}

/// `<transform name=...>` as a matrix (identity if absent).
pub fn transform(e: &Elem, name: &str) -> Result<Mat4> {
    match find(e, name) {
        None => Ok(Mat4::IDENTITY),
        Some(t) if t.tag == "transform" => transform_of(t),
        Some(t) => Err(t.error(format!("'{name}' must be a <transform>"))),
    }
}

/// The matrix of a `<transform>` element: its steps applied in order.
pub fn transform_of(t: &Elem) -> Result<Mat4> {
    let mut m = Mat4::IDENTITY;
    for s in &t.children {
        let step = match s.tag.as_str() {
            "translate" => Mat4::from_translation(vec3_of(s, 0.0, false)?),
            "scale" => Mat4::from_scale(vec3_of(s, 1.0, true)?),
            "rotate" => {
                let axis = vec3_of(s, 0.0, false)?;
                let angle = number_attr(s, "angle")?.ok_or_else(|| s.error("has no 'angle'".into()))?;
                if axis.length() == 0.0 {
                    return Err(s.error("the rotation axis is zero".into()));
                }
                Mat4::from_axis_angle(axis.normalize(), angle.to_radians())
            }
            "matrix" => {
                let v = numbers(s, s.need("value")?)?;
                match v.len() {
                    16 => Mat4::from_cols_array(&v.try_into().unwrap_or([0.0; 16])).transpose(),
                    9 => Mat4::from_cols(
                        Vec4::new(v[0], v[3], v[6], 0.0),
                        Vec4::new(v[1], v[4], v[7], 0.0),
                        Vec4::new(v[2], v[5], v[8], 0.0),
                        Vec4::W,
                    ),
                    n => return Err(s.error(format!("a matrix needs 16 (or 9) numbers, not {n}"))),
                }
            }
            "lookat" => {
                let get = |a: &str| -> Result<Vec3> {
                    let v = numbers(s, s.need(a)?)?;
                    match v.as_slice() {
                        [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                        _ => Err(s.error(format!("'{a}' must be three numbers"))),
                    }
                };
                let origin = get("origin")?;
                let target = get("target")?;
                let up = if s.attr("up").is_some() { get("up")? } else { Vec3::Y };
                let dir = (target - origin).normalize_or_zero();
                let left = up.cross(dir).normalize_or_zero();
                if dir == Vec3::ZERO || left == Vec3::ZERO {
                    return Err(s.error("origin equals target, or up is parallel to the view".into()));
                }
                let new_up = dir.cross(left);
                Mat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0))
            }
            t => {
                return Err(s.error(format!("<{t}> is not a transform step (matrix, translate, rotate, scale, lookat)")))
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(t.error("the transform is not finite".into()));
    }
    Ok(m)
}
