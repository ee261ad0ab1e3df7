//! Warnock's area subdivision: decide a window of the image at once when the faces in
//! it allow, else cut it in four.
//!
//! Source: seed 003, "Subdivizarea ariilor elementare" (J. E. Warnock, *A hidden
//! surface algorithm for computer generated halftone pictures*, University of Utah
//! technical report, 1969). A window (the
//! seed's *arie elementară*) and a face are in one of four relations ([`Relation`]):
//! the face surrounds the window, lies inside it, is disjoint from it, or intersects
//! it. The seed's five rules, tried in order:
//! 1. every face is disjoint: the window is background;
//! 2. exactly one face intersects (or lies inside) and no other touches the window:
//!    its part is drawn, the rest is background;
//! 3. exactly one face surrounds the window and no other touches it: it fills the
//!    window;
//! 4. several faces touch the window, one of them surrounds it and is nearer than all
//!    the others over the whole window: it fills the window;
//! 5. otherwise the window is cut in four and each quarter decided the same way, down
//!    to a single pixel, where the pixel centre is sampled and the nearest face that
//!    covers it wins (on an exact tie of stored keys, the lower face id): a *pixel
//!    decision* whenever several faces cover that pixel.
//!
//! # Exactness
//! Windows are rectangles of pixels and a face *covers* a pixel by the shared rule
//! ([`crate::raster::PolygonCoverage`]), so the relations are about samples. The
//! computed edge function is monotone along x and along y separately, so it takes its
//! extreme values over a grid of samples at the grid's corners: four corner tests per
//! edge tell exactly whether a face surrounds a window, and safely (conservatively)
//! whether it is disjoint from it ([`classify`]). Depth keys are affine, so a face is
//! nearer than another over a window when it is at the window's four corner samples
//! (with a margin that survives the `f32` rounding of stored keys; near-ties go down
//! to pixels, decided on stored keys as the z-buffer decides them). Each sub-window
//! receives only the faces not disjoint from it.
//!
//! Input: a [`PreparedView`]; output: the same [`Frame`] as the z-buffer. Stats:
//! `windows`, `rule1` .. `rule5`, `pixel_decisions` (1x1 windows decided by
//! comparing the faces at the pixel centre), `classifications`, `depth_comparisons`,
//! `max_depth`.
//!
//! Complexity: each window costs O(k e) for its k faces of e edges; a face reaches
//! every window along its outline at every level, so for p pixels of face outlines
//! the work is about O(p log n) windows plus O(F log n) classifications, n the image
//! side. Memory: the frame plus the face lists of one path from the root, O(F log n).
//!
//! Limitations: faces that interpenetrate, or share an edge inside a window, force
//! subdivision down to pixels along that line (as the seed's rules do).

use crate::Result;
use crate::frame::Frame;
use crate::raster::{EdgeFunction, PixelRect, PolygonCoverage};
use crate::surface::RenderOptions;
use crate::surface::image::screen_faces::{
    ScreenFaces, corner_samples, fill_run, hides, intersect, set_pixel, stored_key, surely_nearer,
};
use crate::surface::stats::WarnockStats;
use crate::view::{PreparedView, ViewTransform};

/// How a face's covered samples relate to a window's pixels (seed 003's relations).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Relation {
    /// The face covers every pixel of the window (*A_E conținută în F*).
    Surrounding,
    /// The face's sample box lies within the window (*A_E conține F*), and it does not
    /// cover all of the window.
    Inside,
    /// Neither of the above nor provably disjoint: the face may cover some pixels of
    /// the window, and its box reaches outside it.
    Intersecting,
    /// The face covers no pixel of the window.
    Disjoint,
}

/// The relation of a face's coverage to a window (a non-empty pixel rectangle).
///
/// The computed edge function is monotone in x and in y separately, so over a
/// rectangle of samples it is extreme at the corners: four corner tests per edge tell
/// exactly whether the face covers every sample of the window (surrounding). A face
/// is called disjoint when its sample box misses the window or one of its edges
/// excludes the four corners of the box's overlap with the window: never wrong, but
/// conservative (a sliver passing between samples is called intersecting, and the
/// window is subdivided further).
///
/// ```
/// use obscura::raster::{FillRule, PixelRect, PolygonCoverage};
/// use obscura::surface::warnock::{classify, Relation};
/// let tri = [(1.0, 1.0), (7.0, 1.0), (1.0, 7.0)];
/// let c = PolygonCoverage::new(&tri, FillRule::TopLeft, 16, 16).unwrap();
/// let win = |x0, y0, x1, y1| PixelRect { x0, y0, x1, y1 };
/// assert_eq!(classify(&c, win(1, 1, 3, 3)), Relation::Surrounding);
/// assert_eq!(classify(&c, win(0, 0, 16, 16)), Relation::Inside);
/// assert_eq!(classify(&c, win(4, 4, 8, 8)), Relation::Disjoint);
/// assert_eq!(classify(&c, win(0, 0, 4, 4)), Relation::Intersecting);
/// ```
#[must_use]
pub fn classify(coverage: &PolygonCoverage, window: PixelRect) -> Relation {
    classify_edges(coverage.edges(), coverage.rect(), window)
}

/// [`classify`] from a face's edge functions and sample box.
fn classify_edges(edges: &[EdgeFunction], r: PixelRect, window: PixelRect) -> Relation {
    let o = intersect(r, window);
    if o.is_empty() {
        return Relation::Disjoint;
    }
    let [c0, c1, c2, c3] = corner_samples(o);
    let mut all_in = o == window;
    for e in edges {
        let (top, bottom) = (e.row_term(c0.1), e.row_term(c2.1));
        let n = u8::from(e.inside_row(c0.0, top))
            + u8::from(e.inside_row(c1.0, top))
            + u8::from(e.inside_row(c2.0, bottom))
            + u8::from(e.inside_row(c3.0, bottom));
        if n == 0 {
            return Relation::Disjoint;
        }
        all_in &= n == 4;
    }
    if all_in {
        Relation::Surrounding
    } else if o == r {
        Relation::Inside
    } else {
        Relation::Intersecting
    }
}

/// Renders a prepared view by area subdivision.
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, WarnockStats)> {
    let vp = view.viewport();
    let frame = Frame::new(vp)?;
    let faces = ScreenFaces::new(view, options.fill_rule);
    let root = PixelRect {
        x0: 0,
        y0: 0,
        x1: vp.width,
        y1: vp.height,
    };
    let mut s = Subdivision {
        view,
        transform: view.transform(),
        frame,
        members: Vec::with_capacity(faces.len() * 2),
        relations: Vec::with_capacity(faces.len() * 2),
        keys: Vec::new(),
        counters: Counters::default(),
        options,
        done: 0,
        total: root.area(),
        faces,
        stopped: None,
    };
    for f in 0..s.faces.len() {
        let rel = classify_edges(s.faces.edges_of(f), s.faces.faces[f].rect, root);
        s.counters.classifications += 1;
        if rel != Relation::Disjoint {
            s.members.push(f as u32);
            s.relations.push(rel);
        }
    }
    s.window(root, 0, 0);
    if let Some(e) = s.stopped {
        return Err(e);
    }
    options.report(1.0);
    let c = &s.counters;
    let stats = WarnockStats {
        polygons: view.polygon_count() as u64,
        windows: c.windows,
        rule1: c.rules[0],
        rule2: c.rules[1],
        rule3: c.rules[2],
        rule4: c.rules[3],
        rule5: c.rules[4],
        pixel_decisions: c.pixel_decisions,
        classifications: c.classifications,
        depth_comparisons: c.comparisons,
        max_depth: c.max_depth,
    };
    Ok((s.frame, stats))
}

#[derive(Debug, Default)]
struct Counters {
    windows: u64,
    rules: [u64; 5],
    pixel_decisions: u64,
    classifications: u64,
    comparisons: u64,
    max_depth: u32,
}

struct Subdivision<'v> {
    view: &'v PreparedView<'v>,
    faces: ScreenFaces,
    transform: &'v ViewTransform,
    frame: Frame,
    // The face lists of the windows on the current path, one after the other: a
    // window's faces are `members[start..]` with their relations to it.
    members: Vec<u32>,
    relations: Vec<Relation>,
    keys: Vec<[f64; 4]>,
    counters: Counters,
    options: &'v RenderOptions,
    done: u64,
    total: u64,
    /// The deadline's error (see [`crate::work`]), once it passed: no window is
    /// decided after.
    stopped: Option<crate::Error>,
}

impl Subdivision<'_> {
    /// Decides window `win`, whose faces are `members[start..]`.
    fn window(&mut self, win: PixelRect, start: usize, depth: u32) {
        if self.stopped.is_some() {
            return;
        }
        if self.counters.windows.is_multiple_of(16)
            && let Err(e) = self.options.check_time("Warnock windows")
        {
            self.stopped = Some(e);
            return;
        }
        let c = &mut self.counters;
        c.windows += 1;
        c.max_depth = c.max_depth.max(depth);
        let end = self.members.len();
        match end - start {
            0 => self.decided(win, 0),
            1 => {
                let fi = self.members[start] as usize;
                let f = &self.faces.faces[fi];
                if self.relations[start] == Relation::Surrounding {
                    self.fill_window(win, fi);
                    self.decided(win, 2);
                } else {
                    let r = intersect(win, f.rect);
                    let coverage = self.faces.coverage(self.view, fi);
                    for y in r.y0..r.y1 {
                        if let Some((a, b)) = coverage.as_ref().and_then(|c| c.row_span(y)) {
                            let (a, b) = (a.max(win.x0), b.min(win.x1));
                            fill_run(&mut self.frame, self.transform, y, a, b, &f.plane, f.face);
                        }
                    }
                    self.decided(win, 1);
                }
            }
            _ if win.area() == 1 => {
                self.pixel(win.x0, win.y0, start, end);
                self.decided(win, usize::MAX);
            }
            _ => {
                if let Some(w) = self.surrounding_nearest(win, start, end) {
                    self.fill_window(win, w as usize);
                    self.decided(win, 3);
                } else {
                    self.counters.rules[4] += 1;
                    self.subdivide(win, start, end, depth);
                }
            }
        }
    }

    /// Paints every pixel of the window with face `fi` (a face surrounding it).
    fn fill_window(&mut self, win: PixelRect, fi: usize) {
        let f = &self.faces.faces[fi];
        for y in win.y0..win.y1 {
            fill_run(
                &mut self.frame,
                self.transform,
                y,
                win.x0,
                win.x1,
                &f.plane,
                f.face,
            );
        }
    }

    /// Counts a rule (index 0..4, or none for a pixel decision) and the area done.
    fn decided(&mut self, win: PixelRect, rule: usize) {
        if let Some(n) = self.counters.rules.get_mut(rule) {
            *n += 1;
        }
        let before = self.done;
        self.done += win.area();
        // Report about every 1/64 of the image.
        let step = (self.total / 64).max(1);
        if before / step != self.done / step {
            self.options.report(self.done as f64 / self.total as f64);
        }
    }

    /// Rule 4: a face that surrounds the window and is nearer than every other face
    /// at the window's four corner samples, hence over the whole window.
    fn surrounding_nearest(&mut self, win: PixelRect, start: usize, end: usize) -> Option<u32> {
        if !self.relations[start..end].contains(&Relation::Surrounding) {
            return None;
        }
        let corners = corner_samples(win);
        self.keys.clear();
        for &f in &self.members[start..end] {
            let p = &self.faces.faces[f as usize].plane;
            self.keys.push(corners.map(|(x, y)| p.at(x, y)));
        }
        let mut w: Option<usize> = None;
        for i in 0..end - start {
            if self.relations[start + i] == Relation::Surrounding
                && w.is_none_or(|w| self.keys[i][0] > self.keys[w][0])
            {
                w = Some(i);
            }
        }
        let w = w?;
        let kw = self.keys[w];
        for (i, kg) in self.keys.iter().enumerate() {
            if i != w {
                for c in 0..4 {
                    self.counters.comparisons += 1;
                    if !surely_nearer(kw[c], kg[c]) {
                        return None;
                    }
                }
            }
        }
        Some(self.members[start + w])
    }

    /// A single pixel where no rule applied: the nearest face at its centre (all
    /// faces left surround it).
    fn pixel(&mut self, x: u32, y: u32, start: usize, end: usize) {
        self.counters.pixel_decisions += 1;
        let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
        let mut best = self.members[start];
        let mut best_key = stored_key(&self.faces.faces[best as usize].plane, px, py);
        for &g in &self.members[start + 1..end] {
            self.counters.comparisons += 1;
            let kg = stored_key(&self.faces.faces[g as usize].plane, px, py);
            if hides(kg, g, best_key, best) {
                best = g;
                best_key = kg;
            }
        }
        let f = &self.faces.faces[best as usize];
        set_pixel(&mut self.frame, self.transform, x, y, f.face, best_key);
    }

    /// Rule 5: four quarters (two halves of a one-pixel-wide or -high window), each
    /// given the faces that are not disjoint from it.
    fn subdivide(&mut self, win: PixelRect, start: usize, end: usize, depth: u32) {
        let xm = win.x0 + (win.x1 - win.x0) / 2;
        let ym = win.y0 + (win.y1 - win.y0) / 2;
        let quarters = [
            (win.x0, win.y0, xm, ym),
            (xm, win.y0, win.x1, ym),
            (win.x0, ym, xm, win.y1),
            (xm, ym, win.x1, win.y1),
        ];
        for (x0, y0, x1, y1) in quarters {
            let q = PixelRect { x0, y0, x1, y1 };
            if q.is_empty() {
                continue;
            }
            let child = self.members.len();
            for i in start..end {
                let f = self.members[i];
                // A face that surrounds a window surrounds its quarters.
                let rel = if self.relations[i] == Relation::Surrounding {
                    Relation::Surrounding
                } else {
                    self.counters.classifications += 1;
                    let fu = f as usize;
                    classify_edges(self.faces.edges_of(fu), self.faces.faces[fu].rect, q)
                };
                if rel != Relation::Disjoint {
                    self.members.push(f);
                    self.relations.push(rel);
                }
            }
            self.window(q, child, depth + 1);
            self.members.truncate(child);
            self.relations.truncate(child);
        }
    }
}
