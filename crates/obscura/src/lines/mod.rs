//! Hidden lines: drawings made of line pieces, each with its source edge, its kind and
//! its quantitative invisibility (the number of faces in front of it; 0 = visible).
//!
//! Three algorithms from the lecture notes (seed 004, seed 000; `docs/lines.md`):
//! - [`hlr`]: exact hidden-line removal for any triangle or polygon mesh. Feature edges
//!   (silhouettes, creases, boundaries, borders, intersection lines; [`edges`]) are cut
//!   wherever their image crosses an occluding face's edge, and each piece gets the
//!   number of faces in front of it (Appel 1967, "The notion of quantitative
//!   invisibility and the machine rendering of solids").
//! - [`roberts`]: Roberts' algorithm for scenes of convex polyhedra (Roberts 1963,
//!   "Machine perception of three-dimensional solids").
//! - [`horizon`]: the floating horizon for surfaces `y = f(x, z)` (Wright 1973, "A
//!   two-space solution to the hidden line problem for plotting functions of two
//!   variables"), with exact piecewise-linear horizons.
//!
//! A [`Drawing`] is independent of its output: [`plot`] joins, cleans and orders its
//! pieces into polylines, [`svg`] writes them for people and pen plotters (layers,
//! millimetres on a page), [`preview`] rasterises them to a PNG, and [`json`] keeps
//! every edge with its visible and hidden intervals for other tools.

pub mod check;
mod drawing;
pub mod edges;
pub mod hlr;
pub mod horizon;
pub mod json;
pub mod plot;
pub mod preview;
pub mod roberts;
pub mod svg;

pub use drawing::{Drawing, DrawnEdge, EdgeKind, EdgeKinds, Piece};

use std::sync::Arc;

/// A progress callback for long work: `(done, total)` in units of the work's choosing
/// (edges for hidden-line removal). Called from any thread, often; keep it cheap.
pub type Progress = Arc<dyn Fn(u64, u64) + Send + Sync>;

/// The exact drawing of what `view` sees of `index`'s scene with the default options:
/// feature edges (silhouettes, creases, boundaries, borders, intersection lines) cut
/// into pieces of one quantitative invisibility by [`hlr::draw`]. For other options,
/// Roberts' algorithm or the floating horizon, call [`hlr::draw`], [`roberts::draw`] or
/// [`horizon::draw`].
///
/// ```
/// use obscura::{Scene, SceneIndex, View, Viewport, PrepareOptions, lines};
/// let scene = Scene::demo("cube").unwrap();
/// let index = SceneIndex::new(&scene);
/// let vp = Viewport::new(320, 240).unwrap();
/// let view = View::new(&scene, &scene.default_camera(vp.aspect()), vp,
///                      &PrepareOptions::default()).unwrap();
/// let drawing = lines::draw(&index, &view).unwrap();
/// // A cube seen from a corner: 9 edges in sight (6 silhouettes, 3 creases), 3 hidden.
/// assert_eq!(drawing.visible().count(), 9);
/// assert_eq!(drawing.hidden().count(), 3);
/// let (plot, _) = lines::plot::plot(&drawing, &Default::default()).unwrap();
/// let svg = lines::svg::to_string(&plot, &Default::default()).unwrap();
/// assert!(svg.contains("inkscape:label=\"1-visible\""));
/// ```
pub fn draw(index: &crate::SceneIndex, view: &crate::View) -> crate::Result<Drawing> {
    hlr::draw(index, view, &hlr::HlrOptions::default()).map(|(d, _)| d)
}
