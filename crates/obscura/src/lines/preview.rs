//! A PNG preview of a [`Plot`]: its polylines rasterised at the picture's size, black
//! on white, hidden lines grey (dashed, solid or left out as in the SVG).
//!
//! Each segment is drawn as a capsule of the stroke width: a pixel's coverage is
//! `clamp(width / 2 + 0.5 - d, 0, 1)` with `d` the distance from its centre to the
//! segment (a one-pixel linear ramp at the edge), or 0 or 1 without antialiasing.
//! Coverage is kept per layer as the maximum over its segments, so joints are not drawn
//! darker; the hidden layer goes under the visible one. Only the pixels of each row
//! that the capsule can touch are visited.

use std::path::Path;

use glam::DVec2;

use crate::clip::liang_barsky::clip_segment_2d;
use crate::clip::window::Rect;

use super::plot::{Plot, Polyline};
use super::svg::HiddenStyle;
use crate::{Result, RgbImage};

/// Options of [`render`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct PreviewOptions {
    /// How hidden lines are drawn.
    pub hidden: HiddenStyle,
    /// Stroke width in pixels.
    pub stroke_width: f64,
    /// Smooth edges.
    pub antialias: bool,
}

impl Default for PreviewOptions {
    fn default() -> Self {
        PreviewOptions {
            hidden: HiddenStyle::None,
            stroke_width: 1.0,
            antialias: true,
        }
    }
}

impl PreviewOptions {
    /// These options with another hidden-line style.
    #[must_use]
    pub fn with_hidden(mut self, hidden: HiddenStyle) -> Self {
        self.hidden = hidden;
        self
    }

    /// These options with another stroke width (pixels).
    #[must_use]
    pub fn with_stroke_width(mut self, width: f64) -> Self {
        self.stroke_width = width;
        self
    }

    /// These options with antialiasing on or off.
    #[must_use]
    pub fn with_antialias(mut self, antialias: bool) -> Self {
        self.antialias = antialias;
        self
    }
}

/// Dash and gap lengths of dashed hidden lines in the preview, pixels.
const DASH: [f64; 2] = [6.0, 4.0];

/// The preview image (the picture's size).
pub fn render(plot: &Plot, options: &PreviewOptions) -> Result<RgbImage> {
    let w = options.stroke_width;
    if !(w.is_finite() && w > 0.0 && w <= 1000.0) {
        return Err(crate::Error::option(
            "stroke",
            format!("{w} px: give a stroke width from above 0 to 1000 pixels"),
        ));
    }
    let (width, height) = (plot.width, plot.height);
    let mut image = RgbImage::new(width, height);
    image.pixels.fill([255; 3]);
    let n = width as usize * height as usize;
    // Dashes are cut only inside the picture (and a stroke's width around it): a
    // segment of a drawing read back from JSON may be any length.
    let pad = w + 1.0;
    let area = Rect::new(-pad, -pad, f64::from(width) + pad, f64::from(height) + pad)
        .map_err(|_| crate::Error::option("preview", "picture size out of range"))?;
    let mut layers: Vec<(Vec<f32>, [u8; 3])> = Vec::new();
    if options.hidden != HiddenStyle::None {
        let mut cover = vec![0f32; n];
        for l in &plot.hidden {
            for [a, b] in segments(l, options.hidden == HiddenStyle::Dashed, &area) {
                stroke(&mut cover, width, height, a, b, w, options.antialias);
            }
        }
        layers.push((cover, [128; 3]));
    }
    let mut cover = vec![0f32; n];
    for l in &plot.visible {
        for [a, b] in segments(l, false, &area) {
            stroke(&mut cover, width, height, a, b, w, options.antialias);
        }
    }
    layers.push((cover, [0; 3]));
    for (cover, colour) in &layers {
        for (px, &c) in image.pixels.iter_mut().zip(cover) {
            if c > 0.0 {
                for k in 0..3 {
                    let v = f32::from(px[k]) * (1.0 - c) + f32::from(colour[k]) * c;
                    px[k] = v.round().clamp(0.0, 255.0) as u8;
                }
            }
        }
    }
    Ok(image)
}

/// Renders the preview and writes it as a PNG file.
pub fn write_png(plot: &Plot, options: &PreviewOptions, path: &Path) -> Result<()> {
    render(plot, options)?.write_png(path)
}

/// The segments of a polyline, cut into dashes when asked (dashes run on across the
/// polyline's joints). Dashes are made only for the part of a segment inside `area`;
/// the part outside still advances the dash pattern.
fn segments(line: &Polyline, dashed: bool, area: &Rect) -> Vec<[DVec2; 2]> {
    let pairs = line.points.windows(2).map(|w| [w[0], w[1]]);
    if !dashed {
        return pairs.collect();
    }
    let period = DASH[0] + DASH[1];
    let mut out = Vec::new();
    let mut phase = 0.0f64; // position within the period at the segment's start
    for [a0, b0] in pairs {
        let full = a0.distance(b0);
        if !(full > 0.0) {
            continue;
        }
        let Some((a, b)) = clip_segment_2d(a0, b0, area) else {
            phase = (phase + full) % period;
            continue;
        };
        phase = (phase + a0.distance(a)) % period;
        let len = a.distance(b);
        let mut s = 0.0;
        while s < len {
            let in_dash = phase < DASH[0];
            let step = if in_dash {
                DASH[0] - phase
            } else {
                period - phase
            }
            .min(len - s);
            if in_dash {
                out.push([a.lerp(b, s / len), a.lerp(b, (s + step) / len)]);
            }
            s += step;
            phase = (phase + step) % period;
        }
        phase = (phase + b.distance(b0)) % period;
    }
    out
}

/// Adds a capsule of width `w` from `a` to `b` to the coverage `cover` (max).
fn stroke(cover: &mut [f32], width: u32, height: u32, a: DVec2, b: DVec2, w: f64, aa: bool) {
    // Pixel centres at (x + 0.5, y + 0.5); the capsule reaches r from the segment.
    let r = if aa {
        w / 2.0 + 0.5
    } else {
        (w / 2.0).max(0.5)
    };
    let d = b - a;
    let len2 = d.length_squared();
    let y0 = ((a.y.min(b.y) - r - 0.5).floor().max(0.0)) as i64;
    let y1 = ((a.y.max(b.y) + r - 0.5).ceil().min(f64::from(height) - 1.0)) as i64;
    for y in y0..=y1 {
        let yc = y as f64 + 0.5;
        // The part of the segment within r of this row's centre line.
        let (t0, t1) = if d.y.abs() < 1e-12 {
            if (a.y - yc).abs() > r {
                continue;
            }
            (0.0, 1.0)
        } else {
            let (ta, tb) = ((yc - r - a.y) / d.y, (yc + r - a.y) / d.y);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        };
        if t0 > t1 {
            continue;
        }
        let (xa, xb) = (a.x + d.x * t0, a.x + d.x * t1);
        let x0 = ((xa.min(xb) - r - 0.5).floor().max(0.0)) as i64;
        let x1 = ((xa.max(xb) + r - 0.5).ceil().min(f64::from(width) - 1.0)) as i64;
        for x in x0..=x1 {
            let p = DVec2::new(x as f64 + 0.5, yc);
            let t = if len2 > 0.0 {
                ((p - a).dot(d) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let dist = p.distance(a + d * t);
            let c = if aa {
                (w / 2.0 + 0.5 - dist).clamp(0.0, 1.0)
            } else if dist <= r {
                1.0
            } else {
                0.0
            };
            let cell = &mut cover[y as usize * width as usize + x as usize];
            *cell = cell.max(c as f32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot_of(lines: Vec<Vec<(f64, f64)>>, hidden: Vec<Vec<(f64, f64)>>) -> Plot {
        let conv = |v: Vec<Vec<(f64, f64)>>| {
            v.into_iter()
                .map(|l| Polyline {
                    points: l.into_iter().map(|(x, y)| DVec2::new(x, y)).collect(),
                })
                .collect()
        };
        Plot {
            width: 20,
            height: 10,
            visible: conv(lines),
            hidden: conv(hidden),
        }
    }

    #[test]
    fn dashes_are_cut_only_inside_the_picture() {
        // A segment of 1e18 px (as a drawing read back from JSON may hold) crossing the
        // 20 x 10 picture: dashes only where it can show, the pattern kept in phase.
        let area = Rect::new(-2.0, -2.0, 22.0, 12.0).unwrap();
        let far = Polyline {
            points: vec![DVec2::new(-1e18, 5.0), DVec2::new(1e18, 5.0)],
        };
        let d = segments(&far, true, &area);
        assert!(d.len() <= 4, "{d:?}");
        assert!(d.iter().flatten().all(|p| p.x >= -2.0 && p.x <= 22.0));
        // At 1e9 px the clipped part is still exact enough to be dashed.
        let long = Polyline {
            points: vec![DVec2::new(-1e9, 5.0), DVec2::new(1e9, 5.0)],
        };
        let d = segments(&long, true, &area);
        assert!((2..=4).contains(&d.len()), "{d:?}");
        assert!(
            d.iter()
                .flatten()
                .all(|p| p.x >= -2.0 - 1e-6 && p.x <= 22.0 + 1e-6)
        );
        // Inside the picture, the same dashes as the segment cut to it beforehand.
        let near = Polyline {
            points: vec![DVec2::new(-2.0, 5.0), DVec2::new(22.0, 5.0)],
        };
        let whole = Polyline {
            points: vec![DVec2::new(-12.0, 5.0), DVec2::new(22.0, 5.0)],
        };
        let (a, b) = (segments(&near, true, &area), segments(&whole, true, &area));
        let period = DASH[0] + DASH[1];
        assert_eq!(10.0 % period, 0.0, "the test shifts by whole periods");
        assert_eq!(a, b);
    }

    #[test]
    fn a_horizontal_line_darkens_exactly_its_row() {
        // Along y = 4.5 (the centres of row 4), one pixel wide, without antialiasing:
        // the pixels whose centres are within half a pixel of it (round caps reach
        // the centres 1.5 and 18.5).
        let p = plot_of(vec![vec![(2.0, 4.5), (18.0, 4.5)]], vec![]);
        let img = render(&p, &PreviewOptions::default().with_antialias(false)).unwrap();
        for y in 0..10u32 {
            for x in 0..20u32 {
                let px = img.pixels[(y * 20 + x) as usize];
                let on = y == 4 && (1..=18).contains(&x);
                assert_eq!(px == [0; 3], on, "pixel {x},{y}: {px:?}");
            }
        }
        // Antialiased, a line on a row boundary (y = 5) covers rows 4 and 5 by half.
        let p = plot_of(vec![vec![(2.0, 5.0), (18.0, 5.0)]], vec![]);
        let img = render(&p, &PreviewOptions::default()).unwrap();
        let at = |x: u32, y: u32| img.pixels[(y * 20 + x) as usize][0];
        assert_eq!((at(10, 4), at(10, 5), at(10, 3)), (128, 128, 255));
    }

    #[test]
    fn hidden_lines_follow_the_style() {
        let p = plot_of(vec![], vec![vec![(0.0, 4.5), (20.0, 4.5)]]);
        let row = |style| {
            let img = render(
                &p,
                &PreviewOptions::default()
                    .with_hidden(style)
                    .with_antialias(false),
            )
            .unwrap();
            (0..20).map(|x| img.pixels[80 + x][0]).collect::<Vec<u8>>()
        };
        assert!(row(HiddenStyle::None).iter().all(|&v| v == 255));
        assert!(row(HiddenStyle::Solid).iter().all(|&v| v == 128));
        // Dashes of 6 px, gaps of 4: [0, 6] and [10, 16], which reach the pixel
        // centres within half a pixel: pixels 0..=6 and 9..=16 grey.
        let dashed = row(HiddenStyle::Dashed);
        for (x, &v) in dashed.iter().enumerate() {
            let want = if x <= 6 || (9..=16).contains(&x) {
                128
            } else {
                255
            };
            assert_eq!(v, want, "pixel {x}: {dashed:?}");
        }
    }

    #[test]
    fn bad_stroke_widths_are_refused() {
        let p = plot_of(vec![], vec![]);
        for w in [0.0, -1.0, f64::NAN, 1e9] {
            assert!(render(&p, &PreviewOptions::default().with_stroke_width(w)).is_err());
        }
    }
}
