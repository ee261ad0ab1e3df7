//! [`View`]: the per-view decisions every algorithm reads, made once.
//!
//! A view decides, for one camera and viewport, which objects survive frustum culling
//! (by bounding sphere, then box: `cull::frustum`) and which faces of the kept objects
//! are back faces (`cull::backface`, with the eye-space normal of the transformed
//! vertices). The image-space algorithms read these decisions through the screen
//! polygons of a [`PreparedView`](super::PreparedView), which the face pass builds from
//! them; the ray casters and the BSP read them directly and never pay for clipped
//! polygons. No algorithm re-derives them.
//!
//! The back faces are decided by one function (`is_back_face`), at one of two moments:
//! on the first call of [`View::back_facing`] (cached), or, for a view turned into
//! polygons before anyone asked, inside the face pass as it reaches each polygon. The
//! second keeps the z-buffer's path to one traversal of the faces and no per-polygon
//! flags, as fast as before the decisions moved here (`docs/performance.md`, "Issue
//! 22: README figures beside the old build").
//!
//! Scene polygons are numbered in scene order: object by object, each object's mesh
//! polygons in order ([`View::polygon_base`]); the index's world triangles
//! ([`crate::accel::triangles::SceneTriangles`]) number them the same way.

use std::sync::OnceLock;
use std::time::Instant;

use glam::DVec3;

use super::prepare::{check_budget, checked_transform, confirm_inside, visible_objects};
use super::{PipelineStats, PrepareOptions, ViewTransform, ViewVertex, passes};
use crate::Result;
use crate::cull::backface::BackfaceMode;
use crate::geom::newell_normal;
use crate::scene::{Camera, Scene, Viewport};

/// One camera's view of a scene: its transform, the objects it keeps, the eye-space
/// vertices of those objects and the back faces among their polygons. The cheap part
/// of a view; [`View::into_prepared`] adds the clipped screen polygons.
///
/// ```
/// use obscura::{scene::{demo, Viewport}, view::{PrepareOptions, View}};
/// let scene = demo::cube();
/// let vp = Viewport::new(64, 48).unwrap();
/// let view = View::new(&scene, &scene.default_camera(vp.aspect()), vp, &PrepareOptions::default()).unwrap();
/// // A closed cube seen from a corner: 3 of its 6 faces face away.
/// assert_eq!(view.back_facing().iter().filter(|&&b| b).count(), 3);
/// assert_eq!(view.into_prepared().polygon_count(), 3);
/// ```
#[derive(Clone, Debug)]
pub struct View<'s> {
    pub(super) scene: &'s Scene,
    pub(super) camera: Camera,
    pub(super) viewport: Viewport,
    pub(super) transform: ViewTransform,
    pub(super) options: PrepareOptions,
    /// The kept objects, as `(index, wholly inside the frustum)`.
    pub(super) visible: Vec<(usize, bool)>,
    /// Per scene object, whether it is kept.
    pub(super) kept: Vec<bool>,
    /// Per kept object (slot of `visible`), its first vertex in `vertices`; then the total.
    pub(super) bases: Vec<u32>,
    /// The vertex pass's output for the kept objects (a prepared view appends the
    /// vertices made by clipping).
    pub(super) vertices: Vec<ViewVertex>,
    /// Outcode of every vertex of `vertices` (emptied once the polygons are built).
    pub(super) codes: Vec<u8>,
    /// Per scene object, its first scene polygon; then the total.
    pub(super) polygon_base: Vec<u32>,
    /// Per scene polygon, whether it is a culled back face (false for objects not kept):
    /// decided on first request ([`View::back_facing`]), or at once for a view with an
    /// occlusion stage. A view turned into polygons before anyone asks decides its back
    /// faces inside the face pass instead, with the same function ([`is_back_face`]),
    /// and keeps no flags: one traversal of the faces, not two.
    pub(super) back_facing: OnceLock<Vec<bool>>,
    /// Per scene polygon, whether the face pass skips it: a back face or a face the
    /// occlusion stage culled; `None` when nothing but back faces is skipped.
    pub(super) skip: Option<Vec<bool>>,
    /// The occlusion stage's decisions, if the view was made with one.
    pub(super) culling: Option<crate::cull::occlusion::Culling>,
    /// Time of the back-face pass run by [`View::new`] (with an occlusion stage only),
    /// reported with the face pass's stage.
    pub(super) back_face_ms: f64,
    pub(super) stats: PipelineStats,
}

impl<'s> View<'s> {
    /// Decides what a camera sees of a scene: objects culled by the frustum, vertices
    /// of the kept objects taken to eye, clip and screen space (back faces are decided
    /// when first asked for, or by the face pass).
    /// Errors: an invalid viewport or camera (see [`Camera::validate_for`]), or a view
    /// over the memory budget of `options` (its vertices and polygons, estimated
    /// before anything is allocated).
    pub fn new(
        scene: &'s Scene,
        camera: &Camera,
        viewport: Viewport,
        options: &PrepareOptions,
    ) -> Result<View<'s>> {
        Self::build(scene, camera, viewport, options, None)
    }

    /// A view that leaves out what an occlusion-culling run decided
    /// ([`crate::cull::occlusion::cull`], [`crate::SceneIndex::cull`]) for the same
    /// camera and viewport: objects culled whole are never transformed, faces of culled
    /// clusters never reach an algorithm. The picture is the same as without it.
    ///
    /// # Errors
    /// As [`Self::new`]; and a culling run made for another scene (its counts differ).
    pub fn new_culled(
        scene: &'s Scene,
        camera: &Camera,
        viewport: Viewport,
        options: &PrepareOptions,
        culling: crate::cull::occlusion::Culling,
    ) -> Result<View<'s>> {
        let polygons: usize = scene.objects().iter().map(|o| o.mesh.polygon_count()).sum();
        if culling.objects.len() != scene.objects().len() || culling.faces.len() != polygons {
            return Err(crate::Error::InvalidOption {
                option: "culling".into(),
                reason: "a culling run made for another scene".into(),
            });
        }
        Self::build(scene, camera, viewport, options, Some(culling))
    }

    fn build(
        scene: &'s Scene,
        camera: &Camera,
        viewport: Viewport,
        options: &PrepareOptions,
        culling: Option<crate::cull::occlusion::Culling>,
    ) -> Result<View<'s>> {
        viewport.validate()?;
        let t = checked_transform(scene, camera, viewport)?;
        let mut stats = PipelineStats::default();
        let threads = passes::thread_count();

        let culled = culling.as_ref().map(|c| c.objects.as_slice());
        let mut visible = visible_objects(scene, &t, options, culled, &mut stats);

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
        let (vertices, codes) = passes::transform_vertices(scene, &visible, &bases, &t, threads);
        confirm_inside(scene, &mut visible, &bases, &codes);
        stats.push(
            "vertices: world -> eye -> clip",
            "vertices",
            vertex_total as u64,
            vertex_total as u64,
            start,
        );

        let start = Instant::now();
        let mut kept = vec![false; scene.objects().len()];
        for &(k, _) in &visible {
            kept[k] = true;
        }
        let mut polygon_base = Vec::with_capacity(scene.objects().len() + 1);
        let mut total = 0u32;
        for o in scene.objects() {
            polygon_base.push(total);
            total += o.mesh.polygon_count() as u32;
        }
        polygon_base.push(total);
        // Back faces: decided here only when the occlusion stage's mask is merged with
        // them; otherwise on first request, or fused into the face pass.
        let back_facing = OnceLock::new();
        let skip = culling.as_ref().and_then(|c| {
            let any = visible.iter().any(|&(k, _)| {
                let (a, b) = (polygon_base[k] as usize, polygon_base[k + 1] as usize);
                c.faces[a..b].iter().any(|&f| f)
            });
            any.then(|| {
                let back = back_faces(
                    &BackFaceInput {
                        scene,
                        visible: &visible,
                        bases: &bases,
                        vertices: &vertices,
                        polygon_base: &polygon_base,
                        t: &t,
                        mode: options.backface,
                    },
                    threads,
                );
                let skip = back.iter().zip(&c.faces).map(|(&b, &f)| b || f).collect();
                let _ = back_facing.set(back);
                skip
            })
        });
        let back_face_ms = start.elapsed().as_secs_f64() * 1e3;

        Ok(View {
            scene,
            camera: *camera,
            viewport,
            transform: t,
            options: *options,
            visible,
            kept,
            bases,
            vertices,
            codes,
            polygon_base,
            back_facing,
            skip,
            culling,
            back_face_ms,
            stats,
        })
    }

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

    /// Per-stage counts and times (the face stages once the polygons are built).
    #[must_use]
    pub fn stats(&self) -> &PipelineStats {
        &self.stats
    }

    /// The number of transformed vertices (those of the kept objects; a prepared view
    /// adds those made by clipping).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// Per scene object, whether frustum culling keeps it (objects without faces are
    /// never kept).
    #[must_use]
    pub fn kept_objects(&self) -> &[bool] {
        &self.kept
    }

    /// Per scene object, the number of its first polygon in scene order; one more entry
    /// at the end, the scene's polygon count.
    #[must_use]
    pub fn polygon_base(&self) -> &[u32] {
        &self.polygon_base
    }

    /// Per scene polygon (see [`Self::polygon_base`]), whether the view culls it as a
    /// back face. False for the polygons of objects not kept, and of objects the
    /// back-face mode leaves alone.
    #[must_use]
    pub fn back_facing(&self) -> &[bool] {
        self.back_facing.get_or_init(|| {
            back_faces(
                &BackFaceInput {
                    scene: self.scene,
                    visible: &self.visible,
                    bases: &self.bases,
                    vertices: &self.vertices,
                    polygon_base: &self.polygon_base,
                    t: &self.transform,
                    mode: self.options.backface,
                },
                passes::thread_count(),
            )
        })
    }

    /// Per scene polygon, whether the face pass skips it: a back face, or a face the
    /// occlusion stage culled ([`Self::new_culled`]).
    #[must_use]
    pub fn skipped_polygons(&self) -> &[bool] {
        match &self.skip {
            Some(skip) => skip,
            None => self.back_facing(),
        }
    }

    /// The occlusion stage's decisions, for a view made by [`Self::new_culled`].
    #[must_use]
    pub fn culling(&self) -> Option<&crate::cull::occlusion::Culling> {
        self.culling.as_ref()
    }

    /// Takes the occlusion stage's decisions out of the view (which then has none:
    /// [`Self::culling`] is `None`), to keep them past it without copying their
    /// per-face flags. What the view leaves out does not change.
    pub fn take_culling(&mut self) -> Option<crate::cull::occlusion::Culling> {
        self.culling.take()
    }

    /// Per scene polygon, whether the view culls it: its object is outside the frustum
    /// or culled by the occlusion stage, or it is a back face or in a culled cluster.
    /// What the ray casters ignore.
    #[must_use]
    pub fn culled_polygons(&self) -> Vec<bool> {
        let mut out = self.skipped_polygons().to_vec();
        for (k, w) in self.polygon_base.windows(2).enumerate() {
            if !self.kept[k] {
                out[w[0] as usize..w[1] as usize].fill(true);
            }
        }
        out
    }
}

/// What the back-face pass reads.
struct BackFaceInput<'a> {
    scene: &'a Scene,
    visible: &'a [(usize, bool)],
    bases: &'a [u32],
    vertices: &'a [ViewVertex],
    polygon_base: &'a [u32],
    t: &'a ViewTransform,
    mode: BackfaceMode,
}

/// Polygons per unit of parallel work in the back-face pass.
#[cfg(feature = "parallel")]
const CHUNK: usize = 1 << 14;

/// Marks the back faces of the kept objects the mode culls: the normal in eye space
/// (the cross product for triangles, Newell's for larger polygons, flipped by
/// mirroring) against the eye, edge-on counting as back
/// ([`ViewTransform::is_back_facing_eye`]).
fn back_faces(input: &BackFaceInput<'_>, threads: usize) -> Vec<bool> {
    let total = *input.polygon_base.last().unwrap_or(&0) as usize;
    let mut flags = vec![false; total];
    // (slot, first polygon, flags of the polygons from it), cut for parallel work.
    let mut work: Vec<(usize, usize, &mut [bool])> = Vec::new();
    let mut rest: &mut [bool] = &mut flags;
    let mut at = 0usize;
    for (slot, &(k, _)) in input.visible.iter().enumerate() {
        let o = &input.scene.objects()[k];
        let first = input.polygon_base[k] as usize;
        let n = o.mesh.polygon_count();
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(first - at);
        let (mine, tail) = tail.split_at_mut(n);
        rest = tail;
        at = first + n;
        if !input.mode.applies_to(o.closed) {
            continue;
        }
        #[cfg(feature = "parallel")]
        if threads > 1 {
            let mut p = 0;
            for chunk in mine.chunks_mut(CHUNK) {
                let len = chunk.len();
                work.push((slot, p, chunk));
                p += len;
            }
            continue;
        }
        work.push((slot, 0, mine));
    }
    let _ = threads;
    #[cfg(feature = "parallel")]
    if threads > 1 && work.len() > 1 {
        use rayon::prelude::*;
        work.into_par_iter()
            .for_each(|(slot, first, out)| mark(input, slot, first, out));
        return flags;
    }
    for (slot, first, out) in work {
        mark(input, slot, first, out);
    }
    flags
}

/// The back-face flags of polygons `first..first + out.len()` of kept object `slot`.
fn mark(input: &BackFaceInput<'_>, slot: usize, first: usize, out: &mut [bool]) {
    let (k, _) = input.visible[slot];
    let o = &input.scene.objects()[k];
    let base = input.bases[slot];
    let (mstarts, mindices, _) = o.mesh.polygon_arrays();
    let vertices = input.vertices;
    let eye = |i: u32| vertices[(base + i) as usize].eye;
    let mut pts: Vec<DVec3> = Vec::new();
    for (i, flag) in out.iter_mut().enumerate() {
        let p = first + i;
        let poly = &mindices[mstarts[p] as usize..mstarts[p + 1] as usize];
        *flag = is_back_face(o.mirrored, poly, eye, input.t, &mut pts);
    }
}

/// Whether a polygon (vertex indices `poly`, eye positions by `eye`) of an object the
/// back-face mode culls is a back face: its eye-space normal (the cross product for
/// triangles, Newell's for larger polygons, flipped by mirroring) against the eye,
/// edge-on counting as back ([`ViewTransform::is_back_facing_eye`]). `pts` is scratch.
/// The one definition: [`View::back_facing`] and the fused face pass both call it.
#[inline(always)]
pub(super) fn is_back_face(
    mirrored: bool,
    poly: &[u32],
    eye: impl Fn(u32) -> DVec3,
    t: &ViewTransform,
    pts: &mut Vec<DVec3>,
) -> bool {
    let normal = if let &[a, b, c] = poly {
        let (a, b, c) = (eye(a), eye(b), eye(c));
        (b - a).cross(c - a)
    } else {
        pts.clear();
        pts.extend(poly.iter().map(|&i| eye(i)));
        newell_normal(pts)
    };
    let normal = if mirrored { -normal } else { normal };
    t.is_back_facing_eye(normal, eye(poly[0]))
}
