//! Exact piecewise-linear horizons: an upper envelope kept as a sorted array of line
//! spans, the crossing of two segments (seed 004's formula), the parts of a segment
//! above an envelope, and the linear merge of two envelopes.
//!
//! Everything here works in "up" coordinates `(x, v)`: `x` is the pixel column, `v`
//! grows upward (minus the pixel row). An upper horizon is the envelope of the maximum
//! of `v`; the lower horizon is kept as the upper envelope of `-v`, so one merge and
//! one query serve both.

use glam::DVec2;

/// A straight piece of an envelope over `x0 < x1` (`v` from `y0` to `y1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// Left end, `x`.
    pub x0: f64,
    /// Left end, `v`.
    pub y0: f64,
    /// Right end, `x` (greater than `x0`).
    pub x1: f64,
    /// Right end, `v`.
    pub y1: f64,
}

impl Span {
    /// Its value at `x` (clamped to its ends: exact at both ends).
    #[inline]
    #[must_use]
    pub fn at(&self, x: f64) -> f64 {
        if x <= self.x0 {
            self.y0
        } else if x >= self.x1 {
            self.y1
        } else {
            self.y0 + (self.y1 - self.y0) * ((x - self.x0) / (self.x1 - self.x0))
        }
    }
}

/// The crossing of two segments by seed 004's formula (floating horizon, "the points of
/// intersection of the segments that interpolate the current and previous curves"):
/// segment 1 of the current curve from `a` to `b`, segment 2 of the previous horizon
/// from `c` to `d`, with `Δx_j`, `Δy_j` their rises:
///
/// ```text
/// x_i = (Δx2 (x_n1 Δy1 - y_n1 Δx1) - Δx1 (x_n2 Δy2 - y_n2 Δx2)) / (Δy1 Δx2 - Δy2 Δx1)
/// y_i = y_n1 + Δy1 (x_i - x_n1) / Δx1
/// ```
///
/// The seed prints `+` inside both brackets (`y_n1 Δx1 + x_n1 Δy1`); that point lies on
/// neither line in general (for `a = (0,0)`, `b = (4,4)`, `c = (0,3)`, `d = (4,1)` it
/// gives `x = -2` where the lines cross at `(2, 2)`). Eliminating `y` from the two line
/// equations `Δy_j x - Δx_j y = Δy_j x_nj - Δx_j y_nj` gives the signs above.
///
/// Returns `None` for parallel lines or a vertical current segment (`Δx1 = 0`), which
/// the floating horizon never asks about. The point is that of the two lines; it may lie
/// outside the segments.
#[must_use]
pub fn crossing(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Option<DVec2> {
    let (dx1, dy1) = (b.x - a.x, b.y - a.y);
    let (dx2, dy2) = (d.x - c.x, d.y - c.y);
    let den = dy1 * dx2 - dy2 * dx1;
    if den == 0.0 || dx1 == 0.0 || !den.is_finite() {
        return None;
    }
    let xi = (dx2 * (a.x * dy1 - a.y * dx1) - dx1 * (c.x * dy2 - c.y * dx2)) / den;
    let yi = a.y + dy1 * (xi - a.x) / dx1;
    Some(DVec2::new(xi, yi))
}

/// The seed's formula over one common interval, as the horizon uses it: both segments
/// span the same `x` interval from `x_n` to `x_n + Δx` (`x_n1 = x_n2`, `Δx1 = Δx2`),
/// the current one rising `dy1` from `y1`, the previous one `dy2` from `y2`.
/// Substituting into [`crossing`] leaves `x_i = x_n + Δx (y_n2 - y_n1) / (Δy1 - Δy2)`;
/// this returns the fraction `λ = (x_i - x_n) / Δx = (y2 - y1) / (dy1 - dy2)` of the
/// interval, clamped to `[0, 1]` (rounding may put it a hair outside when the segments
/// cross at an end), so the crossing never leaves the interval however short or steep
/// it is. `None` for parallel segments.
#[inline]
#[must_use]
pub fn crossing_fraction(y1: f64, dy1: f64, y2: f64, dy2: f64) -> Option<f64> {
    let den = dy1 - dy2;
    if den == 0.0 {
        return None;
    }
    let l = (y2 - y1) / den;
    if l.is_nan() {
        return None;
    }
    Some(l.clamp(0.0, 1.0))
}

/// Appends `[a, b]` to sorted, disjoint intervals, joining it to the last one when they
/// touch. Empty intervals are dropped.
#[inline]
fn push_interval(out: &mut Vec<[f64; 2]>, a: f64, b: f64) {
    if !(b > a) {
        return;
    }
    if let Some(last) = out.last_mut()
        && last[1] >= a
    {
        last[1] = last[1].max(b);
        return;
    }
    out.push([a, b]);
}

/// How far above the horizon (in pixels) a point must lie to be visible: `1e-9`. Curves
/// that coincide on the screen (a plane seen edge on, a curve starting on the one before)
/// differ there only by rounding, some `1e-13` pixels, which must not make them visible.
pub const ABOVE_TOLERANCE: f64 = 1e-9;

/// The parameter intervals (of `s` in `[0, 1]` along the segment from `p` to `q`, up
/// coordinates) where the segment lies above the envelope `env` by more than
/// [`ABOVE_TOLERANCE`], or where `env` is not defined, appended to `out` in increasing
/// `s`.
///
/// A segment with `p.x == q.x` is tested at that one column against the larger of the
/// envelope's values there (a jump counts at its top).
pub fn above(env: &[Span], p: DVec2, q: DVec2, out: &mut Vec<[f64; 2]>) {
    let mut hint = 0;
    above_from(env, p, q, out, &mut hint);
}

/// [`above`], starting the search for the first span the segment meets at `*hint` (the
/// span where the previous segment of a curve ended), and leaving there the span where
/// this one ends: consecutive segments of a curve drawn left to right then cost no
/// search. A wrong hint costs a binary search. Returns whether some part of the segment
/// lies where the envelope is not defined.
pub fn above_from(
    env: &[Span],
    p: DVec2,
    q: DVec2,
    out: &mut Vec<[f64; 2]>,
    hint: &mut usize,
) -> bool {
    // Lowering the segment by the tolerance tests "above by more than the tolerance".
    let (p, q) = (
        DVec2::new(p.x, p.y - ABOVE_TOLERANCE),
        DVec2::new(q.x, q.y - ABOVE_TOLERANCE),
    );
    if p.x == q.x {
        let Some(top) = value_max(env, p.x) else {
            out.push([0.0, 1.0]);
            return true;
        };
        let (d0, d1) = (p.y - top, q.y - top);
        if d0 > 0.0 && d1 > 0.0 {
            out.push([0.0, 1.0]);
        } else if d0 > 0.0 {
            push_interval(out, 0.0, d0 / (d0 - d1));
        } else if d1 > 0.0 {
            push_interval(out, d0 / (d0 - d1), 1.0);
        }
        return false;
    }
    // Walk the segment left to right; `s` of an x follows the segment's direction.
    let flip = p.x > q.x;
    let (l, r) = if flip { (q, p) } else { (p, q) };
    let seg = Span {
        x0: l.x,
        y0: l.y,
        x1: r.x,
        y1: r.y,
    };
    let width = seg.x1 - seg.x0;
    let frac = |x: f64| ((x - seg.x0) / width).clamp(0.0, 1.0);
    let start = out.len();
    // `u` in [0, 1] runs left to right; converted to `s` at the end.
    let mut k = first_span(env, seg.x0, *hint);
    let mut x = seg.x0;
    let mut outside = false;
    while x < seg.x1 {
        if k < env.len() && env[k].x0 <= x {
            let e = env[k];
            let xq = e.x1.min(seg.x1);
            let (ys0, ye0) = (seg.at(x), e.at(x));
            let (ys1, ye1) = (seg.at(xq), e.at(xq));
            let (d0, d1) = (ys0 - ye0, ys1 - ye1);
            let (u0, u1) = (frac(x), frac(xq));
            if d0 > 0.0 && d1 > 0.0 {
                push_interval(out, u0, u1);
            } else if d0 > 0.0 || d1 > 0.0 {
                let lam = crossing_fraction(ys0, ys1 - ys0, ye0, ye1 - ye0).unwrap_or(0.5);
                let uc = u0 + (u1 - u0) * lam;
                if d0 > 0.0 {
                    push_interval(out, u0, uc);
                } else {
                    push_interval(out, uc, u1);
                }
            }
            x = xq;
            if e.x1 <= xq {
                k += 1;
            }
        } else {
            // No horizon here (before, between or after its spans): visible.
            let xq = if k < env.len() {
                env[k].x0.min(seg.x1)
            } else {
                seg.x1
            };
            push_interval(out, frac(x), frac(xq));
            outside = true;
            x = xq;
        }
    }
    *hint = k.min(env.len());
    if flip {
        out[start..].reverse();
        for iv in &mut out[start..] {
            *iv = [1.0 - iv[1], 1.0 - iv[0]];
        }
    }
    outside
}

/// The first span of `env` that ends after `x` (`env.len()` if none), looked for from
/// `hint` forward a few spans, then by binary search.
#[inline]
fn first_span(env: &[Span], x: f64, hint: usize) -> usize {
    let ok_before = |k: usize| k == 0 || env[k - 1].x1 <= x;
    if hint <= env.len() && ok_before(hint) {
        for k in hint..(hint + 8).min(env.len() + 1) {
            if k == env.len() || env[k].x1 > x {
                return k;
            }
        }
    }
    env.partition_point(|e| e.x1 <= x)
}

/// The envelope's largest value at `x` (at a jump, the top of it), or `None` where it
/// is not defined.
#[must_use]
pub fn value_max(env: &[Span], x: f64) -> Option<f64> {
    let mut k = env.partition_point(|e| e.x1 < x);
    let mut best: Option<f64> = None;
    while k < env.len() && env[k].x0 <= x {
        let v = env[k].at(x);
        best = Some(best.map_or(v, |b: f64| b.max(v)));
        k += 1;
    }
    best
}

/// Builds envelopes span by span, joining a span to the previous one when both are
/// pieces of the same source span (so that merging does not multiply vertices).
struct Builder<'a> {
    out: &'a mut Vec<Span>,
    last_source: Option<(u8, usize)>,
}

impl Builder<'_> {
    #[inline]
    fn emit(&mut self, source: (u8, usize), x0: f64, y0: f64, x1: f64, y1: f64) {
        if !(x1 > x0) {
            return;
        }
        if self.last_source == Some(source)
            && let Some(last) = self.out.last_mut()
            && last.x1 == x0
        {
            last.x1 = x1;
            last.y1 = y1;
            return;
        }
        self.out.push(Span { x0, y0, x1, y1 });
        self.last_source = Some(source);
    }
}

/// A span being swept: its value at the sweep's position is carried from step to step
/// and advanced with its slope, computed once.
#[derive(Clone, Copy)]
struct Cursor {
    span: Span,
    slope: f64,
}

impl Cursor {
    #[inline(always)]
    fn new(span: Span) -> Self {
        Cursor {
            span,
            slope: (span.y1 - span.y0) / (span.x1 - span.x0),
        }
    }

    /// The value at `x` in `[x0, x1]`; exact at the right end.
    #[inline(always)]
    fn at(&self, x: f64) -> f64 {
        if x >= self.span.x1 {
            self.span.y1
        } else {
            self.span.y0 + self.slope * (x - self.span.x0)
        }
    }
}

/// The upper envelope of two envelopes (`max` where both are defined, either one where
/// only it is), written to `out` (cleared first): one left-to-right sweep over the
/// breakpoints of both, `O(|a| + |b|)`. Where they cross, the crossing comes from
/// [`crossing_fraction`], and both sides of it take the same point.
pub fn merge(a: &[Span], b: &[Span], out: &mut Vec<Span>) {
    out.clear();
    out.reserve(a.len() + b.len());
    let mut bld = Builder {
        out,
        last_source: None,
    };
    let (mut i, mut j) = (0usize, 0usize);
    let mut x = match (a.first(), b.first()) {
        (Some(p), Some(q)) => p.x0.min(q.x0),
        (Some(p), None) => p.x0,
        (None, Some(q)) => q.x0,
        (None, None) => return,
    };
    // The active spans' cursors and values at x (valid when active).
    let mut ca = a.first().map(|s| Cursor::new(*s));
    let mut cb = b.first().map(|s| Cursor::new(*s));
    let (mut ya, mut yb) = (
        a.first().map_or(0.0, |s| s.y0),
        b.first().map_or(0.0, |s| s.y0),
    );
    while i < a.len() || j < b.len() {
        let a_on = i < a.len() && a[i].x0 <= x;
        let b_on = j < b.len() && b[j].x0 <= x;
        let na = if i < a.len() {
            if a_on { a[i].x1 } else { a[i].x0 }
        } else {
            f64::INFINITY
        };
        let nb = if j < b.len() {
            if b_on { b[j].x1 } else { b[j].x0 }
        } else {
            f64::INFINITY
        };
        let q = na.min(nb);
        match (a_on, b_on) {
            (false, false) => {}
            (true, false) => {
                let c = ca.as_ref().unwrap_or_else(|| unreachable!());
                let y1 = c.at(q);
                bld.emit((0, i), x, ya, q, y1);
                ya = y1;
            }
            (false, true) => {
                let c = cb.as_ref().unwrap_or_else(|| unreachable!());
                let y1 = c.at(q);
                bld.emit((1, j), x, yb, q, y1);
                yb = y1;
            }
            (true, true) => {
                let (pa, pb) = (
                    ca.as_ref().unwrap_or_else(|| unreachable!()),
                    cb.as_ref().unwrap_or_else(|| unreachable!()),
                );
                let (ya1, yb1) = (pa.at(q), pb.at(q));
                let (d0, d1) = (ya - yb, ya1 - yb1);
                if d0 >= 0.0 && d1 >= 0.0 {
                    bld.emit((0, i), x, ya, q, ya1);
                } else if d0 <= 0.0 && d1 <= 0.0 {
                    bld.emit((1, j), x, yb, q, yb1);
                } else {
                    let lam = crossing_fraction(ya, ya1 - ya, yb, yb1 - yb).unwrap_or(0.5);
                    let xc = (x + (q - x) * lam).clamp(x, q);
                    let yc = ya + (ya1 - ya) * lam;
                    if d0 > 0.0 {
                        bld.emit((0, i), x, ya, xc, yc);
                        bld.emit((1, j), xc, yc, q, yb1);
                    } else {
                        bld.emit((1, j), x, yb, xc, yc);
                        bld.emit((0, i), xc, yc, q, ya1);
                    }
                }
                ya = ya1;
                yb = yb1;
            }
        }
        if a_on && a[i].x1 <= q {
            i += 1;
            if let Some(s) = a.get(i) {
                ca = Some(Cursor::new(*s));
                ya = s.y0;
            }
        }
        if b_on && b[j].x1 <= q {
            j += 1;
            if let Some(s) = b.get(j) {
                cb = Some(Cursor::new(*s));
                yb = s.y0;
            }
        }
        // A span that starts at q (after a gap) starts at its own left value.
        if !a_on && i < a.len() && a[i].x0 <= q {
            ya = a[i].y0;
        }
        if !b_on && j < b.len() && b[j].x0 <= q {
            yb = b[j].y0;
        }
        x = q;
    }
}

/// Merges the envelope `b` into `env` in place ([`merge`] restricted to the spans of
/// `env` that `b`'s range reaches; the others are kept as they are), using `tmp`.
pub fn merge_into(env: &mut Vec<Span>, b: &[Span], tmp: &mut Vec<Span>) {
    let (Some(first), Some(last)) = (b.first(), b.last()) else {
        return;
    };
    let lo = env.partition_point(|e| e.x1 <= first.x0);
    let hi = lo + env[lo..].partition_point(|e| e.x0 < last.x1);
    merge(&env[lo..hi], b, tmp);
    env.splice(lo..hi, tmp.drain(..));
}

/// The upper envelope of any spans (not sorted, possibly overlapping), into `out`:
/// sorted by left end (kept as given when already sorted, as a monotone curve's spans
/// are), cut into runs of spans that do not overlap (each run is an envelope already),
/// and the runs merged pairwise. `O(m)` for a monotone curve, `O(m log m)` at worst.
/// `scratch` holds the intermediate envelopes.
pub fn envelope_of(spans: &mut [Span], out: &mut Vec<Span>, scratch: &mut Vec<Vec<Span>>) {
    out.clear();
    if spans.is_empty() {
        return;
    }
    if !spans.windows(2).all(|w| w[0].x0 <= w[1].x0) {
        spans.sort_unstable_by(|p, q| p.x0.total_cmp(&q.x0));
    }
    // Runs of non-overlapping spans.
    let mut runs: Vec<Vec<Span>> = Vec::new();
    let mut run_start = 0;
    for k in 1..=spans.len() {
        if k == spans.len() || spans[k].x0 < spans[k - 1].x1 {
            if run_start == 0 && k == spans.len() {
                out.extend_from_slice(spans);
                return;
            }
            let mut v = scratch.pop().unwrap_or_default();
            v.clear();
            v.extend_from_slice(&spans[run_start..k]);
            runs.push(v);
            run_start = k;
        }
    }
    while runs.len() > 1 {
        let mut next = Vec::with_capacity(runs.len().div_ceil(2));
        let mut it = runs.into_iter();
        while let Some(p) = it.next() {
            match it.next() {
                Some(q) => {
                    let mut m = scratch.pop().unwrap_or_default();
                    merge(&p, &q, &mut m);
                    scratch.push(p);
                    scratch.push(q);
                    next.push(m);
                }
                None => next.push(p),
            }
        }
        runs = next;
    }
    let last = runs.pop().unwrap_or_default();
    out.extend_from_slice(&last);
    scratch.push(last);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(x0: f64, y0: f64, x1: f64, y1: f64) -> Span {
        Span { x0, y0, x1, y1 }
    }

    /// The brute-force maximum of spans at `x` (None where no span is defined).
    fn brute(spans: &[Span], x: f64) -> Option<f64> {
        spans
            .iter()
            .filter(|s| s.x0 <= x && x <= s.x1)
            .map(|s| s.at(x))
            .fold(None, |m, v| Some(m.map_or(v, |m: f64| m.max(v))))
    }

    #[test]
    fn crossing_of_the_worked_numbers() {
        let p = crossing(
            DVec2::new(0., 0.),
            DVec2::new(4., 4.),
            DVec2::new(0., 3.),
            DVec2::new(4., 1.),
        )
        .unwrap();
        assert!((p - DVec2::new(2., 2.)).length() < 1e-12, "{p}");
        assert_eq!(crossing_fraction(0., 4., 3., -2.), Some(0.5));
        assert_eq!(crossing_fraction(0., 1., 3., 1.), None);
    }

    #[test]
    fn merge_takes_the_maximum_and_keeps_crossings() {
        let a = [span(0., 0., 4., 4.)];
        let b = [span(0., 3., 4., 1.), span(5., 0., 6., 0.)];
        let mut m = Vec::new();
        merge(&a, &b, &mut m);
        assert_eq!(m.len(), 3, "{m:?}");
        assert_eq!(m[0], span(0., 3., 2., 2.));
        assert_eq!(m[1], span(2., 2., 4., 4.));
        assert_eq!(m[2], span(5., 0., 6., 0.));
        for k in 0..=60 {
            let x = f64::from(k) * 0.1;
            assert_eq!(
                brute(&m, x).map(|v| (v * 1e9).round()),
                brute(&[a[0], b[0], b[1]], x).map(|v| (v * 1e9).round()),
                "x = {x}"
            );
        }
    }

    #[test]
    fn merge_does_not_split_a_winning_span_at_the_other_breakpoints() {
        let a = [span(0., 10., 10., 10.)];
        let b: Vec<Span> = (0..10)
            .map(|k| span(f64::from(k), 0., f64::from(k + 1), 1.))
            .collect();
        let mut m = Vec::new();
        merge(&a, &b, &mut m);
        assert_eq!(m, vec![a[0]]);
    }

    #[test]
    fn above_finds_the_parts_over_the_horizon() {
        let env = [span(0., 3., 2., 2.), span(2., 2., 4., 4.)];
        let mut out = Vec::new();
        // Flat segment at v = 2.5 from x = -1 to 5: visible before x = 0 (no horizon),
        // where the horizon dips under it (x in (1, 2.5)), and after x = 4.
        above(&env, DVec2::new(-1., 2.5), DVec2::new(5., 2.5), &mut out);
        let w = 6.0;
        let expect = [[0.0, 1.0 / w], [2.0 / w, 3.5 / w], [5.0 / w, 1.0]];
        assert_eq!(out.len(), 3, "{out:?}");
        for (o, e) in out.iter().zip(expect) {
            assert!((o[0] - e[0]).abs() < 1e-8 && (o[1] - e[1]).abs() < 1e-8);
        }
        // The same segment drawn right to left: the same parts in its own parameter.
        let mut back = Vec::new();
        above(&env, DVec2::new(5., 2.5), DVec2::new(-1., 2.5), &mut back);
        for (o, e) in back.iter().rev().zip(&out) {
            assert!((o[0] - (1.0 - e[1])).abs() < 1e-8);
        }
        // A vertical segment at x = 2 from v = 0 to 4: visible above v = 2.
        let mut v = Vec::new();
        above(&env, DVec2::new(2., 0.), DVec2::new(2., 4.), &mut v);
        assert_eq!(v.len(), 1);
        assert!((v[0][0] - 0.5).abs() < 1e-8 && v[0][1] == 1.0, "{v:?}");
    }

    #[test]
    fn merging_in_place_equals_merging_whole() {
        let mut rng = crate::rng::SplitMix64(11);
        let mut random_env = |n: usize, from: f64, to: f64| {
            let mut xs: Vec<f64> = (0..2 * n).map(|_| rng.range(from, to)).collect();
            xs.sort_by(f64::total_cmp);
            xs.chunks(2)
                .filter(|c| c[0] < c[1])
                .map(|c| span(c[0], rng.range(0.0, 5.0), c[1], rng.range(0.0, 5.0)))
                .collect::<Vec<_>>()
        };
        for _ in 0..200 {
            let env = random_env(20, 0.0, 100.0);
            let b = random_env(6, 30.0, 60.0);
            let (mut whole, mut tmp) = (Vec::new(), Vec::new());
            merge(&env, &b, &mut whole);
            let mut part = env.clone();
            merge_into(&mut part, &b, &mut tmp);
            for k in 0..=1000 {
                let x = f64::from(k) * 0.1;
                let (p, w) = (value_max(&part, x), value_max(&whole, x));
                assert_eq!(p.is_some(), w.is_some(), "x {x}");
                if let (Some(p), Some(w)) = (p, w) {
                    assert!((p - w).abs() < 1e-9, "x {x}: {p} vs {w}");
                }
            }
        }
    }

    #[test]
    fn envelope_of_overlapping_spans_equals_brute_force() {
        let mut rng = crate::rng::SplitMix64(7);
        for _ in 0..50 {
            let mut spans: Vec<Span> = (0..12)
                .map(|_| {
                    let x0 = rng.next_f64() * 10.0;
                    span(
                        x0,
                        rng.next_f64() * 5.0,
                        x0 + 0.1 + rng.next_f64() * 4.0,
                        rng.next_f64() * 5.0,
                    )
                })
                .collect();
            let all = spans.clone();
            let (mut out, mut scratch) = (Vec::new(), Vec::new());
            envelope_of(&mut spans, &mut out, &mut scratch);
            assert!(
                out.windows(2)
                    .all(|w| w[0].x1 <= w[1].x0 && w[0].x0 < w[0].x1)
            );
            for k in 0..=1500 {
                let x = f64::from(k) * 0.01;
                let (e, b) = (value_max(&out, x), brute(&all, x));
                match (e, b) {
                    (None, None) => {}
                    (Some(e), Some(b)) => assert!((e - b).abs() < 1e-9, "x {x}: {e} {b}"),
                    _ => panic!("x {x}: {e:?} vs {b:?}"),
                }
            }
        }
    }
}
