//! Front-to-back traversal of an octree along a ray.
//!
//! - Input: a ray (origin, direction) and a parameter interval `[t_min, t_max]`.
//! - Output: the first Partial voxel the ray meets in that interval, with the ray
//!   parameter of its entry into the voxel (clamped to `t_min`).
//! - Order: a ray whose direction is positive along an axis crosses each mid-plane of a
//!   cell from the low child to the high one, never back, so the children it visits
//!   have ever more bits set; any order in which a child comes after its bit-subsets is
//!   front to back, and plain numeric order is one. For other directions the axes
//!   with a negative component are mirrored: the order is `k XOR m` for `k = 0..8`,
//!   with `m` the octant bits of the negative axes ([`front_to_back_order`]). This is
//!   the per-ray form of the seed's front-to-back viewing order (Aref and Samet order
//!   the octants by the viewpoint; a ray from the viewpoint has the same order).
//! - Method: the ray's parameters at the cell's slab planes are kept per axis
//!   (`t0`, `t1`); a child's are `t0` or the midpoint `(t0 + t1) / 2` and the midpoint
//!   or `t1`, chosen by its octant bits, so no child box is ever intersected from
//!   scratch. Only the children the ray crosses are visited (at most 4): the first is
//!   found from the plane the ray enters by and the mid-planes it crossed before, each
//!   next one from the plane the previous one is left by (the state machine of Revelles,
//!   Ureña and Lastra, 2000). In mirrored space that step only ever sets a bit, which is
//!   the front-to-back order above. Zero direction components are replaced by a tiny
//!   positive one (1e-100 of the largest component), which keeps every parameter
//!   finite and the ray's side of each plane right.
//! - Full leaves are passed through: a ray from outside the solids meets a Partial
//!   voxel before any Full one (Full and Empty cells never touch), so only a ray that
//!   starts inside a solid reaches a Full leaf first; it goes on to the solid's boundary
//!   voxels and stops there, seeing the solid from inside (where the z-buffer, culling
//!   back faces, would show what lies beyond).
//! - Complexity: O(depth) nodes per voxel crossed, at most O(2^depth) voxels per ray.

use glam::DVec3;

use super::{NodeKind, Octree};

/// The order in which to visit a cell's children along a ray of this direction so that
/// they come front to back.
#[must_use]
pub fn front_to_back_order(direction: DVec3) -> [u8; 8] {
    let m = negative_mask(direction);
    std::array::from_fn(|k| k as u8 ^ m)
}

fn negative_mask(d: DVec3) -> u8 {
    u8::from(d.x < 0.0) | (u8::from(d.y < 0.0) << 1) | (u8::from(d.z < 0.0) << 2)
}

/// The first Partial voxel along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The voxel (a leaf).
    pub node: u32,
    /// Its source face.
    pub face: u32,
    /// The ray parameter where the ray enters it (at least `t_min`).
    pub t: f64,
    /// Where the ray enters and leaves the voxel (`enter` below `t_min` when the ray
    /// starts inside it).
    pub enter: f64,
    /// Where the ray leaves the voxel.
    pub exit: f64,
}

struct Walk {
    mask: u8,
    t_min: f64,
    t_max: f64,
    visited: u32,
}

impl Octree {
    /// The first Partial voxel that the ray `origin + t direction` meets for `t` in
    /// `[t_min, t_max]`, and the number of nodes entered on the way. Non-finite input,
    /// a zero direction and an empty interval meet nothing. The ray is in world
    /// coordinates: it is moved into the tree's frame ([`Octree::frame_origin`]) first.
    #[must_use]
    pub fn first_hit(
        &self,
        origin: DVec3,
        direction: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> (Option<RayHit>, u32) {
        if !(origin.is_finite() && direction.is_finite())
            || direction == DVec3::ZERO
            || !(t_min <= t_max)
        {
            return (None, 0);
        }
        let origin = origin - self.frame;
        let mask = negative_mask(direction);
        let (lo, hi) = (self.region.min(), self.region.max());
        // Mirror the axes with a negative component through the region's centre.
        let mirrored = DVec3::select(direction.cmplt(DVec3::ZERO), lo + hi - origin, origin);
        // Relative to the direction's length, so that the stand-in for a zero
        // component gives parameters far beyond every real one at any scale.
        let tiny = direction.abs().max_element() * 1e-100;
        let inv = DVec3::ONE / direction.abs().max(DVec3::splat(tiny));
        let t0 = (lo - mirrored) * inv;
        let t1 = (hi - mirrored) * inv;
        let mut walk = Walk {
            mask,
            t_min,
            t_max,
            visited: 0,
        };
        let hit = self.visit(0, t0, t1, &mut walk);
        (hit, walk.visited)
    }

    fn visit(&self, i: u32, t0: DVec3, t1: DVec3, walk: &mut Walk) -> Option<RayHit> {
        let enter = t0.max_element();
        let exit = t1.min_element();
        if enter > exit || exit < walk.t_min || enter > walk.t_max {
            return None;
        }
        walk.visited += 1;
        let n = &self.nodes[i as usize];
        match n.kind {
            NodeKind::Empty | NodeKind::Full => None,
            NodeKind::Partial => Some(RayHit {
                node: i,
                face: n.face,
                t: enter.max(walk.t_min),
                enter,
                exit,
            }),
            NodeKind::Internal => {
                let tm = (t0 + t1) * 0.5;
                // The child the ray enters first: along each axis other than the entry
                // plane's, the upper half if the ray crossed the mid-plane before entering.
                let entry_axis = if t0.x >= t0.y && t0.x >= t0.z {
                    0
                } else if t0.y >= t0.z {
                    1
                } else {
                    2
                };
                let mut k = 0u8;
                for a in 0..3 {
                    if a != entry_axis && tm[a] < enter {
                        k |= 1 << a;
                    }
                }
                loop {
                    let upper = glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0);
                    let c0 = DVec3::select(upper, tm, t0);
                    let c1 = DVec3::select(upper, t1, tm);
                    let child = n.first_child + u32::from(k ^ walk.mask);
                    if let Some(h) = self.visit(child, c0, c1, walk) {
                        return Some(h);
                    }
                    if c1.min_element() > walk.t_max {
                        return None;
                    }
                    // Leave the child through its nearest exit plane: into the upper
                    // neighbour along that axis, or out of the parent if already upper.
                    let exit_axis = if c1.x <= c1.y && c1.x <= c1.z {
                        0
                    } else if c1.y <= c1.z {
                        1
                    } else {
                        2
                    };
                    if k & (1 << exit_axis) != 0 {
                        return None;
                    }
                    k |= 1 << exit_axis;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_starts_at_the_octant_facing_the_ray() {
        assert_eq!(front_to_back_order(DVec3::new(1., 1., 1.))[0], 0);
        assert_eq!(front_to_back_order(DVec3::new(-1., 1., 1.))[0], 1);
        assert_eq!(
            front_to_back_order(DVec3::new(-1., -1., -1.)),
            [7, 6, 5, 4, 3, 2, 1, 0]
        );
        let o = front_to_back_order(DVec3::new(0.0, -2.0, 3.0));
        assert_eq!(o[0], 2);
        assert_eq!(o[7], 5);
    }
}
