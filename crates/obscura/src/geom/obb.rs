//! Oriented bounding boxes (OBB).
//!
//! Source: seed 000, "Περιβάλλοντες Όγκοι (5)": a box oriented arbitrarily holds less
//! empty space than the axis-aligned one, at the price of a costlier ray test (the ray
//! is first rotated into the box's frame).
//!
//! # Representation
//! Three orthonormal axes `a_i` and, per axis, the interval `[lo_i, hi_i]` of the
//! projections `a_i · p` of the points: the box is `{x : lo_i <= a_i · x <= hi_i}`.
//! Storing projections (not a centre and half extents) makes containment exact by
//! construction: [`Obb::contains`] evaluates the same expression that built the box.
//!
//! # Choosing the orientation
//! No closed form gives the minimum-volume box cheaply (O'Rourke's exact algorithm is
//! O(n^3)). [`Obb::from_points`] takes the smallest box among these candidates:
//! 1. the principal axes of the vertices (PCA: eigenvectors of the covariance matrix,
//!    by Jacobi rotations) — Gottschalk, Lin and Manocha's OBBTree idea;
//! 2. the world axes (so the OBB is never larger than the AABB);
//! 3. a coordinate descent from the better of those: rotations about each axis by
//!    multiples of 90°/16, kept when they shrink the box, two rounds.
//!
//! Candidates are compared on a sample of the points (the extreme points along the 13
//! directions of a 26-DOP plus an even stride of at most 1024 vertices); the final box
//! is fitted to all points, and compared with the AABB once more.
//!
//! - Input: points. Output: a box containing all of them.
//! - Complexity: O(n) (a constant number of passes over the points).
//! - Limitations: not the minimum-volume box; PCA is biased by vertex density, which
//!   the world-axes candidate and the descent partly correct.
//!
//! Paper: Gottschalk, Lin and Manocha, "OBBTree: a hierarchical structure for rapid
//! interference detection", SIGGRAPH 1996.

use glam::{DMat3, DVec3};

use super::slab::{KDOP_AXES, slab};

/// An oriented box `{x : lo_i <= axes[i] · x <= hi_i}` with orthonormal axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obb {
    /// Orthonormal, right-handed axes.
    pub axes: [DVec3; 3],
    /// Smallest projection of the contents on each axis.
    pub lo: DVec3,
    /// Largest projection of the contents on each axis.
    pub hi: DVec3,
}

impl Obb {
    /// The box with the given orthonormal axes fitted to the points. `None` for no points.
    #[must_use]
    pub fn with_axes(points: &[DVec3], axes: [DVec3; 3]) -> Option<Self> {
        if points.is_empty() {
            return None;
        }
        let mut lo = DVec3::INFINITY;
        let mut hi = DVec3::NEG_INFINITY;
        for &p in points {
            let q = project(&axes, p);
            lo = lo.min(q);
            hi = hi.max(q);
        }
        Some(Obb { axes, lo, hi })
    }

    /// A tight box around the points (see the module doc for how the orientation is
    /// chosen). `None` for no points or non-finite ones.
    #[must_use]
    pub fn from_points(points: &[DVec3]) -> Option<Self> {
        if points.is_empty() || points.iter().any(|p| !p.is_finite()) {
            return None;
        }
        let sample = sample_points(points);
        let world = [DVec3::X, DVec3::Y, DVec3::Z];
        let mut best = world;
        let mut best_volume = volume_of(&sample, &world);
        if let Some(pca) = principal_axes(points) {
            let v = volume_of(&sample, &pca);
            if v < best_volume {
                best = pca;
                best_volume = v;
            }
        }
        const STEPS: u32 = 16;
        for _round in 0..2 {
            for axis in 0..3 {
                let base = best;
                for k in 1..STEPS {
                    let angle = f64::from(k) * std::f64::consts::FRAC_PI_2 / f64::from(STEPS);
                    let r = DMat3::from_axis_angle(base[axis], angle);
                    let cand = orthonormalize([r * base[0], r * base[1], r * base[2]]);
                    let v = volume_of(&sample, &cand);
                    if v < best_volume {
                        best = cand;
                        best_volume = v;
                    }
                }
            }
        }
        let chosen = Obb::with_axes(points, best)?;
        let aabb = Obb::with_axes(points, world)?;
        Some(if aabb.volume() <= chosen.volume() {
            aabb
        } else {
            chosen
        })
    }

    /// The volume.
    #[must_use]
    pub fn volume(&self) -> f64 {
        let e = (self.hi - self.lo).max(DVec3::ZERO);
        e.x * e.y * e.z
    }

    /// The centre in world coordinates.
    #[must_use]
    pub fn center(&self) -> DVec3 {
        let m = (self.lo + self.hi) * 0.5;
        self.axes[0] * m.x + self.axes[1] * m.y + self.axes[2] * m.z
    }

    /// Half the size along each of the box's axes.
    #[must_use]
    pub fn half_extents(&self) -> DVec3 {
        (self.hi - self.lo) * 0.5
    }

    /// The eight corners in world coordinates.
    #[must_use]
    pub fn corners(&self) -> [DVec3; 8] {
        let mut out = [DVec3::ZERO; 8];
        for (i, c) in out.iter_mut().enumerate() {
            let x = if i & 1 == 0 { self.lo.x } else { self.hi.x };
            let y = if i & 2 == 0 { self.lo.y } else { self.hi.y };
            let z = if i & 4 == 0 { self.lo.z } else { self.hi.z };
            *c = self.axes[0] * x + self.axes[1] * y + self.axes[2] * z;
        }
        out
    }

    /// Whether `p` is inside or on the boundary.
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        let q = project(&self.axes, p);
        q.cmpge(self.lo).all() && q.cmple(self.hi).all()
    }

    /// This box grown by `margin` on every side.
    #[must_use]
    pub fn expanded(&self, margin: f64) -> Self {
        Obb {
            axes: self.axes,
            lo: self.lo - DVec3::splat(margin),
            hi: self.hi + DVec3::splat(margin),
        }
    }

    /// The parameter interval `[t0, t1]` in which the ray `origin + t direction` is
    /// inside the box (slab method in the box's frame), `None` if it misses. The
    /// interval is not clipped to `t >= 0`.
    #[must_use]
    pub fn ray_interval(&self, origin: DVec3, direction: DVec3) -> Option<(f64, f64)> {
        let mut t0 = f64::NEG_INFINITY;
        let mut t1 = f64::INFINITY;
        for i in 0..3 {
            let so = self.axes[i].dot(origin);
            let sd = self.axes[i].dot(direction);
            if !slab(so, sd, self.lo[i], self.hi[i], &mut t0, &mut t1) {
                return None;
            }
        }
        Some((t0, t1))
    }
}

fn project(axes: &[DVec3; 3], p: DVec3) -> DVec3 {
    DVec3::new(axes[0].dot(p), axes[1].dot(p), axes[2].dot(p))
}

fn volume_of(points: &[DVec3], axes: &[DVec3; 3]) -> f64 {
    Obb::with_axes(points, *axes).map_or(f64::INFINITY, |b| b.volume())
}

fn orthonormalize(a: [DVec3; 3]) -> [DVec3; 3] {
    let x = a[0].normalize();
    let y = (a[1] - x * x.dot(a[1])).normalize();
    [x, y, x.cross(y)]
}

/// The extreme points along the 13 directions of a 26-DOP and an even stride of at most
/// 1024 points: enough to compare candidate orientations.
fn sample_points(points: &[DVec3]) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(1024 + 26);
    for axis in KDOP_AXES {
        let (mut lo, mut hi) = (points[0], points[0]);
        let (mut lo_d, mut hi_d) = (axis.dot(lo), axis.dot(hi));
        for &p in points {
            let d = axis.dot(p);
            if d < lo_d {
                lo_d = d;
                lo = p;
            }
            if d > hi_d {
                hi_d = d;
                hi = p;
            }
        }
        out.push(lo);
        out.push(hi);
    }
    let stride = points.len().div_ceil(1024).max(1);
    out.extend(points.iter().step_by(stride).copied());
    out
}

/// Eigenvectors of the covariance matrix of the points, largest variance first.
/// `None` when the points are all equal (no direction is preferred).
fn principal_axes(points: &[DVec3]) -> Option<[DVec3; 3]> {
    let n = points.len() as f64;
    let mean = points.iter().copied().sum::<DVec3>() / n;
    let mut c = [[0.0f64; 3]; 3];
    for &p in points {
        let d = (p - mean).to_array();
        for (i, row) in c.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += d[i] * d[j];
            }
        }
    }
    if c[0][0] + c[1][1] + c[2][2] <= 0.0 {
        return None;
    }
    let (values, vectors) = jacobi_eigen(c);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let axes = [vectors[order[0]], vectors[order[1]], vectors[order[2]]];
    let axes = orthonormalize(axes);
    axes.iter().all(|a| a.is_finite()).then_some(axes)
}

/// Eigen decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: the
/// eigenvalues and the eigenvectors (as unit vectors).
fn jacobi_eigen(mut a: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let diag = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= diag * 1e-15 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            // The smaller root of t^2 + 2 theta t - 1 = 0 (`signum(0) = 1`, so t = 1 at 0).
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A <- J^T A J with the rotation J in the (p, q) plane.
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * row_p[k] - s * row_q[k];
                a[q][k] = s * row_p[k] + c * row_q[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let col = |j: usize| DVec3::new(v[0][j], v[1][j], v[2][j]).normalize();
    ([a[0][0], a[1][1], a[2][2]], [col(0), col(1), col(2)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn jacobi_diagonalizes_a_known_matrix() {
        // Eigenvalues 1, 2, 4 with eigenvectors along a rotated frame.
        let r = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let d = DMat3::from_diagonal(DVec3::new(1.0, 2.0, 4.0));
        let m = r * d * r.transpose();
        let a = [
            [m.x_axis.x, m.y_axis.x, m.z_axis.x],
            [m.x_axis.y, m.y_axis.y, m.z_axis.y],
            [m.x_axis.z, m.y_axis.z, m.z_axis.z],
        ];
        let (values, vectors) = jacobi_eigen(a);
        for (k, &lambda) in values.iter().enumerate() {
            let v = vectors[k];
            assert!((m * v - v * lambda).length() < 1e-12, "{lambda} {v:?}");
        }
        let mut sorted = values;
        sorted.sort_by(f64::total_cmp);
        for (s, e) in sorted.iter().zip([1.0, 2.0, 4.0]) {
            assert!((s - e).abs() < 1e-12);
        }
    }

    #[test]
    fn a_rotated_box_is_recovered_tightly() {
        // The corners of a 4 x 2 x 1 box rotated arbitrarily: the OBB must have volume
        // 8 (up to rounding), far less than its AABB.
        let r = DMat3::from_euler(glam::EulerRot::ZYX, 0.4, 0.9, -0.3);
        let pts: Vec<DVec3> = (0..8)
            .map(|i| {
                let c = DVec3::new(
                    if i & 1 == 0 { -2.0 } else { 2.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -0.5 } else { 0.5 },
                );
                r * c + DVec3::new(3.0, -1.0, 2.0)
            })
            .collect();
        let obb = Obb::from_points(&pts).unwrap();
        assert!((obb.volume() - 8.0).abs() < 1e-9, "{}", obb.volume());
        assert!(pts.iter().all(|&p| obb.contains(p)));
        assert!((obb.center() - DVec3::new(3.0, -1.0, 2.0)).length() < 1e-9);
        let aabb = crate::geom::Aabb::from_points(pts.iter().copied());
        let e = aabb.extent();
        assert!(e.x * e.y * e.z > 2.0 * obb.volume());
    }

    #[test]
    fn never_larger_than_the_aabb_and_contains_every_point() {
        let mut rng = SplitMix64(5);
        for case in 0..40 {
            let n = 1 + case * 7;
            let pts: Vec<DVec3> = (0..n)
                .map(|_| {
                    DVec3::new(
                        rng.range(-3.0, 3.0),
                        rng.range(-1.0, 1.0) * (case % 3) as f64,
                        rng.range(-0.2, 0.2),
                    )
                })
                .collect();
            let obb = Obb::from_points(&pts).unwrap();
            assert!(pts.iter().all(|&p| obb.contains(p)), "case {case}");
            let aabb = crate::geom::Aabb::from_points(pts.iter().copied());
            let e = aabb.extent();
            assert!(obb.volume() <= e.x * e.y * e.z + 1e-12, "case {case}");
            for (i, a) in obb.axes.iter().enumerate() {
                assert!((a.length() - 1.0).abs() < 1e-12);
                for b in &obb.axes[i + 1..] {
                    assert!(a.dot(*b).abs() < 1e-12);
                }
            }
        }
        assert!(Obb::from_points(&[]).is_none());
        assert!(Obb::from_points(&[DVec3::new(f64::NAN, 0.0, 0.0)]).is_none());
        // A single point: a zero-volume box containing it.
        let one = Obb::from_points(&[DVec3::ONE]).unwrap();
        assert!(one.contains(DVec3::ONE) && one.volume() == 0.0);
    }

    #[test]
    fn ray_interval_matches_the_faces_as_polygons() {
        // Brute force: intersect the ray with the six faces of the box as planar
        // quadrilaterals; the entry and exit parameters must match the slab interval.
        let r = DMat3::from_euler(glam::EulerRot::XYZ, 0.5, 0.2, -0.8);
        let pts: Vec<DVec3> = (0..8)
            .map(|i| {
                r * DVec3::new(
                    if i & 1 == 0 { -1.5 } else { 1.5 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -0.5 } else { 0.5 },
                )
            })
            .collect();
        let obb = Obb::from_points(&pts).unwrap();
        let c = obb.corners();
        let faces = [
            [0, 2, 6, 4],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 5, 7, 6],
        ];
        let mut rng = SplitMix64(11);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..500 {
            let o = DVec3::new(
                rng.range(-4.0, 4.0),
                rng.range(-4.0, 4.0),
                rng.range(-4.0, 4.0),
            );
            let target = DVec3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            );
            let d = target - o;
            let mut ts: Vec<f64> = Vec::new();
            for f in faces {
                let quad = f.map(|k| c[k]);
                if let Some(t) = ray_quad(o, d, &quad) {
                    ts.push(t);
                }
            }
            match obb.ray_interval(o, d) {
                Some((t0, t1)) => {
                    hits += 1;
                    let lo = ts.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = ts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    assert!(
                        (lo - t0).abs() < 1e-9 && (hi - t1).abs() < 1e-9,
                        "{ts:?} vs {t0} {t1}"
                    );
                }
                None => {
                    misses += 1;
                    assert!(ts.is_empty(), "{ts:?}");
                }
            }
        }
        assert!(hits > 50 && misses > 50, "{hits} {misses}");
    }

    /// Ray against a planar convex quadrilateral by plane intersection and same-side
    /// tests.
    fn ray_quad(o: DVec3, d: DVec3, q: &[DVec3; 4]) -> Option<f64> {
        let n = (q[1] - q[0]).cross(q[2] - q[0]);
        let den = n.dot(d);
        if den.abs() < 1e-15 {
            return None;
        }
        let t = n.dot(q[0] - o) / den;
        let p = o + d * t;
        let signs: Vec<f64> = (0..4)
            .map(|k| (q[(k + 1) % 4] - q[k]).cross(p - q[k]).dot(n))
            .collect();
        (signs.iter().all(|&s| s >= -1e-12) || signs.iter().all(|&s| s <= 1e-12)).then_some(t)
    }
}
