//! The floating horizon for surfaces `y = f(x, z)` (placeholder).

use super::Drawing;
use crate::{Camera, Error, Result, Viewport};

/// A grid of heights `y` over `x` (columns, `nx`) and `z` (rows, `nz`), row-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeightField {
    /// `nx * nz` heights, row `z` after row `z`.
    pub heights: Vec<f64>,
    /// Samples along x.
    pub nx: usize,
    /// Samples along z.
    pub nz: usize,
}

/// Options of [`draw`].
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
pub struct HorizonOptions {}

/// What the drawing cost.
#[derive(Clone, Debug, Default, serde::Serialize)]
#[non_exhaustive]
pub struct HorizonStats {
    /// Curves drawn.
    pub curves: u64,
}

/// Draws the visible parts of the surface's curves.
pub fn draw(
    _field: &HeightField,
    _camera: &Camera,
    _viewport: Viewport,
    _options: &HorizonOptions,
) -> Result<(Drawing, HorizonStats)> {
    Err(Error::option("algorithm", "horizon: not built yet"))
}
