//! Cohen-Sutherland line clipping: region codes (outcodes), trivial accept and reject,
//! and clipping at one boundary at a time.
//!
//! * **2D** against an axis-aligned rectangle: 4-bit codes in the bit order of seed 001
//!   eq. (6.5): bit 0 `y > ymax`, bit 1 `x > xmax`, bit 2 `y < ymin`, bit 3 `x < xmin`
//!   ([`TOP`], [`RIGHT`], [`BOTTOM`], [`LEFT`]); the four lines make 9 regions
//!   (`9 < 2^4`, figure 6.3). Iterative: while the codes allow neither trivial accept
//!   (`c1 | c2 == 0`) nor trivial reject (`c1 & c2 != 0`), an outside endpoint is moved
//!   to its intersection with one boundary it is outside of, found by substituting
//!   `x` or `y` by `xmin, xmax, ymin, ymax` in the segment's line (seed 001 step 4).
//! * **3D** with 6-bit codes in seed 000's order (the crate's `OUT_*` constants, 27
//!   regions), the recursive `CS_Clip_3D` of seed 000 ("Αποκοπή Ευθυγράμμου Τμήματος
//!   Cohen – Sutherland στις 3Δ"): accept, reject, or split at a plane `R` where the
//!   endpoint codes differ and recurse on the half that is on the inside of `R`.
//!   Against an axis-aligned box (orthographic or parallel view volume, [`clip_segment_box`])
//!   the split is a plane-line intersection; in homogeneous clip space
//!   (`-w <= x, y, z <= w`, [`clip_segment_homogeneous`]) it uses the seed's t-formulae (3)
//!   ([`ClipPlane::intersection_t`]).
//!
//! # Input and output
//! A segment by its two endpoints; the visible part with its endpoints in the same
//! order, or `None`. An endpoint that needs no clipping is returned bit for bit. Any
//! non-finite coordinate gives `None`.
//!
//! # Complexity
//! `O(1)`: at most 4 (2D) or 6 (3D) intersections, one per boundary.
//!
//! # Robustness
//! The new endpoint is put exactly on the boundary it was clipped to, and the bits of
//! boundaries already clipped against are never set again: rounding could otherwise
//! put a point a few ulps outside a boundary it was moved onto and make the loop (or
//! the recursion) go on forever near a corner. This bounds the work to one
//! intersection per boundary and leaves results within rounding of the exact ones.
//!
//! # Limitations
//! The segment must be given in the space of the window: for perspective views use the
//! homogeneous form before the divide by `w` (see [`super::projection_order`]).
//!
//! Paper: Cohen and Sutherland's outcode clipper, published in Newman and Sproull,
//! "Principles of Interactive Computer Graphics", 2nd ed., McGraw-Hill, 1979.

use super::InRange;
use glam::{DVec2, DVec3, DVec4};

use super::view_volume::ClipPlane;
use super::{OUT_BOTTOM, OUT_FAR, OUT_LEFT, OUT_NEAR, OUT_RIGHT, OUT_TOP, Rect, valid_box};
use crate::geom::Aabb;

/// 2D outcode bit 0: `y > ymax` (seed 001 eq. 6.5, `p0`).
pub const TOP: u8 = 1 << 0;
/// 2D outcode bit 1: `x > xmax` (`p1`).
pub const RIGHT: u8 = 1 << 1;
/// 2D outcode bit 2: `y < ymin` (`p2`).
pub const BOTTOM: u8 = 1 << 2;
/// 2D outcode bit 3: `x < xmin` (`p3`).
pub const LEFT: u8 = 1 << 3;

/// The 4-bit region code of `p` against `rect` (eq. 6.5); 0 inside (boundary
/// included). NaN coordinates give `0b1111` (outside everything).
///
/// ```
/// use obscura::clip::{Rect, cohen_sutherland::{outcode_2d, BOTTOM, LEFT, RIGHT, TOP}};
/// use glam::DVec2;
/// let r = Rect::new(0., 0., 4., 3.).unwrap();
/// assert_eq!(outcode_2d(DVec2::new(2., 1.), &r), 0);
/// assert_eq!(outcode_2d(DVec2::new(5., 4.), &r), TOP | RIGHT); // 0011
/// assert_eq!(outcode_2d(DVec2::new(-1., -1.), &r), BOTTOM | LEFT); // 1100
/// ```
#[inline]
#[must_use]
pub fn outcode_2d(p: DVec2, rect: &Rect) -> u8 {
    let (min, max) = (rect.min(), rect.max());
    let mut c = 0;
    if p.y > max.y {
        c |= TOP;
    }
    if p.x > max.x {
        c |= RIGHT;
    }
    if p.y < min.y {
        c |= BOTTOM;
    }
    if p.x < min.x {
        c |= LEFT;
    }
    if p.is_nan() {
        c = TOP | RIGHT | BOTTOM | LEFT;
    }
    c
}

/// What one iteration of the 2D algorithm decided (see [`clip_segment_2d_traced`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Decision2d {
    /// `c1 | c2 == 0`: both endpoints inside, the segment is kept.
    Accept,
    /// `c1 & c2 != 0`: both endpoints beyond the same boundary, nothing is visible.
    Reject,
    /// An outside endpoint is moved onto a boundary line.
    Clip {
        /// The boundary's bit ([`TOP`], [`RIGHT`], [`BOTTOM`] or [`LEFT`]).
        boundary: u8,
        /// Whether the first endpoint moved (else the second).
        first_moved: bool,
        /// Where it moved to.
        to: DVec2,
    },
}

/// One iteration of the 2D algorithm: the current endpoints, their codes, and the
/// decision taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step2d {
    /// Current first endpoint.
    pub p1: DVec2,
    /// Current second endpoint.
    pub p2: DVec2,
    /// Its code (bits of boundaries already clipped against are cleared).
    pub code1: u8,
    /// The second endpoint's code (same rule).
    pub code2: u8,
    /// What was done.
    pub decision: Decision2d,
}

/// Cohen-Sutherland 2D: the part of segment `p1 p2` inside `rect`, or `None`.
///
/// ```
/// use obscura::clip::{Rect, cohen_sutherland::clip_segment_2d};
/// use glam::DVec2;
/// let r = Rect::new(0., 0., 4., 4.).unwrap();
/// let (a, b) = clip_segment_2d(DVec2::new(-2., 1.), DVec2::new(2., 1.), &r).unwrap();
/// assert_eq!((a, b), (DVec2::new(0., 1.), DVec2::new(2., 1.)));
/// assert_eq!(clip_segment_2d(DVec2::new(5., 0.), DVec2::new(6., 9.), &r), None);
/// ```
#[must_use]
pub fn clip_segment_2d(p1: DVec2, p2: DVec2, rect: &Rect) -> Option<(DVec2, DVec2)> {
    clip_2d(p1, p2, rect, |_| {})
}

/// [`clip_segment_2d`] with every iteration recorded, for teaching: the codes, the
/// trivial accept or reject, and each boundary an endpoint was moved to.
#[must_use]
pub fn clip_segment_2d_traced(
    p1: DVec2,
    p2: DVec2,
    rect: &Rect,
) -> (Option<(DVec2, DVec2)>, Vec<Step2d>) {
    let mut steps = Vec::new();
    let result = clip_2d(p1, p2, rect, |s| steps.push(s));
    (result, steps)
}

#[inline]
fn clip_2d(
    mut p1: DVec2,
    mut p2: DVec2,
    rect: &Rect,
    mut record: impl FnMut(Step2d),
) -> Option<(DVec2, DVec2)> {
    if !(p1.in_range() && p2.in_range()) {
        return None;
    }
    let (min, max) = (rect.min(), rect.max());
    let mut done = 0u8;
    let mut c1 = outcode_2d(p1, rect);
    let mut c2 = outcode_2d(p2, rect);
    loop {
        let mut step = Step2d {
            p1,
            p2,
            code1: c1,
            code2: c2,
            decision: Decision2d::Accept,
        };
        if c1 | c2 == 0 {
            record(step);
            return Some((p1, p2));
        }
        if c1 & c2 != 0 {
            step.decision = Decision2d::Reject;
            record(step);
            return None;
        }
        let first_moved = c1 != 0;
        let (out, other, code) = if first_moved {
            (p1, p2, c1)
        } else {
            (p2, p1, c2)
        };
        // The lowest set bit, in the seed's order: top, right, bottom, left.
        let boundary = code & code.wrapping_neg();
        let d = other - out;
        // Equation (6.3) of the segment with x or y replaced by the boundary value.
        // `d` along the clipped axis is non-zero: the endpoints are on either side.
        let moved = match boundary {
            TOP => DVec2::new(out.x + d.x * (max.y - out.y) / d.y, max.y),
            RIGHT => DVec2::new(max.x, out.y + d.y * (max.x - out.x) / d.x),
            BOTTOM => DVec2::new(out.x + d.x * (min.y - out.y) / d.y, min.y),
            _ => DVec2::new(min.x, out.y + d.y * (min.x - out.x) / d.x),
        };
        done |= boundary;
        let code = outcode_2d(moved, rect) & !done;
        step.decision = Decision2d::Clip {
            boundary,
            first_moved,
            to: moved,
        };
        record(step);
        if first_moved {
            p1 = moved;
            c1 = code;
        } else {
            p2 = moved;
            c2 = code;
        }
    }
}

/// The 6-bit region code of `p` against the box (seed 000's digits, the crate's
/// `OUT_*` bits: `x < xmin` is bit 0 ... `z > zmax` is bit 5); 0 inside, boundary
/// included. NaN coordinates give `0x3f`.
#[inline]
#[must_use]
pub fn outcode_box(p: DVec3, bounds: &Aabb) -> u8 {
    let mut c = 0;
    if p.x < bounds.min.x {
        c |= OUT_LEFT;
    }
    if p.x > bounds.max.x {
        c |= OUT_RIGHT;
    }
    if p.y < bounds.min.y {
        c |= OUT_BOTTOM;
    }
    if p.y > bounds.max.y {
        c |= OUT_TOP;
    }
    if p.z < bounds.min.z {
        c |= OUT_NEAR;
    }
    if p.z > bounds.max.z {
        c |= OUT_FAR;
    }
    if p.is_nan() {
        c = 0x3f;
    }
    c
}

/// Cohen-Sutherland 3D against an axis-aligned box (the orthographic or parallel view
/// volume, seed 000 eq. (1)), by the seed's recursive `CS_Clip_3D`. `None` when
/// nothing is inside, or for an empty or non-finite box.
///
/// ```
/// use obscura::clip::cohen_sutherland::clip_segment_box;
/// use obscura::geom::Aabb;
/// use glam::DVec3;
/// let cube = Aabb { min: DVec3::splat(-1.), max: DVec3::ONE };
/// let (a, b) = clip_segment_box(DVec3::new(0., 0., -3.), DVec3::new(0., 0., 3.), &cube).unwrap();
/// assert_eq!((a.z, b.z), (-1., 1.));
/// ```
#[must_use]
pub fn clip_segment_box(p1: DVec3, p2: DVec3, bounds: &Aabb) -> Option<(DVec3, DVec3)> {
    if !(p1.in_range() && p2.in_range() && valid_box(bounds)) {
        return None;
    }
    let (c1, c2) = (outcode_box(p1, bounds), outcode_box(p2, bounds));
    cs_clip_box(p1, p2, c1, c2, 0, bounds)
}

/// `CS_Clip_3D(p1, p2)` of seed 000, with the codes passed down and the planes already
/// split on (`done`) kept clear. Depth at most 6.
fn cs_clip_box(
    p1: DVec3,
    p2: DVec3,
    c1: u8,
    c2: u8,
    done: u8,
    bounds: &Aabb,
) -> Option<(DVec3, DVec3)> {
    if c1 | c2 == 0 {
        return Some((p1, p2));
    }
    if c1 & c2 != 0 {
        return None;
    }
    // R: a plane where the digits of c1 and c2 differ (the lowest such bit).
    let r = (c1 ^ c2) & (c1 ^ c2).wrapping_neg();
    let (axis, value) = match r {
        OUT_LEFT => (0, bounds.min.x),
        OUT_RIGHT => (0, bounds.max.x),
        OUT_BOTTOM => (1, bounds.min.y),
        OUT_TOP => (1, bounds.max.y),
        OUT_NEAR => (2, bounds.min.z),
        _ => (2, bounds.max.z),
    };
    // intersect_plane_line(R, (p1, p2)): the plane `coordinate = value`.
    let t = (value - p1[axis]) / (p2[axis] - p1[axis]);
    let mut i = p1 + (p2 - p1) * t;
    i[axis] = value;
    let done = done | r;
    let ci = outcode_box(i, bounds) & !done;
    if c1 & r != 0 {
        cs_clip_box(i, p2, ci, c2, done, bounds)
    } else {
        cs_clip_box(p1, i, c1, ci, done, bounds)
    }
}

/// Cohen-Sutherland 3D in homogeneous clip space, against `-w <= x, y, z <= w` before
/// the divide (seed 000, "ομογενής αποκοπή"), splitting with the t-formulae (3). A
/// segment crossing `w = 0` (one endpoint behind the eye) is clipped correctly: only
/// its part with `w > 0` can satisfy `-w <= x <= w`.
///
/// ```
/// use obscura::clip::cohen_sutherland::clip_segment_homogeneous;
/// use glam::DVec4;
/// // From the centre to beyond the right plane: t = (x1 - w1) / ((x1 - x2) + (w2 - w1)) = 1/3.
/// let (a, b) = clip_segment_homogeneous(DVec4::new(0., 0., 0., 1.), DVec4::new(3., 0., 0., 1.)).unwrap();
/// assert_eq!(a, DVec4::new(0., 0., 0., 1.));
/// assert_eq!(b, DVec4::new(1., 0., 0., 1.));
/// ```
#[must_use]
pub fn clip_segment_homogeneous(p1: DVec4, p2: DVec4) -> Option<(DVec4, DVec4)> {
    if !(p1.in_range() && p2.in_range()) {
        return None;
    }
    let (c1, c2) = (
        super::outcode_homogeneous(p1),
        super::outcode_homogeneous(p2),
    );
    cs_clip_homogeneous(p1, p2, c1, c2, 0)
}

fn cs_clip_homogeneous(p1: DVec4, p2: DVec4, c1: u8, c2: u8, done: u8) -> Option<(DVec4, DVec4)> {
    if c1 | c2 == 0 {
        return Some((p1, p2));
    }
    if c1 & c2 != 0 {
        return None;
    }
    let r = (c1 ^ c2) & (c1 ^ c2).wrapping_neg();
    let plane = ClipPlane::from_outcode_bit(r)?;
    let t = plane.intersection_t(p1, p2);
    let i = plane.snap_onto(p1 + (p2 - p1) * t);
    let done = done | r;
    let ci = super::outcode_homogeneous(i) & !done;
    if c1 & r != 0 {
        cs_clip_homogeneous(i, p2, ci, c2, done)
    } else {
        cs_clip_homogeneous(p1, i, c1, ci, done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nine_regions_of_the_rectangle() {
        // Figure 6.3: the codes of the 9 regions, from top-left row by row.
        let r = Rect::new(0., 0., 1., 1.).unwrap();
        let codes: Vec<u8> = [2.0, 0.5, -1.0]
            .iter()
            .flat_map(|&y| [-1.0, 0.5, 2.0].map(|x| outcode_2d(DVec2::new(x, y), &r)))
            .collect();
        assert_eq!(
            codes,
            vec![
                0b1001, 0b0001, 0b0011, //
                0b1000, 0b0000, 0b0010, //
                0b1100, 0b0100, 0b0110,
            ]
        );
    }

    #[test]
    fn nan_and_infinite_input_give_nothing() {
        let r = Rect::new(0., 0., 1., 1.).unwrap();
        let nan = DVec2::new(f64::NAN, 0.5);
        assert_eq!(outcode_2d(nan, &r), 0b1111);
        assert_eq!(clip_segment_2d(nan, DVec2::splat(0.5), &r), None);
        assert_eq!(
            clip_segment_2d(DVec2::new(f64::INFINITY, 0.5), DVec2::splat(0.5), &r),
            None
        );
        let cube = Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        };
        assert_eq!(clip_segment_box(DVec3::NAN, DVec3::ONE, &cube), None);
        assert_eq!(
            clip_segment_box(DVec3::ZERO, DVec3::ONE, &Aabb::EMPTY),
            None
        );
        assert_eq!(clip_segment_homogeneous(DVec4::NAN, DVec4::W), None);
    }

    #[test]
    fn trace_records_each_boundary_crossed() {
        // Window [0,4]x[0,4], segment (-2,1) -> (6,3): d = (8,2).
        // c1 = LEFT (1000), c2 = RIGHT (0010); neither trivial.
        // Iteration 1 moves p1 (its code is non-zero) to x = 0: y = 1 + 2*(0+2)/8 = 1.5.
        // Iteration 2 moves p2 towards the new p1 (0,1.5), d = (-6,-1.5), to x = 4:
        // y = 3 + (-1.5)*(4-6)/(-6) = 3 - 0.5 = 2.5.
        let r = Rect::new(0., 0., 4., 4.).unwrap();
        let (res, steps) = clip_segment_2d_traced(DVec2::new(-2., 1.), DVec2::new(6., 3.), &r);
        assert_eq!(res, Some((DVec2::new(0., 1.5), DVec2::new(4., 2.5))));
        assert_eq!(steps.len(), 3);
        assert_eq!((steps[0].code1, steps[0].code2), (LEFT, RIGHT));
        assert_eq!(
            steps[0].decision,
            Decision2d::Clip {
                boundary: LEFT,
                first_moved: true,
                to: DVec2::new(0., 1.5)
            }
        );
        assert_eq!(
            steps[1].decision,
            Decision2d::Clip {
                boundary: RIGHT,
                first_moved: false,
                to: DVec2::new(4., 2.5)
            }
        );
        assert_eq!(steps[2].decision, Decision2d::Accept);
    }

    #[test]
    fn grazing_a_corner_terminates() {
        // A segment through the corner (1, 1) of the unit square, at a slope that
        // rounds badly: every iteration must still clear one boundary.
        let r = Rect::new(0., 0., 1., 1.).unwrap();
        let a = DVec2::new(1.0 - 0.1 * 3.0, 1.0 + 0.1 * 3.0);
        let b = DVec2::new(1.0 + 0.7, 1.0 - 0.7);
        let (res, steps) = clip_segment_2d_traced(a, b, &r);
        assert!(steps.len() <= 5);
        if let Some((p, q)) = res {
            for v in [p, q] {
                assert!(
                    v.cmpge(DVec2::splat(-1e-12)).all() && v.cmple(DVec2::splat(1.0 + 1e-12)).all()
                );
            }
        }
    }
}
