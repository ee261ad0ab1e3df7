//! STL (stereolithography) triangle files, binary and ASCII, read here in one pass.
//!
//! Input: the bytes of a `.stl` file. Output: one object per solid (named after the
//! ASCII `solid` name, or the file) whose faces are the facets in file order; vertices
//! are welded by exact position so that edge adjacency (closed-mesh detection) sees
//! shared edges. The stored facet normal is ignored: the winding (counter-clockwise
//! seen from outside, as the format requires) gives the front side.
//!
//! Format detection, in this order:
//! 1. binary when the size is exactly `84 + 50 n`, `n` being the facet count in bytes
//!    80..84, even when the header starts with `solid` (many exporters write that);
//! 2. ASCII when the text starts with `solid` in any case (`SOLID`, `Solid`), after an
//!    optional UTF-8 byte-order mark and white space, and the first kilobyte holds no
//!    NUL byte;
//! 3. binary when the first kilobyte holds a NUL byte (a binary file whose size does
//!    not match its count: truncated, an error, or with trailing bytes, a warning);
//! 4. otherwise an error saying what either form must look like, and what the file
//!    starts with.
//!
//! ASCII grammar (keywords in any case, one statement per line, any white space):
//! `solid [name]`, then for each facet `facet [normal nx ny nz]`, `outer loop`, three
//! (or more: an n-gon is one face) `vertex x y z`, `endloop`, `endfacet`; then
//! `endsolid [name]`. A file may hold several solids (some exporters write one per
//! part): one object each, in file order, face ids counted across the file. Text
//! after the last `endsolid` that does not start another solid is ignored with a
//! warning; a missing final `endsolid` is accepted.
//!
//! Errors: ASCII ones name `file:line`, the facet (0-based, counted across the file)
//! and, from the second solid on, the solid; binary ones name the facet. A non-finite
//! coordinate, a coordinate beyond
//! [`MAX_COORDINATE`](crate::scene::MAX_COORDINATE), an unexpected statement (naming
//! what was expected and what was found), a file ending inside a facet, a binary file
//! shorter than its header announces (truncated). Trailing bytes after the announced
//! binary facets are a warning.
//!
//! Complexity: O(file size), one hash lookup per corner, however many solids the file
//! holds. Source: the 3D Systems StereoLithography Interface Specification (1989).

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;

use super::{Loaded, coordinate_out_of_range, file_stem, finish_object, palette_color, strip_bom};
use crate::scene::MeshBuilder;
use crate::{Error, Result};

/// Size of the binary header (80 bytes) plus the facet count (4 bytes).
const BINARY_HEADER: u64 = 84;
/// Size of one binary facet: normal and three vertices (12 `f32`) and 2 attribute bytes.
const BINARY_FACET: u64 = 50;
/// How far a NUL byte is looked for to tell a binary file from text.
const SNIFF: usize = 1024;

/// Loads an STL file from its bytes (`path` names it in messages).
pub fn load(path: &Path, bytes: Vec<u8>) -> Result<Loaded> {
    match kind(&bytes) {
        Kind::Binary => load_binary(path, &bytes),
        Kind::Ascii => load_ascii(path, strip_bom(&bytes)),
        Kind::Neither => Err(Error::format(
            path,
            "header",
            format!(
                "not an STL file: an ASCII STL starts with \"solid\", a binary one has an \
                 84-byte header and 50 bytes per facet ({}), but this file {}",
                binary_size_note(&bytes),
                starts_with(&bytes)
            ),
        )),
    }
}

/// What the detection rule of the module doc decides.
#[derive(Debug, PartialEq, Eq)]
enum Kind {
    Binary,
    Ascii,
    Neither,
}

fn kind(bytes: &[u8]) -> Kind {
    if announced_size(bytes).is_some_and(|size| size == bytes.len() as u64) {
        return Kind::Binary;
    }
    let has_nul = bytes[..bytes.len().min(SNIFF)].contains(&0);
    let text = strip_bom(bytes).trim_ascii_start();
    let says_solid = text.len() >= 5
        && text[..5].eq_ignore_ascii_case(b"solid")
        && text.get(5).is_none_or(u8::is_ascii_whitespace);
    if says_solid && !has_nul {
        Kind::Ascii
    } else if has_nul {
        Kind::Binary
    } else {
        Kind::Neither
    }
}

/// The size a binary file of this header has: `84 + 50 n`.
fn announced_size(bytes: &[u8]) -> Option<u64> {
    let n = bytes.get(80..84)?;
    Some(BINARY_HEADER + BINARY_FACET * u64::from(u32::from_le_bytes([n[0], n[1], n[2], n[3]])))
}

/// What the size rule says of a file that is neither form.
fn binary_size_note(bytes: &[u8]) -> String {
    match announced_size(bytes) {
        Some(size) => format!(
            "bytes 80..84 would announce {} facets, {size} bytes, the file has {}",
            (size - BINARY_HEADER) / BINARY_FACET,
            bytes.len()
        ),
        None => format!("the file has {} bytes", bytes.len()),
    }
}

/// "starts with ..." for a message: printable ASCII quoted, anything else in hex.
fn starts_with(bytes: &[u8]) -> String {
    let head = strip_bom(bytes).trim_ascii_start();
    let head = &head[..head.len().min(16)];
    if head.is_empty() {
        "holds only white space".into()
    } else if head.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
        format!("starts with \"{}\"", String::from_utf8_lossy(head))
    } else {
        let hex: Vec<String> = head.iter().map(|b| format!("{b:02X}")).collect();
        format!("starts with the bytes {}", hex.join(" "))
    }
}

/// Welds corners by exact position into one solid's builder.
struct Solid {
    name: String,
    builder: MeshBuilder,
    weld: HashMap<[u64; 3], u32>,
}

impl Solid {
    fn new(name: String) -> Self {
        Solid {
            name,
            builder: MeshBuilder::new(),
            weld: HashMap::new(),
        }
    }

    /// The vertex id of a position (checked finite and in range by the caller).
    fn vertex(&mut self, p: [f64; 3]) -> u32 {
        // +0.0 turns -0.0 into +0.0 so both weld together.
        let key = p.map(|x| (x + 0.0).to_bits());
        let b = &mut self.builder;
        *self
            .weld
            .entry(key)
            .or_insert_with(|| b.push_position(DVec3::from_array(p)))
    }

    fn finish(self, loaded: &mut Loaded) {
        let color = palette_color(loaded.objects.len());
        let object = finish_object(self.name, self.builder, color, &mut loaded.report);
        loaded.objects.push(object);
    }
}

/// Why a vertex cannot be used, if it cannot.
fn bad_vertex(c: usize, p: [f64; 3]) -> Option<String> {
    if let Some(bad) = p.iter().find(|x| !x.is_finite()) {
        return Some(format!("vertex {c} has a non-finite coordinate ({bad})"));
    }
    coordinate_out_of_range(p).map(|m| format!("vertex {c}: {m}"))
}

fn load_binary(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let len = bytes.len() as u64;
    let Some(expected) = announced_size(bytes) else {
        return Err(Error::format(
            path,
            "header",
            format!(
                "truncated: {len} bytes, but a binary STL has an 84-byte header (and an \
                 ASCII one starts with \"solid\")"
            ),
        ));
    };
    let n = (expected - BINARY_HEADER) / BINARY_FACET;
    let mut loaded = Loaded::default();
    if len < expected {
        return Err(Error::format(
            path,
            format!("facet {}", (len - BINARY_HEADER) / BINARY_FACET),
            format!(
                "truncated: the header announces {n} facets ({expected} bytes) but the file \
                 has {len} bytes"
            ),
        ));
    }
    if len > expected {
        loaded.report.messages.push(format!(
            "{} bytes after the {n} facets the header announces were ignored",
            len - expected
        ));
    }
    let mut solid = Solid::new(file_stem(path));
    // `n` facets fit in the file, so this reserves by the file's size.
    solid.builder = MeshBuilder::with_capacity(n as usize / 2, n as usize);
    solid.weld.reserve(n as usize / 2);
    let facets = bytes[BINARY_HEADER as usize..expected as usize].chunks_exact(50);
    for (k, facet) in facets.enumerate() {
        let f = |i: usize| {
            let at = 12 + 4 * i;
            f64::from(f32::from_le_bytes([
                facet[at],
                facet[at + 1],
                facet[at + 2],
                facet[at + 3],
            ]))
        };
        let mut tri = [0u32; 3];
        for (c, id) in tri.iter_mut().enumerate() {
            let p = [f(3 * c), f(3 * c + 1), f(3 * c + 2)];
            if let Some(m) = bad_vertex(c, p) {
                return Err(Error::format(path, format!("facet {k}"), m));
            }
            *id = solid.vertex(p);
        }
        solid
            .builder
            .push_face(&tri, None)
            .map_err(|e| Error::format(path, format!("facet {k}"), e.to_string()))?;
    }
    solid.finish(&mut loaded);
    Ok(loaded)
}

/// Where the ASCII reader is in the grammar.
#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    /// Before a `solid` (or after an `endsolid`).
    Outside,
    /// In a solid, between facets.
    Solid,
    /// After `facet`, before `outer loop`.
    Facet,
    /// Between `outer loop` and `endloop`.
    Loop,
    /// After `endloop`, before `endfacet`.
    LoopDone,
}

impl State {
    /// What may come next, for messages.
    fn expected(self) -> &'static str {
        match self {
            State::Outside => "\"solid\"",
            State::Solid => "\"facet\" or \"endsolid\"",
            State::Facet => "\"outer loop\"",
            State::Loop => "\"vertex x y z\" or \"endloop\"",
            State::LoopDone => "\"endfacet\"",
        }
    }
}

/// The text of a line after its first word, trimmed (a solid's name).
fn rest_after_keyword(line: &[u8]) -> String {
    let line = line.trim_ascii_start();
    let end = line
        .iter()
        .position(u8::is_ascii_whitespace)
        .unwrap_or(line.len());
    String::from_utf8_lossy(line[end..].trim_ascii()).into_owned()
}

/// A token quoted for a message (at most 40 bytes of it).
fn quoted(tok: &[u8]) -> String {
    let shown = &tok[..tok.len().min(40)];
    let more = if tok.len() > 40 { "..." } else { "" };
    format!(
        "\"{}{more}\"",
        String::from_utf8_lossy(shown).escape_debug()
    )
}

fn load_ascii(path: &Path, text: &[u8]) -> Result<Loaded> {
    let mut loaded = Loaded::default();
    let mut state = State::Outside;
    let mut solid: Option<Solid> = None;
    // The solid being read (0-based) and its name, for messages.
    let mut solid_index = 0usize;
    let mut solid_name = String::new();
    let mut solids_seen = 0usize;
    // Facets read so far in the file (face ids count across solids).
    let mut facet = 0usize;
    let mut corners: Vec<u32> = Vec::with_capacity(3);
    let mut offset = 0usize;
    let mut line_no = 0usize;
    while offset < text.len() {
        let end = text[offset..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(text.len(), |i| offset + i);
        let line = &text[offset..end];
        let line_start = offset;
        offset = end + 1;
        line_no += 1;
        let mut tokens = line
            .split(u8::is_ascii_whitespace)
            .filter(|t| !t.is_empty());
        let Some(keyword) = tokens.next() else {
            continue;
        };
        let is = |word: &[u8]| keyword.eq_ignore_ascii_case(word);
        let what = || {
            let at = if solid_index > 0 {
                format!("solid {solid_index} (\"{solid_name}\") ")
            } else {
                String::new()
            };
            if matches!(state, State::Outside | State::Solid) {
                at.trim_end().to_string()
            } else {
                format!("{at}facet {facet}")
            }
        };
        let fail = |message: String| {
            let what = what();
            let message = if what.is_empty() {
                message
            } else {
                format!("{what}: {message}")
            };
            Error::parse(path, line_no, message)
        };
        let unexpected = || {
            fail(format!(
                "expected {}, found {}",
                state.expected(),
                quoted(line.trim_ascii())
            ))
        };
        match state {
            State::Outside => {
                if !is(b"solid") {
                    // Only after a first solid: detection saw "solid" at the start.
                    let rest = &text[line_start..];
                    loaded.report.messages.push(format!(
                        "line {line_no}: {} bytes after the last endsolid that do not start \
                         another solid were ignored",
                        rest.len()
                    ));
                    break;
                }
                let name = rest_after_keyword(line);
                let name = if name.is_empty() {
                    file_stem(path)
                } else {
                    name
                };
                solid_index = solids_seen;
                solids_seen += 1;
                solid_name.clone_from(&name);
                solid = Some(Solid::new(name));
                state = State::Solid;
            }
            State::Solid => {
                if is(b"facet") {
                    corners.clear();
                    state = State::Facet;
                } else if is(b"endsolid") {
                    if let Some(s) = solid.take() {
                        s.finish(&mut loaded);
                    }
                    state = State::Outside;
                } else {
                    return Err(unexpected());
                }
            }
            State::Facet => {
                let second = tokens.next();
                if is(b"outer") && second.is_some_and(|t| t.eq_ignore_ascii_case(b"loop")) {
                    state = State::Loop;
                } else {
                    return Err(unexpected());
                }
            }
            State::Loop => {
                if is(b"vertex") {
                    let mut p = [0.0f64; 3];
                    for (k, c) in p.iter_mut().enumerate() {
                        let tok = tokens.next().ok_or_else(|| {
                            fail(format!("a vertex needs x, y and z; found {k} number(s)"))
                        })?;
                        *c = std::str::from_utf8(tok)
                            .ok()
                            .and_then(|s| s.parse::<f64>().ok())
                            .ok_or_else(|| fail(format!("{} is not a number", quoted(tok))))?;
                    }
                    if let Some(extra) = tokens.next() {
                        return Err(fail(format!(
                            "a vertex has three coordinates; found {} after them",
                            quoted(extra)
                        )));
                    }
                    if let Some(m) = bad_vertex(corners.len(), p) {
                        return Err(fail(m));
                    }
                    let s = solid.as_mut().expect("a solid is open in a loop");
                    corners.push(s.vertex(p));
                } else if is(b"endloop") {
                    if corners.len() < 3 {
                        return Err(fail(format!(
                            "a facet needs 3 vertices, found {}",
                            corners.len()
                        )));
                    }
                    state = State::LoopDone;
                } else {
                    return Err(unexpected());
                }
            }
            State::LoopDone => {
                if !is(b"endfacet") {
                    return Err(unexpected());
                }
                let s = solid.as_mut().expect("a solid is open in a facet");
                s.builder
                    .push_face(&corners, None)
                    .map_err(|e| fail(e.to_string()))?;
                facet += 1;
                state = State::Solid;
            }
        }
    }
    if matches!(state, State::Facet | State::Loop | State::LoopDone) {
        let at = if solid_index > 0 {
            format!("solid {solid_index} ")
        } else {
            String::new()
        };
        return Err(Error::parse(
            path,
            line_no.max(1),
            format!(
                "{at}facet {facet}: truncated: the file ends inside the facet (expected {})",
                state.expected()
            ),
        ));
    }
    // A last solid without its endsolid is kept.
    if let Some(s) = solid {
        s.finish(&mut loaded);
    }
    Ok(loaded)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detection_follows_the_module_rules() {
        assert_eq!(kind(b"SOLID x\n"), Kind::Ascii);
        assert_eq!(kind(b"\xEF\xBB\xBF  \n Solid\n"), Kind::Ascii);
        assert_eq!(kind(b"solidify\n"), Kind::Neither);
        assert_eq!(kind(b"hello world\n"), Kind::Neither);
        assert_eq!(kind(b"solid\0\n"), Kind::Binary);
        let mut binary = vec![b'x'; 84];
        binary[80..84].copy_from_slice(&0u32.to_le_bytes());
        assert_eq!(kind(&binary), Kind::Binary);
    }
}
