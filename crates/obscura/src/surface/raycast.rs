//! Placeholder: being implemented.

use crate::geom::BoundsKind;
use crate::surface::{Algorithm, RenderOptions, Stats};
use crate::view::PreparedView;
use crate::{Frame, Result};

/// How rays find the faces they may hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Acceleration {
    /// Every ray against every face.
    BruteForce,
    /// Per-object bounding volumes first.
    Bounds(BoundsKind),
    /// A bounding-volume hierarchy.
    Bvh,
    /// A uniform grid.
    Grid,
}

/// Renders by casting one ray per pixel from the camera in world space.
pub fn render(
    _view: &PreparedView<'_>,
    _acceleration: Acceleration,
    _options: &RenderOptions,
) -> Result<(Frame, Stats)> {
    Err(super::not_yet(Algorithm::Raycast))
}
