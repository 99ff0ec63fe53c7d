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
use super::texture_file::load_texture;
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
    let mut l = Loader {
        dir,
        opts,
        ids,
        b: SceneBuilder::new(&scene_name(path)),
        bsdfs: HashMap::new(),
        meshes: HashMap::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        emissive: Vec::new(),
        emissive_at: Vec::new(),
        changed: Vec::new(),
        dropped: Vec::new(),
        other_emitters: Vec::new(),
        spectral: false,
        notes: Vec::new(),
        triangles: 0,
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
        if self.triangles > MAX_TRIANGLES {
            return Err(e.error(format!("the scene expands to more than {MAX_TRIANGLES} triangles")));
        }
        let p: Vec<Vec3> = mesh.positions.iter().map(|&v| to_world.transform_point3(v)).collect();
        if p.iter().any(|v| !v.is_finite()) {
            return Err(e.error("a transformed vertex is not finite".into()));
        }
        for t in &mesh.triangles {
            let t = if flip { [t[0], t[2], t[1]] } else { *t };
            let v = t.map(|i| p[i as usize]);
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
        let mesh = Rc::new(match ty {
            "obj" => self.reading(e, super::obj::load_obj_mesh(&path, flip))?,
            "ply" => self.reading(e, super::ply::load_ply(&path))?,
            _ => self.reading(e, super::serialized::load_serialized(&path, index))?,
        });
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
        let tex = self.reading(e, load_texture(&spec.path, spec.srgb))?;
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
        let mut scene = self.b.build().map_err(|e| match e {
            Error::InvalidScene(m) => root.error(m),
            e => e,
        })?;
        scene.warnings = warnings;
        Ok(scene)
    }
}
