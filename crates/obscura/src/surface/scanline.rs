//! Scanline hidden-surface removal with an edge table and an active edge list.
//!
//! Source: seed 003, "Linie de baleiaj": the polygon fill extended to many faces. The
//! active edge list holds per edge `(y_min, x_min, y_max, 1/m)` and the face it
//! bounds; at each scanline the edges starting there join the list, `x` steps by `1/m`,
//! finished edges leave. Crossing an edge flips its face's in/out flag; between two
//! consecutive crossings the faces whose flag is *in* are the candidates, and the
//! nearest one is drawn up to the next crossing. When the list brings nothing new the
//! order stays the same and the nearest face need not be sought again (coherence).
//!
//! # How it runs here
//! - Edge table: every non-horizontal edge of every prepared polygon, bucketed by the
//!   first row whose sample line (`y = j + 0.5`) it meets. A polygon's coverage and
//!   depth plane are set up when its first edge enters, and dropped when its last edge
//!   leaves, so memory follows the faces under the scanline.
//! - Per row: new edges join the active edge list; each steps `x += 1/m` and settles
//!   its exact crossing pixel with the shared edge function
//!   ([`crate::raster::EdgeFunction::inside_row`]), correcting the incremental guess;
//!   the list is kept sorted by crossing (insertion sort: the order barely changes
//!   from one row to the next; new edges are merged in).
//! - A face's span on the row runs from its left crossing to its right one. Coverage
//!   along a row is an interval, every pixel outside the crossings is outside an
//!   edge, and the active edges hold both ends of the span by construction, so
//!   testing the span's first and last pixel against the face's *other* edges proves
//!   it equals the shared coverage rule; the rare row where that fails (a bottom edge
//!   lying on the row's sample line, a sample on a vertex) takes
//!   [`crate::raster::PolygonCoverage::row_span`].
//! - Walking the crossings in order flips the faces' flags. A span with no face is
//!   background; with one face it is filled without any depth comparison; with several,
//!   the depth-key planes are compared at both ends of the span: if one face is nearer
//!   than each other at both ends, by a margin that survives rounding, it is nearer all
//!   along (the difference of two planes is affine), else the span is decided pixel by
//!   pixel (faces that interpenetrate inside it, or near-ties).
//! - Coherence: a span whose set of faces is the one of the previous row's span at the
//!   same place reuses that span's nearest face without comparing, once the order is
//!   known not to change: the winner must hide each other face over the whole overlap
//!   of their sample boxes (checked once, at the box corners, when the set is seen on
//!   two consecutive rows; a failed check is not retried while the set lasts).
//!
//! Input: a [`PreparedView`]; output: the same [`Frame`] as the z-buffer (face ids;
//! depth from the same `f32` depth keys). Stats: `edges`, `max_active_edges`,
//! `max_active_faces`, `spans`, `spans_without_comparison`, `spans_decided_at_ends`,
//! `spans_by_coherence`, `spans_per_pixel`, `depth_comparisons`,
//! `comparisons_skipped_by_coherence`, `order_checks`, `orders_proven`,
//! `crossing_corrections` (pixels the incremental `x` was off), `span_fallbacks`.
//!
//! Complexity: O(E + H) to build the table (E edges, H rows), then per row O(A) for
//! the A active edges (plus the out-of-order pairs the sort repairs), per span O(k)
//! for its k faces, and O(k) per pixel only in spans decided pixel by pixel. Every
//! pixel is written once. Memory: 8 bytes per edge in the table, plus the active faces.
//!
//! Limitations: depth is exact for planar polygons (every prepared polygon is);
//! near-ties are decided on the `f32` keys the z-buffer stores, so the two agree
//! there too unless the z-buffer's own rounding path differs. The order check behind
//! coherence is conservative: faces that touch (a wall standing on a floor) never
//! pass it, so their spans keep being compared at their ends. Single-threaded.

mod edge_table;
pub(crate) mod screen_faces;

use std::ops::Range;

use crate::Result;
use crate::frame::Frame;
use crate::raster::{DepthPlane, EdgeFunction, PixelRect, PolygonCoverage};
use crate::surface::{RenderOptions, Stats};
use crate::view::{PreparedView, ViewTransform};

use edge_table::{EdgeTable, ScanEdge, TableEdge, edge_rows};
use screen_faces::{fill_run, hides, hides_over_overlap, set_pixel, stored_key, surely_nearer};

/// Renders a prepared view with the scanline algorithm.
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, Stats)> {
    let (frame, stats, _) = run(view, options, 0..0)?;
    Ok((frame, stats))
}

/// Renders like [`render`] and also records, for each row in `rows`, the active edge
/// list and the spans with how each was decided (for teaching and tests).
pub fn trace(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    rows: Range<u32>,
) -> Result<(Frame, Stats, Vec<RowTrace>)> {
    run(view, options, rows)
}

/// One entry of the active edge list as seed 003 lists it, `(y_min, x_min, y_max, 1/m)`,
/// with its face and the pixel where its crossing falls on this row.
#[derive(Clone, Debug, PartialEq)]
pub struct ActiveEdge {
    /// The face id of the polygon it bounds.
    pub face: u32,
    /// Top end.
    pub y_min: f64,
    /// Where it crosses this row's sample line (the seed's running `x_min`).
    pub x: f64,
    /// Bottom end.
    pub y_max: f64,
    /// `dx/dy`, the seed's `1/m`.
    pub inverse_slope: f64,
    /// Whether the face lies to its right (the crossing flips the face *in*).
    pub left: bool,
    /// The exact crossing pixel: the first pixel inside a left edge, the first pixel
    /// past a right edge.
    pub crossing: u32,
}

/// How the face of a span was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpanDecision {
    /// No face: background.
    Background,
    /// One face: drawn without comparing depths.
    SingleFace,
    /// Several faces, one nearer than the others at both ends of the span.
    NearestAtEnds,
    /// Several faces, the same set as the previous row's span here: its face reused.
    Coherence,
    /// Several faces whose order changes inside the span (or near-ties): per pixel.
    PerPixel,
}

/// A piece of a row between two consecutive crossings.
#[derive(Clone, Debug, PartialEq)]
pub struct TracedSpan {
    /// First pixel.
    pub x0: u32,
    /// One past the last pixel.
    pub x1: u32,
    /// The face ids whose flag is *in* over the span, ascending.
    pub faces: Vec<u32>,
    /// How the visible face was found.
    pub decision: SpanDecision,
}

/// The state of one row: the sorted active edge list and the spans it made (they
/// partition the row, background included).
#[derive(Clone, Debug, PartialEq)]
pub struct RowTrace {
    /// The row.
    pub row: u32,
    /// The active edge list, sorted by crossing.
    pub active_edges: Vec<ActiveEdge>,
    /// The spans, left to right.
    pub spans: Vec<TracedSpan>,
}

const NONE: u32 = u32::MAX;
/// `slot_of` for a polygon that covers nothing (no coverage or no depth plane).
const DEAD: u32 = u32::MAX - 1;

/// A crossing that flips a face's flag.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    x: u32,
    slot: u32,
    enter: bool,
}

/// A face while its rows are being scanned.
#[derive(Clone, Debug)]
struct ActiveFace {
    plane: DepthPlane,
    rect: PixelRect,
    /// Scene-wide face id.
    face: u32,
    /// Index in the view: identity and tie-break order.
    polygon: u32,
    /// All its edge functions (horizontal ones too), for the span check.
    edges: Vec<EdgeFunction>,
    /// Per vertex pair, the index of its edge function (`NONE` if zero length).
    pair_edge: Vec<u32>,
    /// Its screen points.
    points: Vec<(f64, f64)>,
    /// How many of its edges are in the active edge list.
    edges_active: u32,
    /// Which of its first 64 edges are active on this row.
    active_mask: u64,
    // This row's span, the row it was computed for, which crossings were emitted,
    // and its place in the active set (`NONE`: flag out).
    lo: u32,
    hi: u32,
    stamp: u32,
    emitted: u8,
    position: u32,
}

/// A span with several faces remembered for the next row.
#[derive(Clone, Copy, Debug)]
struct RememberedSpan {
    x0: u32,
    x1: u32,
    hash: u64,
    count: u32,
    /// The nearest face (a polygon index).
    winner: u32,
    order: Order,
    /// Its faces (polygon indices) in the members array.
    members: (u32, u32),
}

/// Whether the nearest face of a set of faces is known to stay the nearest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Order {
    /// Not checked yet (the set was seen on one row only).
    Unknown,
    /// The winner hides every other face of the set wherever they overlap.
    Fixed,
    /// The check failed: faces of the set may swap, so it is not tried again.
    MayChange,
}

/// The previous row's multi-face spans, and the current row's being recorded.
#[derive(Debug, Default)]
struct Coherence {
    previous: Vec<RememberedSpan>,
    previous_members: Vec<u32>,
    current: Vec<RememberedSpan>,
    current_members: Vec<u32>,
    cursor: usize,
}

impl Coherence {
    fn next_row(&mut self) {
        std::mem::swap(&mut self.previous, &mut self.current);
        std::mem::swap(&mut self.previous_members, &mut self.current_members);
        self.current.clear();
        self.current_members.clear();
        self.cursor = 0;
    }

    /// The previous row's span overlapping `x0..x1` with exactly the active set (of
    /// `count` faces; `is_active` tells whether a polygon's flag is in). Spans are
    /// asked for left to right, so a cursor finds them in amortised O(1).
    fn find(
        &mut self,
        x0: u32,
        x1: u32,
        hash: u64,
        count: usize,
        is_active: impl Fn(u32) -> bool,
    ) -> Option<RememberedSpan> {
        while self.cursor < self.previous.len() && self.previous[self.cursor].x1 <= x0 {
            self.cursor += 1;
        }
        self.previous[self.cursor..]
            .iter()
            .take_while(|s| s.x0 < x1)
            .find(|s| {
                s.hash == hash
                    && s.count as usize == count
                    && self.previous_members[s.members.0 as usize..s.members.1 as usize]
                        .iter()
                        .all(|&m| is_active(m))
            })
            .copied()
    }

    fn remember(
        &mut self,
        span: (u32, u32),
        hash: u64,
        members: impl Iterator<Item = u32>,
        winner: u32,
        order: Order,
    ) {
        let a = self.current_members.len() as u32;
        self.current_members.extend(members);
        let b = self.current_members.len() as u32;
        self.current.push(RememberedSpan {
            x0: span.0,
            x1: span.1,
            hash,
            count: b - a,
            winner,
            order,
            members: (a, b),
        });
    }
}

/// Sorts a slice that is nearly sorted in time linear in its length plus the number
/// of out-of-order pairs (stable).
fn insertion_sort_by_key<T: Copy, K: Ord>(v: &mut [T], key: impl Fn(&T) -> K) {
    for i in 1..v.len() {
        let item = v[i];
        let k = key(&item);
        if key(&v[i - 1]) <= k {
            continue;
        }
        let mut j = i;
        while j > 0 && key(&v[j - 1]) > k {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = item;
    }
}

/// A face's contribution to the order-independent hash of a set of faces.
#[inline]
fn face_hash(polygon: u32) -> u64 {
    let mut z = u64::from(polygon).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[derive(Debug, Default)]
struct Counters {
    max_active_edges: usize,
    max_active_faces: usize,
    spans: u64,
    without_comparison: u64,
    at_ends: u64,
    by_coherence: u64,
    per_pixel: u64,
    comparisons: u64,
    skipped: u64,
    order_checks: u64,
    orders_proven: u64,
    corrections: u64,
    fallbacks: u64,
}

struct Scanner<'v> {
    view: &'v PreparedView<'v>,
    options: &'v RenderOptions,
    transform: &'v ViewTransform,
    width: u32,
    height: u32,
    frame: Frame,
    /// Per polygon of the view: its slot, `NONE` when not active, `DEAD` when it
    /// covers nothing.
    slot_of: Vec<u32>,
    slots: Vec<ActiveFace>,
    free_slots: Vec<u32>,
    faces_active: usize,
    touched: Vec<u32>,
    /// The edges of the active edge list, at stable places (a slab with free places).
    edge_store: Vec<ScanEdge>,
    free_edges: Vec<u32>,
    /// The active edge list proper: `(crossing pixel, place in edge_store)`, sorted.
    /// Sorting these small entries instead of the edges keeps the per-row sort and
    /// merge cheap when thousands of edges are active.
    active_edges: Vec<(u32, u32)>,
    incoming: Vec<(u32, u32)>,
    merged: Vec<(u32, u32)>,
    crossings: Vec<Crossing>,
    /// The slots whose flag is in.
    active: Vec<u32>,
    active_hash: u64,
    keys_left: Vec<f64>,
    keys_right: Vec<f64>,
    depth_points: Vec<(f64, f64, f64)>,
    coherence: Coherence,
    counters: Counters,
    trace: Option<RowTrace>,
}

fn run(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    trace_rows: Range<u32>,
) -> Result<(Frame, Stats, Vec<RowTrace>)> {
    let vp = view.viewport();
    let frame = Frame::new(vp)?;
    let table = EdgeTable::build(view, vp.width, vp.height);
    let mut s = Scanner {
        view,
        options,
        transform: view.transform(),
        width: vp.width,
        height: vp.height,
        frame,
        slot_of: vec![NONE; view.polygon_count()],
        slots: Vec::new(),
        free_slots: Vec::new(),
        faces_active: 0,
        touched: Vec::new(),
        edge_store: Vec::new(),
        free_edges: Vec::new(),
        active_edges: Vec::new(),
        incoming: Vec::new(),
        merged: Vec::new(),
        crossings: Vec::new(),
        active: Vec::new(),
        active_hash: 0,
        keys_left: Vec::new(),
        keys_right: Vec::new(),
        depth_points: Vec::new(),
        coherence: Coherence::default(),
        counters: Counters::default(),
        trace: None,
    };
    let mut traces = Vec::new();
    for y in 0..vp.height {
        if y % 64 == 0 {
            options.report(f64::from(y) / f64::from(vp.height));
        }
        if trace_rows.contains(&y) {
            s.trace = Some(RowTrace {
                row: y,
                active_edges: Vec::new(),
                spans: Vec::new(),
            });
        }
        s.row(y, table.bucket(y));
        if let Some(t) = s.trace.take() {
            traces.push(t);
        }
    }
    options.report(1.0);
    let c = &s.counters;
    let mut stats = Stats::default();
    stats.set("polygons", view.polygon_count() as f64);
    stats.set("edges", table.len() as f64);
    stats.set("max_active_edges", c.max_active_edges as f64);
    stats.set("max_active_faces", c.max_active_faces as f64);
    stats.set("spans", c.spans as f64);
    stats.set("spans_without_comparison", c.without_comparison as f64);
    stats.set("spans_decided_at_ends", c.at_ends as f64);
    stats.set("spans_by_coherence", c.by_coherence as f64);
    stats.set("spans_per_pixel", c.per_pixel as f64);
    stats.set("depth_comparisons", c.comparisons as f64);
    stats.set("comparisons_skipped_by_coherence", c.skipped as f64);
    stats.set("order_checks", c.order_checks as f64);
    stats.set("orders_proven", c.orders_proven as f64);
    stats.set("crossing_corrections", c.corrections as f64);
    stats.set("span_fallbacks", c.fallbacks as f64);
    Ok((s.frame, stats, traces))
}

impl Scanner<'_> {
    /// One scanline: new edges, crossings, spans, then stepping the active edges to
    /// the next row.
    fn row(&mut self, y: u32, starting: &[TableEdge]) {
        self.enter_edges(y, starting);
        if self.active_edges.is_empty() && self.incoming.is_empty() {
            self.coherence.next_row();
            if self.trace.is_some() {
                let span = self.traced(0, self.width, SpanDecision::Background);
                if let Some(t) = &mut self.trace {
                    t.spans.push(span);
                }
            }
            return;
        }
        self.settle_crossings(y);
        self.settle_spans(y);
        self.emit_crossings();
        self.walk(y);
        self.coherence.next_row();
        self.step_edges(y);
    }

    /// Sets up the edges of the table that start on row `y` (and their faces, when
    /// their first edge arrives) in `incoming`.
    fn enter_edges(&mut self, y: u32, starting: &[TableEdge]) {
        self.incoming.clear();
        for &TableEdge { polygon, pair } in starting {
            let mut s = self.slot_of[polygon as usize];
            if s == NONE {
                s = self.activate(polygon);
            }
            if s == DEAD {
                continue;
            }
            let f = &mut self.slots[s as usize];
            let Some(&k) = f.pair_edge.get(pair as usize).filter(|&&k| k != NONE) else {
                continue;
            };
            let e = f.edges[k as usize];
            let n = f.points.len();
            let (p, q) = (f.points[pair as usize], f.points[(pair as usize + 1) % n]);
            let (ya, yb) = (p.1.min(q.1), p.1.max(q.1));
            let Some((first, last)) = edge_rows(ya, yb, f.rect.y0, f.rect.y1) else {
                continue;
            };
            debug_assert_eq!(first, y);
            debug_assert_eq!(ya, e.oy);
            let inverse_slope = e.dx / e.dy;
            f.edges_active += 1;
            let edge = ScanEdge {
                edge: e,
                index: k,
                x: e.ox + (f64::from(y) + 0.5 - e.oy) * inverse_slope,
                inverse_slope,
                y_max: yb,
                slot: s,
                last_row: last,
                x_lo: f.rect.x0,
                x_hi: f.rect.x1,
                pixel: f.rect.x0,
                left: e.sign < 0.0,
            };
            let place = match self.free_edges.pop() {
                Some(k) => {
                    self.edge_store[k as usize] = edge;
                    k
                }
                None => {
                    self.edge_store.push(edge);
                    (self.edge_store.len() - 1) as u32
                }
            };
            self.incoming.push((0, place));
        }
    }

    /// Sets up a polygon whose first edge arrives: its coverage (the shared rule)
    /// and depth plane, in a free slot. `DEAD` if it covers nothing.
    fn activate(&mut self, polygon: u32) -> u32 {
        let poly = self.view.polygon(polygon as usize);
        let s = match self.free_slots.pop() {
            Some(s) => s,
            None => {
                self.slots.push(ActiveFace {
                    plane: DepthPlane {
                        x0: 0.0,
                        y0: 0.0,
                        z0: 0.0,
                        dzdx: 0.0,
                        dzdy: 0.0,
                    },
                    rect: PixelRect {
                        x0: 0,
                        y0: 0,
                        x1: 0,
                        y1: 0,
                    },
                    face: 0,
                    polygon: 0,
                    edges: Vec::new(),
                    pair_edge: Vec::new(),
                    points: Vec::new(),
                    edges_active: 0,
                    active_mask: 0,
                    lo: 0,
                    hi: 0,
                    stamp: NONE,
                    emitted: 0,
                    position: NONE,
                });
                (self.slots.len() - 1) as u32
            }
        };
        let f = &mut self.slots[s as usize];
        f.points.clear();
        f.points.extend(poly.vertices().map(|v| (v.x, v.y)));
        self.depth_points.clear();
        self.depth_points
            .extend(poly.vertices().map(|v| (v.x, v.y, v.zq)));
        let coverage =
            PolygonCoverage::new(&f.points, self.options.fill_rule, self.width, self.height);
        let plane = DepthPlane::from_points(&self.depth_points).filter(|p| {
            [p.x0, p.y0, p.z0, p.dzdx, p.dzdy]
                .iter()
                .all(|v| v.is_finite())
        });
        let (Some(coverage), Some(plane)) = (coverage, plane) else {
            self.free_slots.push(s);
            self.slot_of[polygon as usize] = DEAD;
            return DEAD;
        };
        f.plane = plane;
        f.rect = coverage.rect();
        f.face = poly.face;
        f.polygon = polygon;
        f.edges.clear();
        f.edges.extend_from_slice(coverage.edges());
        // The coverage made one edge function per pair of distinct consecutive points.
        f.pair_edge.clear();
        let n = f.points.len();
        let mut k = 0;
        for i in 0..n {
            if f.points[i] == f.points[(i + 1) % n] {
                f.pair_edge.push(NONE);
            } else {
                f.pair_edge.push(k);
                k += 1;
            }
        }
        debug_assert_eq!(k as usize, f.edges.len());
        f.edges_active = 0;
        f.stamp = NONE;
        f.emitted = 0;
        f.position = NONE;
        self.slot_of[polygon as usize] = s;
        self.faces_active += 1;
        let c = &mut self.counters;
        c.max_active_faces = c.max_active_faces.max(self.faces_active);
        s
    }

    /// Settles every active edge's crossing pixel and folds them into per-face
    /// bounds: a face's span lies right of all its left edges and left of all its
    /// right edges (and inside its sample box). Then sorts the list by crossing: the
    /// edges already there barely change order from one row to the next (insertion
    /// sort, linear in the number of swaps), the starting ones are sorted apart and
    /// merged in.
    fn settle_crossings(&mut self, y: u32) {
        let py = f64::from(y) + 0.5;
        self.touched.clear();
        let mut corrections = 0;
        for entry in self.active_edges.iter_mut().chain(self.incoming.iter_mut()) {
            let e = &mut self.edge_store[entry.1 as usize];
            corrections += e.cross(py);
            entry.0 = e.pixel;
            let f = &mut self.slots[e.slot as usize];
            if f.stamp != y {
                f.stamp = y;
                f.lo = e.x_lo;
                f.hi = e.x_hi;
                f.active_mask = 0;
                self.touched.push(e.slot);
            }
            if e.index < 64 {
                f.active_mask |= 1 << e.index;
            }
            if e.left {
                f.lo = f.lo.max(e.pixel);
            } else {
                f.hi = f.hi.min(e.pixel);
            }
        }
        self.counters.corrections += corrections;
        insertion_sort_by_key(&mut self.active_edges, |e| e.0);
        if !self.incoming.is_empty() {
            self.incoming.sort_unstable_by_key(|e| e.0);
            self.merged.clear();
            let mut a = 0;
            for &entry in &self.incoming {
                while a < self.active_edges.len() && self.active_edges[a].0 <= entry.0 {
                    self.merged.push(self.active_edges[a]);
                    a += 1;
                }
                self.merged.push(entry);
            }
            self.merged.extend_from_slice(&self.active_edges[a..]);
            std::mem::swap(&mut self.active_edges, &mut self.merged);
            self.incoming.clear();
        }
        let c = &mut self.counters;
        c.max_active_edges = c.max_active_edges.max(self.active_edges.len());
        if let Some(t) = &mut self.trace {
            t.active_edges = self
                .active_edges
                .iter()
                .map(|&(_, k)| &self.edge_store[k as usize])
                .map(|e| ActiveEdge {
                    face: self.slots[e.slot as usize].face,
                    y_min: e.edge.oy,
                    x: e.x,
                    y_max: e.y_max,
                    inverse_slope: e.inverse_slope,
                    left: e.left,
                    crossing: e.pixel,
                })
                .collect();
        }
    }

    /// Makes each face's span exactly the shared coverage rule's. The crossings bound
    /// the covered pixels, and coverage along a row is an interval, so a span whose
    /// first and last pixels are covered is exact; otherwise the rule decides.
    fn settle_spans(&mut self, y: u32) {
        let py = f64::from(y) + 0.5;
        for &s in &self.touched {
            let f = &mut self.slots[s as usize];
            let (a, b) = (f.lo, f.hi);
            if a >= b {
                continue;
            }
            let (pa, pb) = (f64::from(a) + 0.5, f64::from(b) - 0.5);
            // Every edge active on this row holds both ends inside by construction
            // (a left edge's crossing is its first inside pixel, and is at or left of
            // the span's start; a right edge's is its first outside pixel, at or
            // right of the span's end): only the others need a test.
            let skip = f.active_mask;
            let exact = f.edges.iter().enumerate().all(|(k, e)| {
                if k < 64 && skip & (1 << k) != 0 {
                    return true;
                }
                let row = e.row_term(py);
                e.inside_row(pa, row) && e.inside_row(pb, row)
            });
            if !exact {
                self.counters.fallbacks += 1;
                let coverage = PolygonCoverage::new(
                    &f.points,
                    self.options.fill_rule,
                    self.width,
                    self.height,
                );
                let (a, b) = coverage.and_then(|c| c.row_span(y)).unwrap_or((a, a));
                f.lo = a;
                f.hi = b;
            }
        }
    }

    /// The crossings in the order of the active edge list: each face enters at its
    /// left edge and leaves at its right edge (at its exact span ends).
    fn emit_crossings(&mut self) {
        self.crossings.clear();
        for &(_, k) in &self.active_edges {
            let e = &self.edge_store[k as usize];
            let f = &mut self.slots[e.slot as usize];
            if f.lo >= f.hi {
                continue;
            }
            let bit = if e.left { 1 } else { 2 };
            if f.emitted & bit == 0 {
                f.emitted |= bit;
                self.crossings.push(Crossing {
                    x: if e.left { f.lo } else { f.hi },
                    slot: e.slot,
                    enter: e.left,
                });
            }
        }
        // A face whose span was bounded by its sample box rather than an edge.
        for &s in &self.touched {
            let f = &mut self.slots[s as usize];
            if f.lo < f.hi {
                if f.emitted & 1 == 0 {
                    self.crossings.push(Crossing {
                        x: f.lo,
                        slot: s,
                        enter: true,
                    });
                }
                if f.emitted & 2 == 0 {
                    self.crossings.push(Crossing {
                        x: f.hi,
                        slot: s,
                        enter: false,
                    });
                }
            }
            f.emitted = 0;
        }
        insertion_sort_by_key(&mut self.crossings, |c| c.x);
    }

    /// Walks the crossings left to right, flipping flags and deciding each span.
    fn walk(&mut self, y: u32) {
        let crossings = std::mem::take(&mut self.crossings);
        let mut x = 0;
        let mut i = 0;
        while i < crossings.len() {
            let cx = crossings[i].x;
            if cx > x {
                self.span(y, x, cx);
                x = cx;
            }
            while i < crossings.len() && crossings[i].x == cx {
                let c = crossings[i];
                self.flip(c.slot, c.enter);
                i += 1;
            }
        }
        debug_assert!(self.active.is_empty(), "every face leaves on its row");
        if x < self.width {
            self.span(y, x, self.width);
        }
        self.crossings = crossings;
    }

    /// Steps the active edges to the next row, dropping finished ones and freeing
    /// faces whose last edge left.
    fn step_edges(&mut self, y: u32) {
        let slots = &mut self.slots;
        let free = &mut self.free_slots;
        let slot_of = &mut self.slot_of;
        let store = &mut self.edge_store;
        let free_edges = &mut self.free_edges;
        let mut ended = 0;
        self.active_edges.retain(|&(_, k)| {
            let e = &mut store[k as usize];
            if e.last_row == y {
                free_edges.push(k);
                let f = &mut slots[e.slot as usize];
                f.edges_active -= 1;
                if f.edges_active == 0 {
                    slot_of[f.polygon as usize] = NONE;
                    free.push(e.slot);
                    ended += 1;
                }
                false
            } else {
                e.x += e.inverse_slope;
                true
            }
        });
        self.faces_active -= ended;
    }

    fn flip(&mut self, s: u32, enter: bool) {
        let f = &mut self.slots[s as usize];
        self.active_hash ^= face_hash(f.polygon);
        if enter {
            f.position = self.active.len() as u32;
            self.active.push(s);
        } else {
            let p = f.position as usize;
            f.position = NONE;
            self.active.swap_remove(p);
            if let Some(&moved) = self.active.get(p) {
                self.slots[moved as usize].position = p as u32;
            }
        }
    }

    /// Draws the span `x0..x1` of row `y` from the faces whose flag is in.
    fn span(&mut self, y: u32, x0: u32, x1: u32) {
        let decision = match self.active.len() {
            0 => SpanDecision::Background,
            1 => {
                self.counters.spans += 1;
                self.counters.without_comparison += 1;
                let f = &self.slots[self.active[0] as usize];
                fill_run(&mut self.frame, self.transform, y, x0, x1, &f.plane, f.face);
                SpanDecision::SingleFace
            }
            _ => {
                self.counters.spans += 1;
                self.nearest(y, x0, x1)
            }
        };
        if self.trace.is_some() {
            let t = self.traced(x0, x1, decision);
            if let Some(tr) = &mut self.trace {
                tr.spans.push(t);
            }
        }
    }

    fn traced(&self, x0: u32, x1: u32, decision: SpanDecision) -> TracedSpan {
        let mut faces: Vec<u32> = self
            .active
            .iter()
            .map(|&s| self.slots[s as usize].face)
            .collect();
        faces.sort_unstable();
        TracedSpan {
            x0,
            x1,
            faces,
            decision,
        }
    }

    /// Decides and draws a span with several faces.
    fn nearest(&mut self, y: u32, x0: u32, x1: u32) -> SpanDecision {
        let k = self.active.len();
        let hash = self.active_hash;
        let (slots, slot_of) = (&self.slots, &self.slot_of);
        let seen = self.coherence.find(x0, x1, hash, k, |p| {
            let s = slot_of[p as usize];
            s < DEAD && slots[s as usize].position != NONE
        });
        let k = k as u64;
        if let Some(s) = seen.filter(|s| s.order == Order::Fixed) {
            self.counters.by_coherence += 1;
            self.counters.skipped += 3 * (k - 1);
            let f = &self.slots[self.slot_of[s.winner as usize] as usize];
            fill_run(&mut self.frame, self.transform, y, x0, x1, &f.plane, f.face);
            let members = self.active.iter().map(|&a| self.slots[a as usize].polygon);
            self.coherence
                .remember((x0, x1), hash, members, s.winner, Order::Fixed);
            return SpanDecision::Coherence;
        }

        // The planes at both end samples; the nearest at the left end must beat each
        // other face at both ends.
        let py = f64::from(y) + 0.5;
        let (pl, pr) = (f64::from(x0) + 0.5, f64::from(x1) - 0.5);
        self.keys_left.clear();
        self.keys_right.clear();
        for &s in &self.active {
            let p = &self.slots[s as usize].plane;
            self.keys_left.push(p.at(pl, py));
            self.keys_right.push(p.at(pr, py));
        }
        let mut w = 0;
        for g in 1..self.active.len() {
            if self.keys_left[g] > self.keys_left[w] {
                w = g;
            }
        }
        self.counters.comparisons += k - 1;
        let mut nearer_all_along = true;
        for g in 0..self.active.len() {
            if g != w {
                self.counters.comparisons += 2;
                if !(surely_nearer(self.keys_left[w], self.keys_left[g])
                    && surely_nearer(self.keys_right[w], self.keys_right[g]))
                {
                    nearer_all_along = false;
                    break;
                }
            }
        }
        if nearer_all_along {
            self.counters.at_ends += 1;
            let ws = self.active[w];
            let f = &self.slots[ws as usize];
            let winner = f.polygon;
            fill_run(&mut self.frame, self.transform, y, x0, x1, &f.plane, f.face);
            // The same set on the previous row: check once whether the order can
            // change anywhere, so that later rows may skip the comparisons.
            let order = match seen {
                None => Order::Unknown,
                Some(s) if s.order == Order::Unknown && s.winner == winner => {
                    if self.order_is_fixed(ws) {
                        Order::Fixed
                    } else {
                        Order::MayChange
                    }
                }
                Some(_) => Order::MayChange,
            };
            let members = self.active.iter().map(|&a| self.slots[a as usize].polygon);
            self.coherence
                .remember((x0, x1), hash, members, winner, order);
            return SpanDecision::NearestAtEnds;
        }

        self.counters.per_pixel += 1;
        for x in x0..x1 {
            let px = f64::from(x) + 0.5;
            let first = &self.slots[self.active[0] as usize];
            let (mut best, mut best_key) = (first, stored_key(&first.plane, px, py));
            for &g in &self.active[1..] {
                let f = &self.slots[g as usize];
                let kg = stored_key(&f.plane, px, py);
                if hides(kg, f.polygon, best_key, best.polygon) {
                    best = f;
                    best_key = kg;
                }
            }
            self.counters.comparisons += k - 1;
            let face = best.face;
            set_pixel(&mut self.frame, self.transform, x, y, face, best_key);
        }
        SpanDecision::PerPixel
    }

    /// Whether the face in slot `winner` hides every other active face wherever both
    /// can be seen.
    fn order_is_fixed(&mut self, winner: u32) -> bool {
        self.counters.order_checks += 1;
        let w = &self.slots[winner as usize];
        for &g in &self.active {
            if g != winner {
                let f = &self.slots[g as usize];
                let (ok, n) = hides_over_overlap(&w.plane, w.rect, &f.plane, f.rect);
                self.counters.comparisons += n;
                if !ok {
                    return false;
                }
            }
        }
        self.counters.orders_proven += 1;
        true
    }
}
