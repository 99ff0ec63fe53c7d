//! [`Scene`] and its [`SceneBuilder`]. The builder is how built-in scenes and file loaders make a
//! scene; `build` validates everything once (finite coordinates, lights, camera). Degenerate triangles
//! (zero area: they cannot block or be seen) are dropped as they are added, so they take no memory,
//! and counted in [`Scene::degenerate_skipped`] so the caller can warn; the builder's ids still count
//! them ([`Dropped`]), so lights and messages name triangles in the order they were given. `build`
//! moves the builder's arrays into the scene: a scene at the loaders' limit is never held twice.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::dropped::Dropped;
use super::{Camera, Light, LightId, Material, MaterialId, Texture, TextureId, TriId};
use crate::error::{Error, Result};
use crate::geometry::{Aabb, Triangle};

/// A validated scene: flat arrays indexed by [`TriId`], [`MaterialId`] and [`LightId`].
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name (built-in name or file stem).
    pub name: String,
    /// All triangles, lights' triangles included.
    pub triangles: Vec<Triangle>,
    /// Material of each triangle.
    pub tri_material: Vec<MaterialId>,
    /// The light each triangle belongs to, if any.
    pub tri_light: Vec<Option<LightId>>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Lights (at least one).
    pub lights: Vec<Light>,
    /// The scene's own camera, if it has one.
    pub camera: Option<Camera>,
    /// The scene's own image size (width, height), if the file gives one (a Mitsuba film).
    pub image_size: Option<(u32, u32)>,
    /// Textures, indexed by [`TextureId`] ([`Material::texture`]).
    pub textures: Vec<Texture>,
    /// Texture coordinates of each triangle's vertices, per triangle (zeros for triangles without);
    /// empty when no triangle has any, and then [`Scene::albedo_at`] ignores textures.
    pub tri_uv: Vec<[Vec2; 3]>,
    /// Bounding box of all triangles.
    pub bounds: Aabb,
    /// Degenerate (zero-area) triangles dropped while building.
    pub degenerate_skipped: usize,
    /// What a scene file holds that plie reads but does not render (specular colours, textures,
    /// metallic-roughness), one sentence each, for the caller to warn about; empty for built-ins.
    pub warnings: Vec<String>,
    /// Every file the loader read, as it named them: the scene file first, then the files it names
    /// (MTL libraries, Mitsuba includes, meshes, textures, glTF buffers and images), each once; empty
    /// for built-ins. A command must not write over any of them.
    pub sources: Vec<PathBuf>,
}

impl Scene {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The triangle with this id.
    #[inline]
    pub fn triangle(&self, t: TriId) -> &Triangle {
        &self.triangles[t.idx()]
    }

    /// The material of a triangle.
    #[inline]
    pub fn material_of(&self, t: TriId) -> &Material {
        &self.materials[self.tri_material[t.idx()].idx()]
    }

    /// The scene's camera, or a default one framing the scene. The default looks from the side most
    /// surfaces face (area-weighted front normals, horizontal part), so an open room is seen through
    /// its open side; where no side dominates, from -z.
    pub fn camera_or_default(&self) -> Camera {
        self.camera.unwrap_or_else(|| {
            let (mut sum, mut area) = (Vec3::ZERO, 0.0);
            for (t, l) in self.triangles.iter().zip(&self.tri_light) {
                if l.is_none() {
                    let c = t.cross();
                    sum += c;
                    area += c.length();
                }
            }
            let horizontal = Vec3::new(sum.x, 0.0, sum.z);
            let from = if horizontal.length() > 0.05 * area { horizontal } else { -Vec3::Z };
            Camera::framing(&self.bounds, 40.0, from)
        })
    }

    /// A length scale for tolerances: the largest extent of the scene's bounding box.
    pub fn scale(&self) -> f32 {
        self.bounds.size().max_element()
    }

    /// The scene's absolute tolerance ([`crate::geometry::tolerance_of`]): `1e-5` of its size, or
    /// for a scene far from the origin, the rounding of its coordinates to `f32` with room to spare.
    pub fn tolerance(&self) -> f32 {
        crate::geometry::tolerance_of(self.scale(), self.bounds.largest_abs())
    }
}

/// A light before validation: its polygon, radiance and triangles.
#[derive(Clone, Debug)]
struct PendingLight {
    polygon: Vec<Vec3>,
    radiance: Vec3,
    triangles: Vec<u32>,
}

/// Builds a [`Scene`] triangle by triangle.
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    name: String,
    /// The triangles kept: all but the degenerate ones ([`SceneBuilder::dropped`]).
    triangles: Vec<Triangle>,
    tri_material: Vec<MaterialId>,
    /// The ids of the degenerate triangles dropped as they were added.
    dropped: Dropped,
    materials: Vec<Material>,
    lights: Vec<PendingLight>,
    camera: Option<Camera>,
    image_size: Option<(u32, u32)>,
    textures: Vec<Texture>,
    /// Per kept triangle once any triangle has texture coordinates (zeros for those without).
    tri_uv: Vec<[Vec2; 3]>,
    /// True once any triangle, kept or not, has texture coordinates.
    has_uv: bool,
    /// Files read ([`Scene::sources`]).
    sources: Vec<PathBuf>,
}

impl SceneBuilder {
    /// An empty scene named `name`.
    pub fn new(name: &str) -> SceneBuilder {
        SceneBuilder { name: name.to_string(), ..Default::default() }
    }

    /// Adds a material and returns its id.
    pub fn material(&mut self, m: Material) -> MaterialId {
        self.materials.push(m);
        MaterialId(self.materials.len() as u32 - 1)
    }

    /// Adds a non-emitting diffuse material.
    pub fn diffuse(&mut self, name: &str, albedo: Vec3) -> MaterialId {
        self.material(Material::diffuse(name, albedo))
    }

    /// Adds a triangle `a, b, c` (counter-clockwise around its front) and returns its id. Ids count
    /// every triangle added; the scene drops degenerate ones, so its [`TriId`]s are those of the
    /// triangles kept, in order (lights name triangles by the builder's ids, [`SceneBuilder::build`]
    /// maps them).
    pub fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3, m: MaterialId) -> TriId {
        self.add(Triangle::new(a, b, c), m, None)
    }

    /// Adds a triangle with texture coordinates for its vertices.
    pub fn triangle_uv(&mut self, v: [Vec3; 3], uv: [Vec2; 3], m: MaterialId) -> TriId {
        if !self.has_uv {
            self.has_uv = true;
            self.tri_uv.resize(self.triangles.len(), [Vec2::ZERO; 3]);
        }
        self.add(Triangle::new(v[0], v[1], v[2]), m, Some(uv))
    }

    /// Stores `t` unless it is degenerate (then only its id is recorded); a triangle with a
    /// non-finite coordinate is stored, for `build` to report.
    fn add(&mut self, t: Triangle, m: MaterialId, uv: Option<[Vec2; 3]>) -> TriId {
        let id = TriId(self.triangle_count() as u32);
        if t.v.iter().all(|v| v.is_finite()) && t.is_degenerate() {
            self.dropped.push(id.0, m);
            return id;
        }
        self.triangles.push(t);
        self.tri_material.push(m);
        if self.has_uv {
            self.tri_uv.push(uv.unwrap_or([Vec2::ZERO; 3]));
        }
        id
    }

    /// Adds a texture and returns its id.
    pub fn texture(&mut self, t: Texture) -> TextureId {
        self.textures.push(t);
        TextureId(self.textures.len() as u32 - 1)
    }

    /// Records a file the loader read ([`Scene::sources`]); a file already recorded is not repeated.
    pub fn source(&mut self, path: &Path) {
        self.sources.push(path.to_path_buf());
    }

    /// Sets the scene's own image size.
    pub fn image_size(&mut self, width: u32, height: u32) {
        self.image_size = Some((width, height));
    }

    /// Adds the quad `a, b, c, d` as triangles `(a, b, c)` and `(a, c, d)`.
    pub fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, m: MaterialId) {
        self.triangle(a, b, c, m);
        self.triangle(a, c, d, m);
    }

    /// Number of triangles added so far, degenerate ones included (the next triangle's id).
    pub fn triangle_count(&self) -> usize {
        self.triangles.len() + self.dropped.count()
    }

    /// Adds a light: a convex polygon, counter-clockwise around the side it emits to, with radiance
    /// `radiance`. Its triangles (a fan) are added with an emissive material named `name`.
    pub fn light(&mut self, name: &str, polygon: &[Vec3], radiance: Vec3) -> LightId {
        let m = self.material(Material {
            name: name.to_string(),
            albedo: Vec3::splat(0.78),
            emission: radiance,
            texture: None,
        });
        let first = self.triangle_count() as u32;
        for i in 1..polygon.len().saturating_sub(1) {
            self.triangle(polygon[0], polygon[i], polygon[i + 1], m);
        }
        let triangles = (first..self.triangle_count() as u32).collect();
        self.lights.push(PendingLight { polygon: polygon.to_vec(), radiance, triangles });
        LightId(self.lights.len() as u32 - 1)
    }

    /// Declares already-added triangles to be one light with this polygon and radiance (for loaders,
    /// whose emissive triangles come from the file).
    pub fn light_from_triangles(&mut self, triangles: Vec<TriId>, polygon: Vec<Vec3>, radiance: Vec3) -> LightId {
        let triangles = triangles.into_iter().map(|t| t.0).collect();
        self.lights.push(PendingLight { polygon, radiance, triangles });
        LightId(self.lights.len() as u32 - 1)
    }

    /// Sets the scene's camera.
    pub fn camera(&mut self, c: Camera) {
        self.camera = Some(c);
    }

    /// Validates and builds the scene. Errors: no triangles, non-finite coordinates, a material index
    /// out of range, no lights, a light that is not a valid convex polygon, a light triangle index out of
    /// range or degenerate, an invalid camera. Triangles are named by the ids the builder returned.
    pub fn build(mut self) -> Result<Scene> {
        let bad = |m: String| Err(Error::InvalidScene(m));
        if self.triangle_count() == 0 {
            return bad("the scene has no triangles".into());
        }
        self.check_triangles()?;
        for m in &self.materials {
            if m.texture.is_some_and(|t| t.idx() >= self.textures.len()) {
                return bad(format!("material '{}' uses a texture that does not exist", m.name));
            }
        }
        if let Some((w, h)) = self.image_size {
            if w == 0 || h == 0 || w > 32768 || h > 32768 {
                return bad(format!("image size {w}x{h} must be between 1 and 32768"));
            }
        }
        if self.lights.is_empty() {
            return bad("the scene has no lights (no emissive triangles)".into());
        }
        if let Some(c) = &self.camera {
            c.validate()?;
        }
        let (lights, tri_light) = self.resolve_lights()?;
        if self.triangles.is_empty() {
            return bad("every triangle of the scene is degenerate".into());
        }
        let bounds = self.triangles.iter().fold(Aabb::EMPTY, |b, t| b.union(t.aabb()));
        // A light planar and convex only up to the rounding of its corners (one small against its
        // distance from the origin, see `Light::new`) must be so within a quarter of the margin the
        // per-light queries grow their pyramids by (ten tolerances, [`Scene::tolerance`]), so that
        // its samples stay inside that pyramid; a light within `1e-4` of its own size is so in any
        // scene holding it.
        let tol = 2.5 * crate::geometry::tolerance_of(bounds.size().max_element(), bounds.largest_abs());
        for (li, l) in lights.iter().enumerate() {
            let dev = l.deviation();
            if dev > tol.max(1e-4 * l.size()) {
                return bad(format!(
                    "light {li} is too small for its distance from the origin: rounded to f32, its corners lie \
                     up to {dev} off a flat convex polygon, more than this scene's tolerance ({tol}) allows; \
                     move the scene nearer the origin"
                ));
            }
        }
        // The arrays grew by doubling: give back what they did not fill (for a large array this
        // remaps its pages, it does not copy them).
        self.triangles.shrink_to_fit();
        self.tri_material.shrink_to_fit();
        self.tri_uv.shrink_to_fit();
        Ok(Scene {
            name: self.name,
            triangles: self.triangles,
            tri_material: self.tri_material,
            tri_light,
            materials: self.materials,
            lights,
            camera: self.camera,
            image_size: self.image_size,
            textures: self.textures,
            tri_uv: self.tri_uv,
            bounds,
            degenerate_skipped: self.dropped.count(),
            warnings: Vec::new(),
            sources: {
                let mut seen = std::collections::HashSet::new();
                self.sources.into_iter().filter(|p| seen.insert(p.clone())).collect()
            },
        })
    }

    /// The first triangle, in the order given, with a non-finite coordinate or a material that does
    /// not exist, as an error. Degenerate triangles were dropped, but not their material's check.
    fn check_triangles(&self) -> Result<()> {
        let n = self.materials.len();
        let finite = |t: &Triangle| t.v.iter().all(|v| v.is_finite());
        let stored = self.triangles.iter().zip(&self.tri_material).position(|(t, m)| !finite(t) || m.idx() >= n);
        let stored = stored.map(|s| (self.dropped.given(s as u32), s));
        let dropped = self.dropped.first_missing_material(n);
        let missing = |i: u32, m: MaterialId| Error::InvalidScene(format!("triangle {i} uses material {} of {n}", m.0));
        match (stored, dropped) {
            (Some((i, _)), Some((d, m))) if d < i => Err(missing(d, m)),
            (None, Some((d, m))) => Err(missing(d, m)),
            (Some((i, s)), _) if !finite(&self.triangles[s]) => Err(Error::InvalidScene(format!(
                "triangle {i} has a non-finite coordinate: {}",
                super::light::list_points(&self.triangles[s].v)
            ))),
            (Some((i, s)), _) => Err(missing(i, self.tri_material[s])),
            (None, None) => Ok(()),
        }
    }

    /// The lights, their triangles named by where they are stored, and the light of each stored
    /// triangle. Errors name lights by index and triangles by the ids the builder returned.
    fn resolve_lights(&mut self) -> Result<(Vec<Light>, Vec<Option<LightId>>)> {
        let bad = |m: String| Err(Error::InvalidScene(m));
        let given = self.triangle_count();
        let mut tri_light = vec![None; self.triangles.len()];
        let mut lights = Vec::with_capacity(self.lights.len());
        for (li, pl) in std::mem::take(&mut self.lights).into_iter().enumerate() {
            let mut ids = Vec::with_capacity(pl.triangles.len());
            for t in pl.triangles {
                if t as usize >= given {
                    return bad(format!("light {li}: triangle index {t} out of range"));
                }
                let Some(r) = self.dropped.stored(t) else {
                    return bad(format!("light {li}: triangle {t} has zero area"));
                };
                if tri_light[r as usize].is_some() {
                    return bad(format!("triangle {t} belongs to two lights"));
                }
                tri_light[r as usize] = Some(LightId(li as u32));
                ids.push(TriId(r));
            }
            let light = Light::new(pl.polygon, pl.radiance, ids).map_err(|e| match e {
                Error::InvalidScene(m) => Error::InvalidScene(format!("light {li}: {m}")),
                e => e,
            })?;
            lights.push(light);
        }
        Ok((lights, tri_light))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zero-area triangle: three points on a line.
    const LINE: [Vec3; 3] = [Vec3::ZERO, Vec3::ONE, Vec3::new(2.0, 2.0, 2.0)];
    const SQUARE: [Vec3; 4] =
        [Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 2.0, 1.0), Vec3::new(1.0, 2.0, 1.0), Vec3::new(1.0, 2.0, 0.0)];

    fn lamp(b: &mut SceneBuilder) -> MaterialId {
        b.material(Material { emission: Vec3::ONE, ..Material::diffuse("lamp", Vec3::ZERO) })
    }

    /// A scene of plain and textured triangles, a light from triangles and a light polygon; with
    /// `junk`, degenerate triangles (plain and textured) before, between and after them all.
    fn scene(junk: bool) -> SceneBuilder {
        let mut b = SceneBuilder::new("mixed");
        let (white, red, lamp) = (b.diffuse("white", Vec3::splat(0.8)), b.diffuse("red", Vec3::X), lamp(&mut b));
        let degenerate = |b: &mut SceneBuilder, n: usize| {
            for k in 0..n.min(if junk { n } else { 0 }) {
                match k % 2 {
                    0 => b.triangle(LINE[0], LINE[1], LINE[2], red),
                    _ => b.triangle_uv(LINE, [Vec2::ONE; 3], white),
                };
            }
        };
        degenerate(&mut b, 3);
        b.triangle(Vec3::ZERO, Vec3::Z, Vec3::X, white);
        degenerate(&mut b, 2);
        let uv = [Vec2::ZERO, Vec2::Y, Vec2::X];
        b.triangle_uv([Vec3::ZERO, Vec3::Y, Vec3::Z], uv, red);
        degenerate(&mut b, 1);
        let l1 = b.triangle(SQUARE[0], SQUARE[1], SQUARE[2], lamp);
        degenerate(&mut b, 4);
        let l2 = b.triangle(SQUARE[0], SQUARE[2], SQUARE[3], lamp);
        degenerate(&mut b, 1);
        b.light_from_triangles(vec![l1, l2], SQUARE.to_vec(), Vec3::ONE);
        b.light("panel", &SQUARE.map(|p| p + Vec3::X), Vec3::splat(2.0));
        degenerate(&mut b, 2);
        b.triangle(Vec3::X, Vec3::ONE, Vec3::Y, red);
        degenerate(&mut b, 5);
        b
    }

    #[test]
    fn degenerate_triangles_are_dropped_as_they_are_added_and_the_scene_is_the_same() {
        let (clean, mixed) = (scene(false), scene(true));
        assert_eq!((clean.triangle_count(), mixed.triangle_count()), (7, 7 + 18));
        // The builder holds only the triangles it keeps.
        assert_eq!((mixed.triangles.len(), mixed.tri_material.len(), mixed.tri_uv.len()), (7, 7, 7));
        let (clean, mixed) = (clean.build().unwrap(), mixed.build().unwrap());
        assert_eq!((clean.degenerate_skipped, mixed.degenerate_skipped), (0, 18));
        assert_eq!(mixed.triangles, clean.triangles);
        assert_eq!(mixed.tri_material, clean.tri_material);
        assert_eq!(mixed.tri_uv, clean.tri_uv);
        assert_eq!(mixed.tri_light, clean.tri_light);
        assert_eq!(mixed.lights, clean.lights);
        assert_eq!(mixed.materials, clean.materials);
        assert_eq!(mixed.bounds, clean.bounds);
        // What the clean scene holds, so that the comparison is not between two wrong scenes.
        assert_eq!(clean.triangles.len(), 7);
        assert_eq!(clean.lights[0].triangles, [TriId(2), TriId(3)]);
        assert_eq!(clean.lights[1].triangles, [TriId(4), TriId(5)]);
        let light = |i: u32| Some(LightId(i));
        assert_eq!(clean.tri_light, [None, None, light(0), light(0), light(1), light(1), None]);
        assert_eq!(clean.tri_uv[1], [Vec2::ZERO, Vec2::Y, Vec2::X]);
        assert!(clean.tri_uv.iter().enumerate().all(|(i, uv)| i == 1 || *uv == [Vec2::ZERO; 3]));
    }

    #[test]
    fn a_dropped_textured_triangle_still_gives_the_scene_texture_coordinates() {
        // As when degenerate triangles were dropped by `build`: one textured triangle, kept or not,
        // makes `tri_uv` per triangle (zeros for those without).
        let mut b = SceneBuilder::new("uv");
        let w = b.diffuse("white", Vec3::ONE);
        b.triangle(Vec3::ZERO, Vec3::Z, Vec3::X, w);
        b.triangle_uv(LINE, [Vec2::ONE; 3], w);
        let l = lamp(&mut b);
        b.light("lamp", &SQUARE, Vec3::ONE);
        b.triangle(Vec3::X, Vec3::ONE, Vec3::Y, l);
        let s = b.build().unwrap();
        assert_eq!((s.tri_uv.len(), s.degenerate_skipped), (s.triangles.len(), 1));
        assert!(s.tri_uv.iter().all(|uv| *uv == [Vec2::ZERO; 3]));
    }

    /// A builder whose triangles 0, 1 and 2 are degenerate and 3 is not, with one light (triangles 4, 5).
    fn three_degenerate() -> SceneBuilder {
        let mut b = SceneBuilder::new("errors");
        let w = b.diffuse("white", Vec3::ONE);
        for _ in 0..3 {
            b.triangle(LINE[0], LINE[1], LINE[2], w);
        }
        b.triangle(Vec3::ZERO, Vec3::Z, Vec3::X, w);
        b.light("lamp", &SQUARE, Vec3::ONE);
        b
    }

    fn error(b: SceneBuilder) -> String {
        b.build().unwrap_err().to_string()
    }

    #[test]
    fn errors_name_triangles_by_the_ids_the_builder_returned() {
        let scene = |f: &dyn Fn(&mut SceneBuilder)| {
            let mut b = three_degenerate();
            f(&mut b);
            error(b)
        };
        let square = || SQUARE.map(|p| p + Vec3::X).to_vec();
        // A light naming a degenerate triangle, or one that does not exist.
        let e = scene(&|b| _ = b.light_from_triangles(vec![TriId(1)], square(), Vec3::ONE));
        assert_eq!(e, "invalid scene: light 1: triangle 1 has zero area");
        let e = scene(&|b| {
            b.triangle(LINE[0], LINE[1], LINE[2], MaterialId(0));
            b.light_from_triangles(vec![TriId(6)], square(), Vec3::ONE);
        });
        assert_eq!(e, "invalid scene: light 1: triangle 6 has zero area");
        let e = scene(&|b| {
            b.triangle(LINE[0], LINE[1], LINE[2], MaterialId(0));
            b.light_from_triangles(vec![TriId(7)], square(), Vec3::ONE);
        });
        assert_eq!(e, "invalid scene: light 1: triangle index 7 out of range");
        let e = scene(&|b| _ = b.light_from_triangles(vec![TriId(5)], square(), Vec3::ONE));
        assert_eq!(e, "invalid scene: triangle 5 belongs to two lights");
        // A triangle with a NaN or infinite coordinate (which `Triangle::is_degenerate` calls
        // degenerate) is reported, not dropped.
        for bad in [f32::NAN, f32::INFINITY] {
            let p = [Vec3::new(bad, 0.0, 0.0), Vec3::Z, Vec3::X];
            let e = scene(&|b| _ = b.triangle(p[0], p[1], p[2], MaterialId(0)));
            let points = super::super::light::list_points(&p);
            assert_eq!(e, format!("invalid scene: triangle 6 has a non-finite coordinate: {points}"));
            assert!(Triangle::new(p[0], p[1], p[2]).is_degenerate());
        }
        // Materials that do not exist: the first triangle, in the order given, dropped or not.
        let missing = |id: u32| {
            let mut b = SceneBuilder::new("missing");
            let w = b.diffuse("white", Vec3::ONE);
            for i in 0..6 {
                let t = if i < 3 { LINE } else { [Vec3::ZERO, Vec3::Z, Vec3::X] };
                b.triangle(t[0], t[1], t[2], if i == id { MaterialId(9) } else { w });
            }
            b.light("lamp", &SQUARE, Vec3::ONE);
            error(b)
        };
        assert_eq!(missing(1), "invalid scene: triangle 1 uses material 9 of 2");
        assert_eq!(missing(4), "invalid scene: triangle 4 uses material 9 of 2");
        let e = scene(&|b| {
            b.triangle(LINE[0], LINE[1], LINE[2], MaterialId(7));
            b.triangle(Vec3::ZERO, Vec3::Y, Vec3::X, MaterialId(8));
        });
        assert_eq!(e, "invalid scene: triangle 6 uses material 7 of 2");
        let e = scene(&|b| {
            b.triangle(Vec3::ZERO, Vec3::Y, Vec3::NAN, MaterialId(0));
            b.triangle(LINE[0], LINE[1], LINE[2], MaterialId(7));
        });
        assert!(e.starts_with("invalid scene: triangle 6 has a non-finite coordinate"), "{e}");
        let e = scene(&|b| {
            b.triangle(LINE[0], LINE[1], LINE[2], MaterialId(7));
            b.triangle(Vec3::ZERO, Vec3::Y, Vec3::NAN, MaterialId(0));
        });
        assert_eq!(e, "invalid scene: triangle 6 uses material 7 of 2");
    }

    #[test]
    fn scenes_of_degenerate_triangles_only_give_the_same_errors() {
        assert_eq!(error(SceneBuilder::new("empty")), "invalid scene: the scene has no triangles");
        let mut b = SceneBuilder::new("flat");
        let w = b.diffuse("white", Vec3::ONE);
        b.triangle(LINE[0], LINE[1], LINE[2], w);
        assert_eq!(error(b.clone()), "invalid scene: the scene has no lights (no emissive triangles)");
        b.light_from_triangles(Vec::new(), SQUARE.to_vec(), Vec3::ONE);
        assert_eq!(error(b), "invalid scene: every triangle of the scene is degenerate");
    }
}
