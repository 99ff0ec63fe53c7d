//! Texture images (issue 18): a PNG, JPEG or OpenEXR file decoded into a [`Texture`] of linear RGB
//! texels. 8- and 16-bit images are sRGB-encoded unless the scene says they are raw (linear) data;
//! float images (EXR) are linear. Reads are bounded ([`super::input`]) and so is the decoded size: at
//! most [`MAX_TEXTURE_SIDE`] texels a side and [`MAX_SCENE_TEXTURE_BYTES`] of texels per scene.
//!
//! A scene's loader reads its textures through one [`TextureFiles`], which reads and decodes each
//! file once (by resolved path) however many materials use it, as sRGB colour, as raw values or both:
//! one decode gives both readings. The texels keep the width of the file ([`Texels`]: 3 bytes a texel
//! for 8-bit images, 6 for 16-bit, 12 for float ones); the two readings of an 8- or 16-bit file share
//! its codes (an `Arc<Vec>`, so the RGB buffer made from the decoded image is kept without a copy) and
//! differ in their tables, and those of a float file are the same texels.

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
/// from a 16-bit one and 12 from a float one; an 8- or 16-bit file also keeps two tables of the
/// linear value of each code (sRGB colour and raw values), of 1 KiB or 256 KiB each.
pub const MAX_SCENE_TEXTURE_BYTES: u64 = 1 << 30;

/// The most bytes the image decoder may allocate for one image.
const MAX_DECODE_BYTES: u64 = 2 << 30;

/// The textures of one scene being loaded: each file is read and decoded once, whatever the number
/// of materials using it and whether they read it as sRGB colour or raw values, and the texels of all
/// of them are bounded by [`MAX_SCENE_TEXTURE_BYTES`].
pub struct TextureFiles {
    /// Decoded files by resolved path.
    decoded: HashMap<PathBuf, Views>,
    /// Bytes of texels decoded so far.
    bytes: u64,
    /// The most bytes of texels ([`MAX_SCENE_TEXTURE_BYTES`]).
    limit: u64,
    /// Images decoded (or tried) so far ([`TextureFiles::decodes`]).
    decodes: usize,
}

impl Default for TextureFiles {
    fn default() -> Self {
        TextureFiles { decoded: HashMap::new(), bytes: 0, limit: MAX_SCENE_TEXTURE_BYTES, decodes: 0 }
    }
}

/// One decoded image read both ways: the same texture but for its texels.
struct Views {
    /// 8- and 16-bit values as they are (raw data: Mitsuba's `raw`, or `gamma` 1).
    raw: Texture,
    /// 8- and 16-bit values through the sRGB curve (colour).
    srgb: Texture,
}

impl Views {
    /// The reading `srgb` asks for.
    fn get(&self, srgb: bool) -> &Texture {
        if srgb {
            &self.srgb
        } else {
            &self.raw
        }
    }

    /// Bytes held by both: shared codes or texels once.
    fn bytes(&self) -> u64 {
        let (raw, srgb) = (&self.raw.texels, &self.srgb.texels);
        let shared = match (&**raw, &**srgb) {
            _ if Arc::ptr_eq(raw, srgb) => srgb.bytes(),
            (Texels::Rgb8 { codes: a, .. }, Texels::Rgb8 { codes: b, .. }) if Arc::ptr_eq(a, b) => a.len(),
            (Texels::Rgb16 { codes: a, .. }, Texels::Rgb16 { codes: b, .. }) if Arc::ptr_eq(a, b) => 2 * a.len(),
            _ => 0,
        };
        (raw.bytes() + srgb.bytes() - shared) as u64
    }
}

impl TextureFiles {
    /// The texture of the image file at `path` (`srgb`: decode 8/16-bit values with the sRGB curve),
    /// read and decoded the first time the file is asked for, either way. Errors name the file.
    pub fn load(&mut self, path: &Path, srgb: bool) -> Result<Texture> {
        let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if let Some(views) = self.decoded.get(&key) {
            return Ok(views.get(srgb).clone());
        }
        let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let views = self.decode_views(&name, bytes, Views::bytes).map_err(|m| parse_error(path, None, m))?;
        let t = views.get(srgb).clone();
        self.decoded.insert(key, views);
        Ok(t)
    }

    /// Decodes an image file's bytes (a glTF image in a buffer or data URI) as a texture named
    /// `name`; `srgb` as in [`TextureFiles::load`]. Not cached: the caller decodes each image once.
    pub fn decode(&mut self, name: &str, bytes: Vec<u8>, srgb: bool) -> std::result::Result<Texture, String> {
        let views = self.decode_views(name, bytes, |v| v.get(srgb).texels.bytes() as u64)?;
        Ok(views.get(srgb).clone())
    }

    /// Images decoded (or tried) so far: one per file whichever ways it is read, one per
    /// [`TextureFiles::decode`].
    pub fn decodes(&self) -> usize {
        self.decodes
    }

    /// Decodes an image file's bytes both ways and counts the `kept` bytes of them against the limit.
    fn decode_views(
        &mut self,
        name: &str,
        bytes: Vec<u8>,
        kept: impl FnOnce(&Views) -> u64,
    ) -> std::result::Result<Views, String> {
        self.decodes += 1;
        let views = decode_within(name, bytes, (self.bytes, self.limit))?;
        let (w, h, needed) = (views.raw.width, views.raw.height, kept(&views));
        if self.bytes.saturating_add(needed) > self.limit {
            return Err(over_limit((w, h), needed, (self.bytes, self.limit)));
        }
        self.bytes += needed;
        Ok(views)
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

/// The error of a texture of `w x h` texels needing `needed` bytes when the scene's textures before it
/// take `used` of at most `limit`.
fn over_limit((w, h): (u32, u32), needed: u64, (used, limit): (u64, u64)) -> String {
    format!(
        "texture of {w}x{h} texels needs {needed} bytes decoded, the scene's textures before it {used}: \
         more than the limit of {limit} bytes of texels per scene"
    )
}

/// Decodes a texture whose texels, with the `used` bytes of the scene's textures before it, may take at
/// most `limit` bytes (checked from the image's header, before decoding: the codes and both tables).
fn decode_within(name: &str, bytes: Vec<u8>, (used, limit): (u64, u64)) -> std::result::Result<Views, String> {
    let mut reader =
        ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| format!("cannot read texture: {e}"))?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(MAX_DECODE_BYTES);
    reader.limits(limits.clone());
    let mut decoder = reader.into_decoder().map_err(|e| format!("cannot decode texture: {e}"))?;
    let (w, h) = decoder.dimensions();
    let (per_texel, tables) = match decoder.color_type() {
        ColorType::L8 | ColorType::La8 | ColorType::Rgb8 | ColorType::Rgba8 => (3, 2 * 256 * 4),
        ColorType::L16 | ColorType::La16 | ColorType::Rgb16 | ColorType::Rgba16 => (6, 2 * 65536 * 4),
        _ => (12, 0),
    };
    let needed = w as u64 * h as u64 * per_texel + tables;
    if used.saturating_add(needed) > limit {
        return Err(over_limit((w, h), needed, (used, limit)));
    }
    // As `ImageReader::decode`: the image buffer counts against the decoder's allocation limit.
    limits.reserve(decoder.total_bytes()).map_err(|e| format!("cannot decode texture: {e}"))?;
    decoder.set_limits(limits).map_err(|e| format!("cannot decode texture: {e}"))?;
    let image = DynamicImage::from_decoder(decoder).map_err(|e| format!("cannot decode texture: {e}"))?;
    let [raw, srgb] = texels(image)
        .map(|t| Texture::from_texels(name, w, h, t).ok_or_else(|| format!("texture has an empty size {w}x{h}")));
    Ok(Views { raw: raw?, srgb: srgb? })
}

/// A channel value of an integer image read as raw data (`srgb` false) or sRGB colour.
fn curve(srgb: bool, c: f32) -> f32 {
    if srgb {
        srgb_to_linear(c.clamp(0.0, 1.0))
    } else {
        c
    }
}

/// A table value, negative and non-finite values made zero.
fn sanitize(v: f32) -> f32 {
    if v.is_finite() {
        v.max(0.0)
    } else {
        0.0
    }
}

/// The tables of both readings (raw, sRGB) from the `f32` value of each of `N` codes.
fn tables<const N: usize>(values: Option<Vec<f32>>) -> Option<[Box<[f32; N]>; 2]> {
    let values = values?;
    let table = |srgb: bool| {
        let t: Box<[f32]> = values.iter().map(|&v| sanitize(curve(srgb, v))).collect();
        Box::<[f32; N]>::try_from(t).ok()
    };
    Some([table(false)?, table(true)?])
}

/// The texels of a decoded image read as raw values and as sRGB colour, in the width of its channels.
/// Every texel reads the value the image's conversion to `f32` RGB gives, sRGB-decoded in the second
/// reading for integer channels, negative and non-finite texels made zero. The readings share the
/// codes of an integer image (each with its table) and are the same texels for a float one.
fn texels(image: DynamicImage) -> [Arc<Texels>; 2] {
    use DynamicImage as D;
    // The f32 value of every code: the image crate's own conversion, in an image of the same layout
    // and colour space (so the very arithmetic the whole image's would use).
    let space = image.color_space();
    let values = |mut codes: DynamicImage| -> Option<Vec<f32>> {
        codes.set_color_space(space).ok()?;
        Some(codes.into_rgb32f().pixels().map(|p| p[0]).collect())
    };
    let codes8 = |x: u32| x as u8;
    let codes16 = |x: u32| x as u16;
    let values8 = match &image {
        D::ImageLuma8(_) => values(D::ImageLuma8(ImageBuffer::from_fn(256, 1, |x, _| Luma([codes8(x)])))),
        D::ImageLumaA8(_) => values(D::ImageLumaA8(ImageBuffer::from_fn(256, 1, |x, _| LumaA([codes8(x), 255])))),
        D::ImageRgb8(_) => values(D::ImageRgb8(ImageBuffer::from_fn(256, 1, |x, _| Rgb([codes8(x); 3])))),
        D::ImageRgba8(_) => {
            values(D::ImageRgba8(ImageBuffer::from_fn(256, 1, |x, _| Rgba([codes8(x), codes8(x), codes8(x), 255]))))
        }
        _ => None,
    };
    if let Some(tables) = tables::<256>(values8) {
        let codes = Arc::new(image.into_rgb8().into_raw());
        return tables.map(|table| Arc::new(Texels::Rgb8 { codes: codes.clone(), table }));
    }
    let values16 = match &image {
        D::ImageLuma16(_) => values(D::ImageLuma16(ImageBuffer::from_fn(65536, 1, |x, _| Luma([codes16(x)])))),
        D::ImageLumaA16(_) => {
            values(D::ImageLumaA16(ImageBuffer::from_fn(65536, 1, |x, _| LumaA([codes16(x), u16::MAX]))))
        }
        D::ImageRgb16(_) => values(D::ImageRgb16(ImageBuffer::from_fn(65536, 1, |x, _| Rgb([codes16(x); 3])))),
        D::ImageRgba16(_) => values(D::ImageRgba16(ImageBuffer::from_fn(65536, 1, |x, _| {
            Rgba([codes16(x), codes16(x), codes16(x), u16::MAX])
        }))),
        _ => None,
    };
    if let Some(tables) = tables::<65536>(values16) {
        let codes = Arc::new(image.into_rgb16().into_raw());
        return tables.map(|table| Arc::new(Texels::Rgb16 { codes: codes.clone(), table }));
    }
    let float = matches!(image, D::ImageRgb32F(_) | D::ImageRgba32F(_));
    let rgb = image.into_rgb32f();
    let reading = |srgb: bool| {
        let decode = |c: f32| if float { c } else { curve(srgb, c) };
        let texels = rgb
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
        Arc::new(Texels::F32(texels))
    };
    if float {
        let t = reading(false);
        [t.clone(), t]
    } else {
        // Integer channels without a table of their codes (a colour space the codes' image refused).
        [reading(false), reading(true)]
    }
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
        let one = 3 * 64 * 32 + 2 * 1024;
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
        assert_eq!(files.bytes, one, "3 bytes a texel and a table for each reading");
        let raw = files.load(&dir.path().join("a.png"), false).unwrap();
        assert!(raw.texels != a.texels, "another table");
        assert_eq!((files.bytes, files.decodes()), (one, 1), "raw values come from the same decode");
        let e = files.load(&dir.path().join("b.png"), true).unwrap_err().to_string();
        assert!(e.contains("b.png") && e.contains("64x32") && e.contains("limit of"), "{e}");
        assert!(!e.contains('\n'), "one line: {e}");
        assert!(
            MAX_SCENE_TEXTURE_BYTES >= 3 * (MAX_TEXTURE_SIDE as u64).pow(2) + 2 * 1024,
            "the largest 8-bit texture fits"
        );
    }
    /// Issue: a file read both as raw values and as sRGB colour was decoded twice.
    #[test]
    fn a_file_read_raw_and_as_srgb_is_decoded_once_and_reads_as_before() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (23u32, 19u32);
        let n = (w * h) as u64;
        let c = |x: u32, y: u32, k: u32| x * 37 + y * 11 + k * 71;
        let rgb8 = DynamicImage::ImageRgb8(ImageBuffer::from_fn(w, h, |x, y| Rgb([0, 1, 2].map(|k| c(x, y, k) as u8))));
        let la16 = DynamicImage::ImageLumaA16(ImageBuffer::from_fn(w, h, |x, y| LumaA([(c(x, y, 0) * 977) as u16, 9])));
        let float = DynamicImage::ImageRgba32F(ImageBuffer::from_fn(w, h, |x, y| {
            Rgba([0, 1, 2, 3].map(|k| c(x, y, k) as f32 / 100.0 - 0.5))
        }));
        // Each file with the bytes it keeps: the codes once and a table per reading, or the texels once.
        let files = [
            ("rgb8.png", encode(rgb8, ImageFormat::Png), 3 * n + 2 * 256 * 4),
            ("la16.png", encode(la16, ImageFormat::Png), 6 * n + 2 * 65536 * 4),
            ("float.exr", encode(float, ImageFormat::OpenExr), 12 * n),
        ];
        let bits = |v: Vec<Vec3>| -> Vec<[u32; 3]> { v.iter().map(|v| v.to_array().map(f32::to_bits)).collect() };
        let mut cache = TextureFiles::default();
        let mut bytes = 0;
        for (i, (name, file, kept)) in files.iter().enumerate() {
            let path = dir.path().join(name);
            std::fs::write(&path, file).unwrap();
            let first = i % 2 == 0;
            let one = cache.load(&path, first).unwrap();
            let other = cache.load(&path, !first).unwrap();
            let (srgb, raw) = if first { (one, other) } else { (other, one) };
            assert_eq!(cache.decodes(), i + 1, "{name}: one decode for both readings");
            for (t, is_srgb) in [(&srgb, true), (&raw, false)] {
                let got = bits(t.texels.iter().collect());
                assert!(got == bits(reference(file, is_srgb)), "{name} srgb {is_srgb}: the texels of before");
                let again = cache.load(&path, is_srgb).unwrap();
                assert!(Arc::ptr_eq(&t.texels, &again.texels), "{name} srgb {is_srgb}: cached");
            }
            let shared = match (&*raw.texels, &*srgb.texels) {
                (Texels::Rgb8 { codes: a, .. }, Texels::Rgb8 { codes: b, .. }) => Arc::ptr_eq(a, b),
                (Texels::Rgb16 { codes: a, .. }, Texels::Rgb16 { codes: b, .. }) => Arc::ptr_eq(a, b),
                (Texels::F32(_), Texels::F32(_)) => Arc::ptr_eq(&raw.texels, &srgb.texels),
                _ => false,
            };
            assert!(shared, "{name}: the readings share the codes (or the float texels)");
            bytes += kept;
            assert_eq!(cache.bytes, bytes, "{name}: the codes or texels counted once");
        }
        assert_eq!(cache.decodes(), files.len());
    }
}
