//! Cameras (look-at, perspective or orthographic) and viewports.
//!
//! Conventions (see `docs/ARCHITECTURE.md`): right-handed world; the camera looks down
//! `-z` in eye space; OpenGL clip space `-w <= x, y, z <= w`; `gluLookAt` and
//! `gluPerspective` semantics (vertical field of view in degrees).
//!
//! A camera's [`Lens`] moves its image window off the view axis (a lens shift: the
//! off-centre frustum of OpenGL's `glFrustum` and `glOrtho`, the principal point of a
//! pinhole camera away from the image centre) and gives its pixels an aspect ratio
//! (unequal focal lengths `fx != fy`). The default lens is centred with square pixels,
//! and every computation then gives the bits it gave before lenses existed.

use glam::{DMat4, DVec2, DVec3, DVec4};

use crate::geom::Aabb;
use crate::{Error, Result};

/// How the eye space is projected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with this vertical field of view in degrees, in (0, 180).
    Perspective {
        /// Vertical field of view, degrees.
        fov_y_degrees: f64,
    },
    /// Parallel projection showing this height of the world (the width follows the
    /// viewport's aspect ratio).
    Orthographic {
        /// Visible height in world units.
        height: f64,
    },
}

/// Where a camera's image window lies relative to its view axis, and the shape of its
/// pixels.
///
/// The window of a centred camera spans `[-w, w] x [-h, h]`: at unit depth for a
/// perspective camera (`h = tan(fov_y / 2)`), in world units for an orthographic one
/// (`h = height / 2`), with `w = h * aspect * pixel_aspect` for a viewport's `aspect =
/// width / height`. A shift moves the whole window, in units of its own width and
/// height: it spans `[(2 sx - 1) w, (2 sx + 1) w] x [(2 sy - 1) h, (2 sy + 1) h]`. The
/// view direction, the eye and the depths do not change; what the window shows moves.
///
/// # Use cases
/// - Architectural views (a shift lens): shift up to show a tall building's top
///   without tilting the camera, so its verticals stay parallel.
/// - Pinhole cameras whose principal point `(cx, cy)` is off the image centre and whose
///   focal lengths differ ([`Camera::from_intrinsics`] sets both from `fx, fy, cx, cy`).
/// - Tiles of a larger picture: the camera of a sub-window of a view is the same camera
///   with a narrower field of view and a shift, and renders exactly that part of it.
/// - Asymmetric projection matrices (`glFrustum`, `glOrtho` with `l != -r`, off-axis
///   stereo): [`Camera::from_matrices`] reads them into a lens.
///
/// ```
/// use glam::{DVec2, DVec3};
/// use obscura::{Camera, Lens, Viewport};
/// // A window moved a quarter of its width to the right: the view axis, which the
/// // centred camera sees at the image centre, is seen at x = 1/4 of the width.
/// let mut cam = Camera::perspective(DVec3::Z * 5.0, DVec3::ZERO, DVec3::Y, 60.0, 1.0, 10.0);
/// cam.lens = Lens { shift: DVec2::new(0.25, 0.0), ..Lens::CENTRED };
/// let vp = Viewport::new(400, 300)?;
/// let axis = cam.ray(vp, 100.0, 150.0);
/// assert!((axis.direction - DVec3::NEG_Z).length() < 1e-12);
/// # Ok::<(), obscura::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// The shift of the image window, in units of its width (`x`, right) and height
    /// (`y`, up): `(0.5, 0)` moves the window right by half its width, so that the
    /// view axis is seen at the left edge. Finite; zero for a centred camera.
    pub shift: DVec2,
    /// The width of a pixel over its height, in the world seen (a pinhole camera's
    /// `fy / fx`): the window is `pixel_aspect` times wider than square pixels make
    /// it. Positive and finite; 1 for square pixels.
    pub pixel_aspect: f64,
}

impl Lens {
    /// A centred window with square pixels: what [`Camera::perspective`] and
    /// [`Camera::orthographic`] give.
    pub const CENTRED: Lens = Lens {
        shift: DVec2::ZERO,
        pixel_aspect: 1.0,
    };

    /// The centre of the window in normalized device coordinates, `2 shift` (`-0` made
    /// `+0`, so that a zero shift changes no bit of any coordinate).
    #[inline]
    #[must_use]
    pub(crate) fn ndc_centre(&self) -> DVec2 {
        self.shift * 2.0 + DVec2::ZERO
    }
}

impl Default for Lens {
    fn default() -> Self {
        Lens::CENTRED
    }
}

/// The allowance of [`Camera::near_limit`], relative to `near`.
pub const NEAR_ALLOWANCE: f64 = 1.0 / (1u64 << 40) as f64;

/// A look-at camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Where the eye is.
    pub eye: DVec3,
    /// The point looked at.
    pub target: DVec3,
    /// The up direction (need not be orthogonal to the view direction).
    pub up: DVec3,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Distance of the near clipping plane along the view axis (> 0 for perspective).
    pub near: f64,
    /// Distance of the far clipping plane (> near).
    pub far: f64,
    /// Where the image window lies relative to the view axis, and the pixels' aspect
    /// ratio: [`Lens::CENTRED`] unless set.
    pub lens: Lens,
}

/// A ray from a camera through a point of the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (the eye, or for orthographic cameras a point of the eye plane).
    pub origin: DVec3,
    /// The direction; for perspective rays scaled so that `t` is the eye-space depth
    /// (`direction · forward = 1`), for orthographic rays the unit forward vector.
    pub direction: DVec3,
}

/// The rays of one camera through the points of one viewport's image, with the
/// camera's basis and window computed once: the one place a camera ray is computed
/// ([`Camera::ray`] and the ray casters' [`PrimaryRays`](crate::accel::triangles::PrimaryRays)
/// both call it, so their rays are the same bit for bit).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ImageRays {
    pub(crate) right: DVec3,
    pub(crate) up: DVec3,
    pub(crate) forward: DVec3,
    pub(crate) eye: DVec3,
    pub(crate) half_width: f64,
    pub(crate) half_height: f64,
    /// The window's centre in units of its half extents ([`Lens::ndc_centre`]).
    centre: DVec2,
    width: f64,
    height: f64,
    pub(crate) orthographic: bool,
}

impl ImageRays {
    /// The rays of `camera` for `viewport`.
    pub(crate) fn new(camera: &Camera, viewport: Viewport) -> Self {
        let (right, up, forward) = camera.basis();
        let (half_width, half_height) = camera.half_extents(viewport.aspect());
        ImageRays {
            right,
            up,
            forward,
            eye: camera.eye,
            half_width,
            half_height,
            centre: camera.lens.ndc_centre(),
            width: f64::from(viewport.width),
            height: f64::from(viewport.height),
            orthographic: matches!(camera.projection, Projection::Orthographic { .. }),
        }
    }

    /// The window coordinate of image column `px`: `-half_width` at the left edge,
    /// `half_width` at the right, both moved by the lens's shift. (A zero shift adds
    /// `+0` to `2 px / width - 1`, which is never `-0`: the same bits as without it.)
    #[inline]
    pub(crate) fn window_x(&self, px: f64) -> f64 {
        (2.0 * px / self.width - 1.0 + self.centre.x) * self.half_width
    }

    /// The window coordinate of image row `py`: `half_height` at the top (row 0),
    /// `-half_height` at the bottom, both moved by the lens's shift.
    #[inline]
    pub(crate) fn window_y(&self, py: f64) -> f64 {
        (1.0 - 2.0 * py / self.height + self.centre.y) * self.half_height
    }

    /// The largest absolute window coordinates `(x, y)` of the image: the half extents
    /// for a centred window, more for a shifted one.
    #[must_use]
    pub(crate) fn window_reach(&self) -> (f64, f64) {
        (
            (self.centre.x.abs() + 1.0) * self.half_width.abs(),
            (self.centre.y.abs() + 1.0) * self.half_height.abs(),
        )
    }

    /// The ray `(origin, direction)` through window point `(sx, sy)`: from the eye
    /// through the window at unit depth (perspective), or from the window point on the
    /// eye plane along the view axis (orthographic).
    #[inline]
    pub(crate) fn ray_at(&self, sx: f64, sy: f64) -> (DVec3, DVec3) {
        if self.orthographic {
            (self.eye + self.right * sx + self.up * sy, self.forward)
        } else {
            (self.eye, self.forward + self.right * sx + self.up * sy)
        }
    }
}

impl Camera {
    /// The smallest eye-space depth every algorithm keeps: `near` less `2^-40` of it.
    /// A polygon lying on the near plane has depths within a few units in the last
    /// place of `near` once rotated into eye space (or, for the ray casters, once its
    /// ray parameter is computed), on either side; this allowance keeps all of it in
    /// every algorithm. Without it, the pipeline kept or dropped such a polygon whole by
    /// the rounding of its clip coordinates (a quad at depth `near` seen head-on was
    /// dropped for `near` 0.5 and kept for 0.3), and the ray casters kept some of its
    /// pixels.
    #[inline]
    #[must_use]
    pub fn near_limit(&self) -> f64 {
        self.near - self.near.abs() * NEAR_ALLOWANCE
    }

    /// A perspective camera.
    #[must_use]
    pub fn perspective(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        fov_y_degrees: f64,
        near: f64,
        far: f64,
    ) -> Self {
        Camera {
            eye,
            target,
            up,
            projection: Projection::Perspective { fov_y_degrees },
            near,
            far,
            lens: Lens::CENTRED,
        }
    }

    /// An orthographic camera.
    #[must_use]
    pub fn orthographic(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        height: f64,
        near: f64,
        far: f64,
    ) -> Self {
        Camera {
            eye,
            target,
            up,
            projection: Projection::Orthographic { height },
            near,
            far,
            lens: Lens::CENTRED,
        }
    }

    /// The smallest angle a pixel of a perspective view may span, in radians
    /// (`64 f64::EPSILON`, about `1.4e-14`; see [`Camera::validate_for`]). A direction
    /// from the eye is resolved to about `f64::EPSILON` radians at best (the rounding of
    /// `point - eye`), whatever the scene. Views whose pixels span about that (a field
    /// of view of `3e-13` degrees over 64 rows) made ray casting and depth sort
    /// disagree with the z-buffer; with pixels of `1.2 eps` (`1e-12` degrees over 64
    /// rows) they still agreed.
    pub const MIN_PIXEL_ANGLE: f64 = 64.0 * f64::EPSILON;

    /// Checks that the camera can produce an image: finite eye, target and up, a view
    /// direction, an up vector not along it, `near < far`, a field of view in (0, 180)
    /// degrees and `near > 0` (perspective) or a positive height (orthographic). Every
    /// position, distance and height must lie within [`super::MAX_COORDINATE`], and a
    /// perspective camera's `far / near` at most that too: its depth keys `near /
    /// depth` are stored in single precision.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidCamera(m));
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad(format!(
                "eye {:?}, target {:?} and up {:?} must be finite",
                self.eye.to_array(),
                self.target.to_array(),
                self.up.to_array()
            ));
        }
        let limit = super::MAX_COORDINATE;
        if self.eye.abs().max_element() > limit || self.target.abs().max_element() > limit {
            return bad(format!(
                "eye {:?} or target {:?} is beyond the largest coordinate accepted, {limit:e}",
                self.eye.to_array(),
                self.target.to_array()
            ));
        }
        let dir = self.target - self.eye;
        // A few units in the last place of the eye's coordinates: a camera framing a
        // small scene far from the origin (an object at 1e13) still has a direction.
        let scale = self
            .eye
            .abs()
            .max_element()
            .max(self.target.abs().max_element());
        if dir.length() <= 8.0 * f64::EPSILON * scale {
            return bad("the eye is on the target: no view direction".into());
        }
        // The up vector is a direction: its length does not matter (scaled by its
        // largest component, neither 1e-10 nor 1e300 is a problem).
        let up_scale = self.up.abs().max_element();
        if up_scale == 0.0 {
            return bad("the up vector is zero: it must give the image's up direction".into());
        }
        let up = (self.up / up_scale).normalize();
        if dir.normalize().cross(up).length() < 1e-9 {
            return bad(format!(
                "the up vector {:?} is parallel to the view direction {:?} (looking straight \
                 along it): choose another up direction",
                self.up.to_array(),
                dir.normalize().to_array()
            ));
        }
        if !(self.near.is_finite() && self.far.is_finite() && self.far > self.near) {
            return bad(format!(
                "need near < far, both finite (near {:e}, far {:e})",
                self.near, self.far
            ));
        }
        if self.near.abs() > limit || self.far.abs() > limit {
            return bad(format!(
                "near {:e} or far {:e} is beyond the largest distance accepted, {limit:e}",
                self.near, self.far
            ));
        }
        let lens = &self.lens;
        if !(lens.shift.is_finite() && lens.pixel_aspect.is_finite() && lens.pixel_aspect > 0.0) {
            return bad(format!(
                "lens shift {:?} must be finite and pixel aspect {:e} positive and finite",
                lens.shift.to_array(),
                lens.pixel_aspect
            ));
        }
        match self.projection {
            Projection::Perspective { fov_y_degrees } => {
                if !(fov_y_degrees > 0.0 && fov_y_degrees < 180.0) {
                    return bad(format!(
                        "field of view {fov_y_degrees} degrees is not in (0, 180)"
                    ));
                }
                if !(self.near > 0.0) {
                    return bad(format!(
                        "a perspective camera needs near > 0 (near {})",
                        self.near
                    ));
                }
                // Depth keys `near / depth` are stored as `f32`: the farthest one,
                // `near / far`, must stay a normal single-precision number.
                if self.near < self.far / limit {
                    return bad(format!(
                        "near {:e} is too small for far {:e}: far / near must be at most \
                         {limit:e} (depth keys near / depth are stored in single precision)",
                        self.near, self.far
                    ));
                }
            }
            Projection::Orthographic { height } => {
                if !(height > 0.0 && height.is_finite()) {
                    return bad(format!("orthographic height {height:e} must be positive"));
                }
                if height > limit {
                    return bad(format!(
                        "orthographic height {height:e} is beyond the largest distance \
                         accepted, {limit:e}"
                    ));
                }
            }
        }
        Ok(())
    }

    /// [`Camera::validate`], and for a perspective camera, that a pixel of `viewport`
    /// spans at least [`Camera::MIN_PIXEL_ANGLE`] (a field of view of at least about
    /// `5e-11` degrees for 64 rows, `8e-9` for 10,000).
    ///
    /// ```
    /// use obscura::{Camera, Viewport};
    /// use glam::DVec3;
    /// let narrow = Camera::perspective(DVec3::Z * 5.0, DVec3::ZERO, DVec3::Y, 1e-13, 1.0, 10.0);
    /// assert!(narrow.validate().is_ok());
    /// assert!(narrow.validate_for(Viewport::new(64, 64).unwrap()).is_err());
    /// ```
    ///
    /// A camera with a shifted window or non-square pixels (see [`Lens`]) must also keep
    /// its window within [`super::MAX_COORDINATE`] (at unit depth for a perspective
    /// camera, in world units for an orthographic one), and, for a perspective camera,
    /// its pixels at the window's farthest edge (where a pixel spans the smallest
    /// angle, `pixel / (1 + edge^2)` radians) at least [`Camera::MIN_PIXEL_ANGLE`],
    /// across and down.
    pub fn validate_for(&self, viewport: Viewport) -> Result<()> {
        self.validate()?;
        if self.lens != Lens::CENTRED {
            self.validate_lens(viewport)?;
        }
        if let Projection::Perspective { fov_y_degrees } = self.projection {
            let pixel = fov_y_degrees.to_radians() / f64::from(viewport.height.max(1));
            if pixel < Self::MIN_PIXEL_ANGLE {
                return Err(Error::InvalidCamera(format!(
                    "field of view {fov_y_degrees:e} degrees over {} rows: a pixel spans \
                     {pixel:.1e} radians, below the smallest accepted, {:.1e} (directions \
                     from the eye are not resolved that finely in double precision)",
                    viewport.height,
                    Self::MIN_PIXEL_ANGLE
                )));
            }
        }
        Ok(())
    }

    /// The checks of [`Camera::validate_for`] that only a shifted window or non-square
    /// pixels need.
    fn validate_lens(&self, viewport: Viewport) -> Result<()> {
        let rays = ImageRays::new(self, viewport);
        let (reach_x, reach_y) = rays.window_reach();
        let limit = super::MAX_COORDINATE;
        let lens = format!(
            "lens shift {:?} and pixel aspect {:e}",
            self.lens.shift.to_array(),
            self.lens.pixel_aspect
        );
        if !(reach_x <= limit && reach_y <= limit) {
            return Err(Error::InvalidCamera(format!(
                "{lens}: the image window reaches {:e} off the view axis, beyond the \
                 largest accepted, {limit:e}",
                reach_x.max(reach_y)
            )));
        }
        if let Projection::Perspective { .. } = self.projection {
            let sides = [
                ("across", rays.half_width, reach_x, viewport.width),
                ("down", rays.half_height, reach_y, viewport.height),
            ];
            for (side, half, reach, count) in sides {
                let pixel = 2.0 * half / f64::from(count.max(1));
                let angle = pixel / reach.mul_add(reach, 1.0);
                if !(angle >= Self::MIN_PIXEL_ANGLE) {
                    return Err(Error::InvalidCamera(format!(
                        "{lens}: a pixel at the window's edge spans {angle:.1e} radians \
                         {side}, below the smallest accepted, {:.1e} (directions from the \
                         eye are not resolved that finely in double precision)",
                        Self::MIN_PIXEL_ANGLE
                    )));
                }
            }
        }
        Ok(())
    }

    /// Refuses an orthographic window whose pixels are narrower than the rounding of
    /// the coordinates they are computed from: `4 eps` of `magnitude`, the largest
    /// absolute coordinate of the eye and of the scene (see [`crate::view::prepare`],
    /// which calls this). A window 1e-20 high over a unit cube drew only a quarter of
    /// the face that fills it, and one 1e-14 high seen from 10 units over 4 rows (one
    /// `eps` of the coordinates a pixel) made depth sort draw nothing. Perspective views
    /// are checked by angle instead ([`Camera::validate_for`]).
    pub fn validate_window(&self, viewport: Viewport, magnitude: f64) -> Result<()> {
        if let Projection::Orthographic { height } = self.projection {
            // Across, a pixel is `pixel_aspect` times as wide (1 by default, so the
            // `min` changes nothing then); a shifted window's rays start as far from
            // the eye as the window reaches.
            let pixel = height / f64::from(viewport.height.max(1));
            let pixel = pixel.min(pixel * self.lens.pixel_aspect);
            let magnitude = magnitude.max(self.eye.abs().max_element());
            let magnitude = if self.lens == Lens::CENTRED {
                magnitude
            } else {
                let (x, y) = ImageRays::new(self, viewport).window_reach();
                magnitude.max(self.eye.abs().max_element() + x.max(y))
            };
            let floor = 4.0 * f64::EPSILON * magnitude;
            if pixel < floor {
                return Err(Error::InvalidCamera(format!(
                    "orthographic height {height:e} over {} rows: a pixel spans {pixel:.1e}, \
                     below what coordinates as large as {magnitude:.1e} resolve in double \
                     precision ({floor:.1e}); widen the view or move the scene nearer the \
                     origin",
                    viewport.height,
                )));
            }
        }
        Ok(())
    }

    /// The camera's orthonormal basis `(right, up, forward)` in world space.
    #[must_use]
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let f = (self.target - self.eye).normalize();
        // An up vector of extreme length (1e300 squares to infinity) is rescaled first;
        // others are used as given.
        let m = self.up.abs().max_element();
        let up = if m > 1e-100 && m < 1e100 {
            self.up
        } else {
            self.up / m
        };
        let r = f.cross(up).normalize();
        let u = r.cross(f);
        (r, u, f)
    }

    /// World to eye space (`gluLookAt`).
    #[must_use]
    pub fn view_matrix(&self) -> DMat4 {
        let (r, u, f) = self.basis();
        DMat4::from_cols(
            DVec4::new(r.x, u.x, -f.x, 0.0),
            DVec4::new(r.y, u.y, -f.y, 0.0),
            DVec4::new(r.z, u.z, -f.z, 0.0),
            DVec4::new(-r.dot(self.eye), -u.dot(self.eye), f.dot(self.eye), 1.0),
        )
    }

    /// The half extents of the view window at unit depth (perspective) or in world
    /// units (orthographic): `(half_width, half_height)`, for `aspect = width / height`
    /// and the lens's pixel aspect. The window's centre is the lens's shift (see
    /// [`Lens`]), not part of these.
    #[must_use]
    pub fn half_extents(&self, aspect: f64) -> (f64, f64) {
        // Times a pixel aspect of 1: the same bits as without it.
        let aspect = aspect * self.lens.pixel_aspect;
        match self.projection {
            Projection::Perspective { fov_y_degrees } => {
                let h = (fov_y_degrees.to_radians() * 0.5).tan();
                (h * aspect, h)
            }
            Projection::Orthographic { height } => (height * 0.5 * aspect, height * 0.5),
        }
    }

    /// The view window `(left, right, bottom, top)` at unit depth (perspective) or in
    /// world units (orthographic), for `aspect = width / height`: the half extents of
    /// [`Camera::half_extents`] about the centre the lens's shift gives. `glFrustum`'s
    /// arguments are these times `near`, `glOrtho`'s these.
    #[must_use]
    pub fn window(&self, aspect: f64) -> (f64, f64, f64, f64) {
        let (hw, hh) = self.half_extents(aspect);
        let c = self.lens.ndc_centre();
        (
            (c.x - 1.0) * hw,
            (c.x + 1.0) * hw,
            (c.y - 1.0) * hh,
            (c.y + 1.0) * hh,
        )
    }

    /// Eye to clip space for `aspect = width / height`: `gluPerspective` or `glOrtho`
    /// for a centred lens, `glFrustum` or `glOrtho` of [`Camera::window`] for a shifted
    /// one.
    #[must_use]
    pub fn projection_matrix(&self, aspect: f64) -> DMat4 {
        let (n, f) = (self.near, self.far);
        let (hw, hh) = self.half_extents(aspect);
        // The window's centre in normalized device coordinates; zero (and then +0, so
        // that the products below change no bit) for a centred lens.
        let c = self.lens.ndc_centre();
        match self.projection {
            // glFrustum: the third column's (r + l) / (r - l) and (t + b) / (t - b).
            Projection::Perspective { .. } => DMat4::from_cols(
                DVec4::new(1.0 / hw, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 1.0 / hh, 0.0, 0.0),
                DVec4::new(c.x, c.y, (f + n) / (n - f), -1.0),
                DVec4::new(0.0, 0.0, 2.0 * f * n / (n - f), 0.0),
            ),
            // glOrtho: the last column's -(r + l) / (r - l) and -(t + b) / (t - b).
            Projection::Orthographic { .. } => DMat4::from_cols(
                DVec4::new(1.0 / hw, 0.0, 0.0, 0.0),
                DVec4::new(0.0, 1.0 / hh, 0.0, 0.0),
                DVec4::new(0.0, 0.0, -2.0 / (f - n), 0.0),
                DVec4::new(0.0 - c.x, 0.0 - c.y, -(f + n) / (f - n), 1.0),
            ),
        }
    }

    /// The world-space ray through the image point `(px, py)` (pixel units, row 0 at
    /// the top; the centre of pixel `(i, j)` is `(i + 0.5, j + 0.5)`).
    #[must_use]
    pub fn ray(&self, viewport: Viewport, px: f64, py: f64) -> Ray {
        let rays = ImageRays::new(self, viewport);
        let (origin, direction) = rays.ray_at(rays.window_x(px), rays.window_y(py));
        Ray { origin, direction }
    }

    /// A camera that shows the whole box: looking at its centre from the direction
    /// `(1, 0.6, 1.4)` rotated into the given up axis convention, far enough for its
    /// bounding sphere to fit the narrower field of view, with near and far planes
    /// hugging the sphere. Sizes are relative to the box (no absolute floor: a box
    /// 1e-20 across is framed like a unit one); the distance is at least `16 eps` of
    /// the centre's coordinates, so that the eye stays off the target, and the eye
    /// looks from the origin's side when the usual side would put it beyond
    /// [`super::MAX_COORDINATE`]. `up` may have any length.
    #[must_use]
    pub fn framing(bounds: &Aabb, aspect: f64, up: DVec3, fov_y_degrees: f64) -> Self {
        let center = if bounds.is_empty() {
            DVec3::ZERO
        } else {
            bounds.center()
        };
        // The bounding sphere's radius, relative to the scene: no absolute floor (one
        // of 1e-9 left a triangle 1e-20 across an empty picture).
        let radius = if bounds.is_empty() {
            1.0
        } else {
            crate::geom::robust_length(bounds.extent()) * 0.5
        };
        let magnitude = center.abs().max_element();
        let radius = if radius > 0.0 {
            radius
        } else {
            magnitude.max(1.0)
        };
        // Build a pleasant diagonal in the frame where `up` is the vertical (any
        // length: 1e308 or 1e-320 is scaled before it is normalized).
        let up = crate::geom::unit_direction(up).unwrap_or(DVec3::Y);
        let side = if up.abs().dot(DVec3::X) > 0.9 {
            DVec3::Y
        } else {
            DVec3::X
        };
        let a = side.reject_from(up).normalize();
        let b = up.cross(a);
        let dir = (a * 1.0 + b * 1.4 + up * 0.75).normalize();
        let half_fov =
            (fov_y_degrees.to_radians() * 0.5).min((fov_y_degrees.to_radians() * 0.5).tan().atan());
        let half_fov_x = ((half_fov.tan()) * aspect).atan();
        let fit = half_fov.min(half_fov_x).sin();
        // Only the rounding of the coordinates bounds the distance below: the eye must
        // stay distinguishable from the centre (`Camera::validate` asks for 8 `eps` of
        // the coordinates; a box 4 wide at 1e16 was framed from 11 units, "the eye is
        // on the target"). Such a scene is then seen smaller than the view.
        let distance = (radius / fit * 1.05).max(16.0 * f64::EPSILON * magnitude);
        let mut eye = center + dir * distance;
        if eye.abs().max_element() > super::MAX_COORDINATE {
            // A scene near the edge of the range (a box at 1e30 less its size): look
            // from the origin's side instead, which keeps the eye within the range
            // whenever the scene leaves it room.
            let toward_origin = DVec3::select(center.cmpgt(DVec3::ZERO), -dir.abs(), dir.abs());
            eye = center + toward_origin * distance;
        }
        let near = (distance - radius * 1.01).max(distance * 1e-3);
        let far = distance + radius * 1.01;
        Camera::perspective(eye, center, up, fov_y_degrees, near, far)
    }

    /// Sets `near` and `far` to hold the whole box as seen along the view direction,
    /// with a margin: `far` 1 % past the farthest corner; `near` 1 % before the
    /// nearest corner, but for a perspective camera at least `far / 10^9` (an eye
    /// inside the box, or that close to it: whatever lies nearer than a billionth of
    /// the farthest corner's distance is cut away; the depth keys `near / depth` keep
    /// their relative precision at any ratio, so the floor only keeps `near` positive,
    /// and a low one keeps objects near the eye in scenes of vast extent: with
    /// `far / 10^6`, a ground 10^7 wide put the near plane 14 units away); for
    /// an orthographic one it may be negative (planes behind the eye are seen). Nothing
    /// changes when the box is empty or the camera has no view direction (eye on the
    /// target, or not finite): [`Camera::validate`] reports that.
    ///
    /// Used when a camera is moved without giving its planes (the CLI's `--eye`, a scene
    /// file's `[camera]` without `near`/`far`).
    ///
    /// ```
    /// use glam::DVec3;
    /// use obscura::{Camera, geom::Aabb};
    ///
    /// let unit = Aabb { min: DVec3::ZERO, max: DVec3::ONE };
    /// let mut cam = Camera::perspective(DVec3::new(0.5, 0.5, 5.0), DVec3::new(0.5, 0.5, 0.0), DVec3::Y, 60.0, 1.0, 2.0);
    /// cam.fit_depth_range(&unit);
    /// // Corners at 4 and 5 along the view axis.
    /// assert!((cam.near - 4.0 * 0.99).abs() < 1e-12);
    /// assert!(cam.far > 5.0 * 1.01 && cam.far < 5.0 * 1.01 + 1e-5);
    /// ```
    pub fn fit_depth_range(&mut self, bounds: &Aabb) {
        let forward = (self.target - self.eye).normalize_or_zero();
        if bounds.is_empty() || forward == DVec3::ZERO || !forward.is_finite() {
            return;
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in bounds.corners() {
            let d = (c - self.eye).dot(forward);
            lo = lo.min(d);
            hi = hi.max(d);
        }
        let size = bounds.extent().length().max(1e-9);
        // A box wholly behind the eye (or nearly) still gets a valid range.
        let far = if hi > size * 1e-3 {
            hi * 1.01 + size * 1e-6
        } else {
            size * 1e-3
        };
        self.near = match self.projection {
            Projection::Perspective { .. } => (lo * 0.99).max(far * 1e-9),
            Projection::Orthographic { .. } => lo - size * 0.01,
        };
        self.far = far;
    }
}

/// The image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Viewport {
    /// Width in pixels, 1..=[`Viewport::MAX_SIDE`].
    pub width: u32,
    /// Height in pixels, 1..=[`Viewport::MAX_SIDE`].
    pub height: u32,
}

impl Viewport {
    /// The largest accepted side.
    pub const MAX_SIDE: u64 = 16384;

    /// A checked viewport: each side in `1..=16384`.
    pub fn new(width: u64, height: u64) -> Result<Self> {
        let err = |reason: String| {
            Err(Error::InvalidViewport {
                width,
                height,
                reason,
            })
        };
        if width == 0 || height == 0 {
            return err("both sides must be at least 1 pixel".into());
        }
        if width > Self::MAX_SIDE || height > Self::MAX_SIDE {
            return err(format!(
                "each side must be at most {} pixels",
                Self::MAX_SIDE
            ));
        }
        Ok(Viewport {
            width: width as u32,
            height: height as u32,
        })
    }

    /// Checks a viewport made without [`Viewport::new`] (its fields are public): the
    /// same error as `new` for a side of 0 or over [`Viewport::MAX_SIDE`].
    ///
    /// ```
    /// use obscura::Viewport;
    /// assert!(Viewport { width: 0, height: 5 }.validate().is_err());
    /// assert!(Viewport { width: 640, height: 480 }.validate().is_ok());
    /// ```
    pub fn validate(&self) -> Result<()> {
        Viewport::new(u64::from(self.width), u64::from(self.height)).map(|_| ())
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// `width / height`.
    #[must_use]
    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::perspective(
            DVec3::new(0., 0., 5.),
            DVec3::ZERO,
            DVec3::Y,
            90.0,
            1.0,
            10.0,
        )
    }

    #[test]
    fn a_fitted_near_plane_keeps_what_is_near_an_eye_inside_the_box() {
        // A ground 100 km across with a unit box at its centre, seen from 4 units away
        // (the eye inside the scene's box): the near plane was far / 10^4, about 7,
        // and the box vanished.
        let scene = Aabb {
            min: DVec3::new(-5e4, -0.01, -5e4),
            max: DVec3::new(5e4, 1.0, 5e4),
        };
        let mut c = Camera::perspective(
            DVec3::new(0.0, 1.0, 4.0),
            DVec3::ZERO,
            DVec3::Y,
            60.0,
            1.0,
            2.0,
        );
        c.fit_depth_range(&scene);
        let forward = (c.target - c.eye).normalize();
        let farthest = scene
            .corners()
            .into_iter()
            .map(|p| (p - c.eye).dot(forward))
            .fold(f64::MIN, f64::max);
        assert!(c.far > farthest && c.far < farthest * 1.02, "{}", c.far);
        assert!(c.near <= c.far * 1e-9 * 1.000_001, "{} {}", c.near, c.far);
        // The box's nearest point is about 3 units along the view axis.
        assert!(c.near < 0.1, "{}", c.near);
        c.validate().unwrap();
        // A ground 10^7 across (the near plane was 14 with a floor of far / 10^6)
        // and 10^9 across.
        for width in [1e7, 1e9] {
            let ground = Aabb {
                min: DVec3::new(-width / 2.0, -1.5, -width / 2.0),
                max: DVec3::new(width / 2.0, 1.0, width / 2.0),
            };
            c.fit_depth_range(&ground);
            assert!(c.near < 2.0, "ground {width}: near {}", c.near);
            assert!(c.far > width * 0.45, "ground {width}: far {}", c.far);
            c.validate().unwrap();
        }
    }

    #[test]
    fn look_at_maps_target_to_negative_z() {
        let v = cam().view_matrix();
        let t = v.transform_point3(DVec3::ZERO);
        assert!((t - DVec3::new(0., 0., -5.)).length() < 1e-12);
        let c = Camera::perspective(
            DVec3::new(3., 2., 1.),
            DVec3::new(-1., 0., 4.),
            DVec3::Y,
            60.,
            0.1,
            100.,
        );
        let t = c.view_matrix().transform_point3(c.target);
        assert!(t.x.abs() < 1e-12 && t.y.abs() < 1e-12 && t.z < 0.0);
    }

    #[test]
    fn projection_maps_near_and_far_to_clip_bounds() {
        let p = cam().projection_matrix(1.0);
        let near = p * DVec4::new(0., 0., -1., 1.);
        let far = p * DVec4::new(0., 0., -10., 1.);
        assert!((near.z / near.w + 1.0).abs() < 1e-12);
        assert!((far.z / far.w - 1.0).abs() < 1e-12);
        // 90 degree fov: the point (1, 1, -1) is on the top-right corner
        let c = p * DVec4::new(1., 1., -1., 1.);
        assert!((c.x / c.w - 1.0).abs() < 1e-12 && (c.y / c.w - 1.0).abs() < 1e-12);
        let o = Camera::orthographic(DVec3::Z * 5.0, DVec3::ZERO, DVec3::Y, 4.0, 1.0, 9.0)
            .projection_matrix(2.0);
        let c = o * DVec4::new(4., 2., -9., 1.);
        assert!(
            (c.x - 1.0).abs() < 1e-12 && (c.y - 1.0).abs() < 1e-12 && (c.z - 1.0).abs() < 1e-12
        );
    }

    #[test]
    fn rays_go_through_pixel_centres() {
        let c = cam();
        let vp = Viewport::new(2, 2).unwrap();
        let r = c.ray(vp, 1.0, 1.0);
        assert!((r.direction - DVec3::new(0., 0., -1.)).length() < 1e-12);
        let r = c.ray(vp, 2.0, 0.0); // top-right corner
        assert!((r.direction - DVec3::new(1., 1., -1.)).length() < 1e-12);
    }

    #[test]
    fn validation() {
        assert!(cam().validate().is_ok());
        let mut c = cam();
        c.target = c.eye;
        assert!(c.validate().is_err());
        let mut c = cam();
        c.up = DVec3::Z;
        assert!(c.validate().is_err());
        let mut c = cam();
        c.near = 0.0;
        assert!(c.validate().is_err());
        let mut c = cam();
        c.projection = Projection::Perspective {
            fov_y_degrees: 180.0,
        };
        assert!(c.validate().is_err());
        let mut c = cam();
        c.eye.x = f64::NAN;
        assert!(c.validate().is_err());
        assert!(Viewport::new(0, 10).is_err());
        assert!(Viewport::new(16385, 10).is_err());
        assert!(Viewport::new(16384, 16384).is_ok());
    }

    #[test]
    fn framing_sees_the_whole_box() {
        let b = Aabb {
            min: DVec3::new(-1., -2., -3.),
            max: DVec3::new(4., 5., 6.),
        };
        let c = Camera::framing(&b, 16.0 / 9.0, DVec3::Y, 45.0);
        c.validate().unwrap();
        let m = c.projection_matrix(16.0 / 9.0) * c.view_matrix();
        for p in b.corners() {
            let q = m * p.extend(1.0);
            assert!(q.w > 0.0);
            for k in 0..3 {
                assert!(q[k].abs() <= q.w * 1.0001, "corner {p:?} outside: {q:?}");
            }
        }
    }

    #[test]
    fn fitted_depth_range_holds_the_box_along_the_view_axis() {
        // A 2 x 2 x 2 box centred at the origin; the eye on +x looking at it, so the
        // corners lie at distances 3 and 5 along the view axis.
        let b = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        let size = 12f64.sqrt();
        let eye = DVec3::new(4.0, 0.0, 0.0);
        let mut c = Camera::perspective(eye, DVec3::ZERO, DVec3::Z, 60.0, 1.0, 2.0);
        c.fit_depth_range(&b);
        assert_eq!(c.near, 3.0 * 0.99);
        assert_eq!(c.far, 5.0 * 1.01 + size * 1e-6);
        assert!(c.validate().is_ok());
        // The eye inside the box: the near plane keeps 10^9 : 1.
        let mut inside = Camera::perspective(DVec3::ZERO, DVec3::X, DVec3::Z, 60.0, 1.0, 2.0);
        inside.fit_depth_range(&b);
        let far = 1.0 * 1.01 + size * 1e-6;
        assert_eq!(inside.far, far);
        assert_eq!(inside.near, far * 1e-9);
        // Orthographic: the near plane may be behind the eye.
        let mut ortho = Camera {
            projection: Projection::Orthographic { height: 2.0 },
            ..inside
        };
        ortho.fit_depth_range(&b);
        assert_eq!(ortho.near, -1.0 - size * 0.01);
        assert_eq!(ortho.far, far);
        assert!(ortho.validate().is_ok());
        // Nothing to fit: an empty box, or no view direction.
        let mut same = Camera { target: eye, ..c };
        same.fit_depth_range(&b);
        assert_eq!((same.near, same.far), (c.near, c.far));
        let mut empty = c;
        empty.fit_depth_range(&Aabb {
            min: DVec3::splat(f64::INFINITY),
            max: DVec3::splat(f64::NEG_INFINITY),
        });
        assert_eq!(empty, c);
    }
}
