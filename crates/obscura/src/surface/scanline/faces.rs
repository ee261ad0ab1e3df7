//! The faces under the scanline, and the active edge list grouped by face.
//!
//! A face is *live* from the row its first edge enters the active edge list to the
//! row its last edge leaves it. Each live face is one [`ScanFace`] in a dense list that
//! the scan sweeps once per row, in memory order: the face's active edges (at most
//! four for a convex polygon: one or two per side, two only on a row through a vertex)
//! are stored in it, so settling their crossings and folding them into the face's span
//! touches no other memory. A face that would need more (a polygon made non-convex by
//! rounding) has its span taken from the shared coverage rule on every row instead.
//!
//! Each face also has a *slot*, a small stable number that the walk, the set of faces
//! whose flag is in and the remembered spans of `coherence` use, with the data read
//! rarely (the edge functions, for crossings too near a pixel centre, span checks and
//! fallbacks; the plane and box, for pixel-by-pixel decisions and order checks). A slot
//! freed on a row becomes reusable only from the next row on: a slot named by the
//! previous row's remembered spans then still holds the same face, or none.
//!
//! Setting a face up allocates nothing for triangles, quads and clipped polygons up to
//! 16 vertices (the shared [`TriangleSetup`] and [`PolygonSetup`], which give exactly
//! [`crate::raster::PolygonCoverage`]'s edges and box); bigger polygons go through
//! `PolygonCoverage` itself.

use super::edge_table::{ScanEdge, tolerance};
use crate::raster::{
    DepthPlane, EdgeFunction, FillRule, PixelRect, PolygonCoverage, PolygonSetup, TriangleSetup,
    round_down, round_up,
};
use crate::view::PreparedView;

/// `slot_of` for a polygon that is not live.
pub(crate) const NONE: u32 = u32::MAX;
/// `slot_of` for a polygon that covers nothing (no coverage or no finite depth plane).
pub(crate) const DEAD: u32 = u32::MAX - 1;
/// Edge functions kept inline per slot; more go to the slot's overflow vector.
const INLINE_EDGES: usize = 4;
/// Active edges a face holds.
pub(crate) const FACE_EDGES: usize = 2;

/// A live face and its active edges (the fields the sweep reads first come first).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanFace {
    /// Number of active edges.
    pub count: u32,
    /// The smallest last row of its active edges: before it, none leaves.
    pub edges_until: u32,
    /// Its sample box columns `x0..x1`: crossings are clamped to them.
    pub x0: u32,
    /// One past the last column of the sample box.
    pub x1: u32,
    /// The rows `check_from..check_to` on which its span must be checked against its
    /// edges that are not active (elsewhere they are proven to hold, see
    /// [`triangle_check_rows`]).
    pub check_from: u32,
    /// One past the last row to check.
    pub check_to: u32,
    /// Its slot.
    pub slot: u32,
    /// More active edges than it can hold: its span comes from the coverage rule, up
    /// to the last row of its box.
    pub overflow: bool,
    /// Its active edges, the first `count`.
    pub edges: [ScanEdge; FACE_EDGES],
    /// The last row of its sample box.
    pub last_row: u32,
}

impl ScanFace {
    /// Drops the active edges that ended before row `y`.
    #[inline]
    pub fn drop_ended(&mut self, y: u32) {
        if y <= self.edges_until {
            return;
        }
        let mut n = 0;
        let mut until = u32::MAX;
        for j in 0..self.count as usize {
            let e = self.edges[j];
            if e.last_row >= y {
                self.edges[n] = e;
                n += 1;
                until = until.min(e.last_row);
            }
        }
        self.count = n as u32;
        self.edges_until = until;
    }
}

/// What is read of a face by slot.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FaceInfo {
    /// Its depth key as an affine function of screen position.
    pub plane: DepthPlane,
    /// Its sample box.
    pub rect: PixelRect,
    /// Scene-wide face id (written to the frame).
    pub face: u32,
    /// Index in the view: identity and tie-break order.
    pub polygon: u32,
}

/// The edge functions of the faces, by slot.
#[derive(Debug, Default)]
pub(crate) struct EdgeStore {
    /// `INLINE_EDGES` per slot.
    inline: Vec<EdgeFunction>,
    /// Per slot: the edge functions of polygons with more than `INLINE_EDGES`.
    overflow: Vec<Vec<EdgeFunction>>,
    /// Per slot: for polygons that are not triangles, the edge function index of each
    /// vertex pair (`NONE` for a zero-length pair).
    pair_edge: Vec<Vec<u32>>,
    count: Vec<u32>,
}

impl EdgeStore {
    /// The edge functions of the face in slot `s`.
    #[inline(always)]
    pub fn of(&self, s: u32) -> &[EdgeFunction] {
        let n = self.count[s as usize] as usize;
        if n <= INLINE_EDGES {
            let a = s as usize * INLINE_EDGES;
            &self.inline[a..a + n]
        } else {
            &self.overflow[s as usize]
        }
    }

    /// The index among the face's edge functions of the edge from vertex `pair` to
    /// the next, `None` for a zero-length pair.
    #[inline]
    pub fn edge_of_pair(&self, s: u32, pair: u32) -> Option<u32> {
        let map = &self.pair_edge[s as usize];
        if map.is_empty() {
            // A triangle: its three pairs are its three edges.
            return Some(pair);
        }
        map.get(pair as usize).copied().filter(|&k| k != NONE)
    }

    /// The vertex pair of the face's edge function `k`.
    pub fn pair_of_edge(&self, s: u32, k: u32) -> u32 {
        let map = &self.pair_edge[s as usize];
        if map.is_empty() {
            k
        } else {
            map.iter().position(|&e| e == k).unwrap_or(0) as u32
        }
    }

    fn grow(&mut self) {
        self.inline
            .extend_from_slice(&[EdgeFunction::UNSET; INLINE_EDGES]);
        self.overflow.push(Vec::new());
        self.pair_edge.push(Vec::new());
        self.count.push(0);
    }

    fn store(&mut self, s: usize, edges: &[EdgeFunction]) {
        if edges.len() <= INLINE_EDGES {
            let a = s * INLINE_EDGES;
            self.inline[a..a + edges.len()].copy_from_slice(edges);
        } else {
            self.overflow[s].clear();
            self.overflow[s].extend_from_slice(edges);
        }
        self.count[s] = edges.len() as u32;
    }
}

/// The live faces and their slots.
#[derive(Debug)]
pub(crate) struct Faces {
    /// Per polygon of the view: its slot, [`NONE`] or [`DEAD`].
    pub slot_of: Vec<u32>,
    /// The live faces, in no order.
    pub list: Vec<ScanFace>,
    /// Per slot: its face's place in `list`.
    list_index: Vec<u32>,
    /// Per slot: identity, plane and box.
    pub info: Vec<FaceInfo>,
    /// Per slot: its place in the set of faces whose flag is in, or [`NONE`].
    pub position: Vec<u32>,
    /// Per slot: the edge functions.
    pub edges: EdgeStore,
    free: Vec<u32>,
    pending: Vec<u32>,
    fill: FillRule,
    width: u32,
    height: u32,
    /// The `y` of the vertices of the last face set up, when it is a triangle.
    pub triangle_ys: Option<[f64; 3]>,
}

const NO_PLANE: DepthPlane = DepthPlane {
    x0: 0.0,
    y0: 0.0,
    z0: 0.0,
    dzdx: 0.0,
    dzdy: 0.0,
};

/// The contribution of the face in slot `slot` to the order-independent hash of a set
/// of faces (a slot names the same face from one row to the next, see the module doc).
#[inline(always)]
pub(crate) fn slot_hash(slot: u32) -> u64 {
    // One multiplication spreads the bits enough: a set found by its hash is
    // confirmed member by member anyway.
    (u64::from(slot) + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

fn finite(p: &DepthPlane) -> bool {
    [p.x0, p.y0, p.z0, p.dzdx, p.dzdy]
        .iter()
        .all(|v| v.is_finite())
}

/// The rows on which a triangle's span must be checked against its edge that is not
/// active there, as `from..to`; on every other row the check is proven to pass.
///
/// With the vertices `A`, `B`, `C` in `y` order, a row above `B` has edges `AB` and
/// `AC` active and `BC` not; there every point `P` of the triangle on the row has
/// `e_BC(P) >= (yB - y) / (yB - yA) |2 area|` (its barycentric weight of `A` is at
/// least that, and `e_BC(A) = 2 area`); below `B`, symmetrically, `e_AB(P) >= (y - yB) /
/// (yC - yB) |2 area|`. A span end is inside the active edges by their shared test, so
/// within `t` pixels (their crossings' tolerance, see [`tolerance`]) of the triangle,
/// where the inactive edge's function is lower by at most `|dy| t`; and the shared test
/// evaluates it with an error below `16 eps (|dx| h + |dy| w)` for a box of `w x h`.
/// The check can only fail where the bound does not exceed both: within `eps` of `yB`.
/// The tolerance `t` is taken for a steepest edge spanning the whole box (larger than
/// each edge's own).
fn triangle_check_rows(p: [(f64, f64, f64); 3], area2: f64, rows: u32) -> (u32, u32) {
    let [p0, p1, p2] = p;
    // The vertices in y order, by three compare-exchanges.
    let (a, b) = if p1.1 < p0.1 { (p1, p0) } else { (p0, p1) };
    let (b, c) = if p2.1 < b.1 { (p2, b) } else { (b, p2) };
    let (a, b) = if b.1 < a.1 { (b, a) } else { (a, b) };
    let (minx, maxx) = (p0.0.min(p1.0).min(p2.0), p0.0.max(p1.0).max(p2.0));
    let (w, h) = (maxx - minx + 2.0, c.1 - a.1 + 2.0);
    let (ab, bc, ca) = (
        ((b.0 - a.0).abs(), b.1 - a.1),
        ((c.0 - b.0).abs(), c.1 - b.1),
        ((a.0 - c.0).abs(), c.1 - a.1),
    );
    // The steepest slope: the widest run over the shortest non-zero rise (`ca` is the
    // longest rise, non-zero for a triangle with an area).
    let rise =
        ca.1.min(if ab.1 > 0.0 { ab.1 } else { ca.1 })
            .min(if bc.1 > 0.0 { bc.1 } else { ca.1 });
    let steep = ab.0.max(bc.0).max(ca.0) / rise;
    let reach = minx.abs().max(maxx.abs()) + (maxx - minx) + 2.0;
    let edge = EdgeFunction {
        ox: reach,
        oy: 0.0,
        dx: 0.0,
        dy: h,
        sign: 1.0,
        include_zero: false,
    };
    let t = tolerance(&edge, steep, rows);
    let bound = |(dx, dy): (f64, f64)| dy * t + 16.0 * f64::EPSILON * (dx * h + dy * w);
    let above = ab.1 * bound(bc) / area2.abs();
    let below = bc.1 * bound(ab) / area2.abs();
    let eps = 2.0 * above.max(below) + 1e-9;
    if !(eps < 1e6 && b.1.abs() < 1e9) {
        return (0, u32::MAX);
    }
    let from = round_up(b.1 - eps - 0.5).max(0.0);
    let to = (round_down(b.1 + eps - 0.5) + 1.0).max(0.0);
    (from as u32, to as u32)
}

impl Faces {
    /// No face live, for a view of `polygons` polygons on a `width x height` image.
    pub fn new(polygons: usize, fill: FillRule, width: u32, height: u32) -> Self {
        Faces {
            slot_of: vec![NONE; polygons],
            list: Vec::new(),
            list_index: Vec::new(),
            info: Vec::new(),
            position: Vec::new(),
            edges: EdgeStore::default(),
            free: Vec::new(),
            pending: Vec::new(),
            fill,
            width,
            height,
            triangle_ys: None,
        }
    }

    /// Sets up `polygon` of the view in a free slot and adds it to the live faces,
    /// without edges yet. Returns the slot, or [`DEAD`] (remembered) if it covers
    /// nothing.
    #[inline]
    pub fn activate(&mut self, view: &PreparedView<'_>, polygon: u32) -> u32 {
        let poly = view.polygon(polygon as usize);
        let n = poly.len();
        let vertex = |k: usize| {
            let v = poly.vertex(k);
            (v.x, v.y, v.zq)
        };
        let s = self.free.pop().unwrap_or_else(|| {
            let s = self.info.len() as u32;
            self.info.push(FaceInfo {
                plane: NO_PLANE,
                rect: PixelRect {
                    x0: 0,
                    y0: 0,
                    x1: 0,
                    y1: 0,
                },
                face: 0,
                polygon: 0,
            });
            self.position.push(NONE);
            self.list_index.push(NONE);
            self.edges.grow();
            s
        });
        let si = s as usize;
        self.edges.pair_edge[si].clear();
        let (w, h, fill) = (self.width, self.height, self.fill);
        let mut check = (0, u32::MAX);
        self.triangle_ys = None;
        let set = if n == 3 {
            let p = [vertex(0), vertex(1), vertex(2)];
            self.triangle_ys = Some([p[0].1, p[1].1, p[2].1]);
            TriangleSetup::new(p, fill, w, h).map(|TriangleSetup { edges, rect, plane }| {
                self.edges.store(si, &edges);
                let area2 =
                    (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0);
                check = triangle_check_rows(p, area2, rect.y1 - rect.y0);
                (rect, plane)
            })
        } else if PolygonSetup::<16>::fits(n) {
            let mut points = [(0.0, 0.0, 0.0); 16];
            for (k, p) in points[..n].iter_mut().enumerate() {
                *p = vertex(k);
            }
            let mut setup = PolygonSetup::<16>::new();
            if setup.set(&points[..n], fill, w, h) {
                self.edges.store(si, setup.edges());
                setup.depth_plane().map(|p| (setup.rect(), p))
            } else {
                None
            }
        } else {
            let xy: Vec<(f64, f64)> = poly.vertices().map(|v| (v.x, v.y)).collect();
            let xyz: Vec<(f64, f64, f64)> = poly.vertices().map(|v| (v.x, v.y, v.zq)).collect();
            match (
                PolygonCoverage::new(&xy, fill, w, h),
                DepthPlane::from_points(&xyz),
            ) {
                (Some(c), Some(p)) => {
                    self.edges.store(si, c.edges());
                    Some((c.rect(), p))
                }
                _ => None,
            }
        };
        let Some((rect, plane)) = set.filter(|(_, p)| finite(p)) else {
            self.free.push(s);
            self.slot_of[polygon as usize] = DEAD;
            return DEAD;
        };
        if n != 3 {
            // The setups made one edge function per pair of distinct consecutive points.
            let map = &mut self.edges.pair_edge[si];
            let mut k = 0;
            for i in 0..n {
                let (p, q) = (poly.vertex(i), poly.vertex((i + 1) % n));
                if (p.x, p.y) == (q.x, q.y) {
                    map.push(NONE);
                } else {
                    map.push(k);
                    k += 1;
                }
            }
            debug_assert_eq!(k, self.edges.count[si]);
        }
        self.info[si] = FaceInfo {
            plane,
            rect,
            face: poly.face,
            polygon,
        };
        self.position[si] = NONE;
        self.list_index[si] = self.list.len() as u32;
        self.list.push(ScanFace {
            count: 0,
            edges_until: u32::MAX,
            x0: rect.x0,
            x1: rect.x1,
            check_from: check.0,
            check_to: check.1,
            slot: s,
            overflow: false,
            edges: [ScanEdge::NONE; FACE_EDGES],
            last_row: rect.y1 - 1,
        });
        self.slot_of[polygon as usize] = s;
        s
    }

    /// Adds an edge starting on row `y` to the live face in slot `s` (after dropping
    /// its edges that ended on the previous row: where one edge of a side ends and the
    /// next begins, the face then holds one edge per side).
    #[inline]
    pub fn add_edge(&mut self, s: u32, y: u32, edge: ScanEdge) {
        let f = &mut self.list[self.list_index[s as usize] as usize];
        f.drop_ended(y);
        if (f.count as usize) < FACE_EDGES {
            f.edges[f.count as usize] = edge;
            f.count += 1;
            f.edges_until = f.edges_until.min(edge.last_row);
        } else {
            f.overflow = true;
        }
    }
    /// The face at `list[i]` is no longer live: its slot is freed (reusable from the
    /// next row on) and the last face takes its place in the list.
    #[inline]
    pub fn retire(&mut self, i: usize) {
        let s = self.list[i].slot;
        self.slot_of[self.info[s as usize].polygon as usize] = NONE;
        self.pending.push(s);
        self.list.swap_remove(i);
        if let Some(moved) = self.list.get(i) {
            self.list_index[moved.slot as usize] = i as u32;
        }
    }

    /// End of a row: slots freed on it become reusable (see the module doc).
    pub fn end_row(&mut self) {
        self.free.append(&mut self.pending);
    }
}
