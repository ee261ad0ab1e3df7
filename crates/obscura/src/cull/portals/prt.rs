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
//! # Cells from the portals' hulls
//! A PRT1 file has no cell geometry, but in a BSP compiler's output the leaves are
//! convex and disjoint, and every portal lies on the boundary of both its leaves. So
//! the convex hull of a leaf's portal polygons lies inside the leaf. The import gives
//! one cell per leaf, named `leaf N`, whose planes are those of that hull
//! ([`hull_planes`], normals out, each a supporting plane of the leaf's portal
//! vertices): [`CellGraph::locate`] finds a viewer who stands inside the hull of a
//! leaf's portals, and says `None` for one in no hull (a leaf's corners away from its
//! portals, or inside the walls), where portal culling falls back to none with a note.
//! A leaf with one portal, or whose portals are coplanar (or collinear points), has a
//! flat hull, no volume: its cell has no planes and never holds the viewer
//! ([`CellGraph::diagnose`] warns of each such cell; [`flat_leaves`] lists them).
//!
//! The graph is marked [`CellGraph::partial_cells`]: the hulls cover the leaves only in
//! part, so a view whose near rectangle may leave the hull of the viewer's cell (the
//! eye closer to a hull plane than the near rectangle's reach, where it may cut a wall
//! into a leaf whose hull does not reach there) is not portal-culled either, with a
//! note. The import holds no objects; [`assign_objects_inside`] puts a scene's objects
//! in the cells that must hold them: only an object whose box lies inside one hull is
//! known to be in that leaf; any other object is in no cell, and so never portal-culled.
//!
//! Hull: an incremental convex hull (Clarkson and Shor's randomized incremental
//! construction, here in insertion order: "Applications of random sampling in
//! computational geometry, II", Discrete & Computational Geometry 4, 1989), points
//! within a tolerance of a face counted inside, then every face's plane moved out to
//! support all the points and coplanar faces merged. O(n²) for n portal vertices of a
//! leaf (a few dozen in real maps).
//!
//! Other headers (`PRT2`, `PRT1-AM`) are refused with a message that says so. Every
//! error names the file and the line; counts are checked against what is read (a
//! header announcing a billion portals allocates nothing).

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

use super::model::{Cell, CellGraph, Portal};
use crate::geom::{Aabb, Plane};
use crate::scene::Scene;
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
    Ok(hull_cells(leafs, portals))
}

/// The graph of `leafs` cells joined by `portals`, each cell the convex hull of its
/// portals ([`hull_planes`]; no planes when the hull is flat), marked
/// [`CellGraph::partial_cells`].
#[must_use]
pub fn hull_cells(leafs: usize, portals: Vec<Portal>) -> CellGraph {
    let mut points: Vec<Vec<DVec3>> = vec![Vec::new(); leafs];
    for p in &portals {
        for &c in &p.cells {
            if let Some(v) = points.get_mut(c as usize) {
                v.extend(&p.polygon);
            }
        }
    }
    let cells = points
        .iter()
        .enumerate()
        .map(|(i, pts)| Cell {
            name: format!("leaf {i}"),
            planes: hull_planes(pts).unwrap_or_default(),
            objects: Vec::new(),
        })
        .collect();
    let mut graph = CellGraph::new(cells, portals);
    graph.partial_cells = true;
    graph
}

/// The cells without planes (leaves whose portals' hull is flat: one portal, coplanar
/// portals, or none), which never hold the viewer.
#[must_use]
pub fn flat_leaves(graph: &CellGraph) -> Vec<u32> {
    (0..graph.cells.len() as u32)
        .filter(|&c| graph.cells[c as usize].planes.is_empty())
        .collect()
}

/// The planes of the convex hull of `points`, unit normals pointing out, each moved out
/// to the farthest point (`normal · p + d <= 0` holds for every point exactly as
/// computed), coplanar faces merged; `None` when the hull has no volume (fewer than four
/// points, all on a line or a plane within a tolerance relative to the points' extent)
/// or a point is not finite.
#[must_use]
pub fn hull_planes(points: &[DVec3]) -> Option<Vec<Plane>> {
    if points.len() < 4 || points.iter().any(|p| !p.is_finite()) {
        return None;
    }
    // Distinct points (portals of a leaf share their corners).
    let mut pts: Vec<DVec3> = points.to_vec();
    pts.sort_by(|a, b| {
        a.x.total_cmp(&b.x)
            .then(a.y.total_cmp(&b.y))
            .then(a.z.total_cmp(&b.z))
    });
    pts.dedup();
    let b = Aabb::from_points(pts.iter().copied());
    let size = b.extent().length();
    if !(size > 0.0) {
        return None;
    }
    let scale = b.min.abs().max(b.max.abs()).max_element().max(size);
    let eps = 1e-9 * scale;
    // The first tetrahedron: the extreme point in x, the farthest from it, the farthest
    // from their line, the farthest from their plane.
    let i0 = (0..pts.len()).min_by(|&a, &b| pts[a].x.total_cmp(&pts[b].x))?;
    let far =
        |f: &dyn Fn(DVec3) -> f64| (0..pts.len()).max_by(|&a, &b| f(pts[a]).total_cmp(&f(pts[b])));
    let i1 = far(&|p| p.distance(pts[i0]))?;
    let line = pts[i1] - pts[i0];
    let i2 = far(&|p| line.cross(p - pts[i0]).length())?;
    if !(line.cross(pts[i2] - pts[i0]).length() > 1e-7 * size * line.length()) {
        return None;
    }
    let normal = line.cross(pts[i2] - pts[i0]).normalize();
    let i3 = far(&|p| normal.dot(p - pts[i0]).abs())?;
    if !(normal.dot(pts[i3] - pts[i0]).abs() > 1e-7 * size) {
        return None;
    }
    // Faces as vertex triples, counter-clockwise seen from outside.
    let mut faces: Vec<[usize; 3]> = Vec::new();
    let inner = (pts[i0] + pts[i1] + pts[i2] + pts[i3]) / 4.0;
    for f in [[i0, i1, i2], [i0, i1, i3], [i0, i2, i3], [i1, i2, i3]] {
        let n = (pts[f[1]] - pts[f[0]]).cross(pts[f[2]] - pts[f[0]]);
        faces.push(if n.dot(pts[f[0]] - inner) > 0.0 {
            f
        } else {
            [f[0], f[2], f[1]]
        });
    }
    let plane_of = |f: &[usize; 3]| {
        let n = (pts[f[1]] - pts[f[0]])
            .cross(pts[f[2]] - pts[f[0]])
            .normalize_or_zero();
        (n, -n.dot(pts[f[0]]))
    };
    for (i, &p) in pts.iter().enumerate() {
        if [i0, i1, i2, i3].contains(&i) {
            continue;
        }
        let visible: Vec<bool> = faces
            .iter()
            .map(|f| {
                let (n, d) = plane_of(f);
                n.dot(p) + d > eps
            })
            .collect();
        if !visible.iter().any(|&v| v) {
            continue;
        }
        // The horizon: directed edges of visible faces whose reverse is on no visible face.
        let mut edges: Vec<(usize, usize)> = Vec::new();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, v)| **v) {
            for e in 0..3 {
                edges.push((f[e], f[(e + 1) % 3]));
            }
        }
        let horizon: Vec<(usize, usize)> = edges
            .iter()
            .copied()
            .filter(|&(a, b)| !edges.contains(&(b, a)))
            .collect();
        let mut k = 0;
        faces.retain(|_| {
            k += 1;
            !visible[k - 1]
        });
        for (a, b) in horizon {
            faces.push([a, b, i]);
        }
    }
    // Planes, each moved out to support every point, coplanar faces merged.
    let mut planes: Vec<Plane> = Vec::new();
    for f in &faces {
        let (n, _) = plane_of(f);
        if n == DVec3::ZERO {
            continue;
        }
        let d = -pts
            .iter()
            .map(|&p| n.dot(p))
            .fold(f64::NEG_INFINITY, f64::max);
        if planes
            .iter()
            .any(|q| q.normal.dot(n) > 1.0 - 1e-12 && (q.d - d).abs() <= eps)
        {
            continue;
        }
        planes.push(Plane { normal: n, d });
    }
    (planes.len() >= 4).then_some(planes)
}

/// Gives `scene` the cells and portals of the PRT1 file at `path` ([`read_prt`]), its
/// objects assigned by [`assign_objects_inside`] (replacing any cells it had), and
/// returns a line that says what was imported: leaves, portals, leaves without volume
/// (never holding the viewer), objects in cells.
///
/// # Errors
/// Those of [`read_prt`].
pub fn attach(scene: &mut Scene, path: impl AsRef<Path>) -> Result<String> {
    let mut graph = read_prt(path)?;
    assign_objects_inside(&mut graph, scene);
    let flat = flat_leaves(&graph).len();
    let mut held = vec![false; scene.objects().len()];
    for c in &graph.cells {
        for &k in &c.objects {
            held[k as usize] = true;
        }
    }
    let summary = format!(
        "{} leaves, {} portals; {flat} leaves without volume (their portals one or coplanar: \
         the viewer is never located in them); {} of {} objects inside a leaf's portal hull \
         (the others are never portal-culled)",
        graph.cells.len(),
        graph.portals.len(),
        held.iter().filter(|&&h| h).count(),
        held.len()
    );
    scene.set_cells(Some(std::sync::Arc::new(graph)));
    Ok(summary)
}

/// Puts each object of `scene` in the cells of an imported graph that must hold it:
/// an object whose world box lies inside the hull of one cell (within a rounding
/// tolerance) is in that leaf, and goes in every cell whose hull its box meets; any
/// other object may reach a leaf's part no hull covers, and is in no cell (never
/// portal-culled). Replaces the cells' object lists. Conservative for any graph whose
/// cells lie inside disjoint convex leaves.
pub fn assign_objects_inside(graph: &mut CellGraph, scene: &Scene) {
    use super::floorplan::box_meets_cell;
    for cell in &mut graph.cells {
        cell.objects.clear();
    }
    for (k, o) in scene.objects().iter().enumerate() {
        let b = &o.bounds;
        let eps = 1e-9 * (1.0 + b.min.abs().max_element().max(b.max.abs().max_element()));
        let inside_one = graph.cells.iter().any(|c| {
            !c.planes.is_empty()
                && c.planes
                    .iter()
                    .all(|pl| b.corners().iter().all(|&p| pl.signed_distance(p) <= eps))
        });
        if !inside_one {
            continue;
        }
        for cell in &mut graph.cells {
            if !cell.planes.is_empty() && box_meets_cell(b, &cell.planes) {
                cell.objects.push(k as u32);
            }
        }
    }
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
