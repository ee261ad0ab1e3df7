//! Line segment clipping against any convex polygon with `n`-bit region codes.
//!
//! Source: seed 001 §6.1.1 ("Αποκοπή ευθυγράμμων τμημάτων"). The `n` lines of the
//! edges of a convex `n`-gon split the plane into at most `2^n` regions; a point's
//! code `w = b_{n-1} ... b_1 b_0` has `b_i = 0` when it lies in half-plane-0 of line `i`
//! (the window's side, line included) and `1` in the open half-plane-1 (eq. 6.1).
//! Two observations drive the algorithm: the points of code `00...0`, and only they,
//! are inside the window; and bit `i` of two points differs exactly when line `i`
//! separates them. To clip a segment `PQ`:
//!
//! 1. compute the codes `p` and `q` of `P` and `Q`;
//! 2. if `p = q = 0` the segment is inside: done;
//! 3. `r = p XOR q`: each line `i` with `r_i = 1` crosses `PQ` at a point `T_i` other
//!    than `P` and `Q`;
//! 4. compute each `T_i` (the intersection of line `i` with the line of `PQ`);
//! 5. sort the `T_i` together with `P` and `Q` along the segment, cutting `PQ` into
//!    pieces each entirely inside or entirely outside the window;
//! 6. run steps 1-2 on each piece (here: the code of its midpoint) and keep the pieces
//!    of code 0.
//!
//! For the rectangle with the vertex order of figure 6.3 ([`ConvexWindow::rectangle`])
//! the codes are the 4-bit Cohen-Sutherland codes of eq. (6.5).
//!
//! # Deviations from the seed, and why
//! * Lines are in the general form `a x + b y + c = 0`, not the seed's
//!   `a x + b y + 1 = 0`, which cannot represent a line through the origin (see
//!   [`super::window`]).
//! * `T_i` is computed along the segment, `T_i = P + t_i (Q - P)` with
//!   `t_i = L_i(P) / (L_i(P) - L_i(Q))` where `L_i` is line `i`'s equation: that is the
//!   solution of the seed's 2x2 system (6.2)-(6.3), without its division by a
//!   determinant that vanishes for segments through the origin, and the `t_i` are what
//!   step 5 sorts (sorting by one coordinate, as the seed says, fails for a segment
//!   parallel to that axis).
//! * [`clip_segment`] also rejects at once when `p AND q != 0` (both endpoints beyond
//!   the same line, the Cohen-Sutherland shortcut); the seed's steps reach the same
//!   result after splitting. [`clip_segment_traced`] follows the seed's steps exactly.
//! * For a convex window the kept pieces are contiguous (the window meets a line in
//!   one interval), so they are returned merged as one segment; rounding can only make
//!   a kept piece of near-zero length disappear or appear at a window vertex.
//!
//! # Input, output, complexity
//! A [`ConvexWindow`] (either winding; non-convex and degenerate windows are refused
//! when it is built) and a segment; the visible part with endpoints in the same
//! order, or `None`; non-finite input gives `None`. `O(n + k log k + k n)` for `k`
//! crossing lines (each piece's midpoint is coded against all `n` lines); no
//! allocation unless `k > 16`.
//!
//! Paper: Cyrus and Beck, "Generalized two- and three-dimensional clipping", Computers
//! & Graphics 3(1), 1978 (clipping a segment by any convex region).

use super::InRange;
use std::fmt;

use glam::DVec2;

use super::ConvexWindow;

/// An `n`-bit region code `b_{n-1} ... b_0` (any `n`): bit `i` is 1 when the point is
/// in the open half-plane-1 of edge line `i`. Displayed as the seed writes it, most
/// significant bit first.
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct RegionCode {
    words: Vec<u64>,
    bits: usize,
}

impl RegionCode {
    fn zero(bits: usize) -> Self {
        RegionCode {
            words: vec![0; bits.div_ceil(64)],
            bits,
        }
    }

    fn set(&mut self, i: usize) {
        self.words[i / 64] |= 1 << (i % 64);
    }

    /// The number of bits (the window's edge count).
    #[must_use]
    pub fn bit_count(&self) -> usize {
        self.bits
    }

    /// Bit `i` (`b_i`).
    ///
    /// # Panics
    /// If `i >= bit_count()`.
    #[must_use]
    pub fn bit(&self, i: usize) -> bool {
        assert!(i < self.bits, "bit {i} of a {}-bit code", self.bits);
        self.words[i / 64] >> (i % 64) & 1 == 1
    }

    /// Whether the code is `00...0`: the point is inside the window.
    #[must_use]
    pub fn is_zero(&self) -> bool {
        self.words.iter().all(|&w| w == 0)
    }

    /// `self XOR other`: the lines that separate the two points.
    #[must_use]
    pub fn xor(&self, other: &RegionCode) -> RegionCode {
        self.combine(other, |a, b| a ^ b)
    }

    /// `self AND other`: the lines both points are beyond.
    #[must_use]
    pub fn and(&self, other: &RegionCode) -> RegionCode {
        self.combine(other, |a, b| a & b)
    }

    fn combine(&self, other: &RegionCode, f: impl Fn(u64, u64) -> u64) -> RegionCode {
        let bits = self.bits.max(other.bits);
        let word = |c: &RegionCode, k: usize| c.words.get(k).copied().unwrap_or(0);
        RegionCode {
            words: (0..bits.div_ceil(64))
                .map(|k| f(word(self, k), word(other, k)))
                .collect(),
            bits,
        }
    }

    /// The indices of the bits set, in increasing order.
    pub fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.bits).filter(|&i| self.bit(i))
    }

    /// The low 64 bits as an integer (the whole code when `n <= 64`).
    #[must_use]
    pub fn low_bits(&self) -> u64 {
        self.words.first().copied().unwrap_or(0)
    }
}

impl fmt::Display for RegionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for i in (0..self.bits).rev() {
            f.write_str(if self.bit(i) { "1" } else { "0" })?;
        }
        Ok(())
    }
}

impl fmt::Debug for RegionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "RegionCode({self})")
    }
}

/// The region code of `p` (eq. 6.1). A NaN coordinate sets every bit.
#[must_use]
pub fn region_code(window: &ConvexWindow, p: DVec2) -> RegionCode {
    let mut code = RegionCode::zero(window.edge_count());
    for i in 0..window.edge_count() {
        // `!(>= 0)` also sends NaN to half-plane-1.
        if !(window.edge_value(i, p) >= 0.0) {
            code.set(i);
        }
    }
    code
}

/// Where line `i` crosses the segment (step 4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// The line (edge) index `i`.
    pub line: usize,
    /// The parameter along `PQ`: `T_i = P + t (Q - P)`, `0 <= t <= 1`.
    pub t: f64,
    /// The point `T_i`.
    pub point: DVec2,
}

/// One piece of the segment between consecutive sorted points (step 5) and the
/// decision of step 6.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Start point.
    pub from: DVec2,
    /// End point.
    pub to: DVec2,
    /// Parameters of the start and end along `PQ`.
    pub t: (f64, f64),
    /// The code of the piece (of its midpoint).
    pub code: RegionCode,
    /// Whether it is kept (code 0).
    pub kept: bool,
}

/// Every intermediate value of the seed's six steps, for teaching and for tests.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// Step 1: the code `p` of `P`.
    pub p_code: RegionCode,
    /// Step 1: the code `q` of `Q`.
    pub q_code: RegionCode,
    /// Step 2: `p = q = 0`, the segment was accepted as it is.
    pub accepted_whole: bool,
    /// Step 3: `r = p XOR q`.
    pub xor: RegionCode,
    /// `p AND q` (not a step of the seed: non-zero means Cohen-Sutherland would have
    /// rejected at once).
    pub and: RegionCode,
    /// Step 4: the crossings `T_i`, sorted along `PQ` (step 5).
    pub crossings: Vec<Crossing>,
    /// Steps 5-6: the pieces and which were kept.
    pub pieces: Vec<Piece>,
    /// The result (the kept pieces, merged).
    pub result: Option<(DVec2, DVec2)>,
}

/// `t` of the crossing of line `i`, from the values of its equation at `P` and `Q`
/// (of opposite codes, so of opposite signs or one zero); clamped to `[0, 1]` in case
/// rounding disagrees with the codes.
#[inline]
fn crossing_t(lp: f64, lq: f64) -> f64 {
    let t = lp / (lp - lq);
    if t >= 0.0 {
        t.min(1.0)
    } else {
        0.0 // negative, or NaN from 0/0 (both values zero after rounding)
    }
}

#[inline]
fn point_at(p: DVec2, q: DVec2, t: f64) -> DVec2 {
    if t == 0.0 {
        p
    } else if t == 1.0 {
        q
    } else {
        p + (q - p) * t
    }
}

/// Region-code clipping of segment `p q` against a convex window (steps 1-6, with the
/// trivial reject shortcut). `None` when nothing is inside.
///
/// ```
/// use obscura::clip::{ConvexWindow, region_codes::clip_segment};
/// use glam::DVec2;
/// // A triangle with a vertex at the origin (the seed's line form could not describe it).
/// let tri = ConvexWindow::new(&[DVec2::ZERO, DVec2::new(4., 0.), DVec2::new(0., 4.)]).unwrap();
/// let (a, b) = clip_segment(&tri, DVec2::new(-1., 1.), DVec2::new(5., 1.)).unwrap();
/// assert_eq!((a, b), (DVec2::new(0., 1.), DVec2::new(3., 1.)));
/// ```
#[must_use]
pub fn clip_segment(window: &ConvexWindow, p: DVec2, q: DVec2) -> Option<(DVec2, DVec2)> {
    if !(p.in_range() && q.in_range()) {
        return None;
    }
    let n = window.edge_count();
    let mut inline = [0.0f64; 16];
    let mut spill = Vec::new();
    let mut k = 0;
    for i in 0..n {
        let (lp, lq) = (window.edge_value(i, p), window.edge_value(i, q));
        let (bp, bq) = (lp < 0.0, lq < 0.0);
        if bp && bq {
            return None; // p AND q != 0
        }
        if bp != bq {
            let t = crossing_t(lp, lq);
            if k < inline.len() {
                inline[k] = t;
            } else {
                if k == inline.len() {
                    spill.extend_from_slice(&inline);
                }
                spill.push(t);
            }
            k += 1;
        }
    }
    if k == 0 {
        // No line separates P and Q and neither is beyond any line: both inside.
        return Some((p, q));
    }
    let ts: &mut [f64] = if k <= inline.len() {
        &mut inline[..k]
    } else {
        &mut spill
    };
    ts.sort_unstable_by(f64::total_cmp);
    let mut kept: Option<(f64, f64)> = None;
    let mut start = 0.0;
    for end in ts.iter().copied().chain(std::iter::once(1.0)) {
        let mid = point_at(p, q, 0.5 * (start + end));
        if window.contains(mid) {
            kept = Some(match kept {
                Some((a, _)) => (a, end),
                None => (start, end),
            });
        }
        start = end;
    }
    kept.map(|(t0, t1)| (point_at(p, q, t0), point_at(p, q, t1)))
}

/// The seed's six steps with every intermediate value recorded ([`Trace`]). The
/// result equals [`clip_segment`]'s. Non-finite input gives a trace with all-ones
/// codes and no result.
#[must_use]
pub fn clip_segment_traced(window: &ConvexWindow, p: DVec2, q: DVec2) -> Trace {
    // Step 1.
    let p_code = region_code(window, p);
    let q_code = region_code(window, q);
    let xor = p_code.xor(&q_code);
    let and = p_code.and(&q_code);
    let mut trace = Trace {
        accepted_whole: false,
        p_code,
        q_code,
        xor,
        and,
        crossings: Vec::new(),
        pieces: Vec::new(),
        result: None,
    };
    if !(p.in_range() && q.in_range()) {
        return trace;
    }
    // Step 2.
    if trace.p_code.is_zero() && trace.q_code.is_zero() {
        trace.accepted_whole = true;
        trace.result = Some((p, q));
        return trace;
    }
    // Steps 3-4.
    trace.crossings = trace
        .xor
        .ones()
        .map(|i| {
            let t = crossing_t(window.edge_value(i, p), window.edge_value(i, q));
            Crossing {
                line: i,
                t,
                point: point_at(p, q, t),
            }
        })
        .collect();
    // Step 5.
    trace.crossings.sort_by(|a, b| a.t.total_cmp(&b.t));
    let mut cuts = vec![(0.0, p)];
    cuts.extend(trace.crossings.iter().map(|c| (c.t, c.point)));
    cuts.push((1.0, q));
    // Step 6.
    let mut kept: Option<(DVec2, DVec2)> = None;
    for pair in cuts.windows(2) {
        let ((t0, a), (t1, b)) = (pair[0], pair[1]);
        let code = region_code(window, point_at(p, q, 0.5 * (t0 + t1)));
        let keep = code.is_zero();
        if keep {
            kept = Some(match kept {
                Some((first, _)) => (first, b),
                None => (a, b),
            });
        }
        trace.pieces.push(Piece {
            from: a,
            to: b,
            t: (t0, t1),
            code,
            kept: keep,
        });
    }
    trace.result = kept;
    trace
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_display_most_significant_bit_first() {
        let sq = ConvexWindow::new(&[
            DVec2::new(0., 1.),
            DVec2::new(1., 1.),
            DVec2::new(1., 0.),
            DVec2::new(0., 0.),
        ])
        .unwrap();
        // Above and to the right: lines 0 (y = 1) and 1 (x = 1), "0011".
        let c = region_code(&sq, DVec2::new(2., 2.));
        assert_eq!(c.to_string(), "0011");
        assert_eq!(c.low_bits(), 0b0011);
        assert_eq!(c.ones().collect::<Vec<_>>(), vec![0, 1]);
        assert_eq!(
            region_code(&sq, DVec2::new(f64::NAN, 0.)).to_string(),
            "1111"
        );
    }

    #[test]
    fn codes_wider_than_64_bits() {
        // A 100-gon inscribed in the unit circle; a far point is beyond the lines
        // facing it only, a centre point beyond none.
        let verts: Vec<DVec2> = (0..100)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 100.0;
                DVec2::new(a.cos(), a.sin())
            })
            .collect();
        let w = ConvexWindow::new(&verts).unwrap();
        assert!(region_code(&w, DVec2::ZERO).is_zero());
        let far = region_code(&w, DVec2::new(-3., 0.));
        assert_eq!(far.bit_count(), 100);
        assert!(far.bit(49) && far.bit(50) && !far.bit(0) && !far.bit(99));
        // Entering from the far point: crossings exist beyond bit 64, and more than 16
        // of them (the spill path).
        let trace = clip_segment_traced(&w, DVec2::new(-3., 0.01), DVec2::new(3., -0.02));
        assert!(trace.crossings.len() > 16);
        let fast = clip_segment(&w, DVec2::new(-3., 0.01), DVec2::new(3., -0.02));
        assert_eq!(trace.result, fast);
        let (a, b) = fast.unwrap();
        assert!((a.length() - 1.0).abs() < 1e-3 && (b.length() - 1.0).abs() < 1e-3);
    }
}
