//! The polygons depth sort works on: the view's polygons and the pieces made by
//! splitting them, with their eye-space planes, extents and the pairwise tests.
//!
//! Paper: Newell, Newell and Sancha, "A solution to the hidden surface problem",
//! Proceedings of the ACM Annual Conference, 1972 (the tests and splits).

use glam::DVec3;

use crate::clip::split::{Split, split_polygon};
use crate::geom::Plane;
use crate::raster::{DepthPlane, FillRule, PixelRect, PolygonCoverage};
use crate::surface::image::paint::{PixelRays, ScreenCut, piece_region};
use crate::view::{PreparedView, ViewTransform, ViewVertex};

/// Relative tolerance of plane tests: a vertex within `RELATIVE_EPS * scale` of a
/// plane counts as on it, `scale` being the largest absolute eye coordinate of the two
/// polygons compared (see [`WorkSet::sides`]). With the largest coordinate of the whole
/// view instead, a ground 2e5 across set a tolerance of 1e-4 for triangles 1e-4
/// across seen from 7e-4, and two of them were painted in the wrong order.
const RELATIVE_EPS: f64 = 1e-9;

/// A polygon being sorted.
#[derive(Clone, Copy, Debug)]
pub(super) struct Poly {
    pub face: u32,
    pub object: u32,
    /// Index of the view polygon it is (a piece of).
    pub source: u32,
    start: u32,
    len: u32,
    /// The polygon of the whole view polygon (itself unless it is a piece).
    root: u32,
    /// Its cuts: `cuts[cut_start..cut_start + cut_len]` of the set (see
    /// [`WorkSet::cuts`]).
    cut_start: u32,
    cut_len: u32,
    /// Eye-space plane, unit normal, oriented so the viewpoint is on its positive side.
    pub plane: Plane,
    /// Distance within which a point counts as on `plane` by this polygon's own scale
    /// (includes the original polygon's own deviation from it); a comparison with
    /// another polygon takes the larger of the two.
    pub eps: f64,
    /// Pixels whose samples lie in its screen box (clipped to the image); for a
    /// piece, its vertices' box widened by two pixels, which holds every sample it
    /// paints (its whole polygon's on its sides of its [`WorkSet::cuts`]).
    pub rect: PixelRect,
    /// Eye-space depth extent.
    pub dmin: f64,
    pub dmax: f64,
}

/// Signed distances of one polygon's vertices from another's plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct Range {
    pub min: f64,
    pub max: f64,
}

/// How two polygons `p`, `q` lie relative to each other's planes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sides {
    /// `p`'s vertices against `q`'s plane.
    pub p_by_q: Range,
    /// `q`'s vertices against `p`'s plane.
    pub q_by_p: Range,
    pub p_eps: f64,
    pub q_eps: f64,
}

impl Sides {
    /// One polygon lies in the other's plane (within the tolerance).
    pub fn coplanar(&self) -> bool {
        let on = |r: Range, e: f64| r.min >= -e && r.max <= e;
        on(self.p_by_q, self.q_eps) || on(self.q_by_p, self.p_eps)
    }

    /// Test 3: `p` lies entirely on the far side of `q`'s plane (the side without the
    /// viewpoint), so `p` cannot hide `q`.
    pub fn p_behind_q_plane(&self) -> bool {
        self.p_by_q.max <= self.q_eps
    }

    /// Test 4: `q` lies entirely on the near side of `p`'s plane.
    pub fn q_before_p_plane(&self) -> bool {
        self.q_by_p.min >= -self.p_eps
    }

    /// Test 3 with the roles swapped: `q` entirely behind `p`'s plane.
    pub fn q_behind_p_plane(&self) -> bool {
        self.q_by_p.max <= self.p_eps
    }

    /// Test 4 with the roles swapped: `p` entirely in front of `q`'s plane.
    pub fn p_before_q_plane(&self) -> bool {
        self.p_by_q.min >= -self.q_eps
    }

    /// `p` has vertices strictly on both sides of `q`'s plane.
    pub fn p_spans_q_plane(&self) -> bool {
        self.p_by_q.min < -self.q_eps && self.p_by_q.max > self.q_eps
    }

    /// `q` has vertices strictly on both sides of `p`'s plane.
    pub fn q_spans_p_plane(&self) -> bool {
        self.q_by_p.min < -self.p_eps && self.q_by_p.max > self.p_eps
    }
}

/// The polygons and everything needed to test, split and paint them.
pub(super) struct WorkSet {
    pub polys: Vec<Poly>,
    verts: Vec<ViewVertex>,
    /// Depth-key plane of each view polygon (pieces paint with their source's plane).
    depth_planes: Vec<Option<DepthPlane>>,
    transform: ViewTransform,
    fill: FillRule,
    width: u32,
    height: u32,
    /// Number of view polygons.
    pub view_polygons: usize,
    /// Set once a conflict is left unresolved (the split budget spent, or a split that
    /// rounding prevents) or the comparison budget is spent: the polygons painted from
    /// then on are depth-tested against what is painted (see `super::render_variant`).
    pub fallback: bool,
    scratch: Vec<DVec3>,
    /// The splits that made the pieces, as the cuts their pixels are painted with.
    cuts: Vec<ScreenCut>,
    /// The view's pixel rays in eye space (for the cuts).
    rays: PixelRays,
    /// Per polygon made from a view polygon (not the pieces, added after), the
    /// coverage of its screen polygon, computed once when first needed.
    coverages: Vec<std::cell::OnceCell<Option<PolygonCoverage>>>,
    /// The memory budget the pieces of splits are held to (see [`crate::budget`]).
    pub budget: crate::budget::MemoryBudget,
    /// Set when a split was refused because the set passed the budget: the render
    /// ends with this error.
    pub over_budget: Option<crate::Error>,
    /// The deadline of the render (see [`crate::work`]), checked by the sorts.
    pub deadline: crate::work::Deadline,
}

impl WorkSet {
    /// The view's polygons that cover at least one pixel sample (the others are not
    /// painted by any algorithm).
    pub fn from_view(view: &PreparedView<'_>, fill: FillRule) -> WorkSet {
        let vp = view.viewport();
        let t = *view.transform();
        let mut ws = WorkSet {
            polys: Vec::with_capacity(view.polygon_count()),
            verts: Vec::with_capacity(view.vertices().len()),
            depth_planes: Vec::with_capacity(view.polygon_count()),
            transform: t,
            fill,
            width: vp.width,
            height: vp.height,
            view_polygons: view.polygon_count(),
            fallback: false,
            scratch: Vec::new(),
            cuts: Vec::new(),
            rays: PixelRays::new(view, |p| t.world_to_eye(p), |d| t.rotation * d),
            coverages: Vec::new(),
            budget: crate::budget::MemoryBudget::new(u64::MAX),
            over_budget: None,
            deadline: crate::work::Deadline::default(),
        };
        let mut screen = Vec::new();
        for (i, poly) in view.polygons().enumerate() {
            screen.clear();
            screen.extend(poly.vertices().map(|v| (v.x, v.y)));
            let depth_plane = poly.depth_plane();
            ws.depth_planes.push(depth_plane);
            let Some(cov) = PolygonCoverage::new(&screen, fill, vp.width, vp.height) else {
                continue;
            };
            if depth_plane.is_none() {
                continue;
            }
            let eye = poly.eye_points();
            let Some(plane) = Plane::newell(&eye) else {
                continue;
            };
            let plane = if facing_viewer(&plane, t.orthographic) {
                plane
            } else {
                plane.flipped()
            };
            let thickness = eye
                .iter()
                .fold(0.0f64, |m, &p| m.max(plane.evaluate(p).abs()));
            let scale = eye.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
            let base_eps = RELATIVE_EPS * scale.max(f64::MIN_POSITIVE);
            let start = ws.verts.len() as u32;
            ws.verts.extend(poly.vertices().copied());
            let (dmin, dmax) = depth_extent(&eye);
            ws.polys.push(Poly {
                face: poly.face,
                object: poly.object,
                source: i as u32,
                start,
                len: poly.len() as u32,
                root: ws.polys.len() as u32,
                cut_start: 0,
                cut_len: 0,
                plane,
                eps: base_eps + thickness,
                rect: cov.rect(),
                dmin,
                dmax,
            });
        }
        ws.coverages = vec![std::cell::OnceCell::new(); ws.polys.len()];
        ws
    }

    /// The projected vertices of polygon `i`.
    pub fn vertices(&self, i: u32) -> &[ViewVertex] {
        let p = &self.polys[i as usize];
        &self.verts[p.start as usize..(p.start + p.len) as usize]
    }

    /// The projected vertices of the whole view polygon polygon `i` is a piece of (its
    /// own if it is not a piece).
    pub fn whole_vertices(&self, i: u32) -> &[ViewVertex] {
        self.vertices(self.polys[i as usize].root)
    }

    /// The cuts of the splits that made polygon `i` out of its view polygon, first to
    /// last (empty for a polygon that is not a piece): a piece paints the pixels of
    /// its whole polygon on its side of every cut.
    pub fn cuts(&self, i: u32) -> &[ScreenCut] {
        let p = &self.polys[i as usize];
        &self.cuts[p.cut_start as usize..(p.cut_start + p.cut_len) as usize]
    }

    /// The depth-key plane polygon `i` is painted with (its source's).
    pub fn depth_plane(&self, i: u32) -> Option<&DepthPlane> {
        self.depth_planes[self.polys[i as usize].source as usize].as_ref()
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Signed distances of `p` from `q`'s plane and of `q` from `p`'s.
    pub fn sides(&self, p: u32, q: u32) -> Sides {
        let (pp, qp) = (&self.polys[p as usize], &self.polys[q as usize]);
        Sides {
            p_by_q: self.range(p, &qp.plane),
            q_by_p: self.range(q, &pp.plane),
            p_eps: pp.eps.max(qp.eps),
            q_eps: qp.eps.max(pp.eps),
        }
    }

    fn range(&self, i: u32, plane: &Plane) -> Range {
        let mut r = Range {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        };
        // The distance `split_polygon` splits by, so tests and splits agree.
        for d in plane.signed_distances(self.vertices(i).iter().map(|v| v.eye)) {
            r.min = r.min.min(d);
            r.max = r.max.max(d);
        }
        r
    }

    /// Whether the pixel boxes of `p` and `q` are disjoint in x (test 1).
    pub fn x_disjoint(&self, p: u32, q: u32) -> bool {
        let (a, b) = (&self.polys[p as usize].rect, &self.polys[q as usize].rect);
        a.x1 <= b.x0 || b.x1 <= a.x0
    }

    /// Whether the pixel boxes of `p` and `q` are disjoint in y (test 2).
    pub fn y_disjoint(&self, p: u32, q: u32) -> bool {
        let (a, b) = (&self.polys[p as usize].rect, &self.polys[q as usize].rect);
        a.y1 <= b.y0 || b.y1 <= a.y0
    }

    /// Test 5, negated: whether the projections of `p` and `q` share a pixel sample.
    /// First the separating-axis test of two convex polygons (an edge line of either
    /// polygon with the other on its outer side; touching counts as separated unless
    /// one is a piece), then, if no edge separates them, the exact check on the
    /// samples both cover under the shared coverage rule (overlaps smaller than a
    /// pixel change nothing in the image), and for pieces on the samples they paint.
    pub fn projections_overlap(&self, p: u32, q: u32) -> bool {
        let (a, b) = (self.vertices(p), self.vertices(q));
        // A piece paints samples within rounding of its own vertices' polygon, but
        // maybe on its edges, which touching polygons share: pieces are separated
        // only by a gap, and touching ones are checked on the samples they paint.
        let pieces = !(self.cuts(p).is_empty() && self.cuts(q).is_empty());
        let gap = if pieces { GAP } else { -TOUCH };
        if separated(a, b, gap) || separated(b, a, gap) {
            return false;
        }
        if self.own_samples_overlap(p, q) {
            return true;
        }
        pieces && self.pieces_overlap(p, q)
    }

    /// The coverage of polygon `i`'s own vertices: its whole polygon's, computed once,
    /// unless it is a piece.
    fn own_coverage(&self, i: u32) -> Option<std::borrow::Cow<'_, PolygonCoverage>> {
        if self.cuts(i).is_empty() {
            return self.whole_coverage(i).map(std::borrow::Cow::Borrowed);
        }
        let screen: Vec<(f64, f64)> = self.vertices(i).iter().map(|v| (v.x, v.y)).collect();
        PolygonCoverage::new(&screen, self.fill, self.width, self.height)
            .map(std::borrow::Cow::Owned)
    }

    /// Whether the coverages of the own vertices of `p` and `q` share a sample.
    fn own_samples_overlap(&self, p: u32, q: u32) -> bool {
        let (a, b) = (self.vertices(p), self.vertices(q));
        // Only samples in the box of the overlap region (widened far above rounding)
        // can be covered by both: most overlaps of small polygons hold none.
        let region = overlap_region(a, b);
        let (mut minx, mut miny, mut maxx, mut maxy) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for &(x, y) in &region {
            minx = minx.min(x);
            maxx = maxx.max(x);
            miny = miny.min(y);
            maxy = maxy.max(y);
        }
        const WIDEN: f64 = 1e-6;
        let first = |v: f64, n: u32| (v - WIDEN - 0.5).ceil().clamp(0.0, f64::from(n)) as u32;
        let end =
            |v: f64, n: u32| ((v + WIDEN - 0.5).floor() + 1.0).clamp(0.0, f64::from(n)) as u32;
        if region.is_empty() || !(minx.is_finite() && maxx.is_finite()) {
            return false;
        }
        let (x0, x1) = (first(minx, self.width), end(maxx, self.width));
        let (y0, y1) = (first(miny, self.height), end(maxy, self.height));
        if x0 >= x1 || y0 >= y1 {
            return false;
        }
        let (Some(ca), Some(cb)) = (self.own_coverage(p), self.own_coverage(q)) else {
            return false;
        };
        for y in y0..y1 {
            if let (Some((a0, a1)), Some((b0, b1))) = (ca.row_span(y), cb.row_span(y))
                && a0.max(b0).max(x0) < a1.min(b1).min(x1)
            {
                return true;
            }
        }
        false
    }

    /// [`WorkSet::projections_overlap`] when `p` or `q` is a piece: whether a pixel in
    /// both boxes is painted by both. A piece paints the pixels of its whole polygon
    /// on its sides of its cuts, which may include samples on its own vertices' edges
    /// that their coverage rule would leave out: the test must be on what is painted,
    /// or two polygons painting the same pixel could be left unordered.
    fn pieces_overlap(&self, p: u32, q: u32) -> bool {
        let (a, b) = (&self.polys[p as usize].rect, &self.polys[q as usize].rect);
        let (x0, x1) = (a.x0.max(b.x0), a.x1.min(b.x1));
        let (y0, y1) = (a.y0.max(b.y0), a.y1.min(b.y1));
        if x0 >= x1 || y0 >= y1 {
            return false;
        }
        let (Some(cp), Some(cq)) = (self.whole_coverage(p), self.whole_coverage(q)) else {
            return false;
        };
        let (kp, kq) = (self.cuts(p), self.cuts(q));
        (y0..y1).any(|y| {
            let (Some((a0, a1)), Some((b0, b1))) = (cp.row_span(y), cq.row_span(y)) else {
                return false;
            };
            (a0.max(b0).max(x0)..a1.min(b1).min(x1))
                .any(|x| kp.iter().all(|c| c.keeps(x, y)) && kq.iter().all(|c| c.keeps(x, y)))
        })
    }

    /// Which of `p` and `q` is nearer where their projections overlap: the region
    /// both cover (`p`'s projection clipped by `q`'s edges) is convex and the
    /// difference of their depth keys is affine in screen space, so its signs at the
    /// region's corners decide. `Greater`: `p` is nearer or level everywhere there;
    /// `Less`: `q` is; `None`: they cross inside the region (interpenetration), or
    /// the region is empty to rounding. Seed 003 suggests the same for the common
    /// zone ("the common zone can even be analysed pixel by pixel").
    pub fn nearer_over_overlap(&self, p: u32, q: u32) -> Option<std::cmp::Ordering> {
        let (zp, zq) = (self.depth_plane(p)?, self.depth_plane(q)?);
        let region = overlap_region(self.vertices(p), self.vertices(q));
        if region.len() < 3 {
            return None;
        }
        let (mut lo, mut hi, mut scale) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for &(x, y) in &region {
            let (a, b) = (zp.at(x, y), zq.at(x, y));
            lo = lo.min(a - b);
            hi = hi.max(a - b);
            scale = scale.max(a.abs()).max(b.abs());
        }
        let tol = 1e-9 * scale;
        if lo >= -tol && hi > tol {
            Some(std::cmp::Ordering::Greater)
        } else if hi <= tol && lo < -tol {
            Some(std::cmp::Ordering::Less)
        } else {
            None
        }
    }

    /// Whether the sort must stop: an earlier budget error, or the deadline passed
    /// (then recorded as the error the render ends with).
    pub fn out_of_time(&mut self) -> bool {
        if self.over_budget.is_some() {
            return true;
        }
        match self.deadline.check("depth-sort comparisons and painting") {
            Ok(()) => false,
            Err(e) => {
                self.over_budget = Some(e);
                true
            }
        }
    }

    /// Splits polygon `i` by `by`'s plane (seed 000: "R is split in two by the plane of
    /// Q, the new polygons replace R"). Returns the two new polygons, or `None` if `i`
    /// does not cross the plane. Pieces keep `i`'s face, plane and tolerance; their
    /// vertices equal to `i`'s keep their exact projection, new ones are projected
    /// once and shared by both pieces.
    pub fn split(&mut self, i: u32, by: u32) -> Option<[u32; 2]> {
        if self.over_budget.is_some() {
            return None;
        }
        let bytes = self.bytes();
        if bytes > self.budget.limit() {
            self.over_budget = Some(self.budget.exceeded(
                "depth-sort split pieces",
                self.polys.len() as u64,
                bytes,
            ));
            return None;
        }
        let plane = self.polys[by as usize].plane;
        let eps = self.polys[by as usize].eps.max(self.polys[i as usize].eps);
        let parent = self.polys[i as usize];
        let mut eye = std::mem::take(&mut self.scratch);
        eye.clear();
        eye.extend(self.vertices(i).iter().map(|v| v.eye));
        let split = split_polygon(&eye, &plane, eps);
        let result = match split {
            Split::Spanning { front, back } => {
                Some([(front, true), (back, false)].map(|(piece, side)| {
                    let cut = self.rays.cut(&parent.plane, &plane, side);
                    self.push_piece(&parent, &eye, &piece, cut)
                }))
            }
            _ => None,
        };
        self.scratch = eye;
        result
    }

    /// The bytes the set's vectors hold (by capacity; the coverages' spans are not
    /// counted).
    fn bytes(&self) -> u64 {
        fn b<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * size_of::<T>()) as u64
        }
        b(&self.polys) + b(&self.verts) + b(&self.depth_planes) + b(&self.cuts) + b(&self.coverages)
    }

    fn push_piece(
        &mut self,
        parent: &Poly,
        parent_eye: &[DVec3],
        piece: &[DVec3],
        cut: ScreenCut,
    ) -> u32 {
        let start = self.verts.len() as u32;
        let t = self.transform;
        for &e in piece {
            let v = match parent_eye.iter().position(|&p| p == e) {
                Some(j) => self.verts[(parent.start as usize) + j],
                // Inside the view volume up to rounding (a convex combination of
                // vertices inside it), so no clipping is needed.
                None => t.to_screen(t.eye_to_clip(e), e),
            };
            self.verts.push(v);
        }
        let (dmin, dmax) = depth_extent(piece);
        let cut_start = self.cuts.len() as u32;
        let inherited = parent.cut_start as usize..(parent.cut_start + parent.cut_len) as usize;
        self.cuts.extend_from_within(inherited);
        self.cuts.push(cut);
        let region = piece_region(
            &self.verts[start as usize..],
            f64::from(self.width),
            f64::from(self.height),
        );
        self.polys.push(Poly {
            start,
            len: piece.len() as u32,
            rect: region,
            dmin,
            dmax,
            cut_start,
            cut_len: parent.cut_len + 1,
            ..*parent
        });
        (self.polys.len() - 1) as u32
    }

    /// The coverage of the whole view polygon polygon `i` is (a piece of).
    fn whole_coverage(&self, i: u32) -> Option<&PolygonCoverage> {
        let root = self.polys[i as usize].root;
        self.coverages[root as usize]
            .get_or_init(|| {
                let screen: Vec<(f64, f64)> =
                    self.vertices(root).iter().map(|v| (v.x, v.y)).collect();
                PolygonCoverage::new(&screen, self.fill, self.width, self.height)
            })
            .as_ref()
    }
}

/// Whether the viewpoint (the eye-space origin, or infinity along +z for parallel
/// projections) is on the plane's positive side.
fn facing_viewer(plane: &Plane, orthographic: bool) -> bool {
    if orthographic {
        plane.normal.z >= 0.0
    } else {
        plane.d >= 0.0
    }
}

fn depth_extent(eye: &[DVec3]) -> (f64, f64) {
    eye.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(-p.z), hi.max(-p.z))
        })
}

/// Convex polygon `a` clipped by the edges of convex polygon `b` (Sutherland-Hodgman
/// in the plane), as screen points.
fn overlap_region(a: &[ViewVertex], b: &[ViewVertex]) -> Vec<(f64, f64)> {
    let mut poly: Vec<(f64, f64)> = a.iter().map(|v| (v.x, v.y)).collect();
    let n = b.len();
    let mut area2 = 0.0;
    for k in 0..n {
        let (p, q) = (&b[k], &b[(k + 1) % n]);
        area2 += p.x * q.y - q.x * p.y;
    }
    if area2 == 0.0 {
        return Vec::new();
    }
    let sign = area2.signum();
    let mut out = Vec::with_capacity(poly.len() + n);
    for k in 0..n {
        let (p, q) = (&b[k], &b[(k + 1) % n]);
        // Positive inside (left of p -> q for a positive area).
        let inside = |v: (f64, f64)| sign * ((q.x - p.x) * (v.1 - p.y) - (q.y - p.y) * (v.0 - p.x));
        out.clear();
        for i in 0..poly.len() {
            let (u, w) = (poly[i], poly[(i + 1) % poly.len()]);
            let (du, dw) = (inside(u), inside(w));
            if du >= 0.0 {
                out.push(u);
            }
            if (du >= 0.0) != (dw >= 0.0) {
                let t = du / (du - dw);
                out.push((u.0 + (w.0 - u.0) * t, u.1 + (w.1 - u.1) * t));
            }
        }
        std::mem::swap(&mut poly, &mut out);
        if poly.len() < 3 {
            return Vec::new();
        }
    }
    poly
}

/// Whether an edge line of convex polygon `a` has all of `b` on its outer side, at
/// least `gap` beyond it (relative to the screen coordinates). With a negative gap
/// ([`TOUCH`]), touching counts as separated (within a margin far above rounding):
/// polygons that meet only along a line share no pixel sample except samples exactly
/// on that line, which the coverage rule gives to one of them (or, for edges with
/// different endpoints, decides by rounding: a near tie). Pieces, which may paint
/// such samples on their own edges, are separated only by a gap ([`GAP`]).
fn separated(a: &[ViewVertex], b: &[ViewVertex], gap: f64) -> bool {
    let n = a.len();
    // Orientation of `a` (screen y is down, either winding is possible).
    let mut area2 = 0.0;
    for k in 0..n {
        let (p, q) = (&a[k], &a[(k + 1) % n]);
        area2 += p.x * q.y - q.x * p.y;
    }
    if area2 == 0.0 {
        return false;
    }
    let scale = a
        .iter()
        .chain(b)
        .fold(1.0f64, |m, v| m.max(v.x.abs()).max(v.y.abs()));
    for k in 0..n {
        let (p, q) = (&a[k], &a[(k + 1) % n]);
        // Outward normal of edge p -> q.
        let (nx, ny) = if area2 > 0.0 {
            (q.y - p.y, p.x - q.x)
        } else {
            (p.y - q.y, q.x - p.x)
        };
        let len = (nx * nx + ny * ny).sqrt();
        if len == 0.0 {
            continue;
        }
        let margin = gap * scale * len;
        let amax = a.iter().fold(f64::NEG_INFINITY, |m, v| {
            m.max(nx * (v.x - p.x) + ny * (v.y - p.y))
        });
        let bmin = b.iter().fold(f64::INFINITY, |m, v| {
            m.min(nx * (v.x - p.x) + ny * (v.y - p.y))
        });
        if bmin >= amax + margin {
            return true;
        }
    }
    false
}

/// Polygons within this much of touching (relative to the screen coordinates) are
/// [`separated`] (the coverage rule gives samples on a shared edge to one of them).
const TOUCH: f64 = 1e-9;

/// The gap that separates a piece from another polygon: far above the distance by
/// which the samples a piece paints can lie outside its own vertices' polygon.
const GAP: f64 = 1e-6;

/// Screen tiles listing the polygons whose pixel box touches them, to find the
/// polygons that may overlap a given one without looking at all.
pub(super) struct TileGrid {
    tile: u32,
    columns: u32,
    rows: u32,
    cells: Vec<Vec<u32>>,
    seen: Vec<u32>,
    stamp: u32,
}

impl TileGrid {
    /// Tiles of `tile` pixels over a `width x height` image.
    pub fn new(width: u32, height: u32, tile: u32) -> Self {
        let tile = tile.max(1);
        let columns = width.div_ceil(tile).max(1);
        let rows = height.div_ceil(tile).max(1);
        TileGrid {
            tile,
            columns,
            rows,
            cells: vec![Vec::new(); (columns * rows) as usize],
            seen: Vec::new(),
            stamp: 0,
        }
    }

    /// A grid whose tiles are about twice the typical polygon box (the median side),
    /// a power of two from 8 to 128 pixels: small enough that a tile holds few
    /// polygons, large enough that a polygon touches few tiles.
    pub fn for_polygons(width: u32, height: u32, polys: &[Poly]) -> Self {
        let mut sides: Vec<u32> = polys
            .iter()
            .map(|p| (p.rect.x1 - p.rect.x0).max(p.rect.y1 - p.rect.y0))
            .collect();
        let tile = if sides.is_empty() {
            32
        } else {
            let mid = sides.len() / 2;
            let (_, &mut median, _) = sides.select_nth_unstable(mid);
            (2 * median).next_power_of_two().clamp(8, 128)
        };
        Self::new(width, height, tile)
    }

    fn tiles(&self, r: &PixelRect) -> (u32, u32, u32, u32) {
        if r.is_empty() {
            return (0, 0, 0, 0);
        }
        (
            r.x0 / self.tile,
            r.y0 / self.tile,
            ((r.x1 - 1) / self.tile + 1).min(self.columns),
            ((r.y1 - 1) / self.tile + 1).min(self.rows),
        )
    }

    /// Registers polygon `i` with pixel box `r`, keeping every tile's list in
    /// ascending `key` order (ties: later insertions last).
    pub fn insert(&mut self, i: u32, r: &PixelRect, key: impl Fn(u32) -> f64) {
        let (tx0, ty0, tx1, ty1) = self.tiles(r);
        let k = key(i);
        for ty in ty0..ty1 {
            for tx in tx0..tx1 {
                let cell = &mut self.cells[(ty * self.columns + tx) as usize];
                if cell.last().is_none_or(|&j| key(j) <= k) {
                    cell.push(i);
                } else {
                    let at = cell.partition_point(|&j| key(j) <= k);
                    cell.insert(at, i);
                }
            }
        }
    }

    /// The polygons registered in the tiles `r` touches for which `alive` holds, each
    /// once, into `out`. In each tile the scan stops at the first polygon for which
    /// `stop` holds (lists are in key order, so a bound on the key ends a tile).
    /// Entries for which `alive` is false are dropped from the tiles scanned.
    pub fn query(
        &mut self,
        r: &PixelRect,
        alive: impl Fn(u32) -> bool,
        stop: impl Fn(u32) -> bool,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.seen.iter_mut().for_each(|s| *s = 0);
            self.stamp = 1;
        }
        let (tx0, ty0, tx1, ty1) = self.tiles(r);
        for ty in ty0..ty1 {
            for tx in tx0..tx1 {
                let cell = &mut self.cells[(ty * self.columns + tx) as usize];
                // Drop dead entries from the part scanned, keeping the order.
                let mut keep = 0;
                let mut scan = 0;
                while scan < cell.len() {
                    let i = cell[scan];
                    scan += 1;
                    if !alive(i) {
                        continue;
                    }
                    cell[keep] = i;
                    keep += 1;
                    if stop(i) {
                        break;
                    }
                    let k = i as usize;
                    if k >= self.seen.len() {
                        self.seen.resize(k + 1, 0);
                    }
                    if self.seen[k] != self.stamp {
                        self.seen[k] = self.stamp;
                        out.push(i);
                    }
                }
                if keep < scan {
                    cell.drain(keep..scan);
                }
            }
        }
    }
}
