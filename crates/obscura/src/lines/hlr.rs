//! Exact hidden-line removal with quantitative invisibility (placeholder).

use std::time::Duration;

use super::{Drawing, EdgeKinds, Progress};
use crate::{Error, Result, SceneIndex, View};

/// Options of [`draw`].
#[derive(Clone, Default)]
#[non_exhaustive]
pub struct HlrOptions {
    /// The edges to find (see [`super::edges::EdgeOptions`]).
    pub edges: super::edges::EdgeOptions,
    /// Stop with [`Error::TimeLimit`] after this long.
    pub time_limit: Option<Duration>,
    /// Called as edges are finished.
    pub progress: Option<Progress>,
}

/// What the drawing cost.
#[derive(Clone, Debug, Default, serde::Serialize)]
#[non_exhaustive]
pub struct HlrStats {
    /// Edges considered.
    pub edges: u64,
    /// Pieces made.
    pub pieces: u64,
}

/// Draws the feature edges of what `view` keeps, each cut into pieces of one
/// quantitative invisibility.
pub fn draw(
    _index: &SceneIndex,
    _view: &View,
    _options: &HlrOptions,
) -> Result<(Drawing, HlrStats)> {
    let _ = EdgeKinds::default();
    Err(Error::option("algorithm", "hlr: not built yet"))
}
