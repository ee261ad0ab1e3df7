//! Scenes: objects made of planar faces, each with a transform, a colour and flags,
//! plus an optional camera.
//!
//! # Face ids
//! Faces are numbered from 0 in load order across the whole scene: object `k`'s local
//! face `f` has id `objects[k].first_face + f`. For OBJ files that is the order of the
//! `f` lines across all objects. An n-gon split into triangles keeps one id; a dropped
//! degenerate face keeps its id too (it just never appears in an image).

mod adjacency;
mod arrays;
mod camera;
mod camera_matrices;
pub mod demo;
pub mod load;
mod mesh;
pub mod occluder;
pub(crate) mod random;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat4, DVec3};

pub use adjacency::{EdgeAdjacency, MeshEdge, is_convex_closed};
pub use arrays::Faces;
pub(crate) use camera::ImageRays;
pub use camera::{Camera, Lens, Projection, Ray, Viewport};
pub use camera_matrices::Intrinsics;

/// The largest magnitude of a world coordinate (and of a camera's position and planes)
/// that obscura accepts. Its single-precision structures (the `f32` depth keys, the
/// BVH's `f32` boxes) hold values up to about 3.4e38; a bound far below that keeps
/// their arithmetic (differences, products of two coordinates) finite. Larger values
/// are refused with an error naming the object or the camera.
pub const MAX_COORDINATE: f64 = 1e30;

/// The smallest size of an object (the largest side of its box in world coordinates,
/// for an object with faces) that obscura accepts: `1e-30`, `1 / MAX_COORDINATE`. Products of
/// coordinates (plane normals, the ray casters' edge functions, the octree's
/// separating axes) are powers of a scene's size up to the fourth, and the BVH's
/// boxes are single precision: below this they lose their precision to underflow
/// (a triangle 1e-100 across squared its normal to zero). Smaller objects are refused
/// by [`Scene::add`] with an error naming the object and both sizes.
pub const MIN_EXTENT: f64 = 1e-30;

/// Whether the linear part of an affine transform is singular, judged on its columns
/// scaled to a largest entry of 1 each: a determinant that only overflows or
/// underflows (a scale of 1e200 or 1e-200 cubed) is not singular, one whose columns
/// are dependent is. Returns the sign of the determinant (`-1` mirrors), `None` when
/// singular or not finite.
#[must_use]
pub fn transform_orientation(m: &DMat4) -> Option<f64> {
    let cols = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    let mut n = [DVec3::ZERO; 3];
    for (k, c) in cols.iter().enumerate() {
        let big = c.abs().max_element();
        if !(big > 0.0 && big.is_finite()) {
            return None;
        }
        n[k] = *c / big;
    }
    let det = n[0].dot(n[1].cross(n[2]));
    (det != 0.0 && det.is_finite()).then(|| det.signum())
}
pub use mesh::{
    DEGENERACY_TOLERANCE, FaceError, FaceOutcome, LoadReport, Material, Mesh, MeshBuilder,
    PLANARITY_TOLERANCE,
};

use crate::geom::{Aabb, Sphere};
use crate::{Error, Result};

/// What is needed to add an object to a scene.
#[derive(Clone, Debug)]
pub struct ObjectDesc {
    /// A name for messages (file object/group name, or made up).
    pub name: String,
    /// The geometry, shareable between objects.
    pub mesh: Arc<Mesh>,
    /// Object to world (affine).
    pub transform: DMat4,
    /// Colour (linear RGB, 0..=1) for faces without a material.
    pub color: [f32; 3],
    /// Closed oriented 2-manifold (back faces may be culled); `None` detects it.
    pub closed: Option<bool>,
    /// Convex (implies closed); `None` detects it.
    pub convex: Option<bool>,
}

impl ObjectDesc {
    /// An object with identity transform, a default colour and detected flags.
    #[must_use]
    pub fn new(name: impl Into<String>, mesh: Mesh) -> Self {
        ObjectDesc {
            name: name.into(),
            mesh: Arc::new(mesh),
            transform: DMat4::IDENTITY,
            color: [0.8, 0.8, 0.8],
            closed: None,
            convex: None,
        }
    }

    /// Sets the transform.
    #[must_use]
    pub fn with_transform(mut self, transform: DMat4) -> Self {
        self.transform = transform;
        self
    }

    /// Sets the colour.
    #[must_use]
    pub fn with_color(mut self, color: [f32; 3]) -> Self {
        self.color = color;
        self
    }

    /// Sets the closed flag (instead of detecting it).
    #[must_use]
    pub fn with_closed(mut self, closed: bool) -> Self {
        self.closed = Some(closed);
        self
    }

    /// Sets the convex flag (instead of detecting it).
    #[must_use]
    pub fn with_convex(mut self, convex: bool) -> Self {
        self.convex = Some(convex);
        self
    }
}

/// An object of a scene.
#[derive(Clone, Debug)]
pub struct Object {
    /// Its name.
    pub name: String,
    /// Its geometry.
    pub mesh: Arc<Mesh>,
    /// Object to world.
    pub transform: DMat4,
    /// Colour of faces without a material.
    pub color: [f32; 3],
    /// Closed oriented 2-manifold: its back faces can never be seen from outside.
    pub closed: bool,
    /// Convex.
    pub convex: bool,
    /// The scene-wide id of local face 0.
    pub first_face: u32,
    /// Whether the transform mirrors (negative determinant): winding flips in world space.
    pub mirrored: bool,
    /// World-space box.
    pub bounds: Aabb,
    /// World-space bounding sphere.
    pub sphere: Sphere,
    /// Its occluder mesh, in world space (faces counter-clockwise seen from outside):
    /// a simplified mesh inside the object that the occluders and occlusion-buffer
    /// culling methods use in place of its faces, never drawn. Set with
    /// [`Scene::set_occluder`], which checks it (see [`occluder`]).
    pub occluder: Option<Arc<Mesh>>,
}

impl Object {
    /// The world-space vertices of polygon `i`.
    #[must_use]
    pub fn world_polygon(&self, i: usize) -> Vec<DVec3> {
        self.mesh
            .polygon(i)
            .iter()
            .map(|&v| {
                self.transform
                    .transform_point3(self.mesh.positions()[v as usize])
            })
            .collect()
    }

    /// The world-space position of every vertex of the mesh, in mesh order (each
    /// computed as [`Self::world_polygon`] computes it).
    #[must_use]
    pub fn world_positions(&self) -> Vec<DVec3> {
        let mut out = Vec::with_capacity(self.mesh.positions().len());
        self.world_positions_into(&mut out);
        out
    }

    /// Replaces `out` with the world-space position of every vertex of the mesh, in
    /// mesh order (each computed as [`Self::world_polygon`] computes it).
    pub(crate) fn world_positions_into(&self, out: &mut Vec<DVec3>) {
        out.clear();
        out.extend(
            self.mesh
                .positions()
                .iter()
                .map(|&p| self.transform.transform_point3(p)),
        );
    }

    /// Colour of a local face: its material's, else the object's.
    #[must_use]
    pub fn face_color(&self, face: u32) -> [f32; 3] {
        self.mesh
            .face_material(face)
            .map_or(self.color, |m| m.color)
    }
}

/// A scene: objects and an optional camera.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    objects: Vec<Object>,
    camera: Option<Camera>,
    up: Option<DVec3>,
    report: LoadReport,
    face_count: u32,
    sources: Vec<PathBuf>,
    cells: Option<Arc<crate::cull::portals::CellGraph>>,
}

/// Colours given to objects that have none, in order.
pub const PALETTE: [[f32; 3]; 8] = [
    [0.90, 0.45, 0.25],
    [0.30, 0.60, 0.90],
    [0.55, 0.80, 0.35],
    [0.95, 0.80, 0.30],
    [0.70, 0.45, 0.85],
    [0.35, 0.80, 0.80],
    [0.90, 0.40, 0.60],
    [0.75, 0.75, 0.70],
];

impl Scene {
    /// An empty scene.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Loads a scene from a file: a mesh (`.obj`, `.gltf`, `.glb`, `.stl`, `.ply`) or a
    /// `.toml` scene file, with the default [`load::LoadOptions`]. Built-in scenes come
    /// from [`Scene::demo`] (the CLI's `demo:NAME` maps to it); meshes already in
    /// memory from [`Scene::from_arrays`].
    ///
    /// A format whose cargo feature is disabled (`obj`, `gltf`, `stl`, `ply`,
    /// `toml-scene`, all on by default) is refused with an error naming the feature.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        load::load_file(path.as_ref())
    }

    /// [`Scene::load`] with options: what the scene may read and how much it may
    /// build (see [`load::LoadOptions`]).
    pub fn load_with(path: impl AsRef<Path>, options: &load::LoadOptions) -> Result<Scene> {
        load::load_file_with(path.as_ref(), options)
    }

    /// A built-in demo scene by name (`default`, `seed-task`, `cube`, `sphere`, `city`,
    /// `triangles`; see [`demo`]); an unknown name is [`Error::UnknownDemo`], which
    /// lists the known ones.
    ///
    /// ```
    /// let scene = obscura::Scene::demo("cube")?;
    /// assert_eq!(scene.face_count(), 6);
    /// # Ok::<(), obscura::Error>(())
    /// ```
    pub fn demo(name: &str) -> Result<Scene> {
        demo::scene(name)
    }

    /// The files loading read (the scene file, mesh files, material libraries, glTF
    /// buffers), canonical, each once, in the order first read; empty for a scene
    /// built in memory. A caller writing files can refuse to overwrite any of them.
    #[must_use]
    pub fn source_files(&self) -> &[PathBuf] {
        &self.sources
    }

    /// Sets the list [`Scene::source_files`] returns.
    pub(crate) fn set_source_files(&mut self, files: Vec<PathBuf>) {
        self.sources = files;
    }

    /// Adds an object, checking it, assigning its face ids and computing its bounds
    /// and flags. Returns its index.
    pub fn add(&mut self, desc: ObjectDesc) -> Result<usize> {
        let invalid = |m: String| Error::InvalidObject {
            object: desc.name.clone(),
            message: m,
        };
        if !desc.transform.is_finite() {
            return Err(invalid("the transform has non-finite entries".into()));
        }
        let last_row = desc.transform.row(3);
        if last_row != glam::DVec4::W {
            return Err(invalid(format!(
                "the transform is not affine (last row {:?}, not [0, 0, 0, 1])",
                last_row.to_array()
            )));
        }
        let Some(orientation) = transform_orientation(&desc.transform) else {
            return Err(invalid(
                "the transform is singular (flattens the object)".into(),
            ));
        };
        // Messages name vertices by index, not value: the values may come from a file
        // other than the one whose loader reports the error (a glTF's buffer).
        if let Some(i) = desc.mesh.positions().iter().position(|p| !p.is_finite()) {
            return Err(invalid(format!("vertex {i} is not finite")));
        }
        let world: Vec<DVec3> = {
            let (_, idx, _) = desc.mesh.polygon_arrays();
            let mut used = vec![false; desc.mesh.positions().len()];
            for &i in idx {
                used[i as usize] = true;
            }
            desc.mesh
                .positions()
                .iter()
                .zip(&used)
                .filter(|(_, u)| **u)
                .map(|(&p, _)| desc.transform.transform_point3(p))
                .collect()
        };
        if world.iter().any(|p| !p.is_finite()) {
            return Err(invalid(
                "a vertex overflows to a non-finite value when transformed".into(),
            ));
        }
        if world.iter().any(|p| p.abs().max_element() > MAX_COORDINATE) {
            return Err(invalid(format!(
                "a vertex (after the transform) is beyond the largest coordinate \
                 accepted, {MAX_COORDINATE:e}"
            )));
        }
        let bounds = Aabb::from_points(world.iter().copied());
        let extent = bounds.extent().max_element();
        if !bounds.is_empty() && extent < MIN_EXTENT {
            return Err(invalid(format!(
                "it is {extent:.1e} across (after its transform), below the smallest size \
                 accepted, {MIN_EXTENT:e}: products of its coordinates would underflow \
                 (scale it up; the whole scene may be scaled alike)"
            )));
        }
        let sphere = Sphere::bounding(&world).unwrap_or(Sphere {
            center: DVec3::ZERO,
            radius: 0.0,
        });
        let (closed, convex) = match (desc.closed, desc.convex) {
            (Some(c), Some(v)) => (c, v && c),
            (c, v) => {
                let adj = EdgeAdjacency::new(&desc.mesh);
                let closed = c.unwrap_or_else(|| adj.is_closed());
                let convex =
                    v.unwrap_or_else(|| closed && is_convex_closed(&desc.mesh, &adj, 1e-9));
                (closed, convex && closed)
            }
        };
        let first_face = self.face_count;
        let faces = desc.mesh.face_count();
        self.face_count = first_face
            .checked_add(faces)
            .ok_or_else(|| invalid("more than 2^32 faces in the scene".into()))?;
        self.objects.push(Object {
            name: desc.name,
            mesh: desc.mesh,
            transform: desc.transform,
            color: desc.color,
            closed,
            convex,
            first_face,
            mirrored: orientation < 0.0,
            bounds,
            sphere,
            occluder: None,
        });
        Ok(self.objects.len() - 1)
    }

    /// The objects, in load order.
    #[must_use]
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// The camera the scene file carries, if any.
    #[must_use]
    pub fn camera(&self) -> Option<&Camera> {
        self.camera.as_ref()
    }

    /// The scene's cells and portals, if it has them (a scene file's `[[cell]]` and
    /// `[[portal]]` tables, a demo level, a PRT1 file), for portal culling.
    #[must_use]
    pub fn cells(&self) -> Option<&Arc<crate::cull::portals::CellGraph>> {
        self.cells.as_ref()
    }

    /// Gives the scene its cells and portals (or takes them away).
    pub fn set_cells(&mut self, cells: Option<Arc<crate::cull::portals::CellGraph>>) {
        self.cells = cells;
    }

    /// Sets the scene's camera.
    pub fn set_camera(&mut self, camera: Option<Camera>) {
        self.camera = camera;
    }

    /// The scene's up axis, if known (used to frame the scene when no camera is given).
    #[must_use]
    pub fn up(&self) -> DVec3 {
        self.up.unwrap_or(DVec3::Y)
    }

    /// Sets the scene's up axis.
    pub fn set_up(&mut self, up: DVec3) {
        self.up = Some(up);
    }

    /// What loading fixed or dropped.
    #[must_use]
    pub fn report(&self) -> &LoadReport {
        &self.report
    }

    /// Mutable access to the report (for loaders).
    pub fn report_mut(&mut self) -> &mut LoadReport {
        &mut self.report
    }

    /// Number of face ids in the scene.
    #[must_use]
    pub fn face_count(&self) -> u32 {
        self.face_count
    }

    /// Number of polygons (after triangulation) in the scene.
    #[must_use]
    pub fn polygon_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.polygon_count()).sum()
    }

    /// Number of triangles the polygons would make.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangle_count()).sum()
    }

    /// The world-space box of everything.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.objects
            .iter()
            .fold(Aabb::EMPTY, |b, o| b.union(o.bounds))
    }

    /// The object and local face of a face id.
    #[must_use]
    pub fn locate_face(&self, id: u32) -> Option<(usize, u32)> {
        if id >= self.face_count {
            return None;
        }
        let k = self.objects.partition_point(|o| o.first_face <= id) - 1;
        Some((k, id - self.objects[k].first_face))
    }

    /// Fails with [`Error::EmptyScene`] when there is no polygon to render. The
    /// message carries the load report's warnings (the first few), which usually say
    /// why: nodes or primitives skipped, faces dropped.
    pub fn ensure_not_empty(&self, what: &str) -> Result<()> {
        const SHOWN: usize = 5;
        if self.polygon_count() == 0 {
            let mut why = if self.objects.is_empty() {
                format!("{what} has no objects")
            } else {
                format!(
                    "{what} has {} object(s) but no usable face",
                    self.objects.len()
                )
            };
            let warnings = self.report.warnings();
            if !warnings.is_empty() {
                why.push_str(" (loading warned: ");
                why.push_str(&warnings[..warnings.len().min(SHOWN)].join("; "));
                if warnings.len() > SHOWN {
                    why.push_str(&format!("; and {} more", warnings.len() - SHOWN));
                }
                why.push(')');
            }
            return Err(Error::EmptyScene(why));
        }
        Ok(())
    }

    /// The default camera for this scene: its own if it has one, else one framing
    /// its bounds.
    #[must_use]
    pub fn default_camera(&self, aspect: f64) -> Camera {
        self.camera
            .unwrap_or_else(|| Camera::framing(&self.bounds(), aspect, self.up(), 45.0))
    }

    /// [`Scene::default_camera`], checked: a scene with no camera of its own so close
    /// to [`MAX_COORDINATE`] that no eye within that range frames it (a triangle
    /// reaching 9e29) gets an error that says so, instead of a camera whose eye or
    /// planes are out of range, which [`Camera::validate`] would refuse without saying
    /// that no one gave that camera.
    pub fn automatic_camera(&self, aspect: f64) -> Result<Camera> {
        let camera = self.default_camera(aspect);
        match camera.validate() {
            Ok(()) => Ok(camera),
            Err(Error::InvalidCamera(e)) if self.camera.is_none() => {
                let b = self.bounds();
                Err(Error::InvalidCamera(format!(
                    "the automatic camera cannot frame the scene (bounds {:e}..{:e} on x, \
                     {:e}..{:e} on y, {:e}..{:e} on z): {e}; give a camera whose eye, target, \
                     near and far lie within {MAX_COORDINATE:e}",
                    b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
                )))
            }
            Err(e) => Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_span_objects_and_flags_are_detected() {
        let mut s = Scene::new();
        let cube = demo::box_mesh(DVec3::ZERO, DVec3::ONE);
        let a = s.add(ObjectDesc::new("a", cube.clone())).unwrap();
        let b = s
            .add(
                ObjectDesc::new("b", demo::grid_mesh(1., 1., 2, 2))
                    .with_transform(DMat4::from_scale(DVec3::new(-1., 1., 1.))),
            )
            .unwrap();
        assert_eq!((a, b), (0, 1));
        assert_eq!(s.face_count(), 6 + 4);
        assert_eq!(s.locate_face(5), Some((0, 5)));
        assert_eq!(s.locate_face(6), Some((1, 0)));
        assert_eq!(s.locate_face(10), None);
        assert!(s.objects()[0].closed && s.objects()[0].convex);
        assert!(!s.objects()[1].closed && s.objects()[1].mirrored);
    }

    #[test]
    fn bad_objects_are_refused_with_their_name() {
        let mut s = Scene::new();
        let e = s
            .add(
                ObjectDesc::new("flat", demo::box_mesh(DVec3::ZERO, DVec3::ONE))
                    .with_transform(DMat4::from_scale(DVec3::new(1., 0., 1.))),
            )
            .unwrap_err();
        assert!(e.to_string().contains("\"flat\""), "{e}");
        let mut m = DMat4::IDENTITY;
        m.w_axis.x = f64::NAN;
        let e = s
            .add(ObjectDesc::new("nan", demo::box_mesh(DVec3::ZERO, DVec3::ONE)).with_transform(m))
            .unwrap_err();
        assert!(e.to_string().contains("nan"), "{e}");
        assert!(matches!(
            s.ensure_not_empty("test"),
            Err(Error::EmptyScene(_))
        ));
    }
}
