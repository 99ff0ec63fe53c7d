//! [`Scene`] and its [`SceneBuilder`]. The builder is how built-in scenes and file loaders make a
//! scene; `build` validates everything once (finite coordinates, lights, camera) and drops degenerate
//! triangles (zero area: they cannot block or be seen), counting them in
//! [`Scene::degenerate_skipped`] so the caller can warn.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::{Camera, Light, LightId, Material, MaterialId, Texture, TextureId, TriId};
use crate::error::{Error, Result};
use crate::geometry::{Aabb, Triangle, TOLERANCE_REL};

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
    triangles: Vec<Triangle>,
    tri_material: Vec<MaterialId>,
    materials: Vec<Material>,
    lights: Vec<PendingLight>,
    camera: Option<Camera>,
    image_size: Option<(u32, u32)>,
    textures: Vec<Texture>,
    /// Per triangle once any triangle has texture coordinates (zeros for those without).
    tri_uv: Vec<[Vec2; 3]>,
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

    /// Adds a triangle `a, b, c` (counter-clockwise around its front) and returns its id.
    pub fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3, m: MaterialId) -> TriId {
        self.triangles.push(Triangle::new(a, b, c));
        self.tri_material.push(m);
        if !self.tri_uv.is_empty() {
            self.tri_uv.push([Vec2::ZERO; 3]);
        }
        TriId(self.triangles.len() as u32 - 1)
    }

    /// Adds a triangle with texture coordinates for its vertices.
    pub fn triangle_uv(&mut self, v: [Vec3; 3], uv: [Vec2; 3], m: MaterialId) -> TriId {
        self.tri_uv.resize(self.triangles.len(), [Vec2::ZERO; 3]);
        self.triangles.push(Triangle::new(v[0], v[1], v[2]));
        self.tri_material.push(m);
        self.tri_uv.push(uv);
        TriId(self.triangles.len() as u32 - 1)
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

    /// Number of triangles so far.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
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
        let first = self.triangles.len() as u32;
        for i in 1..polygon.len().saturating_sub(1) {
            self.triangle(polygon[0], polygon[i], polygon[i + 1], m);
        }
        let triangles = (first..self.triangles.len() as u32).collect();
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
    /// range or degenerate, an invalid camera.
    pub fn build(self) -> Result<Scene> {
        let bad = |m: String| Err(Error::InvalidScene(m));
        if self.triangles.is_empty() {
            return bad("the scene has no triangles".into());
        }
        for (i, t) in self.triangles.iter().enumerate() {
            if !t.v.iter().all(|v| v.is_finite()) {
                return bad(format!("triangle {i} has a non-finite coordinate: {}", super::light::list_points(&t.v)));
            }
            let m = self.tri_material[i];
            if m.idx() >= self.materials.len() {
                return bad(format!("triangle {i} uses material {} of {}", m.0, self.materials.len()));
            }
        }
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
        // Drop degenerate triangles, remapping ids.
        let mut remap = vec![u32::MAX; self.triangles.len()];
        let mut triangles = Vec::with_capacity(self.triangles.len());
        let mut tri_material = Vec::with_capacity(self.triangles.len());
        let mut tri_uv = Vec::with_capacity(self.tri_uv.len());
        for (i, t) in self.triangles.iter().enumerate() {
            if !t.is_degenerate() {
                remap[i] = triangles.len() as u32;
                triangles.push(*t);
                tri_material.push(self.tri_material[i]);
                if let Some(uv) = self.tri_uv.get(i) {
                    tri_uv.push(*uv);
                }
            }
        }
        let degenerate_skipped = self.triangles.len() - triangles.len();
        let mut tri_light = vec![None; triangles.len()];
        let mut lights = Vec::with_capacity(self.lights.len());
        for (li, pl) in self.lights.into_iter().enumerate() {
            let mut ids = Vec::with_capacity(pl.triangles.len());
            for t in pl.triangles {
                match remap.get(t as usize) {
                    None => return bad(format!("light {li}: triangle index {t} out of range")),
                    Some(&u32::MAX) => return bad(format!("light {li}: triangle {t} has zero area")),
                    Some(&r) => {
                        if tri_light[r as usize].is_some() {
                            return bad(format!("triangle {t} belongs to two lights"));
                        }
                        tri_light[r as usize] = Some(LightId(li as u32));
                        ids.push(TriId(r));
                    }
                }
            }
            let light = Light::new(pl.polygon, pl.radiance, ids).map_err(|e| match e {
                Error::InvalidScene(m) => Error::InvalidScene(format!("light {li}: {m}")),
                e => e,
            })?;
            lights.push(light);
        }
        if triangles.is_empty() {
            return bad("every triangle of the scene is degenerate".into());
        }
        let bounds = triangles.iter().fold(Aabb::EMPTY, |b, t| b.union(t.aabb()));
        // A light planar and convex only up to the rounding of its corners (one small against its
        // distance from the origin, see `Light::new`) must be so within a quarter of the margin the
        // per-light queries grow their pyramids by (ten tolerances), so that its samples stay
        // inside that pyramid; a light within `1e-4` of its own size is so in any scene holding it.
        let tol = 2.5 * TOLERANCE_REL * bounds.size().max_element();
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
        Ok(Scene {
            name: self.name,
            triangles,
            tri_material,
            tri_light,
            materials: self.materials,
            lights,
            camera: self.camera,
            image_size: self.image_size,
            textures: self.textures,
            tri_uv,
            bounds,
            degenerate_skipped,
            warnings: Vec::new(),
            sources: {
                let mut seen = std::collections::HashSet::new();
                self.sources.into_iter().filter(|p| seen.insert(p.clone())).collect()
            },
        })
    }
}
