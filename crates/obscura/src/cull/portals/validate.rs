//! Checks of a cell model: leaks and errors found and reported with their place.
//!
//! A cells-and-portals scene is only as good as its model: a portal that does not lie
//! on the boundary of its cells, a cell whose planes do not close, two cells that
//! overlap, or a door in the walls without a portal (a *leak*) make portal culling
//! wrong. Tools of the field (Quake's `vis`, Umbra) leak silently; here each problem is
//! a [`CellIssue`] that names the cell or portal and the point where it is.
//!
//! The geometry of a cell comes from its planes alone: the vertices of the convex
//! region are the points where three planes meet that lie behind every other plane
//! (an O(n^4) enumeration, fine for cells of tens of planes). A cell is *open* when its
//! planes do not bound a finite region: it is then clipped by a huge box, and a vertex on
//! that box shows the region runs off to infinity.

use glam::DVec3;

use super::model::CellGraph;
use crate::geom::{Aabb, Plane, is_convex, max_plane_deviation, polygon_area};
use crate::scene::Scene;
use crate::{Error, Result};

/// Half the side of the box that closes open cells (far beyond any sensible scene).
pub(crate) const HUGE: f64 = 1.0e7;

/// The shape of a convex cell computed from its planes.
#[derive(Clone, Debug, Default)]
pub struct CellShape {
    /// The vertices of the region (clipped by a huge box when it is open).
    pub vertices: Vec<DVec3>,
    /// For each plane of the cell (in order), its face: the region's vertices on that
    /// plane, in order around the face (empty when the plane does not touch the region
    /// over an area: a redundant plane).
    pub faces: Vec<Vec<DVec3>>,
    /// The planes do not bound a finite region.
    pub open: bool,
}

impl CellShape {
    /// The cell's region from its planes (normals pointing out).
    #[must_use]
    pub fn new(planes: &[Plane]) -> CellShape {
        let mut all: Vec<Plane> = planes
            .iter()
            .filter(|p| p.normal.length() > 0.0 && p.normal.is_finite() && p.d.is_finite())
            .map(Plane::normalized)
            .collect();
        let own = all.len();
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            all.push(Plane {
                normal: axis,
                d: -HUGE,
            });
            all.push(Plane {
                normal: -axis,
                d: -HUGE,
            });
        }
        let tol = 1e-7;
        let mut vertices: Vec<DVec3> = Vec::new();
        let mut open = false;
        let n = all.len();
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    let Some(p) = meet(&all[i], &all[j], &all[k]) else {
                        continue;
                    };
                    let scale = 1.0 + p.abs().max_element();
                    if all.iter().all(|pl| pl.evaluate(p) <= tol * scale)
                        && vertices.iter().all(|v| v.distance(p) > 1e-9 * scale)
                    {
                        // A vertex on the huge box: the cell's own planes leave the
                        // region unbounded.
                        open |= i >= own || j >= own || k >= own;
                        vertices.push(p);
                    }
                }
            }
        }
        if vertices.is_empty() {
            open = false;
        }
        let centroid = vertices.iter().copied().sum::<DVec3>() / vertices.len().max(1) as f64;
        let faces = planes
            .iter()
            .map(|pl| {
                if pl.normal.length() == 0.0 || !pl.normal.is_finite() {
                    return Vec::new();
                }
                let pl = pl.normalized();
                let on: Vec<DVec3> = vertices
                    .iter()
                    .copied()
                    .filter(|&v| pl.evaluate(v).abs() <= 1e-6 * (1.0 + v.abs().max_element()))
                    .collect();
                if on.len() < 3 {
                    return Vec::new();
                }
                order_around(on, pl.normal, centroid)
            })
            .collect();
        CellShape {
            vertices,
            faces,
            open,
        }
    }

    /// The box around the vertices.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices.iter().copied())
    }

    /// A point inside the region (the mean of its vertices).
    #[must_use]
    pub fn centroid(&self) -> DVec3 {
        self.vertices.iter().copied().sum::<DVec3>() / self.vertices.len().max(1) as f64
    }
}

/// The point where three planes meet (Cramer's rule), `None` when they do not meet in
/// one point.
fn meet(a: &Plane, b: &Plane, c: &Plane) -> Option<DVec3> {
    let bc = b.normal.cross(c.normal);
    let det = a.normal.dot(bc);
    if det.abs() < 1e-12 {
        return None;
    }
    let p = (bc * -a.d + c.normal.cross(a.normal) * -b.d + a.normal.cross(b.normal) * -c.d) / det;
    p.is_finite().then_some(p)
}

/// Points of a convex face ordered counter-clockwise seen from the side `normal` points to.
fn order_around(mut pts: Vec<DVec3>, normal: DVec3, _inside: DVec3) -> Vec<DVec3> {
    let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    pts.sort_by(|a, b| {
        let (da, db) = (*a - c, *b - c);
        let ta = da.dot(v).atan2(da.dot(u));
        let tb = db.dot(v).atan2(db.dot(u));
        ta.total_cmp(&tb)
    });
    pts
}

/// What kind of problem a [`CellIssue`] is.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum CellIssueKind {
    /// A portal names a cell that does not exist, or the same cell twice.
    BadPortalCells {
        /// The portal.
        portal: usize,
    },
    /// A portal's polygon has fewer than three vertices, non-finite ones, or no area.
    DegeneratePortal {
        /// The portal.
        portal: usize,
    },
    /// A portal's polygon is not planar.
    NonPlanarPortal {
        /// The portal.
        portal: usize,
        /// The largest distance of a vertex from the polygon's plane.
        deviation: f64,
    },
    /// A portal's polygon is not convex.
    NonConvexPortal {
        /// The portal.
        portal: usize,
    },
    /// A portal that does not lie on a boundary face of one of its cells.
    PortalOffBoundary {
        /// The portal.
        portal: usize,
        /// The cell whose boundary it misses.
        cell: usize,
        /// How far it is from the nearest boundary face (largest vertex distance).
        distance: f64,
    },
    /// A cell without planes: no geometry, so the viewer can never be located in it
    /// (a PRT1 import). A warning.
    NoGeometry {
        /// The cell.
        cell: usize,
    },
    /// A cell whose planes do not bound a finite region.
    OpenCell {
        /// The cell.
        cell: usize,
    },
    /// A cell whose planes leave no region with volume.
    EmptyCell {
        /// The cell.
        cell: usize,
    },
    /// Two cells whose regions overlap with volume.
    Overlap {
        /// The first cell.
        a: usize,
        /// The second cell.
        b: usize,
    },
    /// A cell holds an object index the scene does not have.
    BadObject {
        /// The cell.
        cell: usize,
        /// The object index.
        object: u32,
    },
    /// An object whose bounds lie wholly outside a cell that holds it. A warning.
    ObjectOutside {
        /// The cell.
        cell: usize,
        /// The object.
        object: u32,
    },
    /// A place on a cell's boundary where one can see into another cell (no scene face
    /// closes it) and no portal covers it: a door without a portal.
    Leak {
        /// The cell.
        cell: usize,
        /// Index of the cell's plane the leak is on.
        plane: usize,
    },
}

/// One problem of a cell model, with its place.
#[derive(Clone, Debug, PartialEq)]
pub struct CellIssue {
    /// What it is.
    pub kind: CellIssueKind,
    /// Where (a point of the portal, cell or leak).
    pub place: DVec3,
    /// A message naming the cells and portals by name.
    pub message: String,
    /// An error (the model is wrong) or a warning.
    pub error: bool,
}

/// The result of [`CellGraph::diagnose`]: every problem found.
#[derive(Clone, Debug, Default)]
pub struct CellReport {
    /// The problems, errors and warnings.
    pub issues: Vec<CellIssue>,
    /// The shape of each cell, from its planes.
    pub shapes: Vec<CellShape>,
}

impl CellReport {
    /// The errors.
    pub fn errors(&self) -> impl Iterator<Item = &CellIssue> {
        self.issues.iter().filter(|i| i.error)
    }

    /// The warnings.
    pub fn warnings(&self) -> impl Iterator<Item = &CellIssue> {
        self.issues.iter().filter(|i| !i.error)
    }

    /// Whether there is no error.
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.errors().next().is_none()
    }
}

fn fmt_p(p: DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

impl CellGraph {
    /// Checks the model without a scene: portals (cells, shape, place on the boundary
    /// of both cells), cells (open, empty, overlapping). `Err` names the first errors;
    /// `Ok` holds the warnings. See [`CellGraph::diagnose`] for every issue.
    pub fn validate(&self) -> Result<CellReport> {
        self.diagnose(None).into_result()
    }

    /// [`CellGraph::validate`] plus the checks that need the scene: objects the cells
    /// hold (in range, inside their cells) and leaks (openings in the scene's faces on
    /// a cell boundary that no portal covers).
    pub fn validate_with_scene(&self, scene: &Scene) -> Result<CellReport> {
        self.diagnose(Some(scene)).into_result()
    }

    /// Every issue of the model (and of the scene it describes, when given), errors
    /// and warnings, each with its place; never fails.
    #[must_use]
    pub fn diagnose(&self, scene: Option<&Scene>) -> CellReport {
        let mut issues = Vec::new();
        let shapes: Vec<CellShape> = self
            .cells
            .iter()
            .map(|c| CellShape::new(&c.planes))
            .collect();
        let name = |i: usize| {
            self.cells
                .get(i)
                .map_or_else(|| format!("#{i}"), |c| format!("\"{}\"", c.name))
        };
        let mut push = |kind, place, message: String, error| {
            issues.push(CellIssue {
                kind,
                place,
                message,
                error,
            });
        };
        // Cells.
        for (i, (cell, shape)) in self.cells.iter().zip(&shapes).enumerate() {
            if cell.planes.is_empty() {
                push(
                    CellIssueKind::NoGeometry { cell: i },
                    DVec3::ZERO,
                    format!(
                        "cell {}: no planes: the viewer is never located in it",
                        name(i)
                    ),
                    false,
                );
                continue;
            }
            if shape.open {
                let far = shape
                    .vertices
                    .iter()
                    .copied()
                    .max_by(|a, b| a.abs().max_element().total_cmp(&b.abs().max_element()))
                    .unwrap_or_default();
                push(
                    CellIssueKind::OpenCell { cell: i },
                    far,
                    format!(
                        "cell {}: open: its planes do not bound a finite region (it reaches {})",
                        name(i),
                        fmt_p(far)
                    ),
                    true,
                );
            } else if shape.vertices.len() < 4 || {
                let c = shape.centroid();
                let depth = cell
                    .planes
                    .iter()
                    .map(|p| -p.signed_distance(c))
                    .fold(f64::INFINITY, f64::min);
                !(depth > 1e-9)
            } {
                push(
                    CellIssueKind::EmptyCell { cell: i },
                    shape.centroid(),
                    format!("cell {}: its planes leave no region with volume", name(i)),
                    true,
                );
            }
        }
        // Overlaps: the intersection of two regions has an interior point.
        let boxes: Vec<Aabb> = shapes.iter().map(CellShape::bounds).collect();
        for a in 0..self.cells.len() {
            if self.cells[a].planes.is_empty() || shapes[a].open || shapes[a].vertices.is_empty() {
                continue;
            }
            for b in a + 1..self.cells.len() {
                if self.cells[b].planes.is_empty()
                    || shapes[b].open
                    || shapes[b].vertices.is_empty()
                    || !boxes[a].overlaps(&boxes[b])
                {
                    continue;
                }
                let both: Vec<Plane> = self.cells[a]
                    .planes
                    .iter()
                    .chain(&self.cells[b].planes)
                    .copied()
                    .collect();
                let s = CellShape::new(&both);
                if s.vertices.len() < 4 {
                    continue;
                }
                let c = s.centroid();
                let depth = both
                    .iter()
                    .map(|p| -p.signed_distance(c))
                    .fold(f64::INFINITY, f64::min);
                let scale = 1e-6 * (1.0 + boxes[a].extent().max_element());
                if depth > scale {
                    push(
                        CellIssueKind::Overlap { a, b },
                        c,
                        format!(
                            "cells {} and {} overlap around {}",
                            name(a),
                            name(b),
                            fmt_p(c)
                        ),
                        true,
                    );
                }
            }
        }
        // Portals.
        for (pi, portal) in self.portals.iter().enumerate() {
            let poly = &portal.polygon;
            let place = if poly.is_empty() {
                DVec3::ZERO
            } else {
                poly.iter().copied().sum::<DVec3>() / poly.len() as f64
            };
            let [ca, cb] = portal.cells.map(|c| c as usize);
            if ca >= self.cells.len() || cb >= self.cells.len() || ca == cb {
                push(
                    CellIssueKind::BadPortalCells { portal: pi },
                    place,
                    format!(
                        "portal {pi}: joins cells {} and {} ({} cells exist)",
                        portal.cells[0],
                        portal.cells[1],
                        self.cells.len()
                    ),
                    true,
                );
                continue;
            }
            let pname = format!("portal {pi} (cells {} and {})", name(ca), name(cb));
            let size = poly
                .iter()
                .map(|p| p.abs().max_element())
                .fold(1.0, f64::max);
            if poly.len() < 3
                || !poly.iter().all(|p| p.is_finite())
                || polygon_area(poly) <= 1e-12 * size * size
            {
                push(
                    CellIssueKind::DegeneratePortal { portal: pi },
                    place,
                    format!(
                        "{pname}: degenerate polygon (fewer than 3 vertices, non-finite, or no area)"
                    ),
                    true,
                );
                continue;
            }
            let dev = max_plane_deviation(poly);
            if dev > 1e-6 * size {
                push(
                    CellIssueKind::NonPlanarPortal {
                        portal: pi,
                        deviation: dev,
                    },
                    place,
                    format!("{pname}: not planar (a vertex {dev:.3e} from its plane)"),
                    true,
                );
                continue;
            }
            if !is_convex(poly) {
                push(
                    CellIssueKind::NonConvexPortal { portal: pi },
                    place,
                    format!("{pname}: not convex"),
                    true,
                );
            }
            for cell in [ca, cb] {
                if self.cells[cell].planes.is_empty() {
                    continue;
                }
                let d = boundary_distance(&self.cells[cell].planes, poly);
                if d > 1e-6 * size {
                    push(
                        CellIssueKind::PortalOffBoundary {
                            portal: pi,
                            cell,
                            distance: d,
                        },
                        place,
                        format!(
                            "{pname}: does not lie on a boundary face of cell {} (off by {d:.3e} around {})",
                            name(cell),
                            fmt_p(place)
                        ),
                        true,
                    );
                }
            }
        }
        if let Some(scene) = scene {
            scene_checks(self, scene, &shapes, &mut push);
        }
        CellReport { issues, shapes }
    }
}

impl CellReport {
    fn into_result(self) -> Result<CellReport> {
        let errors: Vec<&str> = self.errors().map(|i| i.message.as_str()).collect();
        if errors.is_empty() {
            return Ok(self);
        }
        let more = if errors.len() > 5 {
            format!(" (and {} more)", errors.len() - 5)
        } else {
            String::new()
        };
        Err(Error::InvalidCells {
            message: format!("{}{more}", errors[..errors.len().min(5)].join("; ")),
        })
    }
}

/// How far a polygon is from lying on a boundary face of a convex cell: for the best
/// plane of the cell, the largest of (a vertex's distance from that plane, a vertex's
/// distance in front of any other plane). 0 for a portal on the boundary.
fn boundary_distance(planes: &[Plane], poly: &[DVec3]) -> f64 {
    let mut best = f64::INFINITY;
    for (i, pl) in planes.iter().enumerate() {
        if pl.normal.length() == 0.0 {
            continue;
        }
        let mut worst = 0.0f64;
        for &v in poly {
            worst = worst.max(pl.signed_distance(v).abs());
            for (j, other) in planes.iter().enumerate() {
                if j != i && other.normal.length() > 0.0 {
                    worst = worst.max(other.signed_distance(v));
                }
            }
        }
        best = best.min(worst);
    }
    best
}

/// Whether the segment `a..b` crosses a polygon (within `eps` of its edges).
pub(crate) fn segment_hits_polygon(a: DVec3, b: DVec3, poly: &[DVec3], eps: f64) -> bool {
    let Some(pl) = Plane::newell(poly) else {
        return false;
    };
    let pl = pl.normalized();
    let (da, db) = (pl.evaluate(a), pl.evaluate(b));
    if (da > 0.0 && db > 0.0) || (da < 0.0 && db < 0.0) || da == db {
        return false;
    }
    let t = da / (da - db);
    let p = a + (b - a) * t;
    point_in_convex_or_not(p, poly, pl.normal, eps)
}

/// Whether `p` (on the polygon's plane) is inside the polygon, within `eps` (any
/// simple polygon: crossing count in the plane's 2D projection).
fn point_in_convex_or_not(p: DVec3, poly: &[DVec3], n: DVec3, eps: f64) -> bool {
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let q: Vec<(f64, f64)> = poly
        .iter()
        .map(|&x| ((x - p).dot(u), (x - p).dot(v)))
        .collect();
    let m = q.len();
    let mut inside = false;
    for i in 0..m {
        let (x0, y0) = q[i];
        let (x1, y1) = q[(i + 1) % m];
        // Near an edge counts as inside.
        let (ex, ey) = (x1 - x0, y1 - y0);
        let len2 = ex * ex + ey * ey;
        let t = if len2 > 0.0 {
            ((-x0 * ex - y0 * ey) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (cx, cy) = (x0 + t * ex, y0 + t * ey);
        if cx * cx + cy * cy <= eps * eps {
            return true;
        }
        if (y0 > 0.0) != (y1 > 0.0) {
            let x = x0 + (0.0 - y0) * ex / ey;
            if x > 0.0 {
                inside = !inside;
            }
        }
    }
    inside
}

/// Whether any face of the scene crosses the segment.
pub(crate) fn segment_hits_scene(scene: &Scene, a: DVec3, b: DVec3, eps: f64) -> bool {
    let seg = Aabb::from_points([a, b]);
    let grow = DVec3::splat(eps);
    scene.objects().iter().any(|o| {
        let ob = Aabb {
            min: o.bounds.min - grow,
            max: o.bounds.max + grow,
        };
        ob.overlaps(&seg)
            && (0..o.mesh.polygon_count())
                .any(|i| segment_hits_polygon(a, b, &o.world_polygon(i), eps))
    })
}

fn scene_checks(
    graph: &CellGraph,
    scene: &Scene,
    shapes: &[CellShape],
    push: &mut impl FnMut(CellIssueKind, DVec3, String, bool),
) {
    let objects = scene.objects();
    for (ci, cell) in graph.cells.iter().enumerate() {
        for &o in &cell.objects {
            let Some(obj) = objects.get(o as usize) else {
                push(
                    CellIssueKind::BadObject {
                        cell: ci,
                        object: o,
                    },
                    shapes[ci].centroid(),
                    format!(
                        "cell \"{}\": holds object {o}, the scene has {}",
                        cell.name,
                        objects.len()
                    ),
                    true,
                );
                continue;
            };
            if cell.planes.is_empty() {
                continue;
            }
            let b = obj.bounds;
            let size = 1e-6 * (1.0 + b.extent().max_element());
            let outside = cell
                .planes
                .iter()
                .any(|pl| b.corners().iter().all(|&c| pl.signed_distance(c) > size));
            if outside {
                push(
                    CellIssueKind::ObjectOutside {
                        cell: ci,
                        object: o,
                    },
                    b.center(),
                    format!(
                        "cell \"{}\": holds object \"{}\" whose bounds lie outside it (around {})",
                        cell.name,
                        obj.name,
                        fmt_p(b.center())
                    ),
                    false,
                );
            }
        }
    }
    // Leaks: sample each boundary face; a sample not under a portal must be closed by
    // a scene face crossing the boundary there.
    for (ci, (cell, shape)) in graph.cells.iter().zip(shapes).enumerate() {
        if cell.planes.is_empty() || shape.open {
            continue;
        }
        let scale = shape.bounds().extent().max_element().max(1e-9);
        let eps = 1e-6 * scale;
        let portals: Vec<&Vec<DVec3>> = graph
            .portals
            .iter()
            .filter(|p| p.cells.contains(&(ci as u32)))
            .map(|p| &p.polygon)
            .collect();
        'faces: for (pi, face) in shape.faces.iter().enumerate() {
            if face.len() < 3 {
                continue;
            }
            let n = cell.planes[pi].normal.normalize();
            for p in face_samples(face, n, 0.25) {
                let (a, b) = (p - n * 1e-3 * scale.min(1e3), p + n * 1e-3 * scale.min(1e3));
                if portals
                    .iter()
                    .any(|poly| segment_hits_polygon(a, b, poly, eps))
                {
                    continue;
                }
                // Only an opening into another cell leaks (one into the void beyond
                // the level shows nothing that culling could remove).
                if graph.locate(b).is_none_or(|o| o as usize == ci) {
                    continue;
                }
                if !segment_hits_scene(scene, a, b, eps) {
                    push(
                        CellIssueKind::Leak {
                            cell: ci,
                            plane: pi,
                        },
                        p,
                        format!(
                            "cell \"{}\": leak at {} on its plane {pi}: no wall and no portal there",
                            cell.name,
                            fmt_p(p)
                        ),
                        true,
                    );
                    continue 'faces;
                }
            }
        }
    }
}

/// Sample points inside a convex face: a grid of spacing about `step` (at least 8 by 8
/// over the face, at most 200 by 200), kept where inside the face (not on its edges).
fn face_samples(face: &[DVec3], n: DVec3, step: f64) -> Vec<DVec3> {
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let o = face[0];
    let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &p in face {
        let (a, b) = ((p - o).dot(u), (p - o).dot(v));
        u0 = u0.min(a);
        u1 = u1.max(a);
        v0 = v0.min(b);
        v1 = v1.max(b);
    }
    let nu = (((u1 - u0) / step).ceil() as usize).clamp(8, 200);
    let nv = (((v1 - v0) / step).ceil() as usize).clamp(8, 200);
    let c = face.iter().copied().sum::<DVec3>() / face.len() as f64;
    let mut out = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let a = u0 + (u1 - u0) * (i as f64 + 0.5) / nu as f64;
            let b = v0 + (v1 - v0) * (j as f64 + 0.5) / nv as f64;
            let p = o + u * a + v * b;
            // Inside the convex face, strictly: behind every edge's inward test.
            let m = face.len();
            let inside = (0..m).all(|k| {
                let (e0, e1) = (face[k], face[(k + 1) % m]);
                let inward = n.cross(e1 - e0);
                let side = (p - e0).dot(inward) * (c - e0).dot(inward).signum();
                side > 1e-9
            });
            if inside {
                out.push(p);
            }
        }
    }
    out
}
