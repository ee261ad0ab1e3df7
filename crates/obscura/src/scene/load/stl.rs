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
//! exporters write that); otherwise it is ASCII when it starts with `solid` and has no
//! NUL byte in its first kilobyte, else binary.
//!
//! Errors (naming the file and the 0-based facet): a non-finite coordinate, a malformed
//! ASCII facet, a binary file shorter than its header announces (truncated). Trailing
//! bytes after the announced facets are a warning. Limitation: an ASCII file holding
//! several `solid` blocks yields the first one only (`stl_io` stops at `endsolid`).
//!
//! Complexity: O(facets) with one hash lookup per corner. Source: the 3D Systems
//! StereoLithography Interface Specification (1989).

use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use glam::DVec3;

use super::{Loaded, file_stem, finish_object, palette_color};
use crate::scene::MeshBuilder;
use crate::{Error, Result};

/// Size of the binary header (80 bytes) plus the facet count (4 bytes).
const BINARY_HEADER: u64 = 84;
/// Size of one binary facet: normal and three vertices (12 `f32`) and 2 attribute bytes.
const BINARY_FACET: u64 = 50;

/// Loads an STL file from its bytes (`path` names it in messages).
pub fn load(path: &Path, mut bytes: Vec<u8>) -> Result<Loaded> {
    let mut loaded = Loaded::default();
    let name;
    let count_hint;
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
                "{}: {} bytes after the {n} facets the header announces were ignored",
                path.display(),
                len - expected
            ));
        }
        // stl_io decides ASCII vs binary by a leading "solid "; make sure it reads
        // this header as binary.
        bytes[0] = 0;
        name = file_stem(path);
        count_hint = n as usize;
    } else {
        // stl_io wants the first line to be "solid NAME"; normalise it ("solid" alone,
        // leading blanks) and keep the name.
        let start = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(0);
        let eol = bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| start + i);
        let first = String::from_utf8_lossy(&bytes[start..eol]);
        let solid_name = first.trim().strip_prefix("solid").unwrap_or("").trim();
        name = if solid_name.is_empty() {
            file_stem(path)
        } else {
            solid_name.to_string()
        };
        let mut fixed = b"solid obscura\n".to_vec();
        fixed.extend_from_slice(&bytes[(eol + 1).min(bytes.len())..]);
        bytes = fixed;
        count_hint = bytes.len() / 200;
    }

    let mut cursor = Cursor::new(bytes);
    let reader = stl_io::create_stl_reader(&mut cursor)
        .map_err(|e| Error::format(path, "header", e.to_string()))?;
    let mut b = MeshBuilder::with_capacity(count_hint.min(1 << 24) / 2, count_hint.min(1 << 24));
    let mut weld: HashMap<[u32; 3], u32> = HashMap::with_capacity(count_hint.min(1 << 24) / 2);
    for (k, facet) in reader.enumerate() {
        let element = || format!("facet {k}");
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
    let object = finish_object(name, b, palette_color(0), &mut loaded.report);
    loaded.objects.push(object);
    Ok(loaded)
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
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let rest = &bytes[start..];
    let says_solid = rest.starts_with(b"solid") && rest.get(5).is_none_or(u8::is_ascii_whitespace);
    // A NUL byte early on is a binary file whose size does not match its facet count
    // (truncated or padded), not text.
    let has_nul = bytes[..bytes.len().min(1024)].contains(&0);
    !says_solid || has_nul
}
