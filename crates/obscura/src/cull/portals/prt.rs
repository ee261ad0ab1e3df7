//! Import (and export) of the Quake tools' text portal file, PRT1, so that real level
//! data can be used.
//!
//! The format, as the BSP compilers (`qbsp`, `q3map`) write it for `vis`:
//!
//! ```text
//! PRT1
//! <number of leafs (clusters)>
//! <number of portals>
//! [<number of solid faces>]          (Quake III's q3map adds this line)
//! <point count> <leaf a> <leaf b> [<hint flag>] (x y z) (x y z) ...   one line per portal
//! [<point count> <leaf> (x y z) ...]                                 one line per face
//! ```
//!
//! A PRT1 file has no cell geometry: the import gives a [`CellGraph`] with one cell per
//! leaf, named `leaf N`, **without planes**, and the portals. Such cells never hold the
//! viewer ([`CellGraph::locate`] returns `None`, and portal culling falls back to none);
//! the graph serves the adjacency and the PVS computations that need portals only.
//! Other headers (`PRT2`, `PRT1-AM`) are refused with a message that says so. Every
//! error names the file and the line; counts are checked against what is read (a
//! header announcing a billion portals allocates nothing).

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

use super::model::{Cell, CellGraph, Portal};
use crate::{Error, Result};

/// The most leafs a file may declare (beyond any real map, far below memory limits).
const MAX_LEAFS: usize = 1 << 22;

/// Reads a PRT1 file.
pub fn read_prt(path: impl AsRef<Path>) -> Result<CellGraph> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_prt(&text, path)
}

/// Parses the text of a PRT1 file; `path` names it in errors.
pub fn parse_prt(text: &str, path: &Path) -> Result<CellGraph> {
    let err = |line: usize, message: String| Error::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    // Non-empty lines with their 1-based numbers.
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let (n, header) = lines
        .next()
        .ok_or_else(|| err(1, "empty file: expected the header \"PRT1\"".into()))?;
    if header != "PRT1" {
        let shown: String = header.chars().take(20).collect();
        return Err(err(
            n,
            format!(
                "header \"{shown}\": only the PRT1 portal format is supported (not PRT2 or PRT1-AM)"
            ),
        ));
    }
    let mut count = |what: &str| -> Result<(usize, usize)> {
        let (n, l) = lines
            .next()
            .ok_or_else(|| err(0, format!("the file ends before the {what}")))?;
        let v: usize = l.parse().map_err(|_| {
            err(
                n,
                format!("expected the {what} (an integer), found \"{l}\""),
            )
        })?;
        Ok((n, v))
    };
    let (nl, leafs) = count("number of leafs")?;
    if leafs > MAX_LEAFS || leafs > text.len() {
        return Err(err(
            nl,
            format!("{leafs} leafs is more than the file can describe"),
        ));
    }
    let (_, portals_declared) = count("number of portals")?;
    let mut rest: Vec<(usize, &str)> = lines.collect();
    // Quake III's optional line with the number of solid faces.
    let mut faces_declared = 0usize;
    if let Some(&(_, l)) = rest.first()
        && !l.is_empty()
        && l.bytes().all(|b| b.is_ascii_digit())
    {
        faces_declared = l.parse().unwrap_or(usize::MAX);
        rest.remove(0);
    }
    if portals_declared > rest.len() {
        let last = rest.last().map_or(nl, |r| r.0);
        return Err(err(
            last,
            format!(
                "the header announces {portals_declared} portals, the file has {} lines of them",
                rest.len()
            ),
        ));
    }
    let mut portals = Vec::new();
    for &(n, l) in rest.iter().take(portals_declared) {
        let (count, ids, points) = parse_polygon_line(l, 2, true).map_err(|m| err(n, m))?;
        let [a, b] = [ids[0], ids[1]];
        for id in [a, b] {
            if id >= leafs {
                return Err(err(
                    n,
                    format!("leaf {id} out of range (the file has {leafs} leafs)"),
                ));
            }
        }
        if count != points.len() {
            return Err(err(
                n,
                format!("{count} points announced, {} given", points.len()),
            ));
        }
        if a == b {
            return Err(err(n, format!("a portal from leaf {a} to itself")));
        }
        portals.push(Portal {
            cells: [a as u32, b as u32],
            polygon: points,
        });
    }
    let faces = &rest[portals_declared..];
    if faces_declared != faces.len() && faces_declared != 0 {
        let last = faces.last().map_or(nl, |r| r.0);
        return Err(err(
            last,
            format!(
                "the header announces {faces_declared} solid faces, the file has {} lines of them",
                faces.len()
            ),
        ));
    }
    if faces_declared == 0
        && let Some(&(n, _)) = faces.first()
    {
        return Err(err(
            n,
            format!("more lines than the {portals_declared} portals announced"),
        ));
    }
    for &(n, l) in faces {
        parse_polygon_line(l, 1, false).map_err(|m| err(n, m))?;
    }
    let cells = (0..leafs)
        .map(|i| Cell {
            name: format!("leaf {i}"),
            planes: Vec::new(),
            objects: Vec::new(),
        })
        .collect();
    Ok(CellGraph::new(cells, portals))
}

/// `count id.. [flag] (x y z)...`: the count, the ids and the points.
fn parse_polygon_line(
    l: &str,
    ids: usize,
    flag: bool,
) -> std::result::Result<(usize, Vec<usize>, Vec<DVec3>), String> {
    let (head, tail) = l.split_at(l.find('(').unwrap_or(l.len()));
    let nums: Vec<&str> = head.split_whitespace().collect();
    if nums.len() != 1 + ids && !(flag && nums.len() == 2 + ids) {
        return Err(format!(
            "expected a point count and {ids} leaf numbers before the points, found \"{}\"",
            head.trim()
        ));
    }
    let int = |s: &str| {
        s.parse::<usize>()
            .map_err(|_| format!("\"{s}\" is not a non-negative integer"))
    };
    let count = int(nums[0])?;
    if count < 3 {
        return Err(format!("a polygon of {count} points"));
    }
    let idv = nums[1..=ids]
        .iter()
        .map(|s| int(s))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let mut points = Vec::new();
    let mut rest = tail;
    while let Some(open) = rest.find('(') {
        if !rest[..open].trim().is_empty() {
            return Err(format!(
                "unexpected \"{}\" between points",
                rest[..open].trim()
            ));
        }
        let close = rest[open..]
            .find(')')
            .ok_or_else(|| "a point without its closing \")\"".to_string())?
            + open;
        let xyz: Vec<&str> = rest[open + 1..close].split_whitespace().collect();
        if xyz.len() != 3 {
            return Err(format!("a point of {} coordinates", xyz.len()));
        }
        let mut p = [0.0; 3];
        for (k, s) in xyz.iter().enumerate() {
            p[k] = s
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("coordinate \"{s}\" is not a finite number"))?;
        }
        points.push(DVec3::from_array(p));
        rest = &rest[close + 1..];
    }
    if !rest.trim().is_empty() {
        return Err(format!("unexpected \"{}\" after the points", rest.trim()));
    }
    Ok((count, idv, points))
}

/// Writes a graph's portals as a PRT1 file (one leaf per cell; cells' planes and
/// objects are not part of the format).
#[must_use]
pub fn write_prt(graph: &CellGraph) -> String {
    let mut s = format!("PRT1\n{}\n{}\n", graph.cells.len(), graph.portals.len());
    for p in &graph.portals {
        let _ = write!(s, "{} {} {}", p.polygon.len(), p.cells[0], p.cells[1]);
        for v in &p.polygon {
            let _ = write!(s, " ({} {} {})", v.x, v.y, v.z);
        }
        s.push('\n');
    }
    s
}
