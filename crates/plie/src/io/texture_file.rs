//! Texture images (issue 18): a PNG, JPEG or OpenEXR file decoded into a [`Texture`] of linear RGB
//! texels. 8- and 16-bit images are sRGB-encoded unless the scene says they are raw (linear) data;
//! float images (EXR) are linear. Reads are bounded ([`super::input`]) and so is the decoded size.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;
use image::{DynamicImage, ImageReader, Limits};

use super::input::{read_bounded, MAX_INPUT_BYTES};
use super::parse_error;
use crate::error::Result;
use crate::scene::texture::{srgb_to_linear, Texture};

/// The largest texture side plie decodes.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Loads the image at `path` as a texture; `srgb`: decode 8/16-bit values with the sRGB curve.
pub fn load_texture(path: &Path, srgb: bool) -> Result<Texture> {
    let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    decode_texture(&name, bytes, srgb).map_err(|m| parse_error(path, None, m))
}

/// Decodes an image file's bytes as a texture named `name`; `srgb` as in [`load_texture`].
pub fn decode_texture(name: &str, bytes: Vec<u8>, srgb: bool) -> std::result::Result<Texture, String> {
    let fail = |m: String| m;
    let mut reader = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| fail(format!("cannot read texture: {e}")))?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(2 << 30);
    reader.limits(limits);
    let image = reader.decode().map_err(|e| fail(format!("cannot decode texture: {e}")))?;
    let float = matches!(image, DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_));
    let (w, h) = (image.width(), image.height());
    let rgb = image.into_rgb32f();
    let decode = |c: f32| if srgb && !float { srgb_to_linear(c.clamp(0.0, 1.0)) } else { c };
    let texels: Vec<Vec3> = rgb
        .pixels()
        .map(|p| {
            let v = Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]));
            if v.is_finite() {
                v.max(Vec3::ZERO)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    Texture::new(name, w, h, texels).ok_or_else(|| fail(format!("texture has an empty size {w}x{h}")))
}
