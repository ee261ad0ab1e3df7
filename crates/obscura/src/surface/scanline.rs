//! Placeholder: being implemented.

use crate::surface::{Algorithm, RenderOptions, Stats};
use crate::view::PreparedView;
use crate::{Frame, Result};

/// Renders a prepared view.
pub fn render(_view: &PreparedView<'_>, _options: &RenderOptions) -> Result<(Frame, Stats)> {
    Err(super::not_yet(Algorithm::Scanline))
}
