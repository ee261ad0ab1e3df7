//! Wavefront MTL material libraries: the diffuse colour (`Kd`) of each `newmtl`.
//!
//! Input: an `.mtl` file named by an OBJ `mtllib`. Output: `(name, colour)` pairs in
//! file order; a material without `Kd` gets the MTL default diffuse 0.8 grey.
//! Everything else (ambient, specular, textures, illumination models) is ignored: the
//! visibility algorithms only need a flat colour per face.
//!
//! Problems in a library never fail the load: an unreadable file is returned as an
//! error for the OBJ loader to turn into a warning, and unusable `Kd` lines (malformed,
//! before any `newmtl`, or `Kd spectral` / `Kd xyz`, which are not supported) make one
//! warning naming the library, how many lines and the first few (the material keeps
//! the default colour). Colours are clamped to `0..=1`. A UTF-8 byte-order mark at
//! the start is skipped.
//!
//! Complexity: one pass over the text. Source: the MTL specification (Appendix B2 of
//! the Wavefront Advanced Visualizer manual).

use std::path::Path;

use super::reference::Sources;
use super::{Tally, clamp_color, read_file};
use crate::Result;

/// The MTL default diffuse reflectance.
const DEFAULT_KD: [f32; 3] = [0.8, 0.8, 0.8];

/// Reads a material library; malformed lines become warnings in `warnings`.
pub fn load(path: &Path, warnings: &mut Vec<String>) -> Result<Vec<(String, [f32; 3])>> {
    let bytes = read_file(path)?;
    Ok(parse(
        path,
        &String::from_utf8_lossy(super::strip_bom(&bytes)),
        warnings,
    ))
}

/// [`load`] within a load: the library read is recorded in `sources` (its path is
/// already resolved by the OBJ loader).
pub(crate) fn load_in(
    path: &Path,
    sources: &mut Sources<'_>,
    warnings: &mut Vec<String>,
) -> Result<Vec<(String, [f32; 3])>> {
    let bytes = sources.read(path)?;
    Ok(parse(
        path,
        &String::from_utf8_lossy(super::strip_bom(&bytes)),
        warnings,
    ))
}

/// Parses the text of a material library; unusable `Kd` lines make one warning
/// (naming `path`) in `warnings`.
pub fn parse(path: &Path, text: &str, warnings: &mut Vec<String>) -> Vec<(String, [f32; 3])> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out: Vec<(String, [f32; 3])> = Vec::new();
    let mut bad = Tally::default();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let mut tokens = line.split_ascii_whitespace();
        match tokens.next() {
            Some("newmtl") => {
                let name = line.trim_start()["newmtl".len()..].trim();
                out.push((name.to_string(), DEFAULT_KD));
            }
            Some("Kd") => {
                let mut warn = |m: String| bad.add(|| format!("line {}: {m}", k + 1));
                let Some(current) = out.last_mut() else {
                    warn("Kd before any newmtl".into());
                    continue;
                };
                let values: Vec<&str> = tokens.collect();
                if matches!(values.first(), Some(&("spectral" | "xyz"))) {
                    warn(format!(
                        "Kd {} is not supported (material \"{}\")",
                        values[0], current.0
                    ));
                    continue;
                }
                let numbers: Option<Vec<f64>> = values
                    .iter()
                    .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect();
                match numbers.as_deref() {
                    // One value means a grey (r = g = b).
                    Some(&[g]) => current.1 = clamp_color([g; 3]),
                    Some(&[r, g, b]) => current.1 = clamp_color([r, g, b]),
                    _ => warn(format!(
                        "malformed Kd \"{}\" (expected 1 or 3 finite numbers; material \"{}\")",
                        values.join(" "),
                        current.0
                    )),
                }
            }
            _ => {}
        }
    }
    bad.finish(warnings, |n| {
        format!(
            "{}: {n} Kd line(s) not used (their materials keep the default colour)",
            path.display()
        )
    });
    out
}
