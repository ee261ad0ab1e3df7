//! The occlusion-culling stage: which method runs, what it culls and why.
//!
//! [`cull`] decides, for one camera and viewport, which objects and which clusters
//! ([`super::clusters`]) of a scene cannot be seen, and gives each culled one its
//! reason. [`crate::View::new_culled`] then leaves them out: their vertices are never
//! transformed and their faces never reach an algorithm. The frustum stage runs first
//! in every method but [`CullMethod::None`]; objects and clusters it removes carry
//! [`CullReason::Frustum`].
//!
//! The rule: never cull anything visible. Each method is tested for it on hundreds of
//! viewpoints (the picture with culling equals the picture without, pixel for pixel).

use std::time::Instant;

use serde::Serialize;

use crate::Result;
use crate::index::SceneIndex;
use crate::scene::{Camera, Viewport};

/// Which occlusion-culling method a view uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum CullMethod {
    /// No culling stage at all (the view's own frustum culling of objects still runs,
    /// as [`crate::PrepareOptions::frustum_cull_objects`] says).
    None,
    /// Objects and clusters outside the view volume.
    #[default]
    Frustum,
    /// Cells and portals, from a region: the viewer's cell (BSP), its PVS row, and
    /// portal rendering that shrinks the frustum through each portal.
    Portals,
    /// Screen-space portals, from a point (Luebke-Georges): portal rectangles
    /// intersected recursively, no precomputation.
    ScreenPortals,
    /// Occluders ranked by the Coorg-Teller metric, their shadow volumes, the bounds
    /// hierarchy walked against them.
    Occluders,
    /// Occluder fusion: occluders rasterized into a conservative occlusion buffer,
    /// bounding boxes tested against it.
    Buffer,
}

impl CullMethod {
    /// Every method, in the order above.
    pub const ALL: [CullMethod; 6] = [
        CullMethod::None,
        CullMethod::Frustum,
        CullMethod::Portals,
        CullMethod::ScreenPortals,
        CullMethod::Occluders,
        CullMethod::Buffer,
    ];

    /// The method's name as the CLI spells it (`screen-portals`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            CullMethod::None => "none",
            CullMethod::Frustum => "frustum",
            CullMethod::Portals => "portals",
            CullMethod::ScreenPortals => "screen-portals",
            CullMethod::Occluders => "occluders",
            CullMethod::Buffer => "buffer",
        }
    }

    /// The method of a name ([`Self::name`]).
    #[must_use]
    pub fn from_name(name: &str) -> Option<CullMethod> {
        CullMethod::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Why an object or a cluster was culled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case", tag = "reason", content = "id")]
#[non_exhaustive]
pub enum CullReason {
    /// Outside the view volume.
    Frustum,
    /// Not reached through the portals (outside the viewer cell's PVS, or outside the
    /// frustum shrunk through every portal sequence leading to it).
    Portal,
    /// Inside the shadow volume of this occluder (its index in the method's ranked
    /// occluder list, [`Culling::occluders`]).
    Occluder(u32),
    /// Behind the occlusion buffer at every pixel its bounds cover.
    Buffer,
}

impl CullReason {
    /// A short name (`frustum`, `portal`, `occluder`, `buffer`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            CullReason::Frustum => "frustum",
            CullReason::Portal => "portal",
            CullReason::Occluder(_) => "occluder",
            CullReason::Buffer => "buffer",
        }
    }
}

/// Options of [`cull`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct CullOptions {
    /// The method.
    pub method: CullMethod,
    /// Whether big objects are culled cluster by cluster (clusters of about
    /// [`super::clusters::CLUSTER_TRIANGLES`] triangles), besides whole objects.
    pub clusters: bool,
    /// Portals: replace each shrunk frustum by the bounding box of its screen
    /// rectangle (the seed's hardware-friendly approximation) instead of the exact
    /// convex frustum.
    pub portal_bounding_box: bool,
    /// Occluders: how many of the best-ranked candidates are used.
    pub max_occluders: usize,
    /// The occlusion buffer: its kind and resolution.
    pub buffer: super::buffer::BufferOptions,
}

impl Default for CullOptions {
    fn default() -> Self {
        CullOptions {
            method: CullMethod::Frustum,
            clusters: true,
            portal_bounding_box: false,
            max_occluders: 64,
            buffer: super::buffer::BufferOptions::default(),
        }
    }
}

impl CullOptions {
    /// The default options with this method.
    #[must_use]
    pub fn with_method(method: CullMethod) -> Self {
        CullOptions {
            method,
            ..CullOptions::default()
        }
    }
}

/// The counts and times of one culling run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[non_exhaustive]
pub struct CullStats {
    /// Objects with faces tested (every object of the scene with at least one face).
    pub objects_tested: u64,
    /// Objects culled whole, by any reason.
    pub objects_culled: u64,
    /// Clusters tested (those of objects not culled whole).
    pub clusters_tested: u64,
    /// Clusters culled (inside objects not culled whole).
    pub clusters_culled: u64,
    /// Faces (scene polygons) of the objects tested.
    pub faces_tested: u64,
    /// Faces culled, whole objects and clusters together.
    pub faces_culled: u64,
    /// Culled objects by reason: frustum, portal, occluder, buffer.
    pub objects_by_reason: ReasonCounts,
    /// Culled clusters by reason.
    pub clusters_by_reason: ReasonCounts,
    /// The time of each stage, `(name, milliseconds)`, in order.
    pub stages: Vec<(String, f64)>,
    /// The whole run in milliseconds.
    pub total_ms: f64,
}

/// Counts per [`CullReason`] kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ReasonCounts {
    /// [`CullReason::Frustum`].
    pub frustum: u64,
    /// [`CullReason::Portal`].
    pub portal: u64,
    /// [`CullReason::Occluder`].
    pub occluder: u64,
    /// [`CullReason::Buffer`].
    pub buffer: u64,
}

impl ReasonCounts {
    fn add(&mut self, r: CullReason) {
        match r {
            CullReason::Frustum => self.frustum += 1,
            CullReason::Portal => self.portal += 1,
            CullReason::Occluder(_) => self.occluder += 1,
            CullReason::Buffer => self.buffer += 1,
        }
    }
}

/// What a culling run decided: per object and per cluster, culled (with the reason) or
/// kept; the faces that follow; notes (such as "the viewer is outside every cell: no
/// portal culling"); counts and times.
#[derive(Clone, Debug, PartialEq)]
pub struct Culling {
    /// The method that ran.
    pub method: CullMethod,
    /// Per scene object: `Some(reason)` if culled whole.
    pub objects: Vec<Option<CullReason>>,
    /// Per cluster of [`SceneIndex::clusters`]: `Some(reason)` if culled. A cluster of
    /// an object culled whole carries the object's reason.
    pub clusters: Vec<Option<CullReason>>,
    /// The occluders the method used, best first (for [`CullReason::Occluder`]): each
    /// as the scene polygon it came from, or `u32::MAX` for a face of an object's
    /// occluder mesh.
    pub occluders: Vec<u32>,
    /// Per scene polygon (scene order, as [`crate::View::polygon_base`]): culled.
    pub faces: Vec<bool>,
    /// What the method wants the user to know (fallbacks taken, leaks found).
    pub notes: Vec<String>,
    /// The occlusion buffer's depths, for [`CullMethod::Buffer`] (what `--explain`
    /// draws beside the culled objects).
    pub buffer_image: Option<BufferImage>,
    /// Counts and times.
    pub stats: CullStats,
}

impl Culling {
    /// Nothing culled: every object and cluster kept.
    #[must_use]
    pub fn keep_all(index: &SceneIndex<'_>, method: CullMethod) -> Culling {
        let scene = index.scene();
        let faces = scene.objects().iter().map(|o| o.mesh.polygon_count()).sum();
        Culling {
            method,
            objects: vec![None; scene.objects().len()],
            clusters: vec![None; index.clusters().len()],
            occluders: Vec::new(),
            faces: vec![false; faces],
            notes: Vec::new(),
            buffer_image: None,
            stats: CullStats::default(),
        }
    }

    /// Culls object `k` whole (a reason already given stays).
    pub fn cull_object(&mut self, k: usize, reason: CullReason) {
        if self.objects[k].is_none() {
            self.objects[k] = Some(reason);
        }
    }

    /// Culls cluster `c` (a reason already given stays).
    pub fn cull_cluster(&mut self, c: usize, reason: CullReason) {
        if self.clusters[c].is_none() {
            self.clusters[c] = Some(reason);
        }
    }

    /// Recomputes [`Self::faces`] and the counts from the object and cluster decisions
    /// (every method ends with it).
    pub fn finish(&mut self, index: &SceneIndex<'_>) {
        let scene = index.scene();
        let clusters = index.clusters();
        let mut s = CullStats {
            stages: std::mem::take(&mut self.stats.stages),
            total_ms: self.stats.total_ms,
            ..CullStats::default()
        };
        let mut base = 0usize;
        let mut object_base = Vec::with_capacity(scene.objects().len());
        for (k, o) in scene.objects().iter().enumerate() {
            object_base.push(base);
            let n = o.mesh.polygon_count();
            if n > 0 {
                s.objects_tested += 1;
                s.faces_tested += n as u64;
            }
            let culled = self.objects[k];
            self.faces[base..base + n].fill(culled.is_some());
            if let Some(r) = culled.filter(|_| n > 0) {
                s.objects_culled += 1;
                s.objects_by_reason.add(r);
            }
            base += n;
        }
        for c in 0..clusters.len() {
            let k = clusters.object(c) as usize;
            if let Some(r) = self.objects[k] {
                self.clusters[c] = Some(r);
                continue;
            }
            s.clusters_tested += 1;
            if let Some(r) = self.clusters[c] {
                s.clusters_culled += 1;
                s.clusters_by_reason.add(r);
                for &p in clusters.polygons(c) {
                    self.faces[object_base[k] + p as usize] = true;
                }
            }
        }
        s.faces_culled = self.faces.iter().filter(|&&f| f).count() as u64;
        self.stats = s;
    }

    /// Adds a stage time to the stats.
    pub fn stage(&mut self, name: &str, start: Instant) {
        self.stats
            .stages
            .push((name.to_owned(), start.elapsed().as_secs_f64() * 1e3));
    }
}

/// An occlusion buffer's depths as an image: row 0 at the top, one value per buffer
/// pixel (per tile pixel for a masked buffer: the tile's conservative depth), the
/// eye-space depth behind which a box is hidden; `f32::INFINITY` where nothing covers.
#[derive(Clone, Debug, PartialEq)]
pub struct BufferImage {
    /// Width in buffer pixels.
    pub width: u32,
    /// Height in buffer pixels.
    pub height: u32,
    /// `width * height` depths.
    pub depth: Vec<f32>,
}

/// Decides what one view of the index's scene cannot see. The frustum stage runs first
/// for every method but [`CullMethod::None`]; the method then culls among what is left.
///
/// Errors: an invalid camera or viewport, and what the method refuses (portals without
/// cells in the scene are not an error: the method notes it and culls by the frustum).
pub fn cull(
    index: &SceneIndex<'_>,
    camera: &Camera,
    viewport: Viewport,
    options: &CullOptions,
) -> Result<Culling> {
    let start = Instant::now();
    viewport.validate()?;
    let t = crate::view::checked_transform(index.scene(), camera, viewport)?;
    let mut c = Culling::keep_all(index, options.method);
    if options.method != CullMethod::None {
        let s = Instant::now();
        super::clusters::frustum(index, &t, options.clusters, &mut c);
        c.stage("frustum", s);
    }
    match options.method {
        CullMethod::None | CullMethod::Frustum => {}
        CullMethod::Portals => super::portals::cull_portals(index, &t, options, &mut c)?,
        CullMethod::ScreenPortals => {
            super::portals::cull_screen_portals(index, &t, options, &mut c)?;
        }
        CullMethod::Occluders => super::occluders::cull(index, &t, options, &mut c)?,
        CullMethod::Buffer => super::buffer::cull(index, &t, options, &mut c)?,
    }
    c.stats.total_ms = start.elapsed().as_secs_f64() * 1e3;
    c.finish(index);
    Ok(c)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::scene::demo;
    use crate::surface::{Algorithm, RenderOptions};
    use crate::view::{PrepareOptions, View};

    /// The contract every method keeps, here for the frustum stage: a view made with
    /// the culling draws the same ids and depths as the view without it, for every
    /// algorithm, and the culled faces are counted.
    #[test]
    fn frustum_stage_keeps_the_picture_for_every_algorithm() {
        let scene = demo::city(6, 6, 7);
        let index = SceneIndex::new(&scene);
        let vp = Viewport::new(96, 64).unwrap();
        let camera = Camera::perspective(
            DVec3::new(-2.0, 1.7, -2.0),
            DVec3::new(10.0, 1.5, 8.0),
            DVec3::Y,
            60.0,
            0.1,
            500.0,
        );
        let opts = PrepareOptions::default();
        let culling = index
            .cull(&camera, vp, &CullOptions::with_method(CullMethod::Frustum))
            .unwrap();
        assert!(culling.stats.faces_culled > 0, "{:?}", culling.stats);
        assert_eq!(
            culling.stats.objects_by_reason.frustum,
            culling.stats.objects_culled
        );
        let plain = View::new(&scene, &camera, vp, &opts).unwrap();
        let culled = View::new_culled(&scene, &camera, vp, &opts, culling).unwrap();
        assert!(culled.vertex_count() <= plain.vertex_count());
        for a in Algorithm::ALL {
            let o = RenderOptions::default();
            let (f0, _) = index.render_view(&plain, a, &o).unwrap();
            let (f1, _) = index.render_view(&culled, a, &o).unwrap();
            assert_eq!(f0.ids, f1.ids, "{a:?}: ids");
            assert_eq!(f0.depth, f1.depth, "{a:?}: depth");
        }
    }
}
