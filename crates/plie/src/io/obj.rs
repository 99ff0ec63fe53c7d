//! Wavefront OBJ + MTL scenes (SPEC §1 scene model), read with `tobj` through a checking line filter
//! (`obj_lines.rs`).
//!
//! What is read: `v` (with an optional `w`, which divides; vertex colours are ignored), `vt` (texture
//! coordinates; a malformed one reads as (0, 0), as they were once ignored), `f` (polygons are
//! fan-triangulated; positive and negative indices; texture indices are kept where every corner of the
//! face has one; normal indices are only checked), `o`/`g`, `mtllib` (paths relative to the OBJ;
//! several names on one line are allowed), `usemtl`, and in the MTL files `newmtl`, `Kd` (diffuse
//! albedo, clamped to [0, 1]), `Ke` (emitted radiance) and `map_Kd` (a texture the albedo is multiplied
//! by, issue 18: sRGB, bilinear, repeating; `v` flipped, since OBJ puts `v = 0` at the image's bottom;
//! its file confined to the scene's folder like `mtllib`). A repeated `Kd` in one material: the last
//! one counts, as in other OBJ readers. Everything else (normals, `Ka`, `Ks`, `d`, `Tr`, other maps,
//! lines, points) is ignored: surfaces are opaque and Lambertian; a non-zero `Ks`, a missing `map_Kd`
//! file and a `map_Kd` on faces without texture coordinates (which would change how the scene looks)
//! are reported in [`Scene::warnings`]. An emissive triangle emits on the side its counter-clockwise
//! winding faces; vertex normals are not used. Emissive triangles are grouped into lights by
//! [`super::lights`]. [`load_obj_mesh`] reads an OBJ's geometry alone (for Mitsuba scenes).
//!
//! Faces before any `usemtl` get a grey default material (albedo 0.8). Everything that would make a
//! scene silently differ from its file is an error naming the file and line: a `mtllib` that cannot be
//! read, a `usemtl` naming a material no library defines, a malformed number, a malformed or
//! out-of-range index (vertex, texture coordinate or normal), a non-finite number (also in the MTL
//! files), a face with fewer than 3 vertices, an empty file, a file without lights. Lines may end in
//! `\n`, `\r\n` or a lone `\r`; a UTF-8 byte-order mark at the start is skipped (`obj_lines.rs`).

use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::BufReader;
use std::path::Path;
use std::str::SplitWhitespace;

use glam::{Vec2, Vec3};

use super::input::{open_regular, short, LoadOptions, MAX_INPUT_BYTES};
use super::lights::{self, EmissiveTriangle};
use super::mtl::{load_libraries, material, Libraries};
use super::obj_lines::{parse_finite, rest_after_keyword, strip_comment, LineFilter, LineRules};
use super::texture_file::TextureFiles;
use super::tri_mesh::TriMesh;
use super::{material_warnings, parse_error, scene_name};
use crate::error::{Error, Result};
use crate::scene::{Material, MaterialId, Scene, SceneBuilder, TextureId};

/// Loads an OBJ file and the MTL files it names (see the module doc), the MTL files only from the
/// OBJ's folder.
pub fn load_obj(path: &Path) -> Result<Scene> {
    load_obj_with(path, LoadOptions::default())
}

/// [`load_obj`] with options.
pub fn load_obj_with(path: &Path, opts: LoadOptions) -> Result<Scene> {
    let file = open_regular(path, MAX_INPUT_BYTES)?;
    let libs = RefCell::new(Libraries { opts, ..Default::default() });
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut reader = LineFilter::new(BufReader::new(file), ObjRules::new(&libs));
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let result = tobj::load_obj_buf(&mut reader, &options, |lib| load_libraries(path, dir, lib, &libs, opts));
    if let Some(e) = libs.borrow_mut().error.take() {
        return Err(e);
    }
    if let Some((line, message)) = reader.error() {
        return Err(parse_error(path, Some(*line), message.clone()));
    }
    let (models, materials) = result.map_err(|e| parse_error(path, Some(reader.line()), e.to_string()))?;
    let materials = materials.map_err(|e| parse_error(path, None, format!("material library: {e}")))?;
    if reader.line() == 0 {
        return Err(parse_error(path, None, "the file is empty".into()));
    }
    let mut libs = libs.borrow_mut();
    let mut scene = build(path, &models, &materials, &reader.rules.tri_lines, &mut libs)?;
    scene.warnings = material_warnings(&libs.ignored);
    Ok(scene)
}

/// Loads an OBJ file's geometry only (a mesh a Mitsuba scene names): positions, faces and texture
/// coordinates (`v` flipped, so `(0, 0)` is the image's top-left corner as [`crate::scene::texture`]
/// expects, unless `flip_v` is false); `mtllib`, `usemtl` and materials are ignored.
pub fn load_obj_mesh(path: &Path, flip_v: bool) -> Result<TriMesh> {
    let file = open_regular(path, MAX_INPUT_BYTES)?;
    let libs = RefCell::new(Libraries::default());
    let mut rules = ObjRules::new(&libs);
    rules.mesh_only = true;
    let mut reader = LineFilter::new(BufReader::new(file), rules);
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let result = tobj::load_obj_buf(&mut reader, &options, |_| Err(tobj::LoadError::OpenFileFailed));
    if let Some((line, message)) = reader.error() {
        return Err(parse_error(path, Some(*line), message.clone()));
    }
    let (models, _) = result.map_err(|e| parse_error(path, Some(reader.line()), e.to_string()))?;
    let mut mesh = TriMesh::default();
    let all_uv = models.iter().all(|m| has_uvs(&m.mesh));
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        if all_uv {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], if flip_v { 1.0 - t[1] } else { t[1] })));
        }
        let n = mesh.positions.len() as u32;
        for t in m.indices.chunks_exact(3) {
            let t = [t[0] + base, t[1] + base, t[2] + base];
            if t.iter().any(|&i| i >= n) {
                return Err(parse_error(path, None, "face vertex index out of range".into()));
            }
            mesh.triangles.push(t);
        }
    }
    if mesh.triangles.is_empty() {
        return Err(parse_error(path, None, "no faces: the file defines no triangles".into()));
    }
    Ok(mesh)
}

/// True if `tobj` gave every vertex of the mesh texture coordinates.
fn has_uvs(m: &tobj::Mesh) -> bool {
    !m.texcoords.is_empty() && m.texcoords.len() / 2 == m.positions.len() / 3
}

/// Checks OBJ lines (module doc) and keeps what the loader needs to name lines later.
struct ObjRules<'a> {
    libs: &'a RefCell<Libraries>,
    vertices: usize,
    /// Texture coordinates (`vt`) so far.
    texcoords: usize,
    /// Normals (`vn`) so far: only counted, so that normal indices can be checked.
    normals: usize,
    /// Geometry only (a mesh a Mitsuba scene names): `mtllib` and `usemtl` are dropped.
    mesh_only: bool,
    /// The line of every triangle `tobj` will produce, in order.
    tri_lines: Vec<u32>,
    /// Scratch of [`ObjRules::face`]: each corner's vertex and texture index.
    corners: Vec<(u64, Option<u64>)>,
}

impl<'a> ObjRules<'a> {
    fn new(libs: &'a RefCell<Libraries>) -> Self {
        ObjRules {
            libs,
            vertices: 0,
            texcoords: 0,
            normals: 0,
            mesh_only: false,
            tri_lines: Vec::new(),
            corners: Vec::new(),
        }
    }

    fn vertex(&mut self, words: SplitWhitespace, out: &mut String) -> Result<(), String> {
        self.vertices += 1;
        let n = self.vertices;
        let (mut tokens, mut count) = ([""; 7], 0);
        for word in words.take(8) {
            if let Some(slot) = tokens.get_mut(count) {
                *slot = word;
            }
            count += 1;
        }
        let what = || format!("vertex {n}");
        match count {
            3 | 6 => {
                out.push('v');
                for t in &tokens[..3] {
                    parse_finite(t, what)?;
                    out.push(' ');
                    out.push_str(t);
                }
            }
            4 => {
                let mut p = [0.0f32; 4];
                for (x, t) in p.iter_mut().zip(&tokens) {
                    *x = parse_finite(t, what)?;
                }
                if p[3] == 0.0 {
                    return Err(format!("vertex {n} has weight w = 0"));
                }
                let v = Vec3::new(p[0], p[1], p[2]) / p[3];
                if !v.is_finite() {
                    return Err(format!("vertex {n} is not finite after dividing by w = {}", p[3]));
                }
                let _ = write!(out, "v {} {} {}", v.x, v.y, v.z);
            }
            k => return Err(format!("vertex {n} has {k} numbers; expected x y z, x y z w or x y z r g b")),
        }
        Ok(())
    }

    fn texcoord(&mut self, words: SplitWhitespace, out: &mut String) -> Result<(), String> {
        self.texcoords += 1;
        let n = self.texcoords;
        let tokens: Vec<&str> = words.take(4).collect();
        let what = || format!("texture coordinate {n}");
        // Texture coordinates were ignored before textures were read: a malformed one still loads,
        // as (0, 0), so that every later index keeps its meaning.
        let (u, v) = match tokens[..] {
            [u] => (parse_finite(u, what).unwrap_or(0.0), 0.0),
            [u, v, ..] => (parse_finite(u, what).unwrap_or(0.0), parse_finite(v, what).unwrap_or(0.0)),
            _ => (0.0, 0.0),
        };
        let _ = write!(out, "vt {u} {v}");
        Ok(())
    }

    fn face(&mut self, line: usize, words: SplitWhitespace, out: &mut String) -> Result<(), String> {
        // (what the index names, how many of them are defined, their plural in messages)
        let v = ("vertex", self.vertices as u64, "vertices");
        let t = ("texture coordinate", self.texcoords as u64, "texture coordinates (vt)");
        let vn = ("normal", self.normals as u64, "normals (vn)");
        let resolve = |index: &str, (what, n, plural): (&str, u64, &str), token: &str| -> Result<u64, String> {
            let i: i64 = index.parse().map_err(|_| format!("malformed {what} index '{}' in a face", short(token)))?;
            match i {
                0 => Err(format!("{what} index 0 in a face (OBJ indices start at 1)")),
                i if i > 0 && i as u64 <= n => Ok(i as u64),
                i if i < 0 && i.unsigned_abs() <= n => Ok(n + 1 - i.unsigned_abs()),
                i => Err(format!("{what} index {i} out of range: {n} {plural} are defined before this line")),
            }
        };
        let corners = &mut self.corners;
        corners.clear();
        for token in words.clone() {
            let mut parts = token.split('/');
            let absolute = resolve(parts.next().unwrap_or(""), v, token)?;
            let uv = match parts.next() {
                Some(s) if !s.is_empty() => Some(resolve(s, t, token)?),
                _ => None,
            };
            // Normals are not used, but an index naming none is as wrong as a vertex index.
            if let Some(s) = parts.next().filter(|s| !s.is_empty()) {
                resolve(s, vn, token)?;
            }
            corners.push((absolute, uv));
        }
        // Texture indices only when every corner has one, so tobj's arrays stay parallel.
        let with_uv = corners.iter().all(|c| c.1.is_some());
        out.push('f');
        for (token, &(p, uv)) in words.zip(corners.iter()) {
            let mut parts = token.split('/');
            out.push(' ');
            push_index(out, parts.next().unwrap_or(""), p);
            if let (Some(uv), true) = (uv, with_uv) {
                out.push('/');
                push_index(out, parts.next().unwrap_or(""), uv);
            }
        }
        let k = corners.len();
        if k < 3 {
            return Err(format!("face with {k} vertices; a face needs at least 3"));
        }
        self.tri_lines.extend(std::iter::repeat_n(line as u32, k - 2));
        Ok(())
    }

    fn usemtl(&mut self, name: &str, out: &mut String) -> Result<(), String> {
        if name.is_empty() {
            return Err("usemtl without a material name".into());
        }
        let libs = self.libs.borrow();
        if !libs.names.contains(name) {
            return Err(if libs.libs.is_empty() {
                format!("usemtl '{}', but no mtllib comes before it: the material is not defined", short(name))
            } else {
                format!("usemtl '{}': no material of that name in {}", short(name), short(&libs.libs.join(", ")))
            });
        }
        let _ = write!(out, "usemtl {name}");
        Ok(())
    }
}

/// Writes the index `value` that the face token's part `text` resolved to: the text itself when it is
/// plain digits (it reads as `value`, as `tobj` would read it), else the number (a relative index).
fn push_index(out: &mut String, text: &str, value: u64) {
    if !text.is_empty() && text.bytes().all(|b| b.is_ascii_digit()) {
        out.push_str(text);
    } else {
        let _ = write!(out, "{value}");
    }
}

impl LineRules for ObjRules<'_> {
    fn rewrite(&mut self, line: usize, text: &str, out: &mut String) -> Result<(), String> {
        if self.libs.borrow().error.is_some() {
            return Err("reading stopped: a material library failed".into());
        }
        let text = strip_comment(text);
        let mut words = text.split_whitespace();
        let Some(keyword) = words.next() else { return Ok(()) };
        match keyword {
            "v" => self.vertex(words, out),
            "vt" => self.texcoord(words, out),
            "vn" => {
                self.normals += 1;
                Ok(())
            }
            "usemtl" | "mtllib" if self.mesh_only => Ok(()),
            "f" => self.face(line, words, out),
            "usemtl" => self.usemtl(rest_after_keyword(text, keyword), out),
            "mtllib" => {
                let name = rest_after_keyword(text, keyword);
                if name.is_empty() {
                    return Err("mtllib without a file name".into());
                }
                let mut libs = self.libs.borrow_mut();
                libs.line = line;
                libs.libs.push(name.to_string());
                let _ = write!(out, "mtllib {name}");
                Ok(())
            }
            "o" | "g" => {
                let _ = write!(out, "{keyword} {}", rest_after_keyword(text, keyword));
                Ok(())
            }
            _ => Ok(()),
        }
    }
}

/// Builds the scene from `tobj`'s meshes; `tri_lines` is the OBJ line of every triangle, in order;
/// `libs` what the material libraries gave (textures are loaded here, each file once).
fn build(
    path: &Path,
    models: &[tobj::Model],
    materials: &[tobj::Material],
    tri_lines: &[u32],
    libs: &mut Libraries,
) -> Result<Scene> {
    let has_mtllib = !libs.names.is_empty() || !libs.libs.is_empty();
    let ignored = &mut libs.ignored;
    let mut b = SceneBuilder::new(&scene_name(path));
    b.source(path);
    for f in &libs.files {
        b.source(f);
    }
    let mut files = TextureFiles::default();
    let mut by_file: HashMap<&Path, TextureId> = HashMap::new();
    let mut loaded: HashMap<&str, TextureId> = HashMap::new();
    for (material, file) in &libs.textures {
        let id = match by_file.get(file.as_path()) {
            Some(&id) => id,
            None => {
                let id = b.texture(files.load(file, true)?);
                b.source(file);
                by_file.insert(file, id);
                id
            }
        };
        loaded.insert(material.as_str(), id);
    }
    let mut ids: HashMap<Option<usize>, (MaterialId, Material)> = HashMap::new();
    let mut emissive = Vec::new();
    let mut emissive_info = Vec::new();
    let mut t = 0usize;
    for model in models {
        let mesh = &model.mesh;
        let (mut m, mat) = ids
            .entry(mesh.material_id)
            .or_insert_with(|| {
                let mut mat = material(materials, mesh.material_id);
                mat.texture = loaded.get(mat.name.as_str()).copied();
                (b.material(mat.clone()), mat)
            })
            .clone();
        let uvs = (mat.texture.is_some() && has_uvs(mesh)).then_some(&mesh.texcoords);
        if mat.texture.is_some() && uvs.is_none() {
            m = b.material(Material { texture: None, ..mat.clone() });
            ignored.push((
                "map_Kd on faces without texture coordinates (vt): the flat Kd colour is used there".into(),
                mat.name.clone(),
            ));
        }
        let uv = |i: u32| {
            let t = uvs.and_then(|t| t.get(i as usize * 2..i as usize * 2 + 2)).unwrap_or(&[0.0, 1.0]);
            Vec2::new(t[0], 1.0 - t[1])
        };
        let vertex = |i: u32| {
            let i = i as usize * 3;
            mesh.positions.get(i..i + 3).map(|p| Vec3::new(p[0], p[1], p[2]))
        };
        for tri in mesh.indices.chunks_exact(3) {
            let line = tri_lines.get(t).map(|&l| l as usize);
            t += 1;
            let (Some(a), Some(bb), Some(c)) = (vertex(tri[0]), vertex(tri[1]), vertex(tri[2])) else {
                return Err(parse_error(path, line, "face vertex index out of range".into()));
            };
            let id = match uvs {
                Some(_) => b.triangle_uv([a, bb, c], [uv(tri[0]), uv(tri[1]), uv(tri[2])], m),
                None => b.triangle(a, bb, c, m),
            };
            if mat.is_emissive() {
                emissive.push(EmissiveTriangle { id, vertices: [a, bb, c], radiance: mat.emission });
                emissive_info.push((line, mat.name.clone()));
            }
        }
    }
    if b.triangle_count() == 0 {
        return Err(parse_error(path, None, "no faces: the file defines no triangles".into()));
    }
    if emissive.is_empty() {
        let hint = if has_mtllib { "" } else { "; the file has no mtllib" };
        let message = format!("no lights: no face has an emissive material (Ke > 0 in an MTL file){hint}");
        return Err(parse_error(path, None, message));
    }
    lights::add_lights(&mut b, &emissive).map_err(|z| {
        let (line, name) = &emissive_info[z.index];
        parse_error(path, *line, format!("emissive face (material '{name}') has zero area: a light must have an area"))
    })?;
    b.build().map_err(|e| match e {
        Error::InvalidScene(m) => parse_error(path, None, m),
        e => e,
    })
}
