//! Stanford PLY meshes (issue 18; SPEC §1 scene input): ASCII and binary (little- and big-endian).
//!
//! Read: the `vertex` element's `x`, `y`, `z` and texture coordinates (`u`/`v`, `s`/`t` or
//! `texture_u`/`texture_v`), and the `face` element's index list (`vertex_indices` or `vertex_index`),
//! polygons fan-triangulated. Other elements and properties are skipped. Every count is checked
//! against the bytes left before anything is allocated, so a lying header cannot make the reader
//! allocate without bound; every error names the file and, in the header and in ASCII bodies, the line.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::input::{read_bounded, short, MAX_INPUT_BYTES};
use super::parse_error;
use super::tri_mesh::TriMesh;
use crate::error::{Error, Result, SceneElement};

/// Reads the PLY file at `path`. A problem with one vertex or face is an [`Error::SceneElement`]
/// naming it; others are [`Error::Parse`] with the line where known.
pub fn load_ply(path: &Path) -> Result<TriMesh> {
    let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
    parse_located(&bytes).map_err(|p| match p.record {
        Some((element, index)) => Error::SceneElement {
            path: path.to_path_buf(),
            element: SceneElement::Ply { element, index, line: p.line },
            message: p.message,
        },
        None => parse_error(path, p.line, p.message),
    })
}

/// A scalar type of the format.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Scalar>,
    value: Scalar,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// An error: the line (where known) and the message.
type PlyError = (Option<usize>, String);

/// A problem in the file: the line (where known), the record it is in when it is one vertex's or
/// face's (element and 0-based index), and the message.
struct Problem {
    line: Option<usize>,
    record: Option<(&'static str, usize)>,
    message: String,
}

impl From<PlyError> for Problem {
    fn from((line, message): PlyError) -> Problem {
        Problem { line, record: None, message }
    }
}

/// Parses a whole PLY file; an error is the line (where known) and the message (naming the record).
pub fn parse_ply(bytes: &[u8]) -> std::result::Result<TriMesh, PlyError> {
    parse_located(bytes).map_err(|p| match p.record {
        Some((element, index)) => (p.line, format!("{element} {index} {}", p.message)),
        None => (p.line, p.message),
    })
}

/// [`parse_ply`] with the record of a problem apart.
fn parse_located(bytes: &[u8]) -> std::result::Result<TriMesh, Problem> {
    let (format, elements, body, header_lines) = header(bytes)?;
    let mut mesh = TriMesh::default();
    let mut source = match format {
        Format::Ascii => Source::Ascii { text: body, pos: 0, line: header_lines },
        Format::Little | Format::Big => Source::Binary { data: body, pos: 0, big: format == Format::Big },
    };
    for e in &elements {
        let min_size = match format {
            Format::Ascii => e.properties.len().max(1) * 2 - 1,
            _ => e.properties.iter().map(|p| p.list.unwrap_or(p.value).size()).sum::<usize>().max(1),
        };
        if e.count > source.remaining() / min_size.max(1) + usize::from(min_size == 0) {
            return Err((
                None,
                format!("element '{}' claims {} items, more than the file holds", short(&e.name), e.count),
            )
                .into());
        }
        match e.name.as_str() {
            "vertex" => read_vertices(e, &mut source, &mut mesh)?,
            "face" => read_faces(e, &mut source, &mut mesh)?,
            _ => {
                for _ in 0..e.count {
                    for p in &e.properties {
                        source.skip_property(p)?;
                    }
                    source.end_item()?;
                }
            }
        }
    }
    let n = mesh.positions.len();
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
        return Err((
            None,
            format!("face index {} out of range: the file has {n} vertices", t.iter().max().unwrap_or(&0)),
        )
            .into());
    }
    if mesh.triangles.is_empty() {
        return Err((None, "no faces: the file defines no triangles".to_string()).into());
    }
    Ok(mesh)
}

/// A parsed header: format, elements, the body's bytes and the number of header lines.
type Header<'a> = (Format, Vec<Element>, &'a [u8], usize);

/// Parses the header.
fn header(bytes: &[u8]) -> std::result::Result<Header<'_>, PlyError> {
    let mut pos = 0;
    let mut line = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .ok_or((Some(line + 1), "the header has no end_header line".to_string()))?;
        let raw = &bytes[pos..pos + end];
        pos += end + 1;
        line += 1;
        let text = std::str::from_utf8(raw).map_err(|_| (Some(line), "the header is not text".to_string()))?.trim();
        let err = |m: String| (Some(line), m);
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if text != "ply" {
                return Err(err("not a PLY file: the first line is not 'ply'".into()));
            }
            continue;
        }
        match words.as_slice() {
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(err(format!("unknown format '{}'", short(f)))),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count = count
                    .parse::<usize>()
                    .map_err(|_| err(format!("element count '{}' is not a number", short(count))))?;
                elements.push(Element { name: name.to_string(), count, properties: Vec::new() });
            }
            ["property", "list", count, value, name] => {
                let (Some(c), Some(v)) = (Scalar::parse(count), Scalar::parse(value)) else {
                    return Err(err(format!("unknown type in '{}'", short(text))));
                };
                if matches!(c, Scalar::F32 | Scalar::F64) {
                    return Err(err("a list count must be an integer type".into()));
                }
                let e = elements.last_mut().ok_or_else(|| err("property before any element".into()))?;
                e.properties.push(Property { name: name.to_string(), list: Some(c), value: v });
            }
            ["property", ty, name] => {
                let v = Scalar::parse(ty).ok_or_else(|| err(format!("unknown type '{}'", short(ty))))?;
                let e = elements.last_mut().ok_or_else(|| err("property before any element".into()))?;
                e.properties.push(Property { name: name.to_string(), list: None, value: v });
            }
            ["end_header"] => break,
            _ => return Err(err(format!("unknown header line '{}'", short(text)))),
        }
    }
    let format = format.ok_or((None, "the header has no format line".to_string()))?;
    Ok((format, elements, &bytes[pos..], line))
}

/// The body, read value by value.
enum Source<'a> {
    Ascii { text: &'a [u8], pos: usize, line: usize },
    Binary { data: &'a [u8], pos: usize, big: bool },
}

impl Source<'_> {
    fn remaining(&self) -> usize {
        match self {
            Source::Ascii { text, pos, .. } => text.len() - pos,
            Source::Binary { data, pos, .. } => data.len() - pos,
        }
    }

    /// The 1-based line of the value last read (ASCII; `line` counts the newlines passed).
    fn line(&self) -> Option<usize> {
        match self {
            Source::Ascii { line, .. } => Some(*line + 1),
            Source::Binary { .. } => None,
        }
    }

    /// The next value, as `f64`.
    fn value(&mut self, ty: Scalar) -> std::result::Result<f64, PlyError> {
        match self {
            Source::Ascii { text, pos, line } => {
                while *pos < text.len() && text[*pos].is_ascii_whitespace() {
                    if text[*pos] == b'\n' {
                        *line += 1;
                    }
                    *pos += 1;
                }
                let start = *pos;
                while *pos < text.len() && !text[*pos].is_ascii_whitespace() {
                    *pos += 1;
                }
                let word = std::str::from_utf8(&text[start..*pos]).unwrap_or("");
                let l = Some(*line + 1);
                if word.is_empty() {
                    return Err((l, "the file ends in the middle of an element".into()));
                }
                let v: f64 = word.parse().map_err(|_| (l, format!("'{}' is not a number", short(word))))?;
                if !v.is_finite() {
                    return Err((l, format!("'{}' is not finite", short(word))));
                }
                Ok(v)
            }
            Source::Binary { data, pos, big } => {
                let n = ty.size();
                let b =
                    data.get(*pos..*pos + n).ok_or((None, "the file ends in the middle of an element".to_string()))?;
                *pos += n;
                let mut a = [0u8; 8];
                a[..n].copy_from_slice(b);
                if *big {
                    a[..n].reverse();
                }
                let v = match ty {
                    Scalar::I8 => a[0] as i8 as f64,
                    Scalar::U8 => a[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(a),
                };
                if !v.is_finite() {
                    return Err((None, "a value is not finite".into()));
                }
                Ok(v)
            }
        }
    }

    /// A list's length, checked against the bytes left.
    fn count(&mut self, ty: Scalar, value: Scalar) -> std::result::Result<usize, PlyError> {
        let n = self.value(ty)?;
        let line = self.line();
        if n < 0.0 || n.fract() != 0.0 {
            return Err((line, format!("list length {n} is not a count")));
        }
        let per = match self {
            Source::Ascii { .. } => 2,
            Source::Binary { .. } => value.size(),
        };
        if n as usize > self.remaining() / per + 1 {
            return Err((line, format!("list of {n} values, more than the file holds")));
        }
        Ok(n as usize)
    }

    fn skip_property(&mut self, p: &Property) -> std::result::Result<(), PlyError> {
        let n = match p.list {
            Some(c) => self.count(c, p.value)?,
            None => 1,
        };
        for _ in 0..n {
            self.value(p.value)?;
        }
        Ok(())
    }

    /// ASCII: the rest of an item's line must be empty.
    fn end_item(&mut self) -> std::result::Result<(), PlyError> {
        if let Source::Ascii { text, pos, line } = self {
            while *pos < text.len() && text[*pos] != b'\n' {
                if !text[*pos].is_ascii_whitespace() {
                    return Err((Some(*line + 1), "more values on the line than the element has properties".into()));
                }
                *pos += 1;
            }
        }
        Ok(())
    }
}

fn read_vertices(e: &Element, src: &mut Source, mesh: &mut TriMesh) -> std::result::Result<(), Problem> {
    let find = |names: &[&str]| e.properties.iter().position(|p| p.list.is_none() && names.contains(&p.name.as_str()));
    let (Some(x), Some(y), Some(z)) = (find(&["x"]), find(&["y"]), find(&["z"])) else {
        return Err((None, "the vertex element has no x, y, z properties".to_string()).into());
    };
    let u = find(&["u", "s", "texture_u", "texture_s"]);
    let v = find(&["v", "t", "texture_v", "texture_t"]);
    let uv = u.zip(v);
    mesh.positions.reserve(e.count);
    let mut values = vec![0.0f64; e.properties.len()];
    for _ in 0..e.count {
        for (i, p) in e.properties.iter().enumerate() {
            match p.list {
                Some(_) => src.skip_property(p)?,
                None => values[i] = src.value(p.value)?,
            }
        }
        src.end_item()?;
        let p = Vec3::new(values[x] as f32, values[y] as f32, values[z] as f32);
        if !p.is_finite() {
            let (line, record) = (src.line(), Some(("vertex", mesh.positions.len())));
            return Err(Problem { line, record, message: "is not finite in single precision".into() });
        }
        mesh.positions.push(p);
        if let Some((u, v)) = uv {
            mesh.uvs.push(Vec2::new(values[u] as f32, values[v] as f32));
        }
    }
    Ok(())
}

fn read_faces(e: &Element, src: &mut Source, mesh: &mut TriMesh) -> std::result::Result<(), Problem> {
    let list = e
        .properties
        .iter()
        .position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"))
        .ok_or((None, "the face element has no vertex_indices list".to_string()))?;
    let mut poly: Vec<u32> = Vec::new();
    for f in 0..e.count {
        for (i, p) in e.properties.iter().enumerate() {
            if i != list {
                src.skip_property(p)?;
                continue;
            }
            let n = src.count(p.list.unwrap_or(Scalar::U8), p.value)?;
            poly.clear();
            for _ in 0..n {
                let v = src.value(p.value)?;
                if v < 0.0 || v.fract() != 0.0 || v > u32::MAX as f64 {
                    let message = format!("has the index {v}, not a vertex index");
                    return Err(Problem { line: src.line(), record: Some(("face", f)), message });
                }
                poly.push(v as u32);
            }
            if n < 3 {
                let message = format!("has {n} vertices; a face needs at least 3");
                return Err(Problem { line: src.line(), record: Some(("face", f)), message });
            }
            for k in 1..n - 1 {
                mesh.triangles.push([poly[0], poly[k], poly[k + 1]]);
            }
        }
        src.end_item()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = "ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_with_uvs() {
        let m = parse_ply(QUAD.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.uvs[2], Vec2::ONE);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn binary_both_endians() {
        for big in [false, true] {
            let mut b = format!(
                "ply\nformat binary_{}_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n",
                if big { "big" } else { "little" }
            )
            .into_bytes();
            for v in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
                for c in v {
                    b.extend(if big { c.to_be_bytes() } else { c.to_le_bytes() });
                }
            }
            b.push(3);
            for i in [0u32, 1, 2] {
                b.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
            }
            let m = parse_ply(&b).unwrap();
            assert_eq!(m.positions[1], Vec3::X);
            assert_eq!(m.triangles, vec![[0, 1, 2]]);
        }
    }

    /// A bad face or vertex is a typed error naming the record, its line and the file.
    #[test]
    fn bad_records_are_scene_element_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("q.ply");
        std::fs::write(&path, QUAD.replace("4 0 1 2 3", "2 0 1")).unwrap();
        match load_ply(&path) {
            Err(Error::SceneElement { path: p, element, message }) => {
                assert_eq!(p, path);
                assert_eq!(element, SceneElement::Ply { element: "face", index: 0, line: Some(17) });
                assert!(message.contains("a face needs at least 3"), "{message}");
            }
            other => panic!("expected face 0's error: {:?}", other.err()),
        }
        // The untyped form keeps the record in the message.
        let (line, m) = parse_ply(QUAD.replace("4 0 1 2 3", "2 0 1").as_bytes()).unwrap_err();
        assert_eq!((line, m.as_str()), (Some(17), "face 0 has 2 vertices; a face needs at least 3"));
    }

    #[test]
    fn errors_name_the_line() {
        let bad = QUAD.replace("1 1 0 1 1", "1 nope 0 1 1");
        let (line, m) = parse_ply(bad.as_bytes()).unwrap_err();
        assert_eq!(line, Some(15), "{m}");
        let bad = QUAD.replace("4 0 1 2 3", "4 0 1 2 9");
        assert!(parse_ply(bad.as_bytes()).unwrap_err().1.contains("out of range"));
        let bad = QUAD.replace("element vertex 4", "element vertex 4000000000000");
        assert!(parse_ply(bad.as_bytes()).unwrap_err().1.contains("more than the file holds"));
        let cut = &QUAD.as_bytes()[..QUAD.len() - 4];
        assert!(parse_ply(cut).is_err());
        assert!(parse_ply(b"ply\nformat ascii 1.0\n").unwrap_err().1.contains("end_header"));
    }
}
