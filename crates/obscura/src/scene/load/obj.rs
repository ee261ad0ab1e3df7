//! Wavefront OBJ: polygonal geometry with objects, groups and MTL diffuse colours.
//!
//! Input: the bytes of a `.obj` file (UTF-8; invalid bytes are replaced, which only
//! matters inside names). Output: one object per `o` or `g` statement that is followed
//! by faces (named from the statement, the first name when `g` lists several), plus one
//! for faces before the first such statement (named after the file). Each object gets
//! its own mesh holding only the vertices its faces use, so face ids (`f` lines in file
//! order) follow the objects in order, as the scene numbers them.
//!
//! Read: `v x y z [w]` (`w` and trailing vertex colours are accepted and ignored), `f`
//! with `v`, `v/vt`, `v//vn` and `v/vt/vn` references, negative (relative) indices,
//! `o`, `g`, `usemtl`, `mtllib` (diffuse `Kd` through [`super::mtl`], resolved relative
//! to the OBJ file by the rule of `super::reference`), comments (`#` to the end of the line), blank lines, `\` line
//! continuations, CRLF line ends. Ignored: `vt`, `vn`, `vp`, `l`, `p`, `s` and every
//! other statement (curves, surfaces, display attributes).
//!
//! A UTF-8 byte-order mark at the start of the file is skipped.
//!
//! Errors (naming `file:line`): a malformed number, a non-finite coordinate (NaN,
//! infinity or an overflowing value), a coordinate beyond
//! [`MAX_COORDINATE`](crate::scene::MAX_COORDINATE), a face with fewer than three vertices, index 0,
//! a relative index reaching before the first vertex, an index beyond the file's
//! vertices (checked once the whole file is read, so forward references are accepted),
//! an `mtllib` leading out of the OBJ's folder tree (an absolute path, `..`, a symbolic
//! link: [`Error::OutsideReference`], whether or not a material is used, unless
//! [`LoadOptions::allow_outside_references`](super::LoadOptions) is set).
//! Warnings (in the [`LoadReport`](crate::scene::LoadReport)): an unreadable material
//! library, unknown material names (one warning for all of them, with the first few
//! names and lines).
//!
//! Why not `tobj`: it cannot report the line of a bad statement, and every loader
//! error here must name its file and line.
//!
//! Complexity: one pass over the text, then one over the faces; O(bytes + faces). A
//! library named on several `mtllib` lines is read once; per-object vertex and
//! material tables are stamped, not reset, so many objects cost nothing extra.
//! Source: the Wavefront OBJ and MTL specifications (Appendix B1/B2 of the Advanced
//! Visualizer manual); the degenerate/non-planar face rules are `MeshBuilder`'s.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use super::reference::{Sources, Syntax};
use super::{
    LoadOptions, Loaded, Tally, coordinate_out_of_range, file_stem, finish_object, mtl,
    palette_color, strip_bom,
};
use crate::scene::{FaceError, Material, MeshBuilder};
use crate::{Error, Result};
use glam::DVec3;

/// Sentinel for "no material" in the per-face material table.
const NO_MATERIAL: u32 = u32::MAX;

/// A run of consecutive faces started by `o` or `g` (or the file start).
struct Run {
    name: String,
    first_face: usize,
}

/// Everything the text pass collects; meshes are built from it afterwards.
#[derive(Default)]
struct Parsed {
    positions: Vec<DVec3>,
    /// Face `k` uses `face_indices[face_starts[k]..face_starts[k + 1]]` (0-based,
    /// relative indices already resolved; positive ones not yet range-checked).
    face_starts: Vec<usize>,
    face_indices: Vec<u64>,
    face_lines: Vec<u32>,
    face_materials: Vec<u32>,
    runs: Vec<Run>,
    material_names: Vec<String>,
    material_lines: Vec<usize>,
    libraries: Vec<(String, usize)>,
}

/// Loads an OBJ file from its bytes (`path` names it in messages and resolves `mtllib`),
/// with the default [`LoadOptions`]: material libraries only inside its folder tree.
pub fn load(path: &Path, bytes: &[u8]) -> Result<Loaded> {
    let options = LoadOptions::default();
    load_in(path, bytes, &mut Sources::new(&options))
}

/// [`load`] within a load: its options say which libraries may be read, and the
/// libraries read are recorded in `sources`.
pub(crate) fn load_in(path: &Path, bytes: &[u8], sources: &mut Sources<'_>) -> Result<Loaded> {
    let parsed = parse(path, bytes)?;
    build(path, parsed, sources)
}

/// White space between OBJ tokens (a lone `\r` of a CRLF line end included).
fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\x0b' | b'\x0c')
}

/// The tokens of a line, stopping at a `#` comment.
struct Tokens<'a> {
    s: &'a [u8],
    i: usize,
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];
    fn next(&mut self) -> Option<&'a [u8]> {
        let s = self.s;
        let mut i = self.i;
        while i < s.len() && is_blank(s[i]) {
            i += 1;
        }
        if i == s.len() || s[i] == b'#' {
            self.i = s.len();
            return None;
        }
        let start = i;
        while i < s.len() && !is_blank(s[i]) && s[i] != b'#' {
            i += 1;
        }
        self.i = i;
        Some(&s[start..i])
    }
}

fn text(tok: &[u8]) -> Cow<'_, str> {
    String::from_utf8_lossy(tok)
}

/// The text of a line after its keyword, without comment, trimmed (names may contain
/// spaces).
fn rest_of_line(line: &[u8], keyword: &[u8]) -> String {
    let start = line
        .windows(keyword.len())
        .position(|w| w == keyword)
        .map_or(line.len(), |i| i + keyword.len());
    let rest = &line[start..];
    let rest = &rest[..rest.iter().position(|&b| b == b'#').unwrap_or(rest.len())];
    text(rest).trim().to_string()
}

fn parse(path: &Path, bytes: &[u8]) -> Result<Parsed> {
    let err = |line: usize, message: String| Error::parse(path, line, message);
    let mut p = Parsed {
        face_starts: vec![0],
        runs: vec![Run {
            name: file_stem(path),
            first_face: 0,
        }],
        ..Parsed::default()
    };
    let mut material_ids: HashMap<String, u32> = HashMap::new();
    let mut current_material = NO_MATERIAL;
    let mut lines = strip_bom(bytes).split(|&b| b == b'\n');
    let mut line_no = 0usize;
    while let Some(raw) = lines.next() {
        line_no += 1;
        let first_line = line_no;
        let mut line: Cow<'_, [u8]> = Cow::Borrowed(raw);
        // A trailing backslash joins the next line (rare: only then do we allocate),
        // in place: linear in the joined length however many lines are joined.
        loop {
            let end = line.iter().rposition(|&b| !is_blank(b));
            if end.is_none_or(|e| line[e] != b'\\') {
                break;
            }
            let joined = line.to_mut();
            joined.truncate(end.unwrap_or(0));
            joined.push(b' ');
            let Some(next) = lines.next() else {
                break;
            };
            line_no += 1;
            joined.extend_from_slice(next);
        }
        let mut tokens = Tokens { s: &line, i: 0 };
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            b"v" => {
                let mut xyz = [0.0; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let tok = tokens.next().ok_or_else(|| {
                        err(
                            first_line,
                            format!("a vertex needs x, y and z; found {k} coordinate(s)"),
                        )
                    })?;
                    *c = parse_number(tok).map_err(|m| err(first_line, m))?;
                    if !c.is_finite() {
                        return Err(err(
                            first_line,
                            format!("coordinate \"{}\" is not finite", text(tok)),
                        ));
                    }
                }
                if let Some(m) = coordinate_out_of_range(xyz) {
                    return Err(err(first_line, m));
                }
                // w or vertex colours: must be numbers, otherwise unused.
                for tok in tokens {
                    parse_number(tok).map_err(|m| err(first_line, m))?;
                }
                p.positions.push(DVec3::from_array(xyz));
            }
            b"f" | b"fo" => {
                let before = p.face_indices.len();
                let n = p.positions.len() as u64;
                for tok in tokens {
                    let v = parse_reference(tok, n).map_err(|m| err(first_line, m))?;
                    p.face_indices.push(v);
                }
                let count = p.face_indices.len() - before;
                if count < 3 {
                    return Err(err(
                        first_line,
                        format!("a face needs at least 3 vertices, found {count}"),
                    ));
                }
                p.face_starts.push(p.face_indices.len());
                p.face_lines
                    .push(u32::try_from(first_line).unwrap_or(u32::MAX));
                p.face_materials.push(current_material);
            }
            b"o" | b"g" => {
                let name = tokens.next().map_or_else(
                    || {
                        if keyword == b"o" {
                            format!("object {}", p.runs.len())
                        } else {
                            "default".to_string()
                        }
                    },
                    |t| text(t).into_owned(),
                );
                p.runs.push(Run {
                    name,
                    first_face: p.face_lines.len(),
                });
            }
            b"usemtl" => {
                let name = rest_of_line(&line, keyword);
                current_material = if name.is_empty() {
                    NO_MATERIAL
                } else {
                    let next = p.material_names.len() as u32;
                    *material_ids.entry(name.clone()).or_insert_with(|| {
                        p.material_names.push(name);
                        p.material_lines.push(first_line);
                        next
                    })
                };
            }
            b"mtllib" => {
                let rest = rest_of_line(&line, keyword);
                let dir = path.parent().unwrap_or(Path::new(""));
                // A library name may contain spaces: take the whole rest when it names
                // a file, else the space-separated names.
                if !rest.is_empty() && dir.join(&rest).is_file() {
                    p.libraries.push((rest, first_line));
                } else {
                    for name in rest.split_ascii_whitespace() {
                        p.libraries.push((name.to_string(), first_line));
                    }
                }
            }
            _ => {}
        }
    }
    // Positive indices may point forward, so they are checked against the final count.
    let n = p.positions.len() as u64;
    for (k, w) in p.face_starts.windows(2).enumerate() {
        if let Some(&bad) = p.face_indices[w[0]..w[1]].iter().find(|&&i| i >= n) {
            return Err(err(
                p.face_lines[k] as usize,
                format!(
                    "vertex index {} is out of range: the file has {n} vertices",
                    bad + 1
                ),
            ));
        }
    }
    Ok(p)
}

/// Powers of ten that are exact in `f64`.
const EXACT_POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses a number, exactly as `str::parse::<f64>` does.
///
/// Plain decimals (`-12.345`) with a mantissa below 2^53 and at most 22 fraction
/// digits take Clinger's fast path: mantissa and power of ten are both exact, so one
/// correctly rounded division gives the correctly rounded result. Everything else
/// (exponents, long mantissas, `nan`, `inf`) goes to the standard library.
fn parse_number(tok: &[u8]) -> std::result::Result<f64, String> {
    let (neg, digits) = match tok.first() {
        Some(b'-') => (true, &tok[1..]),
        Some(b'+') => (false, &tok[1..]),
        _ => (false, tok),
    };
    let mut mantissa: u64 = 0;
    let mut fraction_digits: Option<usize> = None;
    let mut any_digit = false;
    let mut fast = digits.len() <= 19;
    for &b in digits {
        match b {
            b'0'..=b'9' => {
                mantissa = mantissa * 10 + u64::from(b - b'0');
                any_digit = true;
                if let Some(f) = fraction_digits.as_mut() {
                    *f += 1;
                }
            }
            b'.' if fraction_digits.is_none() => fraction_digits = Some(0),
            _ => {
                fast = false;
                break;
            }
        }
        if !fast {
            break;
        }
    }
    let k = fraction_digits.unwrap_or(0);
    if fast && any_digit && mantissa < (1 << 53) && k < EXACT_POW10.len() {
        let v = mantissa as f64 / EXACT_POW10[k];
        return Ok(if neg { -v } else { v });
    }
    std::str::from_utf8(tok)
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| format!("\"{}\" is not a number", text(tok)))
}

/// A decimal integer (optionally signed), or `None`.
fn parse_integer(tok: &[u8]) -> Option<i64> {
    let (neg, digits) = match tok.first() {
        Some(b'-') => (true, &tok[1..]),
        Some(b'+') => (false, &tok[1..]),
        _ => (false, tok),
    };
    if digits.is_empty() || digits.len() > 18 {
        return None;
    }
    let mut v: i64 = 0;
    for &b in digits {
        if !b.is_ascii_digit() {
            return None;
        }
        v = v * 10 + i64::from(b - b'0');
    }
    Some(if neg { -v } else { v })
}

/// Resolves one `v[/vt[/vn]]` reference of an `f` line to a 0-based vertex index,
/// `n` being the number of vertices defined so far (for negative indices).
fn parse_reference(tok: &[u8], n: u64) -> std::result::Result<u64, String> {
    let mut parts = tok.split(|&b| b == b'/');
    let v = parts.next().unwrap_or(b"");
    let index = parse_integer(v)
        .ok_or_else(|| format!("\"{}\": \"{}\" is not a vertex index", text(tok), text(v)))?;
    // Texture and normal references are unused but must be well formed.
    for (what, part) in ["texture", "normal"].iter().zip(parts.by_ref()) {
        if !part.is_empty() && !matches!(parse_integer(part), Some(i) if i != 0) {
            return Err(format!(
                "\"{}\": \"{}\" is not a {what} index",
                text(tok),
                text(part)
            ));
        }
    }
    if parts.next().is_some() {
        return Err(format!(
            "\"{}\" has too many '/' (expected v, v/vt, v//vn or v/vt/vn)",
            text(tok)
        ));
    }
    match index {
        0 => Err(format!(
            "\"{}\": vertex index 0 is invalid (OBJ indices start at 1, or count back from -1)",
            text(tok)
        )),
        i if i > 0 => Ok(i as u64 - 1),
        i => {
            let back = i.unsigned_abs();
            if back > n {
                Err(format!(
                    "relative vertex index {i} reaches before the first vertex ({n} vertices so far)"
                ))
            } else {
                Ok(n - back)
            }
        }
    }
}

fn build(path: &Path, p: Parsed, sources: &mut Sources<'_>) -> Result<Loaded> {
    let mut loaded = Loaded::default();
    let colors = resolve_materials(path, &p, sources, &mut loaded.report.messages)?;

    // Per-vertex remap shared by all objects: `stamp[v]` says which object last
    // mapped `v`, so no O(vertices) reset is needed per object.
    let mut stamp = vec![u32::MAX; p.positions.len()];
    let mut local = vec![0u32; p.positions.len()];
    // The same for materials: `material_stamp[m]` says which object last added `m`
    // (resetting a table of every material per object was O(objects x materials)).
    let mut material_stamp = vec![u32::MAX; p.material_names.len()];
    let mut local_material = vec![NO_MATERIAL; p.material_names.len()];
    let mut face = Vec::new();
    let face_total = p.face_lines.len();
    for (r, run) in p.runs.iter().enumerate() {
        let end = p.runs.get(r + 1).map_or(face_total, |n| n.first_face);
        if run.first_face == end {
            continue;
        }
        let faces = run.first_face..end;
        let corners = p.face_starts[end] - p.face_starts[run.first_face];
        let mut b = MeshBuilder::with_capacity(corners.min(p.positions.len()), faces.len());
        for f in faces {
            face.clear();
            for &v in &p.face_indices[p.face_starts[f]..p.face_starts[f + 1]] {
                let v = v as usize;
                if stamp[v] != r as u32 {
                    stamp[v] = r as u32;
                    local[v] = b.push_position(p.positions[v]);
                }
                face.push(local[v]);
            }
            let m = p.face_materials[f];
            let material = match colors.get(m as usize).copied().flatten() {
                Some(color) => {
                    if material_stamp[m as usize] != r as u32 {
                        material_stamp[m as usize] = r as u32;
                        local_material[m as usize] = b.push_material(Material {
                            name: p.material_names[m as usize].clone(),
                            color,
                        });
                    }
                    Some(local_material[m as usize])
                }
                None => None,
            };
            b.push_face(&face, material).map_err(|e: FaceError| {
                Error::parse(path, p.face_lines[f] as usize, e.to_string())
            })?;
        }
        let color = palette_color(loaded.objects.len());
        let object = finish_object(run.name.clone(), b, color, &mut loaded.report);
        loaded.objects.push(object);
    }
    Ok(loaded)
}

/// The colour of each material name used by `usemtl` (`None` when unknown), with a
/// warning per unreadable library and one for all unknown names. Every library is
/// checked against the folder rule, even when no material is used (and it is not
/// read): a refused reference is an error.
fn resolve_materials(
    path: &Path,
    p: &Parsed,
    sources: &mut Sources<'_>,
    warnings: &mut Vec<String>,
) -> Result<Vec<Option<[f32; 3]>>> {
    let mut resolved = Vec::with_capacity(p.libraries.len());
    // A library named again (on another `mtllib` line) is resolved and read once: its
    // materials are already in, first definition first.
    let mut named: std::collections::HashSet<&str> = std::collections::HashSet::new();
    for (name, line) in &p.libraries {
        if !named.insert(name.as_str()) {
            continue;
        }
        match sources.resolve(path, &format!("line {line}"), name, Syntax::Path) {
            Ok(lib) => resolved.push((Ok(lib), *line)),
            Err(e @ Error::OutsideReference { .. }) => return Err(e),
            Err(e) => resolved.push((Err(e), *line)),
        }
    }
    if p.material_names.is_empty() {
        return Ok(Vec::new());
    }
    let mut library: HashMap<String, [f32; 3]> = HashMap::new();
    for (lib, line) in resolved {
        match lib.and_then(|lib_path| mtl::load_in(&lib_path, sources, warnings)) {
            Ok(materials) => {
                for (m, color) in materials {
                    library.entry(m).or_insert(color);
                }
            }
            Err(e) => warnings.push(format!(
                "line {line}: material library not read ({e}); its materials use the object colour"
            )),
        }
    }
    let mut unknown = Tally::default();
    let colors = p
        .material_names
        .iter()
        .zip(&p.material_lines)
        .map(|(name, line)| {
            let color = library.get(name).copied();
            if color.is_none() {
                unknown.add(|| format!("\"{name}\" (line {line})"));
            }
            color
        })
        .collect();
    unknown.finish(warnings, |n| {
        format!("{n} unknown material(s), whose faces use the object colour")
    });
    Ok(colors)
}
