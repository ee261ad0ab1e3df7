//! The fast z-buffer's drawing loop: polygons of a view drawn into a band of rows of the
//! frame, with the kernels compiled for the processor's vector extensions.
//!
//! The band's depth array holds negated `f32` keys (see [`crate::raster::depth_span`])
//! until [`keys_to_depths`] turns them into eye-space depths.

use crate::Frame;
use crate::frame::BACKGROUND;
use crate::raster::kernel::{DepthTarget, Portable, RasterKernel, is_narrow};
#[cfg(target_arch = "x86_64")]
use crate::raster::simd::Avx2;
use crate::raster::{DepthPlane, EdgeFunction, FillRule, PixelRect, PolygonSetup, TriangleSetup};
use crate::view::{PreparedView, ViewTransform};

use super::Counts;

/// Which compiled variant of the drawing kernels to run. Every variant is the same
/// source compiled with different instruction sets: they give identical frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// Baseline instructions of the target (SSE2 on x86-64); always available.
    Portable,
    /// x86-64 with AVX2 (4 doubles or 8 floats per instruction).
    Avx2,
    /// x86-64 with AVX-512 F, VL, BW and DQ (8 doubles or 16 floats per instruction).
    Avx512,
}

impl Kernel {
    /// The fastest kernel this processor runs.
    #[must_use]
    pub fn detect() -> Kernel {
        [Kernel::Avx512, Kernel::Avx2]
            .into_iter()
            .find(|k| k.is_available())
            .unwrap_or(Kernel::Portable)
    }

    /// Whether this processor runs the kernel.
    #[must_use]
    pub fn is_available(self) -> bool {
        match self {
            Kernel::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => Avx2::new().is_some(),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => {
                Avx2::new().is_some()
                    && std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                    && std::arch::is_x86_feature_detected!("avx512bw")
                    && std::arch::is_x86_feature_detected!("avx512dq")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }
}

/// Rows `y0..y1` of a frame: the keys (negated, see the module doc) and ids.
pub(super) struct Band<'a> {
    pub target: DepthTarget<'a>,
    pub y1: u32,
    pub width: u32,
    pub height: u32,
}

/// Draws the rows of the band of one set-up polygon: narrow ones by masks of their
/// columns, wide ones by row spans.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn draw_polygon<K: RasterKernel>(
    kernel: K,
    band: &mut Band<'_>,
    c: &mut Counts,
    edges: &[EdgeFunction],
    rect: PixelRect,
    plane: Option<DepthPlane>,
    face: u32,
) {
    let Some(plane) = plane else {
        return;
    };
    let y0 = band.target.y0;
    // A polygon spanning several bands is counted by the band of its first row.
    if rect.y0 >= y0 && rect.y0 < band.y1 {
        c.drawn += 1;
    }
    let rows = rect.y0.max(y0)..rect.y1.min(band.y1);
    if rows.is_empty() {
        return;
    }
    let s = if is_narrow(edges, rect) {
        kernel.draw_narrow(edges, rect, rows, &plane, &mut band.target, face)
    } else {
        kernel.draw_wide(edges, rect, rows, &plane, &mut band.target, face)
    };
    c.tested += s.tested;
    c.written += s.written;
}

/// Draws polygons `polygons` (indices into the view, ascending) into the band.
#[inline(always)]
fn draw_band_impl<K: RasterKernel>(
    kernel: K,
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
) -> Counts {
    let (starts, indices, faces) = view.polygon_arrays();
    let vertices = view.vertices();
    let (width, height) = (band.width, band.height);
    let mut polygon = PolygonSetup::<16>::new();
    let mut points = [(0.0, 0.0, 0.0); 16];
    let mut c = Counts::default();
    for p in polygons {
        let (s, e) = (starts[p] as usize, starts[p + 1] as usize);
        let face = faces[p];
        let point = |i: u32| {
            let v = &vertices[i as usize];
            (v.x, v.y, v.zq)
        };
        if let &[a, b, d] = &indices[s..e] {
            let Some(t) = TriangleSetup::new([point(a), point(b), point(d)], fill, width, height)
            else {
                continue;
            };
            draw_polygon(kernel, band, &mut c, &t.edges, t.rect, Some(t.plane), face);
        } else if PolygonSetup::<16>::fits(e - s) {
            let n = e - s;
            for (q, &i) in points.iter_mut().zip(&indices[s..e]) {
                *q = point(i);
            }
            if !polygon.set(&points[..n], fill, width, height) {
                continue;
            }
            let t = &polygon;
            draw_polygon(
                kernel,
                band,
                &mut c,
                t.edges(),
                t.rect(),
                t.depth_plane(),
                face,
            );
        } else {
            // Rare: more than 16 vertices. The shared coverage, with its allocations.
            let poly = view.polygon(p);
            let Some(cov) = poly.coverage(fill, width, height) else {
                continue;
            };
            draw_polygon(
                kernel,
                band,
                &mut c,
                cov.edges(),
                cov.rect(),
                poly.depth_plane(),
                face,
            );
        }
    }
    c
}

fn draw_band_portable(
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
) -> Counts {
    draw_band_impl(Portable, view, polygons, fill, band)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn draw_band_avx2(
    kernel: Avx2,
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
) -> Counts {
    draw_band_impl(kernel, view, polygons, fill, band)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt,avx512f,avx512vl,avx512bw,avx512dq")]
fn draw_band_avx512(
    kernel: Avx2,
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    band: &mut Band<'_>,
) -> Counts {
    draw_band_impl(kernel, view, polygons, fill, band)
}

/// Draws `polygons` into the band with the kernel (the portable one if the processor
/// lacks the kernel's instructions).
pub(super) fn draw_band(
    view: &PreparedView<'_>,
    polygons: impl Iterator<Item = usize>,
    fill: FillRule,
    kernel: Kernel,
    band: &mut Band<'_>,
) -> Counts {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = Avx2::new() {
        match kernel {
            // SAFETY: `Avx2::new` checked AVX2, POPCNT, BMI1 and LZCNT.
            Kernel::Avx2 => return unsafe { draw_band_avx2(avx2, view, polygons, fill, band) },
            // SAFETY: the same, and AVX-512 F, VL, BW and DQ just checked.
            Kernel::Avx512 if kernel.is_available() => {
                return unsafe { draw_band_avx512(avx2, view, polygons, fill, band) };
            }
            _ => {}
        }
    }
    draw_band_portable(view, polygons, fill, band)
}

/// Draws every polygon of the view into the whole frame on this thread.
pub(super) fn draw_all(
    view: &PreparedView<'_>,
    fill: FillRule,
    kernel: Kernel,
    frame: &mut Frame,
) -> Counts {
    let mut band = Band {
        target: DepthTarget {
            keys: &mut frame.depth,
            ids: &mut frame.ids,
            width: frame.width as usize,
            y0: 0,
        },
        y1: frame.height,
        width: frame.width,
        height: frame.height,
    };
    draw_band(view, 0..view.polygon_count(), fill, kernel, &mut band)
}

/// Turns the negated keys of a drawn frame into eye-space depths (`+inf` where the id
/// is the background), as the reference does.
#[inline(always)]
fn keys_to_depths_impl(t: &ViewTransform, depth: &mut [f32], ids: &[u32]) {
    let (near, far) = (t.near, t.far);
    if t.orthographic {
        for (d, &id) in depth.iter_mut().zip(ids) {
            let z = f64::from(-*d);
            let v = (far - z * (far - near)) as f32;
            *d = if id != BACKGROUND { v } else { f32::INFINITY };
        }
    } else {
        for (d, &id) in depth.iter_mut().zip(ids) {
            let v = (near / f64::from(-*d)) as f32;
            *d = if id != BACKGROUND { v } else { f32::INFINITY };
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn keys_to_depths_avx2(t: &ViewTransform, depth: &mut [f32], ids: &[u32]) {
    keys_to_depths_impl(t, depth, ids);
}

/// Converts rows of keys to depths with the kernel.
pub(super) fn keys_to_depths_rows(
    t: &ViewTransform,
    kernel: Kernel,
    depth: &mut [f32],
    ids: &[u32],
) {
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: both kernels imply AVX2, checked just before the call.
        Kernel::Avx2 | Kernel::Avx512 if Kernel::Avx2.is_available() => unsafe {
            keys_to_depths_avx2(t, depth, ids);
        },
        _ => keys_to_depths_impl(t, depth, ids),
    }
}

/// Converts a whole frame's keys to depths.
pub(super) fn keys_to_depths(t: &ViewTransform, kernel: Kernel, frame: &mut Frame) {
    keys_to_depths_rows(t, kernel, &mut frame.depth, &frame.ids);
}
