//! Roberts' algorithm for scenes of convex polyhedra (placeholder).

use super::Drawing;
use crate::{Error, Result, View};

/// Options of [`draw`].
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
pub struct RobertsOptions {}

/// What the drawing cost.
#[derive(Clone, Debug, Default, serde::Serialize)]
#[non_exhaustive]
pub struct RobertsStats {
    /// Edges considered.
    pub edges: u64,
}

/// Draws the edges of the convex bodies `view` keeps, hidden parts marked.
pub fn draw(_view: &View, _options: &RobertsOptions) -> Result<(Drawing, RobertsStats)> {
    Err(Error::option("algorithm", "roberts: not built yet"))
}
