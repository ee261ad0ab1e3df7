//! One prepared polygon, read from a [`PreparedView`](super::PreparedView)'s flat
//! arrays.

use glam::DVec3;

use super::ViewVertex;
use crate::geom::Plane;
use crate::raster::{DepthPlane, FillRule, PolygonCoverage};

/// One prepared polygon: a convex screen-space polygon with its face id.
#[derive(Clone, Copy, Debug)]
pub struct ViewPolygon<'a> {
    /// The scene-wide face id.
    pub face: u32,
    /// The object index.
    pub object: u32,
    pub(super) indices: &'a [u32],
    pub(super) vertices: &'a [ViewVertex],
}

impl<'a> ViewPolygon<'a> {
    /// Number of vertices.
    #[must_use]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether it has no vertex (never true for polygons of a view).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Vertex `k`.
    #[inline]
    #[must_use]
    pub fn vertex(&self, k: usize) -> &'a ViewVertex {
        &self.vertices[self.indices[k] as usize]
    }

    /// The vertices in order.
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = &'a ViewVertex> + 'a {
        let v = self.vertices;
        self.indices.iter().map(move |&i| &v[i as usize])
    }

    /// Indices of the vertices in [`PreparedView::vertices`](super::PreparedView::vertices).
    #[must_use]
    pub fn indices(&self) -> &'a [u32] {
        self.indices
    }

    /// Screen positions.
    #[must_use]
    pub fn screen_points(&self) -> Vec<(f64, f64)> {
        self.vertices().map(|v| (v.x, v.y)).collect()
    }

    /// Eye-space positions.
    #[must_use]
    pub fn eye_points(&self) -> Vec<DVec3> {
        self.vertices().map(|v| v.eye).collect()
    }

    /// The plane in eye space (Newell).
    #[must_use]
    pub fn eye_plane(&self) -> Option<Plane> {
        Plane::newell(&self.eye_points())
    }

    /// The depth-key plane in screen space.
    #[must_use]
    pub fn depth_plane(&self) -> Option<DepthPlane> {
        let pts: Vec<(f64, f64, f64)> = self.vertices().map(|v| (v.x, v.y, v.zq)).collect();
        DepthPlane::from_points(&pts)
    }

    /// The pixels it covers in a `width x height` image.
    #[must_use]
    pub fn coverage(&self, fill: FillRule, width: u32, height: u32) -> Option<PolygonCoverage> {
        PolygonCoverage::new(&self.screen_points(), fill, width, height)
    }
}
