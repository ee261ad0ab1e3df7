//! The shared front end: from a scene, a camera and a viewport to screen-space convex
//! polygons that every image-space algorithm consumes.
//!
//! ```text
//! Scene ─ objects ─► frustum cull (sphere, box in clip space) ─► transform vertices
//!       (world → eye → clip) ─► back-face cull ─► trivial reject by outcodes
//!       ─► Sutherland-Hodgman against the six planes (only faces that cross one)
//!       ─► divide by w, map to pixels ─► PreparedView
//! ```
//!
//! Each stage counts faces in and out and its time ([`PipelineStats`], `--stats`).
//!
//! # Conventions
//! Screen `x` goes right and `y` down in pixels, row 0 at the top. Each vertex keeps
//! its eye-space position (so object-space algorithms can work in eye space) and a
//! *depth key* `zq`, affine in screen space, larger nearer: `near / depth` for
//! perspective, `(far - depth) / (far - near)` for orthographic projections. An
//! orthographic view's planes are first brought in to the depths its objects can have
//! (see [`fitted_orthographic_planes`]), so that its clip coordinates and `f32` keys
//! resolve the scene however wide the planes are set.
//!
//! Vertices inside the view volume are transformed once and shared by the polygons
//! that use them; only polygons crossing a clip plane get new vertices.

mod decisions;
mod options;
mod passes;
mod polygon;
mod prepare;
#[cfg(test)]
mod reference;
mod stats;
#[cfg(test)]
mod tests;
mod transform;

pub use decisions::View;
pub use options::PrepareOptions;
pub use polygon::ViewPolygon;
pub(crate) use prepare::checked_transform;
pub use prepare::{BUDGET_STRUCTURE, PreparedView, fitted_orthographic_planes, prepare};
pub use stats::{PipelineStats, StageStats};
pub use transform::{ModelView, ViewTransform, ViewVertex};
