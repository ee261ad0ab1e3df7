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
//!   first row whose sample line (`y = j + 0.5`) it meets.
//! - Per row: new edges join the active edge list; each steps `x += 1/m` and settles
//!   its exact crossing pixel with the shared edge function
//!   ([`crate::raster::EdgeFunction::inside_row`]), correcting the incremental guess;
//!   the list is kept sorted by crossing (an adaptive sort: it changes little from one
//!   row to the next).
//! - A face's span on the row runs from its left crossing to its right one; two more
//!   pixel tests (its first and last pixel against all its edges) prove it equals the
//!   shared coverage rule, and the rare row where they fail (a sample exactly on a
//!   vertex, a bottom edge) takes [`crate::raster::PolygonCoverage::row_span`].
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
//!   two consecutive rows).
//!
//! Input: a [`PreparedView`]; output: the same [`Frame`] as the z-buffer (face ids;
//! depth from the same `f32` depth keys). Stats: `edges`, `max_active_edges`,
//! `spans`, `spans_without_comparison`, `spans_decided_at_ends`, `spans_by_coherence`,
//! `spans_per_pixel`, `depth_comparisons`, `comparisons_skipped_by_coherence`,
//! `crossing_corrections` (pixels the incremental `x` was off), `span_fallbacks`.
//!
//! Complexity: O(E log E) to build the table, then per row O(A) for the active edges
//! (A of them; the sort is near-linear as the order barely changes), plus per span
//! O(k) for its k faces, and O(k) per pixel only in spans decided pixel by pixel.
//! Every pixel is written once. Memory O(E + F) besides the frame.
//!
//! Limitations: depth is exact for planar polygons (every prepared polygon is);
//! near-ties are decided on the `f32` keys the z-buffer stores, so the two agree
//! there too unless the z-buffer's own rounding path differs.

mod edge_table;
pub(crate) mod screen_faces;

use std::ops::Range;

use crate::Result;
use crate::frame::Frame;
use crate::surface::{RenderOptions, Stats};
use crate::view::{PreparedView, ViewTransform};

use edge_table::{EdgeTable, ScanEdge};
use screen_faces::{
    ScreenFaces, fill_run, hides, hides_over_overlap, set_pixel, stored_key, surely_nearer,
};

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

/// A crossing that flips a face's flag.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    x: u32,
    face: u32,
    enter: bool,
}

/// A span with several faces remembered for the next row.
#[derive(Clone, Copy, Debug)]
struct RememberedSpan {
    x0: u32,
    x1: u32,
    hash: u64,
    count: u32,
    winner: u32,
    order: Order,
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

    /// The previous row's span overlapping `x0..x1` with exactly the active set.
    /// Spans are asked for left to right, so a cursor finds them in amortised O(1).
    fn find(
        &mut self,
        x0: u32,
        x1: u32,
        hash: u64,
        active: &[u32],
        position: &[u32],
    ) -> Option<RememberedSpan> {
        while self.cursor < self.previous.len() && self.previous[self.cursor].x1 <= x0 {
            self.cursor += 1;
        }
        self.previous[self.cursor..]
            .iter()
            .take_while(|s| s.x0 < x1)
            .find(|s| {
                s.hash == hash
                    && s.count as usize == active.len()
                    && self.previous_members[s.members.0 as usize..s.members.1 as usize]
                        .iter()
                        .all(|&m| position[m as usize] != NONE)
            })
            .copied()
    }

    fn remember(&mut self, x0: u32, x1: u32, hash: u64, active: &[u32], winner: u32, order: Order) {
        let a = self.current_members.len() as u32;
        self.current_members.extend_from_slice(active);
        self.current.push(RememberedSpan {
            x0,
            x1,
            hash,
            count: active.len() as u32,
            winner,
            order,
            members: (a, self.current_members.len() as u32),
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
fn face_hash(f: u32) -> u64 {
    let mut z = u64::from(f).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[derive(Debug, Default)]
struct Counters {
    max_active_edges: usize,
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
    faces: ScreenFaces,
    transform: &'v ViewTransform,
    width: u32,
    frame: Frame,
    // Per face: this row's span, the row it was computed for, which crossings were
    // emitted, and its place in the active set (NONE: flag out).
    lo: Vec<u32>,
    hi: Vec<u32>,
    stamp: Vec<u32>,
    emitted: Vec<u8>,
    position: Vec<u32>,
    touched: Vec<u32>,
    active_edges: Vec<ScanEdge>,
    incoming: Vec<ScanEdge>,
    incoming_order: Vec<(u32, u32)>,
    merged: Vec<ScanEdge>,
    crossings: Vec<Crossing>,
    active: Vec<u32>,
    active_hash: u64,
    keys_left: Vec<f64>,
    keys_right: Vec<f64>,
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
    let faces = ScreenFaces::new(view, options.fill_rule);
    let table = EdgeTable::build(view, &faces, vp.height);
    let n = faces.len();
    let mut s = Scanner {
        view,
        faces,
        transform: view.transform(),
        width: vp.width,
        frame,
        lo: vec![0; n],
        hi: vec![0; n],
        stamp: vec![NONE; n],
        emitted: vec![0; n],
        position: vec![NONE; n],
        touched: Vec::new(),
        active_edges: Vec::new(),
        incoming: Vec::new(),
        incoming_order: Vec::new(),
        merged: Vec::new(),
        crossings: Vec::new(),
        active: Vec::new(),
        active_hash: 0,
        keys_left: Vec::new(),
        keys_right: Vec::new(),
        coherence: Coherence::default(),
        counters: Counters::default(),
        trace: None,
    };
    let mut traces = Vec::new();
    for y in 0..vp.height {
        if y % 64 == 0 {
            options.report(f64::from(y) / f64::from(vp.height));
        }
        let tracing = trace_rows.contains(&y);
        if tracing {
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
    stats.set("faces_scanned", n as f64);
    stats.set("edges", table.len() as f64);
    stats.set("max_active_edges", c.max_active_edges as f64);
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
    /// One scanline: crossings, spans, then stepping the active edges to the next row.
    fn row(&mut self, y: u32, starting: &[ScanEdge]) {
        let py = f64::from(y) + 0.5;
        if self.active_edges.is_empty() && starting.is_empty() {
            self.coherence.next_row();
            if self.trace.is_some() {
                let span = self.traced(0, self.width, SpanDecision::Background);
                if let Some(t) = &mut self.trace {
                    t.spans.push(span);
                }
            }
            return;
        }
        self.settle_crossings(y, py, starting);
        self.settle_spans(y);
        self.emit_crossings();
        self.walk(y);
        self.coherence.next_row();
        self.active_edges.retain_mut(|e| {
            if e.last_row == y {
                false
            } else {
                e.x += e.inverse_slope;
                true
            }
        });
    }

    /// Settles every active edge's crossing pixel and folds them into per-face
    /// bounds: a face's span lies right of all its left edges and left of all its
    /// right edges (and inside its sample box). Then sorts the list by crossing: the
    /// edges already there barely change order from one row to the next (insertion
    /// sort, linear in the number of swaps), the starting ones are sorted apart and
    /// merged in.
    fn settle_crossings(&mut self, y: u32, py: f64, starting: &[ScanEdge]) {
        self.touched.clear();
        self.incoming.clear();
        self.incoming.extend_from_slice(starting);
        let mut corrections = 0;
        for e in self.active_edges.iter_mut().chain(self.incoming.iter_mut()) {
            corrections += e.cross(py);
            let f = e.face as usize;
            if self.stamp[f] != y {
                self.stamp[f] = y;
                self.lo[f] = e.x_lo;
                self.hi[f] = e.x_hi;
                self.touched.push(e.face);
            }
            if e.left {
                self.lo[f] = self.lo[f].max(e.pixel);
            } else {
                self.hi[f] = self.hi[f].min(e.pixel);
            }
        }
        self.counters.corrections += corrections;
        insertion_sort_by_key(&mut self.active_edges, |e| e.pixel);
        if !self.incoming.is_empty() {
            self.incoming_order.clear();
            self.incoming_order.extend(
                self.incoming
                    .iter()
                    .enumerate()
                    .map(|(k, e)| (e.pixel, k as u32)),
            );
            self.incoming_order.sort_unstable();
            self.merged.clear();
            let mut a = 0;
            for &(pixel, k) in &self.incoming_order {
                while a < self.active_edges.len() && self.active_edges[a].pixel <= pixel {
                    self.merged.push(self.active_edges[a]);
                    a += 1;
                }
                self.merged.push(self.incoming[k as usize]);
            }
            self.merged.extend_from_slice(&self.active_edges[a..]);
            std::mem::swap(&mut self.active_edges, &mut self.merged);
        }
        let c = &mut self.counters;
        c.max_active_edges = c.max_active_edges.max(self.active_edges.len());
        if let Some(t) = &mut self.trace {
            t.active_edges = self
                .active_edges
                .iter()
                .map(|e| ActiveEdge {
                    face: self.faces.faces[e.face as usize].face,
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
        for &f in &self.touched {
            let f = f as usize;
            let (a, b) = (self.lo[f], self.hi[f]);
            if a >= b {
                continue;
            }
            if !(self.faces.covers(f, a, y) && self.faces.covers(f, b - 1, y)) {
                self.counters.fallbacks += 1;
                let (a, b) = self
                    .faces
                    .coverage(self.view, f)
                    .and_then(|c| c.row_span(y))
                    .unwrap_or((a, a));
                self.lo[f] = a;
                self.hi[f] = b;
            }
        }
    }

    /// The crossings in the order of the active edge list: each face enters at its
    /// left edge and leaves at its right edge (at its exact span ends).
    fn emit_crossings(&mut self) {
        self.crossings.clear();
        for e in &self.active_edges {
            let f = e.face as usize;
            if self.lo[f] >= self.hi[f] {
                continue;
            }
            let bit = if e.left { 1 } else { 2 };
            if self.emitted[f] & bit == 0 {
                self.emitted[f] |= bit;
                self.crossings.push(Crossing {
                    x: if e.left { self.lo[f] } else { self.hi[f] },
                    face: e.face,
                    enter: e.left,
                });
            }
        }
        // A face whose span was bounded by its sample box rather than an edge.
        for &f in &self.touched {
            let fu = f as usize;
            if self.lo[fu] < self.hi[fu] {
                if self.emitted[fu] & 1 == 0 {
                    self.crossings.push(Crossing {
                        x: self.lo[fu],
                        face: f,
                        enter: true,
                    });
                }
                if self.emitted[fu] & 2 == 0 {
                    self.crossings.push(Crossing {
                        x: self.hi[fu],
                        face: f,
                        enter: false,
                    });
                }
            }
            self.emitted[fu] = 0;
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
                self.flip(c.face, c.enter);
                i += 1;
            }
        }
        debug_assert!(self.active.is_empty(), "every face leaves on its row");
        if x < self.width {
            self.span(y, x, self.width);
        }
        self.crossings = crossings;
    }

    fn flip(&mut self, f: u32, enter: bool) {
        let fu = f as usize;
        self.active_hash ^= face_hash(f);
        if enter {
            self.position[fu] = self.active.len() as u32;
            self.active.push(f);
        } else {
            let p = self.position[fu] as usize;
            self.active.swap_remove(p);
            if let Some(&moved) = self.active.get(p) {
                self.position[moved as usize] = p as u32;
            }
            self.position[fu] = NONE;
        }
    }

    /// Draws the span `x0..x1` of row `y` from the faces whose flag is in.
    fn span(&mut self, y: u32, x0: u32, x1: u32) {
        let decision = match self.active.len() {
            0 => SpanDecision::Background,
            1 => {
                self.counters.spans += 1;
                self.counters.without_comparison += 1;
                let f = &self.faces.faces[self.active[0] as usize];
                fill_run(&mut self.frame, self.transform, y, x0, x1, f);
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
            .map(|&f| self.faces.faces[f as usize].face)
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
        let k = self.active.len() as u64;
        let hash = self.active_hash;
        let seen = self
            .coherence
            .find(x0, x1, hash, &self.active, &self.position);
        if let Some(s) = seen.filter(|s| s.order == Order::Fixed) {
            self.counters.by_coherence += 1;
            self.counters.skipped += 3 * (k - 1);
            let f = &self.faces.faces[s.winner as usize];
            fill_run(&mut self.frame, self.transform, y, x0, x1, f);
            self.coherence
                .remember(x0, x1, hash, &self.active, s.winner, Order::Fixed);
            return SpanDecision::Coherence;
        }

        // The planes at both end samples; the nearest at the left end must beat each
        // other face at both ends.
        let py = f64::from(y) + 0.5;
        let (pl, pr) = (f64::from(x0) + 0.5, f64::from(x1) - 0.5);
        self.keys_left.clear();
        self.keys_right.clear();
        for &f in &self.active {
            let p = &self.faces.faces[f as usize].plane;
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
            let winner = self.active[w];
            let f = &self.faces.faces[winner as usize];
            fill_run(&mut self.frame, self.transform, y, x0, x1, f);
            // The same set on the previous row: check once whether the order can
            // change anywhere, so that later rows may skip the comparisons.
            let order = match seen {
                None => Order::Unknown,
                Some(s) if s.order == Order::Unknown && s.winner == winner => {
                    if self.order_is_fixed(winner) {
                        Order::Fixed
                    } else {
                        Order::MayChange
                    }
                }
                Some(_) => Order::MayChange,
            };
            self.coherence
                .remember(x0, x1, hash, &self.active, winner, order);
            return SpanDecision::NearestAtEnds;
        }

        self.counters.per_pixel += 1;
        for x in x0..x1 {
            let px = f64::from(x) + 0.5;
            let mut best = self.active[0];
            let mut best_key = stored_key(&self.faces.faces[best as usize].plane, px, py);
            for &g in &self.active[1..] {
                let kg = stored_key(&self.faces.faces[g as usize].plane, px, py);
                if hides(kg, g, best_key, best) {
                    best = g;
                    best_key = kg;
                }
            }
            self.counters.comparisons += k - 1;
            let f = &self.faces.faces[best as usize];
            set_pixel(&mut self.frame, self.transform, x, y, f, best_key);
        }
        SpanDecision::PerPixel
    }

    /// Whether `winner` hides every other active face wherever both can be seen.
    fn order_is_fixed(&mut self, winner: u32) -> bool {
        self.counters.order_checks += 1;
        let w = &self.faces.faces[winner as usize];
        for &g in &self.active {
            if g != winner {
                let (ok, n) = hides_over_overlap(w, &self.faces.faces[g as usize]);
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
