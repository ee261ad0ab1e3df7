//! Splitting a convex polygon by a plane into the piece in front and the piece behind.
//!
//! Source: seed 000 ("Αλγόριθμος BSP (3)": the polygons that cross the partitioning
//! plane are split "by extending a clipping algorithm so that it returns both the
//! inside and the outside part"). This is that extension of Sutherland-Hodgman: one
//! pass over the edges, each vertex sent to the side it lies on, each crossing edge
//! contributing its intersection point to both pieces. Used by the BSP tree and by depth
//! sort when an overlap is cyclic.
//!
//! Vertices within `eps` (a distance, in the units of the points) of the plane count as
//! on it: they go to both pieces, and a polygon with all vertices on the plane is
//! coplanar, not split. Intersections are computed from the front endpoint towards the
//! back one, so two polygons sharing an edge get bit-identical new vertices.
//!
//! Papers: Sutherland and Hodgman, "Reentrant polygon clipping", CACM 17(1), 1974 (the
//! one stage extended here); Fuchs, Kedem and Naylor, "On visible surface generation by
//! a priori tree structures", SIGGRAPH 1980 (splitting by a plane).

use super::InRange;
use glam::DVec3;

use crate::geom::{Plane, PlaneSide};

/// How a polygon lies relative to a plane.
#[derive(Clone, Debug, PartialEq)]
pub enum Split {
    /// Entirely in front (vertices on the plane allowed).
    Front,
    /// Entirely behind (vertices on the plane allowed).
    Back,
    /// In the plane; `same_direction` when its normal points the plane's way.
    Coplanar {
        /// Whether the polygon faces the same way as the plane.
        same_direction: bool,
    },
    /// Crossing: the two pieces, each with at least three vertices.
    Spanning {
        /// The part on the positive side.
        front: Vec<DVec3>,
        /// The part on the negative side.
        back: Vec<DVec3>,
    },
}

/// Splits a convex polygon by a plane. See the module doc for `eps`.
///
/// Degenerate input splits nothing: a plane whose normal is zero or not finite, a
/// "polygon" of fewer than three vertices, or one with a coordinate out of range
/// (not finite or beyond [`super::MAX_CLIP_COORDINATE`]), gives [`Split::Front`]. A
/// negative or NaN `eps` counts as 0.
///
/// ```
/// use obscura::clip::split::{split_polygon, Split};
/// use obscura::geom::Plane;
/// use glam::DVec3;
/// let square = [DVec3::new(-1., -1., 0.), DVec3::new(1., -1., 0.), DVec3::new(1., 1., 0.), DVec3::new(-1., 1., 0.)];
/// let plane = Plane::from_point_normal(DVec3::ZERO, DVec3::X);
/// match split_polygon(&square, &plane, 1e-9) {
///     Split::Spanning { front, back } => { assert_eq!(front.len(), 4); assert_eq!(back.len(), 4); }
///     other => panic!("{other:?}"),
/// }
/// ```
#[must_use]
pub fn split_polygon(points: &[DVec3], plane: &Plane, eps: f64) -> Split {
    let len = plane.normal.length();
    if points.len() < 3
        || !(len > 0.0 && len.is_finite() && plane.d.is_finite())
        || points.iter().any(|p| !p.in_range())
    {
        return Split::Front;
    }
    // A negative or NaN tolerance would make a vertex both sides of the plane.
    let eps = if eps > 0.0 { eps } else { 0.0 };
    let dist: Vec<f64> = plane.signed_distances(points.iter().copied()).collect();
    let side = |d: f64| PlaneSide::of_distance(d, eps);
    match PlaneSide::of_distances(dist.iter().copied(), eps) {
        PlaneSide::On => {
            let n = crate::geom::newell_normal(points);
            return Split::Coplanar {
                same_direction: n.dot(plane.normal) >= 0.0,
            };
        }
        PlaneSide::Front => return Split::Front,
        PlaneSide::Back => return Split::Back,
        PlaneSide::Spanning => {}
    }
    let n = points.len();
    let (mut f, mut b) = (Vec::with_capacity(n + 1), Vec::with_capacity(n + 1));
    for i in 0..n {
        let j = (i + 1) % n;
        let (pi, di, si) = (points[i], dist[i], side(dist[i]));
        let sj = side(dist[j]);
        match si {
            PlaneSide::Front => f.push(pi),
            PlaneSide::Back => b.push(pi),
            _ => {
                f.push(pi);
                b.push(pi);
            }
        }
        let crossing = matches!(
            (si, sj),
            (PlaneSide::Front, PlaneSide::Back) | (PlaneSide::Back, PlaneSide::Front)
        );
        if crossing {
            let (pa, da, pb, db) = if si == PlaneSide::Front {
                (pi, di, points[j], dist[j])
            } else {
                (points[j], dist[j], pi, di)
            };
            let t = da / (da - db);
            let x = pa + (pb - pa) * t;
            f.push(x);
            b.push(x);
        }
    }
    if f.len() < 3 {
        return Split::Back;
    }
    if b.len() < 3 {
        return Split::Front;
    }
    Split::Spanning { front: f, back: b }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::polygon_area;

    #[test]
    fn pieces_keep_the_area_and_lie_on_their_sides() {
        let tri = [
            DVec3::new(0., 0., 0.),
            DVec3::new(4., 0., 0.),
            DVec3::new(0., 4., 0.),
        ];
        let plane = Plane::from_point_normal(DVec3::new(1., 0., 0.), DVec3::new(1., 0.2, 0.));
        let Split::Spanning { front, back } = split_polygon(&tri, &plane, 1e-12) else {
            panic!()
        };
        assert!((polygon_area(&front) + polygon_area(&back) - 8.0).abs() < 1e-12);
        assert!(front.iter().all(|&p| plane.signed_distance(p) >= -1e-12));
        assert!(back.iter().all(|&p| plane.signed_distance(p) <= 1e-12));
    }

    #[test]
    fn vertices_on_the_plane_do_not_split() {
        let tri = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 1., 0.),
            DVec3::new(0., 2., 0.),
        ];
        let plane = Plane::from_point_normal(DVec3::ZERO, DVec3::X);
        assert_eq!(split_polygon(&tri, &plane, 1e-9), Split::Front);
        let flat = Plane::from_point_normal(DVec3::ZERO, -DVec3::Z);
        assert_eq!(
            split_polygon(&tri, &flat, 1e-9),
            Split::Coplanar {
                same_direction: false
            }
        );
        // A vertex exactly on the plane between a front and a back vertex: pieces share it.
        let sq = [
            DVec3::new(-1., 0., 0.),
            DVec3::new(0., -1., 0.),
            DVec3::new(1., 0., 0.),
            DVec3::new(0., 1., 0.),
        ];
        let Split::Spanning { front, back } = split_polygon(&sq, &plane, 1e-9) else {
            panic!()
        };
        assert_eq!((front.len(), back.len()), (3, 3));
    }
}
