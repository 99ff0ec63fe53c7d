//! Image output (SPEC §2, step 3): radiance per pixel to a tone-mapped 8-bit sRGB PNG for viewing, and
//! to linear 32-bit float OpenEXR or PFM for measurement; plus a PFM reader for bit-exact comparisons.
//!
//! Input is row-major, top row first, linear RGB. PNG: each channel is clamped to [0, 1] (NaN becomes
//! 0), encoded with the sRGB transfer function and rounded. EXR (via the `image` crate, lossless) and
//! PFM store the values as they are. PFM layout: `PF\n{w} {h}\n-1.0\n`, then little-endian `f32` RGB
//! rows from the bottom row up. Every file is written through [`super::write_atomic`].

use std::path::Path;

use ::image::codecs::openexr::OpenExrEncoder;
use ::image::codecs::png::PngEncoder;
use ::image::{ExtendedColorType, ImageEncoder};
use glam::Vec3;

use super::{parse_error, write_atomic};
use crate::error::{Error, Result};

/// An output image format, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png`: tone-mapped 8-bit sRGB.
    Png,
    /// `.exr`: linear 32-bit float RGB.
    Exr,
    /// `.pfm`: linear 32-bit float RGB, portable float map.
    Pfm,
}

impl ImageFormat {
    /// The supported extensions, for messages.
    pub const EXTENSIONS: &'static str = ".png, .exr, .pfm";

    /// The format for a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        match ext.as_str() {
            "png" => Ok(ImageFormat::Png),
            "exr" => Ok(ImageFormat::Exr),
            "pfm" => Ok(ImageFormat::Pfm),
            "" if path.is_dir() => Err(Error::Image {
                path: path.to_path_buf(),
                message: format!("is a directory; give an image file name ({})", Self::EXTENSIONS),
            }),
            "" => Err(Error::Image {
                path: path.to_path_buf(),
                message: format!("has no extension to choose the image format; supported: {}", Self::EXTENSIONS),
            }),
            _ => Err(Error::Image {
                path: path.to_path_buf(),
                message: format!("unknown image format '.{ext}'; supported: {}", Self::EXTENSIONS),
            }),
        }
    }
}

/// The sRGB transfer function of a linear value clamped to [0, 1], as an 8-bit value (NaN gives 0).
pub fn srgb_encode(linear: f32) -> u8 {
    let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Writes a `width` x `height` image of linear radiance (row-major, top row first) to `path`, in the
/// format of its extension ([`ImageFormat`]), atomically.
pub fn save_image(path: &Path, width: u32, height: u32, radiance: &[Vec3]) -> Result<()> {
    let format = ImageFormat::from_path(path)?;
    let image_err = |message: String| Error::Image { path: path.to_path_buf(), message };
    if width == 0 || height == 0 {
        return Err(image_err(format!("image size {width} x {height} is empty")));
    }
    if width as u64 * height as u64 != radiance.len() as u64 {
        return Err(image_err(format!(
            "{width} x {height} image needs {} pixels, got {}",
            width as u64 * height as u64,
            radiance.len()
        )));
    }
    let io = |e: std::io::Error| Error::Io { path: path.to_path_buf(), source: e };
    match format {
        ImageFormat::Png => {
            let bytes: Vec<u8> = radiance.iter().flat_map(|p| p.to_array().map(srgb_encode)).collect();
            write_atomic(path, |w| {
                PngEncoder::new(w)
                    .write_image(&bytes, width, height, ExtendedColorType::Rgb8)
                    .map_err(|e| image_err(e.to_string()))
            })
        }
        ImageFormat::Exr => {
            let bytes: Vec<u8> = radiance.iter().flat_map(|p| p.to_array()).flat_map(f32::to_ne_bytes).collect();
            write_atomic(path, |w| {
                OpenExrEncoder::new(w)
                    .write_image(&bytes, width, height, ExtendedColorType::Rgb32F)
                    .map_err(|e| image_err(e.to_string()))
            })
        }
        ImageFormat::Pfm => {
            let bytes = encode_pfm(width, height, radiance);
            write_atomic(path, |w| w.write_all(&bytes).map_err(io))
        }
    }
}

/// The PFM file for an image (row-major, top row first): header, then rows bottom to top.
pub fn encode_pfm(width: u32, height: u32, radiance: &[Vec3]) -> Vec<u8> {
    let mut out = format!("PF\n{width} {height}\n-1.0\n").into_bytes();
    out.reserve(radiance.len() * 12);
    for row in radiance.chunks(width.max(1) as usize).rev() {
        for p in row {
            for c in p.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

/// Reads a PFM file: `(width, height, pixels)`, pixels row-major, top row first. Accepts colour (`PF`)
/// and greyscale (`Pf`, expanded to grey RGB) maps of either byte order; rejects anything malformed,
/// truncated or with trailing bytes.
pub fn load_pfm(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let bytes = super::input::read_bounded(path, super::input::MAX_INPUT_BYTES)?;
    decode_pfm(&bytes).map_err(|m| parse_error(path, None, m))
}

/// [`load_pfm`] on bytes in memory.
pub fn decode_pfm(bytes: &[u8]) -> Result<(u32, u32, Vec<Vec3>), String> {
    // Header: four whitespace-separated tokens, then exactly one whitespace byte.
    let mut pos = 0;
    let mut tokens = Vec::new();
    while tokens.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() && pos - start < 32 {
            pos += 1;
        }
        if pos == start || pos >= bytes.len() {
            return Err("truncated or malformed PFM header".into());
        }
        tokens.push(std::str::from_utf8(&bytes[start..pos]).map_err(|_| "malformed PFM header")?);
    }
    pos += 1; // the single whitespace byte after the scale
    let channels = match tokens[0] {
        "PF" => 3,
        "Pf" => 1,
        t => return Err(format!("not a PFM file: magic '{t}', expected 'PF' or 'Pf'")),
    };
    let dim = |t: &str| t.parse::<u32>().ok().filter(|&d| d > 0).ok_or(format!("bad PFM dimension '{t}'"));
    let (w, h) = (dim(tokens[1])?, dim(tokens[2])?);
    let scale: f32 = tokens[3].parse().map_err(|_| format!("bad PFM scale '{}'", tokens[3]))?;
    if !(scale.is_finite() && scale != 0.0) {
        return Err(format!("bad PFM scale '{}'", tokens[3]));
    }
    let data = &bytes[pos..];
    let expected = w as u128 * h as u128 * channels * 4;
    if data.len() as u128 != expected {
        let what = if (data.len() as u128) < expected { "truncated" } else { "trailing bytes after the" };
        return Err(format!("{what} PFM data: {w} x {h} needs {expected} bytes, found {}", data.len()));
    }
    let read = |c: &[u8]| {
        let b = [c[0], c[1], c[2], c[3]];
        if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let row_bytes = w as usize * channels as usize * 4;
    let mut pixels = Vec::with_capacity(w as usize * h as usize);
    for row in data.chunks_exact(row_bytes).rev() {
        for px in row.chunks_exact(channels as usize * 4) {
            let v: Vec<f32> = px.chunks_exact(4).map(read).collect();
            pixels.push(if channels == 3 { Vec3::new(v[0], v[1], v[2]) } else { Vec3::splat(v[0]) });
        }
    }
    Ok((w, h, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_rows_are_bottom_up() {
        let img = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)];
        let bytes = encode_pfm(1, 2, &img);
        assert!(bytes.starts_with(b"PF\n1 2\n-1.0\n"));
        assert_eq!(&bytes[12..16], &4.0f32.to_le_bytes());
        assert_eq!(decode_pfm(&bytes).unwrap(), (1, 2, img.to_vec()));
    }

    #[test]
    fn pfm_rejects_bad_headers() {
        assert!(decode_pfm(b"").is_err());
        assert!(decode_pfm(b"P6\n1 1\n-1.0\n000000000000").is_err());
        assert!(decode_pfm(b"PF\n0 1\n-1.0\n").is_err());
        assert!(decode_pfm(b"PF\n1 1\nnan\n000000000000").is_err());
        assert!(decode_pfm(b"PF\n1 1\n-1.0").is_err());
    }

    #[test]
    fn srgb_endpoints() {
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(1.0), 255);
        assert_eq!(srgb_encode(f32::NAN), 0);
        assert_eq!(srgb_encode(-3.0), 0);
        assert_eq!(srgb_encode(7.0), 255);
    }
}
