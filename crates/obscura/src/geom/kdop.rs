//! Discrete oriented polytopes (k-DOPs).
//!
//! Source: seed 000, "Περιβάλλοντες Όγκοι (5)": polyhedra whose faces have
//! predetermined orientations. A k-DOP is the intersection of k/2 slabs
//! `lo_i <= n_i · x <= hi_i` with fixed normals `n_i`; more directions mean less empty
//! space and a costlier ray test (one slab per direction), the seeds' trade-off.
//!
//! # Axes
//! The directions are integer vectors (unnormalized; a slab does not care), the
//! classical ones of Klosowski et al. (1998):
//!
//! | k | directions |
//! | --- | --- |
//! | 6 (the AABB) | (1,0,0) (0,1,0) (0,0,1) |
//! | 14 | the 3 above + the 4 cube diagonals (1,1,1) (1,1,-1) (1,-1,1) (1,-1,-1) |
//! | 18 | the 3 axes + the 6 edge diagonals (1,1,0) (1,-1,0) (1,0,1) (1,0,-1) (0,1,1) (0,1,-1) |
//! | 26 | all 13 |
//!
//! [`BoundsKind::Kdop`](crate::geom::BoundsKind::Kdop) uses the 26-DOP.
//!
//! - Input: points; output: the tightest k-DOP with these directions, O(n k).
//! - Containment is exact by construction ([`Kdop::contains`] evaluates the same dot
//!   products that built it).
//! - Limitations: the directions are fixed in world space, so a thin object at an
//!   angle none of them matches keeps some empty space (an OBB adapts, a k-DOP does
//!   not).
//!
//! Paper: Klosowski, Held, Mitchell, Sowizral and Zikan, "Efficient collision detection
//! using bounding volume hierarchies of k-DOPs", IEEE TVCG 4(1), 1998.

use glam::DVec3;

use super::slab::slab;
pub use super::slab::{KDOP_AXES, RaySlabs};

/// Which directions a k-DOP uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum KdopKind {
    /// 14-DOP: axes and cube diagonals.
    K14,
    /// 18-DOP: axes and edge diagonals.
    K18,
    /// 26-DOP: all 13 directions.
    #[default]
    K26,
}

impl KdopKind {
    /// k (the number of faces).
    #[must_use]
    pub fn k(self) -> usize {
        2 * self.axis_indices().len()
    }

    /// Indices into [`KDOP_AXES`] of the directions used.
    #[must_use]
    pub(crate) fn axis_indices(self) -> &'static [usize] {
        match self {
            KdopKind::K14 => &[0, 1, 2, 3, 4, 5, 6],
            KdopKind::K18 => &[0, 1, 2, 7, 8, 9, 10, 11, 12],
            KdopKind::K26 => &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12],
        }
    }
}

/// A k-DOP: per used direction `n_i` of [`KDOP_AXES`], the interval `[lo_i, hi_i]` of
/// `n_i · x` over its contents. Unused slots are unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kdop {
    /// Which directions are used.
    pub kind: KdopKind,
    /// Smallest projection per direction (indexed like [`KDOP_AXES`]).
    pub lo: [f64; 13],
    /// Largest projection per direction.
    pub hi: [f64; 13],
}

impl Kdop {
    /// The tightest k-DOP of the points. `None` for no points or non-finite ones.
    #[must_use]
    pub fn from_points(points: &[DVec3], kind: KdopKind) -> Option<Self> {
        if points.is_empty() || points.iter().any(|p| !p.is_finite()) {
            return None;
        }
        let mut lo = [f64::NEG_INFINITY; 13];
        let mut hi = [f64::INFINITY; 13];
        for &i in kind.axis_indices() {
            lo[i] = f64::INFINITY;
            hi[i] = f64::NEG_INFINITY;
            for &p in points {
                let d = KDOP_AXES[i].dot(p);
                lo[i] = lo[i].min(d);
                hi[i] = hi[i].max(d);
            }
        }
        Some(Kdop { kind, lo, hi })
    }

    /// Whether `p` is inside or on the boundary.
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        self.kind.axis_indices().iter().all(|&i| {
            let d = KDOP_AXES[i].dot(p);
            d >= self.lo[i] && d <= self.hi[i]
        })
    }

    /// This k-DOP with every face moved out by `margin` (in world units).
    #[must_use]
    pub fn expanded(&self, margin: f64) -> Self {
        let mut out = *self;
        for &i in self.kind.axis_indices() {
            let m = margin * KDOP_AXES[i].length();
            out.lo[i] -= m;
            out.hi[i] += m;
        }
        out
    }

    /// The parameter interval `[t0, t1]` in which the ray `origin + t direction` is
    /// inside (intersection of the slabs), `None` if it misses. Not clipped to `t >= 0`.
    #[must_use]
    pub fn ray_interval(&self, origin: DVec3, direction: DVec3) -> Option<(f64, f64)> {
        let mut t0 = f64::NEG_INFINITY;
        let mut t1 = f64::INFINITY;
        for &i in self.kind.axis_indices() {
            let n = KDOP_AXES[i];
            if !slab(
                n.dot(origin),
                n.dot(direction),
                self.lo[i],
                self.hi[i],
                &mut t0,
                &mut t1,
            ) {
                return None;
            }
        }
        Some((t0, t1))
    }
}

impl Kdop {
    /// [`Kdop::ray_interval`] with the ray's projections computed beforehand.
    #[must_use]
    pub(crate) fn ray_interval_projected(&self, ray: &RaySlabs) -> Option<(f64, f64)> {
        let mut t0 = f64::NEG_INFINITY;
        let mut t1 = f64::INFINITY;
        for &i in self.kind.axis_indices() {
            if !ray.clip(i, self.lo[i], self.hi[i], &mut t0, &mut t1) {
                return None;
            }
        }
        Some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn random_points(rng: &mut SplitMix64, n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|_| {
                DVec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-1.0, 3.0),
                    rng.range(-0.5, 0.5),
                )
            })
            .collect()
    }

    #[test]
    fn contains_every_point_and_a_cube_gives_its_known_faces() {
        let mut rng = SplitMix64(3);
        for kind in [KdopKind::K14, KdopKind::K18, KdopKind::K26] {
            for n in [1, 2, 5, 50, 300] {
                let pts = random_points(&mut rng, n);
                let k = Kdop::from_points(&pts, kind).unwrap();
                assert!(pts.iter().all(|&p| k.contains(p)), "{kind:?} {n}");
            }
        }
        // The unit cube [0,1]^3: on (1,1,1) from 0 to 3, on (1,-1,0) from -1 to 1.
        let cube: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let k = Kdop::from_points(&cube, KdopKind::K26).unwrap();
        assert_eq!((k.lo[3], k.hi[3]), (0.0, 3.0));
        assert_eq!((k.lo[8], k.hi[8]), (-1.0, 1.0));
        assert!(!k.contains(DVec3::new(1.0, 1.0, 1.0001)));
        assert_eq!(KdopKind::K14.k(), 14);
        assert_eq!(KdopKind::K18.k(), 18);
        assert_eq!(KdopKind::K26.k(), 26);
        assert!(Kdop::from_points(&[], KdopKind::K26).is_none());
    }

    #[test]
    fn the_octahedron_corner_is_cut_by_the_diagonal_faces() {
        // An octahedron |x|+|y|+|z| <= 1: the 14-DOP is exactly the octahedron cut by
        // the box [-1,1]^3, so (0.5, 0.5, 0.5) (sum 1.5) is outside it, though inside
        // the AABB; the 18-DOP bounds |x|+|y| <= 1 only, so it keeps that point.
        let pts = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        let k14 = Kdop::from_points(&pts, KdopKind::K14).unwrap();
        let k18 = Kdop::from_points(&pts, KdopKind::K18).unwrap();
        let p = DVec3::splat(0.5);
        assert!(!k14.contains(p));
        assert!(k18.contains(p));
        assert!(k14.contains(DVec3::new(0.3, 0.3, 0.3)));
    }

    #[test]
    fn ray_interval_agrees_with_sampled_membership() {
        // Brute force: march the ray in small steps and test containment with the
        // face inequalities; the inside samples must lie within the interval, and the
        // interval (shrunk by one step) must hold only inside samples.
        let mut rng = SplitMix64(17);
        for kind in [KdopKind::K14, KdopKind::K18, KdopKind::K26] {
            let pts = random_points(&mut rng, 40);
            let k = Kdop::from_points(&pts, kind).unwrap();
            let (mut hits, mut misses) = (0, 0);
            for _ in 0..200 {
                let o = DVec3::new(
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                );
                let d = DVec3::new(
                    rng.range(-4.0, 4.0),
                    rng.range(-3.0, 5.0),
                    rng.range(-3.0, 3.0),
                ) - o;
                let steps = 4000;
                let dt = 2.0 / f64::from(steps);
                let inside: Vec<f64> = (0..=steps)
                    .map(|s| f64::from(s) * dt)
                    .filter(|&t| k.contains(o + d * t))
                    .collect();
                match k.ray_interval(o, d) {
                    Some((t0, t1)) if t1 >= 0.0 && t0 <= 2.0 => {
                        hits += 1;
                        for &t in &inside {
                            assert!(t >= t0 - 1e-9 && t <= t1 + 1e-9);
                        }
                        if t1 - t0 > 3.0 * dt {
                            assert!(!inside.is_empty());
                            let (a, b) = (inside[0], *inside.last().unwrap());
                            assert!(a <= t0.max(0.0) + dt + 1e-9, "{a} {t0}");
                            assert!(b >= t1.min(2.0) - dt - 1e-9, "{b} {t1}");
                        }
                    }
                    _ => {
                        misses += 1;
                        assert!(
                            inside.is_empty(),
                            "{kind:?}: {} inside samples",
                            inside.len()
                        );
                    }
                }
            }
            assert!(hits > 20 && misses > 20, "{hits} {misses}");
        }
    }

    #[test]
    fn projected_rays_give_the_same_intervals() {
        let mut rng = SplitMix64(23);
        for kind in [KdopKind::K14, KdopKind::K18, KdopKind::K26] {
            let k = Kdop::from_points(&random_points(&mut rng, 30), kind).unwrap();
            for _ in 0..300 {
                let o = DVec3::new(
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                );
                let mut d = DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                if rng.next_f64() < 0.2 {
                    d.z = 0.0; // parallel to some slabs
                }
                assert_eq!(
                    k.ray_interval(o, d),
                    k.ray_interval_projected(&RaySlabs::new(o, d))
                );
            }
        }
    }

    #[test]
    fn rays_parallel_to_a_face_are_handled() {
        let cube: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let k = Kdop::from_points(&cube, KdopKind::K26).unwrap();
        // Along x at y = z = 0.5: inside from x = 0 to 1.
        let (t0, t1) = k
            .ray_interval(DVec3::new(-1.0, 0.5, 0.5), DVec3::X)
            .unwrap();
        assert!((t0 - 1.0).abs() < 1e-12 && (t1 - 2.0).abs() < 1e-12);
        // Along x at y = 2: outside the y slab, never inside.
        assert!(
            k.ray_interval(DVec3::new(-1.0, 2.0, 0.5), DVec3::X)
                .is_none()
        );
    }
}
