//! `obscura lines`: what it writes and how it refuses bad input. Drawings come from a
//! saved JSON file (`--drawing`) made here, so these tests do not depend on any one
//! hidden-line algorithm.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn obscura(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_obscura"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the binary runs")
}

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("obscura-lines-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// A saved drawing of a 400 x 300 picture: the four sides of a rectangle from
/// (100, 50) to (300, 250), each given as its own edge, one side twice, and a hidden
/// diagonal.
fn write_drawing(dir: &Path) -> PathBuf {
    let piece = |k: usize, a: [f64; 2], b: [f64; 2], q: u32| {
        let (vis, hid) = if q == 0 {
            ("[[0.0, 1.0]]", "[]")
        } else {
            ("[]", "[[0.0, 1.0]]")
        };
        format!(
            r#"{{"edge": {k}, "vertices": [{k}, {}], "object": 0, "kind": "crease",
               "faces": [null, null], "world": [[0, 0, 0], [1, 0, 0]],
               "visible": {vis}, "hidden": {hid},
               "pieces": [{{"t": [0.0, 1.0], "invisibility": {q},
                            "points": [[{}, {}], [{}, {}]]}}]}}"#,
            k + 1,
            a[0],
            a[1],
            b[0],
            b[1]
        )
    };
    let sides = [
        ([100.0, 50.0], [300.0, 50.0], 0),
        ([300.0, 250.0], [300.0, 50.0], 0),
        ([300.0, 250.0], [100.0, 250.0], 0),
        ([100.0, 50.0], [100.0, 250.0], 0),
        ([100.0, 250.0], [300.0, 250.0], 0),
        ([100.0, 50.0], [300.0, 250.0], 2),
    ];
    let edges: Vec<String> = sides
        .iter()
        .enumerate()
        .map(|(k, &(a, b, q))| piece(k, a, b, q))
        .collect();
    let doc = format!(
        r#"{{"format": "obscura-lines", "version": 1, "width": 400, "height": 300,
            "edges": [{}]}}"#,
        edges.join(",\n")
    );
    let path = dir.join("drawing.json");
    std::fs::write(&path, doc).unwrap();
    path
}

const INKSCAPE: &str = "http://www.inkscape.org/namespaces/inkscape";

/// The root's attributes and, per layer, its label and the points of its paths.
type Layers = Vec<(String, Vec<Vec<(f64, f64)>>)>;

fn read_svg(path: &Path) -> (Vec<(String, String)>, Layers) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).expect("well-formed XML");
    let root = doc.root_element();
    let attrs = root
        .attributes()
        .map(|a| (a.name().to_string(), a.value().to_string()))
        .collect();
    let layers = root
        .children()
        .filter(|n| n.has_tag_name("g"))
        .map(|g| {
            assert_eq!(g.attribute((INKSCAPE, "groupmode")), Some("layer"));
            let paths = g
                .children()
                .filter(|n| n.has_tag_name("path"))
                .map(|p| {
                    p.attribute("d")
                        .unwrap()
                        .split([' ', 'M', 'L'])
                        .filter(|s| !s.is_empty())
                        .map(|xy| {
                            let (x, y) = xy.split_once(',').unwrap();
                            (x.parse().unwrap(), y.parse().unwrap())
                        })
                        .collect()
                })
                .collect();
            (g.attribute((INKSCAPE, "label")).unwrap().to_string(), paths)
        })
        .collect();
    (attrs, layers)
}

fn attr<'a>(list: &'a [(String, String)], name: &str) -> &'a str {
    list.iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v.as_str())
        .unwrap_or_else(|| panic!("no {name}"))
}

#[test]
fn help_shows_the_flags_and_examples() {
    let dir = tempdir("help");
    let o = obscura(&["lines", "--help"], &dir);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    for flag in [
        "--algo",
        "--edges",
        "--crease",
        "--hidden",
        "--units",
        "--page",
        "--margin",
        "--stroke",
        "--png",
        "--json",
        "--check",
        "--field",
        "--function",
        "--eye",
        "--time-limit",
        "Examples:",
        "1-visible",
    ] {
        assert!(out.contains(flag), "{flag} missing from:\n{out}");
    }
}

#[test]
fn a_saved_drawing_is_joined_and_written_in_pixels() {
    let dir = tempdir("px");
    write_drawing(&dir);
    let o = obscura(
        &[
            "lines",
            "--drawing",
            "drawing.json",
            "--hidden",
            "dashed",
            "-o",
            "out.svg",
            "--png",
            "out.png",
            "--json",
            "again.json",
            "--stats",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(
        out.contains("wrote out.svg (1 visible and 1 hidden polylines"),
        "{out}"
    );
    // The duplicated side counted as such.
    assert!(out.contains("duplicates 200.0 px"), "{out}");
    let (root, layers) = read_svg(&dir.join("out.svg"));
    assert_eq!(attr(&root, "viewBox"), "0 0 400 300");
    assert_eq!(attr(&root, "width"), "400");
    let labels: Vec<&str> = layers.iter().map(|l| l.0.as_str()).collect();
    assert_eq!(labels, ["1-visible", "2-hidden"]);
    // The rectangle as one closed polyline of its four corners.
    let rect = &layers[0].1;
    assert_eq!(rect.len(), 1);
    assert_eq!(rect[0].len(), 5);
    assert_eq!(rect[0][0], rect[0][4]);
    for c in [(100.0, 50.0), (300.0, 50.0), (300.0, 250.0), (100.0, 250.0)] {
        assert!(rect[0].contains(&c), "{c:?} not in {rect:?}");
    }
    let png = std::fs::read(dir.join("out.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // The JSON written back holds the same edges.
    let again = std::fs::read_to_string(dir.join("again.json")).unwrap();
    assert!(again.contains("\"algorithm\": \"saved\""), "{again}");
    assert_eq!(again.matches("\"kind\": \"crease\"").count(), 6);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn millimetres_on_a_page_as_asked() {
    let dir = tempdir("mm");
    write_drawing(&dir);
    let o = obscura(
        &[
            "lines",
            "--drawing",
            "drawing.json",
            "--units",
            "mm",
            "--page",
            "A4",
            "--margin",
            "15",
            "-o",
            "a4.svg",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains(" mm ->"), "{}", text(&o));
    let (root, layers) = read_svg(&dir.join("a4.svg"));
    assert_eq!(attr(&root, "width"), "210mm");
    assert_eq!(attr(&root, "height"), "297mm");
    assert_eq!(attr(&root, "viewBox"), "0 0 210 297");
    // Hidden lines are left out by default.
    assert_eq!(layers.len(), 1);
    // The 200 x 200 px box fills the 180 mm between the margins, centred.
    let pts: Vec<(f64, f64)> = layers[0].1.iter().flatten().copied().collect();
    let (xmin, xmax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let (ymin, ymax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    assert!(
        (xmin - 15.0).abs() < 1e-3 && (xmax - 195.0).abs() < 1e-3,
        "{xmin} {xmax}"
    );
    assert!((ymax - ymin - 180.0).abs() < 1e-3 && ((ymin + ymax) / 2.0 - 148.5).abs() < 1e-3);
    // A given size, landscape.
    let o = obscura(
        &[
            "lines",
            "--drawing",
            "drawing.json",
            "--page",
            "300x200mm",
            "-o",
            "custom.svg",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    let (root, _) = read_svg(&dir.join("custom.svg"));
    assert_eq!(attr(&root, "viewBox"), "0 0 300 200");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_pages_units_and_outputs_are_refused_before_writing() {
    let dir = tempdir("bad");
    write_drawing(&dir);
    let cases: [(&[&str], &[&str]); 7] = [
        (&["--page", "A5"], &["--page", "A5"]),
        (&["--page", "0x10mm"], &["--page"]),
        (
            &["--units", "px", "--page", "A4"],
            &["--page", "--units mm"],
        ),
        (
            &["--units", "mm", "--margin", "200"],
            &["--margin", "no room"],
        ),
        (
            &["-o", "drawing.json", "--force-extension"],
            &["refusing to overwrite"],
        ),
        (&["-o", "out.png"], &["-o", ".svg"]),
        (&["--hidden", "dotted"], &["--hidden", "dotted"]),
    ];
    for (extra, words) in cases {
        let mut args = vec!["lines", "--drawing", "drawing.json"];
        args.extend_from_slice(extra);
        if !extra.contains(&"-o") {
            args.extend_from_slice(&["-o", "never.svg"]);
        }
        let o = obscura(&args, &dir);
        assert!(!o.status.success(), "{args:?} succeeded");
        let out = text(&o);
        for w in words {
            assert!(out.contains(w), "{args:?}: '{w}' not in: {out}");
        }
        assert!(!dir.join("never.svg").exists(), "{args:?} wrote a file");
    }
    // The input itself is untouched, and no temporary file is left.
    assert!(
        std::fs::read_to_string(dir.join("drawing.json"))
            .unwrap()
            .contains("obscura-lines")
    );
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["drawing.json"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_output_that_is_the_input_scene_is_refused() {
    let dir = tempdir("scene");
    let obj = dir.join("tri.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = obscura(
        &["lines", "tri.obj", "-o", "tri.obj", "--force-extension"],
        &dir,
    );
    assert!(!o.status.success());
    assert!(text(&o).contains("refusing to overwrite"), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(&obj).unwrap(),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    );
    // Height-field flags belong to the floating horizon.
    let o = obscura(&["lines", "tri.obj", "--function", "ripple"], &dir);
    assert!(!o.status.success());
    assert!(text(&o).contains("--algo horizon"), "{}", text(&o));
    std::fs::remove_dir_all(&dir).ok();
}

/// Each algorithm end to end on its demo, checked by ray casting (`--check` fails the
/// run on any disagreement), and the refusals a user meets: Roberts on a non-convex
/// object (named), a height field over the memory budget, a non-finite height.
#[test]
fn algorithms_run_checked_and_refuse_what_they_cannot_draw() {
    let dir = tempdir("algos");
    for (algo, scene) in [("hlr", "demo:default"), ("roberts", "demo:blocks")] {
        let o = obscura(
            &[
                "lines", scene, "--algo", algo, "--size", "320x180", "--check", "-o", "d.svg",
            ],
            &dir,
        );
        assert!(o.status.success(), "{algo}: {}", text(&o));
        assert!(
            text(&o).contains("0 pieces disagree"),
            "{algo}: {}",
            text(&o)
        );
        assert!(
            std::fs::read_to_string(dir.join("d.svg"))
                .unwrap()
                .contains("<path d=\"M")
        );
    }
    let o = obscura(
        &["lines", "demo:default", "--algo", "roberts", "-o", "r.svg"],
        &dir,
    );
    assert!(
        !o.status.success() && text(&o).contains("convex"),
        "{}",
        text(&o)
    );
    assert!(!dir.join("r.svg").exists());
    let o = obscura(
        &[
            "lines",
            "--algo",
            "horizon",
            "--function",
            "ripple",
            "--grid",
            "2000",
            "--memory-limit",
            "64M",
            "-o",
            "h.svg",
        ],
        &dir,
    );
    assert!(
        !o.status.success() && text(&o).contains("memory budget"),
        "{}",
        text(&o)
    );
    std::fs::write(dir.join("nan.csv"), "1,2\n3,nan\n").unwrap();
    let o = obscura(
        &[
            "lines", "--algo", "horizon", "--field", "nan.csv", "-o", "n.svg",
        ],
        &dir,
    );
    assert!(
        !o.status.success() && text(&o).contains("nan.csv:2"),
        "{}",
        text(&o)
    );
    let o = obscura(
        &[
            "lines",
            "--algo",
            "horizon",
            "--function",
            "peaks",
            "--grid",
            "40",
            "-o",
            "p.svg",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", text(&o));
    std::fs::remove_dir_all(&dir).ok();
}

/// A height field's two families of curves and the ridgeline mode run from the CLI; an
/// unknown family is refused naming the flag.
#[test]
fn height_field_curves_and_ridgeline() {
    let dir = tempdir("curves");
    for extra in [&["--curves", "both"][..], &["--ridgeline"][..]] {
        let mut args = vec![
            "lines",
            "--algo",
            "horizon",
            "--function",
            "bumps",
            "--grid",
            "30",
            "-o",
            "c.svg",
        ];
        args.extend_from_slice(extra);
        let o = obscura(&args, &dir);
        assert!(o.status.success(), "{extra:?}: {}", text(&o));
    }
    let o = obscura(
        &[
            "lines",
            "--algo",
            "horizon",
            "--function",
            "bumps",
            "--curves",
            "y",
            "-o",
            "d.svg",
        ],
        &dir,
    );
    assert!(
        !o.status.success() && text(&o).contains("--curves"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Plotting cannot stop half-way, so a drawing whose pieces would take longer than the
/// time left is refused before plotting, naming --time-limit: a 1000x1000 height
/// field's million segments (about a second to plot) under a 0.05 s limit.
#[test]
fn plotting_past_the_time_limit_is_refused_by_its_estimate() {
    let dir = tempdir("plot-limit");
    let o = obscura(
        &[
            "lines",
            "--algo",
            "horizon",
            "--function",
            "ripple",
            "--grid",
            "1000",
            "--size",
            "64x48",
            "--time-limit",
            "0.05",
            "-o",
            "o.svg",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(err.contains("--time-limit"), "{err}");
    assert!(!dir.join("o.svg").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
