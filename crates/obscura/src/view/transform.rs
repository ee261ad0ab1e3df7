//! The camera maths of a view: world -> eye -> clip -> screen, in one
//! [`ViewTransform`], and the [`ViewVertex`] it produces.

use glam::{DMat3, DMat4, DVec3, DVec4};

use crate::clip::outcode_homogeneous;
use crate::clip::sutherland_hodgman::{ClipEyeVertex, clip_polygon_homogeneous_masked};
use crate::cull::frustum::{Containment, classify_clip_points, classify_sphere, frustum_planes};
use crate::geom::Sphere;
use crate::scene::{Camera, Object, Projection, Viewport};

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
    pub fn eye_to_clip(&self, eye: DVec3) -> DVec4 {
        let c = self.projection * eye.extend(1.0);
        DVec4::new(c.x, c.y, self.near_z(c.w, -eye.z), c.w)
    }

    /// The clip `z` of a point of depth `depth` and clip `w` (see [`Self::eye_to_clip`]).
    #[inline(always)]
    #[must_use]
    pub fn near_z(&self, w: f64, depth: f64) -> f64 {
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
    pub fn world_to_clip(&self, p: DVec3) -> DVec4 {
        self.eye_to_clip(self.world_to_eye(p))
    }

    /// The pixel rectangle `(min x, min y, max x, max y)` (y down, not clipped to the
    /// image) that the corners of a world box project to; `None` when a corner is at
    /// or behind the eye plane (its projection bounds nothing).
    #[must_use]
    pub fn screen_box(&self, b: &crate::geom::Aabb) -> Option<(f64, f64, f64, f64)> {
        let mut r = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for c in b.corners() {
            let clip = self.world_to_clip(c);
            if !(clip.w > 0.0) {
                return None;
            }
            let p = self.clip_to_pixel(clip);
            r = (r.0.min(p.x), r.1.min(p.y), r.2.max(p.x), r.3.max(p.y));
        }
        Some(r)
    }

    /// The six planes of the view volume in eye space (see [`frustum_planes`]), for
    /// [`Self::object_containment`].
    #[must_use]
    pub fn eye_frustum_planes(&self) -> [DVec4; 6] {
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
    pub fn zq_of_depth(&self, depth: f64) -> f64 {
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

    /// The pixel position of a clip-space point in front of the eye (`w > 0`): divide by
    /// `w`, map `x` right and `y` down, as a [`crate::Frame`].
    #[inline]
    #[must_use]
    pub fn clip_to_pixel(&self, clip: DVec4) -> glam::DVec2 {
        glam::DVec2::new(
            (clip.x / clip.w + 1.0) * 0.5 * self.width,
            (1.0 - clip.y / clip.w) * 0.5 * self.height,
        )
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
    pub fn is_back_facing_eye(&self, normal: DVec3, point: DVec3) -> bool {
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
