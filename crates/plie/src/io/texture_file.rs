//! Texture images (issue 18): a PNG, JPEG or OpenEXR file decoded into a [`Texture`] of linear RGB
//! texels. 8- and 16-bit images are sRGB-encoded unless the scene says they are raw (linear) data;
//! float images (EXR) are linear. Reads are bounded ([`super::input`]) and so is the decoded size: at
//! most [`MAX_TEXTURE_SIDE`] texels a side and [`MAX_SCENE_TEXTURE_BYTES`] of texels per scene.
//!
//! A scene's loader reads its textures through one [`TextureFiles`], which decodes each file once
//! (by resolved path) however many materials use it, and keeps the texels in the width of the file
//! ([`Texels`]: 3 bytes a texel for 8-bit images, 6 for 16-bit, 12 for float ones).

use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use image::{ColorType, DynamicImage, ImageBuffer, ImageDecoder, ImageReader, Limits, Luma, LumaA, Rgb, Rgba};

use super::input::{read_bounded, MAX_INPUT_BYTES};
use super::parse_error;
use crate::error::Result;
use crate::scene::texture::{srgb_to_linear, Texels, Texture};

/// The largest texture side plie decodes.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// The most bytes of decoded texels one scene keeps, all its textures together (1 GiB: one 8-bit
/// texture of the largest side, 16384 x 16384, fits). A texel takes 3 bytes from an 8-bit image, 6
/// from a 16-bit one and 12 from a float one.
pub const MAX_SCENE_TEXTURE_BYTES: u64 = 1 << 30;

/// The most bytes the image decoder may allocate for one image.
const MAX_DECODE_BYTES: u64 = 2 << 30;

/// The textures of one scene being loaded: each file is read and decoded once, whatever the number
/// of materials using it, and the texels of all of them are bounded by [`MAX_SCENE_TEXTURE_BYTES`].
pub struct TextureFiles {
    /// Decoded files by (resolved path, sRGB).
    decoded: HashMap<(PathBuf, bool), Texture>,
    /// Bytes of texels decoded so far.
    bytes: u64,
    /// The most bytes of texels ([`MAX_SCENE_TEXTURE_BYTES`]).
    limit: u64,
}

impl Default for TextureFiles {
    fn default() -> Self {
        TextureFiles { decoded: HashMap::new(), bytes: 0, limit: MAX_SCENE_TEXTURE_BYTES }
    }
}

impl TextureFiles {
    /// The texture of the image file at `path` (`srgb`: decode 8/16-bit values with the sRGB curve),
    /// read and decoded the first time only. Errors name the file.
    pub fn load(&mut self, path: &Path, srgb: bool) -> Result<Texture> {
        let key = (path.canonicalize().unwrap_or_else(|_| path.to_path_buf()), srgb);
        if let Some(t) = self.decoded.get(&key) {
            return Ok(t.clone());
        }
        let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let t = self.decode(&name, bytes, srgb).map_err(|m| parse_error(path, None, m))?;
        self.decoded.insert(key, t.clone());
        Ok(t)
    }

    /// Decodes an image file's bytes (a glTF image in a buffer or data URI) as a texture named
    /// `name`; `srgb` as in [`TextureFiles::load`]. Not cached: the caller decodes each image once.
    pub fn decode(&mut self, name: &str, bytes: Vec<u8>, srgb: bool) -> std::result::Result<Texture, String> {
        let t = decode_within(name, bytes, srgb, (self.bytes, self.limit))?;
        self.bytes += t.texels.bytes() as u64;
        Ok(t)
    }
}

/// Loads the image at `path` as a texture; `srgb`: decode 8/16-bit values with the sRGB curve.
pub fn load_texture(path: &Path, srgb: bool) -> Result<Texture> {
    TextureFiles::default().load(path, srgb)
}

/// Decodes an image file's bytes as a texture named `name`; `srgb` as in [`load_texture`].
pub fn decode_texture(name: &str, bytes: Vec<u8>, srgb: bool) -> std::result::Result<Texture, String> {
    TextureFiles::default().decode(name, bytes, srgb)
}

/// Decodes a texture whose texels, with the `used` bytes of the scene's textures before it, may take at
/// most `limit` bytes (checked from the image's header, before decoding).
fn decode_within(
    name: &str,
    bytes: Vec<u8>,
    srgb: bool,
    (used, limit): (u64, u64),
) -> std::result::Result<Texture, String> {
    let mut reader =
        ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| format!("cannot read texture: {e}"))?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(MAX_DECODE_BYTES);
    reader.limits(limits.clone());
    let mut decoder = reader.into_decoder().map_err(|e| format!("cannot decode texture: {e}"))?;
    let (w, h) = decoder.dimensions();
    let per_texel = match decoder.color_type() {
        ColorType::L8 | ColorType::La8 | ColorType::Rgb8 | ColorType::Rgba8 => 3,
        ColorType::L16 | ColorType::La16 | ColorType::Rgb16 | ColorType::Rgba16 => 6,
        _ => 12,
    };
    let needed = w as u64 * h as u64 * per_texel;
    if used.saturating_add(needed) > limit {
        return Err(format!(
            "texture of {w}x{h} texels needs {needed} bytes decoded, the scene's textures before it {used}: \
             more than the limit of {limit} bytes of texels per scene"
        ));
    }
    // As `ImageReader::decode`: the image buffer counts against the decoder's allocation limit.
    limits.reserve(decoder.total_bytes()).map_err(|e| format!("cannot decode texture: {e}"))?;
    decoder.set_limits(limits).map_err(|e| format!("cannot decode texture: {e}"))?;
    let image = DynamicImage::from_decoder(decoder).map_err(|e| format!("cannot decode texture: {e}"))?;
    let texels = texels(image, srgb);
    Texture::from_texels(name, w, h, Arc::new(texels)).ok_or_else(|| format!("texture has an empty size {w}x{h}"))
}

/// The texels of a decoded image, in the width of its channels. Every texel reads the value the
/// image's conversion to `f32` RGB gives, sRGB-decoded if `srgb` for integer channels, negative and
/// non-finite texels made zero.
fn texels(image: DynamicImage, srgb: bool) -> Texels {
    use DynamicImage as D;
    let linear = |c: f32| if srgb { srgb_to_linear(c.clamp(0.0, 1.0)) } else { c };
    let sanitize = |v: f32| if v.is_finite() { v.max(0.0) } else { 0.0 };
    // The table of an integer image: the image crate's own conversion to f32 of every code, in an
    // image of the same layout and colour space (so the very arithmetic the whole image's would use).
    let space = image.color_space();
    let table = |mut codes: DynamicImage| -> Option<Vec<f32>> {
        codes.set_color_space(space).ok()?;
        Some(codes.into_rgb32f().pixels().map(|p| sanitize(linear(p[0]))).collect())
    };
    let codes8 = |x: u32| x as u8;
    let codes16 = |x: u32| x as u16;
    let table8 = match &image {
        D::ImageLuma8(_) => table(D::ImageLuma8(ImageBuffer::from_fn(256, 1, |x, _| Luma([codes8(x)])))),
        D::ImageLumaA8(_) => table(D::ImageLumaA8(ImageBuffer::from_fn(256, 1, |x, _| LumaA([codes8(x), 255])))),
        D::ImageRgb8(_) => table(D::ImageRgb8(ImageBuffer::from_fn(256, 1, |x, _| Rgb([codes8(x); 3])))),
        D::ImageRgba8(_) => {
            table(D::ImageRgba8(ImageBuffer::from_fn(256, 1, |x, _| Rgba([codes8(x), codes8(x), codes8(x), 255]))))
        }
        _ => None,
    };
    if let Some(table) = table8.and_then(|t| Box::<[f32; 256]>::try_from(t.into_boxed_slice()).ok()) {
        return Texels::Rgb8 { codes: image.into_rgb8().into_raw(), table };
    }
    let table16 = match &image {
        D::ImageLuma16(_) => table(D::ImageLuma16(ImageBuffer::from_fn(65536, 1, |x, _| Luma([codes16(x)])))),
        D::ImageLumaA16(_) => {
            table(D::ImageLumaA16(ImageBuffer::from_fn(65536, 1, |x, _| LumaA([codes16(x), u16::MAX]))))
        }
        D::ImageRgb16(_) => table(D::ImageRgb16(ImageBuffer::from_fn(65536, 1, |x, _| Rgb([codes16(x); 3])))),
        D::ImageRgba16(_) => table(D::ImageRgba16(ImageBuffer::from_fn(65536, 1, |x, _| {
            Rgba([codes16(x), codes16(x), codes16(x), u16::MAX])
        }))),
        _ => None,
    };
    if let Some(table) = table16.and_then(|t| Box::<[f32; 65536]>::try_from(t.into_boxed_slice()).ok()) {
        return Texels::Rgb16 { codes: image.into_rgb16().into_raw(), table };
    }
    let float = matches!(image, D::ImageRgb32F(_) | D::ImageRgba32F(_));
    let decode = |c: f32| if float { c } else { linear(c) };
    let texels = image
        .into_rgb32f()
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
    Texels::F32(texels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::ImageFormat;

    /// The decoding before texels were stored narrow: every texel converted to f32 RGB.
    fn reference(bytes: &[u8], srgb: bool) -> Vec<Vec3> {
        let image = ImageReader::new(Cursor::new(bytes)).with_guessed_format().unwrap().decode().unwrap();
        let float = matches!(image, DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_));
        let decode = |c: f32| if srgb && !float { srgb_to_linear(c.clamp(0.0, 1.0)) } else { c };
        let rgb = image.into_rgb32f();
        rgb.pixels()
            .map(|p| {
                let v = Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]));
                if v.is_finite() {
                    v.max(Vec3::ZERO)
                } else {
                    Vec3::ZERO
                }
            })
            .collect()
    }

    fn encode(image: DynamicImage, format: ImageFormat) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        image.write_to(&mut out, format).unwrap();
        out.into_inner()
    }

    #[test]
    fn narrow_texels_read_exactly_what_f32_texels_did() {
        let (w, h) = (61u32, 37u32);
        let c = |x: u32, y: u32, k: u32| (x * 37 + y * 11 + k * 71) as u64;
        let images = [
            ("L8", DynamicImage::ImageLuma8(ImageBuffer::from_fn(w, h, |x, y| Luma([c(x, y, 0) as u8])))),
            ("La8", DynamicImage::ImageLumaA8(ImageBuffer::from_fn(w, h, |x, y| LumaA([c(x, y, 0) as u8, 7])))),
            (
                "Rgb8",
                DynamicImage::ImageRgb8(ImageBuffer::from_fn(w, h, |x, y| Rgb([0, 1, 2].map(|k| c(x, y, k) as u8)))),
            ),
            (
                "Rgba8",
                DynamicImage::ImageRgba8(ImageBuffer::from_fn(w, h, |x, y| {
                    Rgba([0, 1, 2, 3].map(|k| c(x, y, k) as u8))
                })),
            ),
            ("L16", DynamicImage::ImageLuma16(ImageBuffer::from_fn(w, h, |x, y| Luma([(c(x, y, 0) * 977) as u16])))),
            (
                "Rgb16",
                DynamicImage::ImageRgb16(ImageBuffer::from_fn(w, h, |x, y| {
                    Rgb([0, 1, 2].map(|k| (c(x, y, k) * 1013) as u16))
                })),
            ),
            (
                "Rgba16",
                DynamicImage::ImageRgba16(ImageBuffer::from_fn(w, h, |x, y| {
                    Rgba([0, 1, 2, 3].map(|k| (c(x, y, k) * 1013) as u16))
                })),
            ),
        ];
        for (kind, image) in images {
            let png = encode(image, ImageFormat::Png);
            for srgb in [true, false] {
                let t = decode_texture(kind, png.clone(), srgb).unwrap();
                assert!(!matches!(*t.texels, Texels::F32(_)), "{kind} is stored narrow");
                let got: Vec<Vec3> = t.texels.iter().collect();
                let want = reference(&png, srgb);
                let same = got
                    .iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits));
                assert!(same && got.len() == want.len(), "{kind} srgb {srgb}");
            }
        }
        let float = DynamicImage::ImageRgb32F(ImageBuffer::from_fn(w, h, |x, y| {
            Rgb([0, 1, 2].map(|k| c(x, y, k) as f32 / 100.0 - 0.5))
        }));
        let exr = encode(float, ImageFormat::OpenExr);
        let t = decode_texture("f", exr.clone(), true).unwrap();
        assert!(matches!(*t.texels, Texels::F32(_)), "float images stay f32");
        assert_eq!(t.texels.iter().collect::<Vec<_>>(), reference(&exr, true));
    }

    #[test]
    fn files_are_decoded_once_and_bounded_per_scene() {
        let dir = tempfile::tempdir().unwrap();
        let png = encode(DynamicImage::ImageRgb8(ImageBuffer::new(64, 32)), ImageFormat::Png);
        for name in ["a.png", "b.png"] {
            std::fs::write(dir.path().join(name), &png).unwrap();
        }
        let one = 3 * 64 * 32 + 1024;
        let mut files = TextureFiles { limit: one + 100, ..Default::default() };
        let a = files.load(&dir.path().join("a.png"), true).unwrap();
        let again = files.load(&dir.path().join(".").join("a.png"), true).unwrap();
        assert!(Arc::ptr_eq(&a.texels, &again.texels), "one decode for one file");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("a.png", dir.path().join("link.png")).unwrap();
            let linked = files.load(&dir.path().join("link.png"), true).unwrap();
            assert!(Arc::ptr_eq(&a.texels, &linked.texels), "one decode through a link");
        }
        assert_eq!(files.bytes, one, "3 bytes a texel and the table");
        let raw = files.load(&dir.path().join("a.png"), false).unwrap_err().to_string();
        assert!(raw.contains("limit of"), "raw values are another decode: {raw}");
        let e = files.load(&dir.path().join("b.png"), true).unwrap_err().to_string();
        assert!(e.contains("b.png") && e.contains("64x32") && e.contains("limit of"), "{e}");
        assert!(!e.contains('\n'), "one line: {e}");
        assert!(
            MAX_SCENE_TEXTURE_BYTES >= 3 * (MAX_TEXTURE_SIDE as u64).pow(2) + 1024,
            "the largest 8-bit texture fits"
        );
    }
}
