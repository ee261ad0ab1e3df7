//! [`SceneIndex`]: the structures of one scene, each built once, on first use, and
//! shared by every view and every thread.
//!
//! Every view of a scene traverses the same acceleration structures; only the camera
//! changes. The index owns them: the world-space triangles (fan-triangulated faces
//! with their normals, [`SceneTriangles`]), the BVH over them ([`Bvh`]), uniform grids
//! ([`UniformGrid`]), BSP trees ([`BspTree`]), octrees at a depth ([`Octree`]) and the
//! edge adjacency of every mesh ([`EdgeAdjacency`]). Each is built the first time an
//! algorithm asks for it and kept; a view then costs what its traversal costs.
//!
//! ```text
//! Scene ─► SceneIndex ─ triangles, BVH, grid(options), BSP(options), octree(depth),
//!    │                  edge adjacency: built on first use, shared (Sync)
//!    └─► View::new(camera, viewport) ─ per view, once: objects kept, back faces
//!          ├─► ray casters, BSP, octree: the index's structures + the view's decisions
//!          └─► View::into_prepared ─► screen polygons ─► z-buffer, scanline, ...
//! ```
//!
//! ```
//! use obscura::{index::SceneIndex, scene::{demo, Viewport}, view::{PrepareOptions, View}};
//! use obscura::surface::{Algorithm, RenderOptions};
//! let scene = demo::cube();
//! let index = SceneIndex::new(&scene);
//! let vp = Viewport::new(64, 48).unwrap();
//! for eye in [glam::DVec3::new(2., 1.5, 3.), glam::DVec3::new(-3., -1., 2.)] {
//!     let camera = obscura::Camera::perspective(eye, glam::DVec3::ZERO, glam::DVec3::Y, 50.0, 0.1, 20.0);
//!     let view = View::new(&scene, &camera, vp, &PrepareOptions::default()).unwrap();
//!     let (frame, _) = index.render_view(&view, Algorithm::RaycastBvh, &RenderOptions::default()).unwrap();
//!     assert!(frame.covered_pixels() > 0);
//! }
//! assert_eq!(index.builds().bvh, 1); // one hierarchy for both views
//! ```
//!
//! # Options and budgets
//! A structure whose build depends on options is kept per options: grids by their
//! [`GridOptions`] (less the magnitude of the ray origins, see below) and memory
//! budget, BSP trees by their [`BspOptions`] (with the budget they carry), octrees by
//! depth and budget. At most [`KEPT_PER_STRUCTURE`] of each are kept, the oldest
//! dropped first. Memory budgets ([`crate::budget`]) apply to every build as they did
//! without the index; a build refused by its budget is not kept, so the next call
//! tries again (with its own budget).
//!
//! # Threads
//! The index is `Sync`: threads share it by reference. A structure is built by the
//! first thread that asks; others asking meanwhile wait for it (one build), except the
//! octree, whose build runs on rayon's pool and is therefore not done under a lock (a
//! rayon worker waiting for the lock could be the one holding it): two threads asking
//! for the same octree at once may each build it, and the first kept is the one
//! returned to both afterwards.
//!
//! # One grid for every eye
//! A grid's cells are grown for the rounding of the rays it will trace, which grows
//! with the magnitude of their origins ([`GridOptions::ray_origins`], see "Rounding" in
//! [`crate::accel::grid`]). Its answer does not depend on the cells: a ray takes the
//! nearest hit of the watertight test (lowest face id at equal distance) whichever
//! cells it walks, and a ray from an origin the cells were not grown for is traced
//! against every triangle, so frames are bit for bit the same from any grid. The index
//! therefore keeps one grid per grid options and budget, built for origins up to the
//! scene's largest coordinate plus [`GRID_HEADROOM`] times its extent (or the view's
//! eye, if farther): for a scene about the origin growing cells for that costs nothing
//! measurable (`τ` stays below `10^-10` of the scene's size), and one grid serves
//! every view from within a thousand scene sizes. A view from farther (whose rays the
//! kept grid would send to the every-triangle path) replaces the grid with one built
//! for its eye, which serves every nearer eye too.
//!
//! # Limitations
//! The index borrows its scene; a scene changed after indexing needs a new index.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};
use std::time::Instant;

use crate::accel::bsp::BspOptions;
use crate::accel::bsp::BspTree;
use crate::accel::bvh::{Bvh, BvhOptions};
use crate::accel::grid::{GridOptions, UniformGrid};
use crate::accel::octree::Octree;
use crate::accel::triangles::SceneTriangles;
use crate::budget::MemoryBudget;
use crate::lines::edges::IntersectionSegment;
use crate::scene::{EdgeAdjacency, Scene};
use crate::surface::{self, Algorithm, RenderOptions, Stats};
use crate::view::{PrepareOptions, PreparedView, View};
use crate::{Error, Frame, Result};

/// The most structures of one kind (grids, BSP trees, octrees) an index keeps for
/// different options.
pub const KEPT_PER_STRUCTURE: usize = 4;

/// How far from the scene (in multiples of its extent) the ray origins an index's grid
/// is built for may lie (see "One grid for every eye" in the
/// [module documentation](self)).
pub const GRID_HEADROOM: f64 = 1024.0;

/// How many times an index built each structure (each kept one counts once; a build
/// refused by its budget does not count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct IndexBuilds {
    /// World-space triangles.
    pub triangles: u32,
    /// Bounding-volume hierarchies.
    pub bvh: u32,
    /// Uniform grids.
    pub grid: u32,
    /// BSP trees.
    pub bsp: u32,
    /// Octrees.
    pub octree: u32,
    /// Edge adjacencies.
    pub adjacency: u32,
}

#[derive(Default)]
struct Counters {
    triangles: AtomicU32,
    bvh: AtomicU32,
    grid: AtomicU32,
    bsp: AtomicU32,
    octree: AtomicU32,
    adjacency: AtomicU32,
}

/// A slot of a keyed cache: empty until its build succeeds.
type Slot<T> = Arc<Mutex<Option<Arc<T>>>>;

/// Structures kept by key (the options they were built with), the newest last.
struct Keyed<K, T> {
    slots: Mutex<Vec<(K, Slot<T>)>>,
}

impl<K, T> Default for Keyed<K, T> {
    fn default() -> Self {
        Keyed {
            slots: Mutex::new(Vec::new()),
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A build that panicked left no structure behind; the cache itself stays valid.
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl<K: PartialEq, T> Keyed<K, T> {
    /// The slot of `key`, made (and the oldest dropped past the cap) if new.
    fn slot(&self, key: K) -> Slot<T> {
        let mut slots = lock(&self.slots);
        if let Some((_, s)) = slots.iter().find(|(k, _)| *k == key) {
            return Arc::clone(s);
        }
        if slots.len() >= KEPT_PER_STRUCTURE {
            slots.remove(0);
        }
        let s: Slot<T> = Arc::default();
        slots.push((key, Arc::clone(&s)));
        s
    }

    /// The structure of `key`, built by `build` under the slot's lock if not kept yet
    /// (other threads asking for the same key wait). An error is returned, not kept.
    fn get_or_build(&self, key: K, build: impl FnOnce() -> Result<T>) -> Result<Arc<T>> {
        self.get_or_replace(key, |_| true, build)
    }

    /// As [`Self::get_or_build`], with a kept structure that does not `serve` the
    /// caller replaced by a new build (an error keeps the old one).
    fn get_or_replace(
        &self,
        key: K,
        serves: impl FnOnce(&T) -> bool,
        build: impl FnOnce() -> Result<T>,
    ) -> Result<Arc<T>> {
        let slot = self.slot(key);
        let mut held = lock(&slot);
        if let Some(t) = held.as_ref().filter(|t| serves(t)) {
            return Ok(Arc::clone(t));
        }
        let t = Arc::new(build()?);
        *held = Some(Arc::clone(&t));
        Ok(t)
    }

    /// As [`Self::get_or_build`], with the build run outside any lock (for builds that
    /// run on rayon's pool); a structure kept meanwhile by another thread wins.
    fn get_or_build_unlocked(
        &self,
        key: K,
        build: impl FnOnce() -> Result<T>,
    ) -> Result<(Arc<T>, bool)> {
        let slot = self.slot(key);
        if let Some(t) = lock(&slot).as_ref() {
            return Ok((Arc::clone(t), false));
        }
        let t = Arc::new(build()?);
        let mut held = lock(&slot);
        if let Some(kept) = held.as_ref() {
            return Ok((Arc::clone(kept), false));
        }
        *held = Some(Arc::clone(&t));
        Ok((t, true))
    }
}

/// A frame and the z-buffer's buffers kept from one render to the next, as a viewer or
/// an engine keeps its render targets: rendering many views through
/// [`SceneIndex::render_into`] or [`SceneIndex::render_culled_into`] then allocates
/// nothing, and touches no fresh page, once the first frame of the largest size is
/// drawn (a fresh 1920x1080 frame is 16.6 MB to fault in: several milliseconds). The
/// frame of each render is exactly the one a fresh render gives, whatever the renderer
/// drew before and at whatever size. Algorithms other than the z-buffer make their
/// frame as usual; the renderer then holds it.
#[derive(Debug)]
pub struct Renderer {
    frame: Frame,
    zbuffer: surface::zbuffer::Buffers,
}

impl Default for Renderer {
    fn default() -> Self {
        Self::new()
    }
}

impl Renderer {
    /// A renderer holding nothing yet (an empty 0x0 frame; memory is taken on the
    /// first render).
    #[must_use]
    pub fn new() -> Self {
        Renderer {
            frame: Frame {
                width: 0,
                height: 0,
                ids: Vec::new(),
                depth: Vec::new(),
            },
            zbuffer: surface::zbuffer::Buffers::new(),
        }
    }

    /// The frame of the last render (0x0 before the first; unspecified after a render
    /// that failed).
    #[must_use]
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The frame of the last render, the renderer given up.
    #[must_use]
    pub fn into_frame(self) -> Frame {
        self.frame
    }
}

/// The structures of one scene, each built once on first use and shared by every view
/// and thread. See the [module documentation](self).
pub struct SceneIndex<'s> {
    scene: &'s Scene,
    triangles: OnceLock<(SceneTriangles, f64)>,
    bvh: OnceLock<Bvh>,
    adjacency: OnceLock<Vec<EdgeAdjacency>>,
    intersections: OnceLock<Vec<IntersectionSegment>>,
    grids: Keyed<(GridOptions, u64), UniformGrid>,
    bsp: Keyed<BspOptions, BspTree>,
    octrees: Keyed<(u32, u64), Octree>,
    clusters: OnceLock<crate::cull::clusters::Clusters>,
    occluder_candidates: OnceLock<crate::cull::occluders::select::OccluderCandidates>,
    cluster_bvh: OnceLock<crate::cull::occluders::walk::ClusterBvh>,
    pvs: OnceLock<Option<crate::cull::portals::Pvs>>,
    counters: Counters,
}

impl std::fmt::Debug for SceneIndex<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneIndex")
            .field("objects", &self.scene.objects().len())
            .field("builds", &self.builds())
            .finish_non_exhaustive()
    }
}

impl<'s> SceneIndex<'s> {
    /// An index of `scene` with nothing built yet (cheap: structures are built on first
    /// use).
    #[must_use]
    pub fn new(scene: &'s Scene) -> Self {
        SceneIndex {
            scene,
            triangles: OnceLock::new(),
            bvh: OnceLock::new(),
            adjacency: OnceLock::new(),
            intersections: OnceLock::new(),
            grids: Keyed::default(),
            bsp: Keyed::default(),
            octrees: Keyed::default(),
            clusters: OnceLock::new(),
            occluder_candidates: OnceLock::new(),
            cluster_bvh: OnceLock::new(),
            pvs: OnceLock::new(),
            counters: Counters::default(),
        }
    }

    /// The scene.
    #[must_use]
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// How many times each structure was built.
    #[must_use]
    pub fn builds(&self) -> IndexBuilds {
        let c = &self.counters;
        let n = |a: &AtomicU32| a.load(Ordering::Relaxed);
        IndexBuilds {
            triangles: n(&c.triangles),
            bvh: n(&c.bvh),
            grid: n(&c.grid),
            bsp: n(&c.bsp),
            octree: n(&c.octree),
            adjacency: n(&c.adjacency),
        }
    }

    /// The scene's world-space triangles, in scene order (built once).
    pub fn triangles(&self) -> &SceneTriangles {
        &self.triangles_timed().0
    }

    /// The triangles and the milliseconds their build took.
    pub(crate) fn triangles_timed(&self) -> &(SceneTriangles, f64) {
        self.triangles.get_or_init(|| {
            let start = Instant::now();
            let t = SceneTriangles::new(self.scene);
            self.counters.triangles.fetch_add(1, Ordering::Relaxed);
            (t, start.elapsed().as_secs_f64() * 1e3)
        })
    }

    /// The bounding-volume hierarchy over [`Self::triangles`] (default options; built
    /// once).
    pub fn bvh(&self) -> &Bvh {
        self.bvh.get_or_init(|| {
            let bvh = Bvh::build(self.triangles(), &BvhOptions::default());
            self.counters.bvh.fetch_add(1, Ordering::Relaxed);
            bvh
        })
    }

    /// The scene's clusters of about a hundred triangles with their boxes, the unit of
    /// occlusion culling inside big objects (built once).
    pub fn clusters(&self) -> &crate::cull::clusters::Clusters {
        self.clusters
            .get_or_init(|| crate::cull::clusters::Clusters::new(self.scene))
    }

    /// The scene's candidate occluders: large convex planar faces and coplanar
    /// triangle pairs, largest first (built once; ranked per view by the occluder
    /// method, [`crate::cull::occluders`]).
    pub fn occluder_candidates(&self) -> &crate::cull::occluders::select::OccluderCandidates {
        self.occluder_candidates
            .get_or_init(|| crate::cull::occluders::select::OccluderCandidates::new(self.scene))
    }

    /// A binary hierarchy over the boxes of [`Self::clusters`], walked against the
    /// occluders' shadow volumes (built once).
    pub fn cluster_bvh(&self) -> &crate::cull::occluders::walk::ClusterBvh {
        self.cluster_bvh
            .get_or_init(|| crate::cull::occluders::walk::ClusterBvh::new(self.clusters()))
    }

    /// The PVS table of the scene's cells ([`crate::cull::portals::pvs::compute`] with
    /// the default options: no time limit, a budget of portal sequences per cell), built
    /// once; `None` for a scene without cells.
    pub fn pvs(&self) -> Option<&crate::cull::portals::Pvs> {
        self.pvs_with_progress(&|_, _| {})
    }

    /// [`Self::pvs`], reporting `(cells done, cells)` to `progress` while it is computed
    /// (on the first call only; later calls return the table at once).
    pub fn pvs_with_progress(
        &self,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Option<&crate::cull::portals::Pvs> {
        self.pvs
            .get_or_init(|| {
                let graph = self.scene.cells()?;
                // Without a deadline the computation cannot fail.
                crate::cull::portals::pvs::compute(
                    graph,
                    &crate::cull::portals::PvsOptions::default(),
                    progress,
                )
                .ok()
            })
            .as_ref()
    }

    /// Decides what one view cannot see ([`crate::cull::occlusion::cull`]).
    ///
    /// # Errors
    /// As [`crate::cull::occlusion::cull`].
    pub fn cull(
        &self,
        camera: &crate::Camera,
        viewport: crate::Viewport,
        options: &crate::cull::occlusion::CullOptions,
    ) -> Result<crate::cull::occlusion::Culling> {
        crate::cull::occlusion::cull(self, camera, viewport, options)
    }

    /// The edge adjacency of every object's mesh, in object order (built once).
    pub fn edge_adjacency(&self) -> &[EdgeAdjacency] {
        self.adjacency.get_or_init(|| {
            let a = self
                .scene
                .objects()
                .iter()
                .map(|o| EdgeAdjacency::new(&o.mesh))
                .collect();
            self.counters.adjacency.fetch_add(1, Ordering::Relaxed);
            a
        })
    }

    /// Where polygons of the scene pass through each other, one segment per crossing
    /// pair (see [`crate::lines::edges::intersect`]; view independent, built once,
    /// with [`Self::bvh`]).
    pub fn intersection_lines(&self) -> &[IntersectionSegment] {
        self.intersections
            .get_or_init(|| crate::lines::edges::intersect::intersection_lines(self.bvh()))
    }

    /// The uniform grid over [`Self::triangles`] for these options, built under
    /// `budget` the first time (see [`UniformGrid::build_until`]), stopped by
    /// `deadline` (see [`crate::work`]; a stopped build is not kept). One grid is kept
    /// for every [`GridOptions::ray_origins`]: it is built for origins up to
    /// [`GRID_HEADROOM`] scene extents away from the scene, and rebuilt only for
    /// origins farther than it serves (see "One grid for every eye" in the
    /// [module documentation](self)).
    pub fn grid(
        &self,
        options: &GridOptions,
        budget: &MemoryBudget,
        deadline: &crate::work::Deadline,
    ) -> Result<Arc<UniformGrid>> {
        let origins = options.ray_origins.abs();
        let key = GridOptions {
            ray_origins: 0.0,
            ..*options
        };
        self.grids.get_or_replace(
            (key, budget.limit()),
            |kept| kept.serves_origins(origins),
            || {
                let b = self.triangles().bounds();
                let reach = b.magnitude() + GRID_HEADROOM * b.extent().max_element();
                let built_for = key.with_ray_origins(origins.max(reach));
                let g = UniformGrid::build_until(self.triangles(), &built_for, budget, deadline)?;
                self.counters.grid.fetch_add(1, Ordering::Relaxed);
                Ok(g)
            },
        )
    }

    /// The BSP tree of the scene for these options (their memory limit included),
    /// built the first time (see [`BspTree::build`]), stopped by `deadline` (see
    /// [`crate::work`]; a stopped build is not kept).
    pub fn bsp(
        &self,
        options: &BspOptions,
        deadline: &crate::work::Deadline,
    ) -> Result<Arc<BspTree>> {
        self.bsp.get_or_build(*options, || {
            let t = BspTree::build_until(self.scene, options, deadline)?;
            self.counters.bsp.fetch_add(1, Ordering::Relaxed);
            Ok(t)
        })
    }

    /// The octree of the scene at `depth`, checked against the budget of `options`
    /// before it is built the first time ([`surface::octree::check_budget`]), stopped
    /// by the deadline of `options` (see [`crate::work`]; a stopped build is not kept).
    pub fn octree(&self, depth: u32, options: &RenderOptions) -> Result<Arc<Octree>> {
        let (tree, built) =
            self.octrees
                .get_or_build_unlocked((depth, options.budget().limit()), || {
                    let probe = options.clone().with_octree_depth(depth);
                    surface::octree::check_budget(self.scene, &probe)?;
                    Octree::from_scene_until(self.scene, depth, &options.deadline)
                })?;
        if built {
            self.counters.octree.fetch_add(1, Ordering::Relaxed);
        }
        Ok(tree)
    }

    /// Renders a prepared view of this index's scene with an algorithm, taking the
    /// structures it needs from the index (built on first use). The same frame and
    /// stats as [`surface::render`], which builds them for its one call.
    pub fn render(
        &self,
        view: &PreparedView<'_>,
        algorithm: Algorithm,
        options: &RenderOptions,
    ) -> Result<(Frame, Stats)> {
        self.check_scene(view)?;
        surface::render_indexed(self, algorithm, view, options)
    }

    /// Renders a view of this index's scene with an algorithm. The algorithms that
    /// need no screen polygons (the ray casters, BSP, octree:
    /// [`Algorithm::needs_polygons`]) read only the view's decisions; for the others
    /// the polygons are built for this call (to render several of them, build them
    /// once with [`View::into_prepared`] and call [`Self::render`]).
    pub fn render_view(
        &self,
        view: &View<'_>,
        algorithm: Algorithm,
        options: &RenderOptions,
    ) -> Result<(Frame, Stats)> {
        self.check_scene(view)?;
        if algorithm.needs_polygons() {
            return self.render(&view.clone().into_prepared(), algorithm, options);
        }
        surface::render_view_indexed(self, algorithm, view, options)
    }

    /// A view with the culling stage: [`Self::cull`] decides what the camera cannot see,
    /// then [`View::new_culled`] leaves it out (its vertices are never transformed, its
    /// faces reach no algorithm). The decisions stay on the view ([`View::culling`]).
    /// With [`crate::cull::occlusion::CullMethod::None`] nothing is culled beyond the
    /// view's own frustum test of objects, as [`View::new`].
    ///
    /// # Errors
    /// As [`Self::cull`] and [`View::new_culled`].
    pub fn view_culled(
        &self,
        camera: &crate::Camera,
        viewport: crate::Viewport,
        prepare: &PrepareOptions,
        cull: &crate::cull::occlusion::CullOptions,
    ) -> Result<View<'s>> {
        let culling = self.cull(camera, viewport, cull)?;
        View::new_culled(self.scene, camera, viewport, prepare, culling)
    }

    /// Renders one view of this index's scene with the culling stage and an algorithm:
    /// [`Self::view_culled`], then [`Self::render_view`]. Returns the frame, the
    /// algorithm's stats and the culling decisions (what was culled and why, counts and
    /// stage times). Every method is conservative, so the frame equals the one
    /// [`View::new`] gives, pixel for pixel.
    ///
    /// ```
    /// use obscura::cull::occlusion::{CullMethod, CullOptions};
    /// use obscura::{Algorithm, PrepareOptions, RenderOptions, SceneIndex, Viewport};
    /// let scene = obscura::Scene::demo("city")?;
    /// let index = SceneIndex::new(&scene);
    /// let vp = Viewport::new(64, 36)?;
    /// let camera = scene.default_camera(vp.aspect());
    /// let (frame, _, culling) = index.render_culled(
    ///     &camera,
    ///     vp,
    ///     &PrepareOptions::default(),
    ///     &CullOptions::with_method(CullMethod::Frustum),
    ///     Algorithm::ZBuffer,
    ///     &RenderOptions::default(),
    /// )?;
    /// assert_eq!(culling.faces.len(), scene.objects().iter().map(|o| o.mesh.polygon_count()).sum::<usize>());
    /// assert!(frame.covered_pixels() > 0);
    /// # Ok::<(), obscura::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`Self::view_culled`] and [`Self::render_view`].
    pub fn render_culled(
        &self,
        camera: &crate::Camera,
        viewport: crate::Viewport,
        prepare: &PrepareOptions,
        cull: &crate::cull::occlusion::CullOptions,
        algorithm: Algorithm,
        options: &RenderOptions,
    ) -> Result<(Frame, Stats, crate::cull::occlusion::Culling)> {
        let (view, culling) = self.view_and_culling(camera, viewport, prepare, cull)?;
        let (frame, stats) = self.render_owned_view(view, algorithm, options)?;
        Ok((frame, stats, culling))
    }

    /// [`Self::view_culled`] and its decisions, taken out of the view (not copied).
    fn view_and_culling(
        &self,
        camera: &crate::Camera,
        viewport: crate::Viewport,
        prepare: &PrepareOptions,
        cull: &crate::cull::occlusion::CullOptions,
    ) -> Result<(View<'s>, crate::cull::occlusion::Culling)> {
        let mut view = self.view_culled(camera, viewport, prepare, cull)?;
        let culling = view
            .take_culling()
            .expect("a view made with a culling run keeps it");
        Ok((view, culling))
    }

    /// [`Self::render_view`] of a view given away: its polygons are built from it
    /// without copying it.
    fn render_owned_view(
        &self,
        view: View<'_>,
        algorithm: Algorithm,
        options: &RenderOptions,
    ) -> Result<(Frame, Stats)> {
        self.check_scene(&view)?;
        if algorithm.needs_polygons() {
            return self.render(&view.into_prepared(), algorithm, options);
        }
        surface::render_view_indexed(self, algorithm, &view, options)
    }

    /// [`Self::render`] into a [`Renderer`]'s kept frame and buffers: the same frame
    /// and stats, but a renderer drawing many frames with the z-buffer allocates
    /// nothing and faults in no memory after its first frame of the largest size.
    /// Returns the frame (held by the renderer until its next render) and the stats.
    ///
    /// ```
    /// use obscura::{Algorithm, PrepareOptions, RenderOptions, Renderer, SceneIndex, View, Viewport};
    /// let scene = obscura::scene::demo::cube();
    /// let index = SceneIndex::new(&scene);
    /// let mut renderer = Renderer::new();
    /// for (w, h) in [(64, 48), (32, 24)] {
    ///     let vp = Viewport::new(w, h)?;
    ///     let view = View::new(&scene, &scene.default_camera(vp.aspect()), vp, &PrepareOptions::default())?
    ///         .into_prepared();
    ///     let (frame, _) = index.render_into(&mut renderer, &view, Algorithm::ZBuffer, &RenderOptions::default())?;
    ///     assert_eq!(*frame, index.render(&view, Algorithm::ZBuffer, &RenderOptions::default())?.0);
    /// }
    /// # Ok::<(), obscura::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`Self::render`] (the renderer's frame is then unspecified).
    pub fn render_into<'r>(
        &self,
        renderer: &'r mut Renderer,
        view: &PreparedView<'_>,
        algorithm: Algorithm,
        options: &RenderOptions,
    ) -> Result<(&'r Frame, Stats)> {
        self.check_scene(view)?;
        let Renderer { frame, zbuffer } = renderer;
        let stats = surface::render_indexed_into(self, algorithm, view, options, frame, zbuffer)?;
        Ok((frame, stats))
    }

    /// [`Self::render_culled`] into a [`Renderer`]'s kept frame and buffers (see
    /// [`Self::render_into`]): the same frame, stats and decisions.
    ///
    /// # Errors
    /// As [`Self::render_culled`] (the renderer's frame is then unspecified).
    #[allow(clippy::too_many_arguments)]
    pub fn render_culled_into<'r>(
        &self,
        renderer: &'r mut Renderer,
        camera: &crate::Camera,
        viewport: crate::Viewport,
        prepare: &PrepareOptions,
        cull: &crate::cull::occlusion::CullOptions,
        algorithm: Algorithm,
        options: &RenderOptions,
    ) -> Result<(&'r Frame, Stats, crate::cull::occlusion::Culling)> {
        let (view, culling) = self.view_and_culling(camera, viewport, prepare, cull)?;
        let stats = if algorithm.needs_polygons() {
            self.render_into(renderer, &view.into_prepared(), algorithm, options)?
                .1
        } else {
            let (frame, stats) = self.render_owned_view(view, algorithm, options)?;
            renderer.frame = frame;
            stats
        };
        Ok((&renderer.frame, stats, culling))
    }

    fn check_scene(&self, view: &View<'_>) -> Result<()> {
        if std::ptr::eq(view.scene(), self.scene) {
            Ok(())
        } else {
            Err(Error::option(
                "view",
                "the view is of another scene than the index's",
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No time limit.
    const NO_LIMIT: crate::work::Deadline = crate::work::Deadline::NONE;
    use crate::scene::{Camera, Viewport, demo};
    use glam::DVec3;

    fn views(scene: &Scene) -> Vec<View<'_>> {
        let vp = Viewport::new(48, 36).unwrap();
        [DVec3::new(3., 2., 4.), DVec3::new(-4., 1., 3.)]
            .into_iter()
            .map(|eye| {
                let cam = Camera::perspective(eye, DVec3::ZERO, DVec3::Y, 50.0, 0.1, 30.0);
                View::new(scene, &cam, vp, &PrepareOptions::default()).unwrap()
            })
            .collect()
    }

    #[test]
    fn each_structure_is_built_once_for_two_views() {
        let scene = demo::cube();
        let index = SceneIndex::new(&scene);
        assert_eq!(index.builds(), IndexBuilds::default());
        let ro = RenderOptions::default();
        for view in views(&scene) {
            for a in [Algorithm::RaycastBvh, Algorithm::Bsp, Algorithm::Octree] {
                index.render_view(&view, a, &ro).unwrap();
            }
        }
        let b = index.builds();
        assert_eq!((b.triangles, b.bvh, b.bsp, b.octree), (1, 1, 1, 1));
        assert!(std::ptr::eq(index.bvh(), index.bvh()));
        assert!(std::ptr::eq(index.triangles(), index.triangles()));
        let bsp = BspOptions::default().with_memory_limit(ro.memory_limit);
        assert!(Arc::ptr_eq(
            &index.bsp(&bsp, &NO_LIMIT).unwrap(),
            &index.bsp(&bsp, &NO_LIMIT).unwrap()
        ));
        let o1 = index.octree(3, &ro).unwrap();
        assert!(Arc::ptr_eq(&o1, &index.octree(3, &ro).unwrap()));
        assert_eq!(index.builds().octree, 2, "depth 3 is a second octree");
        assert!(std::ptr::eq(index.edge_adjacency(), index.edge_adjacency()));
        assert_eq!(index.builds().adjacency, 1);
    }

    /// One renderer through views of every culling method, algorithms with and
    /// without polygons and sizes growing and shrinking gives each time the frame,
    /// decisions and counts of a fresh render.
    #[test]
    fn a_renderer_gives_the_frames_of_fresh_renders() {
        use crate::cull::occlusion::{CullMethod, CullOptions};
        let scene = demo::city(8, 6, 3);
        let index = SceneIndex::new(&scene);
        let mut renderer = Renderer::new();
        assert_eq!(renderer.frame().ids.len(), 0);
        let prep = PrepareOptions::default();
        let ro = RenderOptions::default();
        let sizes = [(160, 90), (320, 200), (97, 61), (320, 201)];
        let mut covered = 0;
        for (k, method) in CullMethod::ALL.into_iter().enumerate() {
            for (j, &(w, h)) in sizes.iter().enumerate() {
                let vp = crate::Viewport::new(w, h).unwrap();
                let camera = crate::scene::random::orbit_cameras(&scene, 1, (k * 7 + j) as u64)[0];
                let algorithm = if j == 2 {
                    Algorithm::RaycastBvh
                } else {
                    Algorithm::ZBuffer
                };
                let cull = CullOptions::with_method(method);
                let (fresh, fresh_stats, fresh_culling) = index
                    .render_culled(&camera, vp, &prep, &cull, algorithm, &ro)
                    .unwrap();
                let (frame, stats, culling) = index
                    .render_culled_into(&mut renderer, &camera, vp, &prep, &cull, algorithm, &ro)
                    .unwrap();
                let what = format!("{}, {w}x{h}, {algorithm}", method.name());
                assert!(*frame == fresh, "{what}: the kept frame differs");
                assert_eq!(culling.faces, fresh_culling.faces, "{what}");
                assert_eq!(culling.objects, fresh_culling.objects, "{what}");
                let counts = |s: &Stats| {
                    s.zbuffer()
                        .map(|z| (z.polygons, z.polygons_drawn, z.pixels_written))
                };
                assert_eq!(counts(&stats), counts(&fresh_stats), "{what}");
                covered += fresh.covered_pixels();
                // And a prepared view of its own.
                let view = View::new(&scene, &camera, vp, &prep)
                    .unwrap()
                    .into_prepared();
                let (frame, _) = index
                    .render_into(&mut renderer, &view, algorithm, &ro)
                    .unwrap();
                assert!(
                    *frame == fresh,
                    "{what}: the kept frame of the plain view differs"
                );
            }
        }
        assert!(covered > 100_000, "the views must show the city: {covered}");
        assert_eq!(renderer.into_frame().width, 320);
    }

    #[test]
    fn structures_built_by_other_options_are_kept_apart() {
        let scene = demo::cube();
        let index = SceneIndex::new(&scene);
        let a = index.bsp(&BspOptions::default(), &NO_LIMIT).unwrap();
        let b = index
            .bsp(&BspOptions::default().with_seed(7), &NO_LIMIT)
            .unwrap();
        assert!(!Arc::ptr_eq(&a, &b));
        assert!(Arc::ptr_eq(
            &a,
            &index.bsp(&BspOptions::default(), &NO_LIMIT).unwrap()
        ));
        assert_eq!(index.builds().bsp, 2);
        let budget = MemoryBudget::from_option(None);
        let g1 = index
            .grid(&GridOptions::default(), &budget, &NO_LIMIT)
            .unwrap();
        let g2 = index
            .grid(
                &GridOptions::default().with_density(8.0),
                &budget,
                &NO_LIMIT,
            )
            .unwrap();
        assert!(!Arc::ptr_eq(&g1, &g2));
        assert!(Arc::ptr_eq(
            &g1,
            &index
                .grid(&GridOptions::default(), &budget, &NO_LIMIT)
                .unwrap()
        ));
        assert_eq!(index.builds().grid, 2);
    }

    #[test]
    fn a_build_over_its_budget_is_refused_and_not_kept() {
        let scene = demo::cube();
        let index = SceneIndex::new(&scene);
        let tiny = RenderOptions::default().with_memory_limit(Some(64));
        let err = index.octree(6, &tiny).unwrap_err();
        assert!(err.to_string().contains("memory budget"), "{err}");
        assert_eq!(index.builds().octree, 0);
        // The same options fail again (nothing was kept as a success)...
        assert!(index.octree(6, &tiny).is_err());
        // ...and a budget that allows it builds it.
        index.octree(6, &RenderOptions::default()).unwrap();
        assert_eq!(index.builds().octree, 1);
        let tiny_bsp = BspOptions::default().with_memory_limit(Some(64));
        assert!(index.bsp(&tiny_bsp, &NO_LIMIT).is_err());
        assert!(index.bsp(&tiny_bsp, &NO_LIMIT).is_err());
        assert_eq!(index.builds().bsp, 0);
    }

    #[test]
    fn threads_share_one_build() {
        let scene = demo::default_scene();
        let index = SceneIndex::new(&scene);
        let views = views(&scene);
        let ro = RenderOptions::default();
        let frames: Vec<Vec<u32>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..4)
                .map(|i| {
                    let (index, view, ro) = (&index, &views[i % 2], &ro);
                    s.spawn(move || {
                        let (bvh, _) = index.render_view(view, Algorithm::RaycastBvh, ro).unwrap();
                        let (bsp, _) = index.render_view(view, Algorithm::Bsp, ro).unwrap();
                        assert_eq!(bvh.ids, bsp.ids);
                        bvh.ids
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert_eq!(frames[0], frames[2]);
        assert_eq!(frames[1], frames[3]);
        let b = index.builds();
        assert_eq!((b.triangles, b.bvh, b.bsp), (1, 1, 1));
    }

    /// A view of the scene, framed, from `distance` scene sizes (its largest extent)
    /// away from its centre.
    fn view_from(scene: &Scene, distance: f64) -> View<'_> {
        let vp = Viewport::new(32, 24).unwrap();
        let b = scene.bounds();
        let (centre, size) = (b.center(), b.extent().max_element());
        let eye = centre + DVec3::new(0.6, 0.4, 1.0).normalize() * distance * size;
        let fov = (2.0 * (1.2 / distance).atan()).to_degrees();
        let (near, far) = (size * distance * 0.2, size * distance * 2.0);
        let cam = Camera::perspective(eye, centre, DVec3::Y, fov, near, far);
        View::new(scene, &cam, vp, &PrepareOptions::default()).unwrap()
    }

    /// The grid's frames, ids and depth bits, against the BVH's (which no grid touches).
    fn assert_grid_equals_bvh(index: &SceneIndex<'_>, view: &View<'_>, distance: f64) {
        let ro = RenderOptions::default();
        let (grid, _) = index
            .render_view(view, Algorithm::RaycastGrid, &ro)
            .unwrap();
        let (bvh, _) = index.render_view(view, Algorithm::RaycastBvh, &ro).unwrap();
        assert!(bvh.covered_pixels() > 0, "distance {distance:e}");
        assert_eq!(grid.ids, bvh.ids, "ids from distance {distance:e}");
        let bits = |f: &Frame| f.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&grid), bits(&bvh), "depth from distance {distance:e}");
    }

    #[test]
    fn one_grid_serves_eyes_at_very_different_distances() {
        let scene = demo::default_scene();
        let index = SceneIndex::new(&scene);
        // Within the headroom: one grid, whichever eye asks first.
        let reach = GRID_HEADROOM;
        for distance in [3.0, 40.0, reach * 0.5] {
            assert_grid_equals_bvh(&index, &view_from(&scene, distance), distance);
        }
        assert_eq!(index.builds().grid, 1);
        // Farther than the cells' growth covers (they are grown by at least `10^-7` of
        // their size): the grid is rebuilt for that eye, and then serves the nearer ones.
        let far = 1e9;
        assert_grid_equals_bvh(&index, &view_from(&scene, far), far);
        assert_eq!(index.builds().grid, 2);
        for distance in [3.0, reach * 0.5] {
            assert_grid_equals_bvh(&index, &view_from(&scene, distance), distance);
        }
        assert_eq!(index.builds().grid, 2);
        // A grid built for the far eye first gives the near eye's frame bit for bit.
        let fresh = SceneIndex::new(&scene);
        assert_grid_equals_bvh(&fresh, &view_from(&scene, far), far);
        assert_grid_equals_bvh(&fresh, &view_from(&scene, 3.0), 3.0);
        assert_eq!(fresh.builds().grid, 1);
    }

    #[test]
    fn a_view_of_another_scene_is_refused() {
        let (a, b) = (demo::cube(), demo::cube());
        let index = SceneIndex::new(&a);
        let view = &views(&b)[0];
        assert!(
            index
                .render_view(view, Algorithm::RaycastBvh, &RenderOptions::default())
                .is_err()
        );
    }
}
