//! Occluder fusion: an occlusion buffer (seed 000 "από-Σημείο (6)": partial occlusion
//! and occluder fusion). Occluders are rasterized conservatively into a buffer against
//! which bounding boxes are tested: a masked coverage buffer with per-tile depths in the
//! style of Hasselgren, Andersson and Akenine-Möller ("Masked Software Occlusion
//! Culling", High Performance Graphics 2016), or a hierarchical z-buffer (Greene, Kass
//! and Miller, "Hierarchical Z-buffer visibility", SIGGRAPH 1993).
//!
//! STUB of the contract: culls nothing yet.

use super::occlusion::{CullOptions, Culling};
use crate::Result;
use crate::index::SceneIndex;
use crate::view::ViewTransform;

/// Which occlusion buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum BufferKind {
    /// Per 8x4 tile a coverage mask and two depths (MSOC style).
    #[default]
    Masked,
    /// A depth per pixel and its max-depth pyramid.
    HierarchicalZ,
}

/// Options of the occlusion buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct BufferOptions {
    /// The kind of buffer.
    pub kind: BufferKind,
    /// Its resolution as a divisor of the viewport's (1: full resolution).
    pub divisor: u32,
}

impl Default for BufferOptions {
    fn default() -> Self {
        BufferOptions {
            kind: BufferKind::Masked,
            divisor: 1,
        }
    }
}

/// Culls, among what the frustum left, the objects and clusters whose boxes lie behind
/// the occlusion buffer.
pub(crate) fn cull(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let _ = (index, t, options, c);
    Ok(())
}
