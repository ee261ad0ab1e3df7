//! SVG output of a [`Plot`] (the joined and ordered polylines of a
//! [`super::Drawing`]), for people and pen plotters.
//!
//! # Units and page
//! - **Pixels** ([`SvgOptions::page`] `None`): `width` and `height` are the picture's
//!   pixels, the `viewBox` is `0 0 width height`, one user unit is one pixel and the
//!   coordinates are the drawing's own.
//! - **Millimetres on a page** ([`PageLayout`]): `width="210mm" height="297mm"
//!   viewBox="0 0 210 297"`, so one user unit is one millimetre. The lines' bounding box
//!   ([`Fit::Lines`], the default) or the whole picture ([`Fit::Picture`]) is scaled,
//!   aspect kept, to fill the page inside its margins, and centred. Pages: `A4` (210 x 297
//!   mm), `A3` (297 x 420), `letter` (215.9 x 279.4) or `WxHmm`; named pages turn to the
//!   drawing's orientation unless one is asked for ([`Orientation`]).
//!
//! # Layers
//! Visible and hidden lines go on two Inkscape layers (`<g inkscape:groupmode="layer">`):
//! `id="layer1" inkscape:label="1-visible"` and `id="layer2" inkscape:label="2-hidden"`
//! (left out when hidden lines are). The labels begin with the layer's number because
//! that is how the AxiDraw software selects layers (a layer name starting with an
//! integer is that layer's number for "plot only layer N"; names starting with `%` are
//! not plotted) and how vpype's `read` numbers them (the label stripped of everything
//! but digits, then the `id`). Each polyline is one `<path d="M x,y L x,y ...">`, drawn
//! in the order [`super::plot::plot`] chose; stroke, colour and dashes are attributes of
//! the layer group (visible black, hidden grey).
//!
//! # Hidden lines
//! [`HiddenStyle::None`] leaves them out, [`HiddenStyle::Dashed`] gives their layer a
//! `stroke-dasharray` (browsers and Inkscape show dashes; plotter software draws the
//! paths solid, since it follows geometry, not stroke styles),
//! [`HiddenStyle::Solid`] draws them solid and grey.

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec2;

use super::plot::Plot;
use crate::{Error, Result};

/// How hidden lines are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HiddenStyle {
    /// Left out.
    #[default]
    None,
    /// Dashed (a `stroke-dasharray` on their layer).
    Dashed,
    /// Solid, grey.
    Solid,
}

impl std::str::FromStr for HiddenStyle {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "none" => Ok(HiddenStyle::None),
            "dashed" => Ok(HiddenStyle::Dashed),
            "solid" => Ok(HiddenStyle::Solid),
            other => Err(Error::option(
                "hidden",
                format!("unknown style \"{other}\" (expected none, dashed or solid)"),
            )),
        }
    }
}

/// A sheet of paper in millimetres (portrait as named: width <= height for A4, A3,
/// letter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Page {
    /// Width in millimetres.
    pub width_mm: f64,
    /// Height in millimetres.
    pub height_mm: f64,
    /// Whether it was named (A4, A3, letter): a named page turns to the drawing's
    /// orientation under [`Orientation::Auto`]; a size given as `WxHmm` is kept.
    pub named: bool,
}

impl Page {
    /// ISO A4, 210 x 297 mm.
    pub const A4: Page = Page {
        width_mm: 210.0,
        height_mm: 297.0,
        named: true,
    };
    /// ISO A3, 297 x 420 mm.
    pub const A3: Page = Page {
        width_mm: 297.0,
        height_mm: 420.0,
        named: true,
    };
    /// US letter, 8.5 x 11 in.
    pub const LETTER: Page = Page {
        width_mm: 215.9,
        height_mm: 279.4,
        named: true,
    };

    /// Parses `A4`, `A3`, `letter` (any case) or `WxHmm` (e.g. `300x200mm`; the `mm` may
    /// be left out).
    ///
    /// ```
    /// use obscura::lines::svg::Page;
    /// assert_eq!(Page::parse("a4").unwrap(), Page::A4);
    /// let p = Page::parse("300x200mm").unwrap();
    /// assert_eq!((p.width_mm, p.height_mm), (300.0, 200.0));
    /// assert!(Page::parse("A5").is_err() && Page::parse("0x10mm").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<Page> {
        let t = s.trim().to_ascii_lowercase();
        match t.as_str() {
            "a4" => return Ok(Page::A4),
            "a3" => return Ok(Page::A3),
            "letter" => return Ok(Page::LETTER),
            _ => {}
        }
        let bad = || {
            Error::option(
                "page",
                format!(
                    "\"{s}\": give A4, A3, letter or WIDTHxHEIGHTmm with sizes from 1 to \
                     10000 mm, e.g. 300x200mm"
                ),
            )
        };
        let body = t.strip_suffix("mm").unwrap_or(&t);
        let (w, h) = body.split_once('x').ok_or_else(bad)?;
        let num = |v: &str| match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() && (1.0..=10_000.0).contains(&x) => Ok(x),
            _ => Err(bad()),
        };
        Ok(Page {
            width_mm: num(w)?,
            height_mm: num(h)?,
            named: false,
        })
    }
}

/// Which way up the page is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Orientation {
    /// A named page turned to the drawing's orientation; a `WxHmm` page as given.
    #[default]
    Auto,
    /// Taller than wide.
    Portrait,
    /// Wider than tall.
    Landscape,
}

impl std::str::FromStr for Orientation {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Orientation::Auto),
            "portrait" => Ok(Orientation::Portrait),
            "landscape" => Ok(Orientation::Landscape),
            other => Err(Error::option(
                "orientation",
                format!("unknown orientation \"{other}\" (expected auto, portrait or landscape)"),
            )),
        }
    }
}

/// What is fitted to the page.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fit {
    /// The bounding box of the lines (visible and hidden, as drawn).
    #[default]
    Lines,
    /// The whole picture, `0..width` by `0..height` pixels.
    Picture,
}

/// A drawing placed on a page in millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct PageLayout {
    /// The sheet.
    pub page: Page,
    /// Which way up.
    pub orientation: Orientation,
    /// Margin on every side, millimetres.
    pub margin_mm: f64,
    /// What is fitted inside the margins.
    pub fit: Fit,
}

impl PageLayout {
    /// A page with 10 mm margins, turned to the drawing, fitted to its lines.
    #[must_use]
    pub fn new(page: Page) -> Self {
        PageLayout {
            page,
            orientation: Orientation::Auto,
            margin_mm: 10.0,
            fit: Fit::Lines,
        }
    }

    /// This layout with another margin (millimetres).
    #[must_use]
    pub fn with_margin(mut self, margin_mm: f64) -> Self {
        self.margin_mm = margin_mm;
        self
    }

    /// This layout with another orientation.
    #[must_use]
    pub fn with_orientation(mut self, orientation: Orientation) -> Self {
        self.orientation = orientation;
        self
    }

    /// This layout fitting another box.
    #[must_use]
    pub fn with_fit(mut self, fit: Fit) -> Self {
        self.fit = fit;
        self
    }

    /// Where the plot's pixels land on the page: the page size and the map from
    /// pixels to millimetres. Errors: margins that leave no room, a negative or
    /// non-finite margin.
    pub fn place(&self, plot: &Plot) -> Result<Placement> {
        let m = self.margin_mm;
        let picture = (
            DVec2::ZERO,
            DVec2::new(f64::from(plot.width), f64::from(plot.height)),
        );
        let (lo, hi) = match self.fit {
            Fit::Lines => plot.bounds().unwrap_or(picture),
            Fit::Picture => picture,
        };
        let size = hi - lo;
        let (pw, ph) = (self.page.width_mm, self.page.height_mm);
        let (short, long) = (pw.min(ph), pw.max(ph));
        let (w, h) = match self.orientation {
            Orientation::Portrait => (short, long),
            Orientation::Landscape => (long, short),
            Orientation::Auto if self.page.named => {
                if size.x > size.y {
                    (long, short)
                } else {
                    (short, long)
                }
            }
            Orientation::Auto => (pw, ph),
        };
        if !(m.is_finite() && m >= 0.0) {
            return Err(Error::option(
                "margin",
                format!("{m} mm: give zero or a positive number of millimetres"),
            ));
        }
        let (aw, ah) = (w - 2.0 * m, h - 2.0 * m);
        if !(aw > 0.0 && ah > 0.0) {
            return Err(Error::option(
                "margin",
                format!(
                    "{m} mm on each side of a {w} x {h} mm page leaves no room to draw: give \
                     less than {} mm",
                    w.min(h) / 2.0
                ),
            ));
        }
        // Aspect kept: the axis that fills first decides; a box flat along one axis
        // (a single horizontal line) is scaled by the other.
        let sx = if size.x > 0.0 {
            aw / size.x
        } else {
            f64::INFINITY
        };
        let sy = if size.y > 0.0 {
            ah / size.y
        } else {
            f64::INFINITY
        };
        let scale = match sx.min(sy) {
            s if s.is_finite() => s,
            _ => 1.0,
        };
        let centre = DVec2::new(w, h) / 2.0;
        let offset = centre - (lo + hi) / 2.0 * scale;
        Ok(Placement {
            width_mm: w,
            height_mm: h,
            scale,
            offset,
        })
    }
}

/// A plot's pixels on a page: `mm = px * scale + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Page width, millimetres (after orientation).
    pub width_mm: f64,
    /// Page height, millimetres.
    pub height_mm: f64,
    /// Millimetres per pixel.
    pub scale: f64,
    /// Where pixel (0, 0) lands, millimetres.
    pub offset: DVec2,
}

impl Placement {
    /// A pixel position on the page.
    #[must_use]
    pub fn apply(&self, p: DVec2) -> DVec2 {
        p * self.scale + self.offset
    }
}

/// Options of [`to_string`] and [`write`](fn@write).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct SvgOptions {
    /// `None`: pixels; else millimetres on this page.
    pub page: Option<PageLayout>,
    /// How hidden lines are drawn.
    pub hidden: HiddenStyle,
    /// Stroke width in user units (pixels, or millimetres on a page); `None`: 1 px, or
    /// 0.3 mm (a fine pen).
    pub stroke_width: Option<f64>,
    /// Decimals of the coordinates; `None`: 2 in pixels, 3 in millimetres (1 µm).
    pub precision: Option<u8>,
}

impl Default for SvgOptions {
    fn default() -> Self {
        SvgOptions {
            page: None,
            hidden: HiddenStyle::None,
            stroke_width: None,
            precision: None,
        }
    }
}

impl SvgOptions {
    /// These options in millimetres on a page.
    #[must_use]
    pub fn with_page(mut self, page: PageLayout) -> Self {
        self.page = Some(page);
        self
    }

    /// These options with another hidden-line style.
    #[must_use]
    pub fn with_hidden(mut self, hidden: HiddenStyle) -> Self {
        self.hidden = hidden;
        self
    }

    /// These options with a stroke width in user units.
    #[must_use]
    pub fn with_stroke_width(mut self, width: f64) -> Self {
        self.stroke_width = Some(width);
        self
    }

    /// These options with a number of decimals.
    #[must_use]
    pub fn with_precision(mut self, decimals: u8) -> Self {
        self.precision = Some(decimals);
        self
    }
}

/// The stroke width and decimals in effect.
fn effective(options: &SvgOptions) -> Result<(f64, usize)> {
    let mm = options.page.is_some();
    let w = options.stroke_width.unwrap_or(if mm { 0.3 } else { 1.0 });
    if !(w.is_finite() && w > 0.0) {
        return Err(Error::option(
            "stroke",
            format!("{w}: give a positive stroke width"),
        ));
    }
    let p = options.precision.unwrap_or(if mm { 3 } else { 2 });
    if p > 12 {
        return Err(Error::option(
            "precision",
            format!("{p} decimals: give 0 to 12"),
        ));
    }
    Ok((w, usize::from(p)))
}

/// A number with at most `decimals` decimals, trailing zeros left out.
fn number(out: &mut String, x: f64, decimals: usize) {
    let start = out.len();
    let _ = write!(out, "{x:.decimals$}");
    if decimals > 0 {
        while out.ends_with('0') {
            out.pop();
        }
        if out.ends_with('.') {
            out.pop();
        }
    }
    if &out[start..] == "-0" {
        out.replace_range(start.., "0");
    }
}

/// The SVG document of a plot.
///
/// ```
/// use glam::DVec2;
/// use obscura::lines::plot::{Plot, Polyline};
/// use obscura::lines::svg::{to_string, SvgOptions};
/// let plot = Plot {
///     width: 100,
///     height: 50,
///     visible: vec![Polyline { points: vec![DVec2::new(10.0, 10.0), DVec2::new(90.0, 40.0)] }],
///     hidden: vec![],
/// };
/// let svg = to_string(&plot, &SvgOptions::default())?;
/// assert!(svg.contains(r#"viewBox="0 0 100 50""#) && svg.contains("M10,10 L90,40"));
/// # Ok::<(), obscura::Error>(())
/// ```
pub fn to_string(plot: &Plot, options: &SvgOptions) -> Result<String> {
    let (stroke, decimals) = effective(options)?;
    let placement = options.page.map(|l| l.place(plot)).transpose()?;
    let mut s = String::with_capacity(
        64 * (plot.visible.len() + plot.hidden.len())
            + 24 * plot
                .visible
                .iter()
                .chain(&plot.hidden)
                .map(|l| l.points.len())
                .sum::<usize>()
            + 1024,
    );
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n");
    s.push_str(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" \
         xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\" version=\"1.1\"",
    );
    match &placement {
        Some(p) => {
            s.push_str(" width=\"");
            number(&mut s, p.width_mm, 3);
            s.push_str("mm\" height=\"");
            number(&mut s, p.height_mm, 3);
            s.push_str("mm\" viewBox=\"0 0 ");
            number(&mut s, p.width_mm, 3);
            s.push(' ');
            number(&mut s, p.height_mm, 3);
            s.push_str("\">\n");
        }
        None => {
            let _ = writeln!(
                s,
                " width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">",
                w = plot.width,
                h = plot.height
            );
        }
    }
    s.push_str("<title>obscura lines</title>\n");
    let layer = |s: &mut String,
                 number_id: u32,
                 label: &str,
                 colour: &str,
                 dash: bool,
                 lines: &[super::plot::Polyline]| {
        let _ = write!(
            s,
            "<g inkscape:groupmode=\"layer\" id=\"layer{number_id}\" \
             inkscape:label=\"{number_id}-{label}\" fill=\"none\" stroke=\"{colour}\" \
             stroke-width=\""
        );
        number(s, stroke, 6);
        s.push_str("\" stroke-linecap=\"round\" stroke-linejoin=\"round\"");
        if dash {
            s.push_str(" stroke-dasharray=\"");
            number(s, 4.0 * stroke, 6);
            s.push(' ');
            number(s, 3.0 * stroke, 6);
            s.push('"');
        }
        s.push_str(">\n");
        for l in lines {
            s.push_str("<path d=\"M");
            for (k, &p) in l.points.iter().enumerate() {
                let q = placement.as_ref().map_or(p, |pl| pl.apply(p));
                if k == 1 {
                    s.push_str(" L");
                } else if k > 1 {
                    s.push(' ');
                }
                number(s, q.x, decimals);
                s.push(',');
                number(s, q.y, decimals);
            }
            s.push_str("\"/>\n");
        }
        s.push_str("</g>\n");
    };
    layer(&mut s, 1, "visible", "#000000", false, &plot.visible);
    match options.hidden {
        HiddenStyle::None => {}
        HiddenStyle::Dashed => layer(&mut s, 2, "hidden", "#808080", true, &plot.hidden),
        HiddenStyle::Solid => layer(&mut s, 2, "hidden", "#808080", false, &plot.hidden),
    }
    s.push_str("</svg>\n");
    Ok(s)
}

/// Writes the SVG document of a plot to a file.
pub fn write(plot: &Plot, options: &SvgOptions, path: &Path) -> Result<()> {
    let text = to_string(plot, options)?;
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests;
