//! One edge against one body: the seed's `h_j = p_j + t q_j + a w_j` and the hidden
//! parameter interval `t_maxmin < t < t_minmax`.
//!
//! A point `Q(a, t) = s + t d + a g` runs along the edge with `t` and towards the eye
//! with `a >= 0` (`g` is the direction to the viewer in the transformed space). It lies
//! strictly inside the body when every plane column gives `h_j = Q · V_j > 0`; the edge
//! point at `t` is hidden when some `a >= 0` puts `Q` inside. Those `(t, a)` form a
//! convex polygon; the seed finds its corners by solving the equations `h_j = 0`
//! pairwise together with the bounds `t = t0`, `t = t1` and, when the edge may pierce
//! the body, `a = 0`; the corners that satisfy every other inequality give the
//! smallest and largest `t` of the polygon, `t_maxmin` and `t_minmax`.

use glam::DVec4;

/// Relative tolerance of the inequalities (in units of the edge's coordinates).
const EPS: f64 = 1e-9;
/// Hidden intervals shorter than this (in `t`) are none.
const EPS_T: f64 = 1e-12;

/// The seed's quantities of one edge against one body, and what follows from them.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct EdgeAgainstBody {
    /// `p_j = s · V_j`: the plane values at the edge's start.
    pub p: Vec<f64>,
    /// `q_j = d · V_j`: their change along the edge.
    pub q: Vec<f64>,
    /// `w_j = g · V_j`: their change towards the viewer.
    pub w: Vec<f64>,
    /// Whether every point of the edge is left visible by one plane alone (`h_j <= 0`
    /// for all `0 <= t <= 1`, `a >= 0`): the seed's "edge wholly visible" exit.
    pub trivially_visible: bool,
    /// The hidden parameter interval `(t_maxmin, t_minmax)` (open), if any.
    pub hidden: Option<(f64, f64)>,
}

/// Tests the edge `s + t d` (`0 <= t <= 1`, homogeneous points of the transformed
/// space) against the body of plane columns `columns` (inside positive), looking from
/// the direction `g` (the viewer at infinity along it). `penetration` adds the bound
/// `a = 0`, as the seed does when the edge may pierce the body; without it the
/// corners on `a = 0` are not found (the seed's third worked example shows what is
/// then missed).
///
/// ```
/// use glam::DVec4;
/// use obscura::lines::roberts::edge_against_body;
/// // Seed 004's unit cube and the segment (-2, 0, -2)-(2, 0, -2) behind it.
/// let v = [
///     DVec4::new(-2., 0., 0., 1.), DVec4::new(2., 0., 0., 1.),
///     DVec4::new(0., -2., 0., 1.), DVec4::new(0., 2., 0., 1.),
///     DVec4::new(0., 0., -2., 1.), DVec4::new(0., 0., 2., 1.),
/// ];
/// let e = edge_against_body(&v, DVec4::new(-2., 0., -2., 1.), DVec4::new(4., 0., 0., 0.), DVec4::Z, false);
/// assert_eq!(e.p, [5., -3., 1., 1., 5., -3.]);
/// assert_eq!(e.hidden, Some((3. / 8., 5. / 8.)));
/// ```
#[must_use]
pub fn edge_against_body(
    columns: &[DVec4],
    s: DVec4,
    d: DVec4,
    g: DVec4,
    penetration: bool,
) -> EdgeAgainstBody {
    let mut rows = Vec::with_capacity(columns.len());
    let (mut p, mut q, mut w) = (Vec::new(), Vec::new(), Vec::new());
    for v in columns {
        let r = Row {
            p: s.dot(*v),
            q: d.dot(*v),
            w: g.dot(*v),
        };
        p.push(r.p);
        q.push(r.q);
        w.push(r.w);
        rows.push(r);
    }
    let scale = edge_scale(s, d);
    let trivially_visible = trivially_visible(&rows, 0.0, 1.0);
    let hidden = if trivially_visible {
        None
    } else {
        hidden_interval(&rows, 0.0, 1.0, penetration, scale)
    };
    EdgeAgainstBody {
        p,
        q,
        w,
        trivially_visible,
        hidden,
    }
}

/// One plane's `(p_j, q_j, w_j)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Row {
    pub p: f64,
    pub q: f64,
    pub w: f64,
}

impl Row {
    #[inline]
    fn at(&self, t: f64, a: f64) -> f64 {
        self.p + self.q * t + self.w * a
    }
}

/// The size of the edge's coordinates, the unit of the tolerances.
#[inline]
pub(super) fn edge_scale(s: DVec4, d: DVec4) -> f64 {
    s.abs().max_element().max((s + d).abs().max_element())
}

/// Whether one plane alone leaves the part `t0..t1` visible: `h_j <= 0` at both ends
/// for `a = 0` and not growing towards the viewer.
#[inline]
pub(super) fn trivially_visible(rows: &[Row], t0: f64, t1: f64) -> bool {
    rows.iter()
        .any(|r| r.w <= 0.0 && r.p + r.q * t0 <= 0.0 && r.p + r.q * t1 <= 0.0)
}

/// The open interval of `t` in `t0..t1` hidden by the body of `rows`, by the seed's
/// pairwise solutions; `None` when nothing is hidden. A polygon of `(t, a)` without
/// interior (an edge on the body's surface, touching it along a line) hides nothing:
/// the width of its `a` range is checked at the middle `t`.
pub(super) fn hidden_interval(
    rows: &[Row],
    t0: f64,
    t1: f64,
    penetration: bool,
    scale: f64,
) -> Option<(f64, f64)> {
    let tol = EPS * scale.max(f64::MIN_POSITIVE);
    // The bounds as rows of the same form: t - t0 >= 0, t1 - t >= 0, a >= 0.
    let bounds = [
        Row {
            p: -t0,
            q: 1.0,
            w: 0.0,
        },
        Row {
            p: t1,
            q: -1.0,
            w: 0.0,
        },
        Row {
            p: 0.0,
            q: 0.0,
            w: 1.0,
        },
    ];
    let lines = rows
        .iter()
        .chain(&bounds[..if penetration { 3 } else { 2 }]);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, a) in lines.clone().enumerate() {
        for b in lines.clone().skip(i + 1) {
            let det = a.q * b.w - b.q * a.w;
            if det == 0.0 || det.abs() <= 1e-14 * (a.q * b.w).abs().max((b.q * a.w).abs()) {
                continue;
            }
            // Cramer: a.q t + a.w alpha = -a.p, b.q t + b.w alpha = -b.p.
            let t = (-a.p * b.w + b.p * a.w) / det;
            let alpha = (-a.q * b.p + b.q * a.p) / det;
            if !(t.is_finite() && alpha.is_finite()) {
                continue;
            }
            if t < t0 - EPS_T || t > t1 + EPS_T || alpha < -tol {
                continue;
            }
            let slack = |r: &Row| tol + EPS * r.w.abs() * alpha.abs();
            if rows.iter().all(|r| r.at(t, alpha) >= -slack(r)) {
                lo = lo.min(t);
                hi = hi.max(t);
            }
        }
    }
    interior(rows, lo.max(t0), hi.min(t1), tol)
}

/// Bodies with more planes than this are cut by [`hidden_interval_clipped`]: the
/// pairwise solutions cost `O(j^3)` (a sphere of 1,000 faces would take seconds per
/// edge), the clipping `O(j k)` for a polygon of `k` corners.
pub(super) const PAIRWISE_MAX_PLANES: usize = 16;

/// The same interval as [`hidden_interval`] for bodies of many planes: the polygon of
/// `(t, a)` is built by clipping the rectangle `t0 <= t <= t1`, `0 <= a <= A` by one
/// inequality after the other (its corners are the pairwise solutions that satisfy
/// every inequality, the seed's corners), `A` the least height a plane turned towards
/// the viewer allows.
pub(super) fn hidden_interval_clipped(
    rows: &[Row],
    t0: f64,
    t1: f64,
    penetration: bool,
    scale: f64,
) -> Option<(f64, f64)> {
    let top = rows
        .iter()
        .filter(|r| r.w < 0.0)
        .map(|r| (-(r.p + r.q * t0) / r.w).max(-(r.p + r.q * t1) / r.w))
        .fold(f64::INFINITY, f64::min);
    if !top.is_finite() {
        // Unbounded towards the viewer (no plane turned towards it): the seed's way.
        return hidden_interval(rows, t0, t1, penetration, scale);
    }
    if !(top > 0.0) {
        return None;
    }
    let mut poly: Vec<(f64, f64)> = vec![(t0, 0.0), (t1, 0.0), (t1, top), (t0, top)];
    let mut next: Vec<(f64, f64)> = Vec::with_capacity(8);
    for r in rows {
        next.clear();
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (ha, hb) = (r.at(a.0, a.1), r.at(b.0, b.1));
            if ha >= 0.0 {
                next.push(a);
            }
            if (ha >= 0.0) != (hb >= 0.0) {
                let f = ha / (ha - hb);
                next.push((a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f));
            }
        }
        std::mem::swap(&mut poly, &mut next);
        if poly.is_empty() {
            return None;
        }
    }
    let lo = poly.iter().map(|v| v.0).fold(f64::INFINITY, f64::min);
    let hi = poly.iter().map(|v| v.0).fold(f64::NEG_INFINITY, f64::max);
    interior(
        rows,
        lo.max(t0),
        hi.min(t1),
        EPS * scale.max(f64::MIN_POSITIVE),
    )
}

/// `Some((lo, hi))` when the polygon of `(t, a)` spanning `lo..hi` has an interior:
/// at the middle `t` the range of `a` must have width (a concave width, positive
/// inside the span if anywhere).
fn interior(rows: &[Row], lo: f64, hi: f64, tol: f64) -> Option<(f64, f64)> {
    if !(hi - lo > EPS_T) {
        return None;
    }
    let tm = 0.5 * (lo + hi);
    let (mut a_lo, mut a_hi) = (0.0f64, f64::INFINITY);
    for r in rows {
        let c = r.p + r.q * tm;
        if r.w.abs() <= 1e-12 * (r.p.abs() + r.q.abs()).max(1e-300) {
            if c <= tol {
                return None;
            }
        } else if r.w > 0.0 {
            a_lo = a_lo.max(-c / r.w);
        } else {
            a_hi = a_hi.min(-c / r.w);
        }
    }
    (a_hi - a_lo > tol).then_some((lo, hi))
}

/// Where the edge part `t0..t1` is inside the body (`a = 0`): `(t_in, plane entered
/// through, t_out, plane left through)`, the plane `None` where the part starts or
/// ends inside. `None` when no part of positive length is inside.
pub(super) fn inside_interval(
    rows: &[Row],
    scale: f64,
) -> Option<(f64, Option<usize>, f64, Option<usize>)> {
    let tol = EPS * scale.max(f64::MIN_POSITIVE);
    let (mut t_in, mut j_in, mut t_out, mut j_out) = (0.0f64, None, 1.0f64, None);
    for (j, r) in rows.iter().enumerate() {
        if r.q.abs() <= 1e-14 * r.p.abs() || r.q == 0.0 {
            if r.p <= tol {
                return None;
            }
            continue;
        }
        let t = -r.p / r.q;
        if r.q > 0.0 {
            if t > t_in {
                t_in = t;
                j_in = Some(j);
            }
        } else if t < t_out {
            t_out = t;
            j_out = Some(j);
        }
    }
    (t_out - t_in > EPS_T).then_some((t_in, j_in, t_out, j_out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The clipping and the seed's pairwise solutions find the same interval, on
    /// random bodies (planes tangent to a sphere) and random edges.
    #[test]
    fn clipping_agrees_with_the_pairwise_solutions() {
        let mut rng = SplitMix64(4);
        let mut hidden = 0;
        for _ in 0..2000 {
            let n = 4 + (rng.next_u64() % 12) as usize;
            let columns: Vec<DVec4> = (0..n)
                .map(|_| {
                    let v = glam::DVec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    )
                    .normalize();
                    // Inside: -v . x + 1 >= 0 (the unit ball's tangent planes).
                    (-v).extend(1.0)
                })
                .collect();
            let s = DVec4::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-3.0, 0.5),
                1.0,
            );
            let e = DVec4::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-3.0, 0.5),
                1.0,
            );
            let d = e - s;
            let rows: Vec<Row> = columns
                .iter()
                .map(|v| Row {
                    p: s.dot(*v),
                    q: d.dot(*v),
                    w: DVec4::Z.dot(*v),
                })
                .collect();
            let scale = edge_scale(s, d);
            let a = hidden_interval(&rows, 0.0, 1.0, true, scale);
            let b = hidden_interval_clipped(&rows, 0.0, 1.0, true, scale);
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert!(
                        (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                        "{a:?} {b:?}"
                    );
                    hidden += 1;
                }
                _ => panic!("{a:?} {b:?} for {rows:?}"),
            }
        }
        assert!(hidden > 200, "{hidden}");
    }
}
