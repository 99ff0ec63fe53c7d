//! Diffuse-reflectance textures (issue 18; SPEC §1 extends the Lambertian material): a bitmap of linear
//! RGB texels looked up at a hit's texture coordinates with bilinear (or nearest) filtering and a wrap
//! mode. The reflectance at a hit is [`Scene::albedo_at`]: the material's albedo times the texture's
//! value there. Only shading reads textures; the P-LIE construction and every visibility mode ignore
//! them, so images stay bit-identical across exact visibility modes.
//!
//! Texels are stored as narrow as the image file they come from ([`Texels`]): 8- and 16-bit channels
//! as they are (3 or 6 bytes a texel) with a table of the linear value of each code, float channels
//! (OpenEXR) as `f32` (12 bytes a texel, for exactness). A texel reads the same `f32` values either
//! way, so the storage does not change an image.
//!
//! Texture coordinates follow Mitsuba and glTF: `(0, 0)` is the top-left corner of the image, `v`
//! grows downward. Loaders whose format puts `v = 0` at the bottom (OBJ) flip `v` when they read it.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::{Scene, TriId};

/// How texture coordinates outside `[0, 1]` are folded back.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Repeat the image (the default of Mitsuba and glTF).
    #[default]
    Repeat,
    /// Repeat it mirrored every other time.
    Mirror,
    /// Clamp to the edge texel.
    Clamp,
}

/// How texels are interpolated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// Bilinear interpolation of the four nearest texels (texel centres at half-integers).
    #[default]
    Bilinear,
    /// The nearest texel.
    Nearest,
}

/// The texels of a texture, row-major, top row first, in the width of the file they come from.
/// [`Texels::get`] gives every texel as linear RGB.
#[derive(Clone, PartialEq)]
pub enum Texels {
    /// 8 bits per channel (`r, g, b` per texel) and the linear value of each of the 256 codes.
    Rgb8 {
        /// The codes, three per texel; shared by the texels of one file read as sRGB colour and as
        /// raw values, which differ in their table only.
        codes: Arc<Vec<u8>>,
        /// The linear value of each code.
        table: Box<[f32; 256]>,
    },
    /// 16 bits per channel (`r, g, b` per texel) and the linear value of each of the 65,536 codes.
    Rgb16 {
        /// The codes, three per texel; shared as for [`Texels::Rgb8`].
        codes: Arc<Vec<u16>>,
        /// The linear value of each code.
        table: Box<[f32; 65536]>,
    },
    /// Linear RGB floats (float images, and textures made in code).
    F32(Vec<Vec3>),
}

impl Texels {
    /// Number of texels.
    pub fn len(&self) -> usize {
        match self {
            Texels::Rgb8 { codes, .. } => codes.len() / 3,
            Texels::Rgb16 { codes, .. } => codes.len() / 3,
            Texels::F32(v) => v.len(),
        }
    }

    /// True if there are no texels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Texel `i` as linear RGB. Panics if `i` is out of range.
    #[inline]
    pub fn get(&self, i: usize) -> Vec3 {
        match self {
            Texels::Rgb8 { codes, table } => {
                let c = &codes[3 * i..3 * i + 3];
                Vec3::new(table[c[0] as usize], table[c[1] as usize], table[c[2] as usize])
            }
            Texels::Rgb16 { codes, table } => {
                let c = &codes[3 * i..3 * i + 3];
                Vec3::new(table[c[0] as usize], table[c[1] as usize], table[c[2] as usize])
            }
            Texels::F32(v) => v[i],
        }
    }

    /// Every texel as linear RGB, in order.
    pub fn iter(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    /// Bytes held, tables included (and the codes, even where shared with other texels).
    pub fn bytes(&self) -> usize {
        match self {
            Texels::Rgb8 { codes, .. } => codes.len() + 256 * 4,
            Texels::Rgb16 { codes, .. } => codes.len() * 2 + 65536 * 4,
            Texels::F32(v) => v.len() * 12,
        }
    }
}

impl std::fmt::Debug for Texels {
    /// The kind and size only (a texture has millions of texels).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self {
            Texels::Rgb8 { .. } => "Rgb8",
            Texels::Rgb16 { .. } => "Rgb16",
            Texels::F32(_) => "F32",
        };
        write!(f, "Texels::{kind}({} texels)", self.len())
    }
}

/// A bitmap texture of linear RGB texels.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Name (the file it came from).
    pub name: String,
    /// Width in texels (at least 1).
    pub width: u32,
    /// Height in texels (at least 1).
    pub height: u32,
    /// The texels, row-major, top row first; shared by the textures of one file (materials that use
    /// it with different wrap modes or coordinate transforms).
    pub texels: Arc<Texels>,
    /// Wrap mode in `u` and `v`.
    pub wrap: [Wrap; 2],
    /// Filter.
    pub filter: Filter,
    /// Affine map applied to texture coordinates before the lookup: `uv * scale + offset`.
    pub scale: Vec2,
    /// See [`Texture::scale`].
    pub offset: Vec2,
}

impl Texture {
    /// A texture of `width x height` linear texels, repeating, bilinear, no coordinate transform.
    /// `None` if the size does not match the texels or is zero.
    pub fn new(name: &str, width: u32, height: u32, texels: Vec<Vec3>) -> Option<Texture> {
        Texture::from_texels(name, width, height, Arc::new(Texels::F32(texels)))
    }

    /// [`Texture::new`] with texels in any storage.
    pub fn from_texels(name: &str, width: u32, height: u32, texels: Arc<Texels>) -> Option<Texture> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return None;
        }
        Some(Texture {
            name: name.to_string(),
            width,
            height,
            texels,
            wrap: [Wrap::Repeat; 2],
            filter: Filter::Bilinear,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
        })
    }

    /// The filtered value at texture coordinates `uv`. Never panics: non-finite coordinates read
    /// texel (0, 0).
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let uv = uv * self.scale + self.offset;
        let (w, h) = (self.width as i64, self.height as i64);
        let p = Vec2::new(uv.x * w as f32, uv.y * h as f32);
        let p = if p.is_finite() { p } else { Vec2::ZERO };
        match self.filter {
            Filter::Nearest => {
                let x = wrap(self.wrap[0], p.x.floor() as i64, w);
                let y = wrap(self.wrap[1], p.y.floor() as i64, h);
                self.texel(x, y)
            }
            Filter::Bilinear => {
                let q = p - Vec2::splat(0.5);
                let f = q.floor();
                let t = q - f;
                let (x0, y0) = (f.x as i64, f.y as i64);
                let xs = [wrap(self.wrap[0], x0, w), wrap(self.wrap[0], x0.saturating_add(1), w)];
                let ys = [wrap(self.wrap[1], y0, h), wrap(self.wrap[1], y0.saturating_add(1), h)];
                let top = self.texel(xs[0], ys[0]) * (1.0 - t.x) + self.texel(xs[1], ys[0]) * t.x;
                let bottom = self.texel(xs[0], ys[1]) * (1.0 - t.x) + self.texel(xs[1], ys[1]) * t.x;
                top * (1.0 - t.y) + bottom * t.y
            }
        }
    }

    /// The texel in column `x`, row `y` (row 0 at the top) as linear RGB.
    #[inline]
    pub fn texel(&self, x: usize, y: usize) -> Vec3 {
        self.texels.get(y * self.width as usize + x)
    }

    /// The mean of all texels (what a renderer without texture coordinates would show).
    pub fn mean(&self) -> Vec3 {
        self.texels.iter().sum::<Vec3>() / self.texels.len() as f32
    }
}

/// Folds the texel index `i` into `[0, n)` by `mode`.
fn wrap(mode: Wrap, i: i64, n: i64) -> usize {
    let r = match mode {
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Mirror => {
            let k = i.rem_euclid(2 * n);
            if k < n {
                k
            } else {
                2 * n - 1 - k
            }
        }
    };
    r as usize
}

/// The sRGB transfer function's inverse: an encoded value in `[0, 1]` to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Scene {
    /// The diffuse reflectance at `point` on triangle `tri`: the material's albedo, times its texture
    /// at the point's interpolated texture coordinates when it has a texture and the triangle has
    /// coordinates. The one place shading reads a reflectance.
    #[inline]
    pub fn albedo_at(&self, tri: TriId, point: Vec3) -> Vec3 {
        let m = self.material_of(tri);
        let (Some(tex), Some(uv)) = (m.texture, self.tri_uv.get(tri.idx())) else {
            return m.albedo;
        };
        let t = &self.triangles[tri.idx()];
        let (e1, e2, d) = (t.v[1] - t.v[0], t.v[2] - t.v[0], point - t.v[0]);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let det = d11 * d22 - d12 * d12;
        let (b1, b2) = if det > 0.0 { ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det) } else { (0.0, 0.0) };
        let st = uv[0] * (1.0 - b1 - b2) + uv[1] * b1 + uv[2] * b2;
        m.albedo * self.textures[tex.idx()].sample(st)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(filter: Filter, wrap_mode: Wrap) -> Texture {
        // 2 x 2: black, white / red, green (top row first).
        let texels = vec![Vec3::ZERO, Vec3::ONE, Vec3::X, Vec3::Y];
        Texture { filter, wrap: [wrap_mode; 2], ..Texture::new("t", 2, 2, texels).unwrap() }
    }

    #[test]
    fn nearest_reads_the_texel_under_the_coordinate() {
        let t = tex(Filter::Nearest, Wrap::Repeat);
        assert_eq!(t.sample(Vec2::new(0.1, 0.1)), Vec3::ZERO, "top left");
        assert_eq!(t.sample(Vec2::new(0.9, 0.1)), Vec3::ONE, "top right");
        assert_eq!(t.sample(Vec2::new(0.1, 0.9)), Vec3::X, "bottom left: v grows downward");
        assert_eq!(t.sample(Vec2::new(1.1, 1.9)), Vec3::X, "repeat");
        assert_eq!(t.sample(Vec2::new(f32::NAN, 0.0)), Vec3::ZERO, "NaN does not panic");
    }

    #[test]
    fn bilinear_interpolates_between_texel_centres() {
        let t = tex(Filter::Bilinear, Wrap::Clamp);
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)), Vec3::ZERO, "a texel centre is exact");
        assert_eq!(t.sample(Vec2::new(0.5, 0.25)), Vec3::splat(0.5), "halfway between black and white");
        assert_eq!(t.sample(Vec2::new(0.0, 0.0)), Vec3::ZERO, "clamped at the edge");
        let r = tex(Filter::Bilinear, Wrap::Repeat);
        assert_eq!(r.sample(Vec2::new(0.0, 0.25)), Vec3::splat(0.5), "repeat mixes the far edge");
    }

    #[test]
    fn wrap_modes() {
        assert_eq!((-1..5).map(|i| wrap(Wrap::Repeat, i, 2)).collect::<Vec<_>>(), [1, 0, 1, 0, 1, 0]);
        assert_eq!((-1..5).map(|i| wrap(Wrap::Mirror, i, 2)).collect::<Vec<_>>(), [0, 0, 1, 1, 0, 0]);
        assert_eq!((-1..5).map(|i| wrap(Wrap::Clamp, i, 2)).collect::<Vec<_>>(), [0, 0, 1, 1, 1, 1]);
        assert_eq!(wrap(Wrap::Mirror, i64::MIN, 3), wrap(Wrap::Mirror, i64::MIN, 3));
    }

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.21404).abs() < 1e-4);
    }
}
