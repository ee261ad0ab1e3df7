//! Height fields: a grid of heights `y` over `x` and `z`, from a file (see
//! [`super::load`]) or a built-in function.

use glam::DVec3;

use crate::budget::MemoryBudget;
use crate::geom::Aabb;
use crate::{Camera, Error, Result};

/// A grid of heights `y` over `x` (columns, `nx`) and `z` (rows, `nz`), row-major.
///
/// Sample `(i, k)` (column `i`, row `k`) is the world point `(x(i), heights[k nx + i],
/// z(k))`; columns run evenly from `x_range[0]` (column 0) to `x_range[1]`, rows from
/// `z_range[0]` (row 0) to `z_range[1]`. The default extent is `[-1, 1]` in both, whatever
/// the grid's shape ([`HeightField::with_extent`] changes it); heights are used as
/// given ([`HeightField::fit_heights`] rescales them). Row 0 of a file (the top row of
/// an image) is `z = -1`: the far side seen from the default camera, as a map is seen
/// from its southern edge.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    /// `nx * nz` heights, row `z` after row `z`.
    pub heights: Vec<f64>,
    /// Samples along x.
    pub nx: usize,
    /// Samples along z.
    pub nz: usize,
    /// World `x` of the first and the last column.
    pub x_range: [f64; 2],
    /// World `z` of the first and the last row.
    pub z_range: [f64; 2],
}

impl Default for HeightField {
    /// An empty field over `[-1, 1]^2` (refused by [`HeightField::validate`]).
    fn default() -> Self {
        HeightField {
            heights: Vec::new(),
            nx: 0,
            nz: 0,
            x_range: [-1.0, 1.0],
            z_range: [-1.0, 1.0],
        }
    }
}

/// The built-in functions of [`HeightField::function`]: name and formula, over `x` and
/// `z` in `[-1, 1]`.
pub const FUNCTIONS: &[(&str, &str)] = &[
    ("ripple", "sin(r)/r with r = 12 sqrt(x^2 + z^2), times 0.6"),
    ("saddle", "0.5 (x^2 - z^2)"),
    ("bump", "0.8 exp(-8 (x^2 + z^2)): one Gaussian bump"),
    (
        "bumps",
        "three Gaussian bumps of heights 0.7, 0.5 and 0.4 at (-0.4, 0.3), (0.45, -0.2) and (0, -0.6)",
    ),
    ("waves", "0.25 sin(6 x) cos(4 z)"),
    (
        "peaks",
        "the MATLAB peaks surface over [-3, 3]^2, scaled by 0.08",
    ),
    ("plane", "0.5 z: a plane rising toward the default viewer"),
];

impl HeightField {
    /// A field from its heights (row-major, `nz` rows of `nx`), over `[-1, 1]^2`,
    /// checked by [`HeightField::validate`].
    ///
    /// ```
    /// use obscura::lines::horizon::HeightField;
    /// let f = HeightField::new(3, 2, vec![0., 1., 0., 0., 2., 0.])?;
    /// assert_eq!(f.height(1, 1), 2.0);
    /// assert!(HeightField::new(2, 1, vec![0., f64::NAN]).is_err());
    /// # Ok::<(), obscura::Error>(())
    /// ```
    pub fn new(nx: usize, nz: usize, heights: Vec<f64>) -> Result<Self> {
        let f = HeightField {
            heights,
            nx,
            nz,
            ..HeightField::default()
        };
        f.validate()?;
        Ok(f)
    }

    /// Checks the field: at least 2 columns and 1 row, `nx * nz` heights, every one
    /// finite (the error names the first bad sample by row and column), finite extents
    /// with `x_range[0] < x_range[1]` and `z_range[0] < z_range[1]` (equal allowed for a
    /// single row).
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Err(Error::option("height field", reason));
        if self.nx == 0 || self.nz == 0 || self.heights.is_empty() {
            return bad("the grid is empty".into());
        }
        if self.nx < 2 {
            return bad(format!(
                "the grid has {} column(s); at least 2 are needed to draw a curve",
                self.nx
            ));
        }
        if self.nx.checked_mul(self.nz) != Some(self.heights.len()) {
            return bad(format!(
                "{} heights for a grid of {} x {}",
                self.heights.len(),
                self.nx,
                self.nz
            ));
        }
        if let Some(at) = self.heights.iter().position(|h| !h.is_finite()) {
            return bad(format!(
                "the height at row {}, column {} is {} (heights must be finite)",
                at / self.nx,
                at % self.nx,
                self.heights[at]
            ));
        }
        let [x0, x1] = self.x_range;
        let [z0, z1] = self.z_range;
        let limit = crate::scene::MAX_COORDINATE;
        if ![x0, x1, z0, z1]
            .iter()
            .all(|v| v.is_finite() && v.abs() <= limit)
            || !(x0 < x1)
            || !(z0 < z1 || (self.nz == 1 && z0 <= z1))
        {
            return bad(format!(
                "the extent x {:?}, z {:?} must be finite and increasing",
                self.x_range, self.z_range
            ));
        }
        if let Some(h) = self.heights.iter().find(|h| h.abs() > limit) {
            return bad(format!("a height of {h} is beyond {limit:e}"));
        }
        Ok(())
    }

    /// A built-in function of [`FUNCTIONS`] sampled on `nx` by `nz` points over
    /// `[-1, 1]^2`.
    ///
    /// ```
    /// use obscura::lines::horizon::HeightField;
    /// let f = HeightField::function("saddle", 5, 5)?;
    /// assert_eq!(f.height(4, 2), 0.5); // x = 1, z = 0
    /// assert!(HeightField::function("sadle", 5, 5).is_err());
    /// # Ok::<(), obscura::Error>(())
    /// ```
    pub fn function(name: &str, nx: usize, nz: usize) -> Result<Self> {
        HeightField::function_with_budget(name, nx, nz, &MemoryBudget::default())
    }

    /// [`HeightField::function`] held to a memory budget.
    pub fn function_with_budget(
        name: &str,
        nx: usize,
        nz: usize,
        budget: &MemoryBudget,
    ) -> Result<Self> {
        let f: fn(f64, f64) -> f64 = match name {
            "ripple" => |x, z| {
                let r = 12.0 * (x * x + z * z).sqrt();
                if r < 1e-9 { 0.6 } else { 0.6 * r.sin() / r }
            },
            "saddle" => |x, z| 0.5 * (x * x - z * z),
            "bump" => |x, z| 0.8 * (-8.0 * (x * x + z * z)).exp(),
            "bumps" => |x, z| {
                let g = |cx: f64, cz: f64, h: f64| {
                    h * (-12.0 * ((x - cx).powi(2) + (z - cz).powi(2))).exp()
                };
                g(-0.4, 0.3, 0.7) + g(0.45, -0.2, 0.5) + g(0.0, -0.6, 0.4)
            },
            "waves" => |x, z| 0.25 * (6.0 * x).sin() * (4.0 * z).cos(),
            "peaks" => |x, z| {
                let (x, y) = (3.0 * x, 3.0 * z);
                let p = 3.0 * (1.0 - x).powi(2) * (-x * x - (y + 1.0).powi(2)).exp()
                    - 10.0 * (x / 5.0 - x.powi(3) - y.powi(5)) * (-x * x - y * y).exp()
                    - (-(x + 1.0).powi(2) - y * y).exp() / 3.0;
                0.08 * p
            },
            "plane" => |_, z| 0.5 * z,
            _ => {
                let known: Vec<&str> = FUNCTIONS.iter().map(|f| f.0).collect();
                return Err(Error::option(
                    "function",
                    format!("unknown function '{name}' (known: {})", known.join(", ")),
                ));
            }
        };
        HeightField::from_fn(nx, nz, budget, f)
    }

    /// The field of `f(x, z)` sampled on `nx` by `nz` points over `[-1, 1]^2`, held to
    /// `budget`.
    pub fn from_fn(
        nx: usize,
        nz: usize,
        budget: &MemoryBudget,
        f: impl Fn(f64, f64) -> f64,
    ) -> Result<Self> {
        let n = check_size(nx, nz, budget)?;
        let mut heights = crate::budget::try_vec(budget, BUDGET_STRUCTURE, n)?;
        let mut field = HeightField {
            nx,
            nz,
            ..HeightField::default()
        };
        for k in 0..nz {
            let z = field.z(k);
            for i in 0..nx {
                heights.push(f(field.x(i), z));
            }
        }
        field.heights = heights;
        field.validate()?;
        Ok(field)
    }

    /// The field over other extents (see the type's doc).
    pub fn with_extent(mut self, x_range: [f64; 2], z_range: [f64; 2]) -> Result<Self> {
        self.x_range = x_range;
        self.z_range = z_range;
        self.validate()?;
        Ok(self)
    }

    /// The field with its heights mapped linearly onto `[lo, hi]` (the lowest sample to
    /// `lo`, the highest to `hi`; a flat field to `lo`).
    #[must_use]
    pub fn fit_heights(mut self, lo: f64, hi: f64) -> Self {
        let (min, max) = self
            .heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
                (a.min(h), b.max(h))
            });
        let scale = if max > min {
            (hi - lo) / (max - min)
        } else {
            0.0
        };
        for h in &mut self.heights {
            *h = lo + (*h - min) * scale;
        }
        self
    }

    /// World `x` of column `i`.
    #[inline]
    #[must_use]
    pub fn x(&self, i: usize) -> f64 {
        grid_coordinate(self.x_range, i, self.nx)
    }

    /// World `z` of row `k`.
    #[inline]
    #[must_use]
    pub fn z(&self, k: usize) -> f64 {
        grid_coordinate(self.z_range, k, self.nz)
    }

    /// The height of column `i`, row `k`.
    #[inline]
    #[must_use]
    pub fn height(&self, i: usize, k: usize) -> f64 {
        self.heights[k * self.nx + i]
    }

    /// The world point of column `i`, row `k`.
    #[inline]
    #[must_use]
    pub fn point(&self, i: usize, k: usize) -> DVec3 {
        DVec3::new(self.x(i), self.height(i, k), self.z(k))
    }

    /// The world box of every sample.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        let (lo, hi) = self
            .heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
                (a.min(h), b.max(h))
            });
        Aabb {
            min: DVec3::new(self.x_range[0], lo, self.z_range[0]),
            max: DVec3::new(self.x_range[1], hi, self.z_range[1]),
        }
    }

    /// A perspective camera in front of the field (on the `+z` side, so rows are
    /// drawn from the last to the first) and above it, looking at its centre, that
    /// shows all of it for the aspect ratio `width / height`.
    #[must_use]
    pub fn default_camera(&self, aspect: f64) -> Camera {
        let b = self.bounds();
        let c = b.center();
        let e = b.extent();
        let dir = DVec3::new(0.0, 0.55, 1.0).normalize();
        let fov: f64 = 40.0;
        let half = (fov.to_radians() * 0.5)
            .tan()
            .min((fov.to_radians() * 0.5).tan() * aspect);
        let radius = 0.5 * e.length().max(1e-9);
        let distance = radius / half.atan().sin() * 1.05;
        let mut cam = Camera::perspective(c + dir * distance, c, DVec3::Y, fov, 0.1, 10.0);
        cam.fit_depth_range(&b);
        cam
    }
}

/// The name budget errors give the height field.
pub(crate) const BUDGET_STRUCTURE: &str = "height field samples";

/// `nx * nz`, refused when empty or over the budget (8 bytes a sample).
pub(crate) fn check_size(nx: usize, nz: usize, budget: &MemoryBudget) -> Result<usize> {
    if nx == 0 || nz == 0 {
        return Err(Error::option(
            "height field",
            format!("the grid {nx} x {nz} is empty"),
        ));
    }
    let n = (nx as u64).saturating_mul(nz as u64);
    budget.check_items(BUDGET_STRUCTURE, n, 8)?;
    usize::try_from(n).map_err(|_| budget.exceeded(BUDGET_STRUCTURE, n, n.saturating_mul(8)))
}

/// The `i`th of `n` evenly spaced values from `r[0]` to `r[1]` (exact at both ends).
#[inline]
fn grid_coordinate(r: [f64; 2], i: usize, n: usize) -> f64 {
    if n <= 1 {
        return r[0];
    }
    if i + 1 == n {
        return r[1];
    }
    let t = i as f64 / (n - 1) as f64;
    r[0] + (r[1] - r[0]) * t
}
