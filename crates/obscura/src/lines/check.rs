//! The sampling oracle: checks a [`Drawing`]'s visibility against ray casting, with no
//! code in common with the algorithms that cut edges into pieces.
//!
//! # Method
//! For every piece, a few points are taken in its interior, a margin (in pixels) away
//! from its ends and from the picture's border, spaced evenly on screen (the 3D
//! parameter of a screen position is found by perspective-correct interpolation of the
//! piece's ends, which are themselves projected here, not read from
//! [`Piece::points`]). For each sample point `P` on its 3D edge, one ray is cast through
//! `P` from the eye (perspective) or along the view axis from the eye plane
//! (orthographic) against the scene's BVH ([`SceneIndex::bvh`], exact watertight
//! triangle tests), ignoring the polygons the edge lies on ([`super::DrawnEdge::faces`]). The
//! point is *covered* when a surface is hit nearer than `P` by more than the tolerance:
//! at a ray parameter below `t_P (1 - tolerance)` (perspective, `t_P = 1`), or below
//! `d_P - tolerance max(|d_P|, far - near)` (orthographic, `d_P` the sample's depth).
//! A visible piece (quantitative invisibility 0) must have no covered sample, a hidden
//! piece only covered samples. Back faces are not ignored: whatever the view culls,
//! a surface in front hides.
//!
//! This is the test of seed 000's ray casting ("Αλγόριθμος Εκπομπής Ακτίνων") turned
//! on a line drawing, as issue 23 asks of `--check`: a user can trust a drawing that
//! passes it, and a test can check any algorithm against it.
//!
//! # Limitations
//! - It checks visible/hidden only, not the number of faces in front of a hidden piece.
//! - Pieces shorter on screen than twice the margin, and samples outside the picture
//!   (by the margin) or outside the near and far planes, are not sampled; the report
//!   counts the pieces left without a sample.
//! - A sample within the tolerance of another surface (coplanar touching faces) counts
//!   as visible.
//!
//! # Complexity
//! One BVH ray per sample: `O(S log T)` for `S` samples and `T` triangles, in parallel
//! with the `parallel` feature.

use glam::{DVec2, DVec3};
use serde::Serialize;

use super::{Drawing, Piece};
use crate::accel::bvh::traverse::{TraceCounters, TraversalStack};
use crate::accel::triangles::{HitContext, PrimaryRays, TieRule, WatertightRay};
use crate::scene::Projection;
use crate::{SceneIndex, View};

/// Options of [`check`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct CheckOptions {
    /// Sample points per piece (at least 1).
    pub samples_per_piece: u32,
    /// Distance in pixels kept from a piece's ends and from the picture's border.
    pub margin_pixels: f64,
    /// Relative depth tolerance (see the module doc).
    pub depth_tolerance: f64,
    /// At most this many disagreements are listed (all are counted).
    pub max_listed: usize,
}

impl CheckOptions {
    /// The defaults: 3 samples a piece, 1 pixel margin, tolerance `1e-6`, 1000 listed.
    pub const DEFAULT: CheckOptions = CheckOptions {
        samples_per_piece: 3,
        margin_pixels: 1.0,
        depth_tolerance: 1e-6,
        max_listed: 1000,
    };

    /// These options with `n` samples per piece.
    #[must_use]
    pub fn with_samples(mut self, n: u32) -> Self {
        self.samples_per_piece = n;
        self
    }

    /// These options with another margin in pixels.
    #[must_use]
    pub fn with_margin(mut self, pixels: f64) -> Self {
        self.margin_pixels = pixels;
        self
    }

    /// These options with another relative depth tolerance.
    #[must_use]
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.depth_tolerance = tolerance;
        self
    }
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions::DEFAULT
    }
}

/// Whether a point is seen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Visibility {
    /// Nothing nearer hides it.
    Visible,
    /// A surface lies in front of it.
    Hidden,
}

/// A sample whose visibility disagrees with its piece's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Disagreement {
    /// Index of the piece in [`Drawing::pieces`].
    pub piece: u32,
    /// Its edge (index in [`Drawing::edges`]).
    pub edge: u32,
    /// The sample's parameter along the 3D edge.
    pub t: f64,
    /// The sample's position in pixels.
    pub pixel: [f64; 2],
    /// What the drawing says.
    pub expected: Visibility,
    /// What ray casting found.
    pub found: Visibility,
    /// The polygon (global number) hit in front of the sample, if any.
    pub occluder: Option<u32>,
}

/// What [`check`] found.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct CheckReport {
    /// Pieces with at least one sample.
    pub pieces_checked: u64,
    /// Pieces left without a sample (too short on screen, outside the picture).
    pub pieces_unsampled: u64,
    /// Pieces that cannot be checked: an edge index out of range or a parameter
    /// interval outside `0..=1` or not finite.
    pub pieces_invalid: u64,
    /// Sample points cast.
    pub samples: u64,
    /// Pieces with at least one disagreeing sample.
    pub pieces_disagreeing: u64,
    /// Disagreeing samples (all of them, listed or not).
    pub disagreement_count: u64,
    /// The first disagreeing samples, by piece (at most [`CheckOptions::max_listed`]).
    pub disagreements: Vec<Disagreement>,
}

impl CheckReport {
    /// Whether every sample agrees and every piece was valid.
    #[must_use]
    pub fn agrees(&self) -> bool {
        self.disagreement_count == 0 && self.pieces_invalid == 0
    }

    fn merge(&mut self, o: CheckReport, max_listed: usize) {
        self.pieces_checked += o.pieces_checked;
        self.pieces_unsampled += o.pieces_unsampled;
        self.pieces_invalid += o.pieces_invalid;
        self.samples += o.samples;
        self.pieces_disagreeing += o.pieces_disagreeing;
        self.disagreement_count += o.disagreement_count;
        let room = max_listed.saturating_sub(self.disagreements.len());
        self.disagreements
            .extend(o.disagreements.into_iter().take(room));
    }
}

/// What every sample test reads, made once.
struct Caster<'a> {
    index: &'a SceneIndex<'a>,
    view: &'a View<'a>,
    drawing: &'a Drawing,
    options: CheckOptions,
    /// Identity: hits report polygon numbers.
    polygon_ids: Vec<u32>,
    tie: TieRule,
    eye: DVec3,
    forward: DVec3,
    orthographic: bool,
}

/// Per-thread scratch: the ignored polygons (an edge's own, set and reset per piece)
/// and a traversal stack.
struct Scratch {
    ignored: Vec<bool>,
    stack: TraversalStack,
}

/// Checks every piece of `drawing` (a drawing of `view` of `index`'s scene) against ray
/// casting; see the [module documentation](self).
#[must_use]
pub fn check(
    index: &SceneIndex,
    view: &View,
    drawing: &Drawing,
    options: &CheckOptions,
) -> CheckReport {
    let camera = view.camera();
    let (_, _, forward) = camera.basis();
    let polygons = index.triangles().polygon_count();
    let caster = Caster {
        index,
        view,
        drawing,
        options: CheckOptions {
            samples_per_piece: options.samples_per_piece.max(1),
            margin_pixels: options.margin_pixels.max(0.0),
            depth_tolerance: options.depth_tolerance.max(0.0),
            ..*options
        },
        polygon_ids: (0..polygons as u32).collect(),
        tie: PrimaryRays::new(camera, view.viewport()).tie_rule(),
        eye: camera.eye,
        forward,
        orthographic: matches!(camera.projection, Projection::Orthographic { .. }),
    };
    let scratch = || Scratch {
        ignored: vec![false; polygons],
        stack: TraversalStack::default(),
    };
    const CHUNK: usize = 256;
    let n = drawing.pieces.len();
    let chunks = n.div_ceil(CHUNK);
    let run = |s: &mut Scratch, c: usize| caster.chunk(s, c * CHUNK..((c + 1) * CHUNK).min(n));
    #[cfg(feature = "parallel")]
    let parts: Vec<CheckReport> = {
        use rayon::prelude::*;
        (0..chunks)
            .into_par_iter()
            .map_init(scratch, |s, c| run(s, c))
            .collect()
    };
    #[cfg(not(feature = "parallel"))]
    let parts: Vec<CheckReport> = {
        let mut s = scratch();
        (0..chunks).map(|c| run(&mut s, c)).collect()
    };
    let mut report = CheckReport::default();
    for p in parts {
        report.merge(p, caster.options.max_listed);
    }
    report
}

impl Caster<'_> {
    fn chunk(&self, s: &mut Scratch, range: std::ops::Range<usize>) -> CheckReport {
        let mut r = CheckReport::default();
        for i in range {
            self.piece(s, i, &mut r);
        }
        r
    }

    /// The pixel position and eye depth of a world point; `None` at or behind the eye
    /// plane (perspective).
    fn project(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let t = self.view.transform();
        let eye = t.world_to_eye(p);
        let clip = t.eye_to_clip(eye);
        if !self.orthographic && !(clip.w > 0.0) {
            return None;
        }
        let v = t.to_screen(clip, eye);
        Some((DVec2::new(v.x, v.y), -eye.z))
    }

    fn piece(&self, s: &mut Scratch, i: usize, r: &mut CheckReport) {
        let piece: &Piece = &self.drawing.pieces[i];
        let Some(edge) = self.drawing.edges.get(piece.edge as usize) else {
            r.pieces_invalid += 1;
            return;
        };
        let [t0, t1] = piece.t;
        let unit = 0.0..=1.0;
        if !(unit.contains(&t0) && unit.contains(&t1)) {
            r.pieces_invalid += 1;
            return;
        }
        let (a, b) = (edge.point(t0), edge.point(t1));
        let (Some((sa, da)), Some((sb, db))) = (self.project(a), self.project(b)) else {
            r.pieces_unsampled += 1;
            return;
        };
        let o = &self.options;
        let length = sa.distance(sb);
        if !(length > 2.0 * o.margin_pixels) {
            r.pieces_unsampled += 1;
            return;
        }
        let own = edge.faces;
        for f in own.iter().flatten() {
            if let Some(x) = s.ignored.get_mut(*f as usize) {
                *x = true;
            }
        }
        let expected = if piece.is_visible() {
            Visibility::Visible
        } else {
            Visibility::Hidden
        };
        let (w, h) = (
            f64::from(self.drawing.width),
            f64::from(self.drawing.height),
        );
        let lo = o.margin_pixels / length;
        let n = o.samples_per_piece;
        let (mut sampled, mut disagreed) = (false, false);
        for k in 0..n {
            // Evenly on screen, then back to the 3D parameter: 1/depth and u/depth are
            // linear on screen in perspective.
            let f = lo + (1.0 - 2.0 * lo) * (f64::from(k) + 0.5) / f64::from(n);
            let u = if self.orthographic {
                f
            } else {
                f * da / (f * da + (1.0 - f) * db)
            };
            let t = t0 + (t1 - t0) * u;
            let p = edge.point(t);
            let Some((pixel, depth)) = self.project(p) else {
                continue;
            };
            let m = o.margin_pixels;
            let camera = self.view.camera();
            let inside = pixel.x >= m && pixel.x <= w - m && pixel.y >= m && pixel.y <= h - m;
            if !(inside && depth >= camera.near && depth <= camera.far) {
                continue;
            }
            sampled = true;
            r.samples += 1;
            let occluder = self.occluder(s, p, depth);
            let found = if occluder.is_some() {
                Visibility::Hidden
            } else {
                Visibility::Visible
            };
            if found != expected {
                disagreed = true;
                r.disagreement_count += 1;
                if r.disagreements.len() < o.max_listed {
                    r.disagreements.push(Disagreement {
                        piece: i as u32,
                        edge: piece.edge,
                        t,
                        pixel: [pixel.x, pixel.y],
                        expected,
                        found,
                        occluder,
                    });
                }
            }
        }
        for f in own.iter().flatten() {
            if let Some(x) = s.ignored.get_mut(*f as usize) {
                *x = false;
            }
        }
        if sampled {
            r.pieces_checked += 1;
        } else {
            r.pieces_unsampled += 1;
        }
        r.pieces_disagreeing += u64::from(disagreed);
    }

    /// The polygon hit nearer than `p` (of eye depth `depth`) by more than the
    /// tolerance, if any.
    fn occluder(&self, s: &mut Scratch, p: DVec3, depth: f64) -> Option<u32> {
        let camera = self.view.camera();
        let tol = self.options.depth_tolerance;
        let (origin, direction, t_min, t_max) = if self.orthographic {
            let range = (camera.far - camera.near).abs();
            (
                p - self.forward * depth,
                self.forward,
                camera.near_limit(),
                depth - tol * depth.abs().max(range),
            )
        } else {
            (
                self.eye,
                p - self.eye,
                camera.near_limit() / depth,
                1.0 - tol,
            )
        };
        let ray = WatertightRay::new(origin, direction)?;
        let bvh = self.index.bvh();
        if bvh.is_empty() || !(t_min <= t_max) {
            return None;
        }
        let ctx = HitContext {
            ray,
            ignored: &s.ignored,
            faces: &self.polygon_ids,
            t_min,
            tie: self.tie,
        };
        let hit = bvh.closest_hit(&ctx, t_max, &mut s.stack, &mut TraceCounters::default());
        (hit.is_hit() && hit.t < t_max).then_some(hit.face)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lines::{DrawnEdge, EdgeKind};
    use crate::scene::{Camera, Viewport, demo};
    use crate::view::PrepareOptions;

    /// A unit cube seen head-on: its front face's bottom edge is visible, its back
    /// face's bottom edge hidden behind the front face.
    #[test]
    fn front_edge_visible_back_edge_hidden() {
        let scene = demo::cube();
        let index = SceneIndex::new(&scene);
        let b = scene.bounds();
        let c = b.center();
        let eye = c + DVec3::new(0.0, 0.3, 5.0);
        let camera = Camera::perspective(eye, c, DVec3::Y, 40.0, 0.1, 50.0);
        let vp = Viewport::new(200, 150).unwrap();
        let view = View::new(&scene, &camera, vp, &PrepareOptions::default()).unwrap();
        let (lo, hi) = (b.min, b.max);
        let edge = |z: f64| DrawnEdge {
            vertices: None,
            object: Some(0),
            kind: EdgeKind::Other,
            faces: [None, None],
            world: [DVec3::new(lo.x, lo.y, z), DVec3::new(hi.x, lo.y, z)],
        };
        let piece = |e: u32, qi: u32| Piece {
            edge: e,
            t: [0.0, 1.0],
            points: [DVec2::ZERO; 2],
            invisibility: qi,
        };
        let mut d = Drawing::new(200, 150);
        // A point just outside the front face (not on it): visible; the back edge
        // (slightly inside the cube, so not on a face): hidden.
        let eps = 1e-3 * (hi.z - lo.z);
        d.edges = vec![edge(hi.z + eps), edge(lo.z + eps)];
        d.pieces = vec![piece(0, 0), piece(1, 1)];
        let r = check(&index, &view, &d, &CheckOptions::default());
        assert_eq!(r.pieces_checked, 2, "{r:?}");
        assert!(r.agrees(), "{r:?}");
        d.pieces = vec![piece(0, 1), piece(1, 0)];
        let r = check(&index, &view, &d, &CheckOptions::default());
        assert_eq!(r.pieces_disagreeing, 2, "{r:?}");
        assert_eq!(r.disagreement_count, 6);
        assert_eq!(r.disagreements[0].found, Visibility::Visible);
        assert_eq!(r.disagreements[3].found, Visibility::Hidden);
        assert!(r.disagreements[3].occluder.is_some());
        // Invalid pieces are counted, not checked.
        d.pieces = vec![piece(7, 0)];
        let r = check(&index, &view, &d, &CheckOptions::default());
        assert_eq!((r.pieces_invalid, r.agrees()), (1, false));
    }
}
