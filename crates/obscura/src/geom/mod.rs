//! Geometry shared by every algorithm: planes, polygons, bounding volumes.
//!
//! Everything here works in `f64`: these are the computations that decide topology
//! (which side of a plane, which polygon is in front), so they must not flip under
//! rounding. Epsilons are documented where they are used.
//!
//! Papers: each module cites its own (Newell's normal, Ritter 1990, Gottschalk et al.
//! 1996, Klosowski et al. 1998, Kay and Kajiya 1986, Meisters 1975).

use glam::DVec3;

mod aabb;
pub mod kdop;
pub mod obb;
mod plane;
mod polygon;
mod predicates;
pub(crate) mod slab;
mod sphere;
mod triangulate;

pub use aabb::Aabb;
pub use kdop::{Kdop, KdopKind, RaySlabs};
pub use obb::Obb;
pub use plane::{Plane, PlaneSide};
pub use polygon::{is_convex, max_plane_deviation, newell_normal, polygon_area, polygon_centroid};
pub use predicates::orient3d;
pub use sphere::Sphere;
#[cfg(test)]
pub(crate) use triangulate::triangulate_within;
pub use triangulate::{Triangulation, triangulate, triangulate_reporting};

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
                    "RenderOptions::bounds",
                    format!("unknown bounding volume \"{s}\" (known: sphere, aabb, obb, kdop)"),
                )
            })
    }
}

/// The length of `v`, scaled by its largest component before squaring, so that it
/// neither overflows (components beyond about 1e154) nor underflows (below about
/// 1e-154) where `v.length()` would. Zero for a zero vector, not finite for a
/// non-finite one.
#[must_use]
pub(crate) fn robust_length(v: DVec3) -> f64 {
    let m = v.abs().max_element();
    if m > 0.0 && m.is_finite() {
        m * (v / m).length()
    } else {
        m
    }
}

/// The unit vector along `v`, whatever its length (`1e308` or `1e-320` included:
/// scaled by its largest component before it is normalized); `None` for a zero or
/// non-finite vector.
#[must_use]
pub(crate) fn unit_direction(v: DVec3) -> Option<DVec3> {
    let m = v.abs().max_element();
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    let u = (v / m).normalize();
    u.is_finite().then_some(u)
}

#[cfg(test)]
mod scale_tests {
    use super::*;

    #[test]
    fn lengths_and_directions_at_extreme_scales() {
        for k in [1e-300, 1e-200, 1e-100, 1.0, 1e100, 1e200, 1e307] {
            let v = DVec3::new(3.0, 0.0, 4.0) * k;
            let l = robust_length(v);
            assert!((l / k - 5.0).abs() < 1e-5, "{k}: {l}");
            let u = unit_direction(v).unwrap();
            assert!((u - DVec3::new(0.6, 0.0, 0.8)).length() < 1e-6, "{k}: {u}");
        }
        // Subnormal lengths too.
        assert_eq!(unit_direction(DVec3::Z * 1e-320), Some(DVec3::Z));
        assert_eq!(unit_direction(DVec3::ZERO), None);
        assert_eq!(unit_direction(DVec3::new(f64::NAN, 0.0, 1.0)), None);
        assert_eq!(unit_direction(DVec3::new(f64::INFINITY, 0.0, 1.0)), None);
        assert_eq!(robust_length(DVec3::ZERO), 0.0);
    }
}
