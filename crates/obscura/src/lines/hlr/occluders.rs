//! The occluders of one view: every polygon the view keeps (clipped to the view
//! volume by the pipeline, back faces of closed objects left out), with the planes
//! that bound the region it hides, and a screen grid to find them by.
//!
//! A convex polygon `P` hides the point `X` when `X` lies in the closed cone from the
//! eye through `P` (inside every *side plane*, spanned by the eye and one edge of `P`;
//! in an orthographic view the side planes hold the view direction instead) and
//! strictly behind the plane of `P`. Every such test is the sign of a function linear
//! along an edge, so the part of an edge a polygon hides is one parameter interval
//! ([`super::cut`]).
//!
//! Signs come from a floating-point evaluation with a forward error bound; when the
//! value is within the bound, from the exact predicates of the `robust` crate
//! (Shewchuk's adaptive `orient3d`, `orient2d`). A side shared by two polygons is
//! evaluated from the same ordered pair of vertices in both, so the two compute exactly
//! opposite values: no point of an edge falls between them, none is in both interiors.

use glam::{DVec3, DVec4};

use crate::view::View;

/// Relative forward error bound of the floating-point plane values (far above the few
/// units in the last place the evaluations can lose); values closer to zero than this
/// fraction of their absolute sum are decided exactly.
const FILTER: f64 = 1e-12;

/// An oriented plane through three world points `p`, as a function of the point `x`:
/// `((p1 - p0) x (p2 - p0)) . (x - p0)` (that is `-orient3d(p0, p1, p2, x)`), times
/// `sign`. Side planes, polygon planes: every test is one of these.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane3 {
    p: [DVec3; 3],
    n: DVec3,
    /// The absolute values the filter's bound is made of.
    nabs: DVec3,
    /// +1 or -1.
    sign: f64,
}

impl Plane3 {
    fn new(p: [DVec3; 3], sign: f64) -> Plane3 {
        let (u, v) = (p[1] - p[0], p[2] - p[0]);
        Plane3 {
            p,
            n: u.cross(v),
            nabs: DVec3::new(
                (u.y * v.z).abs() + (u.z * v.y).abs(),
                (u.z * v.x).abs() + (u.x * v.z).abs(),
                (u.x * v.y).abs() + (u.y * v.x).abs(),
            ),
            sign,
        }
    }

    /// The plane's value at `x`: exact in sign (0 exactly on the plane), affine in `x`.
    #[inline]
    pub fn value(&self, x: DVec3, counters: &mut PredicateCounters) -> f64 {
        let d = x - self.p[0];
        let v = self.n.dot(d);
        if v.abs() > FILTER * self.nabs.dot(d.abs()) {
            return self.sign * v;
        }
        // A point that defines the plane (a vertex shared by the edge and the occluder)
        // is on it: the exact predicate would reach the same 0 by its slowest path.
        if x == self.p[0] || x == self.p[1] || x == self.p[2] {
            return 0.0;
        }
        counters.exact += 1;
        self.sign * plane_exact(&self.p, x)
    }
}

/// One occluding polygon.
#[derive(Clone, Copy, Debug)]
pub(super) struct Occluder {
    /// Its scene polygon number.
    pub polygon: u32,
    /// Its face id (a face split into several convex polygons counts once).
    pub face: u32,
    /// Its side planes: `sides[first..first + count]`, positive inside.
    pub first: u32,
    pub count: u32,
    /// Its plane, positive strictly behind it (seen from the eye).
    pub plane: Plane3,
    /// Screen box in pixels: min x, min y, max x, max y.
    pub bbox: [f64; 4],
    /// Its smallest eye-space depth.
    pub near_depth: f64,
}

/// Counts of the exact fallbacks, for the statistics.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PredicateCounters {
    pub exact: u64,
}

/// The occluders of a view and the screen grid that finds them.
#[derive(Debug)]
pub(super) struct Occluders {
    pub list: Vec<Occluder>,
    /// Per occluder, its screen box and nearest depth (`[min x, min y, max x, max y,
    /// depth]`), apart from the rest so that the filters read only these.
    pub bounds: Vec<[f64; 5]>,
    pub sides: Vec<Plane3>,
    /// Grid: cell size in pixels, columns, rows, CSR starts and occluder numbers.
    pub cell: f64,
    pub columns: usize,
    pub rows: usize,
    pub starts: Vec<u32>,
    pub items: Vec<u32>,
    /// Polygons left out: degenerate or seen exactly edge-on (no area in the image).
    pub edge_on: u64,
}

/// `((p1 - p0) x (p2 - p0)) . (x - p0)`, exact in sign.
fn plane_exact(p: &[DVec3; 3], x: DVec3) -> f64 {
    // orient3d(a, b, c, x) = det[a - x; b - x; c - x] = -((b - a) x (c - a)) . (x - a).
    -crate::geom::orient3d(p[0], p[1], p[2], x)
}

/// How the eye sees: from a point, or along a direction.
#[derive(Clone, Copy, Debug)]
pub(super) enum Eye {
    /// Perspective: the eye's world position.
    Point(DVec3),
    /// Orthographic: the viewing direction (world).
    Direction(DVec3),
}

impl Eye {
    /// The side plane through the occluder edge `a -> b`, whose value is positive on
    /// the left of the edge's image (as `inside` says) and 0 on the plane through the
    /// eye (or holding the view direction) and the edge. The edge is taken in a
    /// canonical order, so two polygons sharing it compute exactly opposite values.
    fn side(self, a: DVec3, b: DVec3, inside: f64) -> Plane3 {
        let (a, b, sign) = if (a.x, a.y, a.z) <= (b.x, b.y, b.z) {
            (a, b, inside)
        } else {
            (b, a, -inside)
        };
        match self {
            Eye::Point(e) => Plane3::new([e, a, b], sign),
            Eye::Direction(d) => Plane3::new([a, b, a + d], sign),
        }
    }
}

impl Occluders {
    /// The occluders of a view: the polygons of the kept objects less the view's back
    /// faces, clipped by the near plane, those wholly outside another plane of the view
    /// volume left out; and a grid of cells about 1.5 times the median polygon's size.
    pub fn new(view: &View<'_>) -> Occluders {
        let t = view.transform();
        let camera = view.camera();
        let eye = if t.orthographic {
            Eye::Direction(camera.basis().2)
        } else {
            Eye::Point(camera.eye)
        };
        let scene = view.scene();
        let back = view.back_facing();
        let mut list = Vec::new();
        let mut sides = Vec::new();
        let mut edge_on = 0;
        let mut world: Vec<DVec3> = Vec::new();
        let mut clip: Vec<DVec4> = Vec::new();
        let mut pts: Vec<(DVec3, DVec4)> = Vec::new();
        let mut clipped: Vec<(DVec3, DVec4)> = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            if !view.kept_objects()[k] {
                continue;
            }
            world.clear();
            world.extend(
                o.mesh
                    .positions()
                    .iter()
                    .map(|&p| o.transform.transform_point3(p)),
            );
            clip.clear();
            clip.extend(world.iter().map(|&w| t.world_to_clip(w)));
            let base = view.polygon_base()[k];
            for p in 0..o.mesh.polygon_count() {
                let polygon = base + p as u32;
                if back[polygon as usize] {
                    continue;
                }
                pts.clear();
                pts.extend(
                    o.mesh
                        .polygon(p)
                        .iter()
                        .map(|&i| (world[i as usize], clip[i as usize])),
                );
                if outside_a_plane(&pts) {
                    continue;
                }
                let poly: &[(DVec3, DVec4)] = if pts.iter().any(|(_, c)| c.z + c.w < 0.0) {
                    clip_near(&pts, &mut clipped);
                    &clipped
                } else {
                    &pts
                };
                let Some((plane, inside)) = plane_of(poly, eye) else {
                    edge_on += 1;
                    continue;
                };
                let first = sides.len() as u32;
                for i in 0..poly.len() {
                    let (a, b) = (poly[i].0, poly[(i + 1) % poly.len()].0);
                    if a != b {
                        sides.push(eye.side(a, b, inside));
                    }
                }
                let mut bbox = [
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ];
                let mut near_depth = f64::INFINITY;
                for (w, c) in poly {
                    let glam::DVec2 { x, y } = t.clip_to_pixel(*c);
                    bbox = [
                        bbox[0].min(x),
                        bbox[1].min(y),
                        bbox[2].max(x),
                        bbox[3].max(y),
                    ];
                    near_depth = near_depth.min(-t.world_to_eye(*w).z);
                }
                list.push(Occluder {
                    polygon,
                    face: o.first_face + o.mesh.polygon_face(p),
                    first,
                    count: sides.len() as u32 - first,
                    plane,
                    bbox,
                    near_depth,
                });
            }
        }
        let (width, height) = (t.width, t.height);
        let cell = cell_size(&list, width, height);
        let columns = ((width / cell).ceil() as usize).max(1);
        let rows = ((height / cell).ceil() as usize).max(1);
        let mut counts = vec![0u32; columns * rows + 1];
        let range = |o: &Occluder| {
            let c0 = ((o.bbox[0] / cell).floor().max(0.0) as usize).min(columns - 1);
            let c1 = ((o.bbox[2] / cell).floor().max(0.0) as usize).min(columns - 1);
            let r0 = ((o.bbox[1] / cell).floor().max(0.0) as usize).min(rows - 1);
            let r1 = ((o.bbox[3] / cell).floor().max(0.0) as usize).min(rows - 1);
            (c0, c1, r0, r1)
        };
        for o in &list {
            let (c0, c1, r0, r1) = range(o);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    counts[r * columns + c + 1] += 1;
                }
            }
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; *counts.last().unwrap_or(&0) as usize];
        for (n, o) in list.iter().enumerate() {
            let (c0, c1, r0, r1) = range(o);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let slot = &mut fill[r * columns + c];
                    items[*slot as usize] = n as u32;
                    *slot += 1;
                }
            }
        }
        let bounds = list
            .iter()
            .map(|o| [o.bbox[0], o.bbox[1], o.bbox[2], o.bbox[3], o.near_depth])
            .collect();
        Occluders {
            list,
            bounds,
            sides,
            cell,
            columns,
            rows,
            starts: counts,
            items,
            edge_on,
        }
    }

    /// Appends to `out` the occluders of every cell the screen segment `p -> q` passes
    /// through (with repeats; the caller sorts and removes them).
    pub fn gather(&self, p: [f64; 2], q: [f64; 2], out: &mut Vec<u32>) {
        let cell = self.cell;
        let clamp_r = |y: f64| ((y / cell).floor().max(0.0) as usize).min(self.rows - 1);
        let clamp_c = |x: f64| ((x / cell).floor().max(0.0) as usize).min(self.columns - 1);
        let (r0, r1) = (clamp_r(p[1].min(q[1])), clamp_r(p[1].max(q[1])));
        let dy = q[1] - p[1];
        let margin = 1e-6 * cell;
        for r in r0..=r1 {
            // The segment's x extent within the row band (the whole segment when one
            // band holds it).
            let (mut x0, mut x1) = (p[0].min(q[0]), p[0].max(q[0]));
            if r0 != r1 {
                let (lo, hi) = (r as f64 * cell, (r + 1) as f64 * cell);
                let ta = ((lo - p[1]) / dy).clamp(0.0, 1.0);
                let tb = ((hi - p[1]) / dy).clamp(0.0, 1.0);
                let xa = p[0] + (q[0] - p[0]) * ta;
                let xb = p[0] + (q[0] - p[0]) * tb;
                x0 = xa.min(xb);
                x1 = xa.max(xb);
            }
            let (c0, c1) = (clamp_c(x0 - margin), clamp_c(x1 + margin));
            let row = r * self.columns;
            out.extend_from_slice(
                &self.items[self.starts[row + c0] as usize..self.starts[row + c1 + 1] as usize],
            );
        }
    }

    /// The sides of occluder `o`.
    #[inline]
    pub fn sides_of(&self, o: &Occluder) -> &[Plane3] {
        &self.sides[o.first as usize..(o.first + o.count) as usize]
    }
}

/// Whether every vertex lies outside one plane of the view volume other than the near
/// plane (such a polygon hides nothing inside the volume).
fn outside_a_plane(pts: &[(DVec3, DVec4)]) -> bool {
    let tests: [fn(&DVec4) -> bool; 5] = [
        |c| c.x < -c.w,
        |c| c.x > c.w,
        |c| c.y < -c.w,
        |c| c.y > c.w,
        |c| c.z > c.w,
    ];
    tests.iter().any(|f| pts.iter().all(|(_, c)| f(c)))
}

/// The polygon clipped to `z + w >= 0` (the near side of the view volume): what of it
/// can hide anything a renderer draws. New vertices are interpolated in world space.
fn clip_near(pts: &[(DVec3, DVec4)], out: &mut Vec<(DVec3, DVec4)>) {
    out.clear();
    let f = |c: &DVec4| c.z + c.w;
    for i in 0..pts.len() {
        let (a, b) = (&pts[i], &pts[(i + 1) % pts.len()]);
        let (fa, fb) = (f(&a.1), f(&b.1));
        if fa >= 0.0 {
            out.push(*a);
        }
        if (fa >= 0.0) != (fb >= 0.0) {
            let s = fa / (fa - fb);
            out.push((a.0 + (b.0 - a.0) * s, a.1 + (b.1 - a.1) * s));
        }
    }
}

/// The plane of a convex polygon (from its first vertex and the fan triangle of
/// largest area), positive strictly behind it, and the sign of its inside for its side
/// planes; `None` when it is seen exactly edge-on (the eye, or in an orthographic view
/// the view direction, in its plane) or degenerate: then its image has no area and it
/// hides nothing.
fn plane_of(poly: &[(DVec3, DVec4)], eye: Eye) -> Option<(Plane3, f64)> {
    if poly.len() < 3 {
        return None;
    }
    let p0 = poly[0].0;
    let (mut best, mut area) = (1, 0.0);
    for k in 1..poly.len() - 1 {
        let a = (poly[k].0 - p0).cross(poly[k + 1].0 - p0).length_squared();
        if a > area {
            (best, area) = (k, a);
        }
    }
    if !(area > 0.0) {
        return None;
    }
    let p = [p0, poly[best].0, poly[best + 1].0];
    // The plane's value on the eye's side, and the orientation of the polygon's image
    // (the inside of every side plane: the value of the side plane of p0 -> p1 at p2).
    let (eye_side, inside) = match eye {
        Eye::Point(e) => (plane_exact(&p, e), plane_exact(&[e, p[0], p[1]], p[2])),
        Eye::Direction(d) => (
            plane_exact(&p, p0 - d),
            plane_exact(&[p[0], p[1], p[0] + d], p[2]),
        ),
    };
    if eye_side == 0.0 || inside == 0.0 || !(eye_side.is_finite() && inside.is_finite()) {
        return None;
    }
    Some((Plane3::new(p, -eye_side.signum()), inside.signum()))
}

/// A cell size in pixels: 1.5 times the median of the occluders' larger screen extents
/// (over a sample), between 2 and 256 pixels, and no more than about 4 million cells.
fn cell_size(list: &[Occluder], width: f64, height: f64) -> f64 {
    let step = (list.len() / 4096).max(1);
    let mut sizes: Vec<f64> = list
        .iter()
        .step_by(step)
        .map(|o| (o.bbox[2] - o.bbox[0]).max(o.bbox[3] - o.bbox[1]))
        .filter(|s| s.is_finite())
        .collect();
    let median = if sizes.is_empty() {
        64.0
    } else {
        let mid = sizes.len() / 2;
        *sizes.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let min_for_cells = (width * height / 4.0e6).sqrt();
    (1.5 * median).clamp(2.0, 256.0).max(min_for_cells)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn fast_values_agree_in_sign_with_exact_predicates() {
        let mut rng = SplitMix64(5);
        let mut r = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - 2.0;
        let mut c = PredicateCounters::default();
        for _ in 0..3000 {
            let (a, b, e, x) = (r(), r(), r(), r());
            let plane = Plane3::new([e, a, b], 1.0);
            let v = plane.value(x, &mut c);
            let plain = (a - e).cross(b - e).dot(x - e);
            assert!(
                (v - plain).abs() <= 1e-9 * (1.0 + plain.abs()),
                "{v} {plain}"
            );
            assert_eq!(plane_exact(&[e, a, b], x).signum(), v.signum());
            // A point exactly on the plane (one of its points) is 0 exactly.
            assert_eq!(plane.value(a, &mut c), 0.0);
        }
        // Collinear with an edge, but with no exact float: decided exactly.
        let (a, b) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.7, 1.1, 0.9));
        let x = a + (b - a) * 3.0;
        let plane = Plane3::new([DVec3::new(5.0, -1.0, 2.0), a, b], 1.0);
        let v = plane.value(x, &mut c);
        assert_eq!(v.signum(), plane_exact(&plane.p, x).signum());
    }

    #[test]
    fn shared_sides_compute_opposite_values() {
        let (a, b) = (DVec3::new(0.1, 0.3, -2.0), DVec3::new(0.7, -0.2, -3.0));
        let x = DVec3::new(0.4, 0.05, -2.5);
        let mut c = PredicateCounters::default();
        for eye in [
            Eye::Point(DVec3::new(0.3, 0.1, 4.0)),
            Eye::Direction(DVec3::new(0.1, 0.2, -1.0)),
        ] {
            let (s, t) = (eye.side(a, b, 1.0), eye.side(b, a, 1.0));
            assert_eq!(s.value(x, &mut c), -t.value(x, &mut c));
        }
    }

    #[test]
    fn plane_of_a_facing_triangle_puts_the_eye_in_front() {
        // A triangle at z = -1, counter-clockwise seen from the eye at z = 0 (or along
        // -z).
        let pts: Vec<(DVec3, DVec4)> = [
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(1.0, 0.0, -1.0),
            DVec3::new(0.0, 1.0, -1.0),
        ]
        .iter()
        .map(|&p| (p, DVec4::ZERO))
        .collect();
        let mut c = PredicateCounters::default();
        for eye in [Eye::Point(DVec3::ZERO), Eye::Direction(-DVec3::Z)] {
            let (plane, inside) = plane_of(&pts, eye).unwrap();
            assert!(plane.value(DVec3::new(0.2, 0.2, -2.0), &mut c) > 0.0);
            assert!(plane.value(DVec3::new(0.2, 0.2, -0.5), &mut c) < 0.0);
            assert_eq!(plane.value(DVec3::new(5.0, 3.0, -1.0), &mut c), 0.0);
            // Behind the triangle's interior: along the ray from the eye, or straight
            // behind it along the view direction.
            let centre = match eye {
                Eye::Point(_) => DVec3::new(0.3, 0.3, -1.0) * 3.0,
                Eye::Direction(_) => DVec3::new(0.3, 0.3, -4.0),
            };
            for k in 0..3 {
                let s = eye.side(pts[k].0, pts[(k + 1) % 3].0, inside);
                assert!(s.value(centre, &mut c) > 0.0, "side {k} {eye:?}");
            }
        }
        // Edge-on: the eye (origin) in the plane.
        let on: Vec<(DVec3, DVec4)> = [
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(0.0, 0.0, -2.0),
            DVec3::new(0.0, 1.0, -1.0),
        ]
        .iter()
        .map(|&p| (p, DVec4::ZERO))
        .collect();
        assert!(plane_of(&on, Eye::Point(DVec3::ZERO)).is_none());
        assert!(plane_of(&on, Eye::Direction(-DVec3::Z)).is_none());
    }
}
