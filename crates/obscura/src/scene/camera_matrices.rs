//! Cameras from what other programs hold: a view and a projection matrix (OpenGL,
//! glam), or pinhole intrinsics (vision, robotics).
//!
//! obscura's [`Camera`] is a look-at camera whose view is a rigid motion; its
//! [`Lens`] holds an off-centre window (a principal point away from the image centre,
//! `glFrustum`'s `l != -r`) and non-square pixels (`fx != fy`). These constructors
//! recover such a camera and refuse, with an [`Error::InvalidCamera`] saying why, what
//! it cannot represent (a skewed projection, a depth that depends on `x` or `y`, a view
//! that scales) and what is not a camera at all (NaN, a singular matrix).
//!
//! Source: the pinhole model `u = fx X / Z + cx` of Hartley and Zisserman, "Multiple
//! View Geometry in Computer Vision", 2nd ed., 2004, section 6.1; the matrices of
//! `glFrustum` and `glOrtho` in the OpenGL 2.1 reference pages.

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4};

use super::{Camera, Lens, Projection, Viewport};
use crate::{Error, Result};

/// Relative tolerance of the checks of a matrix's shape (rotation rows orthonormal,
/// zero terms zero), and within which a lens is taken for centred with square pixels
/// (a shift of at most this many image widths, a pixel aspect this close to 1).
const SHAPE_TOLERANCE: f64 = 1e-9;

/// Pinhole intrinsics: focal lengths and principal point in pixels, and the image size.
///
/// Pixel convention (obscura's, see `docs/ARCHITECTURE.md`): the image's top-left
/// corner is `(0, 0)`, `x` goes right and `y` down, and pixel `(i, j)` covers
/// `[i, i + 1) x [j, j + 1)`, its centre at `(i + 0.5, j + 0.5)`. The centre of a
/// `width x height` image is therefore `(width / 2, height / 2)`. OpenCV puts pixel
/// centres at integers: add 0.5 to its `cx` and `cy` (its centre of a 64 x 48 image,
/// `(31.5, 23.5)`, is obscura's `(32, 24)`; given unchanged, it is taken for a
/// principal point half a pixel up and left of the centre).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Focal length in pixels along `x`.
    pub fx: f64,
    /// Focal length in pixels along `y`.
    pub fy: f64,
    /// Principal point, `x` (pixels from the left edge).
    pub cx: f64,
    /// Principal point, `y` (pixels from the top edge).
    pub cy: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Intrinsics {
    /// The viewport of the image.
    pub fn viewport(&self) -> Result<Viewport> {
        Viewport::new(u64::from(self.width), u64::from(self.height))
    }

    /// The vertical field of view in degrees, `2 atan(height / 2 / fy)`, of the
    /// centred window of the same size (the window itself may be off-centre, see
    /// [`Intrinsics::lens`]).
    #[must_use]
    pub fn fov_y_degrees(&self) -> f64 {
        (2.0 * (f64::from(self.height) * 0.5 / self.fy).atan()).to_degrees()
    }

    /// The lens of these intrinsics: the window shifted by `((width / 2 - cx) /
    /// width, (cy - height / 2) / height)` (the principal point right of the centre
    /// moves the window left), pixels of aspect `fy / fx`. A principal point within
    /// `1e-9` of the largest side of the centre and focal lengths within a relative
    /// `1e-9` of each other give exactly [`Lens::CENTRED`]'s fields.
    ///
    /// ```
    /// use glam::DVec2;
    /// use obscura::scene::Intrinsics;
    /// let k = Intrinsics { fx: 400.0, fy: 500.0, cx: 300.0, cy: 250.0, width: 640, height: 480 };
    /// let lens = k.lens();
    /// assert_eq!(lens.shift, DVec2::new(20.0 / 640.0, 10.0 / 480.0));
    /// assert_eq!(lens.pixel_aspect, 1.25);
    /// ```
    #[must_use]
    pub fn lens(&self) -> Lens {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (mx, my) = (w * 0.5, h * 0.5);
        let off = SHAPE_TOLERANCE * mx.max(my);
        let centred = |c: f64, m: f64| (c - m).abs() <= off;
        let shift = DVec2::new(
            if centred(self.cx, mx) {
                0.0
            } else {
                (mx - self.cx) / w
            },
            if centred(self.cy, my) {
                0.0
            } else {
                (self.cy - my) / h
            },
        );
        let pixel_aspect = if ((self.fx - self.fy) / self.fy).abs() <= SHAPE_TOLERANCE {
            1.0
        } else {
            self.fy / self.fx
        };
        Lens {
            shift,
            pixel_aspect,
        }
    }
}

impl Camera {
    /// The camera of a world-to-eye `view` matrix and an eye-to-clip `projection`
    /// matrix for `viewport`, in OpenGL's conventions (the eye looks down `-z`, clip
    /// space `-w <= x, y, z <= w`): what [`Camera::view_matrix`] and
    /// [`Camera::projection_matrix`] return, glam's `look_at_rh`,
    /// `perspective_rh_gl` and `orthographic_rh_gl` (an `f32` `Mat4` converts with
    /// `as_dmat4()`), and the off-centre frusta of `glFrustum` and `glOrtho`.
    ///
    /// The projection is perspective when its last row is `(0, 0, -1, 0)` and
    /// orthographic when it is `(0, 0, 0, 1)`; near and far are read off its third
    /// row; an off-centre window becomes the camera's [`Lens`] shift, and a ratio of
    /// the scales other than the viewport's aspect ratio its pixel aspect (a shift
    /// within `1e-9` of the window and a pixel aspect within `1e-9` of 1 are taken for
    /// [`Lens::CENTRED`]'s). Refused, with a message saying which: non-finite or
    /// singular matrices, a view that is not a rotation and a translation, a skewed
    /// projection (`x` and `y` mixed), a perspective one whose window moves with depth
    /// (`x` or `y` plus a constant), an oblique orthographic one (`x` or `y` plus a
    /// multiple of depth), and a depth that depends on `x` or `y`.
    ///
    /// ```
    /// use glam::DVec3;
    /// use obscura::{Camera, Viewport};
    /// let viewport = Viewport::new(640, 480)?;
    /// let camera = Camera::perspective(DVec3::new(1.0, 2.0, 5.0), DVec3::ZERO, DVec3::Y, 50.0, 0.5, 40.0);
    /// let view = camera.view_matrix();
    /// let projection = camera.projection_matrix(viewport.aspect());
    /// let again = Camera::from_matrices(view, projection, viewport)?;
    /// assert!((again.eye - camera.eye).length() < 1e-12);
    /// assert!((again.near - 0.5).abs() < 1e-12 && (again.far - 40.0).abs() < 1e-9);
    /// # Ok::<(), obscura::Error>(())
    /// ```
    pub fn from_matrices(view: DMat4, projection: DMat4, viewport: Viewport) -> Result<Camera> {
        let (eye, up, forward) = pose(&view)?;
        let p = projection;
        if !p.is_finite() {
            return bad("the projection matrix has non-finite entries".into());
        }
        let det = p.determinant();
        if !(det.is_finite() && det != 0.0) {
            return bad("the projection matrix is singular (not invertible)".into());
        }
        let last = p.row(3);
        let perspective = last == DVec4::new(0.0, 0.0, -1.0, 0.0);
        if !perspective && last != DVec4::W {
            return bad(format!(
                "the projection matrix's last row {:?} is neither perspective's (0, 0, -1, 0) \
                 nor orthographic's (0, 0, 0, 1)",
                last.to_array()
            ));
        }
        let (sx, sy) = (p.x_axis.x, p.y_axis.y);
        let scale = sx.abs().max(sy.abs());
        let zero = |t: f64, of: f64| t.abs() <= SHAPE_TOLERANCE * of;
        let skew = [p.y_axis.x, p.x_axis.y];
        if !skew.iter().all(|&t| zero(t, scale)) {
            return bad(format!(
                "the projection is skewed (terms {skew:?}, which mix x and y, are not \
                 zero): obscura's cameras have rectangular pixels"
            ));
        }
        // The window's centre in normalized device coordinates: for a perspective
        // projection the depth terms of x and y (glFrustum's (r + l) / (r - l)), for
        // an orthographic one their constants (glOrtho's -(r + l) / (r - l)). The
        // other pair must be zero.
        let (centre, others, what) = if perspective {
            (
                DVec2::new(p.z_axis.x, p.z_axis.y),
                [p.w_axis.x, p.w_axis.y],
                "x or y plus a constant: the window moves with depth",
            )
        } else {
            (
                DVec2::new(-p.w_axis.x, -p.w_axis.y),
                [p.z_axis.x, p.z_axis.y],
                "x or y plus a multiple of depth: an oblique projection",
            )
        };
        if !others.iter().all(|&t| zero(t, scale)) {
            return bad(format!(
                "the projection is not a camera's (terms {others:?}, {what}, are not zero)"
            ));
        }
        let depth_row = [p.x_axis.z, p.y_axis.z];
        if !depth_row.iter().all(|&t| zero(t, p.z_axis.z.abs())) {
            return bad(format!(
                "the projection's depth depends on x or y (terms {depth_row:?} of its third \
                 row are not zero: an oblique near plane?)"
            ));
        }
        if !(sx > 0.0 && sy > 0.0) {
            return bad(format!(
                "the projection's scales {sx:e} (x) and {sy:e} (y) must be positive"
            ));
        }
        // Window width over height is `sy / sx`; over the viewport's, the pixels'.
        let pixel_aspect = (sy / sx) / viewport.aspect();
        let pixel_aspect = if (pixel_aspect - 1.0).abs() <= SHAPE_TOLERANCE {
            1.0
        } else {
            pixel_aspect
        };
        let shift = DVec2::select(
            centre.abs().cmple(DVec2::splat(2.0 * SHAPE_TOLERANCE)),
            DVec2::ZERO,
            centre * 0.5,
        );
        let (a, b) = (p.z_axis.z, p.w_axis.z);
        let (projection, near, far) = if perspective {
            let fov_y_degrees = (2.0 * (1.0 / sy).atan()).to_degrees();
            (
                Projection::Perspective { fov_y_degrees },
                b / (a - 1.0),
                b / (a + 1.0),
            )
        } else {
            let height = 2.0 / sy;
            (
                Projection::Orthographic { height },
                (b + 1.0) / a,
                (b - 1.0) / a,
            )
        };
        let mut camera = look_along(eye, up, forward, projection, near, far);
        camera.lens = Lens {
            shift,
            pixel_aspect,
        };
        camera.validate_for(viewport)?;
        Ok(camera)
    }

    /// The camera at the pose of a world-to-eye `view` matrix (OpenGL's convention, as
    /// [`Camera::from_matrices`] takes it) with pinhole `intrinsics`, seeing depths from
    /// `near` to `far`; its viewport is [`Intrinsics::viewport`].
    ///
    /// A pixel `(u, v)` (obscura's convention, see [`Intrinsics`]) sees the eye-space
    /// direction `((u - cx) / fx, (cy - v) / fy, -1)`: the principal point may be
    /// anywhere and the focal lengths may differ, both held by the camera's
    /// [`Lens`] ([`Intrinsics::lens`]). From OpenCV's world-to-camera `[R | t]`
    /// (looking down `+z`, `y` down), the view is
    /// `DMat4::from_scale(DVec3::new(1.0, -1.0, -1.0)) * rt`.
    ///
    /// ```
    /// use glam::DVec3;
    /// use obscura::scene::Intrinsics;
    /// use obscura::Camera;
    /// let k = Intrinsics { fx: 500.0, fy: 500.0, cx: 320.0, cy: 240.0, width: 640, height: 480 };
    /// let pose = Camera::perspective(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, 45.0, 0.1, 100.0);
    /// let camera = Camera::from_intrinsics(pose.view_matrix(), &k, 0.1, 100.0)?;
    /// assert!((k.fov_y_degrees() - 51.28).abs() < 0.01);
    /// // The principal point's pixel sees straight ahead.
    /// let ray = camera.ray(k.viewport()?, k.cx, k.cy);
    /// assert!((ray.direction - DVec3::NEG_Z).length() < 1e-12);
    /// # Ok::<(), obscura::Error>(())
    /// ```
    pub fn from_intrinsics(
        view: DMat4,
        intrinsics: &Intrinsics,
        near: f64,
        far: f64,
    ) -> Result<Camera> {
        let k = intrinsics;
        let viewport = k.viewport()?;
        if ![k.fx, k.fy, k.cx, k.cy].iter().all(|v| v.is_finite()) {
            return bad(format!(
                "intrinsics fx {}, fy {}, cx {}, cy {} must be finite",
                k.fx, k.fy, k.cx, k.cy
            ));
        }
        if !(k.fx > 0.0 && k.fy > 0.0) {
            return bad(format!(
                "focal lengths fx {} and fy {} must be positive",
                k.fx, k.fy
            ));
        }
        let (eye, up, forward) = pose(&view)?;
        let projection = Projection::Perspective {
            fov_y_degrees: k.fov_y_degrees(),
        };
        let mut camera = look_along(eye, up, forward, projection, near, far);
        camera.lens = k.lens();
        camera.validate_for(viewport)?;
        Ok(camera)
    }
}

/// `Err(InvalidCamera(message))`.
fn bad<T>(message: String) -> Result<T> {
    Err(Error::InvalidCamera(message))
}

/// The eye, up and forward directions of a rigid world-to-eye matrix.
fn pose(view: &DMat4) -> Result<(DVec3, DVec3, DVec3)> {
    if !view.is_finite() {
        return bad("the view matrix has non-finite entries".into());
    }
    if view.row(3) != DVec4::W {
        return bad(format!(
            "the view matrix is not affine (last row {:?}, not [0, 0, 0, 1])",
            view.row(3).to_array()
        ));
    }
    let r = DMat3::from_mat4(*view);
    let det = r.determinant();
    if !(det.is_finite() && det != 0.0) {
        return bad("the view matrix is singular (not invertible)".into());
    }
    let rows = [r.row(0), r.row(1), r.row(2)];
    let orthonormal = (0..3).all(|i| {
        (0..3).all(|j| {
            let expected = if i == j { 1.0 } else { 0.0 };
            (rows[i].dot(rows[j]) - expected).abs() <= SHAPE_TOLERANCE
        })
    });
    if !orthonormal || det < 0.0 {
        return bad(
            "the view matrix is not a rotation and a translation (it scales, shears or \
             mirrors): obscura's cameras are rigid"
                .into(),
        );
    }
    let t = view.w_axis.truncate();
    // world -> eye is `R p + t`, so the eye (eye-space origin) is `-R^T t`.
    let eye = -(r.transpose() * t);
    Ok((eye, rows[1], -rows[2]))
}

/// A look-at camera at `eye` looking along `forward` with `up`.
fn look_along(
    eye: DVec3,
    up: DVec3,
    forward: DVec3,
    projection: Projection,
    near: f64,
    far: f64,
) -> Camera {
    // The target's distance does not matter (the basis normalizes the direction); one
    // of the size of the eye's coordinates keeps the direction resolved far from the
    // origin.
    let distance = eye.abs().max_element().max(1.0);
    Camera {
        eye,
        target: eye + forward * distance,
        up,
        projection,
        near,
        far,
        lens: Lens::CENTRED,
    }
}
