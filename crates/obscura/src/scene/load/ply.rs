//! PLY (Stanford polygon files), ASCII and binary in either byte order, read here in
//! one pass.
//!
//! Input: the bytes of a `.ply` file. Output: one object (named after the file) whose
//! faces are the `face` elements in file order, over the `vertex` elements' `x`, `y`,
//! `z` (any numeric type, usually `float` or `double`). Face corners come from the
//! `vertex_indices` list (or `vertex_index`, its common alternative spelling) of any
//! integer type; a face element declaring both lists is refused (which one is meant
//! is a guess, and reading both would join them into one polygon). Other properties
//! (normals, colours, texture coordinates) and other elements (edges, materials) are
//! read past and ignored; reading stops once the vertices and faces are read.
//!
//! Header: `ply`, `format ascii|binary_little_endian|binary_big_endian 1.0`,
//! `element NAME COUNT`, `property TYPE NAME`, `property list COUNT_TYPE ITEM_TYPE NAME`
//! (types `char`, `uchar`, `short`, `ushort`, `int`, `uint`, `float`, `double` and
//! their sized spellings `int8` ... `float64`), `comment` and `obj_info` lines, blank
//! lines, `end_header`. A UTF-8 byte-order mark before `ply` is skipped. Element and
//! property names are checked for repeats with a hash set.
//!
//! Body: in ASCII, one element per line (blank lines are skipped; an element without
//! properties takes no line); in binary, the values packed in the declared byte order
//! (an element of fixed size that is not needed is skipped in one step).
//!
//! Errors are sentences naming `file:line` (the header, and ASCII bodies) or the file
//! and the element with its 0-based index (binary bodies): an unknown header keyword or
//! type, a malformed count, a name declared twice, a missing `x`/`y`/`z` or index list,
//! a malformed or out-of-range value (a `uchar` of 300, a list length below 0), a
//! line with more or fewer values than the header's properties take, a non-finite
//! coordinate, a coordinate beyond [`MAX_COORDINATE`](crate::scene::MAX_COORDINATE), a
//! face with fewer than three corners, an index that is negative or not below the
//! vertex count, a body shorter than the header announces (truncated).
//!
//! Why not a PLY crate: `ply-rs-bw` (used before) printed its own debug structures in
//! errors and could not say which element a binary error was in.
//!
//! Complexity: O(file size). Source: Greg Turk, "The PLY Polygon File Format" (1994).

use std::collections::HashSet;
use std::path::Path;

use glam::DVec3;

use super::{Loaded, coordinate_out_of_range, file_stem, finish_object, palette_color, strip_bom};
use crate::scene::MeshBuilder;
use crate::{Error, Result};

/// A scalar type of the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
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

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The name the header uses.
    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// The integer range of an integer type.
    fn range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            _ => (0, u32::MAX.into()),
        }
    }

    /// Parses an ASCII value of this type.
    fn parse_text(self, tok: &str) -> std::result::Result<f64, String> {
        if self.is_integer() {
            let (lo, hi) = self.range();
            match tok.parse::<i64>() {
                Ok(v) if (lo..=hi).contains(&v) => Ok(v as f64),
                Ok(v) => Err(format!(
                    "{v} is out of the range of a {} ({lo} to {hi})",
                    self.name()
                )),
                Err(_) => Err(format!(
                    "\"{}\" is not an integer (a {})",
                    shown(tok),
                    self.name()
                )),
            }
        } else {
            let v = tok
                .parse::<f64>()
                .map_err(|_| format!("\"{}\" is not a number", shown(tok)))?;
            // A `float` holds what its binary form would: 1e39 overflows to infinity.
            Ok(if self == Scalar::F32 {
                f64::from(v as f32)
            } else {
                v
            })
        }
    }

    /// Decodes a binary value of this type (`b` holds at least its size).
    fn decode(self, b: &[u8], little: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:literal) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if little {
                    <$t>::from_le_bytes(a)
                } else {
                    <$t>::from_be_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(get!(i16, 2)),
            Scalar::U16 => f64::from(get!(u16, 2)),
            Scalar::I32 => f64::from(get!(i32, 4)),
            Scalar::U32 => f64::from(get!(u32, 4)),
            Scalar::F32 => f64::from(get!(f32, 4)),
            Scalar::F64 => get!(f64, 8),
        }
    }
}

/// A token shown in a message: at most 40 characters, escaped.
fn shown(tok: &str) -> String {
    let mut s: String = tok.chars().take(40).collect();
    if s.len() < tok.len() {
        s.push_str("...");
    }
    s.escape_debug().to_string()
}

/// What a property is used for here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// x, y or z of a vertex.
    Axis(usize),
    /// The corner list of a face.
    Corners,
    Other,
}

#[derive(Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Scalar>,
    ty: Scalar,
    role: Role,
    /// 1-based header line.
    line: usize,
}

#[derive(Debug)]
struct ElementDef {
    name: String,
    count: u64,
    properties: Vec<Property>,
    line: usize,
}

impl ElementDef {
    /// Bytes per element in binary, when no property is a list.
    fn fixed_size(&self) -> Option<u64> {
        self.properties
            .iter()
            .map(|p| p.list.is_none().then_some(p.ty.size() as u64))
            .sum()
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

struct Header {
    encoding: Encoding,
    elements: Vec<ElementDef>,
    /// Byte offset of the body.
    body: usize,
    /// 1-based line of the body's first line.
    body_line: usize,
}

/// Parses the header; errors name its line.
fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let err = |line: usize, m: String| Error::parse(path, line, format!("PLY header: {m}"));
    let mut encoding = None;
    let mut elements: Vec<ElementDef> = Vec::new();
    let mut element_names: HashSet<String> = HashSet::new();
    let mut property_names: HashSet<String> = HashSet::new();
    let mut offset = 0usize;
    let mut line_no = 0usize;
    loop {
        if offset >= bytes.len() {
            return Err(err(
                line_no.max(1),
                "the file ends before \"end_header\"".into(),
            ));
        }
        let end = bytes[offset..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| offset + i);
        let raw = &bytes[offset..end];
        offset = (end + 1).min(bytes.len());
        line_no += 1;
        let text = String::from_utf8_lossy(raw);
        let mut words = text.split_ascii_whitespace();
        let keyword = words.next();
        if line_no == 1 {
            if keyword != Some("ply") || words.next().is_some() {
                return Err(err(
                    1,
                    format!(
                        "not a PLY file: the first line must be \"ply\", found \"{}\"",
                        shown(text.trim())
                    ),
                ));
            }
            continue;
        }
        let Some(keyword) = keyword else { continue };
        match keyword {
            "end_header" => break,
            "comment" | "obj_info" => {}
            "format" => {
                let found = match words.next() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::Little,
                    Some("binary_big_endian") => Encoding::Big,
                    other => {
                        return Err(err(
                            line_no,
                            format!(
                                "format \"{}\" is not one of ascii, binary_little_endian, \
                                 binary_big_endian",
                                shown(other.unwrap_or(""))
                            ),
                        ));
                    }
                };
                match words.next() {
                    Some("1.0" | "1") => {}
                    other => {
                        return Err(err(
                            line_no,
                            format!(
                                "format version \"{}\" is not supported (only 1.0)",
                                shown(other.unwrap_or(""))
                            ),
                        ));
                    }
                }
                if encoding.is_some_and(|e| e != found) {
                    return Err(err(
                        line_no,
                        "a second format line contradicts the first".into(),
                    ));
                }
                encoding = Some(found);
            }
            "element" => {
                let (Some(name), Some(count), None) = (words.next(), words.next(), words.next())
                else {
                    return Err(err(line_no, "expected \"element NAME COUNT\"".into()));
                };
                let count = count.parse::<u64>().map_err(|_| {
                    err(
                        line_no,
                        format!(
                            "element \"{}\": count \"{}\" is not a non-negative integer",
                            shown(name),
                            shown(count)
                        ),
                    )
                })?;
                if !element_names.insert(name.to_string()) {
                    return Err(err(
                        line_no,
                        format!("element \"{}\" is declared twice", shown(name)),
                    ));
                }
                property_names.clear();
                elements.push(ElementDef {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: line_no,
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(err(line_no, "a property before any element".into()));
                };
                let words: Vec<&str> = words.collect();
                let scalar = |w: &str| {
                    Scalar::parse(w).ok_or_else(|| {
                        err(
                            line_no,
                            format!(
                                "unknown type \"{}\" (expected char, uchar, short, ushort, \
                                 int, uint, float, double or int8 ... float64)",
                                shown(w)
                            ),
                        )
                    })
                };
                let (list, ty, name) = match words.as_slice() {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if !count.is_integer() {
                            return Err(err(
                                line_no,
                                format!(
                                    "the length of list \"{}\" has type {}, expected an \
                                     integer type",
                                    shown(name),
                                    count.name()
                                ),
                            ));
                        }
                        (Some(count), scalar(item)?, *name)
                    }
                    [ty, name] if *ty != "list" => (None, scalar(ty)?, *name),
                    _ => {
                        return Err(err(
                            line_no,
                            "expected \"property TYPE NAME\" or \"property list COUNT_TYPE \
                             ITEM_TYPE NAME\""
                                .into(),
                        ));
                    }
                };
                if !property_names.insert(name.to_string()) {
                    return Err(err(
                        line_no,
                        format!("property \"{}\" is declared twice", shown(name)),
                    ));
                }
                element.properties.push(Property {
                    name: name.to_string(),
                    list,
                    ty,
                    role: Role::Other,
                    line: line_no,
                });
            }
            other => {
                return Err(err(
                    line_no,
                    format!(
                        "unknown keyword \"{}\" (expected format, element, property, comment, \
                         obj_info or end_header)",
                        shown(other)
                    ),
                ));
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(err(line_no, "no \"format\" line before end_header".into()));
    };
    Ok(Header {
        encoding,
        elements,
        body: offset,
        body_line: line_no + 1,
    })
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

/// Marks the properties the mesh uses, checking the vertex and face elements.
fn assign_roles(path: &Path, elements: &mut [ElementDef]) -> Result<()> {
    let err = |line: usize, m: String| Error::parse(path, line, format!("PLY header: {m}"));
    for e in elements.iter_mut() {
        match e.name.as_str() {
            "vertex" => {
                for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                    let Some(p) = e.properties.iter_mut().find(|p| p.name == axis) else {
                        return Err(err(
                            e.line,
                            format!("the vertex element has no property {axis}"),
                        ));
                    };
                    if p.list.is_some() {
                        return Err(err(
                            p.line,
                            format!(
                                "property {axis} of the vertex element is a list, expected a number"
                            ),
                        ));
                    }
                    p.role = Role::Axis(k);
                }
            }
            "face" => {
                let mut lists = e.properties.iter_mut().filter(|p| is_index_list(&p.name));
                let Some(p) = lists.next() else {
                    return Err(err(
                        e.line,
                        "the face element has no vertex_indices (or vertex_index) list".into(),
                    ));
                };
                if let Some(second) = lists.next() {
                    return Err(err(
                        second.line,
                        "the face element has both a vertex_indices and a vertex_index list \
                         (which one holds the corners is ambiguous)"
                            .into(),
                    ));
                }
                if p.list.is_none() {
                    return Err(err(p.line, format!("property {} is not a list", p.name)));
                }
                if !p.ty.is_integer() {
                    return Err(err(
                        p.line,
                        format!(
                            "vertex indices are floating-point numbers ({}), expected integers",
                            p.ty.name()
                        ),
                    ));
                }
                p.role = Role::Corners;
            }
            _ => {}
        }
    }
    Ok(())
}

/// What the mesh takes from the body.
#[derive(Default)]
struct Mesh {
    positions: Vec<DVec3>,
    face_starts: Vec<usize>,
    face_indices: Vec<i64>,
    /// The line of each face (ASCII), for index errors found after reading.
    face_lines: Vec<usize>,
}

/// The body being read, and where.
struct Body<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
    /// The 1-based line of the next ASCII line.
    line: usize,
}

/// One element's values that the mesh uses.
#[derive(Default)]
struct Values {
    xyz: [f64; 3],
}

impl Body<'_> {
    /// An error about element `index` of `def`: at its line in ASCII (`line`), naming
    /// the element otherwise.
    fn error(&self, def: &ElementDef, index: u64, line: usize, message: String) -> Error {
        let element = format!("{} {index}", def.name);
        match self.encoding {
            Encoding::Ascii => Error::parse(self.path, line, format!("{element}: {message}")),
            _ => Error::format(self.path, element, message),
        }
    }

    fn truncated(&self, def: &ElementDef, index: u64) -> String {
        format!(
            "truncated: the header announces {} {} element(s), the file ends at {} {index}",
            def.count, def.name, def.name
        )
    }

    /// Skips every element of `def` (not needed by the mesh).
    fn skip(&mut self, def: &ElementDef, corners: &mut Vec<i64>) -> Result<()> {
        if self.encoding != Encoding::Ascii
            && let Some(size) = def.fixed_size()
        {
            let total = size.checked_mul(def.count);
            let left = (self.bytes.len() - self.at) as u64;
            if total.is_none_or(|t| t > left) {
                let index = left / size.max(1);
                return Err(self.error(def, index, 0, self.truncated(def, index)));
            }
            self.at += total.unwrap_or(0) as usize;
            return Ok(());
        }
        if def.properties.is_empty() {
            return Ok(()); // an element without properties takes no line
        }
        let mut values = Values::default();
        for i in 0..def.count {
            corners.clear();
            self.read(def, i, &mut values, corners)?;
        }
        Ok(())
    }

    /// Reads element `index` of `def`: its coordinates into `values`, its corner list
    /// appended to `corners`. Returns the element's line (ASCII; 0 in binary).
    fn read(
        &mut self,
        def: &ElementDef,
        index: u64,
        values: &mut Values,
        corners: &mut Vec<i64>,
    ) -> Result<usize> {
        match self.encoding {
            Encoding::Ascii => self.read_ascii(def, index, values, corners),
            _ => self.read_binary(def, index, values, corners).map(|()| 0),
        }
    }

    fn read_ascii(
        &mut self,
        def: &ElementDef,
        index: u64,
        values: &mut Values,
        corners: &mut Vec<i64>,
    ) -> Result<usize> {
        // The next non-blank line.
        let (raw, line) = loop {
            if self.at >= self.bytes.len() {
                return Err(self.error(def, index, self.line, self.truncated(def, index)));
            }
            let end = self.bytes[self.at..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(self.bytes.len(), |i| self.at + i);
            let raw = &self.bytes[self.at..end];
            self.at = (end + 1).min(self.bytes.len());
            let line = self.line;
            self.line += 1;
            if !raw.trim_ascii().is_empty() {
                break (raw, line);
            }
        };
        let text = String::from_utf8_lossy(raw);
        let mut tokens = text.split_ascii_whitespace();
        let fail = |m: String| self.error(def, index, line, m);
        let mut taken = 0usize;
        let mut next = |what: &str| {
            taken += 1;
            tokens.next().ok_or_else(|| {
                format!(
                    "the line ends after {} value(s), but {what} is still to come",
                    taken - 1
                )
            })
        };
        for p in &def.properties {
            match p.list {
                None => {
                    let tok = next(&format!("property {}", p.name)).map_err(fail)?;
                    let v =
                        p.ty.parse_text(tok)
                            .map_err(|m| fail(format!("property {}: {m}", p.name)))?;
                    if let Role::Axis(k) = p.role {
                        values.xyz[k] = v;
                    }
                }
                Some(count_type) => {
                    let tok = next(&format!("the length of list {}", p.name)).map_err(fail)?;
                    let n = count_type
                        .parse_text(tok)
                        .map_err(|m| fail(format!("length of list {}: {m}", p.name)))?;
                    if n < 0.0 {
                        return Err(fail(format!("list {} has a negative length {n}", p.name)));
                    }
                    for _ in 0..n as u64 {
                        let tok = next(&format!("an item of list {}", p.name)).map_err(fail)?;
                        let v =
                            p.ty.parse_text(tok)
                                .map_err(|m| fail(format!("list {}: {m}", p.name)))?;
                        if p.role == Role::Corners {
                            corners.push(v as i64);
                        }
                    }
                }
            }
        }
        let extra = tokens.count();
        if extra > 0 {
            return Err(fail(format!(
                "{} values on the line, the header's properties take {taken}",
                taken + extra
            )));
        }
        Ok(line)
    }

    fn read_binary(
        &mut self,
        def: &ElementDef,
        index: u64,
        values: &mut Values,
        corners: &mut Vec<i64>,
    ) -> Result<()> {
        let little = self.encoding == Encoding::Little;
        for p in &def.properties {
            match p.list {
                None => {
                    let v = self.take(def, index, p.ty, little)?;
                    if let Role::Axis(k) = p.role {
                        values.xyz[k] = v;
                    }
                }
                Some(count_type) => {
                    let n = self.take(def, index, count_type, little)?;
                    if n < 0.0 {
                        return Err(self.error(
                            def,
                            index,
                            0,
                            format!("list {} has a negative length {n}", p.name),
                        ));
                    }
                    let n = n as usize;
                    let size = p.ty.size();
                    if n.saturating_mul(size) > self.bytes.len() - self.at {
                        return Err(self.error(def, index, 0, self.truncated(def, index)));
                    }
                    if p.role == Role::Corners {
                        for k in 0..n {
                            let v = p.ty.decode(&self.bytes[self.at + k * size..], little);
                            corners.push(v as i64);
                        }
                    }
                    self.at += n * size;
                }
            }
        }
        Ok(())
    }

    /// One binary value.
    fn take(&mut self, def: &ElementDef, index: u64, ty: Scalar, little: bool) -> Result<f64> {
        let size = ty.size();
        if self.bytes.len() - self.at < size {
            return Err(self.error(def, index, 0, self.truncated(def, index)));
        }
        let v = ty.decode(&self.bytes[self.at..], little);
        self.at += size;
        Ok(v)
    }
}

/// Loads a PLY file from its bytes (`path` names it in messages).
pub fn load(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let bytes = strip_bom(bytes);
    let Header {
        encoding,
        mut elements,
        body,
        body_line,
    } = parse_header(path, bytes)?;
    assign_roles(path, &mut elements)?;
    let mut body = Body {
        path,
        bytes,
        at: body,
        encoding,
        line: body_line,
    };
    // Reserve by what the file can hold, not by what its header claims.
    let cap = |count: u64| count.min((bytes.len() / 4) as u64) as usize;
    let mut mesh = Mesh {
        face_starts: vec![0],
        ..Mesh::default()
    };
    let has = |name: &str| elements.iter().any(|e| e.name == name);
    let (mut have_vertices, mut have_faces) = (!has("vertex"), !has("face"));
    let mut corners = Vec::new();
    let mut values = Values::default();
    for def in &elements {
        if have_vertices && have_faces {
            break; // later elements cannot change the mesh
        }
        match def.name.as_str() {
            "vertex" => {
                mesh.positions.reserve(cap(def.count));
                for i in 0..def.count {
                    let line = body.read(def, i, &mut values, &mut corners)?;
                    let p = DVec3::from_array(values.xyz);
                    if !p.is_finite() {
                        let shown = values.xyz.map(|c| c.to_string()).join(", ");
                        return Err(body.error(
                            def,
                            i,
                            line,
                            format!("non-finite coordinate ({shown})"),
                        ));
                    }
                    if let Some(m) = coordinate_out_of_range(values.xyz) {
                        return Err(body.error(def, i, line, m));
                    }
                    mesh.positions.push(p);
                }
                have_vertices = true;
            }
            "face" => {
                mesh.face_lines.reserve(cap(def.count));
                for i in 0..def.count {
                    let line = body.read(def, i, &mut values, &mut mesh.face_indices)?;
                    let start = mesh.face_starts[mesh.face_starts.len() - 1];
                    let found = mesh.face_indices.len() - start;
                    if found < 3 {
                        return Err(body.error(
                            def,
                            i,
                            line,
                            format!("a face needs at least 3 vertices, found {found}"),
                        ));
                    }
                    mesh.face_starts.push(mesh.face_indices.len());
                    mesh.face_lines.push(line);
                }
                have_faces = true;
            }
            _ => body.skip(def, &mut corners)?,
        }
    }
    build(path, encoding, mesh)
}

fn build(path: &Path, encoding: Encoding, mesh: Mesh) -> Result<Loaded> {
    let mut loaded = Loaded::default();
    let mut b = MeshBuilder::with_capacity(mesh.positions.len(), mesh.face_lines.len());
    for &p in &mesh.positions {
        b.push_position(p);
    }
    let n = mesh.positions.len();
    let mut face = Vec::new();
    for (k, w) in mesh.face_starts.windows(2).enumerate() {
        let fail = |message: String| match encoding {
            Encoding::Ascii => {
                Error::parse(path, mesh.face_lines[k], format!("face {k}: {message}"))
            }
            _ => Error::format(path, format!("face {k}"), message),
        };
        face.clear();
        for &i in &mesh.face_indices[w[0]..w[1]] {
            if i < 0 || i as u64 >= n as u64 {
                return Err(fail(format!(
                    "vertex index {i} is out of range (the file has {n} vertices, indices 0..{})",
                    n.saturating_sub(1)
                )));
            }
            face.push(i as u32);
        }
        b.push_face(&face, None).map_err(|e| fail(e.to_string()))?;
    }
    let object = finish_object(file_stem(path), b, palette_color(0), &mut loaded.report);
    loaded.objects.push(object);
    Ok(loaded)
}
