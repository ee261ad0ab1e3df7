//! Portal rendering (seed 000 "από-Περιοχή (4)-(7)", the pseudocode
//! `portal render(c, f, PVS)`): from the viewer's cell, recursively through each portal
//! leading to a cell of the PVS, the frustum shrunk to the portal.
//!
//! A frustum is a set of planes (inside where `normal · p + d <= 0`, unit normals).
//! Through a portal `R` the new frustum `f' = clip frustum(f, R)` is `f` plus the planes
//! through the eye and each edge of `R` (the exact convex frustum), or, with the
//! bounding-box option, `f`'s near and far planes plus the four planes through the eye
//! bounding the screen rectangle of `R` clipped to `f` (the seed's remedy for frustums
//! of odd shapes). The recursion goes through a portal only if `R` clipped to `f` is
//! not empty, and only away from the eye (a portal seen from the far side leads back).
//!
//! Soundness:
//! - Portals are clipped only by the planes through the eye: the part of `R` on the
//!   lines of sight inside `f`. (Clipping by the near plane would lose the part of an
//!   oblique portal closer than it, through which farther points are seen.)
//! - An eye on (within the tolerance of) a portal's plane passes the whole frustum.
//! - Rays are seen only from the near plane on: a wall closer than it is clipped away
//!   and the lines of sight start in the cell behind it. The walk therefore starts from
//!   every cell that meets the ball around the eye through the corners of the near
//!   rectangle (`start_cells`), each with its own PVS row.
//! - A walk that passes its budget of visits is abandoned (no portal culling).
//! - Orthographic views, whose lines of sight do not meet at the eye, are not
//!   portal-culled.
//!
//! What the model must hold for this to be right: cells cover the space the viewer and
//! the objects of cells are in, and every cell boundary that is not a portal is opaque.

use glam::{DMat3, DVec3};

use super::model::CellGraph;
use super::pvs::Pvs;
use super::stab::{Adjacency, clip_polygon, tolerance};
use crate::geom::{Aabb, Plane};
use crate::view::ViewTransform;

/// A frustum plane relative to the eye (`q = p - eye`): inside where `n · q + d <= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LocalPlane {
    pub n: DVec3,
    pub d: f64,
    /// Through the eye (`d == 0`): the planes a portal is clipped by.
    pub through_eye: bool,
}

/// One step of a portal walk: a cell entered through a portal with a frustum.
#[derive(Clone, Debug, PartialEq)]
pub struct Visit {
    /// The cell.
    pub cell: u32,
    /// The portal crossed into it (`None` for a cell the walk starts in).
    pub portal: Option<u32>,
    /// The visit it came from.
    pub parent: Option<usize>,
    /// The frustum in the cell, world space, inside where `normal · p + d <= 0`.
    pub frustum: Vec<Plane>,
    local: Vec<LocalPlane>,
}

impl Visit {
    /// Whether a world box may hold something inside this visit's frustum (false only
    /// when every corner lies outside one plane by more than the tolerance).
    #[must_use]
    pub fn may_see(&self, eye: DVec3, b: &Aabb) -> bool {
        box_in_planes(&self.local, eye, b)
    }
}

pub(crate) fn box_in_planes(planes: &[LocalPlane], eye: DVec3, b: &Aabb) -> bool {
    if b.is_empty() {
        return false;
    }
    let corners = b.corners().map(|c| c - eye);
    let size = corners
        .iter()
        .fold(0.0f64, |m, q| m.max(q.abs().max_element()));
    let eps = 1e-9 * (1.0 + size);
    planes
        .iter()
        .all(|p| corners.iter().any(|&q| p.n.dot(q) + p.d <= eps))
}

/// The portal walk from the cell holding `eye`, starting with the world-space
/// `frustum` (planes through the eye, inside where `normal · p + d <= 0`), through
/// every portal (no PVS), exact frustums; empty when `eye` is in no cell. The seed's
/// example: from E the walk goes E -> D -> A and stops.
#[must_use]
pub fn portal_walk(graph: &CellGraph, eye: DVec3, frustum: &[Plane]) -> Vec<Visit> {
    let Some(start) = graph.locate(eye) else {
        return Vec::new();
    };
    let local: Vec<LocalPlane> = frustum
        .iter()
        .map(|p| {
            let p = p.normalized();
            let d = p.d + p.normal.dot(eye);
            let through_eye = d.abs() <= tolerance(graph);
            LocalPlane {
                n: p.normal,
                d: if through_eye { 0.0 } else { d },
                through_eye,
            }
        })
        .collect();
    let adjacency = Adjacency::new(graph);
    let mut w = Walker::new(graph, &adjacency, eye, None, None, usize::MAX);
    w.walk(start, local);
    w.visits
}

/// The frustum of a perspective view in world space (left, right, bottom, top, near,
/// far; inside where `normal · p + d <= 0`), for [`portal_walk`].
#[must_use]
pub fn view_frustum(t: &ViewTransform) -> Vec<Plane> {
    view_planes(t)
        .iter()
        .map(|p| Plane {
            normal: p.n,
            d: p.d - p.n.dot(t.eye),
        })
        .collect()
}

/// The frustum of a perspective view as planes relative to the eye (the view's six
/// planes; left, right, bottom and top pass through the eye).
pub(crate) fn view_planes(t: &ViewTransform) -> Vec<LocalPlane> {
    let rt = t.rotation.transpose();
    t.eye_frustum_planes()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // Eye space: inside where n·e + w >= 0, e = R q.
            let n = -(rt * p.truncate());
            let len = n.length();
            LocalPlane {
                n: n / len,
                d: if i < 4 { 0.0 } else { -p.w / len },
                through_eye: i < 4,
            }
        })
        .collect()
}

/// The radius of the ball around the eye that holds the near rectangle (the start of
/// every line of sight), a little enlarged.
pub(crate) fn near_radius(t: &ViewTransform) -> f64 {
    let near = t.near.max(t.near_limit);
    let (sx, sy) = (t.projection.x_axis.x, t.projection.y_axis.y);
    near * (1.0 + 1.0 / (sx * sx) + 1.0 / (sy * sy)).sqrt() * (1.0 + 1e-6)
}

/// The cells the walk starts in: the eye's (first) and every other cell the ball of
/// `radius` around the eye may meet (all its planes within `radius` of the eye).
pub(crate) fn start_cells(graph: &CellGraph, eye: DVec3, eye_cell: u32, radius: f64) -> Vec<u32> {
    let eps = tolerance(graph);
    let mut v = vec![eye_cell];
    for (i, c) in graph.cells.iter().enumerate() {
        if i as u32 != eye_cell
            && !c.planes.is_empty()
            && c.planes
                .iter()
                .all(|p| p.signed_distance(eye) <= radius + eps)
        {
            v.push(i as u32);
        }
    }
    v
}

/// How a portal lies for a cell, relative to the eye.
pub(crate) enum Side {
    /// The eye is on the cell's side: lines of sight cross it into the next cell.
    Through,
    /// The eye is on (or near) its plane, or its plane is not one of the cell's:
    /// pass the whole frustum.
    Whole,
    /// The eye is beyond it: nothing is seen through it from here.
    Behind,
}

/// Where the eye lies relative to portal `p` as a boundary of `cell`.
pub(crate) fn portal_side(graph: &CellGraph, cell: u32, p: u32, eye: DVec3, eps: f64) -> Side {
    let poly = &graph.portals[p as usize].polygon;
    let Some(pl) = graph.cells[cell as usize].planes.iter().find(|pl| {
        let len = pl.normal.length();
        len > 0.0
            && poly
                .iter()
                .all(|&v| (pl.normal.dot(v) + pl.d).abs() <= eps * len * 16.0)
    }) else {
        return Side::Whole;
    };
    let n = pl.normal / pl.normal.length();
    // The eye's distance to the portal's plane, from the portal's own vertices.
    let dist = poly.iter().map(|&v| n.dot(eye - v)).sum::<f64>() / poly.len() as f64;
    if dist > eps {
        Side::Behind
    } else if dist >= -eps {
        Side::Whole
    } else {
        Side::Through
    }
}

pub(crate) struct Walker<'a> {
    graph: &'a CellGraph,
    adjacency: &'a Adjacency,
    eye: DVec3,
    eps: f64,
    pvs: Option<&'a Pvs>,
    /// World to eye rotation, for the bounding-box option.
    bbox: Option<DMat3>,
    max_visits: usize,
    source: u32,
    on_path: Vec<bool>,
    pub visits: Vec<Visit>,
    pub aborted: bool,
}

impl<'a> Walker<'a> {
    pub(crate) fn new(
        graph: &'a CellGraph,
        adjacency: &'a Adjacency,
        eye: DVec3,
        pvs: Option<&'a Pvs>,
        bbox: Option<DMat3>,
        max_visits: usize,
    ) -> Self {
        Walker {
            graph,
            adjacency,
            eye,
            eps: tolerance(graph),
            pvs,
            bbox,
            max_visits,
            source: 0,
            on_path: vec![false; graph.cells.len()],
            visits: Vec::new(),
            aborted: false,
        }
    }

    /// Walks from `start` (with its PVS row) with the frustum `planes`.
    pub(crate) fn walk(&mut self, start: u32, planes: Vec<LocalPlane>) {
        self.source = start;
        self.visit(start, planes, None, None);
    }

    fn visit(
        &mut self,
        cell: u32,
        planes: Vec<LocalPlane>,
        portal: Option<u32>,
        parent: Option<usize>,
    ) {
        if self.aborted {
            return;
        }
        if self.visits.len() >= self.max_visits {
            self.aborted = true;
            return;
        }
        let idx = self.visits.len();
        self.visits.push(Visit {
            cell,
            portal,
            parent,
            frustum: planes
                .iter()
                .map(|p| Plane {
                    normal: p.n,
                    d: p.d - p.n.dot(self.eye),
                })
                .collect(),
            local: planes.clone(),
        });
        self.on_path[cell as usize] = true;
        for &(p, next) in &self.adjacency.neighbours[cell as usize] {
            if self.aborted {
                break;
            }
            if self.on_path[next as usize]
                || self.pvs.is_some_and(|t| !t.contains(self.source, next))
            {
                continue;
            }
            let next_planes = match portal_side(self.graph, cell, p, self.eye, self.eps) {
                Side::Behind => continue,
                Side::Whole => Some(planes.clone()),
                Side::Through => self.through(&planes, p),
            };
            if let Some(f) = next_planes {
                self.visit(next, f, Some(p), Some(idx));
            }
        }
        self.on_path[cell as usize] = false;
    }

    /// `clip frustum(f, R)`: `None` when the portal clipped to `f` is empty.
    fn through(&self, planes: &[LocalPlane], p: u32) -> Option<Vec<LocalPlane>> {
        let poly: Vec<DVec3> = self.graph.portals[p as usize]
            .polygon
            .iter()
            .map(|&v| v - self.eye)
            .collect();
        let mut clipped = poly.clone();
        for pl in planes.iter().filter(|pl| pl.through_eye) {
            clipped = clip_polygon(&clipped, pl.n, 0.0, self.eps);
            if clipped.len() < 3 {
                return None;
            }
        }
        match self.bbox {
            None => {
                let mut f = planes.to_vec();
                let centroid = poly.iter().sum::<DVec3>() / poly.len() as f64;
                let m = poly.len();
                for i in 0..m {
                    let n = poly[i].cross(poly[(i + 1) % m]);
                    let len = n.length();
                    if !(len > 1e-300) || !len.is_finite() {
                        continue;
                    }
                    let mut n = n / len;
                    if n.dot(centroid) > 0.0 {
                        n = -n;
                    }
                    f.push(LocalPlane {
                        n,
                        d: 0.0,
                        through_eye: true,
                    });
                }
                Some(f)
            }
            Some(r) => {
                let (mut x0, mut y0, mut x1, mut y1) = (
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                );
                for &q in &clipped {
                    let e = r * q;
                    let depth = -e.z;
                    if !(depth > 1e-9 * (1.0 + e.abs().max_element())) {
                        // A point at the eye plane: no rectangle bounds it.
                        return Some(planes.to_vec());
                    }
                    let (x, y) = (e.x / depth, e.y / depth);
                    x0 = x0.min(x);
                    x1 = x1.max(x);
                    y0 = y0.min(y);
                    y1 = y1.max(y);
                }
                let grow = |v: f64| 1e-9 * (1.0 + v.abs());
                let (x0, x1, y0, y1) = (x0 - grow(x0), x1 + grow(x1), y0 - grow(y0), y1 + grow(y1));
                let rt = r.transpose();
                let mut f: Vec<LocalPlane> =
                    planes.iter().filter(|p| !p.through_eye).copied().collect();
                for n_e in [
                    DVec3::new(1.0, 0.0, x1),
                    DVec3::new(-1.0, 0.0, -x0),
                    DVec3::new(0.0, 1.0, y1),
                    DVec3::new(0.0, -1.0, -y0),
                ] {
                    let n = rt * n_e;
                    f.push(LocalPlane {
                        n: n / n.length(),
                        d: 0.0,
                        through_eye: true,
                    });
                }
                Some(f)
            }
        }
    }
}
