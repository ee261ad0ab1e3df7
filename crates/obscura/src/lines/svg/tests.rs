use glam::DVec2;

use super::*;
use crate::lines::plot::Polyline;

const INKSCAPE: &str = "http://www.inkscape.org/namespaces/inkscape";

fn line(points: &[(f64, f64)]) -> Polyline {
    Polyline {
        points: points.iter().map(|&(x, y)| DVec2::new(x, y)).collect(),
    }
}

/// A 400 x 300 picture: a visible triangle and a hidden stroke.
fn sample() -> Plot {
    Plot {
        width: 400,
        height: 300,
        visible: vec![
            line(&[(100.0, 50.0), (300.0, 50.0), (200.0, 250.0), (100.0, 50.0)]),
            line(&[(120.5, 60.25), (130.125, 70.0)]),
        ],
        hidden: vec![line(&[(150.0, 100.0), (250.0, 100.0)])],
    }
}

/// Attributes as (name, value).
type Attributes = Vec<(String, String)>;

/// The layers: (id, label, attributes) and the points of each path.
struct Parsed {
    root: Attributes,
    layers: Vec<(String, String, Attributes, Vec<Vec<DVec2>>)>,
}

fn parse(svg: &str) -> Parsed {
    let doc = roxmltree::Document::parse(svg).expect("the SVG is well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg");
    assert_eq!(
        root.tag_name().namespace(),
        Some("http://www.w3.org/2000/svg")
    );
    let attrs = |n: roxmltree::Node| {
        n.attributes()
            .map(|a| (a.name().to_string(), a.value().to_string()))
            .collect::<Vec<_>>()
    };
    let mut layers = Vec::new();
    for g in root.children().filter(|n| n.has_tag_name("g")) {
        assert_eq!(g.attribute((INKSCAPE, "groupmode")), Some("layer"));
        let mut paths = Vec::new();
        for path in g.children().filter(|n| n.is_element()) {
            assert_eq!(path.tag_name().name(), "path");
            let d = path.attribute("d").unwrap();
            let pts = d
                .split([' ', 'M', 'L'])
                .filter(|s| !s.is_empty())
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    DVec2::new(x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            paths.push(pts);
        }
        layers.push((
            g.attribute("id").unwrap().to_string(),
            g.attribute((INKSCAPE, "label")).unwrap().to_string(),
            attrs(g),
            paths,
        ));
    }
    Parsed {
        root: attrs(root),
        layers,
    }
}

fn attr<'a>(list: &'a [(String, String)], name: &str) -> Option<&'a str> {
    list.iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v.as_str())
}

#[test]
fn pixels_svg_parses_with_named_layers_and_the_plot_s_points() {
    let plot = sample();
    let svg = to_string(
        &plot,
        &SvgOptions::default().with_hidden(HiddenStyle::Dashed),
    )
    .unwrap();
    let parsed = parse(&svg);
    assert_eq!(attr(&parsed.root, "width"), Some("400"));
    assert_eq!(attr(&parsed.root, "height"), Some("300"));
    assert_eq!(attr(&parsed.root, "viewBox"), Some("0 0 400 300"));
    let names: Vec<(&str, &str)> = parsed
        .layers
        .iter()
        .map(|l| (l.0.as_str(), l.1.as_str()))
        .collect();
    assert_eq!(names, [("layer1", "1-visible"), ("layer2", "2-hidden")]);
    assert!(attr(&parsed.layers[1].2, "stroke-dasharray").is_some());
    assert!(attr(&parsed.layers[0].2, "stroke-dasharray").is_none());
    assert_eq!(attr(&parsed.layers[0].2, "stroke-width"), Some("1"));
    for (layer, lines) in parsed.layers.iter().zip([&plot.visible, &plot.hidden]) {
        assert_eq!(layer.3.len(), lines.len());
        for (got, want) in layer.3.iter().zip(lines.iter()) {
            assert_eq!(got.len(), want.points.len());
            for (g, w) in got.iter().zip(&want.points) {
                // Two decimals.
                assert!(g.distance(*w) <= 0.005 * 2f64.sqrt(), "{g} vs {w}");
            }
        }
    }
}

#[test]
fn hidden_lines_left_out_or_solid() {
    let plot = sample();
    let none = parse(&to_string(&plot, &SvgOptions::default()).unwrap());
    assert_eq!(none.layers.len(), 1);
    let solid = parse(
        &to_string(
            &plot,
            &SvgOptions::default().with_hidden(HiddenStyle::Solid),
        )
        .unwrap(),
    );
    assert_eq!(solid.layers.len(), 2);
    assert!(attr(&solid.layers[1].2, "stroke-dasharray").is_none());
    assert_eq!(
        "dashed".parse::<HiddenStyle>().unwrap(),
        HiddenStyle::Dashed
    );
    assert!("dotted".parse::<HiddenStyle>().is_err());
}

/// The bounding box of every point of the parsed layers.
fn parsed_bounds(p: &Parsed) -> (DVec2, DVec2) {
    let pts: Vec<DVec2> = p
        .layers
        .iter()
        .flat_map(|l| l.3.iter().flatten().copied())
        .collect();
    let lo = pts
        .iter()
        .fold(DVec2::splat(f64::INFINITY), |a, &b| a.min(b));
    let hi = pts
        .iter()
        .fold(DVec2::splat(f64::NEG_INFINITY), |a, &b| a.max(b));
    (lo, hi)
}

#[test]
fn millimetres_on_a_page_fit_the_lines_centred_with_aspect_kept() {
    let plot = sample(); // lines' box: 100..300 x 50..250 (square)
    let layout = PageLayout::new(Page::A4).with_margin(15.0);
    let svg = to_string(
        &plot,
        &SvgOptions::default()
            .with_page(layout)
            .with_hidden(HiddenStyle::Solid),
    )
    .unwrap();
    let parsed = parse(&svg);
    assert_eq!(attr(&parsed.root, "width"), Some("210mm"));
    assert_eq!(attr(&parsed.root, "height"), Some("297mm"));
    assert_eq!(attr(&parsed.root, "viewBox"), Some("0 0 210 297"));
    assert_eq!(attr(&parsed.layers[0].2, "stroke-width"), Some("0.3"));
    // The square box of 200 px fills the width inside the margins: 180 mm, so 0.9 mm
    // a pixel, centred on the page.
    let (lo, hi) = parsed_bounds(&parsed);
    assert!(
        (lo.x - 15.0).abs() < 1e-3 && (hi.x - 195.0).abs() < 1e-3,
        "{lo} {hi}"
    );
    assert!(((lo.y + hi.y) / 2.0 - 148.5).abs() < 1e-3);
    assert!((hi.y - lo.y - 180.0).abs() < 1e-3);
    // A point maps by the same scale on both axes: (120.5, 60.25) px.
    let p = layout.place(&plot).unwrap();
    assert!((p.scale - 0.9).abs() < 1e-12);
    let q = p.apply(DVec2::new(120.5, 60.25));
    let got = parsed.layers[0].3[1][0];
    assert!(got.distance(q) < 1e-3, "{got} vs {q}");
}

#[test]
fn named_pages_turn_to_the_drawing_and_sizes_are_kept() {
    let wide = Plot {
        width: 1000,
        height: 100,
        visible: vec![line(&[(0.0, 10.0), (1000.0, 90.0)])],
        hidden: vec![],
    };
    let size = |layout: PageLayout| {
        let p = layout.place(&wide).unwrap();
        (p.width_mm, p.height_mm)
    };
    assert_eq!(size(PageLayout::new(Page::A3)), (420.0, 297.0));
    assert_eq!(
        size(PageLayout::new(Page::A3).with_orientation(Orientation::Portrait)),
        (297.0, 420.0)
    );
    assert_eq!(
        size(PageLayout::new(Page::parse("100x300mm").unwrap())),
        (100.0, 300.0)
    );
    assert_eq!(
        size(
            PageLayout::new(Page::parse("100x300").unwrap())
                .with_orientation(Orientation::Landscape)
        ),
        (300.0, 100.0)
    );
    let letter = parse(
        &to_string(
            &wide,
            &SvgOptions::default().with_page(PageLayout::new(Page::parse("Letter").unwrap())),
        )
        .unwrap(),
    );
    assert_eq!(attr(&letter.root, "width"), Some("279.4mm"));
    assert_eq!(attr(&letter.root, "viewBox"), Some("0 0 279.4 215.9"));
    // Fitting the picture: its 1000 px width fills 279.4 - 20 mm.
    let p = PageLayout::new(Page::LETTER)
        .with_fit(Fit::Picture)
        .place(&wide)
        .unwrap();
    assert!((p.scale - 259.4 / 1000.0).abs() < 1e-12);
    assert!((p.apply(DVec2::ZERO).x - 10.0).abs() < 1e-9);
}

#[test]
fn bad_pages_margins_and_strokes_are_refused() {
    for s in ["A5", "", "x", "10x", "0x100mm", "-5x10", "1e9x10", "nanx5"] {
        let e = Page::parse(s).unwrap_err().to_string();
        assert!(e.contains("page"), "{s}: {e}");
    }
    let plot = sample();
    let e = PageLayout::new(Page::A4)
        .with_margin(105.0)
        .place(&plot)
        .unwrap_err()
        .to_string();
    assert!(e.contains("margin") && e.contains("no room"), "{e}");
    assert!(
        PageLayout::new(Page::A4)
            .with_margin(-1.0)
            .place(&plot)
            .is_err()
    );
    assert!(to_string(&plot, &SvgOptions::default().with_stroke_width(0.0)).is_err());
    assert!(to_string(&plot, &SvgOptions::default().with_precision(13)).is_err());
}

#[test]
fn precision_rounds_and_trims_coordinates() {
    let mut s = String::new();
    number(&mut s, 1.23456, 3);
    s.push(' ');
    number(&mut s, 2.5, 3);
    s.push(' ');
    number(&mut s, -0.0001, 2);
    s.push(' ');
    number(&mut s, 10.0, 0);
    assert_eq!(s, "1.235 2.5 0 10");
}

#[test]
fn an_empty_plot_is_a_valid_document() {
    let plot = Plot {
        width: 10,
        height: 10,
        ..Plot::default()
    };
    for options in [
        SvgOptions::default(),
        SvgOptions::default().with_page(PageLayout::new(Page::A4)),
    ] {
        let parsed = parse(&to_string(&plot, &options).unwrap());
        assert_eq!(parsed.layers.len(), 1);
        assert!(parsed.layers[0].3.is_empty());
    }
}
