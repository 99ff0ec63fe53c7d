//! glTF 2.0 scenes (`.gltf` with external or embedded buffers, `.glb`), SPEC §1 scene model, read with
//! the `gltf` crate.
//!
//! What is read: every mesh primitive of the default scene (or the first scene) with its node transform
//! applied, in world space; modes TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN, indexed or not; a node
//! transform with negative determinant flips the winding (glTF rule). Material: base colour factor as
//! albedo, times the `baseColorTexture` (sRGB, with its sampler's wrap modes and nearest or bilinear
//! magnification filter, at the primitive's `TEXCOORD_n`; an image from a file in the scene's folder, a
//! data URI or a buffer view) where the primitive has texture coordinates; emissive textures and
//! metallic-roughness are ignored and reported in [`Scene::warnings`];
//! `emissiveFactor` x `KHR_materials_emissive_strength` as emitted radiance;
//! primitives without material get a grey default (albedo 0.8). The first perspective camera met in a
//! depth-first walk of the scene becomes the scene camera (position, `-z` as view direction and `+y` as
//! up from its node transform, `yfov` in degrees). Skins and morph targets are ignored: meshes are
//! taken in their rest pose.
//!
//! Errors name the file and what is wrong (JSON syntax errors also the line). The `gltf` crate trusts
//! accessor types and ranges (it panics or asserts on bad ones), so every accessor is checked first:
//! type, count, stride and byte range within its buffer view and buffer. Sparse accessors, quantized
//! (non-float) positions and point/line primitives are rejected with a clear error, as is a GLB whose
//! header gives another length than the file's.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::{Accessor, Document, Semantic};
use glam::{Mat4, Vec2, Vec3};

use super::input::{read_bounded, resolve_in_scene, short, LoadOptions, MAX_INPUT_BYTES};
use super::lights::{self, EmissiveTriangle};
use super::texture_file::TextureFiles;
use super::{material_warnings, parse_error, scene_name};
use crate::error::{Error, Result, SceneElement};
use crate::scene::texture::{Filter, Texture, Wrap};
use crate::scene::{Camera, Material, MaterialId, Scene, SceneBuilder};

/// Loads a `.gltf` or `.glb` file (see the module doc); buffers only from the file's folder.
pub fn load_gltf(path: &Path) -> Result<Scene> {
    load_gltf_with(path, LoadOptions::default())
}

/// [`load_gltf`] with options.
pub fn load_gltf_with(path: &Path, opts: LoadOptions) -> Result<Scene> {
    let bad = |m: String| parse_error(path, None, m);
    let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
    if bytes.is_empty() {
        return Err(bad("the file is empty".into()));
    }
    check_glb_header(&bytes).map_err(bad)?;
    let raw = ::gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| gltf_error(path, e))?;
    check_primitive_indices(path, raw.document.as_json())?;
    let document = ::gltf::Document::from_json(raw.document.into_json()).map_err(|e| gltf_error(path, e))?;
    let gltf = ::gltf::Gltf { document, blob: raw.blob };
    let (buffers, buffer_files) = load_buffers(path, &gltf.document, gltf.blob.clone(), opts)?;
    let doc = &gltf.document;
    let scene =
        doc.default_scene().or_else(|| doc.scenes().next()).ok_or_else(|| bad("the file has no scene".into()))?;
    let mut builder = SceneBuilder::new(&scene_name(path));
    builder.source(path);
    for f in &buffer_files {
        builder.source(f);
    }
    let mut loader = Loader {
        builder,
        buffers: &buffers,
        dir: path.parent().unwrap_or(Path::new("")),
        opts,
        tex_coord: vec![0; doc.materials().len() + 1],
        materials: vec![None; doc.materials().len() + 1],
        emissive: Vec::new(),
        emissive_info: Vec::new(),
        camera: None,
        ignored: Vec::new(),
        texture_files: TextureFiles::default(),
        images: HashMap::new(),
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(::gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(in_node(path, &node, "appears twice in the scene graph (a cycle or two parents)".into()));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                loader.primitive(&mesh, &prim, world).map_err(|message| Error::SceneElement {
                    path: path.to_path_buf(),
                    element: primitive_element(&mesh, &prim),
                    message,
                })?;
            }
        }
        if loader.camera.is_none() {
            loader.camera(&node, world).map_err(|m| in_node(path, &node, m))?;
        }
        stack.extend(node.children().map(|c| (c, world)).collect::<Vec<_>>().into_iter().rev());
    }
    loader.finish(path)
}

/// `prim` of `mesh` as a [`SceneElement`] (errors and warnings name it).
fn primitive_element(mesh: &::gltf::Mesh, prim: &::gltf::Primitive) -> SceneElement {
    SceneElement::Primitive { mesh: mesh.index(), name: mesh.name().map(str::to_string), primitive: prim.index() }
}

/// An error in `node`.
fn in_node(path: &Path, node: &::gltf::Node, message: String) -> Error {
    Error::SceneElement { path: path.to_path_buf(), element: SceneElement::Node(node.index()), message }
}

/// An error of the `gltf` crate as a parse error (with the JSON line for syntax errors).
fn gltf_error(path: &Path, e: ::gltf::Error) -> Error {
    match e {
        ::gltf::Error::Deserialize(e) => {
            parse_error(path, (e.line() > 0).then_some(e.line()), format!("malformed glTF JSON: {e}"))
        }
        ::gltf::Error::Validation(errors) => {
            let list: Vec<String> = errors.iter().take(5).map(|(p, e)| format!("{}: {e}", p.as_str())).collect();
            parse_error(path, None, format!("invalid glTF: {}", list.join("; ")))
        }
        e => parse_error(path, None, format!("invalid glTF: {e}")),
    }
}

/// The `gltf` crate's validation indexes the accessors of every primitive's `POSITION` unchecked (an
/// index-out-of-bounds panic in `gltf-json`): check every accessor index of a primitive first.
fn check_primitive_indices(path: &Path, root: &::gltf::json::Root) -> Result<()> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let attrs = prim.attributes.iter().map(|(sem, i)| (format!("attribute {}", semantic_name(sem)), i.value()));
            let all = attrs.chain(prim.indices.map(|i| ("indices".to_string(), i.value())));
            for (what, i) in all {
                if i >= n {
                    return Err(Error::SceneElement {
                        path: path.to_path_buf(),
                        element: SceneElement::Primitive { mesh: m, name: mesh.name.clone(), primitive: p },
                        message: format!("{what} names accessor {i}, but the file has {n} accessors"),
                    });
                }
            }
        }
    }
    Ok(())
}

/// The glTF name of an attribute semantic (`POSITION`, `NORMAL`, ...).
fn semantic_name(sem: &::gltf::json::validation::Checked<Semantic>) -> String {
    match sem {
        ::gltf::json::validation::Checked::Valid(s) => s.to_string(),
        ::gltf::json::validation::Checked::Invalid => "(unknown)".to_string(),
    }
}

/// The `gltf` crate subtracts the header size from the GLB's length field unchecked (an overflow
/// panic in debug builds) and ignores bytes after that length: check the header first. The length must
/// be the file's: a longer one means the file is truncated, a shorter one that bytes were appended or
/// the header is corrupt.
fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let Some(length) = bytes.get(8..12) else { return Err("truncated GLB header".into()) };
    let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
    if length < 20 || length as usize != bytes.len() {
        return Err(format!("GLB header says {length} bytes, but the file has {}", bytes.len()));
    }
    Ok(())
}

/// Reads every buffer (GLB chunk, data URI or external file), naming the buffer that fails; the
/// buffers and the external files read.
fn load_buffers(
    path: &Path,
    doc: &Document,
    mut blob: Option<Vec<u8>>,
    opts: LoadOptions,
) -> Result<(Vec<::gltf::buffer::Data>, Vec<PathBuf>)> {
    let base = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    let mut files = Vec::new();
    for buffer in doc.buffers() {
        let what = match buffer.source() {
            ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                format!("buffer {} (data URI)", buffer.index())
            }
            ::gltf::buffer::Source::Uri(uri) => format!("buffer {} ('{}')", buffer.index(), short(uri)),
            ::gltf::buffer::Source::Bin => format!("buffer {} (GLB binary chunk)", buffer.index()),
        };
        let data = match buffer.source() {
            // Files are read here, not by the crate: confined to the scene's folder and bounded.
            ::gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                let Ok(decoded) = urlencoding::decode(uri) else {
                    return Err(parse_error(
                        path,
                        None,
                        format!("{what}: the URI is not UTF-8 after percent-decoding"),
                    ));
                };
                let label = format!("buffer {} URI", buffer.index());
                let file = resolve_in_scene(base, &decoded, &label, opts).map_err(|m| parse_error(path, None, m))?;
                let bytes = read_bounded(&file, MAX_INPUT_BYTES).map_err(|e| match e {
                    Error::Io { source, .. } => parse_error(path, None, format!("cannot load {what}: {source}")),
                    e => parse_error(path, None, format!("cannot load {what}: {e}")),
                })?;
                files.push(file);
                ::gltf::buffer::Data(bytes)
            }
            source => ::gltf::buffer::Data::from_source_and_blob(source, Some(base), &mut blob).map_err(|e| {
                let m = match e {
                    ::gltf::Error::Base64(_) => "the data URI is not valid base64".to_string(),
                    e => e.to_string(),
                };
                parse_error(path, None, format!("cannot load {what}: {m}"))
            })?,
        };
        if data.len() < buffer.length() {
            let m = format!("{what} has {} bytes, but byteLength is {}", data.len(), buffer.length());
            return Err(parse_error(path, None, m));
        }
        out.push(data);
    }
    Ok((out, files))
}

/// Checks that the `gltf` crate can read `acc` safely: not sparse, count >= 1, a type `ok` accepts, a
/// stride no smaller than an element, and every byte inside its buffer view and buffer.
fn check_accessor(
    acc: &Accessor,
    buffers: &[::gltf::buffer::Data],
    expected: &str,
    ok: impl Fn(DataType, Dimensions) -> bool,
) -> Result<(), String> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(format!("accessor {i} is sparse; sparse accessors are not supported"));
    }
    if !ok(acc.data_type(), acc.dimensions()) {
        return Err(format!("accessor {i} is {:?} of {:?}; expected {expected}", acc.dimensions(), acc.data_type()));
    }
    let Some(view) = acc.view() else { return Err(format!("accessor {i} has no bufferView")) };
    let count = acc.count();
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    if count == 0 {
        return Err(format!("accessor {i} has count 0"));
    }
    if stride < elem {
        return Err(format!(
            "bufferView {} has byteStride {stride}, less than an element ({elem} bytes)",
            view.index()
        ));
    }
    let end = stride.checked_mul(count - 1).and_then(|s| s.checked_add(acc.offset())).and_then(|s| s.checked_add(elem));
    if end.is_none_or(|e| e > view.length()) {
        return Err(format!("accessor {i} reads past the end of bufferView {}", view.index()));
    }
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, |d| d.len());
    if view.offset().checked_add(view.length()).is_none_or(|e| e > buffer_len) {
        return Err(format!("bufferView {} reads past the end of buffer {}", view.index(), view.buffer().index()));
    }
    Ok(())
}

/// Scene under construction.
struct Loader<'a> {
    builder: SceneBuilder,
    buffers: &'a [::gltf::buffer::Data],
    /// The scene's folder (image files) and how files are confined.
    dir: &'a Path,
    opts: LoadOptions,
    /// The `TEXCOORD_n` set of each material's base colour texture.
    tex_coord: Vec<u32>,
    /// Our material of each glTF material (last slot: the default material).
    materials: Vec<Option<(MaterialId, Material)>>,
    emissive: Vec<EmissiveTriangle>,
    /// Primitive description and triangle number of each emissive triangle, for errors.
    emissive_info: Vec<(String, usize)>,
    camera: Option<Camera>,
    /// Material features read but not rendered: (what, material) ([`Scene::warnings`]).
    ignored: Vec<(String, String)>,
    /// Image files decoded (each once) and the budget of texels.
    texture_files: TextureFiles,
    /// The decoded image of each glTF image index used so far (materials share them).
    images: HashMap<usize, Texture>,
}

impl Loader<'_> {
    /// Adds the triangles of one primitive, transformed by `world`.
    fn primitive(&mut self, mesh: &::gltf::Mesh, prim: &::gltf::Primitive, world: Mat4) -> Result<(), String> {
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            return Err(format!("mode {mode:?} is not a triangle mode (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN)"));
        }
        let pos_acc = prim.get(&Semantic::Positions).ok_or("no POSITION attribute")?;
        check_accessor(&pos_acc, self.buffers, "Vec3 of F32", |t, d| t == DataType::F32 && d == Dimensions::Vec3)?;
        let buffers = self.buffers;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<Vec3> =
            reader.read_positions().ok_or("cannot read POSITION")?.map(|p| world.transform_point3(p.into())).collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} has a non-finite coordinate {}", positions[i]));
        }
        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => {
                let ok = |t, d| matches!(t, DataType::U8 | DataType::U16 | DataType::U32) && d == Dimensions::Scalar;
                check_accessor(&acc, self.buffers, "Scalar of U8, U16 or U32", ok)?;
                reader.read_indices().ok_or("cannot read indices")?.into_u32().collect()
            }
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!("index {i} out of range: {} vertices", positions.len()));
        }
        if mode == Mode::Triangles && indices.len() % 3 != 0 {
            return Err(format!("{} indices (vertices) is not a multiple of 3 for TRIANGLES", indices.len()));
        }
        let flip = world.determinant() < 0.0;
        let (mut m, mat) = self.material(prim.material())?;
        let uvs = match mat.texture {
            Some(_) => self.tex_coords(prim, &reader, positions.len())?,
            None => None,
        };
        if mat.texture.is_some() && uvs.is_none() {
            m = self.builder.material(Material { texture: None, ..mat.clone() });
            let what = "baseColorTexture on a primitive without its TEXCOORD attribute: the flat colour factor is used";
            self.ignored.push((what.to_string(), mat.name.clone()));
        }
        for (k, t) in triangles(mode, &indices).enumerate() {
            let t = if flip { [t[0], t[2], t[1]] } else { t };
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let id = match &uvs {
                Some(uv) => self.builder.triangle_uv([a, b, c], t.map(|i| uv[i as usize]), m),
                None => self.builder.triangle(a, b, c, m),
            };
            if mat.is_emissive() {
                self.emissive.push(EmissiveTriangle { id, vertices: [a, b, c], radiance: mat.emission });
                self.emissive_info.push((primitive_element(mesh, prim).to_string(), k));
            }
        }
        Ok(())
    }

    /// Our material for a glTF material, created on first use.
    fn material(&mut self, m: ::gltf::Material) -> Result<(MaterialId, Material), String> {
        let slot = m.index().unwrap_or(self.materials.len() - 1);
        if let Some(done) = &self.materials[slot] {
            return Ok(done.clone());
        }
        let mat = match m.index() {
            None => Material::diffuse("default", Vec3::splat(0.8)),
            Some(i) => {
                let pbr = m.pbr_metallic_roughness();
                let base = pbr.base_color_factor();
                let name = m.name().map_or_else(|| format!("material {i}"), str::to_string);
                if pbr.metallic_factor() > 0.0 || pbr.metallic_roughness_texture().is_some() {
                    let what = "metallic-roughness is not rendered: the base colour is shaded as a diffuse surface";
                    self.ignored.push((what.to_string(), name.clone()));
                }
                if m.emissive_texture().is_some() {
                    let what = "emissive textures are not rendered: the flat emissive factor is used";
                    self.ignored.push((what.to_string(), name.clone()));
                }
                let texture = match pbr.base_color_texture() {
                    Some(info) => {
                        self.tex_coord[slot] = info.tex_coord();
                        Some(self.texture(info.texture()).map_err(|e| format!("material {i}: {e}"))?)
                    }
                    None => None,
                };
                let strength = m.emissive_strength().unwrap_or(1.0);
                let emission = Vec3::from(m.emissive_factor()) * strength;
                if !emission.is_finite() || strength.is_nan() || strength < 0.0 {
                    return Err(format!(
                        "material {i}: emissiveFactor {} times KHR_materials_emissive_strength.emissiveStrength {strength} must be finite and non-negative (at most {:e} in f32)",
                        Vec3::from(m.emissive_factor()),
                        f32::MAX
                    ));
                }
                Material {
                    name,
                    albedo: Vec3::new(base[0], base[1], base[2]).clamp(Vec3::ZERO, Vec3::ONE),
                    emission,
                    texture,
                }
            }
        };
        let id = self.builder.material(mat.clone());
        self.materials[slot] = Some((id, mat.clone()));
        Ok((id, mat))
    }

    /// Decodes a texture's image (sRGB) with its sampler's wrap modes and filter.
    fn texture(&mut self, t: ::gltf::Texture) -> Result<crate::scene::TextureId, String> {
        use ::gltf::texture::{MagFilter, WrappingMode};
        let image = t.source();
        let mut tex = match self.images.get(&image.index()) {
            Some(tex) => tex.clone(),
            None => {
                let tex = self.image(&image)?;
                self.images.insert(image.index(), tex.clone());
                tex
            }
        };
        let sampler = t.sampler();
        let wrap = |w: WrappingMode| match w {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::MirroredRepeat => Wrap::Mirror,
            WrappingMode::ClampToEdge => Wrap::Clamp,
        };
        tex.wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
        tex.filter = if sampler.mag_filter() == Some(MagFilter::Nearest) { Filter::Nearest } else { Filter::Bilinear };
        Ok(self.builder.texture(tex))
    }

    /// Decodes an image (sRGB): from a buffer view, a data URI or a file of the scene's folder.
    fn image(&mut self, image: &::gltf::Image) -> Result<Texture, String> {
        use ::gltf::image::Source;
        let what = format!("image {}", image.index());
        let bytes = match image.source() {
            Source::View { view, .. } => {
                let data = self.buffers.get(view.buffer().index()).map(|d| &d.0[..]).unwrap_or(&[]);
                let end = view.offset().checked_add(view.length()).filter(|&e| e <= data.len());
                let end = end.ok_or_else(|| format!("{what}: bufferView {} reads past its buffer", view.index()))?;
                data[view.offset()..end].to_vec()
            }
            Source::Uri { uri, .. } if uri.starts_with("data:") => {
                let b64 = uri
                    .split_once(";base64,")
                    .map(|(_, d)| d)
                    .ok_or_else(|| format!("{what}: a data URI without base64"))?;
                base64::decode(b64).map_err(|_| format!("{what}: the data URI is not valid base64"))?
            }
            Source::Uri { uri, .. } => {
                let decoded = urlencoding::decode(uri).map_err(|_| format!("{what}: the URI is not UTF-8"))?;
                let file = resolve_in_scene(self.dir, &decoded, &format!("{what} URI"), self.opts)?;
                let tex = self.texture_files.load(&file, true).map_err(|e| format!("{what}: {e}"))?;
                self.builder.source(&file);
                return Ok(Texture { name: short(&decoded), ..tex });
            }
        };
        self.texture_files.decode(&what, bytes, true).map_err(|e| format!("{what}: {e}"))
    }

    /// The primitive's texture coordinates for its material's base colour texture, if it has them.
    fn tex_coords<'s, F>(
        &self,
        prim: &::gltf::Primitive,
        reader: &::gltf::mesh::Reader<'s, 's, F>,
        n: usize,
    ) -> Result<Option<Vec<Vec2>>, String>
    where
        F: Clone + Fn(::gltf::Buffer<'s>) -> Option<&'s [u8]>,
    {
        let slot = prim.material().index().unwrap_or(self.tex_coord.len() - 1);
        let set = self.tex_coord[slot];
        let Some(acc) = prim.get(&Semantic::TexCoords(set)) else { return Ok(None) };
        let ok = |t, d| matches!(t, DataType::F32 | DataType::U8 | DataType::U16) && d == Dimensions::Vec2;
        check_accessor(&acc, self.buffers, "Vec2 of F32, U8 or U16", ok)?;
        let uv: Vec<Vec2> = match reader.read_tex_coords(set) {
            Some(r) => r.into_f32().map(Vec2::from).collect(),
            None => return Ok(None),
        };
        if uv.len() != n {
            return Err(format!("TEXCOORD_{set} has {} elements for {n} vertices", uv.len()));
        }
        Ok(Some(uv))
    }

    /// Takes the node's camera if it is perspective.
    fn camera(&mut self, node: &::gltf::Node, world: Mat4) -> Result<(), String> {
        let Some(cam) = node.camera() else { return Ok(()) };
        let ::gltf::camera::Projection::Perspective(p) = cam.projection() else { return Ok(()) };
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y);
        let c = Camera::new(eye, eye + forward, up, p.yfov().to_degrees())
            .map_err(|e| format!("camera {}: {e}", cam.index()))?;
        self.camera = Some(c);
        Ok(())
    }

    /// Groups the lights and builds the scene.
    fn finish(mut self, path: &Path) -> Result<Scene> {
        if self.builder.triangle_count() == 0 {
            return Err(parse_error(path, None, "no triangles: the default scene has no triangle meshes".into()));
        }
        if self.emissive.is_empty() {
            let m = "no lights: no primitive has an emissive material (emissiveFactor > 0)".to_string();
            return Err(parse_error(path, None, m));
        }
        lights::add_lights(&mut self.builder, &self.emissive).map_err(|z| {
            let (prim, k) = &self.emissive_info[z.index];
            parse_error(path, None, format!("{prim}: emissive triangle {k} has zero area: a light must have an area"))
        })?;
        if let Some(c) = self.camera {
            self.builder.camera(c);
        }
        let mut scene = self.builder.build().map_err(|e| match e {
            Error::InvalidScene(m) => parse_error(path, None, m),
            e => e,
        })?;
        scene.warnings = material_warnings(&self.ignored);
        Ok(scene)
    }
}

/// The triangles of a primitive's index list, counter-clockwise, for its mode (glTF 2.0 §3.7.2.1).
fn triangles(mode: Mode, idx: &[u32]) -> Box<dyn Iterator<Item = [u32; 3]> + '_> {
    let n = idx.len();
    match mode {
        Mode::TriangleStrip => Box::new((0..n.saturating_sub(2)).map(move |i| {
            if i % 2 == 0 {
                [idx[i], idx[i + 1], idx[i + 2]]
            } else {
                [idx[i], idx[i + 2], idx[i + 1]]
            }
        })),
        Mode::TriangleFan => Box::new((1..n.saturating_sub(1)).map(move |i| [idx[i], idx[i + 1], idx[0]])),
        _ => Box::new(idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_the_winding() {
        let strip: Vec<_> = triangles(Mode::TriangleStrip, &[0, 1, 2, 3]).collect();
        assert_eq!(strip, [[0, 1, 2], [1, 3, 2]]);
        let fan: Vec<_> = triangles(Mode::TriangleFan, &[0, 1, 2, 3]).collect();
        assert_eq!(fan, [[1, 2, 0], [2, 3, 0]]);
        assert_eq!(triangles(Mode::Triangles, &[0, 1, 2, 3]).count(), 1);
    }
}
