//! STL (stereolithography) triangle files, binary and ASCII, read with `stl_io`.
//!
//! Input: the bytes of a `.stl` file. Output: one object (named after the ASCII
//! `solid` name, or the file) whose faces are the facets in file order; vertices are
//! welded by exact position so that edge adjacency (closed-mesh detection) sees shared
//! edges. The stored facet normal is ignored: the winding (counter-clockwise seen from
//! outside, as the format requires) gives the front side.
//!
//! Format detection: a file is binary when its size is exactly `84 + 50 n`, `n` being
//! the facet count in bytes 80..84, even when its header starts with `solid` (many
//! exporters write that); otherwise it is ASCII when it starts with `solid` (after an
//! optional UTF-8 byte-order mark and white space) and has no NUL byte in its first
//! kilobyte, else binary.
//!
//! An ASCII file holding several `solid ... endsolid` blocks (some exporters write one
//! per part) yields one object per solid, in file order; text after the last
//! `endsolid` that does not start another solid is ignored with a warning.
//!
//! Errors (naming the file and the 0-based facet, counted across the file; with several
//! solids, the solid too): a non-finite coordinate, a coordinate beyond
//! [`MAX_COORDINATE`](crate::scene::MAX_COORDINATE), a malformed ASCII facet, a binary
//! file shorter than its header announces (truncated). Trailing bytes after the
//! announced facets are a warning. Limitations: ASCII errors name the facet, not the
//! line (`stl_io` does not say where it stopped); keywords must be lower case.
//!
//! Complexity: O(facets) with one hash lookup per corner. Source: the 3D Systems
//! StereoLithography Interface Specification (1989).

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use glam::DVec3;

use super::{Loaded, coordinate_out_of_range, file_stem, finish_object, palette_color, strip_bom};
use crate::scene::MeshBuilder;
use crate::{Error, Result};

/// Size of the binary header (80 bytes) plus the facet count (4 bytes).
const BINARY_HEADER: u64 = 84;
/// Size of one binary facet: normal and three vertices (12 `f32`) and 2 attribute bytes.
const BINARY_FACET: u64 = 50;

/// Loads an STL file from its bytes (`path` names it in messages).
pub fn load(path: &Path, mut bytes: Vec<u8>) -> Result<Loaded> {
    let mut loaded = Loaded::default();
    if is_binary(&bytes) {
        if (bytes.len() as u64) < BINARY_HEADER {
            return Err(Error::format(
                path,
                "header",
                format!(
                    "truncated: {} bytes, but a binary STL has an 84-byte header (and an ASCII one starts with \"solid\")",
                    bytes.len()
                ),
            ));
        }
        let n = u64::from(u32::from_le_bytes([
            bytes[80], bytes[81], bytes[82], bytes[83],
        ]));
        let expected = BINARY_HEADER + BINARY_FACET * n;
        let len = bytes.len() as u64;
        if len < expected {
            return Err(Error::format(
                path,
                format!("facet {}", (len - BINARY_HEADER) / BINARY_FACET),
                format!(
                    "truncated: the header announces {n} facets ({expected} bytes) but the file has {len} bytes"
                ),
            ));
        }
        if len > expected {
            loaded.report.messages.push(format!(
                "{} bytes after the {n} facets the header announces were ignored",
                len - expected
            ));
        }
        // stl_io decides ASCII vs binary by a leading "solid "; make sure it reads
        // this header as binary.
        bytes[0] = 0;
        let object = read_solid(path, bytes, file_stem(path), n as usize, "", 0)?;
        finish(object, &mut loaded);
        return Ok(loaded);
    }
    let text = strip_bom(&bytes);
    let solids = split_solids(text);
    let several = solids.len() > 1;
    for (k, solid) in solids.iter().enumerate() {
        // stl_io wants the first line to be "solid NAME"; normalise it ("solid" alone,
        // leading blanks) and keep the name.
        let start = solid
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(0);
        let eol = solid[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(solid.len(), |i| start + i);
        let first = String::from_utf8_lossy(&solid[start..eol]);
        let solid_name = first.trim().strip_prefix("solid").unwrap_or("").trim();
        let name = if solid_name.is_empty() {
            file_stem(path)
        } else {
            solid_name.to_string()
        };
        let mut fixed = b"solid obscura\n".to_vec();
        fixed.extend_from_slice(&solid[(eol + 1).min(solid.len())..]);
        let hint = fixed.len() / 200;
        let prefix = if several {
            format!("solid {k} (\"{name}\") ")
        } else {
            String::new()
        };
        let first_facet = loaded.objects.iter().map(|o| o.mesh.face_count()).sum();
        let object = read_solid(path, fixed, name, hint, &prefix, first_facet)?;
        finish(object, &mut loaded);
    }
    let end: usize = solids.iter().map(|s| s.len()).sum();
    let rest = &text[end..];
    if !rest.iter().all(u8::is_ascii_whitespace) {
        let line = text[..end].iter().filter(|&&b| b == b'\n').count() + 1;
        loaded.report.messages.push(format!(
            "line {line}: {} bytes after the last endsolid that do not start another solid were ignored",
            rest.len()
        ));
    }
    Ok(loaded)
}

/// An ASCII file cut into its `solid ... endsolid` blocks (each ends after its
/// `endsolid` line; the last one may lack it). Bytes after an `endsolid` that do not
/// start another `solid` are left out (the caller warns about them).
fn split_solids(text: &[u8]) -> Vec<&[u8]> {
    let mut solids = Vec::new();
    let mut start = 0;
    let mut at = 0;
    while at < text.len() {
        let eol = text[at..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(text.len(), |i| at + i + 1);
        let line = text[at..eol].trim_ascii_start();
        at = eol;
        if line.starts_with(b"endsolid") {
            solids.push(&text[start..at]);
            start = at;
            let rest = text[at..].trim_ascii_start();
            if !rest.starts_with(b"solid") {
                return solids;
            }
        }
    }
    if start < text.len() || solids.is_empty() {
        solids.push(&text[start..]);
    }
    solids
}

/// Finishes a solid's builder into the next object of the file.
fn finish(object: (String, MeshBuilder), loaded: &mut Loaded) {
    let (name, b) = object;
    let color = palette_color(loaded.objects.len());
    let object = finish_object(name, b, color, &mut loaded.report);
    loaded.objects.push(object);
}

/// Reads the facets of one solid (binary, or ASCII with a normalised first line) into
/// a builder; errors name the facet, after `prefix` (the solid, when a file has
/// several), counting from `first_facet`.
fn read_solid(
    path: &Path,
    bytes: Vec<u8>,
    name: String,
    count_hint: usize,
    prefix: &str,
    first_facet: u32,
) -> Result<(String, MeshBuilder)> {
    let mut cursor = Cursor::new(bytes);
    let reader = stl_io::create_stl_reader(&mut cursor)
        .map_err(|e| Error::format(path, format!("{prefix}header"), e.to_string()))?;
    let count_hint = count_hint.min(1 << 24);
    let mut b = MeshBuilder::with_capacity(count_hint / 2, count_hint);
    let mut weld: HashMap<[u32; 3], u32> = HashMap::with_capacity(count_hint / 2);
    for (k, facet) in reader.enumerate() {
        let element = || format!("{prefix}facet {}", k + first_facet as usize);
        let facet = facet.map_err(|e| Error::format(path, element(), e.to_string()))?;
        let mut tri = [0u32; 3];
        for (c, v) in facet.vertices.iter().enumerate() {
            if let Some(bad) = v.0.iter().find(|x| !x.is_finite()) {
                return Err(Error::format(
                    path,
                    element(),
                    format!("vertex {c} has a non-finite coordinate ({bad})"),
                ));
            }
            if let Some(m) = coordinate_out_of_range(v.0.map(f64::from)) {
                return Err(Error::format(path, element(), format!("vertex {c}: {m}")));
            }
            // +0.0 turns -0.0 into +0.0 so both weld together.
            let key = v.0.map(|x| (x + 0.0).to_bits());
            tri[c] = *weld.entry(key).or_insert_with(|| {
                b.push_position(DVec3::new(
                    f64::from(v.0[0]),
                    f64::from(v.0[1]),
                    f64::from(v.0[2]),
                ))
            });
        }
        b.push_face(&tri, None)
            .map_err(|e| Error::format(path, element(), e.to_string()))?;
    }
    Ok((name, b))
}

/// Whether the bytes are a binary STL (see the module doc for the rule).
fn is_binary(bytes: &[u8]) -> bool {
    if bytes.len() as u64 >= BINARY_HEADER {
        let n = u64::from(u32::from_le_bytes([
            bytes[80], bytes[81], bytes[82], bytes[83],
        ]));
        if bytes.len() as u64 == BINARY_HEADER + BINARY_FACET * n {
            return true;
        }
    }
    let text = strip_bom(bytes);
    let start = text
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(text.len());
    let rest = &text[start..];
    let says_solid = rest.starts_with(b"solid") && rest.get(5).is_none_or(u8::is_ascii_whitespace);
    // A NUL byte early on is a binary file whose size does not match its facet count
    // (truncated or padded), not text.
    let has_nul = bytes[..bytes.len().min(1024)].contains(&0);
    !says_solid || has_nul
}
