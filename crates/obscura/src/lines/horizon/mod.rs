//! The floating horizon for surfaces `y = f(x, z)`, with exact piecewise-linear
//! horizons.
//!
//! # Input and output
//! A [`HeightField`] (heights over a grid of `x` and `z`: from NPY, CSV or a grayscale
//! PNG, [`HeightField::load`], or a built-in function, [`HeightField::function`]), a
//! [`Camera`] and a [`Viewport`]. [`draw`] returns a [`Drawing`] whose edges are the
//! grid's segments (kind [`EdgeKind::Curve`], world ends, `t` along them) and whose
//! pieces are their visible parts (invisibility 0) and, when asked, their hidden parts
//! (invisibility 1), in pixels (x right, y down, as a `Frame`).
//!
//! # The algorithm (seed 004, "floating horizon")
//! The surface is cut by planes of constant `z` into curves `y = f(x, z_k)`, drawn from
//! the nearest to the farthest. A point of the current curve is visible when its image
//! lies above the **upper horizon** (the highest image of every earlier curve at that
//! column) or below the **lower horizon** (the lowest): the surface in front hides the
//! band between them. Where visibility changes along a segment the crossing of the
//! segment with the horizon is computed by the seed's formula ([`crossing`], and in the
//! common-interval form the sweep uses, [`crossing_fraction`]), and only the visible
//! part of the segment is drawn. After the whole curve is tested, the horizons take it
//! in.
//!
//! Unlike the usual implementations (PLplot, BRL-CAD, and the books' versions), which
//! keep one height per pixel column and so draw up to a pixel off and miss crossings
//! between columns, the horizons here are **exact**: each is a sorted array of straight
//! spans ([`envelope::Span`]), the upper envelope of everything drawn so far (the lower
//! one kept as the upper envelope of `-v`). A curve is tested against it with one
//! binary search and a walk, and taken in by a linear merge of the two sorted arrays
//! ([`envelope::merge`]): `O(h + m)` for a horizon of `h` spans and a curve of `m`
//! segments. A span that keeps winning is extended, not split at the other side's
//! breakpoints, so the horizon holds only the vertices of its outline.
//!
//! # Both families and the sides
//! Curves of constant `x` ([`Curves::ConstantX`], [`Curves::Both`]) are drawn as the
//! literature does it (Rogers, "Procedural elements for computer graphics", 1985, §4-2):
//! interleaved with the constant-`z` curves in front-to-back order. The segments of
//! constant `x` between rows `z_k` and `z_k+1` lie behind curve `k` and in front of
//! curve `k + 1`, so they are tested, as one batch, after curve `k` is taken in and
//! before curve `k + 1`; then the horizons take them in. Segments of one batch do not
//! hide one another. With constant-`z` curves only, the two side segments of each
//! strip (the grid's first and last columns) still join the horizons without being
//! drawn, so that a farther curve reaching past a nearer one at the sides is hidden by
//! the surface's edge (Rogers' "edge effect"); with constant-`x` curves only, the
//! constant-`z` curves join the horizons without being drawn.
//!
//! # Ridgeline mode
//! [`HorizonOptions::ridgeline`]: the upper horizon only. Each curve hides everything
//! behind it and below it, as if the area under it were filled (the look of the
//! "Joy Division" plots of stacked pulses).
//!
//! # Views it needs
//! The order of the curves must be an order of occlusion: the view must be **from the
//! front**, every plane `z = z_k` lying wholly nearer or farther than the next. For a
//! perspective camera the eye's `z` must lie outside the grid's `z` range (rows are
//! drawn from the eye's side: a view from behind, `z` below the range, is handled by
//! drawing from the last row to the first); for an orthographic camera the view
//! direction must have a `z` component. A view from above or inside the grid's `z`
//! range is refused with [`Error::InvalidOption`] (option `camera`), as is a camera
//! rolled by more than 45 degrees (the horizons are functions of the picture's columns,
//! so the surface's `y` must point up the picture) and, in perspective, a sample at or
//! behind the near plane. The far plane and the picture's edges clip nothing: pieces
//! outside the picture keep their pixel coordinates.
//!
//! # Complexity
//! `O(nx nz)` to project the samples; per curve `O(h + m)` to merge and
//! `O(m log h)` to test. A 1000 x 1000 grid at 1920 x 1080 is in
//! `benches/horizon.rs`.
//!
//! # Limitations
//! The algorithm knows the surface only through its curves: a band between two
//! horizons is taken as covered, and a fold of one curve over itself does not hide its
//! own parts. Those are the floating horizon's own (Wright 1973 discusses them); the
//! drawing is exact for the algorithm, not a hidden-line drawing of the triangulated
//! surface (for that, make a mesh of the grid and use [`super::hlr`]).
//!
//! # Sources
//! - Seed 004, "Алгоритм плаваючого горизонту": upper and lower horizons, crossing
//!   points by the formula of [`crossing`] (whose printed signs are corrected there),
//!   partial segments.
//! - T. J. Wright, "A two-space solution to the hidden line problem for plotting
//!   functions of two variables", IEEE Trans. Computers C-22(1), 1973.
//! - D. P. Anderson, "Hidden line elimination in projected grid surfaces", ACM
//!   Transactions on Graphics 1(4), 1982 (front-to-back order of the grid's lines).
//! - D. F. Rogers, "Procedural elements for computer graphics", 1985, §4-2 (both
//!   families of curves, the edge effect).

pub mod envelope;
mod field;
mod load;

use glam::DVec2;

pub use envelope::{crossing, crossing_fraction};
pub use field::{FUNCTIONS, HeightField};

use super::{Drawing, DrawnEdge, EdgeKind, Piece};
use crate::budget::MemoryBudget;
use crate::scene::Projection;
use crate::view::ViewTransform;
use crate::{Camera, Error, Result, Viewport};
use envelope::Span;

/// Which curves of the surface are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Curves {
    /// Curves of constant `z` (the classic floating horizon).
    #[default]
    ConstantZ,
    /// Curves of constant `x` (the constant-`z` curves still hide them, undrawn).
    ConstantX,
    /// Both: the grid's lines.
    Both,
}

impl Curves {
    /// The names [`Curves::parse`] accepts, in the order of the variants.
    pub const NAMES: [&'static str; 3] = ["z", "x", "both"];

    /// Parses `z`, `x` or `both`.
    ///
    /// ```
    /// use obscura::lines::horizon::Curves;
    /// assert_eq!(Curves::parse("both").unwrap(), Curves::Both);
    /// assert!(Curves::parse("y").is_err());
    /// ```
    pub fn parse(name: &str) -> Result<Curves> {
        match name {
            "z" => Ok(Curves::ConstantZ),
            "x" => Ok(Curves::ConstantX),
            "both" | "xz" | "zx" => Ok(Curves::Both),
            _ => Err(Error::option(
                "curves",
                format!("unknown curves '{name}' (expected z, x or both)"),
            )),
        }
    }

    fn draws_z(self) -> bool {
        self != Curves::ConstantX
    }

    fn draws_x(self) -> bool {
        self != Curves::ConstantZ
    }
}

/// Options of [`draw`].
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
pub struct HorizonOptions {
    /// The curves drawn.
    pub curves: Curves,
    /// The upper horizon only: each curve hides what lies behind it and below it.
    pub ridgeline: bool,
    /// Emit the hidden parts too, as pieces of invisibility 1.
    pub hidden: bool,
    /// The memory budget in bytes (`None`: [`MemoryBudget::default_limit`]).
    pub memory_limit: Option<u64>,
}

impl HorizonOptions {
    /// These options with other curves.
    #[must_use]
    pub fn with_curves(mut self, curves: Curves) -> Self {
        self.curves = curves;
        self
    }

    /// These options in ridgeline mode or not.
    #[must_use]
    pub fn with_ridgeline(mut self, ridgeline: bool) -> Self {
        self.ridgeline = ridgeline;
        self
    }

    /// These options with the hidden parts emitted or not.
    #[must_use]
    pub fn with_hidden(mut self, hidden: bool) -> Self {
        self.hidden = hidden;
        self
    }
}

/// What the drawing cost.
#[derive(Clone, Debug, Default, serde::Serialize)]
#[non_exhaustive]
pub struct HorizonStats {
    /// Curves drawn (rows of constant `z` and columns of constant `x`).
    pub curves: u64,
    /// Grid segments drawn (each an edge of the drawing).
    pub segments: u64,
    /// Visible pieces emitted.
    pub visible_pieces: u64,
    /// Hidden pieces emitted (with [`HorizonOptions::hidden`]).
    pub hidden_pieces: u64,
    /// The most spans either horizon held.
    pub horizon_spans: u64,
    /// Whether rows were drawn from the last (`z_range[1]`) to the first: the eye is on
    /// the `+z` side.
    pub last_row_first: bool,
}

/// The budget's name for the projected samples.
const PROJECTED: &str = "horizon projected samples";

/// Draws the visible parts of the surface's curves (see the module doc).
///
/// ```
/// use obscura::Viewport;
/// use obscura::lines::horizon::{HeightField, HorizonOptions, draw};
/// let field = HeightField::function("bump", 40, 30)?;
/// let viewport = Viewport::new(640, 480)?;
/// let camera = field.default_camera(viewport.aspect());
/// let (drawing, stats) = draw(&field, &camera, viewport, &HorizonOptions::default())?;
/// assert_eq!(stats.curves, 30);
/// assert!(drawing.visible().count() > 0);
/// # Ok::<(), obscura::Error>(())
/// ```
pub fn draw(
    field: &HeightField,
    camera: &Camera,
    viewport: Viewport,
    options: &HorizonOptions,
) -> Result<(Drawing, HorizonStats)> {
    field.validate()?;
    viewport.validate()?;
    camera.validate_for(viewport)?;
    let budget = MemoryBudget::from_option(options.memory_limit);
    let last_row_first = row_order(field, camera)?;
    let (nx, nz) = (field.nx, field.nz);
    let n = nx * nz;

    // Project every sample once: pixel column, "up" (minus the pixel row), clip w.
    budget.check_items(PROJECTED, n as u64, 24)?;
    let tr = ViewTransform::new(camera, viewport);
    let mut pts: Vec<DVec2> = crate::budget::try_vec(&budget, PROJECTED, n)?;
    let mut ws: Vec<f64> = crate::budget::try_vec(&budget, PROJECTED, n)?;
    for k in 0..nz {
        for i in 0..nx {
            let p = field.point(i, k);
            let e = tr.world_to_eye(p);
            if !tr.orthographic && !(-e.z > tr.near_limit) {
                return Err(Error::option(
                    "camera",
                    format!(
                        "the height field's sample at row {k}, column {i} ({:?}) is not in front \
                         of the camera's near plane: the floating horizon draws only surfaces \
                         wholly in front of a perspective camera",
                        p.to_array()
                    ),
                ));
            }
            let c = tr.eye_to_clip(e);
            let sx = (c.x / c.w + 1.0) * 0.5 * tr.width;
            let sy = (1.0 - c.y / c.w) * 0.5 * tr.height;
            pts.push(DVec2::new(sx, -sy));
            ws.push(c.w);
        }
    }

    let mut stats = HorizonStats {
        last_row_first,
        ..HorizonStats::default()
    };
    let drawn_z = if options.curves.draws_z() {
        nz * (nx - 1)
    } else {
        0
    };
    let drawn_x = if options.curves.draws_x() {
        nx * (nz - 1)
    } else {
        0
    };
    // The drawing is held whole, edges and pieces together (each checked alone below
    // would let their sum pass the budget): one edge and at least one piece a segment.
    budget.check_items(
        "horizon drawing (edges and pieces)",
        (drawn_z + drawn_x) as u64,
        (size_of::<crate::lines::DrawnEdge>() + size_of::<Piece>()) as u64,
    )?;
    let mut drawing = Drawing::new(viewport.width, viewport.height);
    drawing.edges = crate::budget::try_vec(&budget, EDGES, drawn_z + drawn_x)?;
    drawing.pieces = crate::budget::try_vec(&budget, PIECES, drawn_z + drawn_x)?;
    stats.curves = u64::from(options.curves.draws_z()) * nz as u64
        + u64::from(options.curves.draws_x()) * nx as u64;

    let mut run = Run {
        field,
        pts: &pts,
        ws: &ws,
        orthographic: tr.orthographic,
        options,
        budget,
        upper: Vec::new(),
        lower: Vec::new(),
        merged: Vec::new(),
        batch: Vec::new(),
        negated: Vec::new(),
        batch_env: Vec::new(),
        scratch: Vec::new(),
        up_iv: Vec::new(),
        low_iv: Vec::new(),
        vis: Vec::new(),
        hints: [0, 0],
        raise: [true, true],
        drawing,
        stats,
    };
    let rows: Vec<usize> = if last_row_first {
        (0..nz).rev().collect()
    } else {
        (0..nz).collect()
    };
    let side_columns = [0, nx - 1];
    for (step, &k) in rows.iter().enumerate() {
        run.group(
            (0..nx - 1).map(|i| (k * nx + i, k * nx + i + 1)),
            options.curves.draws_z(),
        )?;
        if let Some(&k2) = rows.get(step + 1) {
            if options.curves.draws_x() {
                run.group((0..nx).map(|i| (k * nx + i, k2 * nx + i)), true)?;
            } else {
                run.group(
                    side_columns.iter().map(|&i| (k * nx + i, k2 * nx + i)),
                    false,
                )?;
            }
        }
    }
    let Run { drawing, stats, .. } = run;
    Ok((drawing, stats))
}

/// The budget's names for the drawing's vectors.
const EDGES: &str = "horizon edges";
const PIECES: &str = "horizon pieces";

/// Whether the rows are drawn from the last to the first, or the refusal of a view
/// that is not from the front (see the module doc).
fn row_order(field: &HeightField, camera: &Camera) -> Result<bool> {
    let (right, _, forward) = camera.basis();
    if right.y.abs() > std::f64::consts::FRAC_1_SQRT_2 {
        return Err(Error::option(
            "camera",
            "the camera is rolled by more than 45 degrees: the floating horizon needs the \
             surface's y axis to point up the picture",
        ));
    }
    let [z0, z1] = field.z_range;
    match camera.projection {
        Projection::Perspective { .. } => {
            let ez = camera.eye.z;
            if ez > z1 {
                Ok(true)
            } else if ez < z0 {
                Ok(false)
            } else {
                Err(Error::option(
                    "camera",
                    format!(
                        "the eye's z ({ez}) lies within the height field's z range [{z0}, {z1}] \
                         (a view from above or from inside the grid): the floating horizon needs \
                         the view from the front, the eye's z beyond the range on either side"
                    ),
                ))
            }
        }
        Projection::Orthographic { .. } => {
            if forward.z < -1e-9 {
                Ok(true)
            } else if forward.z > 1e-9 {
                Ok(false)
            } else {
                Err(Error::option(
                    "camera",
                    "the orthographic view direction has no z component (the planes of \
                     constant z are seen edge on): the floating horizon needs the view from \
                     the front or from behind",
                ))
            }
        }
    }
}

/// The state of one drawing.
struct Run<'a> {
    field: &'a HeightField,
    pts: &'a [DVec2],
    ws: &'a [f64],
    orthographic: bool,
    options: &'a HorizonOptions,
    budget: MemoryBudget,
    /// The upper horizon (up coordinates).
    upper: Vec<Span>,
    /// The lower horizon, as the upper envelope of `-v`.
    lower: Vec<Span>,
    merged: Vec<Span>,
    batch: Vec<Span>,
    negated: Vec<Span>,
    batch_env: Vec<Span>,
    scratch: Vec<Vec<Span>>,
    up_iv: Vec<[f64; 2]>,
    low_iv: Vec<[f64; 2]>,
    vis: Vec<[f64; 2]>,
    /// Where the last segment ended in the upper and the lower horizon.
    hints: [usize; 2],
    /// Whether the batch being drawn changes the upper and the lower horizon.
    raise: [bool; 2],
    drawing: Drawing,
    stats: HorizonStats,
}

impl Run<'_> {
    /// Tests the segments `(a, b)` (sample indices) against the horizons, draws them
    /// when `draw` is set, then takes them into the horizons.
    fn group(&mut self, segments: impl Iterator<Item = (usize, usize)>, draw: bool) -> Result<()> {
        self.batch.clear();
        // Undrawn segments are not tested: they always join the horizons.
        self.raise = [!draw, !draw];
        for (a, b) in segments {
            let (p, q) = (self.pts[a], self.pts[b]);
            if draw {
                self.segment(a, b, p, q)?;
            }
            if p.x < q.x {
                self.batch.push(Span {
                    x0: p.x,
                    y0: p.y,
                    x1: q.x,
                    y1: q.y,
                });
            } else if q.x < p.x {
                self.batch.push(Span {
                    x0: q.x,
                    y0: q.y,
                    x1: p.x,
                    y1: p.y,
                });
            }
        }
        if self.batch.is_empty() {
            return Ok(());
        }
        let ridgeline = self.options.ridgeline;
        let mut negated = std::mem::take(&mut self.negated);
        negated.clear();
        if !ridgeline && self.raise[1] {
            negated.extend(self.batch.iter().map(|s| Span {
                y0: -s.y0,
                y1: -s.y1,
                ..*s
            }));
        }
        if self.raise[0] {
            envelope::envelope_of(&mut self.batch, &mut self.batch_env, &mut self.scratch);
            envelope::merge_into(&mut self.upper, &self.batch_env, &mut self.merged);
        }
        if !ridgeline && self.raise[1] {
            envelope::envelope_of(&mut negated, &mut self.batch_env, &mut self.scratch);
            envelope::merge_into(&mut self.lower, &self.batch_env, &mut self.merged);
        }
        self.negated = negated;
        let spans = self.upper.len().max(self.lower.len()) as u64;
        self.stats.horizon_spans = self.stats.horizon_spans.max(spans);
        self.budget
            .check_items("horizon spans", spans, 2 * size_of::<Span>() as u64)?;
        Ok(())
    }

    /// Draws one segment: its visible parts (and hidden ones when asked) as pieces.
    fn segment(&mut self, a: usize, b: usize, p: DVec2, q: DVec2) -> Result<()> {
        self.up_iv.clear();
        let outside = envelope::above_from(&self.upper, p, q, &mut self.up_iv, &mut self.hints[0]);
        // A segment that is nowhere above the upper horizon (by more than the tolerance)
        // and nowhere outside it leaves it as it is; likewise for the lower one. The
        // horizons have the same extent (they take in the same segments), and the upper
        // lies above the lower, so a segment wholly above the upper one is not below the
        // lower one.
        self.raise[0] |= !self.up_iv.is_empty();
        self.raise[1] |= outside;
        self.vis.clear();
        if self.options.ridgeline || self.up_iv == [[0.0, 1.0]] {
            // Wholly above the upper horizon: the lower one cannot add to it.
            self.vis.extend_from_slice(&self.up_iv);
        } else {
            self.low_iv.clear();
            let neg = |v: DVec2| DVec2::new(v.x, -v.y);
            envelope::above_from(
                &self.lower,
                neg(p),
                neg(q),
                &mut self.low_iv,
                &mut self.hints[1],
            );
            self.raise[1] |= !self.low_iv.is_empty();
            union(&self.up_iv, &self.low_iv, &mut self.vis);
        }
        let length = p.distance(q);
        if length > 0.0 {
            drop_slivers(&mut self.vis, MIN_PIECE / length);
        }
        let nx = self.field.nx;
        let edge = u32::try_from(self.drawing.edges.len())
            .map_err(|_| self.budget.exceeded(EDGES, u64::MAX, u64::MAX))?;
        self.drawing.edges.push(DrawnEdge {
            vertices: None,
            object: None,
            kind: EdgeKind::Curve,
            faces: [None, None],
            world: [
                self.field.point(a % nx, a / nx),
                self.field.point(b % nx, b / nx),
            ],
        });
        self.stats.segments += 1;
        let (w0, w1) = (self.ws[a], self.ws[b]);
        let mut at = 0.0;
        for k in 0..self.vis.len() {
            let [s0, s1] = self.vis[k];
            if self.options.hidden && s0 > at {
                self.piece(edge, p, q, w0, w1, at, s0, 1)?;
            }
            self.piece(edge, p, q, w0, w1, s0, s1, 0)?;
            at = s1;
        }
        if self.options.hidden && at < 1.0 {
            self.piece(edge, p, q, w0, w1, at, 1.0, 1)?;
        }
        Ok(())
    }

    /// Emits the piece of screen parameters `s0..s1` of the segment `p`-`q` (up
    /// coordinates; clip `w` at its ends `w0`, `w1`).
    #[allow(clippy::too_many_arguments)]
    fn piece(
        &mut self,
        edge: u32,
        p: DVec2,
        q: DVec2,
        w0: f64,
        w1: f64,
        s0: f64,
        s1: f64,
        invisibility: u32,
    ) -> Result<()> {
        if !(s1 > s0) {
            return Ok(());
        }
        let pieces = &mut self.drawing.pieces;
        if pieces.len() == pieces.capacity() {
            let want = (pieces.len() * 2).max(1024);
            self.budget
                .check_items(PIECES, want as u64, size_of::<Piece>() as u64)?;
            pieces
                .try_reserve(want - pieces.len())
                .map_err(|_| self.budget.exceeded(PIECES, want as u64, u64::MAX))?;
        }
        let at = |s: f64| {
            let v = if s <= 0.0 {
                p
            } else if s >= 1.0 {
                q
            } else {
                p + (q - p) * s
            };
            DVec2::new(v.x, -v.y)
        };
        let t = |s: f64| {
            if self.orthographic || s <= 0.0 || s >= 1.0 {
                s.clamp(0.0, 1.0)
            } else {
                // The screen is affine in 1/w along the edge: s = t w1 / ((1 - t) w0 + t w1).
                s * w0 / ((1.0 - s) * w1 + s * w0)
            }
        };
        pieces.push(Piece {
            edge,
            t: [t(s0), t(s1)],
            points: [at(s0), at(s1)],
            invisibility,
        });
        if invisibility == 0 {
            self.stats.visible_pieces += 1;
        } else {
            self.stats.hidden_pieces += 1;
        }
        Ok(())
    }
}

/// The shortest piece drawn, in pixels: `1e-6`. A segment that starts on the horizon
/// (a segment of constant `x` starts on the curve before it) rises above it only past
/// [`envelope::ABOVE_TOLERANCE`]; without this it would begin with a hidden sliver a
/// billionth of a pixel long.
pub const MIN_PIECE: f64 = 1e-6;

/// Joins visible intervals (of `s` in `[0, 1]`) separated by less than `min`, extends
/// them to the segment's ends when they stop short of them by less than `min`, then
/// drops those shorter than `min`.
fn drop_slivers(vis: &mut Vec<[f64; 2]>, min: f64) {
    if vis.is_empty() {
        return;
    }
    let mut w = 0;
    for r in 1..vis.len() {
        if vis[r][0] - vis[w][1] < min {
            vis[w][1] = vis[r][1];
        } else {
            w += 1;
            vis[w] = vis[r];
        }
    }
    vis.truncate(w + 1);
    if vis[0][0] < min {
        vis[0][0] = 0.0;
    }
    if 1.0 - vis[w][1] < min {
        vis[w][1] = 1.0;
    }
    vis.retain(|iv| iv[1] - iv[0] >= min);
}

/// The union of two sorted lists of disjoint intervals, into `out`.
fn union(a: &[[f64; 2]], b: &[[f64; 2]], out: &mut Vec<[f64; 2]>) {
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let next = if j >= b.len() || (i < a.len() && a[i][0] <= b[j][0]) {
            i += 1;
            a[i - 1]
        } else {
            j += 1;
            b[j - 1]
        };
        match out.last_mut() {
            Some(last) if last[1] >= next[0] => last[1] = last[1].max(next[1]),
            _ => out.push(next),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slivers_are_joined_and_dropped() {
        let mut v = vec![
            [1e-9, 0.3],
            [0.3 + 1e-9, 0.5],
            [0.7, 0.7 + 1e-9],
            [0.8, 1.0 - 1e-9],
        ];
        drop_slivers(&mut v, 1e-6);
        assert_eq!(v, vec![[0.0, 0.5], [0.8, 1.0]]);
    }

    #[test]
    fn union_joins_overlaps() {
        let mut out = Vec::new();
        union(
            &[[0.0, 0.2], [0.5, 0.6]],
            &[[0.1, 0.3], [0.6, 0.9]],
            &mut out,
        );
        assert_eq!(out, vec![[0.0, 0.3], [0.5, 0.9]]);
    }

    #[test]
    fn perspective_t_follows_the_screen() {
        // A segment from depth 1 to depth 3, seen head-on: the screen midpoint is
        // a quarter of the way along the 3D edge (1/w is affine on the screen).
        let s: f64 = 0.5;
        let (w0, w1): (f64, f64) = (1.0, 3.0);
        let t = s * w0 / ((1.0 - s) * w1 + s * w0);
        // Check: the point at t projects to the screen midpoint of x/w from x = 1 at
        // both ends... x(t)/w(t) with x = 1 - 2t, w = 1 + 2t: ends 1/1 and -1/3.
        let (x, w) = (1.0 - 2.0 * t, 1.0 + 2.0 * t);
        assert!((x / w - (1.0 + (-1.0 / 3.0)) / 2.0).abs() < 1e-12);
    }
}
