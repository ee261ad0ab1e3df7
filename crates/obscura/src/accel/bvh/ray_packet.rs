//! The rays of a packet, prepared once for the packet traversal ([`super::packet`]) and
//! its lane arithmetic ([`super::packet_lanes`]): per ray (one lane each) the shifted
//! origins and clamped inverse directions of the single-ray box test of
//! [`super::traverse`], the shear of the watertight triangle test of
//! [`crate::accel::triangles`], and the packet as a whole ([`Frustum`]) for the
//! interval test of a node's children.
//!
//! Its own module, below both users, so that the traversal and the lanes import it
//! and not each other.
//!
//! - Source: Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013),
//!   the shear; Boulos et al., "Geometric and Arithmetic Culling Methods for Entire Ray
//!   Packets" (2006), the interval bounds.

use glam::DVec3;

use super::traverse::{margin, max, min};
use crate::accel::triangles::WatertightRay;
#[cfg(target_arch = "x86_64")]
use crate::cpu::Avx512;

/// The side of a packet's block of pixels.
pub const PACKET_SIDE: usize = 4;

/// Rays per packet.
pub const PACKET: usize = PACKET_SIDE * PACKET_SIDE;

/// The axes `(x, y, z)` of the sheared frame of each axis order (see
/// [`WatertightRay::order_index`]).
const AXES: [(usize, usize, usize); 6] = [
    (1, 2, 0),
    (2, 1, 0),
    (2, 0, 1),
    (0, 2, 1),
    (0, 1, 2),
    (1, 0, 2),
];

/// Lanes of one `f64` pass of the triangle test.
pub(super) const CHUNK: usize = 8;

/// One bit per ray of a packet.
pub(super) type Mask = u32;

/// The rays of a packet prepared for the box test (per ray, as [`super::traverse`]
/// prepares one) and for the watertight triangle test.
#[derive(Clone, Debug)]
#[repr(C, align(64))]
pub struct RayPacket {
    /// Directions (`direction[axis][ray]`).
    pub(super) direction: [[f64; PACKET]; 3],
    /// Lanes holding a ray.
    pub(super) valid: Mask,
    /// The axis order all rays share, `None` when they do not (or there is no ray).
    pub(super) order: Option<u8>,
    /// Origins (`origin[axis][ray]`), for the triangle test.
    pub(super) origin: [[f64; PACKET]; 3],
    /// The shear of each ray's frame (`shear[k][ray]`, k = x, y, z of its order).
    pub(super) shear: [[f64; PACKET]; 3],
    /// Origins shifted for the lower planes of boxes (`o + δ`).
    pub(super) lower: [[f32; PACKET]; 3],
    /// Origins shifted for the upper planes of boxes (`o - δ`).
    pub(super) upper: [[f32; PACKET]; 3],
    /// `1 / direction`, clamped.
    pub(super) inv: [[f32; PACKET]; 3],
    /// The packet as a whole, for the interval test; `None` when a direction
    /// component changes sign across the rays (or is zero).
    pub(super) frustum: Option<Frustum>,
}

/// Bounds over the rays of a packet for the interval test of a node's children (see
/// the module doc): per axis, the planes the rays enter boxes through (`positive`:
/// the lower ones), the extreme shifted origins from which the smallest entry and the
/// largest exit are measured, and the range of `1 / direction`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Frustum {
    pub(super) positive: [bool; 3],
    pub(super) entry_origin: [f32; 3],
    pub(super) exit_origin: [f32; 3],
    pub(super) inv_min: [f32; 3],
    pub(super) inv_max: [f32; 3],
}

impl Frustum {
    #[inline(always)]
    pub(super) fn new(p: &RayPacket) -> Option<Self> {
        let mut f = Frustum {
            positive: [false; 3],
            entry_origin: [0.0; 3],
            exit_origin: [0.0; 3],
            inv_min: [f32::INFINITY; 3],
            inv_max: [f32::NEG_INFINITY; 3],
        };
        let mut lower_max = [f32::NEG_INFINITY; 3];
        let mut upper_min = [f32::INFINITY; 3];
        let first = p.valid.trailing_zeros() as usize;
        for k in 0..3 {
            // Lanes without a ray take the first ray's values.
            let lane = |a: &[[f32; PACKET]; 3], r: usize| {
                if p.valid >> r & 1 != 0 {
                    a[k][r]
                } else {
                    a[k][first]
                }
            };
            let (mut i0, mut i1, mut lo, mut up) = (
                [0.0f32; PACKET],
                [0.0f32; PACKET],
                [0.0f32; PACKET],
                [0.0f32; PACKET],
            );
            for r in 0..PACKET {
                (i0[r], lo[r], up[r]) = (lane(&p.inv, r), lane(&p.lower, r), lane(&p.upper, r));
                i1[r] = i0[r];
            }
            let mut width = PACKET / 2;
            while width > 0 {
                for r in 0..width {
                    i0[r] = min(i0[r], i0[r + width]);
                    i1[r] = max(i1[r], i1[r + width]);
                    lo[r] = max(lo[r], lo[r + width]);
                    up[r] = min(up[r], up[r + width]);
                }
                width /= 2;
            }
            (f.inv_min[k], f.inv_max[k], lower_max[k], upper_min[k]) = (i0[0], i1[0], lo[0], up[0]);
        }
        for k in 0..3 {
            if !(f.inv_min[k] > 0.0 || f.inv_max[k] < 0.0) {
                return None;
            }
            f.positive[k] = f.inv_min[k] > 0.0;
            (f.entry_origin[k], f.exit_origin[k]) = if f.positive[k] {
                (lower_max[k], upper_min[k])
            } else {
                (upper_min[k], lower_max[k])
            };
        }
        Some(f)
    }
}

impl Default for RayPacket {
    fn default() -> Self {
        RayPacket {
            direction: [[0.0; PACKET]; 3],
            valid: 0,
            order: None,
            origin: [[0.0; PACKET]; 3],
            shear: [[0.0; PACKET]; 3],
            lower: [[0.0; PACKET]; 3],
            upper: [[0.0; PACKET]; 3],
            inv: [[0.0; PACKET]; 3],
            frustum: None,
        }
    }
}

impl RayPacket {
    /// Prepares up to [`PACKET`] rays `(origin, direction)` for boxes whose coordinates
    /// are at most `scale` (the [`Bvh::scale`](super::Bvh::scale)). A ray that is not a ray (zero or not
    /// finite direction) gets no lane; rays beyond [`PACKET`] are ignored.
    #[must_use]
    pub fn new(rays: &[(DVec3, DVec3)], scale: f64) -> Self {
        let mut p = RayPacket::default();
        p.prepare(rays, scale);
        p
    }

    /// [`RayPacket::new`] in place, reusing this packet.
    pub fn prepare(&mut self, rays: &[(DVec3, DVec3)], scale: f64) {
        #[cfg(target_arch = "x86_64")]
        if let Some(cpu) = Avx512::new() {
            // SAFETY: `Avx512::new` checked every feature this function enables; its
            // body is safe code.
            unsafe { self.prepare_avx512(cpu, rays, scale) };
            return;
        }
        self.prepare_lanes(rays, scale);
    }

    /// [`RayPacket::prepare_lanes`] compiled for AVX-512 (the compiler vectorizes
    /// its lane loops, divisions included, eight or sixteen lanes wide).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    fn prepare_avx512(&mut self, _: Avx512, rays: &[(DVec3, DVec3)], scale: f64) {
        self.prepare_lanes(rays, scale);
    }

    /// Computes, lane by lane, what [`WatertightRay::new`] and
    /// [`BoxRay::new`](super::traverse::BoxRay::new) compute for one ray: a deliberate
    /// lane-wise twin of them (the same expressions in the same order, so the same bits;
    /// the shift of the origins calls the same `margin`), which the test
    /// `prepared_lanes_equal_single_rays` compares ray by ray.
    #[inline(always)]
    pub(super) fn prepare_lanes(&mut self, rays: &[(DVec3, DVec3)], scale: f64) {
        let n = rays.len().min(PACKET);
        for (r, &(o, d)) in rays[..n].iter().enumerate() {
            (self.origin[0][r], self.origin[1][r], self.origin[2][r]) = (o.x, o.y, o.z);
            (
                self.direction[0][r],
                self.direction[1][r],
                self.direction[2][r],
            ) = (d.x, d.y, d.z);
        }
        for k in 0..3 {
            self.origin[k][n..].fill(0.0);
            self.direction[k][n..].fill(0.0);
        }
        let (o, d) = (&self.origin, &self.direction);
        // Rays: finite, with a direction that is not zero.
        let mut valid = 0;
        let mut order = [0u8; PACKET];
        for r in 0..PACKET {
            let finite = o[0][r].is_finite()
                & o[1][r].is_finite()
                & o[2][r].is_finite()
                & d[0][r].is_finite()
                & d[1][r].is_finite()
                & d[2][r].is_finite();
            let zero = (d[0][r] == 0.0) & (d[1][r] == 0.0) & (d[2][r] == 0.0);
            valid |= Mask::from(finite & !zero) << r;
            // The axis order of `WatertightRay::new`.
            let (ax, ay, az) = (d[0][r].abs(), d[1][r].abs(), d[2][r].abs());
            let kz = if ax >= ay && ax >= az {
                0
            } else if ay >= az {
                1
            } else {
                2
            };
            order[r] = 2 * kz + u8::from(d[kz as usize][r] < 0.0);
        }
        valid &= if n == PACKET { Mask::MAX } else { (1 << n) - 1 };
        self.valid = valid;
        let first = valid.trailing_zeros() as usize;
        let coherent =
            valid != 0 && (0..PACKET).all(|r| valid >> r & 1 == 0 || order[r] == order[first]);
        self.order = coherent.then(|| order[first]);
        // Shears: with one order, lane by lane; otherwise ray by ray.
        if let Some(order) = self.order {
            let (kx, ky, kz) = AXES[order as usize];
            let (dx, dy, dz) = (&d[kx], &d[ky], &d[kz]);
            for r in 0..PACKET {
                self.shear[0][r] = dx[r] / dz[r];
                self.shear[1][r] = dy[r] / dz[r];
                self.shear[2][r] = 1.0 / dz[r];
            }
        } else {
            for r in 0..PACKET {
                let shear = self.ray(r).map_or(DVec3::ZERO, |ray| ray.shear());
                for k in 0..3 {
                    self.shear[k][r] = shear[k];
                }
            }
        }
        // Box test: shifted origins and inverse directions.
        let mut delta = [0.0f64; PACKET];
        for r in 0..PACKET {
            let (x, y, z) = (o[0][r].abs(), o[1][r].abs(), o[2][r].abs());
            // The largest of three finite numbers, whatever the order of comparisons.
            let m = if x > y { x } else { y };
            let m = if m > z { m } else { z };
            delta[r] = margin(m, scale);
        }
        for k in 0..3 {
            for r in 0..PACKET {
                self.lower[k][r] = (o[k][r] + delta[r]) as f32;
                self.upper[k][r] = (o[k][r] - delta[r]) as f32;
                let inv = 1.0 / d[k][r];
                let inv = if inv < -1e30 { -1e30 } else { inv };
                let inv = if inv > 1e30 { 1e30 } else { inv };
                self.inv[k][r] = inv as f32;
            }
        }
        self.frustum = if valid != 0 { Frustum::new(self) } else { None };
    }

    /// The prepared ray of lane `r`, if there is one.
    #[must_use]
    pub fn ray(&self, r: usize) -> Option<WatertightRay> {
        if r >= PACKET || self.valid >> r & 1 == 0 {
            return None;
        }
        let v = |a: &[[f64; PACKET]; 3]| DVec3::new(a[0][r], a[1][r], a[2][r]);
        WatertightRay::new(v(&self.origin), v(&self.direction))
    }

    /// Whether all rays share one axis order (the packet is traced as a packet).
    #[must_use]
    pub fn is_coherent(&self) -> bool {
        self.order.is_some()
    }
}
