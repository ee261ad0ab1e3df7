//! Roberts' algorithm for scenes of convex polyhedra (Roberts 1963, "Machine
//! perception of three-dimensional solids", MIT Lincoln Laboratory TR 315), as seed 004
//! gives it (its section "Алгоритм Робертса", with the two worked examples; the second
//! corrected in `ALGORITHMS.md`).
//!
//! # Steps
//! 1. **Bodies** (`body.rs`): every object the view keeps must be a convex closed
//!    polyhedron (else an error names it). Its *body matrix* has one column
//!    `[a b c d]` per plane ([`body_matrix`]), signed so that the interior point (the
//!    average of its vertices) gives a positive product. The columns are taken to the
//!    view's transformed space by the inverse of the view transform (`V' = T^-1 V`,
//!    perspective included): there every view is a parallel one with the viewer at
//!    `+z` infinity, as in the seed. Planes with `E · V'_j < 0` for the test point at
//!    infinity `E = (0, 0, -1, 0)` (the direction of view) are self-hidden
//!    ([`self_hidden`]); an edge between two self-hidden planes is hidden by its own
//!    body. The box of the transformed body is kept for the box tests.
//! 2. **Priority and boxes**: bodies are sorted by the largest `z` of their
//!    transformed vertices (farthest first, the seed's priority list). A body can hide
//!    an edge only if their boxes overlap in `x` and `y` and the body's nearest `z` is
//!    beyond the edge's farthest; when the `z` ranges overlap, the edge may pierce the
//!    body (the seed's penetration flag).
//! 3. **Edge against body** ([`edge_against_body`]): `h_j = p_j + t q_j + a w_j`
//!    solved pairwise with the bounds `t = t0`, `t = t1` and, with the penetration
//!    flag, `a = 0`; the hidden interval is `t_maxmin < t < t_minmax`. Only the pieces
//!    still visible are tested against the remaining bodies (each piece with its own
//!    `t` bounds).
//! 4. **Penetration**: where an edge of one body enters or leaves another
//!    (penetration points), and the lines joining them on a face of each body: the
//!    intersection lines ([`EdgeKind::Intersection`]), tested against every body,
//!    both of theirs included.
//!
//! # Output
//! A [`Drawing`]: every edge between two planes that differ ([`EdgeKind::Crease`];
//! edges between coplanar polygons, such as a square's diagonal, are not drawn) and
//! every intersection line, cut into pieces with invisibility 0 (visible) or 1
//! (hidden by one body or more: hidden pieces are not tested further, as in the seed).
//! With [`RobertsOptions::quantitative`], hidden pieces are tested against every body
//! too and get the number of faces in front of them, as `hlr` counts them (2 per body
//! wholly in front, 1 for a body the point is in or on, 1 for an edge's own body when
//! it hides it). Edges are clipped to the view volume; pieces are in pixel
//! coordinates.
//!
//! # Departures from the seed, and why
//! - The seed tests a body only against bodies of lower priority. A body whose
//!   farthest point is nearer than the edge's nearest cannot hide it; others can,
//!   whatever their priority (a long tilted slab is nearer than a box at one end and
//!   farther at the other), so every body that passes the box and depth tests is
//!   tested, in priority order.
//! - Joins of penetration points: only those on a face of each body (see
//!   `penetration.rs`), which are the pieces of the intersection line.
//! - A body that crosses the near plane hides only beyond it (the near plane is added
//!   as one more column), as the surface algorithms clip it.
//!
//! - Bodies of more than 16 planes find the same corners by clipping the rectangle of
//!   `(t, a)` plane by plane (`O(j k)` for `k` corners) rather than by the pairwise
//!   solutions (`O(j^3)`): a polyhedral sphere of 264 faces would cost milliseconds
//!   per edge the seed's way.
//!
//! # Complexity
//! `O(E B j^3)` for `E` edges, `B` bodies that pass the box tests and `j <= 16` planes
//! per body (the seed's pairwise solutions), `O(E B j k)` beyond; the intersection
//! lines `O(P e j)` for `P` pairs of overlapping bodies with `e` edges. A time limit
//! and a stop flag ([`RobertsOptions`]) end long runs. 100 boxes at 1920x1080: see
//! `benches/roberts.rs` and `docs/lines.md`.
//!
//! # Limitations
//! Convex bodies only; tolerances are relative (1e-9 of the coordinates), so bodies
//! touching along a face or an edge do not hide each other there.

mod body;
mod edge;
mod penetration;

pub use body::{body_matrix, self_hidden};
pub use edge::{EdgeAgainstBody, edge_against_body};

use glam::{DVec3, DVec4};

use self::body::{Body, Space};
use self::edge::{
    PAIRWISE_MAX_PLANES, Row, edge_scale, hidden_interval, hidden_interval_clipped,
    inside_interval, trivially_visible,
};
use super::{Drawing, DrawnEdge, EdgeKind, Piece};
use crate::work::Deadline;
use crate::{Result, View};

/// Options of [`draw`].
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RobertsOptions {
    /// Find the intersection lines of bodies that pierce each other (stage 4).
    pub intersections: bool,
    /// Quantitative invisibility: give every hidden piece the number of faces in front
    /// of it (as `hlr` does: 2 for a body wholly in front, 1 for the body the point is
    /// in or on, 1 for an edge's own body when it hides it), testing hidden pieces
    /// against every body too. Off (the seed's way): hidden pieces are not tested
    /// further and have invisibility 1.
    pub quantitative: bool,
    /// Stop with [`crate::Error::TimeLimit`] after this long (checked at every edge
    /// and every edge-body test).
    pub time_limit: Option<std::time::Duration>,
    /// Stop with [`crate::Error::Stopped`] once another thread raises this flag.
    pub stop: Option<crate::work::StopFlag>,
}

impl Default for RobertsOptions {
    fn default() -> Self {
        RobertsOptions {
            intersections: true,
            quantitative: false,
            time_limit: None,
            stop: None,
        }
    }
}

/// What the drawing cost.
#[derive(Clone, Debug, Default, serde::Serialize)]
#[non_exhaustive]
pub struct RobertsStats {
    /// Bodies (kept objects).
    pub bodies: u64,
    /// Planes of all bodies (body matrix columns).
    pub planes: u64,
    /// Self-hidden planes.
    pub self_hidden_planes: u64,
    /// Edges considered (body edges and intersection lines).
    pub edges: u64,
    /// Body edges hidden by their own body.
    pub self_hidden_edges: u64,
    /// Edge and body pairs that passed the box and depth tests.
    pub edge_body_tests: u64,
    /// Of those, pairs decided by one plane (the edge wholly visible).
    pub trivially_visible: u64,
    /// Pairs of bodies whose boxes overlap (penetration looked for).
    pub penetration_pairs: u64,
    /// Penetration points found.
    pub penetration_points: u64,
    /// Intersection lines (joins of penetration points).
    pub intersection_lines: u64,
    /// Pieces made.
    pub pieces: u64,
    /// Of those, visible.
    pub visible_pieces: u64,
}

/// The work named by a time-limit error.
const WORK: &str = "Roberts' algorithm";

/// The direction to the viewer in the transformed space.
const TOWARDS_VIEWER: DVec4 = DVec4::Z;

/// Draws the edges of the convex bodies `view` keeps, hidden parts marked, with the
/// intersection lines of bodies that pierce each other. Errors: an object that is not
/// a convex closed polyhedron, named.
///
/// ```
/// use obscura::{scene::{demo, Viewport}, view::{PrepareOptions, View}};
/// use obscura::lines::roberts::{draw, RobertsOptions};
/// let scene = demo::cube();
/// let vp = Viewport::new(64, 48).unwrap();
/// let view = View::new(&scene, &scene.default_camera(vp.aspect()), vp, &PrepareOptions::default()).unwrap();
/// let (drawing, stats) = draw(&view, &RobertsOptions::default()).unwrap();
/// // Seen from a corner: 9 visible edges, 3 hidden.
/// assert_eq!(drawing.edges.len(), 12);
/// assert_eq!(drawing.visible().count(), 9);
/// assert_eq!(stats.self_hidden_edges, 3);
/// ```
pub fn draw(view: &View, options: &RobertsOptions) -> Result<(Drawing, RobertsStats)> {
    let deadline = Deadline::new(options.time_limit, options.stop.clone());
    let space = Space::of(view);
    let scene = view.scene();
    let mut stats = RobertsStats::default();
    let mut cache = body::AdjacencyCache::new();
    let mut bodies: Vec<Body> = Vec::new();
    let mut vertex_base = 0u32;
    for (k, o) in scene.objects().iter().enumerate() {
        if view.kept_objects()[k] {
            deadline.check(WORK)?;
            let b = body::build(view, &space, k, vertex_base, &mut cache)?;
            stats.planes += b.columns.len() as u64;
            stats.self_hidden_planes += b.hidden.iter().filter(|&&h| h).count() as u64;
            bodies.push(b);
        }
        vertex_base += o.mesh.positions().len() as u32;
    }
    stats.bodies = bodies.len() as u64;
    // The seed's priority list: farthest (smallest largest z) first.
    // (Edges are drawn in object order; the bodies hide in priority order.)
    let mut priority: Vec<usize> = (0..bodies.len()).collect();
    priority.sort_by(|&a, &b| bodies[a].hi.z.total_cmp(&bodies[b].hi.z).then(a.cmp(&b)));

    let mut drawing = Drawing::new(space.view.width as u32, space.view.height as u32);
    let mut tester = Tester {
        space: &space,
        bodies: &bodies,
        priority: &priority,
        quantitative: options.quantitative,
        deadline: &deadline,
        events: Vec::new(),
        rows: Vec::new(),
        visible: Vec::new(),
        next: Vec::new(),
    };
    for (i, b) in bodies.iter().enumerate() {
        for e in &b.edges {
            let edge = DrawnEdge {
                vertices: Some(e.vertices),
                object: Some(b.object as u32),
                kind: EdgeKind::Crease,
                faces: [Some(e.polygons[0]), Some(e.polygons[1])],
                world: e.world,
            };
            let own = b.hidden[e.planes[0]] && b.hidden[e.planes[1]];
            if own {
                stats.self_hidden_edges += 1;
            }
            tester.add(&mut drawing, &mut stats, edge, Some(i), own)?;
        }
    }
    if options.intersections {
        for i in 0..bodies.len() {
            for j in i + 1..bodies.len() {
                let (a, b) = (&bodies[i], &bodies[j]);
                if !a.world.overlaps(&b.world) {
                    continue;
                }
                deadline.check(WORK)?;
                stats.penetration_pairs += 1;
                let (points, joins) = penetration::joins(&space, a, b);
                stats.penetration_points += points as u64;
                for jn in joins {
                    stats.intersection_lines += 1;
                    let mid = 0.5 * (jn.world[0] + jn.world[1]);
                    let edge = DrawnEdge {
                        vertices: None,
                        object: Some(a.object.min(b.object) as u32),
                        kind: EdgeKind::Intersection,
                        faces: [
                            Some(polygon_at(view, a, jn.planes[0], mid)),
                            Some(polygon_at(view, b, jn.planes[1], mid)),
                        ],
                        world: jn.world,
                    };
                    tester.add(&mut drawing, &mut stats, edge, None, false)?;
                }
            }
        }
    }
    stats.edges = drawing.edges.len() as u64;
    stats.pieces = drawing.pieces.len() as u64;
    stats.visible_pieces = drawing.visible().count() as u64;
    Ok((drawing, stats))
}

/// The scene polygon of `body` on plane `plane` that holds the world point `p` (the
/// first of the plane's polygons when rounding puts it in none).
fn polygon_at(view: &View, body: &Body, plane: usize, p: DVec3) -> u32 {
    let polys = &body.plane_polygons[plane];
    let o = &view.scene().objects()[body.object];
    let base = view.polygon_base()[body.object];
    for &g in polys {
        let pts = o.world_polygon((g - base) as usize);
        let n = crate::geom::newell_normal(&pts);
        let inside = (0..pts.len()).all(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            (b - a).cross(p - a).dot(n) >= -1e-9 * (b - a).length_squared() * n.length()
        });
        if inside {
            return g;
        }
    }
    polys[0]
}

/// The hiding tests of stage 2, with their scratch space.
struct Tester<'a> {
    space: &'a Space,
    bodies: &'a [Body],
    /// Body indices in the seed's priority order.
    priority: &'a [usize],
    quantitative: bool,
    deadline: &'a Deadline,
    /// Quantitative mode: `(t, change of the count of faces in front)`.
    events: Vec<(f64, i32)>,
    rows: Vec<Row>,
    visible: Vec<(f64, f64)>,
    next: Vec<(f64, f64)>,
}

impl Tester<'_> {
    /// Adds `edge` to the drawing with its pieces: clipped to the view volume, then
    /// (unless `own_hidden`) tested against every body but `own` that may hide it.
    fn add(
        &mut self,
        drawing: &mut Drawing,
        stats: &mut RobertsStats,
        edge: DrawnEdge,
        own: Option<usize>,
        own_hidden: bool,
    ) -> Result<()> {
        self.deadline.check(WORK)?;
        let index = drawing.edges.len() as u32;
        drawing.edges.push(edge);
        let s = self.space.point(edge.world[0]);
        let d = self.space.point(edge.world[1]) - s;
        let Some((t0, t1)) = clip_to_view(s, d) else {
            return Ok(());
        };
        if self.quantitative {
            self.events.clear();
            self.count(stats, s, d, t0, t1, own)?;
            let mut events = std::mem::take(&mut self.events);
            events.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (mut at, mut count) = (t0, i64::from(own_hidden));
            let mut pending: Option<Piece> = None;
            for &(t, delta) in &events {
                let t = t.clamp(t0, t1);
                if t > at {
                    self.push_merged(drawing, &mut pending, (index, s, d), [at, t], count);
                    at = t;
                }
                count += i64::from(delta);
            }
            if at < t1 {
                self.push_merged(drawing, &mut pending, (index, s, d), [at, t1], count);
            }
            drawing.pieces.extend(pending);
            self.events = events;
            return Ok(());
        }
        self.visible.clear();
        if !own_hidden {
            self.visible.push((t0, t1));
            self.hide(stats, s, d, t0, t1, own)?;
        }
        // Pieces: the visible intervals and the gaps between them.
        let mut at = t0;
        let piece = |a: f64, b: f64, invisibility: u32| Piece {
            edge: index,
            t: [a, b],
            points: [self.space.pixel(s + d * a), self.space.pixel(s + d * b)],
            invisibility,
        };
        for &(a, b) in &self.visible {
            if a > at {
                drawing.pieces.push(piece(at, a, 1));
            }
            drawing.pieces.push(piece(a, b, 0));
            at = b;
        }
        if at < t1 {
            drawing.pieces.push(piece(at, t1, 1));
        }
        Ok(())
    }

    /// Appends the piece `t` of count `count` to `pending`, the last piece of the
    /// edge: extended when the count is the same or the piece too short to keep,
    /// pushed to the drawing and replaced otherwise.
    fn push_merged(
        &self,
        drawing: &mut Drawing,
        pending: &mut Option<Piece>,
        (index, s, d): (u32, DVec4, DVec4),
        t: [f64; 2],
        count: i64,
    ) {
        let invisibility = count.max(0) as u32;
        if let Some(p) = pending {
            if p.invisibility == invisibility || t[1] - t[0] <= 1e-12 {
                p.t[1] = t[1];
                p.points[1] = self.space.pixel(s + d * t[1]);
                return;
            }
            drawing.pieces.push(*p);
        }
        *pending = Some(Piece {
            edge: index,
            t,
            points: t.map(|t| self.space.pixel(s + d * t)),
            invisibility,
        });
    }

    /// The box and depth tests of body `i` against the edge part `t0..t1` (whose box
    /// after the divide is `lo..hi`), then its rows `p, q, w` into `self.rows`, and
    /// the trivial test. True when the rows are loaded and the body may hide a part.
    #[allow(clippy::too_many_arguments)]
    fn load_rows(
        &mut self,
        stats: &mut RobertsStats,
        i: usize,
        s: DVec4,
        d: DVec4,
        t0: f64,
        t1: f64,
        lo: DVec3,
        hi: DVec3,
    ) -> Result<bool> {
        let body = &self.bodies[i];
        if !may_hide(body, lo, hi) {
            return Ok(false);
        }
        stats.edge_body_tests += 1;
        self.deadline.check(WORK)?;
        self.rows.clear();
        self.rows.extend(body.hiding.iter().map(|v| Row {
            p: s.dot(*v),
            q: d.dot(*v),
            w: TOWARDS_VIEWER.dot(*v),
        }));
        if trivially_visible(&self.rows, t0, t1) {
            stats.trivially_visible += 1;
            return Ok(false);
        }
        Ok(true)
    }

    /// Quantitative mode: the changes of the count of faces in front along the edge
    /// part `t0..t1`, into `self.events`. A body hiding a point puts two faces in front
    /// of it, one when the point is inside it or on it.
    fn count(
        &mut self,
        stats: &mut RobertsStats,
        s: DVec4,
        d: DVec4,
        t0: f64,
        t1: f64,
        own: Option<usize>,
    ) -> Result<()> {
        let (lo, hi, scale) = edge_box(s, d, t0, t1);
        for &i in self.priority {
            if Some(i) == own || !self.load_rows(stats, i, s, d, t0, t1, lo, hi)? {
                continue;
            }
            let penetration = self.bodies[i].lo.z <= hi.z;
            let Some((h0, h1)) = solve(&self.rows, t0, t1, penetration, scale) else {
                continue;
            };
            self.events.extend([(h0, 2), (h1, -2)]);
            // Inside or on the body (a = 0, the planes let off by twice the tolerance
            // of `inside_interval`, which takes a plane the edge lies in for outside).
            for r in &mut self.rows {
                r.p += 2e-9 * scale;
            }
            if let Some((i0, _, i1, _)) = inside_interval(&self.rows, scale) {
                let (i0, i1) = (i0.max(h0), i1.min(h1));
                if i1 > i0 {
                    self.events.extend([(i0, -1), (i1, 1)]);
                }
            }
        }
        Ok(())
    }

    /// Removes from `self.visible` what the bodies hide.
    fn hide(
        &mut self,
        stats: &mut RobertsStats,
        s: DVec4,
        d: DVec4,
        t0: f64,
        t1: f64,
        own: Option<usize>,
    ) -> Result<()> {
        let (lo, hi, scale) = edge_box(s, d, t0, t1);
        for &i in self.priority {
            if Some(i) == own || !self.load_rows(stats, i, s, d, t0, t1, lo, hi)? {
                continue;
            }
            let penetration = self.bodies[i].lo.z <= hi.z;
            self.next.clear();
            for &(ta, tb) in &self.visible {
                match solve(&self.rows, ta, tb, penetration, scale) {
                    None => self.next.push((ta, tb)),
                    Some((ha, hb)) => {
                        if ha > ta {
                            self.next.push((ta, ha));
                        }
                        if hb < tb {
                            self.next.push((hb, tb));
                        }
                    }
                }
            }
            std::mem::swap(&mut self.visible, &mut self.next);
            if self.visible.is_empty() {
                return Ok(());
            }
        }
        Ok(())
    }
}

/// The box of the edge part `t0..t1` after the divide, and the edge's scale.
fn edge_box(s: DVec4, d: DVec4, t0: f64, t1: f64) -> (DVec3, DVec3, f64) {
    let (a, b) = (s + d * t0, s + d * t1);
    let (pa, pb) = (a.truncate() / a.w, b.truncate() / b.w);
    (pa.min(pb), pa.max(pb), edge_scale(s, d))
}

/// The hidden interval by the seed's pairwise solutions, or by clipping for bodies of
/// many planes (the same corners, found in `O(j k)` rather than `O(j^3)`).
#[inline]
fn solve(rows: &[Row], t0: f64, t1: f64, penetration: bool, scale: f64) -> Option<(f64, f64)> {
    if rows.len() <= PAIRWISE_MAX_PLANES {
        hidden_interval(rows, t0, t1, penetration, scale)
    } else {
        hidden_interval_clipped(rows, t0, t1, penetration, scale)
    }
}

/// The box tests (`x`, `y`) and the depth test: the body must reach nearer than the
/// farthest point of the edge whose box (after the divide) is `lo..hi`.
#[inline]
fn may_hide(body: &Body, lo: DVec3, hi: DVec3) -> bool {
    !(body.lo.x > hi.x
        || body.hi.x < lo.x
        || body.lo.y > hi.y
        || body.hi.y < lo.y
        || body.hi.z <= lo.z)
}

/// The part of the edge `s + t d` (`0 <= t <= 1`) inside the view volume `-w <= x, y,
/// z <= w` (Liang-Barsky in homogeneous coordinates); `None` when it is empty or a
/// point.
fn clip_to_view(s: DVec4, d: DVec4) -> Option<(f64, f64)> {
    crate::clip::liang_barsky::homogeneous_parameters(s, s + d).filter(|(t0, t1)| t1 - t0 > 1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_the_inside_part() {
        // From x/w = -2 to x/w = 2 at w = 1: the middle half is inside.
        let s = DVec4::new(-2.0, 0.0, 0.0, 1.0);
        let d = DVec4::new(4.0, 0.0, 0.0, 0.0);
        assert_eq!(clip_to_view(s, d), Some((0.25, 0.75)));
        assert_eq!(clip_to_view(DVec4::new(2.0, 0.0, 0.0, 1.0), DVec4::X), None);
    }
}
