//! The drawing every hidden-line algorithm returns.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// Why an edge is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EdgeKind {
    /// Between a front-facing and a back-facing face (the outline as seen).
    Silhouette,
    /// Between two faces meeting at a dihedral angle above the crease threshold.
    Crease,
    /// Used by one face only (the edge of an open surface).
    Boundary,
    /// Between faces of different objects or materials.
    Border,
    /// Where two faces pass through each other (not a mesh edge).
    Intersection,
    /// Any other mesh edge (drawn only when every edge is asked for).
    Other,
    /// A curve of a surface plot (the floating horizon's constant-x or constant-z lines).
    Curve,
}

impl EdgeKind {
    /// Every kind, in the order of [`EdgeKinds::NAMES`].
    pub const ALL: [EdgeKind; 7] = [
        EdgeKind::Silhouette,
        EdgeKind::Crease,
        EdgeKind::Boundary,
        EdgeKind::Border,
        EdgeKind::Intersection,
        EdgeKind::Other,
        EdgeKind::Curve,
    ];

    /// The kind's name as the CLI and the JSON output spell it.
    #[must_use]
    pub fn name(self) -> &'static str {
        EdgeKinds::NAMES[self as usize]
    }
}

/// A set of edge kinds, as `--edges silhouette,crease` asks for them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EdgeKinds(u8);

impl EdgeKinds {
    /// Every kind, mesh edges of no feature included.
    pub const ALL: EdgeKinds = EdgeKinds(0x7f);
    /// No kind.
    pub const NONE: EdgeKinds = EdgeKinds(0);
    /// The names, in the order of [`EdgeKind::ALL`].
    pub const NAMES: [&'static str; 7] = [
        "silhouette",
        "crease",
        "boundary",
        "border",
        "intersection",
        "other",
        "curve",
    ];

    /// Whether `kind` is in the set.
    #[must_use]
    pub fn contains(self, kind: EdgeKind) -> bool {
        self.0 & (1 << kind as u8) != 0
    }

    /// The set with `kind` added.
    #[must_use]
    pub fn with(self, kind: EdgeKind) -> EdgeKinds {
        EdgeKinds(self.0 | 1 << kind as u8)
    }

    /// Parses a comma-separated list of kind names, or `all` (every mesh edge).
    ///
    /// ```
    /// use obscura::lines::{EdgeKind, EdgeKinds};
    /// let k = EdgeKinds::parse("silhouette,crease").unwrap();
    /// assert!(k.contains(EdgeKind::Crease) && !k.contains(EdgeKind::Boundary));
    /// assert_eq!(EdgeKinds::parse("all").unwrap(), EdgeKinds::ALL);
    /// assert!(EdgeKinds::parse("silhouete").is_err());
    /// ```
    pub fn parse(list: &str) -> crate::Result<EdgeKinds> {
        let mut set = EdgeKinds::NONE;
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            if name == "all" {
                set = EdgeKinds::ALL;
                continue;
            }
            let Some(k) = EdgeKinds::NAMES.iter().position(|&n| n == name) else {
                return Err(crate::Error::option(
                    "edges",
                    format!(
                        "unknown edge kind '{name}' (expected all or a list of {})",
                        EdgeKinds::NAMES.join(", ")
                    ),
                ));
            };
            set = set.with(EdgeKind::ALL[k]);
        }
        if set == EdgeKinds::NONE {
            return Err(crate::Error::option("edges", "no edge kind given"));
        }
        Ok(set)
    }
}

impl Default for EdgeKinds {
    /// Every feature: silhouettes, creases, boundaries, borders and intersection lines
    /// (not the edges inside smooth or planar regions).
    fn default() -> Self {
        EdgeKinds::NONE
            .with(EdgeKind::Silhouette)
            .with(EdgeKind::Crease)
            .with(EdgeKind::Boundary)
            .with(EdgeKind::Border)
            .with(EdgeKind::Intersection)
            .with(EdgeKind::Curve)
    }
}

/// An edge considered for drawing: a straight 3D segment with where it came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DrawnEdge {
    /// The mesh vertex ids of its ends, in load order across the scene (the first
    /// vertex of the first object is 0), or `None` for an intersection line or a curve.
    pub vertices: Option<[u32; 2]>,
    /// The scene object it belongs to (the first of the two for an intersection line).
    pub object: Option<u32>,
    /// Why it is drawn.
    pub kind: EdgeKind,
    /// The scene polygons the edge lies on (global polygon numbers, as
    /// `View::polygon_base` counts them): the one or two polygons of a mesh edge, the two
    /// that cross for an intersection line. They never hide the edge.
    pub faces: [Option<u32>; 2],
    /// Its ends in world space; the parameter `t` of a [`Piece`] runs from `world[0]`
    /// (t = 0) to `world[1]` (t = 1).
    pub world: [DVec3; 2],
}

impl DrawnEdge {
    /// The world point at parameter `t` along the edge.
    #[must_use]
    pub fn point(&self, t: f64) -> DVec3 {
        self.world[0] + (self.world[1] - self.world[0]) * t
    }
}

/// A piece of an edge with one quantitative invisibility: a straight 2D segment in pixel
/// coordinates (x right, y down, as a `Frame`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Piece {
    /// Index of its edge in [`Drawing::edges`].
    pub edge: u32,
    /// Its parameter interval along the 3D edge, `t[0] < t[1]`.
    pub t: [f64; 2],
    /// Its ends in pixel coordinates (at `t[0]` and `t[1]`).
    pub points: [DVec2; 2],
    /// How many faces lie in front of it (0 = visible).
    pub invisibility: u32,
}

impl Piece {
    /// Whether nothing hides it.
    #[must_use]
    pub fn is_visible(&self) -> bool {
        self.invisibility == 0
    }

    /// Its length in pixels.
    #[must_use]
    pub fn length(&self) -> f64 {
        self.points[0].distance(self.points[1])
    }
}

/// A hidden-line drawing: the edges considered and the pieces they were cut into.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Drawing {
    /// Width of the picture in pixels.
    pub width: u32,
    /// Height of the picture in pixels.
    pub height: u32,
    /// Every edge considered, drawn or not.
    pub edges: Vec<DrawnEdge>,
    /// The pieces, visible and hidden, grouped by edge in increasing `t`.
    pub pieces: Vec<Piece>,
}

impl Drawing {
    /// An empty drawing of a picture's size.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        Drawing {
            width,
            height,
            ..Drawing::default()
        }
    }

    /// The visible pieces.
    pub fn visible(&self) -> impl Iterator<Item = &Piece> {
        self.pieces.iter().filter(|p| p.is_visible())
    }

    /// The hidden pieces.
    pub fn hidden(&self) -> impl Iterator<Item = &Piece> {
        self.pieces.iter().filter(|p| !p.is_visible())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_default_leaves_out_other_edges() {
        let d = EdgeKinds::default();
        assert!(!d.contains(EdgeKind::Other));
        for k in [
            EdgeKind::Silhouette,
            EdgeKind::Crease,
            EdgeKind::Boundary,
            EdgeKind::Border,
            EdgeKind::Intersection,
        ] {
            assert!(d.contains(k), "{k:?}");
        }
        assert_eq!(EdgeKind::Intersection.name(), "intersection");
    }
}
