//! Hidden-surface removal with a BSP tree: paint the tree's fragments in visibility
//! order.
//!
//! Source: seed 000, "Αλγόριθμος BSP (3)-(5)" (`DisplayBSP`) and "Αλγόριθμος
//! Ταξινόμησης Κατά Βάθος (5)" (the front-to-back variant: paint only uncovered
//! pixels, stop once every pixel is covered). The tree ([`BspTree`]) is built once per
//! scene in world space; each view only traverses it.
//!
//! - Input: a [`View`] (for the camera, viewport, transforms and its decisions: the
//!   objects it keeps, the back faces) and a [`BspTree`] of its scene ([`render`]
//!   builds one; [`render_indexed`] takes the one of a [`SceneIndex`], built once per
//!   scene; [`render_with_tree`] takes any). Output: a [`Frame`] equal to the z-buffer's.
//! - Per view: each fragment goes world -> eye (`view.transform().view`; vertices of
//!   the original mesh exactly as `view::prepare` transforms them) -> clipped and
//!   projected (directly when inside the view volume, else
//!   [`crate::view::ViewTransform::clip_and_project`]). A fragment of a polygon the view
//!   culls as a back face ([`View::back_facing`]) is skipped, and so are fragments of
//!   objects the view culls by their bounds ([`View::kept_objects`]: all their points
//!   are outside the view volume, so this changes nothing but time).
//! - A fragment that is a piece of a split polygon is painted as the pixels of the
//!   whole polygon on its sides of the node planes that cut it
//!   ([`BspTree::fragment_cuts`]; the painter in `surface::image::paint`): the pieces of a polygon
//!   then cover each of its pixels exactly once. Painted by their own vertices, a
//!   piece cut again left a crack along the edge its sibling kept whole.
//! - Traversal ([`BspOptions::traversal`](crate::accel::bsp::BspOptions)):
//!   back-to-front overwrites (the painter's algorithm); front-to-back (the default)
//!   writes each pixel once and stops when the image is full. Front to back, a
//!   subtree of 8 fragments or more is skipped when the projection of its box holds
//!   no pixel centre of the image or lies over 8x8 blocks already full: everything
//!   after it in the traversal is farther, so it could not write a pixel there
//!   anyway. Coplanar fragments are ordered so that the lower face id wins exact ties
//!   in both traversals.
//! - Complexity: O(fragments + painted pixels) per view; the build is O(c P log P)
//!   for balanced trees (see [`crate::accel::bsp`]).
//! - Stats: the tree's (nodes, fragments, splits, depth, build time), the per-view
//!   time (`view_ms`), fragments visited, culled (back faces), outside the view,
//!   painted, subtrees skipped, pixels written, and where the traversal ended
//!   (`early_exit`, `visited_fraction`).
//! - Limitations: exact depth ties between polygons that are not coplanar within the
//!   tolerance (e.g. interpenetration lines) may differ from the z-buffer's `f32`
//!   decisions by a pixel; subtrees with a corner behind the eye are never skipped.
//!
//! Papers: Schumacher, Brand, Gilliland and Sharp, AFHRL-TR-69-14, 1969 (priority by
//! separating planes); Fuchs, Kedem and Naylor, "On visible surface generation by a
//! priori tree structures", SIGGRAPH 1980; Gordon and Chen, "Front-to-back display of
//! BSP trees", IEEE CG&A 11(5), 1991 (the front-to-back variant).

use std::ops::ControlFlow;
use std::time::Instant;

use glam::DVec3;

use crate::accel::bsp::{BspTraversal, BspTree, BspVisitor, Viewpoint};
use crate::clip::outcode_homogeneous;
use crate::index::SceneIndex;
use crate::surface::RenderOptions;
use crate::surface::image::paint::{PaintMode, Painter, PixelRays, ScreenCut, piece_region};
use crate::surface::stats::BspStats;
use crate::view::{ModelView, View, ViewTransform, ViewVertex};
use crate::{Error, Frame, Result};

/// Renders a prepared view with a BSP tree built for it from `options.bsp`.
pub fn render(view: &View<'_>, options: &RenderOptions) -> Result<(Frame, BspStats)> {
    render_indexed(&SceneIndex::new(view.scene()), view, options)
}

/// Renders a view with the BSP tree of a scene index for `options.bsp` (built on
/// first use, then shared by every view).
pub fn render_indexed(
    index: &SceneIndex<'_>,
    view: &View<'_>,
    options: &RenderOptions,
) -> Result<(Frame, BspStats)> {
    // The render's budget, unless the BSP options carry their own.
    let bsp = options
        .bsp
        .with_memory_limit(options.bsp.memory_limit.or(options.memory_limit));
    let tree = index.bsp(&bsp, &options.deadline)?;
    render_with_tree(&tree, view, options)
}

impl BspTree {
    /// Renders a view of the scene this tree was built from (see [`render_with_tree`]).
    pub fn render(&self, view: &View<'_>, options: &RenderOptions) -> Result<(Frame, BspStats)> {
        render_with_tree(self, view, options)
    }
}

/// What a view needs to know about each object and polygon.
struct ViewData<'v> {
    /// Per scene object, whether the view keeps it ([`View::kept_objects`]).
    visible: &'v [bool],
    /// Per tree vertex, its eye-space position (only for visible objects).
    eye: Vec<DVec3>,
    /// Per object, the index of its first polygon in `back_facing`.
    polygon_base: &'v [u32],
    /// The view's back faces ([`View::back_facing`]).
    back_facing: &'v [bool],
}

/// The eye positions of the tree's vertices, and the view's decisions: which objects
/// survive object culling and which polygons are back faces, read from the view (the
/// same decisions every algorithm reads).
fn view_data<'v>(tree: &BspTree, view: &'v View<'_>) -> ViewData<'v> {
    let scene = view.scene();
    let t = view.transform();
    let visible = view.kept_objects();
    let model_view: Vec<ModelView> = scene
        .objects()
        .iter()
        .map(|o| t.model_view(&o.transform))
        .collect();
    let eye: Vec<DVec3> = tree
        .vertices()
        .iter()
        .map(|v| {
            let k = v.object as usize;
            if !visible[k] {
                return DVec3::NAN;
            }
            match v.mesh_vertex() {
                Some(i) => model_view[k].apply(scene.objects()[k].mesh.positions()[i as usize]),
                None => t.world_to_eye(v.world),
            }
        })
        .collect();
    ViewData {
        visible,
        eye,
        polygon_base: view.polygon_base(),
        back_facing: view.skipped_polygons(),
    }
}

/// Subtrees with fewer fragments are not tested for occlusion (the test costs about
/// as much as projecting them).
const CULL_MIN_FRAGMENTS: u32 = 8;

#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    visited: u64,
    culled: u64,
    outside: u64,
    hidden: u64,
    subtrees_outside: u64,
}

/// Paints the fragments a traversal visits.
struct Visitor<'a> {
    tree: &'a BspTree,
    data: &'a ViewData<'a>,
    t: ViewTransform,
    painter: &'a mut Painter,
    /// Skip subtrees whose projected box lies outside the image or over pixels
    /// already painted (front to back only: everything after is farther).
    cull_subtrees: bool,
    counts: Counts,
    rays: PixelRays,
    eye_pts: Vec<DVec3>,
    clip_pts: Vec<glam::DVec4>,
    screen: Vec<ViewVertex>,
    whole: Vec<ViewVertex>,
    cuts: Vec<ScreenCut>,
    /// The render's deadline (see [`crate::work`]) and the error that stopped the
    /// traversal.
    deadline: &'a crate::work::Deadline,
    stopped: Option<Error>,
}

impl Visitor<'_> {
    /// Clips and projects the tree vertices `indices` (eye positions from the view
    /// data) into `out`; false when nothing of the polygon is inside the view volume.
    fn project(&mut self, indices: &[u32], whole: bool) -> bool {
        let (data, t) = (self.data, self.t);
        self.eye_pts.clear();
        self.eye_pts
            .extend(indices.iter().map(|&v| data.eye[v as usize]));
        self.clip_pts.clear();
        let (mut and, mut or) = (0x3f, 0);
        for &e in &self.eye_pts {
            let c = t.eye_to_clip(e);
            let code = outcode_homogeneous(c);
            and &= code;
            or |= code;
            self.clip_pts.push(c);
        }
        let out = if whole {
            &mut self.whole
        } else {
            &mut self.screen
        };
        out.clear();
        if and != 0 {
            return false;
        }
        if or == 0 {
            out.extend(
                self.clip_pts
                    .iter()
                    .zip(&self.eye_pts)
                    .map(|(&c, &e)| t.to_screen(c, e)),
            );
            true
        } else {
            t.clip_and_project(&self.eye_pts, out) != 0
        }
    }
}

impl BspVisitor for Visitor<'_> {
    fn enter(&mut self, node: u32) -> bool {
        if !self.cull_subtrees || self.tree.subtree_fragments(node) < CULL_MIN_FRAGMENTS {
            return true;
        }
        let b = self.tree.subtree_bounds(node);
        if b.is_empty() {
            return false;
        }
        // A corner behind the eye plane: its projection bounds nothing.
        let Some((minx, miny, maxx, maxy)) = self.t.screen_box(b) else {
            return true;
        };
        // No pixel centre in the box (widened far above rounding): nothing to paint.
        const WIDEN: f64 = 1e-6;
        if maxx + WIDEN < 0.5
            || maxy + WIDEN < 0.5
            || minx - WIDEN > self.t.width - 0.5
            || miny - WIDEN > self.t.height - 0.5
        {
            self.counts.subtrees_outside += 1;
            return false;
        }
        if self.painter.box_covered(minx, miny, maxx, maxy) {
            self.counts.hidden += 1;
            return false;
        }
        true
    }

    fn fragment(&mut self, f: u32) -> ControlFlow<()> {
        self.counts.visited += 1;
        if self.counts.visited.is_multiple_of(256)
            && let Err(e) = self.deadline.check("BSP traversal")
        {
            self.stopped = Some(e);
            return ControlFlow::Break(());
        }
        let (tree, data) = (self.tree, self.data);
        let frag = tree.fragment(f);
        let k = frag.object as usize;
        if !data.visible[k]
            || data.back_facing[data.polygon_base[k] as usize + frag.polygon as usize]
        {
            self.counts.culled += 1;
            return ControlFlow::Continue(());
        }
        if !self.project(tree.fragment_vertex_indices(f), false) {
            self.counts.outside += 1;
            return ControlFlow::Continue(());
        }
        if tree.fragment_cuts(f).len() == 0 {
            self.painter.paint_vertices(&self.screen, frag.face);
        } else {
            // A piece of a split polygon: the whole polygon's pixels on the piece's
            // sides of its cuts (see the module doc).
            let region = piece_region(&self.screen, self.t.width, self.t.height);
            if !self.project(tree.fragment_vertex_indices(tree.fragment_root(f)), true) {
                self.counts.outside += 1;
                return ControlFlow::Continue(());
            }
            self.cuts.clear();
            for (node, front) in tree.fragment_cuts(f) {
                let cut = self.rays.cut(&frag.plane, &tree.node(node).plane, front);
                self.cuts.push(cut);
            }
            self.painter
                .paint_piece_of(&self.whole, region, &self.cuts, frag.face);
        }
        if self.painter.is_complete() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

/// Renders a view with a tree built (once) from the view's scene. Fails if the tree
/// was built from a scene with other objects or face ids.
///
/// ```
/// use obscura::accel::bsp::{BspOptions, BspTree};
/// use obscura::surface::{bsp, render, Algorithm, RenderOptions};
/// use obscura::{scene::{demo, Camera, Viewport}, prepare, PrepareOptions};
/// use glam::DVec3;
/// let scene = demo::cube();
/// let tree = BspTree::build(&scene, &BspOptions::default()).unwrap();
/// let vp = Viewport::new(40, 30).unwrap();
/// for eye in [DVec3::new(2., 1.5, 3.), DVec3::new(-3., -1., 2.)] {
///     let cam = Camera::perspective(eye, DVec3::ZERO, DVec3::Y, 50.0, 0.1, 20.0);
///     let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
///     let (frame, _) = bsp::render_with_tree(&tree, &view, &RenderOptions::default()).unwrap();
///     let (z, _) = render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap();
///     assert_eq!(frame.ids, z.ids);
/// }
/// ```
pub fn render_with_tree(
    tree: &BspTree,
    view: &View<'_>,
    options: &RenderOptions,
) -> Result<(Frame, BspStats)> {
    if !tree.matches(view.scene()) {
        return Err(Error::option(
            "bsp::render_with_tree tree",
            "the BSP tree was built from another scene (objects, vertices or face ids differ)",
        ));
    }
    let traversal = options.bsp.traversal;
    let mode = match traversal {
        BspTraversal::BackToFront => PaintMode::Overwrite,
        BspTraversal::FrontToBack => PaintMode::WriteOnce,
    };
    let mut painter = Painter::new(view, options.fill_rule, mode)?;
    let start = Instant::now();
    let data = view_data(tree, view);
    let viewpoint = Viewpoint::of_camera(view.camera());
    let mut v = Visitor {
        tree,
        data: &data,
        t: *view.transform(),
        painter: &mut painter,
        cull_subtrees: traversal == BspTraversal::FrontToBack,
        counts: Counts::default(),
        rays: PixelRays::new(view, |p| p - tree.origin(), |d| d),
        eye_pts: Vec::new(),
        clip_pts: Vec::new(),
        screen: Vec::new(),
        whole: Vec::new(),
        cuts: Vec::new(),
        deadline: &options.deadline,
        stopped: None,
    };
    let done = tree.traverse_with(viewpoint, traversal, &mut v);
    if let Some(e) = v.stopped {
        return Err(e);
    }
    let counts = v.counts;
    let view_ms = start.elapsed().as_secs_f64() * 1e3;
    let total = tree.stats().fragments;
    let b = tree.stats();
    let stats = BspStats {
        bsp_nodes: b.nodes,
        bsp_fragments: b.fragments,
        bsp_splits: b.splits,
        bsp_depth: b.depth,
        build_ms: b.build_ms,
        front_to_back: traversal == BspTraversal::FrontToBack,
        view_ms,
        fragments_visited: counts.visited,
        fragments_culled: counts.culled,
        fragments_outside: counts.outside,
        subtrees_hidden: counts.hidden,
        subtrees_outside: counts.subtrees_outside,
        fragments_painted: painter.polygons_painted,
        pixels_written: painter.pixels_written,
        early_exit: !done,
        visited_fraction: if total == 0 {
            1.0
        } else {
            counts.visited as f64 / total as f64
        },
    };
    Ok((painter.finish(), stats))
}
