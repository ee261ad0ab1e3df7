//! The scene as world-space triangles, and the watertight ray-triangle test every ray
//! caster shares (brute force, bounding volumes, BVH, grid).
//!
//! # Triangles
//! [`SceneTriangles`] applies each object's transform to its mesh and fan-triangulates
//! every (convex) polygon: polygon `p0 p1 ... pn` gives `(p0, pk, pk+1)`. All
//! triangles of a polygon carry its scene-wide polygon index, which gives the face id
//! (`first_face + polygon_face`), the object and the world-space normal used by the
//! back-face rule.
//!
//! # The intersection test
//! Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013.
//! The ray is made the `+z` axis of a sheared frame (`kz` = its dominant axis, the
//! other two chosen so that the winding is kept); the three vertices are translated by
//! the origin and sheared, and the 2D edge functions `U, V, W` of the ray's position
//! are evaluated. Two triangles sharing an edge compute the same products for it and
//! negate them exactly, so a ray can neither pass between them nor be refused by both:
//! the test is watertight in floating point, whatever the rounding. Everything is
//! `f64` (the paper falls back to double precision when single precision gives 0; here
//! the zero cases are resolved by the tie rule below instead).
//!
//! # Ties on edges
//! A ray exactly on an edge (`U`, `V` or `W` = 0) is accepted by the rule the
//! rasterizers use, the top-left rule of [`crate::raster`]: the edge and the ray span a
//! plane; with its normal `m` oriented towards the triangle, the edge counts as inside
//! when `m` points to screen `+x` (a *left* edge: `m · right > 0`), or when it is
//! horizontal on screen and `m` points down (`m · right = 0` and `m · up < 0`, a *top*
//! edge). The neighbour across the edge computes exactly `-m`, so exactly one of them
//! takes the ray; and where a pixel centre falls exactly on a projected edge, the same
//! polygon wins as in the z-buffer. With [`crate::raster::FillRule::Inclusive`]
//! ([`PrimaryRays::with_fill_rule`]) a ray on an edge hits, as the rasterizers then
//! cover every sample on an edge.
//!
//! - Complexity: O(T) to build for T triangles; the test is O(1), about 40 flops.
//! - Source: seed 000 "Αλγόριθμος Εκπομπής Ακτίνων" (`intersect_primitive_ray`), seed
//!   002 "Calcolo delle intersezioni".

use std::ops::Range;

use glam::DVec3;

use crate::cull::backface::{BackfaceMode, is_back_facing_parallel, is_back_facing_perspective};
use crate::geom::newell_normal;
use crate::scene::{Camera, ImageRays, Projection, Scene, Viewport};

/// The world-space triangles of a scene (fan triangulation of its polygons).
#[derive(Clone, Debug, Default)]
pub struct SceneTriangles {
    vertices: Vec<[DVec3; 3]>,
    polygon: Vec<u32>,
    faces: Vec<u32>,
    objects: Vec<u32>,
    normals: Vec<DVec3>,
    anchors: Vec<DVec3>,
    object_triangles: Vec<Range<u32>>,
}

impl SceneTriangles {
    /// The triangles of every object of the scene, in scene order.
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        let triangles = scene.triangle_count();
        let polygons = scene.polygon_count();
        let mut out = SceneTriangles {
            vertices: Vec::with_capacity(triangles),
            polygon: Vec::with_capacity(triangles),
            faces: Vec::with_capacity(polygons),
            objects: Vec::with_capacity(polygons),
            normals: Vec::with_capacity(polygons),
            anchors: Vec::with_capacity(polygons),
            object_triangles: Vec::with_capacity(scene.objects().len()),
        };
        let mut world: Vec<DVec3> = Vec::new();
        let mut pts: Vec<DVec3> = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            let first = out.vertices.len() as u32;
            o.world_positions_into(&mut world);
            for p in 0..o.mesh.polygon_count() {
                let poly = o.mesh.polygon(p);
                let index = out.faces.len() as u32;
                // The same normal as the pipeline's back-face test: the cross product
                // for triangles, Newell's for larger polygons; flipped by mirroring.
                let normal = if poly.len() == 3 {
                    let (a, b, c) = (
                        world[poly[0] as usize],
                        world[poly[1] as usize],
                        world[poly[2] as usize],
                    );
                    (b - a).cross(c - a)
                } else {
                    pts.clear();
                    pts.extend(poly.iter().map(|&i| world[i as usize]));
                    newell_normal(&pts)
                };
                out.faces.push(o.first_face + o.mesh.polygon_face(p));
                out.objects.push(k as u32);
                out.normals.push(if o.mirrored { -normal } else { normal });
                out.anchors.push(world[poly[0] as usize]);
                let a = world[poly[0] as usize];
                for w in poly[1..].windows(2) {
                    out.vertices
                        .push([a, world[w[0] as usize], world[w[1] as usize]]);
                    out.polygon.push(index);
                }
            }
            out.object_triangles.push(first..out.vertices.len() as u32);
        }
        out
    }

    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Whether there is no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Number of polygons.
    #[must_use]
    pub fn polygon_count(&self) -> usize {
        self.faces.len()
    }

    /// The vertices of every triangle (counter-clockwise as in the mesh).
    #[must_use]
    pub fn vertices(&self) -> &[[DVec3; 3]] {
        &self.vertices
    }

    /// The polygon of every triangle.
    #[must_use]
    pub fn triangle_polygons(&self) -> &[u32] {
        &self.polygon
    }

    /// The face id of every polygon.
    #[must_use]
    pub fn polygon_faces(&self) -> &[u32] {
        &self.faces
    }

    /// The object of every polygon.
    #[must_use]
    pub fn polygon_objects(&self) -> &[u32] {
        &self.objects
    }

    /// The triangles of each object.
    #[must_use]
    pub(crate) fn object_triangles(&self) -> &[Range<u32>] {
        &self.object_triangles
    }

    /// Which polygons a ray must ignore: per polygon, true when it belongs to an object
    /// whose back faces the mode culls and it faces away from the camera — the
    /// pipeline's rule (`cull::backface`): perspective `n · (eye - p0) <= 0`,
    /// orthographic `n · (-forward) <= 0`, edge-on counting as back.
    #[must_use]
    pub fn ignored_polygons(
        &self,
        scene: &Scene,
        camera: &Camera,
        mode: BackfaceMode,
    ) -> Vec<bool> {
        let culled: Vec<bool> = scene
            .objects()
            .iter()
            .map(|o| mode.applies_to(o.closed))
            .collect();
        let (_, _, forward) = camera.basis();
        let orthographic = matches!(camera.projection, Projection::Orthographic { .. });
        (0..self.faces.len())
            .map(|p| {
                culled[self.objects[p] as usize]
                    && if orthographic {
                        is_back_facing_parallel(self.normals[p], forward)
                    } else {
                        is_back_facing_perspective(self.normals[p], self.anchors[p], camera.eye)
                    }
            })
            .collect()
    }

    /// The box of all triangles.
    #[must_use]
    pub fn bounds(&self) -> crate::geom::Aabb {
        self.vertices
            .iter()
            .flatten()
            .fold(crate::geom::Aabb::EMPTY, |b, &p| b.with_point(p))
    }
}

/// The primary rays of a camera: one through each pixel centre, computed by the one
/// function [`Camera::ray`] calls too (so both give the same rays), with the camera's
/// basis and window computed once.
#[derive(Clone, Copy, Debug)]
pub struct PrimaryRays {
    rays: ImageRays,
    /// Near plane distance (the smallest accepted `t`).
    pub near: f64,
    /// Far plane distance (the largest accepted `t`).
    pub far: f64,
    /// Rays exactly on an edge hit the triangle whatever the edge
    /// ([`crate::raster::FillRule::Inclusive`]) instead of by the top-left rule.
    inclusive: bool,
}

impl PrimaryRays {
    /// The rays of a camera for a viewport.
    #[must_use]
    pub fn new(camera: &Camera, viewport: Viewport) -> Self {
        PrimaryRays {
            rays: ImageRays::new(camera, viewport),
            near: camera.near_limit(),
            far: camera.far,
            inclusive: false,
        }
    }

    /// These rays deciding rays exactly on an edge by `fill`, as the rasterizers do:
    /// the top-left rule (the default), or every edge inclusive.
    #[must_use]
    pub fn with_fill_rule(mut self, fill: crate::raster::FillRule) -> Self {
        self.inclusive = fill == crate::raster::FillRule::Inclusive;
        self
    }

    /// The ray through image point `(px, py)`: `(origin, direction)`.
    #[inline]
    #[must_use]
    pub fn ray(&self, px: f64, py: f64) -> (DVec3, DVec3) {
        self.ray_at(self.window_x(px), self.window_y(py))
    }

    /// What a caster needs to trace the ray through image point `(px, py)`, between the
    /// near plane and whatever `t_max` it is given, with these ignored polygons and
    /// face ids; `None` for a ray [`WatertightRay::new`] refuses.
    #[must_use]
    pub fn context<'a>(
        &self,
        px: f64,
        py: f64,
        ignored: &'a [bool],
        faces: &'a [u32],
    ) -> Option<HitContext<'a>> {
        let (origin, direction) = self.ray(px, py);
        Some(HitContext {
            ray: WatertightRay::new(origin, direction)?,
            ignored,
            faces,
            t_min: self.near,
            tie: self.tie_rule(),
        })
    }

    /// The window coordinate of image column `px` (`sx` of [`Camera::ray`]), so a
    /// caller can compute it once per column.
    #[inline]
    #[must_use]
    pub(crate) fn window_x(&self, px: f64) -> f64 {
        self.rays.window_x(px)
    }

    /// The window coordinate of image row `py` (`sy` of [`Camera::ray`]).
    #[inline]
    #[must_use]
    pub(crate) fn window_y(&self, py: f64) -> f64 {
        self.rays.window_y(py)
    }

    /// The ray through window point `(sx, sy)` (see [`PrimaryRays::window_x`]).
    #[inline]
    #[must_use]
    pub(crate) fn ray_at(&self, sx: f64, sy: f64) -> (DVec3, DVec3) {
        self.rays.ray_at(sx, sy)
    }

    /// The largest coordinate, in absolute value, of the rays' origins: the eye's for
    /// a perspective camera; for an orthographic one, whose rays start across the
    /// window on the eye plane, the eye's plus how far the window reaches from the
    /// view axis (its half extents, more when shifted; `right` and `up` are unit
    /// vectors).
    #[must_use]
    pub(crate) fn origin_magnitude(&self) -> f64 {
        let r = &self.rays;
        let eye = r.eye.abs().max_element();
        if r.orthographic {
            let (x, y) = r.window_reach();
            eye + x + y
        } else {
            eye
        }
    }

    /// The rule that decides rays exactly on an edge (see the module doc).
    #[must_use]
    pub fn tie_rule(&self) -> TieRule {
        let r = &self.rays;
        TieRule {
            inclusive: self.inclusive,
            orthographic: r.orthographic,
            eye: r.eye,
            forward: r.forward,
            right: r.right,
            up: r.up,
        }
    }
}

/// The screen-space top-left rule, expressed in world space for rays exactly on an
/// edge (see the module doc).
#[derive(Clone, Copy, Debug)]
pub struct TieRule {
    inclusive: bool,
    orthographic: bool,
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
}

impl TieRule {
    /// Whether a ray exactly on the edge `p`-`q` of a triangle whose third vertex is
    /// `r` counts as inside it.
    #[cold]
    #[must_use]
    pub(crate) fn accepts_edge(&self, p: DVec3, q: DVec3, r: DVec3) -> bool {
        let (m, side) = if self.orthographic {
            let m = (q - p).cross(self.forward);
            (m, m.dot(r - p))
        } else {
            let m = (p - self.eye).cross(q - self.eye);
            (m, m.dot(r - self.eye))
        };
        // A triangle seen edge-on (its plane through the eye, or along the view
        // direction) projects to a line and covers no sample, whatever the rule: the
        // rays in its plane meet it only by rounding. (Every edge inclusive once
        // accepted them, and an edge-on triangle showed as a line of pixels.)
        if side == 0.0 || !side.is_finite() {
            return false;
        }
        if self.inclusive {
            return true;
        }
        let m = if side < 0.0 { -m } else { m };
        let gx = m.dot(self.right);
        gx > 0.0 || (gx == 0.0 && -m.dot(self.up) > 0.0)
    }
}

/// The order of axes in the sheared frame of a ray: `Z` is the dominant axis of its
/// direction, `X` and `Y` the others, swapped when needed to keep the winding.
/// Implemented by six zero-sized types so the test is compiled once per order, with
/// no indexing at run time.
pub trait AxisOrder {
    /// The axis that becomes x.
    const X: usize;
    /// The axis that becomes y.
    const Y: usize;
    /// The dominant axis of the direction.
    const Z: usize;
}

macro_rules! axis_orders {
    ($($(#[$doc:meta])* $name:ident = ($x:expr, $y:expr, $z:expr);)*) => {
        $(
            $(#[$doc])*
            #[derive(Clone, Copy, Debug)]
            pub struct $name;
            impl AxisOrder for $name {
                const X: usize = $x;
                const Y: usize = $y;
                const Z: usize = $z;
            }
        )*
    };
}

axis_orders! {
    /// Dominant x, positive.
    OrderYzx = (1, 2, 0);
    /// Dominant x, negative.
    OrderZyx = (2, 1, 0);
    /// Dominant y, positive.
    OrderZxy = (2, 0, 1);
    /// Dominant y, negative.
    OrderXzy = (0, 2, 1);
    /// Dominant z, positive.
    OrderXyz = (0, 1, 2);
    /// Dominant z, negative.
    OrderYxz = (1, 0, 2);
}

/// Code to run with a ray's [`AxisOrder`] known at compile time.
pub trait WithAxisOrder {
    /// What it returns.
    type Output;
    /// Runs with the order `O`.
    fn run<O: AxisOrder>(self) -> Self::Output;
}

/// Runs `f` with the axis order of index `order` (see [`WatertightRay::order_index`];
/// 5 and above mean the last order).
#[inline]
pub(crate) fn dispatch_order<F: WithAxisOrder>(order: u8, f: F) -> F::Output {
    match order {
        0 => f.run::<OrderYzx>(),
        1 => f.run::<OrderZyx>(),
        2 => f.run::<OrderZxy>(),
        3 => f.run::<OrderXzy>(),
        4 => f.run::<OrderXyz>(),
        _ => f.run::<OrderYxz>(),
    }
}

/// A ray prepared for the watertight test.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    /// Origin.
    pub origin: DVec3,
    /// Direction (not necessarily unit).
    pub direction: DVec3,
    order: u8,
    shear: DVec3,
}

#[inline(always)]
fn axis(v: DVec3, k: usize) -> f64 {
    match k {
        0 => v.x,
        1 => v.y,
        _ => v.z,
    }
}

impl WatertightRay {
    /// Prepares a ray. `None` when the direction is zero or not finite.
    #[must_use]
    pub fn new(origin: DVec3, direction: DVec3) -> Option<Self> {
        if !(origin.is_finite() && direction.is_finite()) || direction == DVec3::ZERO {
            return None;
        }
        let a = direction.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let dz = axis(direction, kz);
        let order = 2 * kz as u8 + u8::from(dz < 0.0);
        let (kx, ky) = match order {
            0 => (1, 2),
            1 => (2, 1),
            2 => (2, 0),
            3 => (0, 2),
            4 => (0, 1),
            _ => (1, 0),
        };
        Some(WatertightRay {
            origin,
            direction,
            order,
            shear: DVec3::new(axis(direction, kx) / dz, axis(direction, ky) / dz, 1.0 / dz),
        })
    }

    /// Which of the six axis orders this ray has (0..6, the index `dispatch` uses):
    /// rays with equal orders can be tested together by code compiled for one order.
    #[inline]
    #[must_use]
    pub fn order_index(&self) -> u8 {
        self.order
    }

    /// The shear of the ray's frame: `(d_x / d_z, d_y / d_z, 1 / d_z)` in its axis
    /// order (what [`WatertightRay::intersect`] computes with).
    #[inline]
    #[must_use]
    pub(crate) fn shear(&self) -> DVec3 {
        self.shear
    }

    /// Runs `f` with this ray's axis order as a type.
    #[inline]
    pub fn dispatch<F: WithAxisOrder>(&self, f: F) -> F::Output {
        dispatch_order(self.order, f)
    }

    /// The parameter `t` at which the ray hits the triangle, if it does with
    /// `t_min <= t <= t_max`; edges by `tie` (see the module doc). `O` must be this
    /// ray's order (use [`WatertightRay::dispatch`], or [`WatertightRay::intersect_any`]).
    #[inline(always)]
    #[must_use]
    pub fn intersect<O: AxisOrder>(
        &self,
        tri: &[DVec3; 3],
        t_min: f64,
        t_max: f64,
        tie: &TieRule,
    ) -> Option<f64> {
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let a = tri[0] - self.origin;
        let b = tri[1] - self.origin;
        let c = tri[2] - self.origin;
        let (az, bz, cz) = (axis(a, O::Z), axis(b, O::Z), axis(c, O::Z));
        let ax = axis(a, O::X) - sx * az;
        let ay = axis(a, O::Y) - sy * az;
        let bx = axis(b, O::X) - sx * bz;
        let by = axis(b, O::Y) - sy * bz;
        let cx = axis(c, O::X) - sx * cz;
        let cy = axis(c, O::Y) - sy * cz;
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        // Non-short-circuit `|` and `&`: one unpredictable branch instead of six.
        if ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0)) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || det.is_nan() {
            return None;
        }
        if (u == 0.0 || v == 0.0 || w == 0.0) && !Self::edges_accepted(tri, u, v, w, tie) {
            return None;
        }
        let t = (u * (sz * az) + v * (sz * bz) + w * (sz * cz)) / det;
        (t >= t_min && t <= t_max).then_some(t)
    }

    #[cold]
    #[inline(never)]
    fn edges_accepted(tri: &[DVec3; 3], u: f64, v: f64, w: f64, tie: &TieRule) -> bool {
        (u != 0.0 || tie.accepts_edge(tri[1], tri[2], tri[0]))
            && (v != 0.0 || tie.accepts_edge(tri[2], tri[0], tri[1]))
            && (w != 0.0 || tie.accepts_edge(tri[0], tri[1], tri[2]))
    }

    /// [`WatertightRay::intersect`] with the order dispatched at run time.
    #[must_use]
    pub fn intersect_any(
        &self,
        tri: &[DVec3; 3],
        t_min: f64,
        t_max: f64,
        tie: &TieRule,
    ) -> Option<f64> {
        struct One<'a> {
            ray: &'a WatertightRay,
            tri: &'a [DVec3; 3],
            t_min: f64,
            t_max: f64,
            tie: &'a TieRule,
        }
        impl WithAxisOrder for One<'_> {
            type Output = Option<f64>;
            fn run<O: AxisOrder>(self) -> Option<f64> {
                self.ray
                    .intersect::<O>(self.tri, self.t_min, self.t_max, self.tie)
            }
        }
        self.dispatch(One {
            ray: self,
            tri,
            t_min,
            t_max,
            tie,
        })
    }
}

/// The nearest hit so far: nearer wins, on an exact tie the lower face id.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestHit {
    /// Its parameter (the far limit while there is no hit).
    pub t: f64,
    /// Its face id ([`crate::BACKGROUND`] while there is no hit).
    pub face: u32,
}

impl ClosestHit {
    /// No hit yet; hits up to `t_max` (inclusive) will be taken.
    #[must_use]
    pub fn new(t_max: f64) -> Self {
        ClosestHit {
            t: t_max,
            face: crate::BACKGROUND,
        }
    }

    /// Whether something was hit.
    #[must_use]
    pub fn is_hit(&self) -> bool {
        self.face != crate::BACKGROUND
    }

    /// Takes the hit if it is nearer, or as near with a lower face id.
    #[inline]
    pub(crate) fn offer(&mut self, t: f64, face: u32) {
        if t < self.t || (t == self.t && face < self.face) {
            self.t = t;
            self.face = face;
        }
    }
}

/// What a ray caster needs to test one triangle: the ray, the polygons to ignore
/// (back faces), face ids, the near limit and the tie rule.
#[derive(Clone, Copy, Debug)]
pub struct HitContext<'a> {
    /// The ray.
    pub ray: WatertightRay,
    /// Per polygon: whether hits on it are ignored (back faces).
    pub ignored: &'a [bool],
    /// Per polygon: its face id.
    pub faces: &'a [u32],
    /// The smallest accepted parameter (the near plane).
    pub t_min: f64,
    /// Rays exactly on edges.
    pub tie: TieRule,
}

impl HitContext<'_> {
    /// Tests one triangle of polygon `polygon` against the ray and offers the hit to
    /// `closest` (hits beyond `t_max`, which may be nearer than `closest.t`, are not
    /// taken). Returns whether the exact test ran (false for ignored polygons).
    #[inline(always)]
    pub fn test<O: AxisOrder>(
        &self,
        tri: &[DVec3; 3],
        polygon: u32,
        t_max: f64,
        closest: &mut ClosestHit,
    ) -> bool {
        if self.ignored[polygon as usize] {
            return false;
        }
        if let Some(t) = self
            .ray
            .intersect::<O>(tri, self.t_min, t_max.min(closest.t), &self.tie)
        {
            closest.offer(t, self.faces[polygon as usize]);
        }
        true
    }

    /// The nearest hit among all of `triangles` up to `t_max` (brute force), adding the
    /// exact tests made to `tests`.
    #[inline(always)]
    pub(crate) fn closest_of_all<O: AxisOrder>(
        &self,
        triangles: &SceneTriangles,
        t_max: f64,
        tests: &mut u64,
    ) -> ClosestHit {
        let mut closest = ClosestHit::new(t_max);
        for (tri, &poly) in triangles
            .vertices()
            .iter()
            .zip(triangles.triangle_polygons())
        {
            *tests += u64::from(self.test::<O>(tri, poly, t_max, &mut closest));
        }
        closest
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn tie() -> TieRule {
        PrimaryRays::new(
            &Camera::perspective(DVec3::Z * 5.0, DVec3::ZERO, DVec3::Y, 60.0, 0.1, 100.0),
            Viewport::new(10, 10).unwrap(),
        )
        .tie_rule()
    }

    #[test]
    fn primary_rays_equal_camera_rays_bit_for_bit() {
        let vp = Viewport::new(37, 23).unwrap();
        for cam in [
            Camera::perspective(
                DVec3::new(1.0, 2.0, 3.0),
                DVec3::new(-0.3, 0.1, 0.0),
                DVec3::Y,
                50.0,
                0.1,
                100.0,
            ),
            Camera::orthographic(
                DVec3::new(1.0, 2.0, 3.0),
                DVec3::ZERO,
                DVec3::Z,
                4.0,
                0.1,
                100.0,
            ),
        ] {
            let rays = PrimaryRays::new(&cam, vp);
            for j in 0..vp.height {
                for i in 0..vp.width {
                    let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
                    let r = cam.ray(vp, px, py);
                    assert_eq!(rays.ray(px, py), (r.origin, r.direction));
                }
            }
        }
    }

    #[test]
    fn hits_a_triangle_at_the_analytic_distance() {
        let tri = [
            DVec3::new(-1.0, -1.0, -2.0),
            DVec3::new(1.0, -1.0, -2.0),
            DVec3::new(0.0, 1.0, -2.0),
        ];
        let ray =
            WatertightRay::new(DVec3::new(0.1, 0.0, 3.0), DVec3::new(0.0, 0.0, -2.0)).unwrap();
        let t = ray.intersect_any(&tri, 0.0, 10.0, &tie()).unwrap();
        assert!((t - 2.5).abs() < 1e-15, "{t}");
        // Both windings are hit (culling is decided per polygon, not here).
        let back = [tri[0], tri[2], tri[1]];
        assert_eq!(ray.intersect_any(&back, 0.0, 10.0, &tie()), Some(t));
        // Outside the range, or beside the triangle: no hit.
        assert!(ray.intersect_any(&tri, 0.0, 2.4, &tie()).is_none());
        assert!(ray.intersect_any(&tri, 2.6, 10.0, &tie()).is_none());
        let beside = WatertightRay::new(DVec3::new(1.0, 0.5, 3.0), -DVec3::Z).unwrap();
        assert!(beside.intersect_any(&tri, 0.0, 10.0, &tie()).is_none());
        // Parallel to the plane: no hit.
        let parallel = WatertightRay::new(DVec3::new(0.0, 0.0, -2.0), DVec3::X).unwrap();
        assert!(parallel.intersect_any(&tri, -10.0, 10.0, &tie()).is_none());
        assert!(WatertightRay::new(DVec3::ZERO, DVec3::ZERO).is_none());
        assert!(WatertightRay::new(DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 1.0)).is_none());
    }

    /// Random fans of triangles around a centre (a closed disc with shared edges): every
    /// ray through the disc must hit exactly one triangle, never zero or two, with every
    /// axis order and with rays aimed exactly at shared vertices and edges.
    #[test]
    fn watertight_on_shared_edges_and_vertices() {
        let mut rng = SplitMix64(99);
        let tie = tie();
        for case in 0..60 {
            let centre = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            let n = 4 + case % 9;
            let (e1, e2) = {
                let a = DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                )
                .normalize();
                let b = a.any_orthonormal_vector();
                (a, a.cross(b))
            };
            let rim: Vec<DVec3> = (0..n)
                .map(|k| {
                    let ang = std::f64::consts::TAU * (k as f64 + rng.range(-0.2, 0.2)) / n as f64;
                    centre + (e1 * ang.cos() + e2 * ang.sin()) * rng.range(0.5, 1.5)
                })
                .collect();
            let tris: Vec<[DVec3; 3]> =
                (0..n).map(|k| [centre, rim[k], rim[(k + 1) % n]]).collect();
            let normal = e1.cross(e2);
            let eye = centre + normal * rng.range(1.0, 4.0) + e1 * rng.range(-0.5, 0.5);
            // Targets: the centre, every rim vertex's midpoint with the centre (on a
            // shared edge), and random points well inside the disc (n >= 4 and small
            // angular jitter keep the centre inside the rim polygon, so the fan covers
            // a disc of radius > 0.1 around it).
            let mut targets: Vec<DVec3> = vec![centre];
            targets.extend(rim.iter().map(|&r| centre + (r - centre) * 0.5));
            targets.extend(
                (0..40)
                    .map(|_| centre + (e1 * rng.range(-0.07, 0.07) + e2 * rng.range(-0.07, 0.07))),
            );
            for target in targets {
                let ray = WatertightRay::new(eye, target - eye).unwrap();
                let hits = tris
                    .iter()
                    .filter(|t| ray.intersect_any(t, 0.0, 10.0, &tie).is_some())
                    .count();
                assert_eq!(hits, 1, "case {case}: {hits} hits at {target:?}");
            }
        }
    }

    #[test]
    fn exact_edge_hits_follow_the_top_left_rule() {
        // Camera on +z looking at the origin, right = +x, up = +y. Two triangles share
        // the vertical edge x = 0: the one on the right (interior at +x) owns it (its
        // edge is a left edge), the one on the left does not.
        let cam = Camera::perspective(DVec3::Z * 4.0, DVec3::ZERO, DVec3::Y, 60.0, 0.1, 100.0);
        let rays = PrimaryRays::new(&cam, Viewport::new(10, 10).unwrap());
        let tie = rays.tie_rule();
        let right = [
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let left = [
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, -1.0, 0.0),
        ];
        let ray = WatertightRay::new(DVec3::new(0.0, 0.25, 4.0), -DVec3::Z).unwrap();
        assert!(ray.intersect_any(&right, 0.0, 10.0, &tie).is_some());
        assert!(ray.intersect_any(&left, 0.0, 10.0, &tie).is_none());
        // A horizontal edge y = 0: the triangle below it (interior at -y, screen down)
        // owns it (a top edge).
        let below = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
        ];
        let above = [
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(-1.0, 0.0, 0.0),
        ];
        let ray = WatertightRay::new(DVec3::new(0.25, 0.0, 4.0), -DVec3::Z).unwrap();
        assert!(ray.intersect_any(&below, 0.0, 10.0, &tie).is_some());
        assert!(ray.intersect_any(&above, 0.0, 10.0, &tie).is_none());
    }

    #[test]
    fn closest_hit_prefers_nearer_then_lower_id() {
        let mut c = ClosestHit::new(10.0);
        assert!(!c.is_hit());
        c.offer(5.0, 7);
        c.offer(5.0, 9);
        assert_eq!((c.t, c.face), (5.0, 7));
        c.offer(5.0, 3);
        assert_eq!((c.t, c.face), (5.0, 3));
        c.offer(4.0, 8);
        assert_eq!((c.t, c.face), (4.0, 8));
        c.offer(11.0, 0);
        assert_eq!(c.face, 8);
    }

    #[test]
    fn scene_triangles_fan_polygons_and_cull_like_the_pipeline() {
        let scene = crate::scene::demo::cube();
        let tris = SceneTriangles::new(&scene);
        assert_eq!(tris.len(), 12);
        assert_eq!(tris.polygon_count(), 6);
        assert_eq!(tris.polygon_faces(), &[0, 1, 2, 3, 4, 5]);
        let vp = Viewport::new(64, 48).unwrap();
        let cam = scene.default_camera(vp.aspect());
        let ignored = tris.ignored_polygons(&scene, &cam, BackfaceMode::Closed);
        // A cube seen from a corner shows three faces (the pipeline's doc example).
        assert_eq!(ignored.iter().filter(|&&b| !b).count(), 3);
        let view = crate::view::prepare(&scene, &cam, vp, &crate::view::PrepareOptions::default())
            .unwrap();
        let shown: Vec<u32> = view.polygons().map(|p| p.face).collect();
        let front: Vec<u32> = (0..6).filter(|&p| !ignored[p as usize]).collect();
        assert_eq!(shown, front);
        assert!(
            tris.ignored_polygons(&scene, &cam, BackfaceMode::Off)
                .iter()
                .all(|&b| !b)
        );
    }
}
