//! Where a fragment lies relative to a plane: by its bounding sphere when that
//! decides, else vertex by vertex with the crate's one rule
//! ([`crate::geom::PlaneSide::of_distance`]), the rule `split_polygon` splits by, with
//! a tolerance taken from the pair of polygons' extents.

use glam::DVec3;

use super::BspTree;
use crate::geom::{Plane, PlaneSide};

impl BspTree {
    /// The tolerance of fragment `f` by its own extent (see [`BspTree::pair_eps`]).
    pub(super) fn own_eps(&self, f: u32) -> f64 {
        let [cx, cy, cz, r] = self.spheres[f as usize];
        (self.relative_tolerance * (DVec3::new(cx, cy, cz).abs().max_element() + r))
            .max(self.rounding)
            .min(self.eps)
    }

    /// The tolerance of classifying fragment `f` against a plane whose own tolerance is
    /// `eps` (the splitter's, or the tree's for an axis plane): the larger of the two,
    /// each taken from its polygon's extent in the tree's frame (its centre's largest
    /// coordinate plus its radius), at most the tree's. With the tree's tolerance for
    /// every pair, a ground 2e5 across set 1e-4 for triangles 1e-4 across, and two of
    /// them were painted in the wrong order.
    pub(super) fn pair_eps(&self, f: u32, eps: f64) -> f64 {
        eps.max(self.own_eps(f))
    }

    /// Where fragment `f` lies relative to `plane`, by the rule `split_polygon` splits
    /// with ([`PlaneSide::of_distance`]), so both agree on every vertex.
    pub(super) fn classify(&self, f: u32, plane: &Plane, eps: f64) -> PlaneSide {
        let eps = self.pair_eps(f, eps);
        // Most fragments are far from the plane: their bounding sphere decides without
        // reading the vertices (with a margin far above rounding).
        // One square root (the normal's length) for the centre and all the vertices.
        let distance = plane.signed_distance_fn();
        let [cx, cy, cz, r] = self.spheres[f as usize];
        let d = distance(DVec3::new(cx, cy, cz));
        if d - r > eps + self.slack {
            return PlaneSide::Front;
        }
        if d + r < -eps - self.slack {
            return PlaneSide::Back;
        }
        let frag = &self.fragments[f as usize];
        PlaneSide::of_distances(
            self.fragment_indices(frag)
                .iter()
                .map(|&v| distance(self.local[v as usize])),
            eps,
        )
    }
}
