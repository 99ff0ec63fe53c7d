//! Mitsuba scene files (issue 18; SPEC §1 scene input), versions 0.6 (`toWorld`, camelCase names) and
//! 3.x (`to_world`, snake_case): the subset real scenes use, turned into plie's scene model.
//!
//! - XML ([`xml`]): `<default>` and `$name` substitution, `<include>`, `<ref id>`.
//! - Transforms ([`props`]): `matrix`, `translate`, `rotate`, `scale`, `lookat`.
//! - Shapes: `obj`, `ply` (ASCII and binary, [`crate::io::ply`]), `serialized` ([`crate::io::serialized`]),
//!   `rectangle`, `cube`, `disk`, `sphere` (tessellated, [`shapes`]), `shapegroup` and `instance`;
//!   `flip_normals`. An `area` emitter on a shape makes its triangles lights (one-sided, on the side
//!   the shape faces), grouped into convex lights by [`crate::io::lights`].
//! - BSDFs: `diffuse` (and `roughdiffuse`) with a reflectance that is a colour or a `bitmap` texture;
//!   `twosided` (plie shades both sides anyway). A BSDF plie cannot render yet becomes its diffuse part
//!   (plastics: their diffuse reflectance; conductors: black) and one warning lists them; shapes with
//!   a dielectric or `null` BSDF are dropped from shading and shadows, with a warning.
//! - Emitters: `area` only. Point, spot, directional, environment and sun emitters are an error, unless
//!   the scene also has area lights: then they are ignored with a warning.
//! - Sensor: `perspective` with `fov`, `fov_axis`, `to_world` and its film's `width` and `height`:
//!   the scene's camera and image size ([`Scene::camera`], [`Scene::image_size`]).
//!
//! Everything else a scene holds that plie cannot read is an error naming the element, its file and
//! line. Files the scene names (includes, meshes, textures) are read only inside its folder unless
//! [`LoadOptions::allow_outside_paths`]. The library never prints: what was changed or ignored is in
//! [`Scene::warnings`].

pub mod props;
mod sensor;
pub mod shapes;
mod warnings;
pub mod xml;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{Mat4, Vec2, Vec3};

use self::props::{boolean, find, float, integer, string, transform};
use self::xml::{parse_scene, register_ids, Elem};
use super::input::{resolve_in_scene, short, LoadOptions};
use super::lights::{self, EmissiveTriangle};
use super::scene_name;
use super::texture_file::TextureFiles;
use super::tri_mesh::TriMesh;
use crate::error::{Error, Result};
use crate::scene::texture::{Filter, Texture, Wrap};
use crate::scene::{Material, MaterialId, Scene, SceneBuilder, TextureId};

/// The most triangles a Mitsuba scene may expand to (instances included).
pub const MAX_TRIANGLES: usize = 50_000_000;
/// How deep BSDFs may nest (`twosided`, `coating`, `mask` ...).
const MAX_BSDF_NESTING: usize = 16;

/// Loads the Mitsuba scene file at `path` (see the module doc).
pub fn load_mitsuba(path: &Path) -> Result<Scene> {
    load_mitsuba_with(path, LoadOptions::default())
}

/// [`load_mitsuba`] with options.
pub fn load_mitsuba_with(path: &Path, opts: LoadOptions) -> Result<Scene> {
    load_within(path, opts, MAX_TRIANGLES)
}

/// [`load_mitsuba_with`] with a triangle limit (lower in tests).
fn load_within(path: &Path, opts: LoadOptions, max_triangles: usize) -> Result<Scene> {
    let doc = parse_scene(path, opts)?;
    let major = doc.version.split('.').next().and_then(|v| v.parse::<u32>().ok());
    if !matches!(major, Some(0) | Some(2) | Some(3)) {
        return Err(doc
            .root
            .error(format!("version '{}' is not supported (0.x, 2.x and 3.x are)", short(&doc.version))));
    }
    let mut ids = HashMap::new();
    register_ids(&doc.root, &mut ids)?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut b = SceneBuilder::new(&scene_name(path));
    for f in &doc.files {
        b.source(f);
    }
    let mut l = Loader {
        dir,
        opts,
        ids,
        b,
        bsdfs: HashMap::new(),
        meshes: HashMap::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        texture_files: TextureFiles::default(),
        emissive: Vec::new(),
        emissive_at: Vec::new(),
        changed: Vec::new(),
        dropped: Vec::new(),
        other_emitters: Vec::new(),
        spectral: false,
        notes: Vec::new(),
        triangles: 0,
        max_triangles,
        loaded: (0, 0),
        camera: false,
    };
    for e in &doc.root.children {
        match e.tag.as_str() {
            "shape" => l.shape(e, Mat4::IDENTITY)?,
            "sensor" => l.sensor(e)?,
            "emitter" => match e.need("type")? {
                "area" => return Err(e.error("an area emitter must be inside a <shape>".into())),
                t => l.other_emitters.push(format!("{t} ({}:{})", e.file.display(), e.line)),
            },
            "bsdf" | "texture" | "default" | "integrator" | "sampler" | "film" | "rfilter" => {}
            "medium" | "phase" => {
                l.notes.push(format!("{} at line {} is ignored: plie renders no media", e.describe(), e.line))
            }
            t => return Err(e.error(format!("<{t}> is not a scene element plie reads"))),
        }
    }
    l.finish(&doc.root)
}

/// A BSDF as plie renders it.
#[derive(Clone, Debug)]
struct Bsdf {
    name: String,
    albedo: Vec3,
    texture: Option<TexSpec>,
    /// Dielectric or null: the shape is dropped.
    dropped: bool,
}

/// A `bitmap` texture before loading.
#[derive(Clone, Debug, PartialEq)]
struct TexSpec {
    path: PathBuf,
    srgb: bool,
    filter: Filter,
    wrap: [Wrap; 2],
    scale: Vec2,
    offset: Vec2,
}

impl TexSpec {
    fn key(&self) -> String {
        format!("{:?}", self)
    }
}

struct Loader<'a> {
    dir: PathBuf,
    opts: LoadOptions,
    ids: HashMap<String, &'a Elem>,
    b: SceneBuilder,
    /// Mesh files read so far, by (shape type, file, flip_tex_coords, shape_index).
    meshes: HashMap<(String, PathBuf, bool, usize), Rc<TriMesh>>,
    /// Converted BSDFs by element address.
    bsdfs: HashMap<*const Elem, Bsdf>,
    /// Materials by (BSDF address, emission bits, textured).
    materials: HashMap<(*const Elem, [u32; 3], bool), MaterialId>,
    /// Loaded textures by [`TexSpec::key`], with their mean.
    textures: HashMap<String, (TextureId, Vec3)>,
    /// Texture files decoded (each once, whatever the wrap modes and transforms using it).
    texture_files: TextureFiles,
    emissive: Vec<EmissiveTriangle>,
    /// The shape element (file, line) of each emissive triangle.
    emissive_at: Vec<&'a Elem>,
    /// BSDFs rendered by their diffuse part: (name, how).
    changed: Vec<(String, String)>,
    /// Names of the BSDFs of dropped shapes.
    dropped: Vec<String>,
    /// Emitters other than area lights: "type (file:line)".
    other_emitters: Vec<String>,
    /// A spectrum of wavelength:value pairs was averaged to grey.
    spectral: bool,
    /// Other warnings.
    notes: Vec<String>,
    triangles: usize,
    /// The most triangles the scene may expand to: [`MAX_TRIANGLES`].
    max_triangles: usize,
    /// Vertices and triangles of the distinct mesh files read (kept in [`Loader::meshes`]), bounded
    /// like the expanded scene: at most `max_triangles` triangles and three vertices a triangle.
    loaded: (usize, usize),
    camera: bool,
}

impl<'a> Loader<'a> {
    /// The element a `<ref id>` names, or `e` itself.
    fn deref(&self, e: &'a Elem) -> Result<&'a Elem> {
        if e.tag != "ref" {
            return Ok(e);
        }
        let id = e.need("id")?;
        self.ids.get(id).copied().ok_or_else(|| e.error(format!("no element has the id '{}'", short(id))))
    }

    /// A file named by `e`'s string property `name`, inside the scene's folder.
    fn file(&self, e: &Elem, name: &str) -> Result<PathBuf> {
        let f = string(e, name)?.ok_or_else(|| e.error(format!("has no '{name}' string")))?;
        resolve_in_scene(&self.dir, f, name, self.opts).map_err(|m| e.error(m))
    }

    /// Names a mesh or texture file in an error of reading it.
    fn reading<T>(&self, e: &Elem, r: Result<T>) -> Result<T> {
        r.map_err(|err| match err {
            Error::Io { path, source } => e.error(format!("cannot read '{}': {source}", path.display())),
            err => err,
        })
    }

    fn shape(&mut self, e: &'a Elem, parent: Mat4) -> Result<()> {
        let ty = e.need("type")?;
        match ty {
            "shapegroup" => return Ok(()),
            "instance" => {
                let r = e
                    .children
                    .iter()
                    .find(|c| c.tag == "ref")
                    .ok_or_else(|| e.error("names no shapegroup (<ref id>)".into()))?;
                let g = self.deref(r)?;
                if g.tag != "shape" || g.attr("type") != Some("shapegroup") {
                    return Err(r.error(format!("names {}, not a shapegroup", g.describe())));
                }
                let m = parent * transform(e, "to_world")?;
                for c in g.children.iter().filter(|c| c.tag == "shape") {
                    if matches!(c.attr("type"), Some("shapegroup" | "instance")) {
                        return Err(c.error("a shapegroup cannot hold shapegroups or instances".into()));
                    }
                    self.shape(c, m)?;
                }
                return Ok(());
            }
            _ => {}
        }
        let mut to_world = parent * transform(e, "to_world")?;
        let (mesh, analytic) = match ty {
            "obj" | "ply" | "serialized" => (self.mesh_file(e, ty)?, false),
            "rectangle" => (Rc::new(shapes::rectangle()), true),
            "cube" => (Rc::new(shapes::cube()), true),
            "disk" => (Rc::new(shapes::disk()), true),
            "sphere" => {
                let center = props::point(e, "center", Vec3::ZERO)?;
                let radius = float(e, "radius", 1.0)?;
                if radius <= 0.0 {
                    return Err(e.error(format!("radius {radius} must be positive")));
                }
                to_world = to_world * Mat4::from_translation(center) * Mat4::from_scale(Vec3::splat(radius));
                (Rc::new(shapes::sphere()), true)
            }
            t => {
                return Err(e.error(format!(
                    "shape type '{}' is not supported (obj, ply, serialized, rectangle, cube, disk, sphere, shapegroup, instance are)",
                    short(t)
                )))
            }
        };
        let mut bsdf_elem: Option<&'a Elem> = None;
        let mut radiance: Option<Vec3> = None;
        for c in &e.children {
            let c = if c.tag == "ref" { self.deref(c)? } else { c };
            match c.tag.as_str() {
                "bsdf" => bsdf_elem = Some(c),
                "emitter" => match c.need("type")? {
                    "area" => {
                        let p = find(c, "radiance").ok_or_else(|| c.error("has no 'radiance'".into()))?;
                        let v = props::colour(p, &mut self.spectral)?;
                        if v.min_element() < 0.0 {
                            return Err(p.error("radiance cannot be negative".into()));
                        }
                        radiance = Some(v);
                    }
                    t => {
                        return Err(c.error(format!("emitter type '{}' on a shape: only 'area' is supported", short(t))))
                    }
                },
                _ => {}
            }
        }
        let bsdf = match bsdf_elem {
            Some(be) => self.bsdf(be)?,
            None => Bsdf { name: "default".into(), albedo: Vec3::splat(0.5), texture: None, dropped: false },
        };
        let emission = radiance.unwrap_or(Vec3::ZERO);
        if bsdf.dropped && emission == Vec3::ZERO {
            self.dropped.push(bsdf.name.clone());
            return Ok(());
        }
        let textured = bsdf.texture.is_some() && !mesh.uvs.is_empty() && !bsdf.dropped;
        let key =
            (bsdf_elem.map_or(std::ptr::null(), |x| x as *const Elem), emission.to_array().map(f32::to_bits), textured);
        let m = match self.materials.get(&key) {
            Some(&m) => m,
            None => {
                let mut mat = Material::diffuse(&bsdf.name, if bsdf.dropped { Vec3::ZERO } else { bsdf.albedo });
                mat.emission = emission;
                if let (Some(spec), false) = (&bsdf.texture, bsdf.dropped) {
                    let (id, mean) = self.texture(bsdf_elem.unwrap_or(e), spec)?;
                    if textured {
                        mat.texture = Some(id);
                    } else {
                        mat.albedo *= mean;
                        self.notes.push(format!(
                            "material '{}': a texture on a shape without texture coordinates ({} line {}): its mean colour is used",
                            bsdf.name,
                            e.file.display(),
                            e.line
                        ));
                    }
                }
                let m = self.b.material(mat);
                self.materials.insert(key, m);
                m
            }
        };
        let flip = boolean(e, "flip_normals", false)? ^ (analytic && to_world.determinant() < 0.0);
        self.add_mesh(e, &mesh, (to_world, flip), (m, textured), radiance)
    }

    /// Adds `mesh` placed by `to_world` (winding reversed if `flip`) with material `m` (texture
    /// coordinates kept if `textured`), emitting `radiance` if given.
    fn add_mesh(
        &mut self,
        e: &'a Elem,
        mesh: &TriMesh,
        (to_world, flip): (Mat4, bool),
        (m, textured): (MaterialId, bool),
        radiance: Option<Vec3>,
    ) -> Result<()> {
        self.triangles += mesh.triangles.len();
        if self.triangles > self.max_triangles {
            return Err(e.error(format!("the scene expands to more than {} triangles", self.max_triangles)));
        }
        // Vertices are placed as triangles use them, not copied all at once: a mesh may declare
        // many more vertices than its triangles use (150 million from a 2 MB serialized file).
        let place = |i: u32| to_world.transform_point3(mesh.positions[i as usize]);
        for t in &mesh.triangles {
            let placed = t.map(place);
            if placed.iter().any(|v| !v.is_finite()) {
                return Err(e.error("a transformed vertex is not finite".into()));
            }
            let (t, v) = if flip { ([t[0], t[2], t[1]], [placed[0], placed[2], placed[1]]) } else { (*t, placed) };
            let id = if textured {
                self.b.triangle_uv(v, t.map(|i| mesh.uvs.get(i as usize).copied().unwrap_or_default()), m)
            } else {
                self.b.triangle(v[0], v[1], v[2], m)
            };
            if let Some(radiance) = radiance.filter(|r| r.max_element() > 0.0) {
                self.emissive.push(EmissiveTriangle { id, vertices: v, radiance });
                self.emissive_at.push(e);
            }
        }
        Ok(())
    }

    /// The mesh of an `obj`, `ply` or `serialized` shape, read once per file (instances reuse it).
    fn mesh_file(&mut self, e: &Elem, ty: &str) -> Result<Rc<TriMesh>> {
        let path = self.file(e, "filename")?;
        let flip = boolean(e, "flip_tex_coords", true)?;
        let index = integer(e, "shape_index", 0)?;
        let index = usize::try_from(index).map_err(|_| e.error(format!("shape_index {index} is negative")))?;
        let key = (ty.to_string(), path.clone(), flip, index);
        if let Some(m) = self.meshes.get(&key) {
            return Ok(m.clone());
        }
        let (max_vertices, max_triangles) = (3 * self.max_triangles, self.max_triangles);
        // What is left of the budget: a serialized mesh's counts are checked against it before its
        // data is decompressed (a zlib stream can declare and hold far more than its file's size).
        let left = super::serialized::Limits {
            vertices: max_vertices.saturating_sub(self.loaded.0) as u64,
            triangles: max_triangles.saturating_sub(self.loaded.1) as u64,
        };
        let mesh = Rc::new(match ty {
            "obj" => self.reading(e, super::obj::load_obj_mesh(&path, flip))?,
            "ply" => self.reading(e, super::ply::load_ply(&path))?,
            _ => self.reading(e, super::serialized::load_serialized_within(&path, index, left))?,
        });
        self.b.source(&path);
        self.loaded.0 += mesh.positions.len();
        self.loaded.1 += mesh.triangles.len();
        if self.loaded.0 > max_vertices || self.loaded.1 > max_triangles {
            return Err(e.error(format!(
                "the scene's mesh files hold more than {max_triangles} triangles or {max_vertices} vertices"
            )));
        }
        self.meshes.insert(key, mesh.clone());
        Ok(mesh)
    }

    /// Converts a BSDF (memoised per element, so each is reported once).
    fn bsdf(&mut self, e: &'a Elem) -> Result<Bsdf> {
        self.bsdf_nested(e, 0)
    }

    /// [`Loader::bsdf`] at nesting `depth` (a BSDF that contains itself through a `<ref>` would
    /// otherwise recurse without end).
    fn bsdf_nested(&mut self, e: &'a Elem, depth: usize) -> Result<Bsdf> {
        if let Some(b) = self.bsdfs.get(&(e as *const Elem)) {
            return Ok(b.clone());
        }
        if depth > MAX_BSDF_NESTING {
            return Err(e.error(format!("BSDFs nest more than {MAX_BSDF_NESTING} levels deep (one contains itself?)")));
        }
        let name = e.attr("id").map(str::to_string).unwrap_or_else(|| format!("{} line {}", e.file.display(), e.line));
        let ty = e.need("type")?;
        let nested = |l: &Self| -> Result<&'a Elem> {
            let c = e
                .children
                .iter()
                .find(|c| c.tag == "bsdf" || c.tag == "ref")
                .ok_or_else(|| e.error("has no nested BSDF".into()))?;
            l.deref(c)
        };
        let change = |l: &mut Self, how: &str| l.changed.push((name.clone(), format!("{ty}: {how}")));
        let b = match ty {
            "diffuse" | "roughdiffuse" | "lambertian" => {
                let (albedo, texture) = self.reflectance(e, "reflectance")?;
                Bsdf { name: name.clone(), albedo, texture, dropped: false }
            }
            "twosided" => {
                let inner = nested(self)?;
                Bsdf { name: name.clone(), ..self.bsdf_nested(inner, depth + 1)? }
            }
            "plastic" | "roughplastic" | "phong" | "ward" | "modifiedphong" => {
                let (albedo, texture) = self.reflectance(e, "diffuse_reflectance")?;
                change(self, "its diffuse reflectance (the specular part is not rendered)");
                Bsdf { name: name.clone(), albedo, texture, dropped: false }
            }
            "principled" | "principledthin" => {
                let (albedo, texture) = self.reflectance(e, "base_color")?;
                change(self, "its base colour, diffuse");
                Bsdf { name: name.clone(), albedo, texture, dropped: false }
            }
            "conductor" | "roughconductor" | "hair" => {
                change(self, "black (a conductor has no diffuse part)");
                Bsdf { name: name.clone(), albedo: Vec3::ZERO, texture: None, dropped: false }
            }
            "coating" | "roughcoating" | "bumpmap" | "normalmap" | "mask" | "blendbsdf" | "mixturebsdf" => {
                change(self, "its nested BSDF");
                let inner = nested(self)?;
                Bsdf { name: name.clone(), ..self.bsdf_nested(inner, depth + 1)? }
            }
            "dielectric" | "roughdielectric" | "thindielectric" | "null" | "polarizer" | "retarder" => {
                Bsdf { name: format!("{name} ({ty})"), albedo: Vec3::ZERO, texture: None, dropped: true }
            }
            t => return Err(e.error(format!("BSDF type '{}' is not supported", short(t)))),
        };
        self.bsdfs.insert(e as *const Elem, b.clone());
        Ok(b)
    }

    /// A reflectance property: a colour (default 0.5) or a bitmap texture.
    fn reflectance(&mut self, e: &'a Elem, name: &str) -> Result<(Vec3, Option<TexSpec>)> {
        let Some(p) = find(e, name) else { return Ok((Vec3::splat(0.5), None)) };
        let p = self.deref(p)?;
        if p.tag == "texture" {
            return self.bitmap(p).map(|t| (Vec3::ONE, Some(t)));
        }
        let v = props::colour(p, &mut self.spectral)?;
        Ok((v.clamp(Vec3::ZERO, Vec3::ONE), None))
    }

    fn bitmap(&mut self, t: &'a Elem) -> Result<TexSpec> {
        match t.need("type")? {
            "bitmap" => {}
            ty => return Err(t.error(format!("texture type '{}' is not supported (bitmap is)", short(ty)))),
        }
        let path = self.file(t, "filename")?;
        let srgb = !boolean(t, "raw", false)? && float(t, "gamma", -1.0)? != 1.0;
        let filter = match string(t, "filter_type")?.unwrap_or("bilinear") {
            "bilinear" | "ewa" | "trilinear" => Filter::Bilinear,
            "nearest" => Filter::Nearest,
            f => return Err(t.error(format!("filter_type '{}' is not supported (bilinear, nearest)", short(f)))),
        };
        let mode = |s: &str| match s {
            "repeat" => Ok(Wrap::Repeat),
            "mirror" => Ok(Wrap::Mirror),
            "clamp" => Ok(Wrap::Clamp),
            m => Err(t.error(format!("wrap mode '{}' is not supported (repeat, mirror, clamp)", short(m)))),
        };
        let all = string(t, "wrap_mode")?.unwrap_or("repeat");
        let wrap = [mode(string(t, "wrap_mode_u")?.unwrap_or(all))?, mode(string(t, "wrap_mode_v")?.unwrap_or(all))?];
        let m = transform(t, "to_uv")?;
        if m.x_axis.y != 0.0 || m.y_axis.x != 0.0 {
            return Err(t.error("to_uv with a rotation is not supported (scale and translate are)".into()));
        }
        let scale = Vec2::new(m.x_axis.x * float(t, "uscale", 1.0)?, m.y_axis.y * float(t, "vscale", 1.0)?);
        let offset = Vec2::new(m.w_axis.x + float(t, "uoffset", 0.0)?, m.w_axis.y + float(t, "voffset", 0.0)?);
        Ok(TexSpec { path, srgb, filter, wrap, scale, offset })
    }

    /// Loads a texture once; its id and mean colour.
    fn texture(&mut self, e: &Elem, spec: &TexSpec) -> Result<(TextureId, Vec3)> {
        let key = spec.key();
        if let Some(&t) = self.textures.get(&key) {
            return Ok(t);
        }
        let tex = self.texture_files.load(&spec.path, spec.srgb);
        let tex = self.reading(e, tex)?;
        self.b.source(&spec.path);
        let tex = Texture { wrap: spec.wrap, filter: spec.filter, scale: spec.scale, offset: spec.offset, ..tex };
        let mean = tex.mean();
        let id = self.b.texture(tex);
        self.textures.insert(key, (id, mean));
        Ok((id, mean))
    }

    /// The sensor: camera and image size (of the first sensor; later ones are noted and skipped).
    fn sensor(&mut self, e: &Elem) -> Result<()> {
        sensor::check_type(e, &mut self.notes)?;
        if self.camera {
            self.notes.push(format!("sensor at line {}: only the first sensor is used", e.line));
            return Ok(());
        }
        self.camera = true;
        let (camera, (w, h)) = sensor::camera(e, &mut self.notes)?;
        self.b.camera(camera);
        self.b.image_size(w, h);
        Ok(())
    }

    fn finish(mut self, root: &Elem) -> Result<Scene> {
        if self.emissive.is_empty() {
            if let Some(first) = self.other_emitters.first() {
                return Err(root.error(format!(
                    "emitter {first} is not supported: plie renders area lights only (an 'area' emitter inside a <shape>), and the scene has none"
                )));
            }
            return Err(root.error("the scene has no lights: no <shape> has an 'area' emitter".into()));
        }
        let warnings =
            warnings::collect(&self.other_emitters, &mut self.changed, &self.dropped, self.spectral, self.notes);
        lights::add_lights(&mut self.b, &self.emissive).map_err(|z| {
            self.emissive_at[z.index].error("an emissive triangle has zero area: a light must have an area".into())
        })?;
        // The mesh files' arrays are copied into the builder: free them before it builds (for a
        // scene at the triangle limit, hundreds of megabytes at the peak).
        drop(std::mem::take(&mut self.meshes));
        let mut scene = self.b.build().map_err(|e| match e {
            Error::InvalidScene(m) => root.error(m),
            e => e,
        })?;
        scene.warnings = warnings;
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::serialized::write_serialized;

    /// A scene of a light and serialized shapes `indices` of `mesh.serialized`, which holds `meshes`.
    fn scene(meshes: &[TriMesh], indices: &[usize]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("mesh.serialized"), write_serialized(meshes)).unwrap();
        let shapes: String = indices
            .iter()
            .map(|i| {
                format!(
                    r#"<shape type="serialized"><string name="filename" value="mesh.serialized"/><integer name="shape_index" value="{i}"/></shape>"#
                )
            })
            .collect();
        let xml = format!(
            r#"<scene version="3.0.0"><shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>{shapes}</scene>"#
        );
        std::fs::write(dir.path().join("scene.xml"), xml).unwrap();
        dir
    }

    /// A mesh of `n` triangles over `3 n` vertices.
    fn soup(n: u32) -> TriMesh {
        TriMesh {
            positions: (0..3 * n).map(|i| Vec3::new(i as f32, (i % 3) as f32, (i % 2) as f32)).collect(),
            uvs: Vec::new(),
            triangles: (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        }
    }

    #[test]
    fn the_mesh_files_of_a_scene_share_one_triangle_budget() {
        // Three meshes of 4 triangles: two fit a limit of 10 (with the light's 2), the third is an
        // error as soon as its header is read, naming its file.
        let dir = scene(&[soup(4), soup(4), soup(4)], &[0, 1, 2]);
        let path = dir.path().join("scene.xml");
        let e = load_within(&path, LoadOptions::default(), 10).unwrap_err().to_string();
        assert!(e.contains("mesh.serialized") && e.contains("declares 4 triangles: more than the 2 "), "{e}");
        assert!(!e.contains('\n'), "{e}");
        assert_eq!(load_within(&path, LoadOptions::default(), 14).unwrap().triangle_count(), 14);
        // The vertex budget, three a triangle: 2 triangles over 30 vertices do not fit a limit of 9.
        let mut wide = soup(10);
        wide.triangles.truncate(2);
        let dir = scene(&[wide], &[0]);
        let e = load_within(&dir.path().join("scene.xml"), LoadOptions::default(), 9).unwrap_err().to_string();
        assert!(e.contains("declares 30 vertices: more than the 27 "), "{e}");
        // One mesh used twice is read once; its triangles count twice toward the expanded scene.
        let dir = scene(&[soup(4)], &[0, 0]);
        let path = dir.path().join("scene.xml");
        assert_eq!(load_within(&path, LoadOptions::default(), 10).unwrap().triangle_count(), 10);
        let e = load_within(&path, LoadOptions::default(), 9).unwrap_err().to_string();
        assert!(e.contains("expands to more than 9 triangles"), "{e}");
    }

    #[test]
    fn triangles_naming_a_vertex_twice_are_counted_as_the_builder_counts_them() {
        let mut m = soup(2);
        m.triangles.extend([[0, 0, 0], [1, 1, 2], [3, 4, 3]]);
        let dir = scene(&[m], &[0]);
        let s = load_within(&dir.path().join("scene.xml"), LoadOptions::default(), 100).unwrap();
        assert_eq!((s.triangle_count(), s.degenerate_skipped), (2 + 2, 3));
        // They still count toward the limit, and an emissive one is still an error.
        let e = load_within(&dir.path().join("scene.xml"), LoadOptions::default(), 6).unwrap_err().to_string();
        assert!(e.contains("expands to more than 6 triangles"), "{e}");
        let xml = std::fs::read_to_string(dir.path().join("scene.xml")).unwrap().replace(
            r#"value="0"/></shape>"#,
            r#"value="0"/><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#,
        );
        std::fs::write(dir.path().join("scene.xml"), xml).unwrap();
        let e = load_within(&dir.path().join("scene.xml"), LoadOptions::default(), 100).unwrap_err().to_string();
        assert!(e.contains("zero area"), "{e}");
    }
}
