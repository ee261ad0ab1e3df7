//! `obscura lines`: a hidden-line drawing of a scene (or of a height field) as SVG,
//! with an optional PNG preview and the JSON of every edge's visible and hidden
//! intervals.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use obscura::budget::MemoryBudget;
use obscura::lines::horizon::{Curves, HeightField, HorizonOptions};
use obscura::lines::json::LinesFile;
use obscura::lines::plot::{PlotOptions, PlotStats, plot};
use obscura::lines::preview::PreviewOptions;
use obscura::lines::svg::{Fit, HiddenStyle, Orientation, Page, PageLayout, Placement, SvgOptions};
use obscura::lines::{Drawing, EdgeKinds, Progress, edges::EdgeOptions, hlr, horizon, roberts};
use obscura::{Camera, Error, Result, SceneIndex, View, Viewport};
use serde_json::json;

use crate::common::{ViewArgs, parse_number, readable};
use crate::out::{errln, outln};
use crate::outputs::{OutputArgs, Outputs};

pub const EXAMPLES: &str = "\
Examples:
  obscura lines demo:cube -o cube.svg                  # visible lines, pixels
  obscura lines model.obj --hidden dashed --units mm --page A4 --margin 15 -o plot.svg
  obscura lines model.stl --edges silhouette,crease --crease 40 --png preview.png --stats
  obscura lines scene.toml --algo roberts --json edges.json --check
  obscura lines --algo horizon --function ripple --grid 200 -o ripple.svg
  obscura lines --algo horizon --field terrain.png --units mm --page 300x200mm -o terrain.svg
  obscura lines --drawing edges.json --units mm --page A3 --hidden dashed -o a3.svg

Layers: visible lines on the Inkscape layer \"1-visible\" (id layer1), hidden ones on
\"2-hidden\" (id layer2): AxiDraw's layer numbers and vpype's `read` take the leading
number. Pen-up travel is reported before and after ordering the polylines.";

/// The hidden-line algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LinesAlgo {
    /// Exact hidden-line removal of any mesh (feature edges, quantitative invisibility).
    Hlr,
    /// Roberts' algorithm (scenes of convex polyhedra).
    Roberts,
    /// The floating horizon, for a height field y = f(x, z) (--field or --function).
    Horizon,
}

impl LinesAlgo {
    fn name(self) -> &'static str {
        match self {
            LinesAlgo::Hlr => "hlr",
            LinesAlgo::Roberts => "roberts",
            LinesAlgo::Horizon => "horizon",
        }
    }
}

/// What one unit of the SVG is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Units {
    /// Pixels of the picture (--size).
    Px,
    /// Millimetres on a page (--page, --margin).
    Mm,
}

#[derive(Args, Debug)]
pub struct LinesArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// The algorithm.
    #[arg(long, value_enum, default_value = "hlr")]
    pub algo: LinesAlgo,
    /// Edges to draw: a list of silhouette, crease, boundary, border, intersection,
    /// other, or all (every mesh edge). Default: every feature (all but other).
    #[arg(long, value_name = "LIST", value_parser = parse_edges)]
    pub edges: Option<EdgeKinds>,
    /// Dihedral angle in degrees above which an edge is a crease (0 to 180).
    #[arg(long, value_name = "DEG", default_value = "30", value_parser = parse_crease,
          allow_hyphen_values = true)]
    pub crease: f64,
    /// Hidden lines: none (left out), dashed, or solid (grey).
    #[arg(long, value_name = "STYLE", default_value = "none", value_parser = parse_hidden)]
    pub hidden: HiddenStyle,
    /// Units of the SVG: px (the picture's pixels) or mm (on a page; the default when
    /// --page is given).
    #[arg(long, value_enum)]
    pub units: Option<Units>,
    /// Page for --units mm: A4, A3, letter or WIDTHxHEIGHTmm (default A4).
    #[arg(long, value_name = "PAGE", value_parser = parse_page)]
    pub page: Option<Page>,
    /// Page orientation: auto (a named page turns to the drawing; a WxHmm page is kept),
    /// portrait or landscape.
    #[arg(long, value_name = "WAY", default_value = "auto", value_parser = parse_orientation)]
    pub orientation: Orientation,
    /// Margin on each side of the page, millimetres.
    #[arg(long, value_name = "MM", default_value = "10", value_parser = parse_number,
          allow_hyphen_values = true)]
    pub margin: f64,
    /// What fills the page: lines (their bounding box) or picture (the whole image).
    #[arg(long, value_name = "WHAT", default_value = "lines", value_parser = parse_fit)]
    pub fit: Fit,
    /// Stroke width in SVG units (default 1 px, or 0.3 mm on a page); the PNG preview
    /// uses it in pixels (default 1).
    #[arg(long, value_name = "W", value_parser = parse_number, allow_hyphen_values = true)]
    pub stroke: Option<f64>,
    /// Decimals of the SVG coordinates (default 2 in px, 3 in mm).
    #[arg(long, value_name = "N")]
    pub precision: Option<u8>,
    /// Ends closer than this many pixels are joined into one polyline.
    #[arg(long, value_name = "PX", default_value = "0.01", value_parser = parse_number,
          allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Pieces shorter than this many pixels are dropped (their ends merged).
    #[arg(long, value_name = "PX", default_value = "0.1", value_parser = parse_number,
          allow_hyphen_values = true)]
    pub min_length: f64,
    /// Keep the polylines in the order the pieces came (no pen-travel ordering).
    #[arg(long)]
    pub no_order: bool,
    /// The SVG to write.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "OUT.svg",
        default_value = "lines.svg"
    )]
    pub output: PathBuf,
    /// Also write a PNG preview (the picture's size).
    #[arg(long, value_name = "PREVIEW.png")]
    pub png: Option<PathBuf>,
    /// Also write every edge considered with its visible and hidden parameter intervals
    /// (schema in docs/lines.md).
    #[arg(long, value_name = "EDGES.json")]
    pub json: Option<PathBuf>,
    /// Check every piece against ray casting and report disagreements (fails the run
    /// if any).
    #[arg(long)]
    pub check: bool,
    /// Print counts and times.
    #[arg(long)]
    pub stats: bool,
    /// Plot a drawing saved by --json instead of drawing a scene (other page, units,
    /// hidden-line style, without computing the drawing again).
    #[arg(long, value_name = "EDGES.json", conflicts_with_all = ["field", "function", "check", "scene"])]
    pub drawing: Option<PathBuf>,
    /// Height field for --algo horizon: a 2D NumPy array (.npy), a CSV grid of
    /// numbers, or a grayscale PNG (8 or 16 bits).
    #[arg(long, value_name = "FILE", conflicts_with = "function")]
    pub field: Option<PathBuf>,
    /// Built-in height field for --algo horizon, by name.
    #[arg(long, value_name = "NAME")]
    pub function: Option<String>,
    /// Samples on each side of a --function grid (2 to 10000).
    #[arg(long, value_name = "N", default_value = "100", value_parser = clap::value_parser!(u32).range(2..=10_000))]
    pub grid: u32,
    /// Curves of a height field: z (constant z, the default), x (constant x) or both.
    #[arg(long, value_name = "z|x|both", default_value = "z", value_parser = parse_curves)]
    pub curves: Curves,
    /// Ridgeline mode for a height field: the upper horizon only, each curve hiding
    /// what lies behind its filled area.
    #[arg(long)]
    pub ridgeline: bool,
    #[command(flatten)]
    pub naming: OutputArgs,
}

fn parse_curves(s: &str) -> std::result::Result<Curves, String> {
    Curves::parse(s).map_err(|e| reason(&e))
}

fn parse_edges(s: &str) -> std::result::Result<EdgeKinds, String> {
    EdgeKinds::parse(s).map_err(|e| reason(&e))
}

fn parse_hidden(s: &str) -> std::result::Result<HiddenStyle, String> {
    s.parse().map_err(|e: Error| reason(&e))
}

fn parse_page(s: &str) -> std::result::Result<Page, String> {
    Page::parse(s).map_err(|e| reason(&e))
}

fn parse_orientation(s: &str) -> std::result::Result<Orientation, String> {
    s.parse().map_err(|e: Error| reason(&e))
}

fn parse_fit(s: &str) -> std::result::Result<Fit, String> {
    match s.trim().to_ascii_lowercase().as_str() {
        "lines" => Ok(Fit::Lines),
        "picture" => Ok(Fit::Picture),
        other => Err(format!(
            "unknown fit \"{other}\" (expected lines or picture)"
        )),
    }
}

fn parse_crease(s: &str) -> std::result::Result<f64, String> {
    let x = parse_number(s)?;
    if (0.0..=180.0).contains(&x) {
        Ok(x)
    } else {
        Err(format!("{} degrees: give 0 to 180", readable(x)))
    }
}

/// The reason of an option error, without the library's option name (clap names the
/// flag).
fn reason(e: &Error) -> String {
    match e {
        Error::InvalidOption { reason, .. } => reason.clone(),
        e => e.to_string(),
    }
}

/// The library's parameter names as the flags that set them.
const FLAGS: [(&str, &str); 9] = [
    ("page", "--page"),
    ("margin", "--margin"),
    ("stroke", "--stroke"),
    ("precision", "--precision"),
    ("hidden", "--hidden"),
    ("edges", "--edges"),
    ("PlotOptions::tolerance", "--tolerance"),
    ("PlotOptions::min_length", "--min-length"),
    ("orientation", "--orientation"),
];

/// An error naming the flag rather than the library's parameter.
fn flagged(e: Error) -> Error {
    match e {
        Error::InvalidOption { option, reason } => {
            let option = FLAGS
                .iter()
                .find(|(p, _)| *p == option)
                .map_or(option, |(_, f)| (*f).to_string());
            Error::InvalidOption { option, reason }
        }
        e => e,
    }
}

/// The page layout asked for, or `None` for pixels.
fn layout(args: &LinesArgs) -> Result<Option<PageLayout>> {
    let mm = match (args.units, args.page) {
        (Some(Units::Px), Some(_)) => {
            return Err(Error::option(
                "--page",
                "a page is for --units mm; leave --page out for an SVG in pixels",
            ));
        }
        (Some(Units::Mm), _) | (None, Some(_)) => true,
        _ => false,
    };
    Ok(mm.then(|| {
        PageLayout::new(args.page.unwrap_or(Page::A4))
            .with_margin(args.margin)
            .with_orientation(args.orientation)
            .with_fit(args.fit)
    }))
}

/// A progress bar on standard error fed by the library's `(done, total)` callback.
fn progress_bar(name: &str) -> (indicatif::ProgressBar, Progress) {
    let (pb, feed) = crate::common::progress_bar(name);
    let progress: Progress = std::sync::Arc::new(move |done, total| {
        if total > 0 {
            feed(done as f64 / total as f64);
        }
    });
    (pb, progress)
}

/// What the drawing stage gives back.
struct Drawn {
    drawing: Drawing,
    /// The algorithm that drew it (for a saved drawing, the one its file names).
    algorithm: String,
    /// The algorithm's own counters, as JSON.
    stats: serde_json::Value,
    check: Option<CheckSummary>,
    draw_ms: f64,
}

/// What `--check` found, in the CLI's words.
pub struct CheckSummary {
    pub pieces_checked: u64,
    pub samples: u64,
    pub pieces_disagreeing: u64,
    pub report: serde_json::Value,
}

/// Runs `--check`: every piece sampled against ray casting
/// (`obscura::lines::check::check`, the sampling oracle).
fn check_drawing(index: &SceneIndex, view: &View, drawing: &Drawing) -> CheckSummary {
    let report = obscura::lines::check::check(
        index,
        view,
        drawing,
        &obscura::lines::check::CheckOptions::default(),
    );
    CheckSummary {
        pieces_checked: report.pieces_checked,
        samples: report.samples,
        pieces_disagreeing: report.pieces_disagreeing + report.pieces_invalid,
        report: serde_json::to_value(&report).unwrap_or_default(),
    }
}

/// The height field of `--field` or `--function`, held to `--memory-limit`.
fn height_field(args: &LinesArgs) -> Result<HeightField> {
    let budget = args
        .view
        .memory_limit
        .map_or_else(MemoryBudget::default, MemoryBudget::new);
    match (&args.field, &args.function) {
        (None, None) => Err(Error::option(
            "--algo",
            "horizon draws a height field: give --field FILE or --function NAME",
        )),
        (Some(path), _) => HeightField::load_with_budget(path, &budget),
        (None, Some(name)) => {
            let n = args.grid as usize;
            HeightField::function_with_budget(name, n, n, &budget)
        }
    }
}

/// The camera looking at a height field: its own default, with the camera flags applied.
fn field_camera(args: &LinesArgs, field: &HeightField, viewport: Viewport) -> Result<Camera> {
    let mut cam = field.default_camera(viewport.aspect());
    let v = &args.view;
    cam.eye = v.eye.unwrap_or(cam.eye);
    cam.target = v.target.unwrap_or(cam.target);
    cam.up = v.up.unwrap_or(cam.up);
    if let Some(fov) = v.fov {
        cam.projection = obscura::Projection::Perspective { fov_y_degrees: fov };
    }
    if let Some(h) = v.ortho {
        cam.projection = obscura::Projection::Orthographic { height: h };
    }
    cam.near = v.near.unwrap_or(cam.near);
    cam.far = v.far.unwrap_or(cam.far);
    cam.validate()?;
    Ok(cam)
}

pub fn run(args: &LinesArgs) -> Result<()> {
    let horizon = args.algo == LinesAlgo::Horizon;
    if !horizon && (args.field.is_some() || args.function.is_some()) {
        return Err(Error::option(
            if args.field.is_some() {
                "--field"
            } else {
                "--function"
            },
            "height fields are drawn by --algo horizon",
        ));
    }
    if horizon && args.drawing.is_some() {
        return Err(Error::option(
            "--drawing",
            "a saved drawing is plotted as it is: leave out --algo horizon",
        ));
    }
    if horizon && args.view.scene.is_some() {
        return Err(Error::option(
            "--algo",
            "horizon draws a height field (--field or --function), not a SCENE",
        ));
    }
    if horizon && args.check {
        return Err(Error::option(
            "--check",
            "ray casting checks a scene's drawing; a height field has no scene to cast at",
        ));
    }
    let layout = layout(args)?;
    let input = match (&args.field, &args.drawing) {
        (Some(f), _) | (None, Some(f)) => Some(f.to_string_lossy().into_owned()),
        (None, None) => args.view.scene.clone(),
    };
    let mut outputs = Outputs::stage_with_extensions(
        input.as_deref(),
        &[
            ("-o", Some(&args.output)),
            ("--png", args.png.as_deref()),
            ("--json", args.json.as_deref()),
        ],
        args.naming,
        &[("-o", "svg", "SVG drawings")],
    )?;
    let mut svg_options = SvgOptions::default().with_hidden(args.hidden);
    if let Some(l) = layout {
        svg_options = svg_options.with_page(l);
    }
    if let Some(w) = args.stroke {
        svg_options = svg_options.with_stroke_width(w);
    }
    if let Some(p) = args.precision {
        svg_options = svg_options.with_precision(p);
    }
    let plot_options = PlotOptions::default()
        .with_tolerance(args.tolerance)
        .with_min_length(args.min_length)
        .with_order(!args.no_order);

    let bar = std::io::stderr()
        .is_terminal()
        .then(|| progress_bar(args.algo.name()));
    let progress = bar.as_ref().map(|(_, p)| p.clone());
    let (spec, load_ms, drawn) = if let Some(path) = &args.drawing {
        let start = Instant::now();
        let file = LinesFile::read(path)?;
        let drawing = file.to_drawing().map_err(|e| {
            Error::option("--drawing", format!("{}: {}", path.display(), reason(&e)))
        })?;
        let load_ms = start.elapsed().as_secs_f64() * 1e3;
        let drawn = Drawn {
            drawing,
            algorithm: file.algorithm.unwrap_or_else(|| "saved".to_string()),
            stats: serde_json::Value::Null,
            check: None,
            draw_ms: 0.0,
        };
        (path.display().to_string(), load_ms, drawn)
    } else if horizon {
        let start = Instant::now();
        let field = height_field(args)?;
        let load_ms = start.elapsed().as_secs_f64() * 1e3;
        let (w, h) = args.view.size.unwrap_or(crate::common::DEFAULT_SIZE);
        let viewport = Viewport::new(w, h)?;
        let camera = field_camera(args, &field, viewport)?;
        let start = Instant::now();
        let mut options = HorizonOptions::default();
        options.memory_limit = args.view.memory_limit;
        options.hidden = args.hidden != HiddenStyle::None;
        options.curves = args.curves;
        options.ridgeline = args.ridgeline;
        let (drawing, stats) = horizon::draw(&field, &camera, viewport, &options)?;
        let drawn = Drawn {
            drawing,
            algorithm: args.algo.name().to_string(),
            stats: serde_json::to_value(&stats).unwrap_or_default(),
            check: None,
            draw_ms: start.elapsed().as_secs_f64() * 1e3,
        };
        let spec = args
            .field
            .as_ref()
            .map(|p| p.display().to_string())
            .or_else(|| args.function.clone().map(|f| format!("function:{f}")))
            .unwrap_or_default();
        (spec, load_ms, drawn)
    } else {
        let loaded = args.view.load()?;
        outputs.check_inputs(loaded.scene.source_files())?;
        let scene = &loaded.scene;
        let viewport = args.view.viewport(scene)?;
        let camera = args.view.camera(scene, viewport)?;
        let prep = args.view.prepare_options();
        let drawn = args.view.with_threads(|| {
            let index = SceneIndex::new(scene);
            let view = View::new(scene, &camera, viewport, &prep)?;
            let start = Instant::now();
            let (drawing, stats) = match args.algo {
                LinesAlgo::Hlr => {
                    let mut options = hlr::HlrOptions::default();
                    let mut edges = EdgeOptions::default();
                    edges.kinds = args.edges.unwrap_or_default();
                    edges.crease_degrees = args.crease;
                    options.edges = edges;
                    options.time_limit = args.view.remaining_time();
                    options.progress = progress.clone();
                    let (d, s) = hlr::draw(&index, &view, &options)?;
                    (d, serde_json::to_value(&s).unwrap_or_default())
                }
                _ => {
                    let mut options = roberts::RobertsOptions::default();
                    options.time_limit = args.view.remaining_time();
                    let (d, s) = roberts::draw(&view, &options)?;
                    (d, serde_json::to_value(&s).unwrap_or_default())
                }
            };
            let draw_ms = start.elapsed().as_secs_f64() * 1e3;
            let check = args.check.then(|| check_drawing(&index, &view, &drawing));
            Ok::<_, Error>(Drawn {
                drawing,
                algorithm: args.algo.name().to_string(),
                stats,
                check,
                draw_ms,
            })
        })?;
        if let Some((bar, _)) = &bar {
            bar.finish_and_clear();
        }
        let drawn = drawn.map_err(|e| e.in_input(&loaded.spec))?;
        (loaded.spec.clone(), loaded.load_ms, drawn)
    };
    if let Some((bar, _)) = &bar {
        bar.finish_and_clear();
    }

    // Plotting cannot stop half-way: refused by its estimate when it would pass the
    // time left (a 3000x3000 height field's 7 million pieces took 9.5 s).
    obscura::work::Deadline::new(args.view.remaining_time(), None)
        .admit(&obscura::work::Estimate::new(
            "plotting the drawing",
            "pieces",
            drawn.drawing.pieces.len() as f64,
            obscura::work::NS_PER_PLOT_PIECE,
        ))
        .map_err(crate::common::cli_error)?;
    let start = Instant::now();
    let (plotted, plot_stats) = plot(&drawn.drawing, &plot_options).map_err(flagged)?;
    let plot_ms = start.elapsed().as_secs_f64() * 1e3;
    let placement = layout
        .map(|l| l.place(&plotted))
        .transpose()
        .map_err(flagged)?;
    let svg = obscura::lines::svg::to_string(&plotted, &svg_options).map_err(flagged)?;
    outputs.write("-o", |p| {
        std::fs::write(p, &svg).map_err(|e| Error::io(p, e))
    })?;
    if args.png.is_some() {
        let mut preview = PreviewOptions::default().with_hidden(args.hidden);
        if let (Some(w), None) = (args.stroke, layout) {
            preview = preview.with_stroke_width(w);
        }
        let image = obscura::lines::preview::render(&plotted, &preview).map_err(flagged)?;
        outputs.write("--png", |p| image.write_png(p))?;
    }
    if args.json.is_some() {
        let mut file = LinesFile::from_drawing(&drawn.drawing)?;
        file.scene = Some(spec.clone());
        file.algorithm = Some(drawn.algorithm.clone());
        outputs.write("--json", |p| file.write(p))?;
    }
    outputs.commit()?;

    let units = |px: f64| match &placement {
        Some(p) => format!("{:.1} mm", px * p.scale),
        None => format!("{px:.1} px"),
    };
    if args.stats {
        print_stats(
            &spec,
            load_ms,
            &drawn,
            &plot_stats,
            plot_ms,
            placement.as_ref(),
        );
    }
    let (before, after) = (plot_stats.travel_before(), plot_stats.travel_after());
    let saved = if before > 0.0 {
        format!(" ({:.0}% less)", 100.0 * (before - after) / before)
    } else {
        String::new()
    };
    outln!(
        "wrote {} ({} visible and {} hidden polylines; pen-up travel {} -> {}{saved}; {}, {:.1} ms)",
        args.output.display(),
        plot_stats.visible.polylines,
        if args.hidden == HiddenStyle::None {
            0
        } else {
            plot_stats.hidden.polylines
        },
        units(before),
        units(after),
        drawn.algorithm,
        drawn.draw_ms + plot_ms
    );
    if let Some(c) = &drawn.check {
        outln!(
            "check: {} pieces, {} samples cast, {} pieces disagree with ray casting",
            c.pieces_checked,
            c.samples,
            c.pieces_disagreeing
        );
        if c.pieces_disagreeing > 0 {
            if let Some(list) = c.report.get("disagreements").and_then(|d| d.as_array()) {
                for d in list.iter().take(10) {
                    errln!("  {d}");
                }
            }
            return Err(Error::option(
                "--check",
                format!(
                    "{} of {} pieces disagree with ray casting",
                    c.pieces_disagreeing, c.pieces_checked
                ),
            ));
        }
    }
    Ok(())
}

fn print_stats(
    spec: &str,
    load_ms: f64,
    drawn: &Drawn,
    s: &PlotStats,
    plot_ms: f64,
    placement: Option<&Placement>,
) {
    let d = &drawn.drawing;
    outln!("scene {spec}: loaded in {load_ms:.1} ms");
    outln!(
        "drawing: {} edges, {} pieces ({} visible, {} hidden) in {:.2} ms",
        d.edges.len(),
        d.pieces.len(),
        d.visible().count(),
        d.hidden().count(),
        drawn.draw_ms
    );
    if let Some(obj) = drawn.stats.as_object() {
        for (k, v) in obj {
            outln!("  {k:<46} {v:>12}");
        }
    }
    let doc = json!({ "visible": s.visible, "hidden": s.hidden });
    for class in ["visible", "hidden"] {
        let l = &doc[class];
        outln!(
            "{class}: {} pieces -> {} polylines, {} points, length {:.1} px; dropped {} short, \
             duplicates {:.1} px, under visible {:.1} px; travel {:.1} -> {:.1} px",
            l["pieces"],
            l["polylines"],
            l["points"],
            l["length"].as_f64().unwrap_or(0.0),
            l["short_pieces"],
            l["duplicate_length"].as_f64().unwrap_or(0.0),
            l["under_visible_length"].as_f64().unwrap_or(0.0),
            l["travel_before"].as_f64().unwrap_or(0.0),
            l["travel_after"].as_f64().unwrap_or(0.0),
        );
    }
    if s.invalid_pieces > 0 {
        outln!("invalid pieces left out: {}", s.invalid_pieces);
    }
    if let Some(p) = placement {
        outln!(
            "page {} x {} mm, {:.4} mm a pixel",
            readable(p.width_mm),
            readable(p.height_mm),
            p.scale
        );
    }
    outln!("plot: {plot_ms:.2} ms");
}
