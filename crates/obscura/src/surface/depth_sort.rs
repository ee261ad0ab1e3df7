//! Placeholder: being implemented.

use crate::surface::{Algorithm, RenderOptions, Stats};
use crate::view::PreparedView;
use crate::{Frame, Result};

/// Renders a prepared view by depth sort with the five tests.
pub fn render(_view: &PreparedView<'_>, _options: &RenderOptions) -> Result<(Frame, Stats)> {
    Err(super::not_yet(Algorithm::DepthSort))
}

/// Renders a prepared view by depth sort with a covering matrix.
pub fn render_matrix(_view: &PreparedView<'_>, _options: &RenderOptions) -> Result<(Frame, Stats)> {
    Err(super::not_yet(Algorithm::DepthSortMatrix))
}
