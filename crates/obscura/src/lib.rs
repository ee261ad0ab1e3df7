//! # obscura: what can be seen?
//!
//! Given a 3D scene and a view, obscura clips, culls back faces and objects outside
//! the view, and removes hidden surfaces with the classical algorithms of the field
//! behind one interface, each checked against the others. Hidden lines and occlusion
//! culling are not there yet.
//!
//! A scene comes from a file ([`Scene::load`]: OBJ, glTF, STL, PLY or a TOML scene
//! file, each behind a default cargo feature of its name), from arrays in memory
//! ([`Scene::from_arrays`]) or from a built-in demo ([`Scene::demo`]); a camera from
//! look-at parameters ([`Camera::perspective`], [`Camera::orthographic`]), from a view
//! and a projection matrix ([`Camera::from_matrices`]) or from pinhole intrinsics
//! ([`Camera::from_intrinsics`]). `examples/` shows a whole run: load, set a camera,
//! render, read ids and depth, write PNG and NPY.
//!
//! ```text
//! Scene ─► view::prepare ─► PreparedView ─► surface::render(Algorithm) ─► Frame (ids + depth)
//! ```
//!
//! ```
//! use obscura::{Scene, Viewport, prepare, PrepareOptions};
//! use obscura::surface::{render, Algorithm, RenderOptions};
//!
//! let scene = Scene::demo("default")?;
//! let viewport = Viewport::new(320, 240)?;
//! let camera = scene.default_camera(viewport.aspect());
//! let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
//! let (frame, stats) = render(Algorithm::ZBuffer, &view, &RenderOptions::default())?;
//! let tested = stats.zbuffer().map(|z| z.pixels_tested);
//! println!("{} pixels show a face; {tested:?} tested", frame.covered_pixels());
//! # Ok::<(), obscura::Error>(())
//! ```
//!
//! Conventions (coordinates, pixel sampling, ids, depth) are in `docs/ARCHITECTURE.md`
//! and in the docs of [`view`], [`raster`] and [`frame`].

#![warn(missing_docs)]
// `!(x > limit)` is how this crate rejects NaN along with small values; rewriting it
// with partial_cmp would hide that intent.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod budget;
pub mod clip;
pub(crate) mod cpu;
pub mod cull;
mod error;
pub mod frame;
pub mod geom;
pub mod index;
pub mod lines;
mod memory;
pub mod raster;
pub(crate) mod rng;
pub mod scene;
pub mod surface;
pub mod view;
pub mod work;

#[doc(hidden)]
pub mod bench_support;
#[cfg(test)]
mod tests;

pub use error::{Error, Result};
pub use frame::{BACKGROUND, Frame, RgbImage};
pub use index::{Renderer, SceneIndex};
pub use scene::{Camera, Lens, Projection, Scene, Viewport};
pub use surface::{Algorithm, RenderOptions, Stats, render};
pub use view::{PrepareOptions, PreparedView, View, prepare};
