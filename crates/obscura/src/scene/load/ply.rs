//! PLY (Stanford polygon files), ASCII and binary in either byte order, read with
//! `ply-rs-bw`.
//!
//! Input: the bytes of a `.ply` file. Output: one object (named after the file) whose
//! faces are the `face` elements in file order, over the `vertex` elements' `x`, `y`,
//! `z` (any numeric type, usually `float` or `double`). Face corners come from the
//! `vertex_indices` list (or `vertex_index`, its common alternative spelling) of any
//! integer type; a face element declaring both lists is refused (which one is meant
//! is a guess, and reading both would join them into one polygon). Other properties (normals, colours, texture coordinates) and other
//! elements (edges, materials) are read past and ignored.
//!
//! The header is parsed by `ply-rs-bw`; the body is read element by element here, so
//! every error names the element and its 0-based index (and, in ASCII files, the
//! line): a non-finite coordinate, a coordinate beyond
//! [`MAX_COORDINATE`](crate::scene::MAX_COORDINATE), a face with fewer than three corners, an index that
//! is negative or not below the vertex count, a list of non-integer indices, a body
//! shorter than the header announces (truncated), a missing `x`/`y`/`z` or index list.
//!
//! A UTF-8 byte-order mark before the `ply` magic word is skipped.
//!
//! Complexity: O(file size). Source: Greg Turk, "The PLY Polygon File Format" (1994).

use std::io::{BufRead, Cursor};
use std::path::Path;

use glam::DVec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    BeginList, ElementDef, Encoding, PropertyAccess, PropertyAccessResult, PropertyType,
};

use super::{Loaded, coordinate_out_of_range, file_stem, finish_object, palette_color, strip_bom};
use crate::scene::MeshBuilder;
use crate::{Error, Result};

/// One element as the parser fills it: only what obscura uses.
#[derive(Debug, Default)]
struct Element {
    xyz: [f64; 3],
    /// Index lists arrive in the declared type; the two usual ones are filled in place.
    list_i32: Vec<i32>,
    list_u32: Vec<u32>,
    list_other: Vec<i64>,
    list_is_float: bool,
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl Element {
    fn set_coordinate(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        match name {
            "x" => self.xyz[0] = v,
            "y" => self.xyz[1] = v,
            "z" => self.xyz[2] = v,
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }

    fn set_other_list<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        self.list_other = v.into_iter().map(Into::into).collect();
        PropertyAccessResult::Set
    }

    /// The face corners, whatever integer type the file used.
    fn indices(&self) -> impl Iterator<Item = i64> + '_ {
        self.list_i32
            .iter()
            .map(|&i| i64::from(i))
            .chain(self.list_u32.iter().map(|&i| i64::from(i)))
            .chain(self.list_other.iter().copied())
    }
}

impl PropertyAccess for Element {
    fn new() -> Self {
        Self::default()
    }
    fn set_char(&mut self, name: &str, v: i8) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_uchar(&mut self, name: &str, v: u8) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_short(&mut self, name: &str, v: i16) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_ushort(&mut self, name: &str, v: u16) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_int(&mut self, name: &str, v: i32) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_uint(&mut self, name: &str, v: u32) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_float(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        self.set_coordinate(name, f64::from(v))
    }
    fn set_double(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        self.set_coordinate(name, v)
    }
    fn begin_list_int(&mut self, name: &str, _len: usize) -> BeginList<'_, i32> {
        if is_index_list(name) {
            BeginList::Fill(&mut self.list_i32)
        } else {
            BeginList::UseSetter
        }
    }
    fn begin_list_uint(&mut self, name: &str, _len: usize) -> BeginList<'_, u32> {
        if is_index_list(name) {
            BeginList::Fill(&mut self.list_u32)
        } else {
            BeginList::UseSetter
        }
    }
    fn set_list_char(&mut self, name: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.set_other_list(name, v)
    }
    fn set_list_uchar(&mut self, name: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.set_other_list(name, v)
    }
    fn set_list_short(&mut self, name: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.set_other_list(name, v)
    }
    fn set_list_ushort(&mut self, name: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.set_other_list(name, v)
    }
    fn set_list_float(&mut self, name: &str, _v: Vec<f32>) -> PropertyAccessResult {
        self.list_is_float |= is_index_list(name);
        PropertyAccessResult::Ignored
    }
    fn set_list_double(&mut self, name: &str, _v: Vec<f64>) -> PropertyAccessResult {
        self.list_is_float |= is_index_list(name);
        PropertyAccessResult::Ignored
    }
}

/// Where the body reader is, for error messages.
struct Body<'a> {
    path: &'a Path,
    reader: Reader<Cursor<&'a [u8]>>,
    parser: Parser<Element>,
    encoding: Encoding,
    /// The 1-based line of the next ASCII body line.
    line: usize,
    text: String,
}

/// For an ASCII element line the parser accepted: `(values on the line, values its
/// properties take)` when the line has more (the parser ignores them; they mean the
/// line does not match the header), else `None`.
fn extra_values(text: &str, def: &ElementDef) -> Option<(usize, usize)> {
    let tokens: Vec<&str> = text.split_ascii_whitespace().collect();
    let mut at = 0usize;
    for p in def.properties.values() {
        at += match p.data_type {
            PropertyType::Scalar(_) => 1,
            PropertyType::List(..) => 1 + tokens.get(at)?.parse::<usize>().ok()?,
        };
    }
    (tokens.len() > at).then_some((tokens.len(), at))
}

impl Body<'_> {
    /// Reads element `index` of `def`; errors name it (and its line in ASCII files).
    fn read(&mut self, def: &ElementDef, index: usize) -> Result<Element> {
        let element = format!("{} {index}", def.name);
        let truncated = || {
            format!(
                "truncated: the header announces {} {} element(s), the file ends at {element}",
                def.count, def.name
            )
        };
        match self.encoding {
            Encoding::Ascii => {
                self.text.clear();
                let n = self
                    .reader
                    .get_mut()
                    .read_line(&mut self.text)
                    .map_err(|e| Error::io(self.path, e))?;
                let line = self.line;
                self.line += 1;
                if n == 0 {
                    return Err(Error::parse(self.path, line, truncated()));
                }
                let e = self
                    .parser
                    .read_ascii_element(&self.text, def)
                    .map_err(|e| {
                        Error::parse(self.path, line, format!("{element}: {}", one_line(&e)))
                    })?;
                if let Some((found, expected)) = extra_values(&self.text, def) {
                    return Err(Error::parse(
                        self.path,
                        line,
                        format!(
                            "{element}: {found} values on the line, the header's properties \
                             take {expected}"
                        ),
                    ));
                }
                Ok(e)
            }
            Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
                let r = self.reader.get_mut();
                let result = if matches!(self.encoding, Encoding::BinaryLittleEndian) {
                    self.parser.read_little_endian_element(r, def)
                } else {
                    self.parser.read_big_endian_element(r, def)
                };
                result.map_err(|e| {
                    let message = if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        truncated()
                    } else {
                        one_line(&e)
                    };
                    Error::format(self.path, element.clone(), message)
                })
            }
        }
    }

    /// Names an element in an error: `file:line` in ASCII, the element otherwise.
    fn error(&self, def: &ElementDef, index: usize, message: String) -> Error {
        match self.encoding {
            Encoding::Ascii => Error::parse(
                self.path,
                self.line - 1,
                format!("{} {index}: {message}", def.name),
            ),
            _ => Error::format(self.path, format!("{} {index}", def.name), message),
        }
    }
}

/// An error naming the header line that declares an element, or a property of one
/// element, a second time: the header parser keeps one of them, so the body would be
/// read with the wrong columns (ASCII) or misaligned (binary).
fn check_unique_names(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut elements: Vec<String> = Vec::new();
    let mut properties: Vec<String> = Vec::new();
    for (k, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = String::from_utf8_lossy(line);
        let mut words = line.split_ascii_whitespace();
        let (kind, what, seen) = match words.next() {
            Some("end_header") => break,
            Some("element") => {
                properties.clear();
                ("element", words.next(), &mut elements)
            }
            Some("property") => ("property", words.last(), &mut properties),
            _ => continue,
        };
        let Some(name) = what else { continue };
        if seen.iter().any(|n| n == name) {
            return Err(Error::parse(
                path,
                k + 1,
                format!("PLY header: {kind} \"{name}\" is declared twice"),
            ));
        }
        seen.push(name.to_string());
    }
    Ok(())
}

/// Loads a PLY file from its bytes (`path` names it in messages).
pub fn load(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let bytes = strip_bom(bytes);
    let parser = Parser::<Element>::new();
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = parser.read_header(&mut reader).map_err(|e| {
        let line = e.line().unwrap_or(1);
        Error::parse(path, line, format!("PLY header: {}", one_line(&e)))
    })?;
    check_unique_names(path, bytes)?;
    let line = reader.line().max(1);
    let vertex_def = header.elements.get("vertex");
    let face_def = header.elements.get("face");
    if let Some(def) = vertex_def {
        for axis in ["x", "y", "z"] {
            match def.properties.get(axis).map(|p| &p.data_type) {
                Some(PropertyType::Scalar(_)) => {}
                Some(PropertyType::List(..)) => {
                    return Err(Error::format(
                        path,
                        "vertex",
                        format!("property {axis} is a list, expected a number"),
                    ));
                }
                None => {
                    return Err(Error::format(
                        path,
                        "vertex",
                        format!("the vertex element has no property {axis}"),
                    ));
                }
            }
        }
    }
    if let Some(def) = face_def {
        if def.properties.keys().filter(|k| is_index_list(k)).count() > 1 {
            return Err(Error::format(
                path,
                "face",
                "the face element has both a vertex_indices and a vertex_index list \
                 (which one holds the corners is ambiguous)",
            ));
        }
        match def.properties.iter().find(|(k, _)| is_index_list(k)) {
            Some((_, p)) if matches!(p.data_type, PropertyType::List(..)) => {}
            Some((k, _)) => {
                return Err(Error::format(
                    path,
                    "face",
                    format!("property {k} is not a list"),
                ));
            }
            None => {
                return Err(Error::format(
                    path,
                    "face",
                    "the face element has no vertex_indices (or vertex_index) list",
                ));
            }
        }
    }

    let mut body = Body {
        path,
        reader,
        parser,
        encoding: header.encoding,
        line,
        text: String::new(),
    };
    // Reserve by what the file can hold, not by what its header claims.
    let cap = |count: usize| count.min(bytes.len() / 4);
    let mut positions: Vec<DVec3> = Vec::new();
    let mut face_starts: Vec<usize> = vec![0];
    let mut face_indices: Vec<i64> = Vec::new();
    let mut face_lines: Vec<usize> = Vec::new();
    let (mut have_vertices, mut have_faces) = (vertex_def.is_none(), face_def.is_none());
    for (name, def) in &header.elements {
        if have_vertices && have_faces {
            break; // later elements cannot change the mesh
        }
        match name.as_str() {
            "vertex" => {
                positions.reserve(cap(def.count));
                for i in 0..def.count {
                    let e = body.read(def, i)?;
                    let p = DVec3::from_array(e.xyz);
                    if !p.is_finite() {
                        return Err(body.error(
                            def,
                            i,
                            format!("non-finite coordinate {:?}", e.xyz),
                        ));
                    }
                    if let Some(m) = coordinate_out_of_range(e.xyz) {
                        return Err(body.error(def, i, m));
                    }
                    positions.push(p);
                }
                have_vertices = true;
            }
            "face" => {
                face_lines.reserve(cap(def.count));
                for i in 0..def.count {
                    let e = body.read(def, i)?;
                    if e.list_is_float {
                        return Err(body.error(
                            def,
                            i,
                            "vertex indices are floating-point numbers, expected integers".into(),
                        ));
                    }
                    face_indices.extend(e.indices());
                    let corners = face_indices.len() - face_starts[face_starts.len() - 1];
                    if corners < 3 {
                        return Err(body.error(
                            def,
                            i,
                            format!("a face needs at least 3 vertices, found {corners}"),
                        ));
                    }
                    face_starts.push(face_indices.len());
                    face_lines.push(body.line - 1);
                }
                have_faces = true;
            }
            _ => {
                // A binary element without properties occupies no bytes: nothing to
                // skip, however large its count.
                if def.properties.is_empty() && !matches!(body.encoding, Encoding::Ascii) {
                    continue;
                }
                for i in 0..def.count {
                    body.read(def, i)?;
                }
            }
        }
    }

    let mut loaded = Loaded::default();
    let mut b = MeshBuilder::with_capacity(positions.len(), face_lines.len());
    for &p in &positions {
        b.push_position(p);
    }
    let n = positions.len();
    let mut face = Vec::new();
    for (k, w) in face_starts.windows(2).enumerate() {
        face.clear();
        for &i in &face_indices[w[0]..w[1]] {
            if i < 0 || i as u64 >= n as u64 {
                let message = format!(
                    "vertex index {i} is out of range (the file has {n} vertices, indices 0..{})",
                    n.saturating_sub(1)
                );
                return Err(match body.encoding {
                    Encoding::Ascii => {
                        Error::parse(path, face_lines[k], format!("face {k}: {message}"))
                    }
                    _ => Error::format(path, format!("face {k}"), message),
                });
            }
            face.push(i as u32);
        }
        b.push_face(&face, None)
            .map_err(|e| Error::format(path, format!("face {k}"), e.to_string()))?;
    }
    let object = finish_object(file_stem(path), b, palette_color(0), &mut loaded.report);
    loaded.objects.push(object);
    Ok(loaded)
}

/// The parser's multi-line messages on one line.
/// The parser's multi-line messages on one line, without its own "Line N:" prefix
/// (the error already names the line).
fn one_line(e: &impl std::fmt::Display) -> String {
    let s = e.to_string();
    let s = match s.strip_prefix("Line ").and_then(|r| r.split_once(": ")) {
        Some((n, rest)) if n.bytes().all(|b| b.is_ascii_digit()) => rest.to_string(),
        _ => s,
    };
    s.replace("\n\t", "; ").replace('\n', " ")
}
