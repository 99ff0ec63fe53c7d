//! MTL material libraries of OBJ scenes (SPEC §1), read with `tobj` through the checking line filter
//! (`obj_lines.rs`): `newmtl`, `Kd`, `Ke` and `map_Kd`; what a renderer of the file would have shown
//! and plie does not (a specular colour, a missing texture) is noted for the scene's warnings. Numbers
//! that are not finite are errors in every statement that holds numbers (`Kd`, `Ke`, `Ns`, `d`, `Tr`, ...),
//! also in those plie ignores. See `obj.rs` for the whole format.

use std::cell::RefCell;
use std::collections::HashSet;
use std::fmt::Write as _;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::input::{open_regular, resolve_in_scene, short, LoadOptions, MAX_INPUT_BYTES};
use super::obj_lines::{parse_finite, rest_after_keyword, strip_comment, LineFilter, LineRules};
use super::parse_error;
use crate::error::Error;
use crate::scene::Material;

/// State shared by the OBJ filter and the MTL loader.
#[derive(Default)]
pub(super) struct Libraries {
    /// Materials defined by the libraries loaded so far.
    pub(super) names: HashSet<String>,
    /// `mtllib` names seen so far.
    pub(super) libs: Vec<String>,
    /// Line of the `mtllib` being loaded.
    pub(super) line: usize,
    /// The first error loading a library.
    pub(super) error: Option<Error>,
    /// MTL statements read but not rendered: (what, material).
    pub(super) ignored: Vec<(String, String)>,
    /// `map_Kd` textures: (material, file), the file resolved inside the scene's folder.
    pub(super) textures: Vec<(String, PathBuf)>,
    /// The material library files read, in order ([`crate::Scene::sources`]).
    pub(super) files: Vec<PathBuf>,
    /// How files named in the MTL files are confined.
    pub(super) opts: LoadOptions,
}

/// Checks MTL lines: `newmtl` (recording the name), `Kd` and `Ke`, and that numeric statements hold
/// finite numbers; drops the rest, noting in `libs` what a renderer of the file would have shown (a
/// specular colour, a texture).
struct MtlRules<'a> {
    libs: &'a RefCell<Libraries>,
    /// The MTL file's directory (texture paths are relative to it).
    dir: PathBuf,
    /// The material being read.
    material: String,
}

impl MtlRules<'_> {
    fn ignore(&self, what: String) {
        self.libs.borrow_mut().ignored.push((what, self.material.clone()));
    }
}

/// True for MTL statements whose values are numbers (colours, exponents, dissolve, ...). plie reads `Kd`
/// and `Ke` and drops the others, but a non-finite value (`d nan`, `Ns inf`, `Tr 1e39`) in any of them is
/// an error, as in a vertex: the file is broken.
fn is_numeric(keyword: &str) -> bool {
    const NUMERIC: &str = "Ka Kd Ks Ke Kt Tf Ns Ni d Tr sharpness Pr Pm Ps Pc Pcr aniso anisor";
    NUMERIC.split(' ').any(|k| k == keyword)
}

/// An error for the first word of a numeric statement's values that reads as a number but is not finite.
/// Words that are not numbers (`Tf xyz ...`, `d -halo 0.5`) are left to the statement's own rules.
fn check_finite<'a>(keyword: &str, mut values: impl Iterator<Item = &'a str>) -> Result<(), String> {
    match values.find(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite())) {
        Some(w) => Err(format!("{keyword} has a non-finite value '{}'", short(w))),
        None => Ok(()),
    }
}

impl LineRules for MtlRules<'_> {
    fn rewrite(&mut self, _line: usize, text: &str, out: &mut String) -> Result<(), String> {
        let text = strip_comment(text);
        let mut words = text.split_whitespace();
        let Some(keyword) = words.next() else { return Ok(()) };
        if is_numeric(keyword) {
            check_finite(keyword, words.clone())?;
        }
        match keyword {
            "newmtl" => {
                let name = rest_after_keyword(text, keyword);
                if name.is_empty() {
                    return Err("newmtl without a name".into());
                }
                self.libs.borrow_mut().names.insert(name.to_string());
                self.material = name.to_string();
                let _ = write!(out, "newmtl {name}");
            }
            "Ks" if words.any(|w| w.parse::<f32>().is_ok_and(|v| v != 0.0)) => {
                self.ignore("Ks (specular reflection) is not rendered: plie renders diffuse (Kd) only".into());
            }
            "map_Kd" => {
                let file = rest_after_keyword(text, keyword).split_whitespace().last().unwrap_or("");
                let opts = self.libs.borrow().opts;
                let path = resolve_in_scene(&self.dir, file, "map_Kd", opts)?;
                if path.is_file() {
                    self.libs.borrow_mut().textures.push((self.material.clone(), path));
                } else {
                    self.ignore("map_Kd texture file is missing: the flat Kd colour is used".into());
                }
            }
            "Kd" | "Ke" => {
                let tokens: Vec<&str> = words.take(4).collect();
                let rgb = match tokens[..] {
                    [x] => [x, x, x],
                    [r, g, b] => [r, g, b],
                    [first, ..] if first == "spectral" || first == "xyz" => {
                        return Err(format!("{keyword} {first} is not supported; give r g b"))
                    }
                    _ => return Err(format!("{keyword} needs 3 numbers (r g b), found {}", tokens.len())),
                };
                for t in rgb {
                    if parse_finite(t, || keyword)? < 0.0 && keyword == "Ke" {
                        return Err(format!("Ke has a negative value '{t}': emitted radiance cannot be negative"));
                    }
                }
                let _ = write!(out, "{keyword} {} {} {}", rgb[0], rgb[1], rgb[2]);
            }
            _ => {}
        }
        Ok(())
    }
}

/// The `tobj` material loader: loads the library (or libraries) named on one `mtllib` line. Errors are
/// kept in `libs` (tobj would only keep a bare error kind and go on).
pub(super) fn load_libraries(
    obj: &Path,
    dir: &Path,
    lib: &Path,
    libs: &RefCell<Libraries>,
    opts: LoadOptions,
) -> tobj::MTLLoadResult {
    let name = lib.to_string_lossy();
    let names: Vec<&str> = if dir.join(lib).is_file() || !name.contains(char::is_whitespace) {
        vec![&name]
    } else {
        name.split_whitespace().collect()
    };
    let line = libs.borrow().line;
    let mut files: Vec<PathBuf> = Vec::new();
    for n in names {
        let file = resolve_in_scene(dir, n, "mtllib", opts).map_err(|m| {
            libs.borrow_mut().error.get_or_insert(parse_error(obj, Some(line), m));
            tobj::LoadError::OpenFileFailed
        })?;
        files.push(file);
    }
    let (mut all, mut map): (Vec<tobj::Material>, _) = (Vec::new(), Default::default());
    for file in files {
        let (mut mats, names) = load_library(obj, &file, libs)?;
        let offset = all.len();
        all.append(&mut mats);
        for (k, i) in names {
            tobj_insert(&mut map, k, i + offset);
        }
    }
    Ok((all, map))
}

/// Inserts into `tobj`'s material name map, whatever map type it uses.
fn tobj_insert<M: Extend<(String, usize)>>(map: &mut M, name: String, index: usize) {
    map.extend(std::iter::once((name, index)));
}

/// Loads one MTL file; an error is kept in `libs` and `tobj` gets only its kind.
fn load_library(obj: &Path, file: &Path, libs: &RefCell<Libraries>) -> tobj::MTLLoadResult {
    let fail = |e: Error| {
        libs.borrow_mut().error.get_or_insert(e);
        tobj::LoadError::OpenFileFailed
    };
    let line = libs.borrow().line;
    let f = open_regular(file, MAX_INPUT_BYTES)
        .map_err(|e| fail(parse_error(obj, Some(line), format!("mtllib: cannot open material library {e}"))))?;
    libs.borrow_mut().files.push(file.to_path_buf());
    let dir = file.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut reader = LineFilter::new(BufReader::new(f), MtlRules { libs, dir, material: String::new() });
    let result = tobj::load_mtl_buf(&mut reader);
    if let Some((l, message)) = reader.error() {
        let e = parse_error(file, Some(*l), message.clone());
        return Err(fail(e));
    }
    result.map_err(|e| fail(parse_error(file, Some(reader.line()), e.to_string())))
}

/// Our material for a `tobj` material index (`None`: faces before any `usemtl`).
pub(super) fn material(materials: &[tobj::Material], id: Option<usize>) -> Material {
    match id.and_then(|i| materials.get(i)) {
        None => Material::diffuse("default", Vec3::splat(0.8)),
        Some(m) => Material {
            name: m.name.clone(),
            albedo: m.diffuse.map_or(Vec3::splat(0.8), Vec3::from).clamp(Vec3::ZERO, Vec3::ONE),
            emission: m.emissive.map_or(Vec3::ZERO, Vec3::from),
            texture: None,
        },
    }
}
