//! Reading height fields: NumPy `.npy` (2D arrays of floats or integers, little-endian),
//! CSV (rows of numbers) and grayscale PNG (8 or 16 bits).
//!
//! Every loader checks the grid's size against the memory budget before it allocates
//! the heights, and names the file and the line (CSV) or element (NPY header, PNG) of
//! any error. Rows of the file are rows of the grid (`z`), columns are `x` (see
//! [`HeightField`]).

use std::path::Path;

use super::field::{BUDGET_STRUCTURE, HeightField, check_size};
use crate::budget::MemoryBudget;
use crate::{Error, Result};

impl HeightField {
    /// Reads a height field from a `.npy`, `.csv` (or `.txt`) or `.png` file, chosen by
    /// extension, held to the default memory budget. NPY values and CSV numbers are
    /// heights as they are; PNG values are divided by their maximum (255 or 65535), so
    /// heights lie in `[0, 1]`. The field spans `[-1, 1]^2` (see
    /// [`HeightField::with_extent`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        HeightField::load_with_budget(path, &MemoryBudget::default())
    }

    /// [`HeightField::load`] held to a memory budget.
    pub fn load_with_budget(path: impl AsRef<Path>, budget: &MemoryBudget) -> Result<Self> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "npy" => read_npy(path, budget),
            "csv" | "txt" => read_csv(path, budget),
            "png" => read_png(path, budget),
            _ => Err(Error::format(
                path,
                "file name",
                "unsupported height field type (expected .npy, .csv, .txt or .png)",
            )),
        }
    }
}

/// Reads the whole file after checking its length against the budget.
fn read_bounded(path: &Path, budget: &MemoryBudget) -> Result<Vec<u8>> {
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    budget.check("height field file bytes", len, len)?;
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// A field from parsed heights, with any refusal placed in the file.
fn finish(path: &Path, nx: usize, nz: usize, heights: Vec<f64>) -> Result<HeightField> {
    HeightField::new(nx, nz, heights).map_err(|e| match e {
        Error::InvalidOption { reason, .. } => Error::format(path, "grid", reason),
        other => other,
    })
}

/// NumPy's format: magic `\x93NUMPY`, version, header length (2 bytes in version 1, 4
/// in versions 2 and 3), a Python dict literal with `descr`, `fortran_order` and
/// `shape`, then the data.
fn read_npy(path: &Path, budget: &MemoryBudget) -> Result<HeightField> {
    let bytes = read_bounded(path, budget)?;
    let fail = |element: &str, m: String| Error::format(path, element, m);
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(fail("magic", "not a NumPy .npy file".into()));
    }
    let (header_len, start) = match bytes[6] {
        1 => (
            usize::from(u16::from_le_bytes([bytes[8], bytes[9]])),
            10usize,
        ),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(fail("version", format!("unsupported format version {v}"))),
    };
    let end = start
        .checked_add(header_len)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| fail("header", "the header runs past the end of the file".into()))?;
    let header = std::str::from_utf8(&bytes[start..end])
        .map_err(|_| fail("header", "the header is not text".into()))?;
    let descr = dict_value(header, "descr")
        .and_then(|v| v.strip_prefix(['\'', '"']))
        .and_then(|v| v.split(['\'', '"']).next())
        .map(str::to_string)
        .ok_or_else(|| fail("header", "no 'descr' in the header".into()))?;
    let fortran = dict_value(header, "fortran_order")
        .map(|v| v.starts_with("True"))
        .ok_or_else(|| fail("header", "no 'fortran_order' in the header".into()))?;
    let shape_text = dict_value(header, "shape")
        .ok_or_else(|| fail("header", "no 'shape' in the header".into()))?;
    let inner = shape_text
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| fail("shape", format!("unreadable shape {shape_text}")))?;
    let dims: Vec<usize> = inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_end_matches('L').parse::<usize>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| fail("shape", format!("unreadable shape ({inner})")))?;
    let [nz, nx] = dims[..] else {
        return Err(fail(
            "shape",
            format!(
                "a height field is a 2D array (rows z, columns x); this one has {} dimension(s)",
                dims.len()
            ),
        ));
    };
    let (kind, size) = parse_descr(&descr).ok_or_else(|| {
        fail(
            "descr",
            format!(
                "dtype '{descr}' is not supported (expected little-endian float32, float64 or \
                 an integer type)"
            ),
        )
    })?;
    let n = check_size(nx, nz, budget).map_err(|e| match e {
        Error::InvalidOption { reason, .. } => fail("shape", reason),
        other => other.budget_at(path.display().to_string()),
    })?;
    let data = &bytes[end..];
    let need = n.saturating_mul(size);
    if data.len() < need {
        return Err(fail(
            "data",
            format!(
                "{} bytes of data for a {nz} x {nx} array of {size}-byte values ({need} needed)",
                data.len()
            ),
        ));
    }
    let mut heights: Vec<f64> = crate::budget::try_vec(budget, BUDGET_STRUCTURE, n)?;
    for k in 0..nz {
        for i in 0..nx {
            // Fortran order stores columns first.
            let e = if fortran { i * nz + k } else { k * nx + i };
            let b = &data[e * size..(e + 1) * size];
            heights.push(decode(kind, b));
        }
    }
    if let Some(at) = heights.iter().position(|h| !h.is_finite()) {
        return Err(fail(
            &format!("element ({}, {})", at / nx, at % nx),
            format!("height {} is not finite", heights[at]),
        ));
    }
    finish(path, nx, nz, heights)
}

/// The text after `'key':` in a header dict, trimmed.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let k1 = format!("'{key}'");
    let k2 = format!("\"{key}\"");
    let at = header
        .find(&k1)
        .map(|p| p + k1.len())
        .or_else(|| header.find(&k2).map(|p| p + k2.len()))?;
    let rest = header[at..].trim_start();
    Some(rest.strip_prefix(':')?.trim_start())
}

/// The kinds of values a height field's NPY may hold.
#[derive(Clone, Copy)]
enum Kind {
    F32,
    F64,
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
}

/// `(kind, bytes)` of a little-endian (or byte-sized) dtype.
fn parse_descr(d: &str) -> Option<(Kind, usize)> {
    let (order, t) = d.split_at_checked(1)?;
    let one_byte = matches!(t, "i1" | "u1" | "b1");
    if !(order == "<"
        || (order == "|" && one_byte)
        || (order == "=" && cfg!(target_endian = "little")))
    {
        return None;
    }
    Some(match t {
        "f4" => (Kind::F32, 4),
        "f8" => (Kind::F64, 8),
        "i1" => (Kind::I8, 1),
        "i2" => (Kind::I16, 2),
        "i4" => (Kind::I32, 4),
        "i8" => (Kind::I64, 8),
        "u1" | "b1" => (Kind::U8, 1),
        "u2" => (Kind::U16, 2),
        "u4" => (Kind::U32, 4),
        "u8" => (Kind::U64, 8),
        _ => return None,
    })
}

/// One value of `kind` from its little-endian bytes.
fn decode(kind: Kind, b: &[u8]) -> f64 {
    let a = |n: usize| -> [u8; 8] {
        let mut x = [0u8; 8];
        x[..n].copy_from_slice(&b[..n]);
        x
    };
    match kind {
        Kind::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        Kind::F64 => f64::from_le_bytes(a(8)),
        Kind::I8 => f64::from(b[0] as i8),
        Kind::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        Kind::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        Kind::I64 => i64::from_le_bytes(a(8)) as f64,
        Kind::U8 => f64::from(b[0]),
        Kind::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        Kind::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        Kind::U64 => u64::from_le_bytes(a(8)) as f64,
    }
}

/// CSV: one row of the grid a line, numbers separated by commas, semicolons, tabs or
/// spaces; empty lines and lines starting with `#` are skipped. Every row must have
/// as many numbers as the first.
fn read_csv(path: &Path, budget: &MemoryBudget) -> Result<HeightField> {
    let bytes = read_bounded(path, budget)?;
    // Each number takes at least two bytes with its separator: the bytes bound the count.
    budget.check_items(BUDGET_STRUCTURE, bytes.len() as u64 / 2 + 1, 8)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| Error::format(path, "text", format!("not UTF-8 text: {e}")))?;
    let mut heights = Vec::new();
    let (mut nx, mut nz) = (0usize, 0usize);
    for (l, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let before = heights.len();
        for (c, cell) in line
            .split([',', ';', '\t', ' '])
            .filter(|s| !s.trim().is_empty())
            .enumerate()
        {
            let cell = cell.trim();
            let v: f64 = cell.parse().map_err(|_| {
                Error::parse(
                    path,
                    l + 1,
                    format!("column {}: '{cell}' is not a number", c + 1),
                )
            })?;
            if !v.is_finite() {
                return Err(Error::parse(
                    path,
                    l + 1,
                    format!("column {}: height {cell} is not finite", c + 1),
                ));
            }
            heights.push(v);
        }
        let count = heights.len() - before;
        if nz == 0 {
            nx = count;
        } else if count != nx {
            return Err(Error::parse(
                path,
                l + 1,
                format!("{count} numbers where the first row has {nx}"),
            ));
        }
        nz += 1;
    }
    if nz == 0 {
        return Err(Error::format(
            path,
            "grid",
            "no rows of numbers: the grid is empty",
        ));
    }
    finish(path, nx, nz, heights)
}

/// PNG: a grayscale image of 8 or 16 bits per sample; values divided by their maximum.
fn read_png(path: &Path, budget: &MemoryBudget) -> Result<HeightField> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let limit = usize::try_from(budget.limit()).unwrap_or(usize::MAX);
    let dec =
        png::Decoder::new_with_limits(std::io::BufReader::new(file), png::Limits { bytes: limit });
    let bad = |e: png::DecodingError| Error::format(path, "image", e.to_string());
    let mut reader = dec.read_info().map_err(bad)?;
    let (w, h) = reader.info().size();
    let (color, depth) = reader.output_color_type();
    if color != png::ColorType::Grayscale
        || !matches!(depth, png::BitDepth::Eight | png::BitDepth::Sixteen)
    {
        return Err(Error::format(
            path,
            "image",
            format!(
                "a height field PNG is grayscale of 8 or 16 bits; this one is {color:?} of {} bits",
                depth as u8
            ),
        ));
    }
    let (nx, nz) = (w as usize, h as usize);
    let n = check_size(nx, nz, budget).map_err(|e| e.budget_at(path.display().to_string()))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| Error::format(path, "image", "too large"))?;
    let mut buf: Vec<u8> = crate::budget::try_vec(budget, "height field image bytes", size)?;
    buf.resize(size, 0);
    let info = reader.next_frame(&mut buf).map_err(bad)?;
    let stride = info.line_size;
    let mut heights: Vec<f64> = crate::budget::try_vec(budget, BUDGET_STRUCTURE, n)?;
    for k in 0..nz {
        let row = &buf[k * stride..];
        for i in 0..nx {
            heights.push(if depth == png::BitDepth::Sixteen {
                f64::from(u16::from_be_bytes([row[2 * i], row[2 * i + 1]])) / 65535.0
            } else {
                f64::from(row[i]) / 255.0
            });
        }
    }
    finish(path, nx, nz, heights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descr_accepts_little_endian_only() {
        assert!(parse_descr("<f8").is_some());
        assert!(parse_descr("|u1").is_some());
        assert!(parse_descr(">f8").is_none());
        assert!(parse_descr("<c16").is_none());
    }

    #[test]
    fn header_values_are_found() {
        let h = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4), }";
        assert_eq!(
            dict_value(h, "descr"),
            Some("'<f4', 'fortran_order': False, 'shape': (3, 4), }")
        );
        assert!(dict_value(h, "shape").unwrap().starts_with("(3, 4)"));
    }
}
