//! Occluder fusion: an occlusion buffer (seed 000 "από-Σημείο (6)": partial occlusion
//! and occluder fusion). Occluders are rasterized conservatively into a buffer against
//! which bounding boxes are tested: a masked coverage buffer with per-tile depths in the
//! style of Hasselgren, Andersson and Akenine-Möller ("Masked Software Occlusion
//! Culling", High Performance Graphics 2016), or a hierarchical z-buffer (Greene, Kass
//! and Miller, "Hierarchical Z-buffer visibility", SIGGRAPH 1993).
//!
//! The pipeline of one frame ([`OcclusionBuffer::cull`]):
//! 1. **Units**: the objects the frustum kept, or (with [`CullOptions::clusters`]) their
//!    clusters the frustum kept. Each unit's world box is projected: its screen
//!    rectangle, expanded outward to whole pixels (every pixel whose sample the box
//!    could reach), and its nearest depth key, rounded towards nearer. A box with a
//!    corner at or in front of the near plane has neither and is never culled.
//! 2. **Occluders**: units ranked by the area of their screen rectangle (a box that
//!    crosses the near plane ranks first), or nearest box first
//!    ([`BufferOptions::occluder_order`]), taken in that order until
//!    [`BufferOptions::occluder_triangles`] triangles; of each, the front-facing
//!    polygons only (back faces may be culled by the view, so they are no proof of
//!    occlusion), clipped to the near plane, cut into triangles in a fan (the
//!    polygons are convex). A cluster lists its polygons largest first, so with
//!    [`BufferOptions::occluder_min_area`] only those that can cover that many buffer
//!    pixels are taken (a scene that is one big mesh has big walls and floors among
//!    much small detail). They are drawn nearest unit first, each triangle tested
//!    against the buffer before if [`BufferOptions::occluder_queries`].
//! 3. **The buffer**: the triangles rasterized conservatively ([`raster`]): a pixel
//!    counts covered only if every viewport sample it stands for lies inside the
//!    triangle, and its key is the triangle's farthest over the tile (masked) or the
//!    pixel (hierarchical), rounded towards farther. So wherever the buffer holds key
//!    `z`, the z-buffer of the whole scene draws something at least as near as `z`.
//! 4. **Tests**: objects, then clusters of objects kept: a box whose nearest key is
//!    behind the buffer at every pixel of its rectangle is culled
//!    ([`CullReason::Buffer`]).
//!
//! Why no unit is culled by its own faces, and why culling never changes the picture:
//! the nearest key of a unit's box is at least every key of its faces, and a box is
//! culled only where the buffer is strictly nearer than that, so at every pixel the
//! occluder that sets the buffer's key belongs to a unit that is not culled (were it
//! culled, the buffer there would be nearer than its own faces). That unit's face is
//! drawn, nearer than anything in the culled box.
//!
//! The kernels that rasterize run portable or compiled for AVX2
//! ([`BufferOptions::kernel`]); they run the same operations in the same order, so
//! they leave the same bits (the tests compare them).

pub mod hiz;
pub mod masked;
pub mod raster;

use std::time::Instant;

use glam::DVec3;

use super::occlusion::{BufferImage, CullOptions, CullReason, Culling};
use crate::Result;
use crate::cpu::Kernel;
use crate::geom::Aabb;
use crate::index::SceneIndex;
use crate::view::ViewTransform;
use raster::{DEPTH_MARGIN, POLY_MAX, Poly, Tri, f32_up};

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

/// In which order units give their occluders (see [`BufferOptions::occluder_order`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum OccluderOrder {
    /// The units of largest screen rectangle first.
    #[default]
    Largest,
    /// The units of nearest box first.
    Nearest,
}

/// Options of the occlusion buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct BufferOptions {
    /// The kind of buffer.
    pub kind: BufferKind,
    /// Its resolution as a divisor of the viewport's (1: full resolution).
    pub divisor: u32,
    /// The widest buffer in pixels: a larger divisor is taken when the viewport
    /// divided by [`Self::divisor`] is wider (0: no limit). Culling from a buffer of
    /// 960 pixels across at 1920x1080 culled 3791 of the 3819 objects the full
    /// resolution culls on the city's street view, in a third of the time.
    pub max_width: u32,
    /// Fill [`Culling::buffer_image`] with the buffer's depths (what `--explain`
    /// draws); off by default, as it costs a pass over the buffer.
    pub keep_image: bool,
    /// The occluder budget: triangles rasterized at most, taken from the units of
    /// largest screen area first.
    pub occluder_triangles: u32,
    /// The order in which units give their occluders until the budget is spent.
    pub occluder_order: OccluderOrder,
    /// The smallest occluder triangle drawn, in buffer pixels of area: a unit's
    /// polygons are taken largest first while their area, as seen from the unit's
    /// nearest depth, reaches it, and a triangle that projects smaller is not drawn
    /// (0: every front-facing polygon of a unit taken). A triangle of a few pixels
    /// covers few whole tiles of the buffer and costs its set-up; in a scene that is
    /// one big mesh, a cluster's box is large while most of its triangles are small.
    pub occluder_min_area: u32,
    /// Test each occluder triangle against the buffer before drawing it, and skip it
    /// when the buffer is already nearer over its whole rectangle (it could make no
    /// pixel nearer): less overdraw when near occluders come first. (Skipping
    /// triangles hidden at most of their pixels was tried: the pixels left are often
    /// the ones no other occluder covers, and fewer boxes were culled.)
    pub occluder_queries: bool,
    /// The rasterizer's compiled variant (every one gives the same buffer).
    pub kernel: Kernel,
}

impl Default for BufferOptions {
    fn default() -> Self {
        BufferOptions {
            kind: BufferKind::Masked,
            divisor: 1,
            max_width: 1024,
            keep_image: false,
            occluder_triangles: 1 << 12,
            occluder_order: OccluderOrder::Largest,
            occluder_min_area: 0,
            occluder_queries: false,
            kernel: Kernel::Auto,
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
    OcclusionBuffer::default().cull(index, t, options, c)
}

/// What a box test needs: the rectangle of buffer pixels, inclusive, and the nearest
/// key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxRect {
    /// Leftmost buffer pixel.
    pub x0: u32,
    /// Top buffer pixel.
    pub y0: u32,
    /// Rightmost buffer pixel.
    pub x1: u32,
    /// Bottom buffer pixel.
    pub y1: u32,
    /// The nearest depth key of the box, rounded towards nearer.
    pub key: f32,
    /// Screen area of the rectangle in buffer pixels (the occluder rank).
    pub area: f64,
}

/// A unit of culling: an object (`cluster == u32::MAX`) or one of its clusters.
#[derive(Clone, Copy, Debug)]
struct Unit {
    object: u32,
    cluster: u32,
    area: f64,
    /// The nearest key of its box (`+inf` when it crosses the near plane).
    key: f32,
    /// The nearest eye-space depth of its box (0 when it crosses the near plane).
    depth: f64,
    /// How many of its polygons are drawn as occluders (clusters: the first ones).
    take: u32,
}

/// The occlusion buffer and its scratch space, reused frame to frame (no allocation
/// per frame once the sizes are reached).
#[derive(Clone, Debug, Default)]
pub struct OcclusionBuffer {
    masked: masked::MaskedBuffer,
    hiz: hiz::HizBuffer,
    kind: BufferKind,
    divisor: u32,
    width: u32,
    height: u32,
    tris: Vec<Tri>,
    polys: Vec<Poly>,
    units: Vec<Unit>,
    eye: Vec<DVec3>,
    clipped: Vec<DVec3>,
}

impl OcclusionBuffer {
    /// An empty buffer (sized by the first frame).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Empties the buffer for a viewport of `width x height` pixels.
    pub fn reset(&mut self, kind: BufferKind, divisor: u32, width: u32, height: u32) {
        let d = divisor.max(1);
        self.kind = kind;
        self.divisor = d;
        self.width = width.div_ceil(d);
        self.height = height.div_ceil(d);
        let r = f64::from(d - 1) / f64::from(d);
        match kind {
            BufferKind::Masked => self.masked.reset(self.width, self.height, r),
            BufferKind::HierarchicalZ => self.hiz.reset(self.width, self.height, r),
        }
    }

    /// The buffer's size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Rasterizes triangles given in viewport pixels (`[x, y, key]` per vertex, `x`
    /// right and `y` down, the pixel sample at `+0.5`) into the buffer.
    pub fn draw_screen_triangles(&mut self, tris: &[Tri], kernel: Kernel) {
        let d = f64::from(self.divisor);
        self.tris.clear();
        self.tris.extend(
            tris.iter()
                .map(|t| t.map(|[x, y, z]| [(x - 0.5) / d, (y - 0.5) / d, z])),
        );
        let tris = std::mem::take(&mut self.tris);
        self.draw(&tris, kernel);
        self.tris = tris;
    }

    fn draw(&mut self, tris: &[Tri], kernel: Kernel) {
        match self.kind {
            BufferKind::Masked => self.masked.draw(tris, kernel),
            BufferKind::HierarchicalZ => self.hiz.draw(tris, kernel),
        }
    }

    /// Rasterizes planar convex polygons given in viewport pixels (`[x, y, key]` per
    /// vertex, as [`OcclusionBuffer::draw_screen_triangles`]), each as one primitive
    /// (no pixel lost along an inner diagonal). An error naming the first polygon
    /// that is not planar and strictly convex, or has more than eight vertices (see
    /// [`Poly::new`]); nothing is drawn then: split such a polygon into triangles.
    pub fn draw_screen_polygons(&mut self, polys: &[&[[f64; 3]]], kernel: Kernel) -> Result<()> {
        let d = f64::from(self.divisor);
        self.polys.clear();
        for (k, v) in polys.iter().enumerate() {
            let b: Vec<[f64; 3]> = v
                .iter()
                .map(|&[x, y, z]| [(x - 0.5) / d, (y - 0.5) / d, z])
                .collect();
            let Some(p) = Poly::new(&b) else {
                return Err(crate::Error::option(
                    format!("polygon {k}"),
                    "not a planar strictly convex polygon of 3 to 8 vertices",
                ));
            };
            self.polys.push(p);
        }
        let polys = std::mem::take(&mut self.polys);
        self.draw_occluders(&[], &polys, kernel);
        self.polys = polys;
        Ok(())
    }

    fn draw_occluders(&mut self, tris: &[Tri], polys: &[Poly], kernel: Kernel) {
        match self.kind {
            BufferKind::Masked => self.masked.draw_occluders(tris, polys, kernel),
            BufferKind::HierarchicalZ => self.hiz.draw_occluders(tris, polys, kernel),
        }
    }

    /// The key bound of buffer pixel `(x, y)`: every occluder covering its samples is
    /// at least this near (`-inf`: none known).
    #[must_use]
    pub fn bound(&self, x: u32, y: u32) -> f32 {
        match self.kind {
            BufferKind::Masked => self.masked.bound(x, y),
            BufferKind::HierarchicalZ => self.hiz.bound(x, y),
        }
    }

    /// Whether a box projected to `r` is hidden by the buffer.
    #[must_use]
    pub fn hidden(&self, r: &BoxRect) -> bool {
        match self.kind {
            BufferKind::Masked => self.masked.hidden(r.x0, r.y0, r.x1, r.y1, r.key),
            BufferKind::HierarchicalZ => self.hiz.hidden(r.x0, r.y0, r.x1, r.y1, r.key),
        }
    }

    /// The rectangle and nearest key of a world box, or `None` when the box must be
    /// kept whatever the buffer holds: a corner at or in front of the near plane, a
    /// rectangle outside the viewport, or a coordinate that is not finite.
    #[must_use]
    pub fn project_box(&self, t: &ViewTransform, b: &Aabb) -> Option<BoxRect> {
        self.project_box_depth(t, b).map(|(r, _)| r)
    }

    /// [`Self::project_box`] and the nearest eye-space depth of the box.
    fn project_box_depth(&self, t: &ViewTransform, b: &Aabb) -> Option<(BoxRect, f64)> {
        if b.is_empty() {
            return None;
        }
        let near = t.near.max(t.near_limit);
        let (mut x0, mut y0, mut x1, mut y1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        let mut dmin = f64::INFINITY;
        for corner in b.corners() {
            let e = t.world_to_eye(corner);
            let depth = -e.z;
            if !(depth > near) {
                return None;
            }
            let clip = t.eye_to_clip(e);
            if !(clip.w > 0.0) {
                return None;
            }
            let x = (clip.x / clip.w + 1.0) * 0.5 * t.width;
            let y = (1.0 - clip.y / clip.w) * 0.5 * t.height;
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
            dmin = dmin.min(depth);
        }
        if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
            return None;
        }
        // Viewport pixels whose sample (i + 0.5) the rectangle could reach, widened
        // for rounding.
        let slack = 1e-3 + 1e-9 * (x0.abs() + x1.abs() + y0.abs() + y1.abs());
        let i0 = (x0 - 0.5 - slack).floor().max(0.0);
        let j0 = (y0 - 0.5 - slack).floor().max(0.0);
        let i1 = (x1 - 0.5 + slack).ceil().min(t.width - 1.0);
        let j1 = (y1 - 0.5 + slack).ceil().min(t.height - 1.0);
        if !(i0 <= i1 && j0 <= j1) {
            return None;
        }
        let key = t.zq_of_depth(dmin);
        let key = f32_up(key + DEPTH_MARGIN * key.abs() + 1e-12);
        let d = self.divisor;
        let (bx0, by0, bx1, by1) = (i0 as u32 / d, j0 as u32 / d, i1 as u32 / d, j1 as u32 / d);
        Some((
            BoxRect {
                x0: bx0,
                y0: by0,
                x1: bx1.min(self.width - 1),
                y1: by1.min(self.height - 1),
                key,
                area: f64::from(bx1 - bx0 + 1) * f64::from(by1 - by0 + 1),
            },
            dmin,
        ))
    }

    /// The buffer as eye-space depths (see [`BufferImage`]).
    #[must_use]
    pub fn image(&self, t: &ViewTransform) -> BufferImage {
        let (w, h) = (self.width, self.height);
        let mut depth = Vec::with_capacity(w as usize * h as usize);
        for y in 0..h {
            for x in 0..w {
                let k = self.bound(x, y);
                depth.push(if k == f32::NEG_INFINITY {
                    f32::INFINITY
                } else {
                    t.depth_of_zq(f64::from(k)) as f32
                });
            }
        }
        BufferImage {
            width: w,
            height: h,
            depth,
        }
    }

    /// Runs the method on one frame: builds the buffer from the occluders the frustum
    /// kept and culls the objects and clusters behind it (see the [module
    /// documentation](self)).
    pub fn cull(
        &mut self,
        index: &SceneIndex<'_>,
        t: &ViewTransform,
        options: &CullOptions,
        c: &mut Culling,
    ) -> Result<()> {
        let bo = &options.buffer;
        if bo.divisor == 0 {
            return Err(crate::Error::option(
                "buffer divisor",
                "must be at least 1".to_owned(),
            ));
        }
        let start = Instant::now();
        let width = t.width as u32;
        let divisor = if bo.max_width == 0 {
            bo.divisor
        } else {
            bo.divisor.max(width.div_ceil(bo.max_width))
        };
        self.reset(bo.kind, divisor, width, t.height as u32);
        let scene = index.scene();
        let clusters = index.clusters();
        // Units and their rank.
        let mut units = std::mem::take(&mut self.units);
        units.clear();
        let full = f64::from(self.width) * f64::from(self.height);
        for (k, o) in scene.objects().iter().enumerate() {
            if o.mesh.polygon_count() == 0 || c.objects[k].is_some() {
                continue;
            }
            let unit = |b: &Aabb, cluster: usize| {
                let (area, key, depth) = self
                    .project_box_depth(t, b)
                    .map_or((full, f32::INFINITY, 0.0), |(r, d)| (r.area, r.key, d));
                Unit {
                    object: k as u32,
                    cluster: cluster as u32,
                    area,
                    key,
                    depth,
                    take: 0,
                }
            };
            if options.clusters {
                for cl in clusters.of_object(k) {
                    if c.clusters[cl].is_none() {
                        units.push(unit(clusters.bounds(cl), cl));
                    }
                }
            } else {
                units.push(unit(&o.bounds, u32::MAX as usize));
            }
        }
        match bo.occluder_order {
            OccluderOrder::Largest => units.sort_unstable_by(|a, b| b.area.total_cmp(&a.area)),
            OccluderOrder::Nearest => units.sort_unstable_by(|a, b| a.depth.total_cmp(&b.depth)),
        }
        // Occluder triangles and convex polygons.
        self.tris.clear();
        self.polys.clear();
        let budget = bo.occluder_triangles as usize;
        let min_area = f64::from(bo.occluder_min_area);
        // Buffer pixels per world unit at eye depth 1 (perspective) or anywhere
        // (orthographic).
        let scale = t.projection.y_axis.y.abs() * 0.5 * t.height / f64::from(self.divisor);
        let mut used_units = 0usize;
        // The units within the budget, then drawn nearest first: a tile filled by
        // near occluders refuses the farther ones at once (MSOC draws front to back for
        // the same reason).
        let mut selected = 0usize;
        let mut triangles = 0usize;
        let mut at = 0usize;
        while at < units.len() && triangles < budget {
            let u = &mut units[at];
            at += 1;
            if bo.occluder_order == OccluderOrder::Largest && u.area < 2.0 {
                break;
            }
            let o = &scene.objects()[u.object as usize];
            let (take, tris) = if u.cluster == u32::MAX {
                (o.mesh.polygon_count(), o.mesh.triangle_count())
            } else if min_area > 0.0 {
                // World area of the smallest polygon worth drawing from this unit.
                let s = if t.orthographic {
                    scale
                } else {
                    scale / u.depth.max(t.near.max(t.near_limit))
                };
                let least = min_area / (s * s);
                let cl = u.cluster as usize;
                let areas = clusters.areas(cl);
                let take = areas.partition_point(|&a| f64::from(a) >= least);
                let polys = &clusters.polygons(cl)[..take];
                let tris = polys
                    .iter()
                    .map(|&p| o.mesh.polygon(p as usize).len() - 2)
                    .sum();
                (take, tris)
            } else {
                let cl = u.cluster as usize;
                (clusters.polygons(cl).len(), clusters.triangles(cl) as usize)
            };
            if take == 0 {
                continue;
            }
            u.take = take as u32;
            triangles += tris;
            units.swap(selected, at - 1);
            selected += 1;
        }
        units[..selected].sort_unstable_by(|a, b| b.key.total_cmp(&a.key));
        // Objects whose occluder mesh stands for them in this view (drawn once, in
        // place of every unit of the object).
        let mut stood_for: Vec<u32> = Vec::new();
        let world = t.model_view(&glam::DMat4::IDENTITY);
        for u in &units[..selected] {
            used_units += 1;
            let o = &scene.objects()[u.object as usize];
            if let Some(occ) = o.occluder.as_deref()
                && crate::scene::occluder::occluder_usable(o, t)
            {
                if !stood_for.contains(&u.object) {
                    stood_for.push(u.object);
                    for p in 0..occ.polygon_count() as u32 {
                        self.emit(t, &world, occ, false, p, min_area);
                    }
                }
                continue;
            }
            let mv = t.model_view(&o.transform);
            if u.cluster == u32::MAX {
                for p in 0..o.mesh.polygon_count() as u32 {
                    self.emit(t, &mv, &o.mesh, o.mirrored, p, min_area);
                }
            } else {
                for &p in &clusters.polygons(u.cluster as usize)[..u.take as usize] {
                    self.emit(t, &mv, &o.mesh, o.mirrored, p, min_area);
                }
            }
        }
        self.units = units;
        c.stage("buffer occluders", start);
        let s = Instant::now();
        let (tris, polys) = (
            std::mem::take(&mut self.tris),
            std::mem::take(&mut self.polys),
        );
        let (mut drawn, mut drawn_polys) = (tris.len(), polys.len());
        if bo.occluder_queries {
            // Nearest units first: an occluder behind the buffer over its whole
            // rectangle can make no pixel nearer; it is skipped (skipping an occluder
            // never culls more).
            (drawn, drawn_polys) = (0, 0);
            for tri in &tris {
                if !self.occluder_hidden(tri) {
                    drawn += 1;
                    self.draw_occluders(std::slice::from_ref(tri), &[], bo.kernel);
                }
            }
            for poly in &polys {
                if !self.occluder_hidden(poly.vertices()) {
                    drawn_polys += 1;
                    self.draw_occluders(&[], std::slice::from_ref(poly), bo.kernel);
                }
            }
        } else {
            self.draw_occluders(&tris, &polys, bo.kernel);
        }
        (self.tris, self.polys) = (tris, polys);
        c.stage("buffer raster", s);
        // Tests: objects, then clusters of the objects kept.
        let s = Instant::now();
        let (mut culled_objects, mut culled_clusters) = (0usize, 0usize);
        for (k, o) in scene.objects().iter().enumerate() {
            if o.mesh.polygon_count() == 0 || c.objects[k].is_some() {
                continue;
            }
            if self
                .project_box(t, &o.bounds)
                .is_some_and(|r| self.hidden(&r))
            {
                c.cull_object(k, CullReason::Buffer);
                culled_objects += 1;
                continue;
            }
            if !options.clusters {
                continue;
            }
            let range = clusters.of_object(k);
            if range.len() < 2 {
                continue;
            }
            for cl in range {
                if c.clusters[cl].is_some() {
                    continue;
                }
                if self
                    .project_box(t, clusters.bounds(cl))
                    .is_some_and(|r| self.hidden(&r))
                {
                    c.cull_cluster(cl, CullReason::Buffer);
                    culled_clusters += 1;
                }
            }
        }
        c.stage("buffer tests", s);
        c.notes.push(format!(
            "occlusion buffer ({}, {}x{} pixels): {drawn_polys} of {} occluder polygons and \
             {drawn} of {} triangles from {used_units} of {} units; {culled_objects} objects \
             and {culled_clusters} clusters behind it",
            match bo.kind {
                BufferKind::Masked => "masked",
                BufferKind::HierarchicalZ => "hierarchical z",
            },
            self.width,
            self.height,
            self.polys.len(),
            self.tris.len(),
            self.units.len(),
        ));
        if bo.keep_image {
            c.buffer_image = Some(self.image(t));
        }
        Ok(())
    }

    /// Whether the buffer already hides the whole screen rectangle of an occluder
    /// (vertices in buffer coordinates) at its nearest key: drawing it could make no
    /// pixel nearer.
    fn occluder_hidden(&self, v: &[[f64; 3]]) -> bool {
        let (w, h) = (self.width as f64 - 1.0, self.height as f64 - 1.0);
        let (mut x0, mut y0, mut x1, mut y1) = (v[0][0], v[0][1], v[0][0], v[0][1]);
        let mut key = v[0][2];
        for p in &v[1..] {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
            key = key.max(p[2]);
        }
        let (x0, y0) = (x0.floor().max(0.0), y0.floor().max(0.0));
        let (x1, y1) = (x1.ceil().min(w), y1.ceil().min(h));
        !(x0 <= x1 && y0 <= y1)
            || self.hidden(&BoxRect {
                x0: x0 as u32,
                y0: y0 as u32,
                x1: x1 as u32,
                y1: y1 as u32,
                key: f32_up(key),
                area: 0.0,
            })
    }

    /// Appends polygon `p` of `mesh` (an object's, placed by `mv`, or an occluder
    /// mesh, already in world space) to the occluders, if it faces the viewer
    /// (`mirrored`: the placement flips orientation): clipped to the near plane,
    /// projected to buffer coordinates; as one convex polygon when [`Poly::new`]
    /// accepts it, else as triangles.
    fn emit(
        &mut self,
        t: &ViewTransform,
        mv: &crate::view::ModelView,
        mesh: &crate::scene::Mesh,
        mirrored: bool,
        p: u32,
        min_area: f64,
    ) {
        let pos = mesh.positions();
        self.eye.clear();
        self.eye.extend(
            mesh.polygon(p as usize)
                .iter()
                .map(|&i| mv.apply(pos[i as usize])),
        );
        let n = self.eye.len();
        if n < 3 {
            return;
        }
        // Newell's normal (counter-clockwise = front), flipped by a mirroring transform.
        let mut normal = DVec3::ZERO;
        let mut centroid = DVec3::ZERO;
        for i in 0..n {
            let (a, b) = (self.eye[i], self.eye[(i + 1) % n]);
            normal += DVec3::new(
                (a.y - b.y) * (a.z + b.z),
                (a.z - b.z) * (a.x + b.x),
                (a.x - b.x) * (a.y + b.y),
            );
            centroid += a;
        }
        centroid /= n as f64;
        if mirrored {
            normal = -normal;
        }
        let front = if t.orthographic {
            normal.z > 1e-6 * normal.length()
        } else {
            -normal.dot(centroid) > 1e-6 * normal.length() * centroid.length()
        };
        if !front {
            return;
        }
        // Clip to the near plane (depth >= near, a hair beyond it).
        let dn = t.near.max(t.near_limit) * (1.0 + 1e-6);
        self.clipped.clear();
        for i in 0..n {
            let (a, b) = (self.eye[i], self.eye[(i + 1) % n]);
            let (da, db) = (-a.z - dn, -b.z - dn);
            if da >= 0.0 {
                self.clipped.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                let s = da / (da - db);
                let mut q = a + (b - a) * s;
                // Keep the new point on the kept side despite rounding.
                q.z = q.z.min(-dn);
                self.clipped.push(q);
            }
        }
        if self.clipped.len() < 3 {
            return;
        }
        let d = f64::from(self.divisor);
        let project = |e: DVec3| {
            let clip = t.eye_to_clip(e);
            let x = (clip.x / clip.w + 1.0) * 0.5 * t.width;
            let y = (1.0 - clip.y / clip.w) * 0.5 * t.height;
            [(x - 0.5) / d, (y - 0.5) / d, t.zq_of_depth(-e.z)]
        };
        if (4..=POLY_MAX).contains(&self.clipped.len()) {
            let mut v = [[0.0; 3]; POLY_MAX];
            for (slot, &e) in v.iter_mut().zip(&self.clipped) {
                *slot = project(e);
            }
            let v = &v[..self.clipped.len()];
            if let Some(poly) = Poly::new(v) {
                // The smallest worth drawing, by the shoelace area (as a triangle's).
                let area = (0..v.len())
                    .map(|i| {
                        let (a, b) = (v[i], v[(i + 1) % v.len()]);
                        a[0] * b[1] - a[1] * b[0]
                    })
                    .sum::<f64>()
                    .abs()
                    * 0.5;
                if area >= min_area {
                    self.polys.push(poly);
                }
                return;
            }
        }
        let v0 = project(self.clipped[0]);
        let mut prev = project(self.clipped[1]);
        for &e in &self.clipped[2..] {
            let v = project(e);
            let area = ((prev[0] - v0[0]) * (v[1] - v0[1]) - (prev[1] - v0[1]) * (v[0] - v0[0]))
                .abs()
                * 0.5;
            if area >= min_area {
                self.tris.push([v0, prev, v]);
            }
            prev = v;
        }
    }
}
