//! The XML layer of Mitsuba scene files (issue 18): parses a file with `roxmltree` into an owned tree
//! of [`Elem`]s, each knowing its file and line, after
//!
//! - `<default name value>`: parameters, substituted for `$name` in every attribute value;
//! - `<include filename>`: the included file's top-level elements spliced in (its path confined to the
//!   scene's folder like every file a scene names; at most [`MAX_INCLUDE_DEPTH`] levels);
//! - version 0.6 names: every `name` attribute in camelCase (`toWorld`) becomes snake_case
//!   (`to_world`), so the rest of the loader reads one spelling.
//!
//! DTDs are refused (roxmltree's default), so entity expansion cannot blow up; the number of elements
//! is bounded by [`MAX_ELEMENTS`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::error::{Error, Result};
use crate::io::input::{read_bounded, resolve_in_scene, short, LoadOptions};

/// The largest XML file read (256 MiB).
pub const MAX_XML_BYTES: u64 = 256 << 20;
/// How deep `<include>` may nest.
pub const MAX_INCLUDE_DEPTH: usize = 8;
/// The most elements of a scene, includes together.
pub const MAX_ELEMENTS: usize = 1 << 20;
/// How deep elements may nest (real scenes nest a few levels; a deeper file is hostile).
pub const MAX_NESTING: usize = 64;

/// One XML element with its attributes (after substitution) and children.
#[derive(Clone, Debug)]
pub struct Elem {
    /// Tag name.
    pub tag: String,
    /// Attributes in document order.
    pub attrs: Vec<(String, String)>,
    /// Child elements.
    pub children: Vec<Elem>,
    /// The file it is in.
    pub file: Rc<PathBuf>,
    /// Its 1-based line.
    pub line: usize,
}

impl Elem {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The value of attribute `name`, or an error naming the element.
    pub fn need(&self, name: &str) -> Result<&str> {
        self.attr(name).ok_or_else(|| self.error(format!("has no '{name}' attribute")))
    }

    /// `<tag type="..." name="..." id="...">` for messages.
    pub fn describe(&self) -> String {
        let mut s = format!("<{}", self.tag);
        for key in ["type", "name", "id"] {
            if let Some(v) = self.attr(key) {
                s.push_str(&format!(" {key}=\"{}\"", short(v)));
            }
        }
        s.push('>');
        s
    }

    /// An error at this element: file, line, the element and `message`.
    pub fn error(&self, message: String) -> Error {
        Error::Parse {
            path: (*self.file).clone(),
            line: Some(self.line),
            message: format!("{}: {message}", self.describe()),
        }
    }
}

/// A parsed scene file: the `<scene>` element with includes spliced in and defaults applied.
pub struct Document {
    /// The root `<scene>`.
    pub root: Elem,
    /// Its `version` attribute.
    pub version: String,
    /// The files read: the scene file, then its includes.
    pub files: Vec<PathBuf>,
}

/// Parses the scene file at `path`.
pub fn parse_scene(path: &Path, opts: LoadOptions) -> Result<Document> {
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut ctx = Ctx { dir, opts, params: HashMap::new(), elements: 0, files: Vec::new() };
    let root = ctx.file(path, 0)?;
    let version = root.attr("version").unwrap_or("").to_string();
    if version.is_empty() {
        return Err(root.error("has no 'version' attribute (0.6.0 or 3.0.0, say)".into()));
    }
    Ok(Document { root, version, files: ctx.files })
}

struct Ctx {
    dir: PathBuf,
    opts: LoadOptions,
    params: HashMap<String, String>,
    elements: usize,
    /// Files read so far.
    files: Vec<PathBuf>,
}

impl Ctx {
    /// Parses one file (the scene or an include) into its `<scene>` element.
    fn file(&mut self, path: &Path, depth: usize) -> Result<Elem> {
        let bytes = read_bounded(path, MAX_XML_BYTES)?;
        self.files.push(path.to_path_buf());
        let fail = |line: Option<usize>, m: String| Error::Parse { path: path.to_path_buf(), line, message: m };
        let text = std::str::from_utf8(&bytes).map_err(|e| fail(None, format!("not UTF-8 text: {e}")))?;
        let doc = roxmltree::Document::parse(text)
            .map_err(|e| fail(Some(e.pos().row as usize), format!("malformed XML: {e}")))?;
        let file = Rc::new(path.to_path_buf());
        let root = doc.root_element();
        // Not `doc.text_pos_at`: it counts the lines from the start of the text on every call, so a
        // file of N elements took time N^2 (30,000 shapes: 30 s).
        let lines = LineIndex::new(text);
        let line = |n: roxmltree::Node| lines.line(n.range().start);
        if root.tag_name().name() != "scene" {
            return Err(fail(
                Some(line(root)),
                format!("the root element is <{}>, not <scene>", short(root.tag_name().name())),
            ));
        }
        // Defaults first: they apply to the whole file (a parameter already set is kept).
        for d in root.children().filter(|n| n.is_element() && n.tag_name().name() == "default") {
            let (Some(name), Some(value)) = (d.attribute("name"), d.attribute("value")) else {
                return Err(fail(Some(line(d)), "<default> needs 'name' and 'value'".into()));
            };
            self.params.entry(name.to_string()).or_insert_with(|| value.to_string());
        }
        let mut out = self.convert(root, &file, &line, 0)?;
        let mut children = Vec::with_capacity(out.children.len());
        for c in std::mem::take(&mut out.children) {
            if c.tag != "include" {
                children.push(c);
                continue;
            }
            if depth + 1 > MAX_INCLUDE_DEPTH {
                return Err(c.error(format!("includes nest more than {MAX_INCLUDE_DEPTH} levels deep (a cycle?)")));
            }
            let name = c.need("filename")?;
            let inc = resolve_in_scene(&self.dir, name, "include", self.opts).map_err(|m| c.error(m))?;
            let sub = self.file(&inc, depth + 1).map_err(|e| match e {
                Error::Io { source, .. } => c.error(format!("cannot read '{}': {source}", short(name))),
                e => e,
            })?;
            children.extend(sub.children);
        }
        out.children = children;
        Ok(out)
    }

    fn convert(
        &mut self,
        n: roxmltree::Node,
        file: &Rc<PathBuf>,
        line: &dyn Fn(roxmltree::Node) -> usize,
        depth: usize,
    ) -> Result<Elem> {
        self.elements += 1;
        let at = line(n);
        let limit = |message: String| Error::Parse { path: (**file).clone(), line: Some(at), message };
        if self.elements > MAX_ELEMENTS {
            return Err(limit(format!("more than {MAX_ELEMENTS} elements")));
        }
        if depth > MAX_NESTING {
            return Err(limit(format!("elements nest more than {MAX_NESTING} levels deep")));
        }
        let mut attrs = Vec::new();
        for a in n.attributes() {
            let mut v = self.substitute(a.value()).map_err(|m| Error::Parse {
                path: (**file).clone(),
                line: Some(at),
                message: format!("<{}>: {m}", n.tag_name().name()),
            })?;
            if a.name() == "name" {
                v = snake_case(&v);
            }
            attrs.push((a.name().to_string(), v));
        }
        let mut children = Vec::new();
        for c in n.children().filter(|c| c.is_element()) {
            children.push(self.convert(c, file, line, depth + 1)?);
        }
        Ok(Elem { tag: n.tag_name().name().to_string(), attrs, children, file: file.clone(), line: at })
    }

    /// Replaces every `$name` by its parameter's value.
    fn substitute(&self, s: &str) -> std::result::Result<String, String> {
        if !s.contains('$') {
            return Ok(s.to_string());
        }
        let mut out = String::new();
        let mut rest = s;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..len];
            if name.is_empty() {
                out.push('$');
            } else {
                let v = self
                    .params
                    .get(name)
                    .ok_or_else(|| format!("'${}' is not defined by any <default>", short(name)))?;
                out.push_str(v);
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

/// The 1-based line of byte offsets of a text (what `roxmltree::Document::text_pos_at(pos).row`
/// gives), counting line breaks on from the previous offset asked: the elements are visited in
/// document order, so a whole file costs one pass over its text, in constant memory.
struct LineIndex<'t> {
    text: &'t [u8],
    /// The last offset asked (clamped to the text) and its line.
    at: std::cell::Cell<(usize, usize)>,
}

impl<'t> LineIndex<'t> {
    fn new(text: &'t str) -> Self {
        LineIndex { text: text.as_bytes(), at: std::cell::Cell::new((0, 1)) }
    }

    /// 1 plus the number of line breaks before `pos`.
    fn line(&self, pos: usize) -> usize {
        let pos = pos.min(self.text.len());
        let (from, row) = match self.at.get() {
            (at, row) if at <= pos => (at, row),
            _ => (0, 1),
        };
        let row = row + self.text[from..pos].iter().filter(|&&b| b == b'\n').count();
        self.at.set((pos, row));
        row
    }
}

/// `toWorld` -> `to_world`; snake_case stays as it is.
pub fn snake_case(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 4);
    for (i, c) in s.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// Records every element with an `id`; a repeated id is an error.
pub(super) fn register_ids<'a>(e: &'a Elem, ids: &mut HashMap<String, &'a Elem>) -> Result<()> {
    for c in &e.children {
        if c.tag != "ref" {
            if let Some(id) = c.attr("id") {
                if ids.insert(id.to_string(), c).is_some() {
                    return Err(c.error(format!("the id '{}' is used twice", short(id))));
                }
            }
        }
        register_ids(c, ids)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_snake_case() {
        assert_eq!(snake_case("toWorld"), "to_world");
        assert_eq!(snake_case("fovAxis"), "fov_axis");
        assert_eq!(snake_case("to_world"), "to_world");
        assert_eq!(snake_case("diffuseReflectance"), "diffuse_reflectance");
    }

    #[test]
    fn line_index_matches_roxmltree() {
        let text = "<scene version=\"3.0.0\">\n\n  <shape type=\"cube\"/>\r\n<bsdf\n type=\"diffuse\"/>\n</scene>\n";
        let lines = LineIndex::new(text);
        let doc = roxmltree::Document::parse(text).unwrap();
        for pos in (0..=text.len() + 2).chain((0..=text.len()).rev()).chain([7, 30, 3, 50]) {
            assert_eq!(lines.line(pos), doc.text_pos_at(pos).row as usize, "at {pos}");
        }
        assert_eq!(LineIndex::new("").line(0), 1);
    }
}
