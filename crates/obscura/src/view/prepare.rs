//! [`prepare`] and [`PreparedView`]: a [`View`]'s decisions turned into clipped
//! screen polygons by the face pass (outcode rejection, Sutherland-Hodgman, emission).

use std::ops::Deref;
use std::time::Instant;

use super::{PipelineStats, PrepareOptions, View, ViewPolygon, ViewTransform, ViewVertex, passes};
use crate::Result;
use crate::cull::frustum::Containment;
use crate::scene::{Camera, Projection, Scene, Viewport};

/// The result of [`prepare`]: a [`View`] (its decisions, readable through `Deref`)
/// with screen-space convex polygons, their face ids and depth keys.
#[derive(Clone, Debug)]
pub struct PreparedView<'s> {
    /// The view; its vertices extended by those clipping made.
    view: View<'s>,
    starts: Vec<u32>,
    indices: Vec<u32>,
    faces: Vec<u32>,
    objects: Vec<u32>,
}

impl<'s> Deref for PreparedView<'s> {
    type Target = View<'s>;
    fn deref(&self) -> &View<'s> {
        &self.view
    }
}

impl<'s> PreparedView<'s> {
    /// The view whose decisions these polygons follow.
    #[must_use]
    pub fn view(&self) -> &View<'s> {
        &self.view
    }

    /// All vertices (shared transformed ones first, then those made by clipping).
    #[must_use]
    pub fn vertices(&self) -> &[ViewVertex] {
        &self.view.vertices
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
            vertices: &self.view.vertices,
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

    /// A prepared view from its parts (the stage-per-pass reference of the tests).
    #[cfg(test)]
    pub(super) fn from_parts(
        view: View<'s>,
        starts: Vec<u32>,
        indices: Vec<u32>,
        faces: Vec<u32>,
        objects: Vec<u32>,
    ) -> Self {
        PreparedView {
            view,
            starts,
            indices,
            faces,
            objects,
        }
    }
}

impl<'s> View<'s> {
    /// Builds the screen polygons of the faces this view keeps: faces wholly outside a
    /// frustum plane by their vertices' outcodes rejected, those crossing a plane
    /// clipped (Sutherland-Hodgman), the rest emitted as they are. Back faces are the
    /// view's ([`View::back_facing`]), decided in this pass if not asked for before. Infallible: [`View::new`] held the polygons to
    /// the budget already.
    #[must_use]
    pub fn into_prepared(mut self) -> PreparedView<'s> {
        let start = Instant::now();
        let scene = self.scene;
        let threads = passes::thread_count();
        let face_total: usize = self
            .visible
            .iter()
            .map(|&(k, _)| scene.objects()[k].mesh.polygon_count())
            .sum();
        let ctx = passes::FaceContext {
            scene,
            visible: &self.visible,
            bases: &self.bases,
            vertices: &self.vertices,
            codes: &self.codes,
            t: &self.transform,
            polygon_base: &self.polygon_base,
            // Decided already (asked for, or merged with an occlusion stage's mask):
            // read; else decided inside the face pass, which keeps no flags (a later
            // `back_facing()` decides them again by the same function).
            skip: self
                .skip
                .as_deref()
                .or(self.back_facing.get().map(Vec::as_slice)),
            backface: self.options.backface,
        };
        let out = passes::process_faces(&ctx, face_total, threads);
        self.vertices.extend_from_slice(&out.clipped_vertices);
        self.codes = Vec::new();
        let ms = start.elapsed().as_secs_f64() * 1e3 + self.back_face_ms;
        let stats = &mut self.stats;
        stats.push_ms(
            "faces: back-face culling (fused; time of all 3)",
            "faces",
            face_total as u64,
            out.front,
            ms,
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
        PreparedView {
            view: self,
            starts: out.starts,
            indices: out.indices,
            faces: out.faces,
            objects: out.objects,
        }
    }
}

/// Runs the front end of the pipeline: [`View::new`], then [`View::into_prepared`].
/// An empty scene gives an empty view.
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
/// Two passes over the data: one over vertices (transform, outcode, screen
/// position), and one over the kept objects' faces that decides the back faces
/// (the view's rule, [`View::back_facing`]), rejects by outcodes, clips and emits in
/// one go, so no intermediate list of faces is built. The face stages keep their own counts; their time (back faces
/// included) is reported once, in the back-face stage, whose name says so.
/// Clip-space coordinates are not stored: the few polygons that cross a plane
/// recompute them from the eye-space vertices, with the same function, hence the same
/// bits. With the `parallel` feature and more than one rayon thread the passes run on
/// chunks in parallel; the output is the same, in the same order.
pub fn prepare<'s>(
    scene: &'s Scene,
    camera: &Camera,
    viewport: Viewport,
    options: &PrepareOptions,
) -> Result<PreparedView<'s>> {
    Ok(View::new(scene, camera, viewport, options)?.into_prepared())
}

/// The structure named by the prepared view's budget errors.
pub const BUDGET_STRUCTURE: &str = "prepared view (vertices and polygons)";

/// Refuses, before anything is allocated, a prepared view whose visible objects'
/// vertices and polygons would exceed the budget of `options`: per vertex its view
/// vertex and outcode, per polygon its offsets, face and object ids and indices, with
/// room for clipping (each of the six frustum planes can add a vertex to a polygon).
pub(super) fn check_budget(
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
pub(super) fn confirm_inside(
    scene: &Scene,
    visible: &mut [(usize, bool)],
    bases: &[u32],
    codes: &[u8],
) {
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
pub(crate) fn checked_transform(
    scene: &Scene,
    camera: &Camera,
    viewport: Viewport,
) -> Result<ViewTransform> {
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
/// Objects an occlusion-culling run already removed (`culled[k]` is `Some`) are left out
/// without a second test.
pub(super) fn visible_objects(
    scene: &Scene,
    t: &ViewTransform,
    options: &PrepareOptions,
    culled: Option<&[Option<crate::cull::occlusion::CullReason>]>,
    stats: &mut PipelineStats,
) -> Vec<(usize, bool)> {
    let start = Instant::now();
    let planes = t.eye_frustum_planes();
    let mut visible: Vec<(usize, bool)> = Vec::with_capacity(scene.objects().len());
    for (k, o) in scene.objects().iter().enumerate() {
        if o.mesh.polygon_count() == 0 || culled.is_some_and(|c| c[k].is_some()) {
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
