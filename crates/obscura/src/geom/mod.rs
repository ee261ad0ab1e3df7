//! Geometry shared by every algorithm: planes, polygons, bounding volumes.
//!
//! Everything here works in `f64`: these are the computations that decide topology
//! (which side of a plane, which polygon is in front), so they must not flip under
//! rounding. Epsilons are documented where they are used.

mod aabb;
pub mod kdop;
pub mod obb;
mod plane;
mod polygon;
mod sphere;

pub use aabb::Aabb;
pub use kdop::{Kdop, KdopKind, RaySlabs};
pub use obb::Obb;
pub use plane::{Plane, PlaneSide};
#[cfg(test)]
pub(crate) use polygon::triangulate_within;
pub use polygon::{
    Triangulation, is_convex, max_plane_deviation, newell_normal, polygon_area, polygon_centroid,
    triangulate, triangulate_reporting,
};
pub use sphere::Sphere;

/// A kind of bounding volume (for ray casting with per-object bounds, and culling).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BoundsKind {
    /// Bounding sphere.
    Sphere,
    /// Axis-aligned bounding box.
    #[default]
    Aabb,
    /// Oriented bounding box.
    Obb,
    /// Discrete oriented polytope (k-DOP).
    Kdop,
}

impl BoundsKind {
    /// Every kind.
    pub const ALL: [BoundsKind; 4] = [
        BoundsKind::Sphere,
        BoundsKind::Aabb,
        BoundsKind::Obb,
        BoundsKind::Kdop,
    ];

    /// The command-line name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            BoundsKind::Sphere => "sphere",
            BoundsKind::Aabb => "aabb",
            BoundsKind::Obb => "obb",
            BoundsKind::Kdop => "kdop",
        }
    }
}

impl std::str::FromStr for BoundsKind {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        BoundsKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                crate::Error::option(
                    "--bounds",
                    format!("unknown bounding volume \"{s}\" (known: sphere, aabb, obb, kdop)"),
                )
            })
    }
}
