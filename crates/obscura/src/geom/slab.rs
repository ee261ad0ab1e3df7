//! Ray intervals through slabs, the one piece every bounding volume's ray test is made
//! of: a slab `lo <= n · x <= hi` meets the ray `o + t d` for `t` between
//! `(lo - n·o) / n·d` and `(hi - n·o) / n·d`, and a box, OBB or k-DOP is the
//! intersection of its slabs (Kay and Kajiya, "Ray tracing complex scenes", SIGGRAPH
//! 1986). [`Obb`](super::Obb), [`Kdop`](super::Kdop) and [`Aabb`](super::Aabb)
//! narrow an interval slab by slab with [`clip_slab`]; the ray casters test many
//! volumes with one ray's projections computed once ([`RaySlabs`]).
//!
//! The 13 directions of the 26-DOP ([`KDOP_AXES`]) live here too: the ray projections
//! are taken on them, and the OBB samples extreme points along them.

use glam::DVec3;

/// The 13 directions of the 26-DOP: axes, cube diagonals, edge diagonals.
pub const KDOP_AXES: [DVec3; 13] = [
    DVec3::new(1.0, 0.0, 0.0),
    DVec3::new(0.0, 1.0, 0.0),
    DVec3::new(0.0, 0.0, 1.0),
    DVec3::new(1.0, 1.0, 1.0),
    DVec3::new(1.0, 1.0, -1.0),
    DVec3::new(1.0, -1.0, 1.0),
    DVec3::new(1.0, -1.0, -1.0),
    DVec3::new(1.0, 1.0, 0.0),
    DVec3::new(1.0, -1.0, 0.0),
    DVec3::new(1.0, 0.0, 1.0),
    DVec3::new(1.0, 0.0, -1.0),
    DVec3::new(0.0, 1.0, 1.0),
    DVec3::new(0.0, 1.0, -1.0),
];

/// Narrows `[t0, t1]` to where `lo <= so + t sd <= hi`, `inv` being `1 / sd`; false
/// when the interval becomes empty. A ray parallel to the slab (`sd == 0`) keeps the
/// interval when it lies inside the slab and empties it otherwise.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn clip_slab(
    so: f64,
    sd: f64,
    inv: f64,
    lo: f64,
    hi: f64,
    t0: &mut f64,
    t1: &mut f64,
) -> bool {
    if sd == 0.0 {
        return so >= lo && so <= hi;
    }
    let (mut a, mut b) = ((lo - so) * inv, (hi - so) * inv);
    if a > b {
        std::mem::swap(&mut a, &mut b);
    }
    *t0 = t0.max(a);
    *t1 = t1.min(b);
    *t0 <= *t1
}

/// [`clip_slab`] for a projection `sd` whose inverse is not computed beforehand.
#[inline]
pub(crate) fn slab(so: f64, sd: f64, lo: f64, hi: f64, t0: &mut f64, t1: &mut f64) -> bool {
    clip_slab(so, sd, 1.0 / sd, lo, hi, t0, t1)
}

/// A ray's projections on the 13 directions of [`KDOP_AXES`], computed once to test it
/// against many k-DOPs (and axis-aligned boxes, the first three directions).
#[derive(Clone, Copy, Debug)]
pub struct RaySlabs {
    /// `n · origin` per direction.
    origin: [f64; 13],
    /// `1 / (n · direction)` per direction (infinite when the ray is parallel to the
    /// slab).
    inv: [f64; 13],
    /// `n · direction` per direction.
    along: [f64; 13],
}

impl RaySlabs {
    /// Projects the ray `origin + t direction`.
    #[must_use]
    pub fn new(origin: DVec3, direction: DVec3) -> Self {
        let along = KDOP_AXES.map(|n| n.dot(direction));
        RaySlabs {
            origin: KDOP_AXES.map(|n| n.dot(origin)),
            inv: along.map(|a| 1.0 / a),
            along,
        }
    }

    /// Narrows `[t0, t1]` to where the ray is inside slab `i` (`lo <= n_i · x <= hi`);
    /// false when it becomes empty. The one slab clip (`geom::slab`) with the projections computed
    /// beforehand: the same interval as the unprojected test, bit for bit, by
    /// construction.
    #[inline]
    pub fn clip(&self, i: usize, lo: f64, hi: f64, t0: &mut f64, t1: &mut f64) -> bool {
        clip_slab(self.origin[i], self.along[i], self.inv[i], lo, hi, t0, t1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slab_narrows_the_interval_to_its_crossing() {
        // x in [1, 3] along o = 0, d = (2, 0, 0): t in [0.5, 1.5], either direction.
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        assert!(slab(0.0, 2.0, 1.0, 3.0, &mut t0, &mut t1));
        assert_eq!((t0, t1), (0.5, 1.5));
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        assert!(slab(0.0, -2.0, -3.0, -1.0, &mut t0, &mut t1));
        assert_eq!((t0, t1), (0.5, 1.5));
        // An interval already narrower keeps its own ends; a disjoint one empties.
        let (mut t0, mut t1) = (0.75, 1.0);
        assert!(slab(0.0, 2.0, 1.0, 3.0, &mut t0, &mut t1));
        assert_eq!((t0, t1), (0.75, 1.0));
        let (mut t0, mut t1) = (2.0, 4.0);
        assert!(!slab(0.0, 2.0, 1.0, 3.0, &mut t0, &mut t1));
        // Parallel: inside keeps everything, outside nothing.
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        assert!(slab(2.0, 0.0, 1.0, 3.0, &mut t0, &mut t1));
        assert_eq!((t0, t1), (f64::NEG_INFINITY, f64::INFINITY));
        assert!(!slab(4.0, 0.0, 1.0, 3.0, &mut t0, &mut t1));
    }

    #[test]
    fn projected_and_direct_slabs_agree_bit_for_bit() {
        let mut rng = crate::rng::SplitMix64(17);
        for _ in 0..2000 {
            let mut v = || {
                DVec3::new(
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                )
            };
            let (o, mut d, a, b) = (v(), v(), v(), v());
            if d.x > 4.0 {
                d.x = 0.0;
            }
            let ray = RaySlabs::new(o, d);
            for (i, n) in KDOP_AXES.iter().enumerate() {
                let (lo, hi) = (a.x.min(b.x), a.x.max(b.x));
                let (mut p0, mut p1) = (a.y.min(b.y), a.y.max(b.y) + 3.0);
                let (mut q0, mut q1) = (p0, p1);
                let kept = ray.clip(i, lo, hi, &mut p0, &mut p1);
                assert_eq!(kept, slab(n.dot(o), n.dot(d), lo, hi, &mut q0, &mut q1));
                assert_eq!((p0.to_bits(), p1.to_bits()), (q0.to_bits(), q1.to_bits()));
            }
        }
    }
}
