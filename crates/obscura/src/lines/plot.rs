//! Plotter-ready polylines from a [`Drawing`]: pieces joined end to end, duplicates
//! removed, short pieces dropped, and the polylines ordered to shorten pen-up travel.
//!
//! # Input and output
//! [`plot`] takes the pieces of a drawing (pixel coordinates, x right, y down) and
//! returns a [`Plot`]: the visible pieces (quantitative invisibility 0) and the hidden
//! ones (1 or more) as two separate lists of [`Polyline`]s, each list in the order a pen
//! should draw it, and [`PlotStats`] saying what was dropped, merged and how much pen-up
//! travel the ordering saved.
//!
//! # Steps
//! 1. **Duplicates.** Pieces of one class lying on one another (the same segment twice,
//!    reversed, or collinear pieces that overlap) are merged into the union of their
//!    intervals on one line; hidden pieces lying on visible ones are dropped where they
//!    overlap (the pen would draw that stretch twice). Two pieces are on one line when
//!    both ends of the shorter are within `tolerance` of the longer's line; candidates
//!    come from a uniform grid of the segments (each registered in every cell its
//!    `tolerance`-wide band touches), so the work is about linear in the pieces.
//! 2. **Short pieces.** A piece shorter than `min_length` is dropped, and its two ends
//!    are merged into one point, so the lines it linked stay linked.
//! 3. **Joining.** Ends closer than `tolerance` are one node (a grid of `tolerance`-sized
//!    cells). Polylines are walked through the resulting graph, from nodes of odd degree
//!    first (where a line must start or end), at each node taking the unused piece that
//!    turns least; closed loops are walked last. Points where the line goes on straight
//!    (within `tolerance / 10`) are left out.
//! 4. **Order.** Greedy nearest neighbour from the pen's home (0, 0), each polyline
//!    entered at whichever end is nearer (a grid of polyline ends, rebuilt coarser as it
//!    empties), then 2-opt moves over a window of [`TWO_OPT_WINDOW`] polylines (a move
//!    reverses a run of polylines and each of them). If the result travels further than
//!    the order the pieces came in, that order is kept, so travel after <= before.
//!
//! Travel is the pen-up distance from (0, 0) to the first polyline's start and from each
//! polyline's end to the next one's start, per class (a plotter draws the layers one
//! after the other); the way back home is not counted.
//!
//! # Limitations
//! A junction where three or more pieces meet ends or starts a polyline (an Euler
//! decomposition into the fewest polylines is not attempted). Snapping ends to a node
//! moves them by up to `tolerance` (by up to `min_length` across a dropped piece).
//!
//! Sources: the 2-opt move is Croes 1958, "A method for solving traveling-salesman
//! problems"; nearest-neighbour pen ordering is what plotter tools (vpype's `linesort`)
//! do.

use std::collections::HashMap;
use std::time::Instant;

use glam::DVec2;
use serde::Serialize;

use super::Drawing;

/// How many polylines ahead a 2-opt move looks.
pub const TWO_OPT_WINDOW: usize = 40;

/// Options of [`plot`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct PlotOptions {
    /// Ends closer than this (pixels) are joined; a piece whose ends lie within this of
    /// another's line lies on it.
    pub tolerance: f64,
    /// Pieces shorter than this (pixels) are dropped, their ends merged.
    pub min_length: f64,
    /// Merge pieces of one class lying on one another.
    pub dedupe: bool,
    /// Drop hidden pieces where they lie on visible ones.
    pub drop_hidden_under_visible: bool,
    /// Order the polylines to shorten pen-up travel (else: the order of the pieces).
    pub order: bool,
}

impl PlotOptions {
    /// The defaults: tolerance 0.01 px, minimum length 0.1 px, everything on.
    pub const DEFAULT: PlotOptions = PlotOptions {
        tolerance: 0.01,
        min_length: 0.1,
        dedupe: true,
        drop_hidden_under_visible: true,
        order: true,
    };

    /// These options with another joining tolerance (pixels).
    #[must_use]
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }

    /// These options with another minimum piece length (pixels).
    #[must_use]
    pub fn with_min_length(mut self, min_length: f64) -> Self {
        self.min_length = min_length;
        self
    }

    /// These options with ordering on or off.
    #[must_use]
    pub fn with_order(mut self, order: bool) -> Self {
        self.order = order;
        self
    }

    /// These options with duplicate removal on or off (both rules).
    #[must_use]
    pub fn with_dedupe(mut self, dedupe: bool) -> Self {
        self.dedupe = dedupe;
        self.drop_hidden_under_visible = dedupe;
        self
    }

    fn validate(&self) -> crate::Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(crate::Error::option(
                "PlotOptions::tolerance",
                format!("{} px: give a positive number of pixels", self.tolerance),
            ));
        }
        if !(self.min_length.is_finite() && self.min_length >= 0.0) {
            return Err(crate::Error::option(
                "PlotOptions::min_length",
                format!("{} px: give zero or a positive number", self.min_length),
            ));
        }
        Ok(())
    }
}

impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions::DEFAULT
    }
}

/// A line drawn without lifting the pen: two or more points in pixel coordinates.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Polyline {
    /// The points, in drawing order.
    pub points: Vec<DVec2>,
}

impl Polyline {
    /// Where the pen goes down.
    #[must_use]
    pub fn start(&self) -> DVec2 {
        self.points[0]
    }

    /// Where the pen comes up.
    #[must_use]
    pub fn end(&self) -> DVec2 {
        self.points[self.points.len() - 1]
    }

    /// Its length in pixels.
    #[must_use]
    pub fn length(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .sum::<f64>()
            + 0.0
    }
}

/// The polylines of a drawing, ready to plot.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Plot {
    /// Width of the picture in pixels.
    pub width: u32,
    /// Height of the picture in pixels.
    pub height: u32,
    /// The visible lines, in drawing order.
    pub visible: Vec<Polyline>,
    /// The hidden lines, in drawing order.
    pub hidden: Vec<Polyline>,
}

impl Plot {
    /// The bounding box of every point, visible and hidden (`None` without lines).
    #[must_use]
    pub fn bounds(&self) -> Option<(DVec2, DVec2)> {
        let mut it = self
            .visible
            .iter()
            .chain(&self.hidden)
            .flat_map(|p| p.points.iter().copied());
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }
}

/// What [`plot`] did to one class of lines (visible or hidden).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LayerStats {
    /// Pieces of this class in the drawing.
    pub pieces: u64,
    /// Pieces shorter than the minimum length, dropped.
    pub short_pieces: u64,
    /// Length (pixels) removed as duplicates of pieces of the same class.
    pub duplicate_length: f64,
    /// Length (pixels) of hidden pieces removed where they lay on visible ones (0 for
    /// the visible class).
    pub under_visible_length: f64,
    /// Polylines made.
    pub polylines: u64,
    /// Points in them.
    pub points: u64,
    /// Their total length (pixels).
    pub length: f64,
    /// Pen-up travel (pixels) in the order the pieces came in.
    pub travel_before: f64,
    /// Pen-up travel (pixels) in the order chosen.
    pub travel_after: f64,
}

/// What [`plot`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PlotStats {
    /// The visible lines.
    pub visible: LayerStats,
    /// The hidden lines.
    pub hidden: LayerStats,
    /// Pieces with a coordinate that is not finite, left out.
    pub invalid_pieces: u64,
    /// Milliseconds taken.
    pub time_ms: f64,
}

impl PlotStats {
    /// Pen-up travel (pixels) before ordering, both classes.
    #[must_use]
    pub fn travel_before(&self) -> f64 {
        self.visible.travel_before + self.hidden.travel_before
    }

    /// Pen-up travel (pixels) after ordering, both classes.
    #[must_use]
    pub fn travel_after(&self) -> f64 {
        self.visible.travel_after + self.hidden.travel_after
    }
}

/// A straight piece of one class.
#[derive(Clone, Copy, Debug)]
struct Segment {
    a: DVec2,
    b: DVec2,
    hidden: bool,
}

/// Turns a drawing's pieces into ordered polylines (see the module docs).
///
/// ```
/// use glam::{DVec2, DVec3};
/// use obscura::lines::{Drawing, DrawnEdge, EdgeKind, Piece};
/// use obscura::lines::plot::{plot, PlotOptions};
///
/// let mut d = Drawing::new(100, 100);
/// d.edges.push(DrawnEdge {
///     vertices: None, object: None, kind: EdgeKind::Crease, faces: [None, None],
///     world: [DVec3::ZERO, DVec3::X],
/// });
/// // One edge cut in two pieces, and the second piece given twice: one polyline.
/// for (t, a, b) in [([0.0, 0.5], (10.0, 10.0), (50.0, 10.0)),
///                   ([0.5, 1.0], (50.0, 10.0), (90.0, 10.0)),
///                   ([0.5, 1.0], (50.0, 10.0), (90.0, 10.0))] {
///     d.pieces.push(Piece { edge: 0, t, points: [DVec2::new(a.0, a.1), DVec2::new(b.0, b.1)],
///                           invisibility: 0 });
/// }
/// let (p, stats) = plot(&d, &PlotOptions::default())?;
/// assert_eq!(p.visible.len(), 1);
/// assert_eq!(p.visible[0].points.len(), 2); // the straight joint is left out
/// assert!((stats.visible.duplicate_length - 40.0).abs() < 1e-9);
/// # Ok::<(), obscura::Error>(())
/// ```
pub fn plot(drawing: &Drawing, options: &PlotOptions) -> crate::Result<(Plot, PlotStats)> {
    options.validate()?;
    let start = Instant::now();
    let mut stats = PlotStats::default();
    let mut segments = Vec::with_capacity(drawing.pieces.len());
    for p in &drawing.pieces {
        let [a, b] = p.points;
        if !(a.is_finite() && b.is_finite()) {
            stats.invalid_pieces += 1;
            continue;
        }
        let hidden = !p.is_visible();
        if hidden {
            stats.hidden.pieces += 1;
        } else {
            stats.visible.pieces += 1;
        }
        segments.push(Segment { a, b, hidden });
    }
    if options.dedupe || options.drop_hidden_under_visible {
        segments = dedupe(segments, options, &mut stats);
    }
    let mut plot = Plot {
        width: drawing.width,
        height: drawing.height,
        ..Plot::default()
    };
    for hidden in [false, true] {
        let layer = if hidden {
            &mut stats.hidden
        } else {
            &mut stats.visible
        };
        let class: Vec<Segment> = segments
            .iter()
            .filter(|s| s.hidden == hidden)
            .copied()
            .collect();
        let mut lines = join(&class, options, layer);
        layer.travel_before = travel(&lines);
        if options.order {
            lines = order(lines);
        }
        layer.travel_after = travel(&lines);
        layer.polylines = lines.len() as u64;
        layer.points = lines.iter().map(|l| l.points.len() as u64).sum();
        layer.length = lines.iter().map(Polyline::length).sum::<f64>() + 0.0;
        if hidden {
            plot.hidden = lines;
        } else {
            plot.visible = lines;
        }
    }
    stats.time_ms = start.elapsed().as_secs_f64() * 1e3;
    Ok((plot, stats))
}

/// Pen-up travel of polylines drawn in this order from (0, 0).
#[must_use]
pub fn travel(lines: &[Polyline]) -> f64 {
    let mut at = DVec2::ZERO;
    let mut sum = 0.0;
    for l in lines {
        sum += at.distance(l.start());
        at = l.end();
    }
    sum
}

/// Union-find with path halving.
struct Sets(Vec<u32>);

impl Sets {
    fn new(n: usize) -> Self {
        Sets((0..n as u32).collect())
    }
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let up = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = up;
            x = up;
        }
        x
    }
    /// Unites, the smaller root becoming the root (the earlier piece represents).
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

/// The most segments one grid cell compares pairwise; a fuller cell (a star of
/// thousands of lines through one point) is left as it is rather than taking
/// quadratic time.
const CELL_PAIR_LIMIT: usize = 4096;

/// Cells of a segment's `tol`-wide band in a grid of `cell`-sized cells from `origin`.
fn band_cells(s: &Segment, tol: f64, origin: DVec2, cell: f64, out: &mut Vec<(i64, i64)>) {
    let (lo, hi) = (s.a.min(s.b) - tol, s.a.max(s.b) + tol);
    let cy0 = ((lo.y - origin.y) / cell).floor() as i64;
    let cy1 = ((hi.y - origin.y) / cell).floor() as i64;
    let d = s.b - s.a;
    for cy in cy0..=cy1 {
        let (y0, y1) = (
            origin.y + cy as f64 * cell - tol,
            origin.y + (cy + 1) as f64 * cell + tol,
        );
        // The part of the segment within the row band, then its x range.
        let (t0, t1) = if d.y.abs() < 1e-300 {
            (0.0, 1.0)
        } else {
            let (ta, tb) = ((y0 - s.a.y) / d.y, (y1 - s.a.y) / d.y);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        };
        if t0 > t1 {
            continue;
        }
        let (xa, xb) = (s.a.x + d.x * t0, s.a.x + d.x * t1);
        let cx0 = ((xa.min(xb) - tol - origin.x) / cell).floor() as i64;
        let cx1 = ((xa.max(xb) + tol - origin.x) / cell).floor() as i64;
        for cx in cx0..=cx1 {
            out.push((cx, cy));
        }
    }
}

/// A segment's unit direction and length, computed once for the pair tests.
#[derive(Clone, Copy)]
struct Frame {
    u: DVec2,
    len: f64,
}

impl Frame {
    fn of(s: &Segment) -> Frame {
        let d = s.b - s.a;
        let len = d.length();
        Frame {
            u: if len > 0.0 { d / len } else { DVec2::ZERO },
            len,
        }
    }
}

/// Whether `short` lies on `long`'s line within `tol` and overlaps it by more than `tol`.
fn overlapping(long: &Segment, frame: Frame, short: &Segment, tol: f64) -> bool {
    let Frame { u, len } = frame;
    if len == 0.0 {
        return false;
    }
    let n = u.perp();
    let (pa, pb) = (short.a - long.a, short.b - long.a);
    if n.dot(pa).abs() > tol || n.dot(pb).abs() > tol {
        return false;
    }
    let (s0, s1) = (u.dot(pa), u.dot(pb));
    s0.max(s1).min(len) - s0.min(s1).max(0.0) > tol
}

/// Merges overlapping collinear segments (see the module docs, step 1).
fn dedupe(segments: Vec<Segment>, options: &PlotOptions, stats: &mut PlotStats) -> Vec<Segment> {
    let tol = options.tolerance;
    let n = segments.len();
    if n < 2 {
        return segments;
    }
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut total = 0.0;
    for s in &segments {
        lo = lo.min(s.a.min(s.b));
        hi = hi.max(s.a.max(s.b));
        total += s.a.distance(s.b);
    }
    let extent = (hi - lo).max_element();
    // About one segment length a cell, no finer than the tolerance allows and with at
    // most about 4096 cells a side.
    let cell = (total / n as f64).max(8.0 * tol).max(extent / 4096.0);
    let mut keys: Vec<((i64, i64), u32)> = Vec::with_capacity(n * 3);
    let mut cells = Vec::new();
    for (k, s) in segments.iter().enumerate() {
        cells.clear();
        band_cells(s, tol, lo, cell, &mut cells);
        keys.extend(cells.iter().map(|&c| (c, k as u32)));
    }
    keys.sort_unstable();
    let frames: Vec<Frame> = segments.iter().map(Frame::of).collect();
    let mut sets = Sets::new(n);
    let mut merged_any = vec![false; n];
    let mut i = 0;
    while i < keys.len() {
        let mut j = i;
        while j < keys.len() && keys[j].0 == keys[i].0 {
            j += 1;
        }
        let group = &keys[i..j];
        if group.len() <= CELL_PAIR_LIMIT {
            for (x, &(_, a)) in group.iter().enumerate() {
                for &(_, b) in &group[x + 1..] {
                    let (sa, sb) = (&segments[a as usize], &segments[b as usize]);
                    if sa.hidden != sb.hidden {
                        if !options.drop_hidden_under_visible {
                            continue;
                        }
                    } else if !options.dedupe {
                        continue;
                    }
                    let (fa, fb) = (frames[a as usize], frames[b as usize]);
                    let (long, frame, short) = if fa.len >= fb.len {
                        (sa, fa, sb)
                    } else {
                        (sb, fb, sa)
                    };
                    // Directions further apart than the shorter piece can tilt within
                    // the tolerance: not on one line.
                    let short_len = fa.len.min(fb.len);
                    if fa.u.perp_dot(fb.u).abs() * short_len > 2.0 * tol {
                        continue;
                    }
                    if overlapping(long, frame, short, tol) {
                        sets.union(a, b);
                        merged_any[a as usize] = true;
                        merged_any[b as usize] = true;
                    }
                }
            }
        }
        i = j;
    }
    // Groups of segments on one line.
    let mut groups: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        if merged_any[k] {
            groups
                .entry(sets.find(k as u32))
                .or_default()
                .push(k as u32);
        } else {
            out.push(segments[k]);
        }
    }
    let mut roots: Vec<u32> = groups.keys().copied().collect();
    roots.sort_unstable();
    for root in roots {
        let members = &groups[&root];
        // The longest member gives the line.
        let reference = members
            .iter()
            .map(|&m| segments[m as usize])
            .max_by(|x, y| {
                x.a.distance_squared(x.b)
                    .total_cmp(&y.a.distance_squared(y.b))
            })
            .expect("a group has members");
        let origin = reference.a;
        let u = (reference.b - reference.a).normalize();
        let mut spans = [Vec::new(), Vec::new()];
        let mut lengths = [0.0, 0.0];
        for &m in members {
            let s = segments[m as usize];
            let (s0, s1) = (u.dot(s.a - origin), u.dot(s.b - origin));
            spans[s.hidden as usize].push([s0.min(s1), s0.max(s1)]);
            lengths[s.hidden as usize] += s.a.distance(s.b);
        }
        let visible = union(&mut spans[0], tol);
        let hidden_all = union(&mut spans[1], tol);
        let hidden_union: f64 = hidden_all.iter().map(|s| s[1] - s[0]).sum();
        let hidden = if options.drop_hidden_under_visible {
            subtract(&hidden_all, &visible)
        } else {
            hidden_all
        };
        let vis_len: f64 = visible.iter().map(|s| s[1] - s[0]).sum();
        let hid_len: f64 = hidden.iter().map(|s| s[1] - s[0]).sum();
        stats.visible.duplicate_length += (lengths[0] - vis_len).max(0.0);
        stats.hidden.duplicate_length += (lengths[1] - hidden_union).max(0.0);
        stats.hidden.under_visible_length += (hidden_union - hid_len).max(0.0);
        for (spans, hidden) in [(visible, false), (hidden, true)] {
            for [s0, s1] in spans {
                out.push(Segment {
                    a: origin + u * s0,
                    b: origin + u * s1,
                    hidden,
                });
            }
        }
    }
    out
}

/// The union of intervals, merging those that overlap or are within `tol`.
fn union(spans: &mut [[f64; 2]], tol: f64) -> Vec<[f64; 2]> {
    spans.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]));
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(spans.len());
    for &s in spans.iter() {
        match out.last_mut() {
            Some(last) if s[0] <= last[1] + tol => last[1] = last[1].max(s[1]),
            _ => out.push(s),
        }
    }
    out
}

/// `a` less `b` (both sorted unions of intervals).
fn subtract(a: &[[f64; 2]], b: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    for &[mut s0, s1] in a {
        for &[c0, c1] in b {
            if c1 <= s0 || c0 >= s1 {
                continue;
            }
            if c0 > s0 {
                out.push([s0, c0]);
            }
            s0 = s0.max(c1);
            if s0 >= s1 {
                break;
            }
        }
        if s0 < s1 {
            out.push([s0, s1]);
        }
    }
    out
}

/// Joins one class's segments into polylines (steps 2 and 3 of the module docs).
fn join(segments: &[Segment], options: &PlotOptions, stats: &mut LayerStats) -> Vec<Polyline> {
    let tol = options.tolerance;
    let n = segments.len();
    if n == 0 {
        return Vec::new();
    }
    let points: Vec<DVec2> = segments.iter().flat_map(|s| [s.a, s.b]).collect();
    let mut sets = Sets::new(points.len());
    // Ends within `tol` of each other: cells of `tol` (points sorted by cell), each
    // point against the later points of its own cell and those of the four cells after
    // it (each pair looked at once).
    let mut keyed: Vec<(i64, i64, u32)> = points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            (
                (p.y / tol).floor() as i64,
                (p.x / tol).floor() as i64,
                k as u32,
            )
        })
        .collect();
    keyed.sort_unstable();
    // `below` follows the first point at or after cell (cy + 1, cx - 1): it only moves
    // forward as the cells do, so the whole sweep is linear after the sort.
    let mut below = 0;
    let mut i = 0;
    while i < keyed.len() {
        let (cy, cx) = (keyed[i].0, keyed[i].1);
        let mut j = i;
        while j < keyed.len() && (keyed[j].0, keyed[j].1) == (cy, cx) {
            j += 1;
        }
        let mut next = j;
        while next < keyed.len() && (keyed[next].0, keyed[next].1) == (cy, cx + 1) {
            next += 1;
        }
        while below < keyed.len() && (keyed[below].0, keyed[below].1) < (cy + 1, cx - 1) {
            below += 1;
        }
        let mut below_end = below;
        while below_end < keyed.len()
            && (keyed[below_end].0, keyed[below_end].1) <= (cy + 1, cx + 1)
        {
            below_end += 1;
        }
        for x in i..j {
            let k = keyed[x].2;
            let p = points[k as usize];
            for e in keyed[x + 1..next].iter().chain(&keyed[below..below_end]) {
                if points[e.2 as usize].distance(p) <= tol {
                    sets.union(k, e.2);
                }
            }
        }
        i = j;
    }
    let mut long = Vec::with_capacity(n);
    for (k, s) in segments.iter().enumerate() {
        if s.a.distance(s.b) < options.min_length {
            sets.union(2 * k as u32, 2 * k as u32 + 1);
            stats.short_pieces += 1;
        } else {
            long.push(k);
        }
    }
    // Nodes: one per set, at its representative's position.
    let mut node_of_root = vec![u32::MAX; points.len()];
    let mut node_pos: Vec<DVec2> = Vec::new();
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(long.len());
    for &k in &long {
        let mut ends = [0u32; 2];
        for (e, end) in ends.iter_mut().enumerate() {
            let root = sets.find((2 * k + e) as u32);
            if node_of_root[root as usize] == u32::MAX {
                node_of_root[root as usize] = node_pos.len() as u32;
                node_pos.push(points[root as usize]);
            }
            *end = node_of_root[root as usize];
        }
        if ends[0] == ends[1] {
            // Both ends merged through short pieces: too short after all.
            stats.short_pieces += 1;
        } else {
            edges.push(ends);
        }
    }
    // Incidence lists (CSR).
    let nodes = node_pos.len();
    let mut start = vec![0u32; nodes + 1];
    for e in &edges {
        start[e[0] as usize + 1] += 1;
        start[e[1] as usize + 1] += 1;
    }
    for i in 0..nodes {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut incident = vec![0u32; 2 * edges.len()];
    for (k, e) in edges.iter().enumerate() {
        for &v in e {
            incident[fill[v as usize] as usize] = k as u32;
            fill[v as usize] += 1;
        }
    }
    let degree = |v: usize| start[v + 1] - start[v];
    let mut used = vec![false; edges.len()];
    let mut left = vec![0u32; nodes];
    for (v, l) in left.iter_mut().enumerate() {
        *l = degree(v);
    }
    let mut lines = Vec::new();
    let starts = (0..nodes)
        .filter(|&v| degree(v) % 2 == 1)
        .chain(0..nodes)
        .collect::<Vec<_>>();
    for v0 in starts {
        while left[v0] > 0 {
            let mut path = vec![v0 as u32];
            let mut v = v0;
            let mut heading: Option<DVec2> = None;
            loop {
                // The unused piece that turns least.
                let mut best: Option<(u32, f64)> = None;
                for &e in &incident[start[v] as usize..start[v + 1] as usize] {
                    if used[e as usize] {
                        continue;
                    }
                    let [a, b] = edges[e as usize];
                    let w = if a as usize == v { b } else { a };
                    let dir = (node_pos[w as usize] - node_pos[v]).normalize_or_zero();
                    let score = heading.map_or(0.0, |h| -h.dot(dir));
                    if best.is_none_or(|(_, s)| score < s) {
                        best = Some((e, score));
                    }
                }
                let Some((e, _)) = best else { break };
                used[e as usize] = true;
                let [a, b] = edges[e as usize];
                let w = if a as usize == v { b } else { a } as usize;
                left[v] -= 1;
                left[w] -= 1;
                heading = Some((node_pos[w] - node_pos[v]).normalize_or_zero());
                path.push(w as u32);
                v = w;
            }
            let pts: Vec<DVec2> = path.iter().map(|&v| node_pos[v as usize]).collect();
            lines.push(Polyline {
                points: straighten(&pts, tol / 10.0),
            });
        }
    }
    lines
}

/// Leaves out points where the line goes on straight: a point is left out when it and
/// every point left out since the last kept one are within `tol` of the chord from the
/// last kept point to the next kept one.
///
/// Each point `p` left out bounds the chord's direction from the last kept point `a` to
/// within `asin(tol / |p - a|)` of `p - a`'s; the bounds are intersected as points are
/// left out, so each point costs O(1).
fn straighten(points: &[DVec2], tol: f64) -> Vec<DVec2> {
    if points.len() <= 2 {
        return points.to_vec();
    }
    let mut out = vec![points[0]];
    let mut a = points[0];
    // Directions are angles from `base` (the first direction after `a`).
    let mut base: Option<DVec2> = None;
    let (mut lo, mut hi, mut reach) = (f64::NEG_INFINITY, f64::INFINITY, 0.0f64);
    let mut pending: Option<DVec2> = None;
    let angle = |base: DVec2, v: DVec2| base.perp_dot(v).atan2(base.dot(v));
    for &q in &points[1..] {
        let mut v = q - a;
        let mut r = v.length();
        if r == 0.0 && pending.is_none() {
            // The same point twice in a row.
            continue;
        }
        // Back at `a` (a line that returns on itself) ends the chord too.
        let mut theta = if r == 0.0 {
            f64::NAN
        } else {
            angle(*base.get_or_insert(v / r), v)
        };
        if let Some(p) = pending
            && !(theta >= lo && theta <= hi && r >= reach)
        {
            // `q` cannot end a chord that keeps the points since `a` within `tol`.
            out.push(p);
            a = p;
            v = q - a;
            r = v.length();
            if r == 0.0 {
                pending = None;
                base = None;
                continue;
            }
            base = Some(v / r);
            theta = 0.0;
            (lo, hi, reach) = (f64::NEG_INFINITY, f64::INFINITY, 0.0);
        }
        let delta = (tol / r).min(1.0).asin();
        lo = lo.max(theta - delta);
        hi = hi.min(theta + delta);
        reach = reach.max(r);
        pending = Some(q);
    }
    if let Some(p) = pending {
        out.push(p);
    }
    out
}

/// A polyline in a tour: its index and whether it is drawn backwards.
#[derive(Clone, Copy, Debug)]
struct Visit {
    line: u32,
    reversed: bool,
}

/// Orders polylines to shorten pen-up travel (step 4 of the module docs).
fn order(lines: Vec<Polyline>) -> Vec<Polyline> {
    let n = lines.len();
    if n < 2 {
        return lines;
    }
    let ends: Vec<[DVec2; 2]> = lines.iter().map(|l| [l.start(), l.end()]).collect();
    let mut tour = nearest_neighbour(&ends);
    two_opt(&mut tour, &ends);
    let at = |v: &Visit, first: bool| ends[v.line as usize][(v.reversed == first) as usize];
    let mut after = 0.0;
    let mut pos = DVec2::ZERO;
    for v in &tour {
        after += pos.distance(at(v, true));
        pos = at(v, false);
    }
    if after >= travel(&lines) {
        return lines;
    }
    let mut slots: Vec<Option<Polyline>> = lines.into_iter().map(Some).collect();
    tour.iter()
        .map(|v| {
            let mut l = slots[v.line as usize].take().expect("each line once");
            if v.reversed {
                l.points.reverse();
            }
            l
        })
        .collect()
}

/// A grid of the polylines' ends for nearest-neighbour queries.
struct EndGrid {
    lo: DVec2,
    cell: f64,
    nx: i64,
    ny: i64,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl EndGrid {
    /// A grid of the ends (`2 * line + end`) of the lines not yet `taken`.
    fn new(ends: &[[DVec2; 2]], taken: &[bool]) -> Self {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        let mut count = 0usize;
        for (k, e) in ends.iter().enumerate() {
            if !taken[k] {
                for p in e {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
                count += 2;
            }
        }
        let size = (hi - lo).max(DVec2::splat(1e-9));
        // About two ends a cell, at most 2^22 cells.
        let cells = (count as f64 / 2.0).clamp(1.0, (1u64 << 22) as f64);
        let cell = (size.x * size.y / cells)
            .sqrt()
            .max(size.max_element() / 4096.0);
        let nx = (size.x / cell).floor() as i64 + 1;
        let ny = (size.y / cell).floor() as i64 + 1;
        let mut grid = EndGrid {
            lo,
            cell,
            nx,
            ny,
            start: vec![0; (nx * ny) as usize + 1],
            items: vec![0; count],
        };
        for (k, e) in ends.iter().enumerate() {
            if !taken[k] {
                for p in e {
                    let c = grid.cell_index(*p);
                    grid.start[c + 1] += 1;
                }
            }
        }
        for i in 0..(nx * ny) as usize {
            grid.start[i + 1] += grid.start[i];
        }
        let mut fill = grid.start.clone();
        for (k, e) in ends.iter().enumerate() {
            if !taken[k] {
                for (j, p) in e.iter().enumerate() {
                    let c = grid.cell_index(*p);
                    grid.items[fill[c] as usize] = (2 * k + j) as u32;
                    fill[c] += 1;
                }
            }
        }
        grid
    }

    fn cell_xy(&self, p: DVec2) -> (i64, i64) {
        let c = ((p - self.lo) / self.cell).floor();
        (
            (c.x as i64).clamp(0, self.nx - 1),
            (c.y as i64).clamp(0, self.ny - 1),
        )
    }

    fn cell_index(&self, p: DVec2) -> usize {
        let (x, y) = self.cell_xy(p);
        (y * self.nx + x) as usize
    }

    /// The nearest end of a line not yet taken.
    fn nearest(&self, p: DVec2, ends: &[[DVec2; 2]], taken: &[bool]) -> Option<u32> {
        let (cx, cy) = self.cell_xy(p);
        // Distance from p to the edge of its own cell (p may lie outside the grid).
        let mut best: Option<(u32, f64)> = None;
        let max_ring = self.nx.max(self.ny);
        for r in 0..=max_ring {
            let (x0, x1, y0, y1) = (cx - r, cx + r, cy - r, cy + r);
            for y in y0.max(0)..=y1.min(self.ny - 1) {
                let on_edge_row = y == y0 || y == y1;
                let mut x = x0.max(0);
                while x <= x1.min(self.nx - 1) {
                    let c = (y * self.nx + x) as usize;
                    for &item in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                        let line = (item / 2) as usize;
                        if taken[line] {
                            continue;
                        }
                        let d = ends[line][(item % 2) as usize].distance_squared(p);
                        if best.is_none_or(|(_, bd)| d < bd) {
                            best = Some((item, d));
                        }
                    }
                    // Inner rows: only the ring's two columns.
                    x = if on_edge_row || x == x1 { x + 1 } else { x1 };
                }
            }
            if let Some((_, d)) = best {
                // Everything beyond ring r is at least r cells away from p's cell
                // (p itself may lie outside the grid, which only makes it farther).
                if d.sqrt() <= r as f64 * self.cell {
                    break;
                }
            }
        }
        best.map(|(item, _)| item)
    }
}

/// Greedy nearest neighbour from (0, 0).
fn nearest_neighbour(ends: &[[DVec2; 2]]) -> Vec<Visit> {
    let n = ends.len();
    let mut taken = vec![false; n];
    let mut grid = EndGrid::new(ends, &taken);
    let mut built_for = n;
    let mut tour = Vec::with_capacity(n);
    let mut pos = DVec2::ZERO;
    for done in 0..n {
        let remaining = n - done;
        if remaining * 4 < built_for && remaining > 64 {
            grid = EndGrid::new(ends, &taken);
            built_for = remaining;
        }
        let item = grid
            .nearest(pos, ends, &taken)
            .expect("a line is left while the tour is short");
        let line = item / 2;
        let reversed = item % 2 == 1;
        taken[line as usize] = true;
        pos = ends[line as usize][(!reversed) as usize];
        tour.push(Visit { line, reversed });
    }
    tour
}

/// 2-opt moves over a window: reversing visits `i + 1..=j` (and each of them) when
/// that shortens the travel.
fn two_opt(tour: &mut [Visit], ends: &[[DVec2; 2]]) {
    let n = tour.len();
    let first = |v: &Visit| ends[v.line as usize][v.reversed as usize];
    let last = |v: &Visit| ends[v.line as usize][(!v.reversed) as usize];
    for _pass in 0..8 {
        let mut improved = false;
        // i = the visit before the run (None: the pen's home).
        for i in 0..n {
            let before = if i == 0 {
                DVec2::ZERO
            } else {
                last(&tour[i - 1])
            };
            let a = i; // first visit of the run
            for j in a..(a + TWO_OPT_WINDOW).min(n) {
                let run_first = first(&tour[a]);
                let run_last = last(&tour[j]);
                let old = before.distance(run_first)
                    + if j + 1 < n {
                        run_last.distance(first(&tour[j + 1]))
                    } else {
                        0.0
                    };
                // Reversed, the run starts at its last visit's end and ends at its
                // first visit's start.
                let new = before.distance(run_last)
                    + if j + 1 < n {
                        run_first.distance(first(&tour[j + 1]))
                    } else {
                        0.0
                    };
                if new + 1e-9 < old {
                    tour[a..=j].reverse();
                    for v in &mut tour[a..=j] {
                        v.reversed = !v.reversed;
                    }
                    improved = true;
                }
            }
        }
        if !improved {
            break;
        }
    }
}

#[cfg(test)]
mod tests;
