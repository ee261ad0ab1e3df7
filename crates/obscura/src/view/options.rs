//! The options of the view pipeline.

use crate::cull::backface::BackfaceMode;

/// Options of [`prepare`](super::prepare).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct PrepareOptions {
    /// Which objects get back-face culling.
    pub backface: BackfaceMode,
    /// Whether whole objects are culled by their bounding sphere and box.
    pub frustum_cull_objects: bool,
    /// The memory budget of the prepared view in bytes (see [`crate::budget`]):
    /// [`prepare`](super::prepare) estimates its vertices and polygons before it allocates them and
    /// refuses a view over the budget. `None`: the default budget.
    pub memory_limit: Option<u64>,
}

impl PrepareOptions {
    /// Back faces of closed objects culled, objects frustum culled.
    pub const DEFAULT: PrepareOptions = PrepareOptions {
        backface: BackfaceMode::Closed,
        frustum_cull_objects: true,
        memory_limit: None,
    };

    /// These options with a memory budget in bytes (`None`: the default).
    #[must_use]
    pub fn with_memory_limit(mut self, memory_limit: Option<u64>) -> Self {
        self.memory_limit = memory_limit;
        self
    }

    /// These options with another back-face mode.
    #[must_use]
    pub fn with_backface(mut self, backface: BackfaceMode) -> Self {
        self.backface = backface;
        self
    }
}

impl Default for PrepareOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}
