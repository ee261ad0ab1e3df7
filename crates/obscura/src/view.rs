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

mod passes;

use std::time::Instant;

use glam::{DMat3, DMat4, DVec3, DVec4};
use serde::Serialize;

use crate::Result;
use crate::clip::outcode_homogeneous;
use crate::clip::sutherland_hodgman::{ClipEyeVertex, clip_polygon_homogeneous_masked};
use crate::cull::backface::BackfaceMode;
use crate::cull::frustum::{Containment, classify_clip_points, classify_sphere, frustum_planes};
use crate::geom::{Plane, Sphere};
use crate::raster::{DepthPlane, FillRule, PolygonCoverage};
use crate::scene::{Camera, Object, Projection, Scene, Viewport};

/// Options of [`prepare`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub struct PrepareOptions {
    /// Which objects get back-face culling.
    pub backface: BackfaceMode,
    /// Whether whole objects are culled by their bounding sphere and box.
    pub frustum_cull_objects: bool,
    /// The memory budget of the prepared view in bytes (see [`crate::budget`]):
    /// [`prepare`] estimates its vertices and polygons before it allocates them and
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

/// A vertex of a prepared polygon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewVertex {
    /// Screen x in pixels (right).
    pub x: f64,
    /// Screen y in pixels (down).
    pub y: f64,
    /// Depth key: affine in screen space, larger is nearer.
    pub zq: f64,
    /// Eye-space position (the camera looks down -z).
    pub eye: DVec3,
}

/// Object to eye space for one object, relative to the camera
/// ([`ViewTransform::model_view`]): `rotation (shift + linear p)`, where `shift` is the
/// object's translation less the camera's position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelView {
    /// The object transform's linear part.
    pub linear: DMat3,
    /// The object transform's translation less the camera's position (world axes).
    pub shift: DVec3,
    /// World to eye without the translation.
    pub rotation: DMat3,
}

impl ModelView {
    /// The eye-space position of the object-space point `p`. The vertex pass computes
    /// eight points at once with the same operations in the same order (per
    /// coordinate: `shift + (z p.z + (y p.y + x p.x))` with the columns of `linear`,
    /// then `z q.z + (y q.y + x q.x)` with those of `rotation`), so the same bits.
    #[inline(always)]
    #[must_use]
    pub fn apply(&self, p: DVec3) -> DVec3 {
        let (l, r) = (&self.linear, &self.rotation);
        let q = DVec3::from_array(std::array::from_fn(|k| {
            self.shift[k] + (l.z_axis[k] * p.z + (l.y_axis[k] * p.y + l.x_axis[k] * p.x))
        }));
        DVec3::from_array(std::array::from_fn(|k| {
            r.z_axis[k] * q.z + (r.y_axis[k] * q.y + r.x_axis[k] * q.x)
        }))
    }
}

impl ViewVertex {
    /// Eye-space depth (distance along the view axis).
    #[must_use]
    pub fn depth(&self) -> f64 {
        -self.eye.z
    }
}

/// The matrices and constants that map eye space to the screen.
///
/// World points reach eye space relative to the camera: first `p - eye` (in world
/// axes), then [`Self::rotation`]. Far from the origin that difference is exact or
/// nearly so for points near the camera, where the single matrix [`Self::view`]
/// (`rotation p - rotation eye`) would cancel two large products: at an offset of
/// 2^43 its rounding moved a unit triangle seen from 5 units by 1/7 pixel, and the
/// frustum's far plane taken from [`Self::view_projection`] at 4e22 was off by 1e14.
/// [`Self::world_to_eye`], [`Self::model_view`] and [`Self::object_containment`] work
/// this way; the pipeline, BSP and object culling use them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewTransform {
    /// World to eye in one matrix (see the type's doc for the precise path).
    pub view: DMat4,
    /// The camera's position in world space.
    pub eye: DVec3,
    /// World to eye without the translation: the camera's basis as rows.
    pub rotation: DMat3,
    /// Eye to clip.
    pub projection: DMat4,
    /// World to clip.
    pub view_projection: DMat4,
    /// Viewport width in pixels.
    pub width: f64,
    /// Viewport height in pixels.
    pub height: f64,
    /// Near plane distance.
    pub near: f64,
    /// [`Camera::near_limit`]: the smallest depth kept.
    pub near_limit: f64,
    /// `z + w` of clip space per unit of depth beyond the near plane: `2 far / (far -
    /// near)` (perspective) or `2 / (far - near)` (orthographic).
    pub near_scale: f64,
    /// Far plane distance.
    pub far: f64,
    /// Parallel projection.
    pub orthographic: bool,
}

impl ViewTransform {
    /// The transform of a camera for a viewport.
    #[must_use]
    pub fn new(camera: &Camera, viewport: Viewport) -> Self {
        let view = camera.view_matrix();
        let projection = camera.projection_matrix(viewport.aspect());
        ViewTransform {
            view,
            eye: camera.eye,
            rotation: DMat3::from_mat4(view),
            projection,
            view_projection: projection * view,
            width: f64::from(viewport.width),
            height: f64::from(viewport.height),
            near: camera.near,
            near_limit: camera.near_limit(),
            near_scale: match camera.projection {
                Projection::Perspective { .. } => 2.0 * camera.far / (camera.far - camera.near),
                Projection::Orthographic { .. } => 2.0 / (camera.far - camera.near),
            },
            far: camera.far,
            orthographic: matches!(camera.projection, Projection::Orthographic { .. }),
        }
    }

    /// Eye to clip space. `x`, `y` and `w` are the projection's; `z` is `-w` plus
    /// [`Self::near_scale`] times the depth beyond [`Self::near_limit`], which equals
    /// the projection's `z` up to rounding and the allowance, so that the near plane
    /// test `z >= -w` decides by the depth itself: rounding of the projection's `z`
    /// kept or dropped a polygon lying on the near plane at random (see
    /// [`Camera::near_limit`]).
    #[inline]
    #[must_use]
    pub(crate) fn eye_to_clip(&self, eye: DVec3) -> DVec4 {
        let c = self.projection * eye.extend(1.0);
        DVec4::new(c.x, c.y, self.near_z(c.w, -eye.z), c.w)
    }

    /// The clip `z` of a point of depth `depth` and clip `w` (see [`Self::eye_to_clip`]).
    #[inline(always)]
    #[must_use]
    pub(crate) fn near_z(&self, w: f64, depth: f64) -> f64 {
        -w + self.near_scale * (depth - self.near_limit)
    }

    /// Object to eye space for an object placed by `model` (an affine map), relative
    /// to the camera (see the type's doc).
    #[must_use]
    pub fn model_view(&self, model: &DMat4) -> ModelView {
        ModelView {
            linear: DMat3::from_mat4(*model),
            shift: model.w_axis.truncate() - self.eye,
            rotation: self.rotation,
        }
    }

    /// A world point in eye space, relative to the camera (see the type's doc).
    #[inline]
    #[must_use]
    pub fn world_to_eye(&self, p: DVec3) -> DVec3 {
        self.rotation * (p - self.eye)
    }

    /// A world point in clip space: [`Self::world_to_eye`], then the projection.
    #[inline]
    #[must_use]
    pub(crate) fn world_to_clip(&self, p: DVec3) -> DVec4 {
        self.eye_to_clip(self.world_to_eye(p))
    }

    /// The six planes of the view volume in eye space (see [`frustum_planes`]), for
    /// [`Self::object_containment`].
    #[must_use]
    pub(crate) fn eye_frustum_planes(&self) -> [DVec4; 6] {
        frustum_planes(&self.projection)
    }

    /// Where an object lies relative to the view volume: outside by its bounding
    /// sphere, else by the clip-space outcodes of its box's corners (the pipeline's
    /// object culling). `planes` are [`Self::eye_frustum_planes`]; both volumes are
    /// taken to eye space relative to the camera, so the test stays conservative
    /// however far the scene is from the origin.
    #[must_use]
    pub fn object_containment(&self, planes: &[DVec4; 6], o: &Object) -> Containment {
        let sphere = Sphere {
            center: self.world_to_eye(o.sphere.center),
            radius: o.sphere.radius,
        };
        if classify_sphere(planes, &sphere) == Containment::Outside {
            return Containment::Outside;
        }
        if o.bounds.is_empty() {
            return Containment::Outside;
        }
        classify_clip_points(o.bounds.corners().map(|c| self.world_to_clip(c)))
    }

    /// The depth key of an eye-space depth.
    #[inline]
    #[must_use]
    pub(crate) fn zq_of_depth(&self, depth: f64) -> f64 {
        if self.orthographic {
            (self.far - depth) / (self.far - self.near)
        } else {
            self.near / depth
        }
    }

    /// How a stored (`f32`) depth key becomes the eye-space depth a [`crate::Frame`]
    /// holds: one rule for every hidden-surface algorithm, so that the same key gives
    /// the same depth bit for bit whichever algorithm drew it.
    #[inline]
    #[must_use]
    pub fn key_depths(&self) -> crate::raster::lanes::DepthOfKey {
        use crate::raster::lanes::DepthOfKey;
        if self.orthographic {
            DepthOfKey::Orthographic {
                far: self.far,
                range: self.far - self.near,
            }
        } else {
            DepthOfKey::Perspective {
                near: self.near as f32,
            }
        }
    }

    /// The eye-space depth a frame stores for the stored depth key `key` (see
    /// [`Self::key_depths`]); within a unit in the last place of
    /// `depth_of_zq(key) as f32`.
    #[inline]
    #[must_use]
    pub fn depth_of_key(&self, key: f32) -> f32 {
        self.key_depths().depth(key)
    }

    /// The eye-space depth of a depth key.
    #[inline]
    #[must_use]
    pub fn depth_of_zq(&self, zq: f64) -> f64 {
        if self.orthographic {
            self.far - zq * (self.far - self.near)
        } else {
            self.near / zq
        }
    }

    /// Divide by w and map to pixels. Only meaningful inside the view volume.
    #[inline]
    #[must_use]
    pub fn to_screen(&self, clip: DVec4, eye: DVec3) -> ViewVertex {
        let inv_w = 1.0 / clip.w;
        ViewVertex {
            x: (clip.x * inv_w + 1.0) * 0.5 * self.width,
            y: (1.0 - clip.y * inv_w) * 0.5 * self.height,
            zq: self.zq_of_depth(-eye.z),
            eye,
        }
    }

    /// Whether a face with eye-space normal `normal` (counter-clockwise = front)
    /// through eye-space `point` is seen from behind.
    #[inline]
    #[must_use]
    pub(crate) fn is_back_facing_eye(&self, normal: DVec3, point: DVec3) -> bool {
        if self.orthographic {
            crate::cull::backface::is_back_facing_parallel(normal, -DVec3::Z)
        } else {
            crate::cull::backface::is_back_facing_perspective(normal, point, DVec3::ZERO)
        }
    }

    /// Clips an eye-space convex polygon against the view volume and projects it,
    /// appending the screen vertices to `out`. Returns how many were appended (0 when
    /// nothing is visible). For object-space algorithms that make new polygons (BSP
    /// fragments, depth-sort splits).
    pub fn clip_and_project(&self, eye_points: &[DVec3], out: &mut Vec<ViewVertex>) -> usize {
        let input: Vec<ClipEyeVertex> = eye_points
            .iter()
            .map(|&e| ClipEyeVertex {
                clip: self.eye_to_clip(e),
                eye: e,
            })
            .collect();
        let (mut and, mut or) = (0x3f, 0);
        for v in &input {
            let c = outcode_homogeneous(v.clip);
            and &= c;
            or |= c;
        }
        if and != 0 || input.len() < 3 {
            return 0;
        }
        let (mut clipped, mut scratch) = (Vec::new(), Vec::new());
        clip_polygon_homogeneous_masked(&input, or, &mut clipped, &mut scratch);
        self.project_clipped(&clipped, out)
    }

    /// Projects a polygon the clipper made and appends its screen vertices to `out`,
    /// less the corners that rounding made (see [`drop_rounding_corners`]); returns
    /// how many were appended (0 when fewer than three are left).
    pub(crate) fn project_clipped(
        &self,
        clipped: &[ClipEyeVertex],
        out: &mut Vec<ViewVertex>,
    ) -> usize {
        let start = out.len();
        out.extend(clipped.iter().map(|v| self.to_screen(v.clip, v.eye)));
        drop_rounding_corners(out, start);
        if out.len() - start < 3 {
            out.truncate(start);
        }
        out.len() - start
    }
}

/// Removes from the screen polygon `v[start..]` (made convex by clipping) the vertices
/// that repeat the previous one and those whose corner turns against the polygon.
/// Clipping at a corner of the view volume makes both from one vertex: the points where
/// an edge meets two planes at once differ by rounding, e.g. `(-5.6e-16, 0)` and
/// `(-5.6e-16, -5.6e-16)` for a corner at `(0, 0)`, and the coverage rule, which takes
/// the polygon for convex, extended the edge between them, a line of arbitrary
/// direction, across the polygon: a pixel 0.14 pixel inside a triangle was lost.
/// Corners that do not turn (collinear vertices) are kept: their edges lie on one line.
pub(crate) fn drop_rounding_corners(v: &mut Vec<ViewVertex>, start: usize) {
    let same = |a: &ViewVertex, b: &ViewVertex| a.x == b.x && a.y == b.y;
    let mut kept = start;
    for i in start..v.len() {
        if kept == start || !same(&v[kept - 1], &v[i]) {
            v.swap(kept, i);
            kept += 1;
        }
    }
    v.truncate(kept);
    while v.len() > start + 1 && same(&v[start], &v[v.len() - 1]) {
        v.pop();
    }
    loop {
        let p = &v[start..];
        let n = p.len();
        if n < 3 {
            return;
        }
        let area2: f64 = (0..n)
            .map(|i| {
                let (a, b) = (&p[i], &p[(i + 1) % n]);
                a.x * b.y - b.x * a.y
            })
            .sum();
        if !(area2.is_finite() && area2 != 0.0) {
            return;
        }
        let against = (0..n).find(|&i| {
            let (a, b, c) = (&p[(i + n - 1) % n], &p[i], &p[(i + 1) % n]);
            let turn = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
            turn * area2 < 0.0
        });
        match against {
            Some(i) => {
                v.remove(start + i);
            }
            None => return,
        }
    }
}

/// Counts and time of one pipeline stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageStats {
    /// The stage's name.
    pub stage: &'static str,
    /// What is counted: `objects`, `vertices`, `faces` or `polygons`.
    pub unit: &'static str,
    /// How many went in.
    pub input: u64,
    /// How many came out.
    pub output: u64,
    /// Milliseconds spent.
    pub ms: f64,
}

/// The stages of [`prepare`], in order.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PipelineStats {
    /// One entry per stage.
    pub stages: Vec<StageStats>,
}

impl PipelineStats {
    fn push(
        &mut self,
        stage: &'static str,
        unit: &'static str,
        input: u64,
        output: u64,
        since: Instant,
    ) {
        self.stages.push(StageStats {
            stage,
            unit,
            input,
            output,
            ms: since.elapsed().as_secs_f64() * 1e3,
        });
    }

    fn push_untimed(&mut self, stage: &'static str, unit: &'static str, input: u64, output: u64) {
        self.stages.push(StageStats {
            stage,
            unit,
            input,
            output,
            ms: 0.0,
        });
    }

    /// The one stage whose name starts with `name` (a name may carry a note after it,
    /// e.g. "faces: clip (Sutherland-Hodgman) (timed above)" for "faces: clip"):
    /// `None` if no stage or several match. Pick stages by name, not by position.
    #[must_use]
    pub fn stage(&self, name: &str) -> Option<&StageStats> {
        let mut found = self.stages.iter().filter(|s| s.stage.starts_with(name));
        let first = found.next()?;
        found.next().is_none().then_some(first)
    }

    /// Total milliseconds of all stages.
    #[must_use]
    pub fn total_ms(&self) -> f64 {
        self.stages.iter().map(|s| s.ms).sum()
    }
}

/// One prepared polygon: a convex screen-space polygon with its face id.
#[derive(Clone, Copy, Debug)]
pub struct ViewPolygon<'a> {
    /// The scene-wide face id.
    pub face: u32,
    /// The object index.
    pub object: u32,
    indices: &'a [u32],
    vertices: &'a [ViewVertex],
}

impl<'a> ViewPolygon<'a> {
    /// Number of vertices.
    #[must_use]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether it has no vertex (never true for polygons of a view).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Vertex `k`.
    #[inline]
    #[must_use]
    pub fn vertex(&self, k: usize) -> &'a ViewVertex {
        &self.vertices[self.indices[k] as usize]
    }

    /// The vertices in order.
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = &'a ViewVertex> + 'a {
        let v = self.vertices;
        self.indices.iter().map(move |&i| &v[i as usize])
    }

    /// Indices of the vertices in [`PreparedView::vertices`].
    #[must_use]
    pub fn indices(&self) -> &'a [u32] {
        self.indices
    }

    /// Screen positions.
    #[must_use]
    pub fn screen_points(&self) -> Vec<(f64, f64)> {
        self.vertices().map(|v| (v.x, v.y)).collect()
    }

    /// Eye-space positions.
    #[must_use]
    pub fn eye_points(&self) -> Vec<DVec3> {
        self.vertices().map(|v| v.eye).collect()
    }

    /// The plane in eye space (Newell).
    #[must_use]
    pub fn eye_plane(&self) -> Option<Plane> {
        Plane::newell(&self.eye_points())
    }

    /// The depth-key plane in screen space.
    #[must_use]
    pub fn depth_plane(&self) -> Option<DepthPlane> {
        let pts: Vec<(f64, f64, f64)> = self.vertices().map(|v| (v.x, v.y, v.zq)).collect();
        DepthPlane::from_points(&pts)
    }

    /// The pixels it covers in a `width x height` image.
    #[must_use]
    pub fn coverage(&self, fill: FillRule, width: u32, height: u32) -> Option<PolygonCoverage> {
        PolygonCoverage::new(&self.screen_points(), fill, width, height)
    }
}

/// The result of [`prepare`]: screen-space convex polygons with face ids and depth keys,
/// plus everything needed to go back to the scene.
#[derive(Clone, Debug)]
pub struct PreparedView<'s> {
    scene: &'s Scene,
    camera: Camera,
    viewport: Viewport,
    transform: ViewTransform,
    options: PrepareOptions,
    vertices: Vec<ViewVertex>,
    starts: Vec<u32>,
    indices: Vec<u32>,
    faces: Vec<u32>,
    objects: Vec<u32>,
    stats: PipelineStats,
}

impl<'s> PreparedView<'s> {
    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The viewport.
    #[must_use]
    pub fn viewport(&self) -> Viewport {
        self.viewport
    }

    /// The eye/clip/screen transform.
    #[must_use]
    pub fn transform(&self) -> &ViewTransform {
        &self.transform
    }

    /// The options it was prepared with.
    #[must_use]
    pub fn options(&self) -> &PrepareOptions {
        &self.options
    }

    /// Per-stage counts and times.
    #[must_use]
    pub fn stats(&self) -> &PipelineStats {
        &self.stats
    }

    /// All vertices (shared transformed ones first, then those made by clipping).
    #[must_use]
    pub fn vertices(&self) -> &[ViewVertex] {
        &self.vertices
    }

    /// Number of polygons.
    #[must_use]
    pub fn polygon_count(&self) -> usize {
        self.faces.len()
    }

    /// Polygon `i`.
    #[inline]
    #[must_use]
    pub fn polygon(&self, i: usize) -> ViewPolygon<'_> {
        let (s, e) = (self.starts[i] as usize, self.starts[i + 1] as usize);
        ViewPolygon {
            face: self.faces[i],
            object: self.objects[i],
            indices: &self.indices[s..e],
            vertices: &self.vertices,
        }
    }

    /// All polygons, in scene order (ascending face ids).
    pub fn polygons(&self) -> impl ExactSizeIterator<Item = ViewPolygon<'_>> + '_ {
        (0..self.polygon_count()).map(move |i| self.polygon(i))
    }

    /// The flat arrays: `starts` (polygon count + 1), `indices`, `faces`.
    #[must_use]
    pub fn polygon_arrays(&self) -> (&[u32], &[u32], &[u32]) {
        (&self.starts, &self.indices, &self.faces)
    }
}

/// Runs the front end of the pipeline. An empty scene gives an empty view.
///
/// ```
/// use obscura::{scene::{demo, Viewport}, view::{prepare, PrepareOptions}};
/// let scene = demo::cube();
/// let vp = Viewport::new(64, 48).unwrap();
/// let cam = scene.default_camera(vp.aspect());
/// let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
/// assert_eq!(view.polygon_count(), 3); // a closed cube seen from a corner shows 3 faces
/// ```
///
/// # Performance
/// Two passes over the data: one over vertices (transform, outcode, screen position)
/// and one over faces that culls back faces, rejects by outcodes, clips and emits in
/// one go, so no intermediate list of faces is built. The face stages keep their own
/// counts; their time is the fused pass's, reported once (in the back-face stage, whose
/// name says so). Clip-space coordinates are not stored: the few polygons that cross a
/// plane recompute them from the eye-space vertices, with the same function, hence the
/// same bits. With the `parallel` feature and more than one rayon thread both passes
/// run on chunks in parallel; the output is the same, in the same order.
pub fn prepare<'s>(
    scene: &'s Scene,
    camera: &Camera,
    viewport: Viewport,
    options: &PrepareOptions,
) -> Result<PreparedView<'s>> {
    viewport.validate()?;
    let t = checked_transform(scene, camera, viewport)?;
    let mut stats = PipelineStats::default();
    let threads = passes::thread_count();

    let mut visible = visible_objects(scene, &t, options, &mut stats);

    // Vertices: world -> eye -> clip, outcodes, screen positions.
    let start = Instant::now();
    let mut bases: Vec<u32> = Vec::with_capacity(visible.len() + 1);
    let mut vertex_total = 0usize;
    for &(k, _) in &visible {
        bases.push(vertex_total as u32);
        vertex_total += scene.objects()[k].mesh.positions().len();
    }
    bases.push(vertex_total as u32);
    check_budget(scene, &visible, vertex_total, options)?;
    let (mut vertices, codes) = passes::transform_vertices(scene, &visible, &bases, &t, threads);
    confirm_inside(scene, &mut visible, &bases, &codes);
    stats.push(
        "vertices: world -> eye -> clip",
        "vertices",
        vertex_total as u64,
        vertex_total as u64,
        start,
    );

    // Faces: back faces, trivial rejection by outcodes, clipping, in one pass.
    let start = Instant::now();
    let face_total: usize = visible
        .iter()
        .map(|&(k, _)| scene.objects()[k].mesh.polygon_count())
        .sum();
    let ctx = passes::FaceContext {
        scene,
        visible: &visible,
        bases: &bases,
        vertices: &vertices,
        codes: &codes,
        t: &t,
        backface: options.backface,
    };
    let out = passes::process_faces(&ctx, face_total, threads);
    vertices.extend_from_slice(&out.clipped_vertices);
    stats.push(
        "faces: back-face culling (fused; time of all 3)",
        "faces",
        face_total as u64,
        out.front,
        start,
    );
    stats.push_untimed(
        "faces: frustum (outcodes) (timed in fused pass)",
        "faces",
        out.front,
        out.kept,
    );
    stats.push_untimed(
        "faces: clip (Sutherland-Hodgman) (timed above)",
        "faces",
        out.to_clip,
        out.clipped,
    );

    Ok(PreparedView {
        scene,
        camera: *camera,
        viewport,
        transform: t,
        options: *options,
        vertices,
        starts: out.starts,
        indices: out.indices,
        faces: out.faces,
        objects: out.objects,
        stats,
    })
}

/// The structure named by the prepared view's budget errors.
pub const BUDGET_STRUCTURE: &str = "prepared view (vertices and polygons)";

/// Refuses, before anything is allocated, a prepared view whose visible objects'
/// vertices and polygons would exceed the budget of `options`: per vertex its view
/// vertex and outcode, per polygon its offsets, face and object ids and indices, with
/// room for clipping (each of the six frustum planes can add a vertex to a polygon).
fn check_budget(
    scene: &Scene,
    visible: &[(usize, bool)],
    vertex_total: usize,
    options: &PrepareOptions,
) -> Result<()> {
    let budget = crate::budget::MemoryBudget::from_option(options.memory_limit);
    let (mut polygons, mut indices) = (0u64, 0u64);
    for &(k, _) in visible {
        let (_, idx, _) = scene.objects()[k].mesh.polygon_arrays();
        polygons += scene.objects()[k].mesh.polygon_count() as u64;
        indices += idx.len() as u64;
    }
    let vertex_bytes = (size_of::<ViewVertex>() + 1) as u64;
    let bytes = (vertex_total as u64)
        .saturating_mul(vertex_bytes)
        .saturating_add(polygons.saturating_mul(12))
        .saturating_add(indices.saturating_mul(4));
    budget.check(BUDGET_STRUCTURE, polygons, bytes)
}

/// Keeps the "wholly inside" flag of an object only if every one of its vertices has
/// outcode 0. The flag comes from the object's box corners, transformed by the combined
/// matrix; its vertices are transformed in two steps (eye, then clip) and round
/// differently, so a vertex on the frustum's boundary can fall outside though the box
/// is inside. Such an object's faces then go through the outcode tests and clipping
/// like any other (a face with an outside vertex would else keep that vertex's NaN
/// screen position).
fn confirm_inside(scene: &Scene, visible: &mut [(usize, bool)], bases: &[u32], codes: &[u8]) {
    for (slot, (k, inside)) in visible.iter_mut().enumerate() {
        if *inside {
            let first = bases[slot] as usize;
            let n = scene.objects()[*k].mesh.positions().len();
            *inside = codes[first..first + n].iter().all(|&c| c == 0);
        }
    }
}

/// The transform of a camera whose view the scene's coordinates resolve (checked by
/// [`Camera::validate_for`] and [`Camera::validate_window`]), with an orthographic
/// camera's planes fitted to the scene ([`fitted_orthographic_planes`]).
fn checked_transform(scene: &Scene, camera: &Camera, viewport: Viewport) -> Result<ViewTransform> {
    camera.validate_for(viewport)?;
    camera.validate_window(viewport, scene.bounds().magnitude())?;
    let fitted = fitted_orthographic_planes(scene, camera);
    Ok(ViewTransform::new(
        fitted.as_ref().unwrap_or(camera),
        viewport,
    ))
}

/// An orthographic camera's planes brought in to the depths that the scene's objects
/// can have: their boxes' depths, with a margin, within `near..far`; `None` for a
/// perspective camera or planes already that close. Planes that cut no object change
/// nothing in the image, but an orthographic depth is resolved relative to
/// `far - near`: in clip coordinates (`f64`, so also the frustum culling of objects)
/// and in the `f32` keys `(far - depth) / (far - near)`, whose step with `near` 0.001
/// and `far` 1e9 is 60 units. Every face of a scene a few units deep then got the same
/// key (the wrong one won 1,256 of 3,355 pixels of the demo scene, and every depth was
/// 0.001), and with `far` 1e20 the clip coordinates put the whole scene on the near
/// plane. Perspective keys (`near / depth`) keep their relative precision at any depth.
#[must_use]
pub fn fitted_orthographic_planes(scene: &Scene, camera: &Camera) -> Option<Camera> {
    if !matches!(camera.projection, Projection::Orthographic { .. }) {
        return None;
    }
    // Depths relative to the camera (see `ViewTransform`).
    let (_, _, forward) = camera.basis();
    let (mut lo, mut hi, mut size) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for o in scene.objects() {
        if o.bounds.is_empty() || o.mesh.polygon_count() == 0 {
            continue;
        }
        size = size.max(o.bounds.extent().max_element());
        for c in o.bounds.corners() {
            let depth = forward.dot(c - camera.eye);
            lo = lo.min(depth);
            hi = hi.max(depth);
        }
    }
    if !(lo <= hi && lo.is_finite() && hi.is_finite()) {
        return None;
    }
    // Away from every vertex (keys stay positive at the far plane), and never zero.
    let margin = ((hi - lo) * 1e-3)
        .max(size * 1e-6)
        .max(hi.abs().max(lo.abs()) * 1e-9)
        .max(f64::MIN_POSITIVE);
    let (near, far) = (
        (lo - margin).max(camera.near),
        (hi + margin).min(camera.far),
    );
    (near < far && (near > camera.near || far < camera.far)).then_some(Camera {
        near,
        far,
        ..*camera
    })
}

/// The objects to draw, as `(index, wholly inside the frustum)`: those with faces, less
/// those outside the frustum by their bounding sphere, then box (all of them when
/// object culling is off). Counted in `stats`.
fn visible_objects(
    scene: &Scene,
    t: &ViewTransform,
    options: &PrepareOptions,
    stats: &mut PipelineStats,
) -> Vec<(usize, bool)> {
    let start = Instant::now();
    let planes = t.eye_frustum_planes();
    let mut visible: Vec<(usize, bool)> = Vec::with_capacity(scene.objects().len());
    for (k, o) in scene.objects().iter().enumerate() {
        if o.mesh.polygon_count() == 0 {
            continue;
        }
        if !options.frustum_cull_objects {
            visible.push((k, false));
            continue;
        }
        match t.object_containment(&planes, o) {
            Containment::Outside => {}
            Containment::Inside => visible.push((k, true)),
            Containment::Intersecting => visible.push((k, false)),
        }
    }
    stats.push(
        "objects: frustum (sphere, box)",
        "objects",
        scene.objects().len() as u64,
        visible.len() as u64,
        start,
    );
    visible
}

#[cfg(test)]
mod reference {
    use super::*;
    use crate::geom::newell_normal;

    /// The front end as first written: one pass per stage, intermediate lists, a clip-space
    /// copy of every vertex. [`prepare`] must give the same view.
    pub(super) fn prepare_reference<'s>(
        scene: &'s Scene,
        camera: &Camera,
        viewport: Viewport,
        options: &PrepareOptions,
    ) -> Result<PreparedView<'s>> {
        let t = checked_transform(scene, camera, viewport)?;
        let mut stats = PipelineStats::default();

        let mut visible = visible_objects(scene, &t, options, &mut stats);

        // Vertices: world -> eye -> clip, outcodes, screen positions.
        let start = Instant::now();
        let vertex_total: usize = visible
            .iter()
            .map(|&(k, _)| scene.objects()[k].mesh.positions().len())
            .sum();
        let mut vertices: Vec<ViewVertex> = Vec::with_capacity(vertex_total);
        let mut clip: Vec<DVec4> = Vec::with_capacity(vertex_total);
        let mut codes: Vec<u8> = Vec::with_capacity(vertex_total);
        let mut bases: Vec<u32> = Vec::with_capacity(visible.len());
        for &(k, _) in &visible {
            let o = &scene.objects()[k];
            bases.push(vertices.len() as u32);
            let model_view = t.model_view(&o.transform);
            for &p in o.mesh.positions() {
                let eye = model_view.apply(p);
                let c = t.eye_to_clip(eye);
                let code = outcode_homogeneous(c);
                let v = if code == 0 {
                    t.to_screen(c, eye)
                } else {
                    ViewVertex {
                        x: f64::NAN,
                        y: f64::NAN,
                        zq: f64::NAN,
                        eye,
                    }
                };
                vertices.push(v);
                clip.push(c);
                codes.push(code);
            }
        }
        stats.push(
            "vertices: world -> eye -> clip",
            "vertices",
            vertex_total as u64,
            vertex_total as u64,
            start,
        );
        super::confirm_inside(scene, &mut visible, &bases, &codes);

        // Back faces, then trivial rejection by outcodes.
        let start = Instant::now();
        let face_total: usize = visible
            .iter()
            .map(|&(k, _)| scene.objects()[k].mesh.polygon_count())
            .sum();
        let mut front: Vec<(u32, u32)> = Vec::with_capacity(face_total);
        let mut eye_pts: Vec<DVec3> = Vec::new();
        for (slot, &(k, _)) in visible.iter().enumerate() {
            let o = &scene.objects()[k];
            let base = bases[slot] as usize;
            let cull = options.backface.applies_to(o.closed);
            for p in 0..o.mesh.polygon_count() {
                if cull {
                    let poly = o.mesh.polygon(p);
                    let normal = if poly.len() == 3 {
                        let (a, b, c) = (
                            vertices[base + poly[0] as usize].eye,
                            vertices[base + poly[1] as usize].eye,
                            vertices[base + poly[2] as usize].eye,
                        );
                        (b - a).cross(c - a)
                    } else {
                        eye_pts.clear();
                        eye_pts.extend(poly.iter().map(|&i| vertices[base + i as usize].eye));
                        newell_normal(&eye_pts)
                    };
                    let normal = if o.mirrored { -normal } else { normal };
                    if t.is_back_facing_eye(normal, vertices[base + poly[0] as usize].eye) {
                        continue;
                    }
                }
                front.push((slot as u32, p as u32));
            }
        }
        stats.push(
            "faces: back-face culling",
            "faces",
            face_total as u64,
            front.len() as u64,
            start,
        );

        let start = Instant::now();
        let mut kept: Vec<(u32, u32, u8)> = Vec::with_capacity(front.len());
        for &(slot, p) in &front {
            let (k, inside) = visible[slot as usize];
            let base = bases[slot as usize] as usize;
            if inside {
                kept.push((slot, p, 0));
                continue;
            }
            let (mut and, mut or) = (0x3f, 0);
            for &i in scene.objects()[k].mesh.polygon(p as usize) {
                let c = codes[base + i as usize];
                and &= c;
                or |= c;
            }
            if and == 0 {
                kept.push((slot, p, or));
            }
        }
        stats.push(
            "faces: frustum (outcodes)",
            "faces",
            front.len() as u64,
            kept.len() as u64,
            start,
        );

        // Clip faces that cross a plane; emit polygons.
        let start = Instant::now();
        let mut starts: Vec<u32> = Vec::with_capacity(kept.len() + 1);
        let mut indices: Vec<u32> = Vec::with_capacity(kept.len() * 3);
        let mut faces: Vec<u32> = Vec::with_capacity(kept.len());
        let mut objects: Vec<u32> = Vec::with_capacity(kept.len());
        starts.push(0);
        let (mut to_clip, mut clipped_out) = (0u64, 0u64);
        let (mut input, mut out, mut scratch): (
            Vec<ClipEyeVertex>,
            Vec<ClipEyeVertex>,
            Vec<ClipEyeVertex>,
        ) = (Vec::new(), Vec::new(), Vec::new());
        for &(slot, p, or) in &kept {
            let (k, _) = visible[slot as usize];
            let o = &scene.objects()[k];
            let base = bases[slot as usize];
            let poly = o.mesh.polygon(p as usize);
            if or == 0 {
                indices.extend(poly.iter().map(|&i| base + i));
            } else {
                to_clip += 1;
                input.clear();
                input.extend(poly.iter().map(|&i| {
                    let g = (base + i) as usize;
                    ClipEyeVertex {
                        clip: clip[g],
                        eye: vertices[g].eye,
                    }
                }));
                clip_polygon_homogeneous_masked(&input, or, &mut out, &mut scratch);
                let first = vertices.len() as u32;
                let n = t.project_clipped(&out, &mut vertices) as u32;
                if n == 0 {
                    continue;
                }
                clipped_out += 1;
                indices.extend(first..first + n);
            }
            starts.push(indices.len() as u32);
            faces.push(o.first_face + o.mesh.polygon_face(p as usize));
            objects.push(k as u32);
        }
        stats.push(
            "faces: clip (Sutherland-Hodgman, homogeneous)",
            "faces",
            to_clip,
            clipped_out,
            start,
        );

        Ok(PreparedView {
            scene,
            camera: *camera,
            viewport,
            transform: t,
            options: *options,
            vertices,
            starts,
            indices,
            faces,
            objects,
            stats,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo;

    #[test]
    fn cube_from_the_front_shows_one_face_filling_the_expected_square() {
        let scene = demo::cube();
        let vp = Viewport::new(100, 100).unwrap();
        // Unit cube, eye at z = 2.5: the front face (z = 0.5) is at depth 2, and with a
        // 90 degree fov it spans +-0.5/2 of the half-width 1: pixels 37.5 .. 62.5.
        let cam = Camera::perspective(
            DVec3::new(0., 0., 2.5),
            DVec3::ZERO,
            DVec3::Y,
            90.0,
            0.1,
            10.0,
        );
        let v = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
        assert_eq!(v.polygon_count(), 1);
        let p = v.polygon(0);
        assert_eq!(p.face, 5);
        for vert in p.vertices() {
            assert!((vert.x - 37.5).abs() < 1e-9 || (vert.x - 62.5).abs() < 1e-9);
            assert!((vert.depth() - 2.0).abs() < 1e-12);
            assert!((vert.zq - 0.1 / 2.0).abs() < 1e-15);
        }
        let culling = v.stats().stage("faces: back-face culling").unwrap();
        assert_eq!(culling.input, 6);
        assert_eq!(culling.output, 1);
        // Several stages start with "faces:": a name must pick one.
        assert!(v.stats().stage("faces:").is_none());
        assert!(v.stats().stage("no such stage").is_none());
    }

    #[test]
    fn faces_crossing_the_eye_plane_are_clipped_at_near() {
        // A big floor under the eye extends behind it: clipping must keep only w > 0.
        let mut s = Scene::new();
        s.add(crate::scene::ObjectDesc::new(
            "floor",
            demo::grid_mesh(100.0, 100.0, 1, 1),
        ))
        .unwrap();
        let cam = Camera::perspective(
            DVec3::new(0., 1., 0.),
            DVec3::new(0., 1., -1.),
            DVec3::Y,
            60.0,
            0.1,
            1000.0,
        );
        let v = prepare(
            &s,
            &cam,
            Viewport::new(64, 64).unwrap(),
            &PrepareOptions::default(),
        )
        .unwrap();
        assert_eq!(v.polygon_count(), 1);
        for vert in v.polygon(0).vertices() {
            assert!(vert.depth() >= 0.1 - 1e-9);
            assert!(vert.x.is_finite() && vert.y.is_finite());
            assert!(
                vert.x >= -1e-9
                    && vert.x <= 64.0 + 1e-9
                    && vert.y >= 32.0 - 1e-9
                    && vert.y <= 64.0 + 1e-9
            );
        }
    }

    fn same_view(a: &PreparedView<'_>, b: &PreparedView<'_>, what: &str) {
        let bits = |v: &ViewVertex| [v.x, v.y, v.zq, v.eye.x, v.eye.y, v.eye.z].map(f64::to_bits);
        assert_eq!(a.vertices.len(), b.vertices.len(), "{what}");
        assert!(
            a.vertices
                .iter()
                .zip(&b.vertices)
                .all(|(p, q)| bits(p) == bits(q)),
            "{what}: vertices differ"
        );
        assert_eq!(a.starts, b.starts, "{what}");
        assert_eq!(a.indices, b.indices, "{what}");
        assert_eq!(a.faces, b.faces, "{what}");
        assert_eq!(a.objects, b.objects, "{what}");
        let counts = |v: &PreparedView<'_>| {
            v.stats
                .stages
                .iter()
                .map(|s| (s.unit, s.input, s.output))
                .collect::<Vec<_>>()
        };
        assert_eq!(counts(a), counts(b), "{what}");
    }

    #[test]
    fn fused_passes_equal_the_stage_per_pass_pipeline() {
        use crate::scene::random::{mirrored, orbit_cameras, random_triangles};
        // Big enough (more than PARALLEL_MIN faces and vertices) for the parallel passes.
        let scenes = [
            ("triangles", random_triangles(25_000, 3, 1.0, 0.05)),
            ("city", demo::city(60, 60, 4)),
            ("mirrored city", mirrored(&demo::city(12, 12, 5))),
            ("sphere", demo::sphere(160, 80)),
            ("default", demo::default_scene()),
        ];
        let mut clipped = 0;
        for (name, scene) in &scenes {
            for (ci, cam) in orbit_cameras(scene, 2, 17).iter().enumerate() {
                let vp = Viewport::new(200, 150).unwrap();
                for backface in [BackfaceMode::Closed, BackfaceMode::All, BackfaceMode::Off] {
                    let opts = PrepareOptions::default().with_backface(backface);
                    let expect = reference::prepare_reference(scene, cam, vp, &opts).unwrap();
                    clipped += expect.stats.stage("faces: clip").unwrap().output;
                    for threads in [1, 2, 3] {
                        #[cfg(feature = "parallel")]
                        let got = rayon::ThreadPoolBuilder::new()
                            .num_threads(threads)
                            .build()
                            .unwrap()
                            .install(|| prepare(scene, cam, vp, &opts).unwrap());
                        #[cfg(not(feature = "parallel"))]
                        let got = prepare(scene, cam, vp, &opts).unwrap();
                        same_view(
                            &got,
                            &expect,
                            &format!("{name} camera {ci} {backface:?} {threads}"),
                        );
                    }
                }
            }
        }
        assert!(clipped > 100, "the close cameras must clip: {clipped}");
    }

    #[test]
    fn empty_scene_gives_empty_view() {
        let s = Scene::new();
        let cam = Camera::perspective(DVec3::Z, DVec3::ZERO, DVec3::Y, 60.0, 0.1, 10.0);
        let v = prepare(
            &s,
            &cam,
            Viewport::new(8, 8).unwrap(),
            &PrepareOptions::default(),
        )
        .unwrap();
        assert_eq!(v.polygon_count(), 0);
    }
}
