//! The JSON form of a [`Drawing`]: every edge drawn or considered, with its visible and
//! hidden parameter intervals along the 3D edge, so other tools can check and reuse a
//! drawing. The schema is documented in `docs/lines.md` ("SVG, PNG preview and JSON").
//!
//! ```text
//! { "format": "obscura-lines", "version": 1, "width": 1280, "height": 720,
//!   "scene": "demo:cube", "algorithm": "hlr",           (optional)
//!   "edges": [ { "edge": 0, "vertices": [0, 1], "object": 0, "kind": "crease",
//!                "faces": [3, 7], "world": [[x, y, z], [x, y, z]],
//!                "visible": [[0.0, 0.4]], "hidden": [[0.4, 1.0]],
//!                "pieces": [ { "t": [0.0, 0.4], "invisibility": 0,
//!                              "points": [[x, y], [x, y]] }, ... ] }, ... ] }
//! ```
//!
//! [`LinesFile::to_drawing`] turns a file back into the drawing it came from.

use std::path::Path;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::{Drawing, DrawnEdge, EdgeKind, Piece};
use crate::{Error, Result};

/// The value of [`LinesFile::format`].
pub const FORMAT: &str = "obscura-lines";
/// The value of [`LinesFile::version`] this build writes and reads.
pub const VERSION: u32 = 1;

/// A drawing as JSON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinesFile {
    /// Always [`FORMAT`].
    pub format: String,
    /// The schema's version, [`VERSION`].
    pub version: u32,
    /// Width of the picture in pixels.
    pub width: u32,
    /// Height of the picture in pixels.
    pub height: u32,
    /// The scene drawn, as the CLI was given it (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// The algorithm that drew it (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub algorithm: Option<String>,
    /// Every edge considered, in the drawing's order.
    pub edges: Vec<EdgeRecord>,
}

/// One edge and what became of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeRecord {
    /// Its index in the drawing.
    pub edge: u32,
    /// The mesh vertex ids of its ends (load order across the scene), `null` for an
    /// intersection line or a curve.
    pub vertices: Option<[u32; 2]>,
    /// The object it belongs to.
    pub object: Option<u32>,
    /// Why it is drawn: silhouette, crease, boundary, border, intersection, other or
    /// curve.
    pub kind: EdgeKind,
    /// The polygons it lies on (global polygon numbers).
    pub faces: [Option<u32>; 2],
    /// Its ends in world space: `t = 0` at the first, `t = 1` at the second.
    pub world: [[f64; 3]; 2],
    /// The parameter intervals where it is visible, merged where they touch.
    pub visible: Vec<[f64; 2]>,
    /// The parameter intervals where it is hidden, merged where they touch.
    pub hidden: Vec<[f64; 2]>,
    /// Its pieces in increasing `t`, each with one quantitative invisibility.
    pub pieces: Vec<PieceRecord>,
}

/// One piece of an edge.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PieceRecord {
    /// Its parameter interval along the 3D edge.
    pub t: [f64; 2],
    /// How many faces lie in front of it (0 = visible).
    pub invisibility: u32,
    /// Its ends in pixels (x right, y down).
    pub points: [[f64; 2]; 2],
}

/// Sorted intervals with those that touch merged.
fn merged(mut spans: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    spans.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(spans.len());
    for s in spans {
        match out.last_mut() {
            Some(last) if s[0] <= last[1] => last[1] = last[1].max(s[1]),
            _ => out.push(s),
        }
    }
    out
}

impl LinesFile {
    /// The JSON form of a drawing. Errors: a piece naming an edge the drawing does
    /// not have.
    pub fn from_drawing(drawing: &Drawing) -> Result<LinesFile> {
        let mut pieces: Vec<Vec<&Piece>> = vec![Vec::new(); drawing.edges.len()];
        for (k, p) in drawing.pieces.iter().enumerate() {
            let list = pieces.get_mut(p.edge as usize).ok_or_else(|| {
                Error::option(
                    "drawing",
                    format!(
                        "piece {k} names edge {} of a drawing of {} edges",
                        p.edge,
                        drawing.edges.len()
                    ),
                )
            })?;
            list.push(p);
        }
        let edges = drawing
            .edges
            .iter()
            .zip(pieces)
            .enumerate()
            .map(|(k, (e, mut ps))| {
                ps.sort_by(|a, b| a.t[0].total_cmp(&b.t[0]));
                let spans = |visible: bool| {
                    merged(
                        ps.iter()
                            .filter(|p| p.is_visible() == visible)
                            .map(|p| p.t)
                            .collect(),
                    )
                };
                EdgeRecord {
                    edge: k as u32,
                    vertices: e.vertices,
                    object: e.object,
                    kind: e.kind,
                    faces: e.faces,
                    world: e.world.map(|p| p.to_array()),
                    visible: spans(true),
                    hidden: spans(false),
                    pieces: ps
                        .iter()
                        .map(|p| PieceRecord {
                            t: p.t,
                            invisibility: p.invisibility,
                            points: p.points.map(|q| q.to_array()),
                        })
                        .collect(),
                }
            })
            .collect();
        Ok(LinesFile {
            format: FORMAT.to_string(),
            version: VERSION,
            width: drawing.width,
            height: drawing.height,
            scene: None,
            algorithm: None,
            edges,
        })
    }

    /// The drawing back (pieces grouped by edge in increasing `t`). Errors: another
    /// format or version, edges out of order.
    pub fn to_drawing(&self) -> Result<Drawing> {
        if self.format != FORMAT || self.version != VERSION {
            return Err(Error::option(
                "json",
                format!(
                    "format \"{}\" version {}: this build reads \"{FORMAT}\" version {VERSION}",
                    self.format, self.version
                ),
            ));
        }
        // The picture's size as any image of the crate: at most `MAX_SIDE` a side.
        crate::Viewport::new(u64::from(self.width), u64::from(self.height))?;
        let mut d = Drawing::new(self.width, self.height);
        for (k, e) in self.edges.iter().enumerate() {
            if e.edge as usize != k {
                return Err(Error::option(
                    "json",
                    format!("edge {} is at position {k}: edges must be in order", e.edge),
                ));
            }
            d.edges.push(DrawnEdge {
                vertices: e.vertices,
                object: e.object,
                kind: e.kind,
                faces: e.faces,
                world: e.world.map(DVec3::from_array),
            });
            d.pieces.extend(e.pieces.iter().map(|p| Piece {
                edge: k as u32,
                t: p.t,
                points: p.points.map(DVec2::from_array),
                invisibility: p.invisibility,
            }));
        }
        Ok(d)
    }

    /// The JSON text, pretty-printed, ending with a newline.
    #[must_use]
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("JSON of plain values") + "\n"
    }

    /// Parses JSON text.
    pub fn from_json(text: &str) -> Result<LinesFile> {
        serde_json::from_str(text)
            .map_err(|e| Error::option("json", format!("line {}: {e}", e.line())))
    }

    /// Writes the JSON file.
    pub fn write(&self, path: &Path) -> Result<()> {
        std::fs::write(path, self.to_json()).map_err(|e| Error::io(path, e))
    }

    /// Reads a JSON file.
    pub fn read(path: &Path) -> Result<LinesFile> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        serde_json::from_str(&text).map_err(|e| Error::Parse {
            path: path.to_path_buf(),
            line: e.line(),
            message: e.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drawing() -> Drawing {
        let mut d = Drawing::new(64, 48);
        d.edges.push(DrawnEdge {
            vertices: Some([3, 7]),
            object: Some(1),
            kind: EdgeKind::Silhouette,
            faces: [Some(4), None],
            world: [DVec3::new(0.1, -2.0, 3.0), DVec3::new(1.0 / 3.0, 5.0, 1e-7)],
        });
        d.edges.push(DrawnEdge {
            vertices: None,
            object: None,
            kind: EdgeKind::Intersection,
            faces: [Some(1), Some(9)],
            world: [DVec3::ZERO, DVec3::ONE],
        });
        let piece = |edge, t: [f64; 2], q| Piece {
            edge,
            t,
            points: [
                DVec2::new(t[0] * 60.0, 0.1 + t[0]),
                DVec2::new(t[1] * 60.0, 0.1 + t[1]),
            ],
            invisibility: q,
        };
        d.pieces = vec![
            piece(0, [0.0, 0.25], 0),
            piece(0, [0.25, 0.5], 0),
            piece(0, [0.5, 0.7], 2),
            piece(0, [0.7, 0.9], 1),
            piece(0, [0.9, 1.0], 0),
            piece(1, [0.0, 1.0], 1),
        ];
        d
    }

    #[test]
    fn intervals_are_merged_per_visibility() {
        let f = LinesFile::from_drawing(&drawing()).unwrap();
        assert_eq!(f.edges[0].visible, vec![[0.0, 0.5], [0.9, 1.0]]);
        assert_eq!(f.edges[0].hidden, vec![[0.5, 0.9]]);
        assert_eq!(f.edges[1].visible, Vec::<[f64; 2]>::new());
        assert_eq!(f.edges[0].pieces[2].invisibility, 2);
        let text = f.to_json();
        assert!(text.contains("\"kind\": \"silhouette\""), "{text}");
        assert!(text.contains("\"vertices\": null"), "{text}");
    }

    #[test]
    fn json_round_trips_to_the_same_drawing() {
        let d = drawing();
        let f = LinesFile::from_drawing(&d).unwrap();
        let back = LinesFile::from_json(&f.to_json()).unwrap();
        assert_eq!(back, f);
        assert_eq!(back.to_drawing().unwrap(), d);
    }

    #[test]
    fn bad_drawings_and_files_are_refused() {
        let mut d = drawing();
        d.pieces[0].edge = 5;
        let e = LinesFile::from_drawing(&d).unwrap_err().to_string();
        assert!(e.contains("piece 0 names edge 5"), "{e}");
        let mut f = LinesFile::from_drawing(&drawing()).unwrap();
        f.version = 99;
        assert!(f.to_drawing().is_err());
        // A picture larger than any image the crate makes (its preview would not fit).
        let mut f = LinesFile::from_drawing(&drawing()).unwrap();
        f.width = 4_000_000_000;
        let e = f.to_drawing().unwrap_err().to_string();
        assert!(e.contains("4000000000"), "{e}");
        assert!(LinesFile::from_json("{\"format\": 1}").is_err());
    }
}
