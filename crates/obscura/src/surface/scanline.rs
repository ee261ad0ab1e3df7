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
//! Papers: Wylie, Romney, Evans and Erdahl, *Half-tone perspective drawings by
//! computer* (AFIPS Fall Joint Computer Conference, 1967); Watkins, *A real time
//! visible surface algorithm* (PhD thesis, University of Utah, 1970); Sutherland,
//! Sproull and Schumacker, *A characterization of ten hidden-surface algorithms* (ACM
//! Computing Surveys, 1974).
//!
//! # How it runs here
//! - Edge table: every non-horizontal edge of every prepared polygon, bucketed by the
//!   first row whose sample line (`y = j + 0.5`) it meets, filled as the scan goes
//!   down: the polygons are bucketed by the first row of their sample box (where their
//!   first edges start), and on that row each is set up (coverage and depth plane)
//!   and its edges placed, those starting there in the active edge list and the
//!   others in their rows' buckets. A face is dropped when its last edge leaves, so
//!   memory follows the faces under the scanline.
//! - Per row: new edges join the active edge list, held by their face (see
//!   `faces`); each steps `x += 1/m` and settles its exact crossing pixel: from `x`
//!   alone when `x` is provably far enough from every pixel centre, else with the
//!   shared edge function ([`crate::raster::EdgeFunction::inside_row`]). The row's
//!   crossings are then sorted by a counting sort over the columns.
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
//! - Coherence along the row: the nearest face of a span is kept for the next spans
//!   while the set of faces in changes only by faces it is proven to hide (each
//!   entering face is compared with it once, at the first and last samples the two
//!   share) and it does not leave; those spans need no depth comparison at all. An
//!   entering face it hides over the entering face's whole span on the row can never
//!   be seen there, and is left out of the set of faces in.
//! - Coherence between rows (when no face is kept): a span whose set of faces is the
//!   one of the previous row's span at the same place reuses that span's nearest face
//!   without comparing, once the order is known not to change: the winner must hide
//!   each other face over the whole overlap of their sample boxes (checked once, at
//!   the box corners, when the set is seen on two consecutive rows; a failed check is
//!   not retried while the set lasts).
//!
//! Input: a [`PreparedView`]; output: the same [`Frame`] as the z-buffer (face ids;
//! depth from the same `f32` depth keys). Stats: `edges` (placed in the table: the
//! edges of the faces set up that meet a sample line), `max_active_edges`,
//! `max_active_faces`, `spans`, `spans_without_comparison`, `spans_decided_at_ends`,
//! `spans_by_kept_nearest`, `faces_hidden_on_entering`, `spans_by_coherence`,
//! `spans_per_pixel`, `depth_comparisons`, `comparisons_skipped_by_coherence`,
//! `order_checks`, `orders_proven`, `crossing_corrections` (pixels the incremental
//! `x` was off), `span_fallbacks`, and
//! the milliseconds of each stage: `table_ms` (bucketing the polygons), `enter_ms`
//! (the setup of new faces, the placing of their edges, new edges), `sweep_ms`
//! (crossings settled, spans), `sort_ms` (crossings sorted) and `walk_ms` (spans
//! decided and drawn).
//!
//! Complexity: O(P + E + H) to fill the table (P polygons, E edges, H rows), then per
//! row O(A + W) for the A active edges and W columns, per span O(1) when the kept
//! nearest face decides it and O(k) for its k faces otherwise, and O(k) per pixel only
//! in spans decided pixel by pixel. Every pixel is written once. Memory: 4 bytes per
//! polygon in the table, 12 per edge waiting in it, plus the active faces.
//!
//! Limitations: depth is exact for planar polygons (every prepared polygon is);
//! near-ties are decided on the `f32` keys the z-buffer stores, so the two agree
//! there too unless the z-buffer's own rounding path differs. The order check behind
//! coherence is conservative: faces that touch (a wall standing on a floor) never
//! pass it, so their spans keep being compared at their ends. The work is per face
//! and row: on scenes of many small triangles (Sponza: 1.8 million face-rows of about
//! 9 pixels) it costs more than the z-buffer's per-pixel work. Single-threaded.

mod coherence;
mod edge_table;
mod faces;

use std::ops::Range;

use crate::Result;
use crate::frame::Frame;
use crate::raster::DepthPlane;
use crate::raster::edges_row_span;
use crate::surface::RenderOptions;
use crate::surface::stats::ScanlineStats;
use crate::view::{PreparedView, ViewTransform};

use crate::surface::image::screen_faces::{hides, hides_over_overlap, stored_key, surely_nearer};
use coherence::{Coherence, Order};
use edge_table::{EdgeTable, ScanEdge, TableEdge, exact_pixel, tolerance};
use faces::{DEAD, Faces, NONE, slot_hash};

/// Renders a prepared view with the scanline algorithm.
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, ScanlineStats)> {
    let (frame, stats, _) = run(view, options, 0..0)?;
    Ok((frame, stats))
}

/// Renders like [`render`] and also records, for each row in `rows`, the active edge
/// list and the spans with how each was decided (for teaching and tests).
pub fn trace(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    rows: Range<u32>,
) -> Result<(Frame, ScanlineStats, Vec<RowTrace>)> {
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
    /// Several faces, the nearest of the previous span on the row kept: no face that
    /// entered since could be nearer (each was compared with it once, on entering).
    KeptNearest,
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
    /// The face ids whose flag is *in* over the span, ascending (without the faces
    /// left out on entering, see `faces_hidden_on_entering`).
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

/// A crossing that flips a face's flag: its pixel, and in `data` whether the face
/// enters (lowest bit) and, above it, its place in the row's entering faces (entering)
/// or its slot (leaving).
#[derive(Clone, Copy, Debug)]
struct Crossing {
    x: u32,
    data: u32,
}

/// What the walk needs of a face entering the set of faces whose flag is in: its
/// depth key along the row, `key(px) = c + dzdx (px - x0)`, the end of its span, its
/// slot.
#[derive(Clone, Copy, Debug)]
struct Entering {
    c: f64,
    dzdx: f64,
    x0: f64,
    slot: u32,
    end: u32,
}

/// A face whose flag is in: its depth key along the row, `key(px) = c + dzdx (px -
/// x0)`, and the end of its span on the row.
#[derive(Clone, Copy, Debug)]
struct Member {
    c: f64,
    dzdx: f64,
    x0: f64,
    end: u32,
}

impl Member {
    /// The key at `px`.
    #[inline(always)]
    fn key(&self, px: f64) -> f64 {
        self.c + self.dzdx * (px - self.x0)
    }
}

/// The faces whose flag is in, in the order they entered (a face leaving is replaced
/// by the last one): their slots, and their keys along the row in consecutive memory.
/// `hash` is the order-independent hash of the set.
#[derive(Debug, Default)]
struct InSet {
    slot: Vec<u32>,
    member: Vec<Member>,
    hash: u64,
}

/// The nearest face kept along a row (seed 003: the nearest face is not sought again
/// while the list brings nothing that could change it). `valid` means the face in
/// slot `slot` has been proven nearer, with the margin of [`surely_nearer`], than each
/// other face in the set at every sample from where that face was compared to the end
/// of their common span on this row: it stays the nearest until it leaves, or a face
/// enters that it is not proven to hide.
#[derive(Clone, Copy, Debug)]
struct Kept {
    slot: u32,
    valid: bool,
    /// Its keys along the row (a copy: it does not change while the face is in).
    member: Member,
}

#[derive(Debug, Default)]
struct Counters {
    max_active_edges: usize,
    max_active_faces: usize,
    spans: u64,
    without_comparison: u64,
    at_ends: u64,
    kept: u64,
    hidden_on_entering: u64,
    by_coherence: u64,
    per_pixel: u64,
    comparisons: u64,
    skipped: u64,
    order_checks: u64,
    orders_proven: u64,
    corrections: u64,
    fallbacks: u64,
    /// Seconds spent building the table, entering edges, sweeping, sorting crossings
    /// and walking them.
    seconds: [f64; 5],
}

struct Scanner<'v> {
    view: &'v PreparedView<'v>,
    transform: &'v ViewTransform,
    width: u32,
    frame: Frame,
    /// The edges of a face being set up that start on its first row.
    now: Vec<(u32, u32)>,
    /// The live faces with their active edges: the active edge list, by face.
    faces: Faces,
    /// The crossings of this row as the faces give them, then sorted by pixel.
    unsorted: Vec<Crossing>,
    crossings: Vec<Crossing>,
    entering: Vec<Entering>,
    /// Per pixel column (and one past the last), the number of crossings before it.
    bucket_starts: Vec<u32>,
    set: InSet,
    kept: Kept,
    coherence: Coherence,
    counters: Counters,
    trace: Option<RowTrace>,
}

fn run(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    trace_rows: Range<u32>,
) -> Result<(Frame, ScanlineStats, Vec<RowTrace>)> {
    let vp = view.viewport();
    // Zero bits, not background: the pages are first written where spans are drawn,
    // and ids are stored complemented (0 is "nothing drawn") until `keys_to_depths`.
    let frame = Frame::zeroed(vp)?;
    let start = std::time::Instant::now();
    let mut table = EdgeTable::build(view, vp.width, vp.height);
    let table_seconds = start.elapsed().as_secs_f64();
    let mut s = Scanner {
        view,
        transform: view.transform(),
        width: vp.width,
        frame,
        now: Vec::new(),
        faces: Faces::new(view.polygon_count(), options.fill_rule, vp.width, vp.height),
        unsorted: Vec::new(),
        crossings: Vec::new(),
        entering: Vec::new(),
        bucket_starts: vec![0; vp.width as usize + 2],
        set: InSet::default(),
        kept: Kept {
            slot: NONE,
            valid: false,
            member: Member {
                c: 0.0,
                dzdx: 0.0,
                x0: 0.0,
                end: 0,
            },
        },
        coherence: Coherence::default(),
        counters: Counters::default(),
        trace: None,
    };
    let mut traces = Vec::new();
    for y in 0..vp.height {
        if y % 64 == 0 {
            options.report(f64::from(y) / f64::from(vp.height));
        }
        // Once per row: a row of 400,000 overlapping faces takes milliseconds.
        options.check_time("scanline rows")?;
        if trace_rows.contains(&y) {
            s.trace = Some(RowTrace {
                row: y,
                active_edges: Vec::new(),
                spans: Vec::new(),
            });
        }
        s.row(y, &mut table);
        if let Some(t) = s.trace.take() {
            traces.push(t);
        }
    }
    options.report(1.0);
    keys_to_depths(&mut s.frame, s.transform);
    let c = &s.counters;
    let ms = |s: f64| (s * 1e5).round() / 100.0;
    let stats = ScanlineStats {
        polygons: view.polygon_count() as u64,
        edges: table.len() as u64,
        max_active_edges: c.max_active_edges as u64,
        max_active_faces: c.max_active_faces as u64,
        spans: c.spans,
        spans_without_comparison: c.without_comparison,
        spans_decided_at_ends: c.at_ends,
        spans_by_kept_nearest: c.kept,
        faces_hidden_on_entering: c.hidden_on_entering,
        spans_by_coherence: c.by_coherence,
        spans_per_pixel: c.per_pixel,
        depth_comparisons: c.comparisons,
        comparisons_skipped_by_coherence: c.skipped,
        order_checks: c.order_checks,
        orders_proven: c.orders_proven,
        crossing_corrections: c.corrections,
        span_fallbacks: c.fallbacks,
        table_ms: ms(table_seconds),
        enter_ms: ms(c.seconds[1]),
        sweep_ms: ms(c.seconds[2]),
        sort_ms: ms(c.seconds[3]),
        walk_ms: ms(c.seconds[4]),
    };
    Ok((s.frame, stats, traces))
}

/// Writes the face with id `face` and depth-key plane `plane` to pixels `x0..x1` of
/// row `y`: its id complemented, and its stored (`f32`) key stepped along the row as
/// the seeds do, re-anchored per run, in the depth array until [`keys_to_depths`].
#[inline]
fn fill_keys(frame: &mut Frame, y: u32, x0: u32, x1: u32, plane: &DepthPlane, face: u32) {
    let row = y as usize * frame.width as usize;
    let (a, b) = (row + x0 as usize, row + x1 as usize);
    let mut z = plane.at(f64::from(x0) + 0.5, f64::from(y) + 0.5);
    // One scalar loop: spans are a few pixels long, where a vectorised fill costs
    // more in set-up than it saves.
    for (id, d) in frame.ids[a..b].iter_mut().zip(&mut frame.depth[a..b]) {
        *id = !face;
        *d = z as f32;
        z += plane.dzdx;
    }
}

/// Turns the stored keys and complemented ids into eye-space depths and face ids, in
/// one pass at the end rather than a division per pixel while spans are drawn: where
/// the id is 0 (no face drawn) the background (`+inf`,
/// [`crate::frame::BACKGROUND`]). It is the z-buffer's own resolve (in lanes), so the
/// two give the same depth for the same key.
fn keys_to_depths(frame: &mut Frame, t: &ViewTransform) {
    crate::surface::image::resolve::resolve_frame(frame, t);
}

impl Scanner<'_> {
    /// One scanline: new edges, the sweep of the active edge list (crossings settled,
    /// spans of the faces, their crossings), the crossings sorted, and the walk.
    fn row(&mut self, y: u32, table: &mut EdgeTable) {
        let t0 = std::time::Instant::now();
        self.enter_edges(y, table);
        let t1 = std::time::Instant::now();
        if self.trace.is_some() {
            self.sweep::<true>(y);
        } else {
            self.sweep::<false>(y);
        }
        let t2 = std::time::Instant::now();
        self.sort_crossings();
        let t3 = std::time::Instant::now();
        self.walk(y);
        self.coherence.next_row();
        self.faces.end_row();
        let t4 = std::time::Instant::now();
        let s = &mut self.counters.seconds;
        for (k, (a, b)) in [(t0, t1), (t1, t2), (t2, t3), (t3, t4)]
            .into_iter()
            .enumerate()
        {
            s[k + 1] += (b - a).as_secs_f64();
        }
    }

    /// Sets up the polygons whose box starts on row `y` and places their edges in the
    /// table, and adds the edges that start on row `y` to the active edge list.
    fn enter_edges(&mut self, y: u32, table: &mut EdgeTable) {
        let view = self.view;
        let (starts, indices, _) = view.polygon_arrays();
        let vertices = view.vertices();
        // Touch the first vertex of each polygon set up on this row first: their cache
        // misses then overlap here instead of stalling the setups one after another.
        let mut touched = 0.0;
        for &polygon in table.polygons(y) {
            let first = starts
                .get(polygon as usize)
                .and_then(|&k| indices.get(k as usize));
            touched += first
                .and_then(|&v| vertices.get(v as usize))
                .map_or(0.0, |v| v.x);
        }
        std::hint::black_box(touched);
        let mut now = std::mem::take(&mut self.now);
        for k in 0..table.polygons(y).len() {
            let polygon = table.polygons(y)[k];
            let s = self.faces.activate(view, polygon);
            if s == DEAD {
                continue;
            }
            now.clear();
            let rect = self.faces.info[s as usize].rect;
            debug_assert_eq!(rect.y0, y);
            let ys = self.faces.triangle_ys;
            table.place(view, polygon, ys, (rect.y0, rect.y1), |pair, last_row| {
                now.push((pair, last_row));
            });
            for &(pair, last_row) in &now {
                self.add_table_edge(s, y, pair, last_row);
            }
        }
        self.now = now;
        let later = table.take_later(y);
        for &TableEdge {
            polygon,
            pair,
            last_row,
        } in &later
        {
            let s = self.faces.slot_of[polygon as usize];
            if s != NONE && s != DEAD {
                self.add_table_edge(s, y, pair, last_row);
            }
        }
        table.give_back(later);
    }

    /// Adds edge `pair` of the live face in slot `s`, active from row `y` to
    /// `last_row`, to the active edge list.
    #[inline]
    fn add_table_edge(&mut self, s: u32, y: u32, pair: u32, last_row: u32) {
        let Some(k) = self.faces.edges.edge_of_pair(s, pair) else {
            return;
        };
        let e = self.faces.edges.of(s)[k as usize];
        debug_assert!(e.dy > 0.0 && last_row >= y);
        let py = f64::from(y) + 0.5;
        let inverse_slope = e.dx / e.dy;
        self.faces.add_edge(
            s,
            y,
            ScanEdge {
                x: e.ox + (py - e.oy) * inverse_slope,
                inverse_slope,
                tolerance: tolerance(&e, inverse_slope, last_row - y + 1),
                last_row,
                index_left: ScanEdge::index_left(k, e.sign < 0.0),
            },
        );
    }

    /// One pass over the live faces, in memory order. For each: its edges whose last
    /// row was the previous one leave (the face leaves with its last edge); the others
    /// settle their crossing pixel, fold it into the face's span (right of all its
    /// left edges, left of all its right edges, inside its sample box) and step
    /// `x += 1/m`; the span is made exactly the shared coverage rule's; and the face
    /// gives its two crossings: it enters at the span's first pixel and leaves one past
    /// its last.
    ///
    /// The crossings bound the covered pixels, and coverage along a row is an
    /// interval, so a span whose first and last pixels are covered is exact. Every
    /// edge active on the row holds both ends inside by construction (a left edge's
    /// crossing is its first inside pixel, at or left of the span's start; a right
    /// edge's is its first outside pixel, at or right of the span's end): only the
    /// others need a test, and for a triangle only on the rows near its middle vertex
    /// (see `faces::triangle_check_rows`). Where the test fails the rule decides.
    fn sweep<const TRACE: bool>(&mut self, y: u32) {
        let py = f64::from(y) + 0.5;
        let mut traced = Vec::new();
        self.unsorted.clear();
        self.entering.clear();
        let mut active_edges = 0;
        let mut corrections = 0;
        let mut i = 0;
        while i < self.faces.list.len() {
            let faces = &mut self.faces;
            let f = &mut faces.list[i];
            f.drop_ended(y);
            if (!f.overflow && f.count == 0) || y > f.last_row {
                faces.retire(i);
                continue;
            }
            i += 1;
            let slot = f.slot;
            let n = f.count as usize;
            let (x0, x1) = (f.x0, f.x1);
            let (mut lo, mut hi_not) = (x0, !x1);
            if !f.overflow {
                active_edges += n;
                for e in f.edges.iter_mut().take(n) {
                    let (pixel, off) = match ScanEdge::settled_pixel(e.x, e.tolerance) {
                        Some(p) => (p.clamp(i64::from(x0), i64::from(x1)) as u32, 0),
                        None => exact_pixel(
                            &faces.edges.of(slot)[e.index() as usize],
                            e.left(),
                            e.x,
                            py,
                            x0,
                            x1,
                        ),
                    };
                    corrections += off;
                    // Without a branch on the side (it is unpredictable): a left edge
                    // raises `lo`, a right edge lowers `hi`, that is raises `!hi`.
                    let left = ((e.index_left as i32) >> 31) as u32;
                    lo = lo.max(pixel & left);
                    hi_not = hi_not.max(!pixel & !left);
                    if TRACE {
                        traced.push((slot, *e, pixel));
                    }
                    e.x += e.inverse_slope;
                }
            }
            let faces = &mut self.faces;
            let f = &faces.list[i - 1];
            let (mut lo, mut hi) = (lo, !hi_not);
            if lo >= hi && !f.overflow {
                continue;
            }
            let exact = if f.overflow {
                false
            } else if !(f.check_from..f.check_to).contains(&y) {
                true
            } else {
                let edges = faces.edges.of(slot);
                // The edges active on the row hold both ends by construction.
                let mask = f.edges[..n].iter().fold(0u64, |m, e| {
                    let k = e.index();
                    m | u64::from(k < 64) << (k & 63)
                });
                let (pa, pb) = (f64::from(lo) + 0.5, f64::from(hi) - 0.5);
                n >= edges.len()
                    || edges.iter().enumerate().all(|(k, e)| {
                        if k < 64 && mask & (1 << k) != 0 {
                            return true;
                        }
                        let row = e.row_term(py);
                        e.inside_row(pa, row) && e.inside_row(pb, row)
                    })
            };
            if !exact {
                self.counters.fallbacks += 1;
                let rect = faces.info[slot as usize].rect;
                let edges = faces.edges.of(slot);
                (lo, hi) = edges_row_span(edges, rect, y, 0, self.width).unwrap_or((lo, lo));
                if lo >= hi {
                    continue;
                }
            }
            let p = &faces.info[slot as usize].plane;
            self.unsorted.push(Crossing {
                x: lo,
                data: (self.entering.len() as u32) << 1 | 1,
            });
            self.unsorted.push(Crossing {
                x: hi,
                data: slot << 1,
            });
            self.entering.push(Entering {
                c: p.z0 + p.dzdy * (py - p.y0),
                dzdx: p.dzdx,
                x0: p.x0,
                slot,
                end: hi,
            });
        }
        self.counters.corrections += corrections;
        let c = &mut self.counters;
        c.max_active_edges = c.max_active_edges.max(active_edges);
        c.max_active_faces = c.max_active_faces.max(self.faces.list.len());
        if TRACE {
            self.trace_edges(&traced);
        }
    }

    /// Records the active edges settled on this row, as `(slot, edge, crossing pixel)`,
    /// in the trace: the list as the seed shows it, sorted by crossing.
    fn trace_edges(&mut self, traced: &[(u32, ScanEdge, u32)]) {
        let faces = &self.faces;
        let mut edges: Vec<ActiveEdge> = traced
            .iter()
            .map(|&(slot, e, crossing)| {
                let info = &faces.info[slot as usize];
                let poly = self.view.polygon(info.polygon as usize);
                let k = e.index();
                let pair = faces.edges.pair_of_edge(slot, k) as usize;
                let (p, q) = (poly.vertex(pair), poly.vertex((pair + 1) % poly.len()));
                ActiveEdge {
                    face: info.face,
                    y_min: faces.edges.of(slot)[k as usize].oy,
                    x: e.x,
                    y_max: p.y.max(q.y),
                    inverse_slope: e.inverse_slope,
                    left: e.left(),
                    crossing,
                }
            })
            .collect();
        edges.sort_by_key(|e| e.crossing);
        if let Some(t) = &mut self.trace {
            t.active_edges = edges;
        }
    }

    /// Sorts the row's crossings by pixel, faces leaving before faces entering at the
    /// same pixel (an entering face is then never compared with one that has left): a
    /// counting sort over the columns, O(crossings + width) (the seed's "sort the
    /// intersections ascending"). The sweep gives each face's crossings as a pair
    /// (entering, leaving), so placing every second one first puts the leaving ones
    /// first in each column.
    fn sort_crossings(&mut self) {
        let starts = &mut self.bucket_starts;
        starts.fill(0);
        for c in &self.unsorted {
            starts[c.x as usize + 1] += 1;
        }
        let mut before = 0;
        for start in starts.iter_mut() {
            before += *start;
            *start = before;
        }
        let n = self.unsorted.len();
        // Every one of the first `n` is written below: the array only grows, so that
        // it is not cleared row after row.
        if self.crossings.len() < n {
            self.crossings.resize(n, Crossing { x: 0, data: 0 });
        }
        let pairs = self.unsorted.chunks_exact(2);
        debug_assert!(pairs.remainder().is_empty());
        for side in [1, 0] {
            for pair in pairs.clone() {
                let c = pair[side];
                debug_assert_eq!(c.data & 1, 1 - side as u32);
                let at = &mut starts[c.x as usize];
                self.crossings[*at as usize] = c;
                *at += 1;
            }
        }
    }

    /// Walks the crossings left to right, flipping flags and deciding each span.
    fn walk(&mut self, y: u32) {
        let all = std::mem::take(&mut self.crossings);
        let crossings = &all[..self.unsorted.len()];
        self.kept.valid = false;
        let mut x = 0;
        for c in crossings {
            // The span up to this crossing's pixel, once per pixel with crossings.
            if c.x > x {
                self.span(y, x, c.x);
                x = c.x;
            }
            if c.data & 1 != 0 {
                self.enter((c.data >> 1) as usize, c.x);
            } else {
                self.leave(c.data >> 1);
            }
        }
        debug_assert!(self.set.slot.is_empty(), "every face leaves on its row");
        if x < self.width {
            self.span(y, x, self.width);
        }
        self.crossings = all;
    }

    /// Entering face `k` of the row enters at pixel `x`: its flag is in. The kept
    /// nearest face stays valid if it is nearer at the first and last samples the two
    /// share. If that is the entering face's whole span on the row, the entering face
    /// cannot be seen anywhere on it (the kept face is in and nearer at each of its
    /// pixels, whatever else enters), so it is left out of the set of faces in: spans
    /// are then decided among fewer faces, often one.
    #[inline]
    fn enter(&mut self, k: usize, x: u32) {
        let e = self.entering[k];
        let m = Member {
            c: e.c,
            dzdx: e.dzdx,
            x0: e.x0,
            end: e.end,
        };
        if self.kept.valid {
            let w = self.kept.member;
            let last = w.end.min(e.end);
            let (a, b) = (f64::from(x) + 0.5, f64::from(last) - 0.5);
            let hides_at_a = last > x && surely_nearer(w.key(a), m.key(a));
            let hides = hides_at_a && surely_nearer(w.key(b), m.key(b));
            self.counters.comparisons += 1 + u64::from(hides_at_a);
            self.kept.valid = hides;
            if hides && e.end <= w.end {
                self.counters.hidden_on_entering += 1;
                return;
            }
        }
        let set = &mut self.set;
        set.hash ^= slot_hash(e.slot);
        self.faces.position[e.slot as usize] = set.slot.len() as u32;
        set.slot.push(e.slot);
        set.member.push(m);
    }

    /// The face in slot `s` leaves: its flag is out (nothing to do if it was left out
    /// on entering).
    #[inline]
    fn leave(&mut self, s: u32) {
        let i = self.faces.position[s as usize];
        if i == NONE {
            return;
        }
        let i = i as usize;
        let set = &mut self.set;
        set.hash ^= slot_hash(s);
        self.faces.position[s as usize] = NONE;
        set.slot.swap_remove(i);
        set.member.swap_remove(i);
        if let Some(&moved) = set.slot.get(i) {
            self.faces.position[moved as usize] = i as u32;
        }
        if s == self.kept.slot {
            self.kept.valid = false;
        }
    }

    /// Draws the span `x0..x1` of row `y` from the faces whose flag is in. Inlined in
    /// the walk: most spans are background, one face or the kept nearest face, and
    /// need no call; the others go to [`Self::nearest`].
    #[inline(always)]
    fn span(&mut self, y: u32, x0: u32, x1: u32) {
        let decision = match self.set.slot.len() {
            0 => SpanDecision::Background,
            1 => {
                self.counters.spans += 1;
                self.counters.without_comparison += 1;
                let s = self.set.slot[0];
                self.fill(y, x0, x1, s);
                // Alone, it is the nearest until another face enters.
                self.kept = Kept {
                    slot: s,
                    valid: true,
                    member: self.set.member[0],
                };
                SpanDecision::SingleFace
            }
            _ if self.kept.valid => {
                self.counters.spans += 1;
                self.counters.kept += 1;
                self.fill(y, x0, x1, self.kept.slot);
                SpanDecision::KeptNearest
            }
            _ => {
                self.counters.spans += 1;
                self.nearest(y, x0, x1)
            }
        };
        if self.trace.is_some() {
            self.trace_span(x0, x1, decision);
        }
    }

    /// Records a span in the trace.
    #[cold]
    #[inline(never)]
    fn trace_span(&mut self, x0: u32, x1: u32, decision: SpanDecision) {
        let t = self.traced(x0, x1, decision);
        if let Some(tr) = &mut self.trace {
            tr.spans.push(t);
        }
    }

    /// Draws pixels `x0..x1` of row `y` with the face in slot `s`.
    #[inline]
    fn fill(&mut self, y: u32, x0: u32, x1: u32, s: u32) {
        let f = &self.faces.info[s as usize];
        fill_keys(&mut self.frame, y, x0, x1, &f.plane, f.face);
    }

    fn traced(&self, x0: u32, x1: u32, decision: SpanDecision) -> TracedSpan {
        let mut faces: Vec<u32> = self
            .set
            .slot
            .iter()
            .map(|&s| self.faces.info[s as usize].face)
            .collect();
        faces.sort_unstable();
        TracedSpan {
            x0,
            x1,
            faces,
            decision,
        }
    }

    /// Decides and draws a span with several faces and no kept nearest face (see
    /// [`Self::span`]): by coherence with the previous row, else by comparing the keys
    /// at the span's ends (and, to keep the winner along the row, at the end of each
    /// face's common span with it), else pixel by pixel.
    #[inline(never)]
    fn nearest(&mut self, y: u32, x0: u32, x1: u32) -> SpanDecision {
        debug_assert!(!self.kept.valid);
        let k = self.set.slot.len();
        let hash = self.set.hash;
        let seen = self.coherence.find(x0, x1, hash, k, &self.faces.position);
        let k = k as u64;
        if let Some(s) = seen.filter(|s| s.order == Order::Fixed) {
            self.counters.by_coherence += 1;
            self.counters.skipped += 3 * (k - 1);
            self.fill(y, x0, x1, s.winner);
            self.coherence
                .remember((x0, x1), hash, &self.set.slot, s.winner, Order::Fixed);
            // It hides every face of the set wherever they overlap: the nearest along
            // the row too.
            self.kept = Kept {
                slot: s.winner,
                valid: true,
                member: self.set.member[self.faces.position[s.winner as usize] as usize],
            };
            return SpanDecision::Coherence;
        }

        if let Some(ws) = self.nearest_at_ends(x0, x1) {
            self.counters.at_ends += 1;
            self.fill(y, x0, x1, ws);
            // The same set on the previous row: check once whether the order can
            // change anywhere, so that later rows may skip the comparisons.
            let order = match seen {
                None => Order::Unknown,
                Some(s) if s.order == Order::Unknown && s.winner == ws => {
                    if self.order_is_fixed(ws) {
                        Order::Fixed
                    } else {
                        Order::MayChange
                    }
                }
                Some(_) => Order::MayChange,
            };
            self.coherence
                .remember((x0, x1), hash, &self.set.slot, ws, order);
            return SpanDecision::NearestAtEnds;
        }

        self.counters.per_pixel += 1;
        let py = f64::from(y) + 0.5;
        let info = &self.faces.info;
        for x in x0..x1 {
            let px = f64::from(x) + 0.5;
            let first = &info[self.set.slot[0] as usize];
            let (mut best, mut best_key) = (first, stored_key(&first.plane, px, py));
            for &g in &self.set.slot[1..] {
                let f = &info[g as usize];
                let kg = stored_key(&f.plane, px, py);
                if hides(kg, f.polygon, best_key, best.polygon) {
                    best = f;
                    best_key = kg;
                }
            }
            self.counters.comparisons += k - 1;
            let k = self.frame.index(x, y);
            self.frame.ids[k] = !best.face;
            self.frame.depth[k] = best_key;
        }
        SpanDecision::PerPixel
    }

    /// The face nearest at the span's left end, if it is nearer than each other face
    /// (with the margin of [`surely_nearer`]) at both ends of the span `x0..x1`: the
    /// difference of two keys is affine, so it is then nearer all along. When it is
    /// also nearer at the last sample each face shares with it on the row, it is kept
    /// as the nearest for the next spans.
    fn nearest_at_ends(&mut self, x0: u32, x1: u32) -> Option<u32> {
        let members = &self.set.member[..];
        let (pl, pr) = (f64::from(x0) + 0.5, f64::from(x1) - 0.5);
        // The first face with the largest key at the left end (NaN never wins).
        let (mut w, mut best) = (usize::MAX, f64::NEG_INFINITY);
        for (g, m) in members.iter().enumerate() {
            let kg = m.key(pl);
            if kg > best {
                (w, best) = (g, kg);
            }
        }
        let mw = *members.get(w)?;
        // Comparisons are counted locally and added once (also when giving up).
        let mut comparisons = members.len() as u64 - 1;
        let mut kept = true;
        let mut proven = true;
        for (g, m) in members.iter().enumerate() {
            if g == w {
                continue;
            }
            comparisons += 1;
            if !surely_nearer(best, m.key(pl)) {
                proven = false;
                break;
            }
            let b = f64::from(mw.end.min(m.end)) - 0.5;
            comparisons += 1;
            if !surely_nearer(mw.key(b), m.key(b)) {
                kept = false;
                comparisons += 1;
                if !surely_nearer(mw.key(pr), m.key(pr)) {
                    proven = false;
                    break;
                }
            }
        }
        self.counters.comparisons += comparisons;
        if !proven {
            return None;
        }
        let ws = self.set.slot[w];
        self.kept = Kept {
            slot: ws,
            valid: kept,
            member: mw,
        };
        Some(ws)
    }

    /// Whether the face in slot `winner` hides every other face in the set wherever
    /// both can be seen.
    fn order_is_fixed(&mut self, winner: u32) -> bool {
        self.counters.order_checks += 1;
        let w = &self.faces.info[winner as usize];
        for &g in &self.set.slot {
            if g != winner {
                let f = &self.faces.info[g as usize];
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
