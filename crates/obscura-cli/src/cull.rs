//! `obscura cull`: what each occlusion-culling method removes from a view (or from
//! every frame of a camera walk), why, and how long each stage takes; the faces that
//! survive as NumPy, and a picture that explains the decisions.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use glam::DVec3;
use obscura::cull::occlusion::{BufferImage, CullMethod, CullOptions, CullReason, Culling};
use obscura::{
    Algorithm, BACKGROUND, Camera, Error, Projection, RenderOptions, Result, RgbImage, Scene,
    SceneIndex, View, Viewport,
};
use serde_json::json;

use crate::common::{ViewArgs, parse_cull};
use crate::out::{errln, outln};
use crate::outputs::{OutputArgs, Outputs};

pub const EXAMPLES: &str = "\
Examples:
  obscura cull demo:city --method all --eye 0.5,1.5,-20 --target 0.5,1.5,20 --size 1920x1080
  obscura cull demo:city --method buffer --walk walk.csv --stats --stats-json cull.json
  obscura cull scene.toml --method portals --kept kept.npy --explain explain.png

The walk is a CSV file with a header: eye_x,eye_y,eye_z,target_x,target_y,target_z and
optionally fov (degrees); one camera a line. With --walk, --kept writes the faces kept
in any frame and --explain draws the first frame.";

/// The most frames a walk may hold.
pub const MAX_WALK_FRAMES: usize = 1_000_000;

#[derive(Args, Debug)]
pub struct CullArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// The method: portals, screen-portals, occluders, buffer, frustum, none, or all
    /// (frustum, portals, screen-portals, occluders and buffer, a row each).
    #[arg(long, value_name = "METHOD", default_value = "all", value_parser = parse_methods)]
    pub method: Methods,
    /// A camera walk: a CSV file of cameras (see below); every frame is culled.
    #[arg(long, value_name = "PATH.csv", conflicts_with_all = ["eye", "target"])]
    pub walk: Option<PathBuf>,
    /// Print the culled objects and clusters by reason and the time of each stage.
    #[arg(long)]
    pub stats: bool,
    /// Write every frame's counts, reasons and stage times as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats_json: Option<PathBuf>,
    /// Write the face ids that survive culling as a sorted int32 NumPy array (one
    /// method; with --walk, the faces kept in any frame).
    #[arg(long, value_name = "KEPT.npy")]
    pub kept: Option<PathBuf>,
    /// Write a PNG: the scene's z-buffer picture with the culled objects and clusters
    /// drawn through it, coloured by what culled them, beside the occlusion buffer's
    /// depth when the method has one (one method; with --walk, the first frame).
    #[arg(long, value_name = "EXPLAIN.png")]
    pub explain: Option<PathBuf>,
    /// Cull whole objects only, not clusters of about a hundred triangles.
    #[arg(long)]
    pub no_clusters: bool,
    /// Occluders: how many of the best-ranked candidates are used.
    #[arg(long, value_name = "N")]
    pub max_occluders: Option<usize>,
    /// Portals: shrink the frustum to each portal's screen bounding box instead of the
    /// exact convex frustum.
    #[arg(long)]
    pub portal_bounding_box: bool,
    #[command(flatten)]
    pub naming: OutputArgs,
}

/// The methods a run compares.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Methods(pub Vec<CullMethod>);

/// `--method`: one method's name, or `all`.
pub fn parse_methods(s: &str) -> std::result::Result<Methods, String> {
    if s.trim() == "all" {
        return Ok(Methods(
            CullMethod::ALL
                .into_iter()
                .filter(|&m| m != CullMethod::None)
                .collect(),
        ));
    }
    parse_cull(s).map(|m| Methods(vec![m]))
}

/// One camera of a walk, with the line it came from (0 for the command line's).
#[derive(Clone, Debug)]
pub struct Frame0 {
    pub line: usize,
    pub camera: Camera,
}

/// Reads a camera walk: a CSV file with the header
/// `eye_x,eye_y,eye_z,target_x,target_y,target_z[,fov]`, then one camera a line
/// (blank lines and lines starting with `#` are skipped). `base` gives the up vector,
/// the projection when there is no fov column, and near/far unless `fit` says to fit
/// them to `bounds` for each camera. Errors name the file and the line.
pub fn read_walk(
    path: &Path,
    base: &Camera,
    fit: Option<&obscura::geom::Aabb>,
) -> Result<Vec<Frame0>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_walk(path, &text, base, fit)
}

/// [`read_walk`] of text already read.
pub fn parse_walk(
    path: &Path,
    text: &str,
    base: &Camera,
    fit: Option<&obscura::geom::Aabb>,
) -> Result<Vec<Frame0>> {
    const COLUMNS: [&str; 7] = [
        "eye_x", "eye_y", "eye_z", "target_x", "target_y", "target_z", "fov",
    ];
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((hline, header)) = lines.next() else {
        return Err(Error::parse(
            path,
            1,
            "empty walk: want the header eye_x,eye_y,eye_z,target_x,target_y,target_z[,fov] \
             and one camera a line",
        ));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let with_fov = names.len() == 7;
    if !(names.len() == 6 || with_fov) || names.iter().zip(COLUMNS).any(|(a, b)| *a != b) {
        return Err(Error::parse(
            path,
            hline,
            format!(
                "the header is \"{header}\": want eye_x,eye_y,eye_z,target_x,target_y,target_z \
                 and optionally ,fov"
            ),
        ));
    }
    let mut out = Vec::new();
    for (line, l) in lines {
        if out.len() >= MAX_WALK_FRAMES {
            return Err(Error::parse(
                path,
                line,
                format!("more than {MAX_WALK_FRAMES} cameras: split the walk"),
            ));
        }
        let cells: Vec<&str> = l.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            return Err(Error::parse(
                path,
                line,
                format!("{} values, the header has {}", cells.len(), names.len()),
            ));
        }
        let mut v = [0.0f64; 7];
        for (k, c) in cells.iter().enumerate() {
            v[k] = match c.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                _ => {
                    return Err(Error::parse(
                        path,
                        line,
                        format!("{}: \"{c}\" is not a finite number", names[k]),
                    ));
                }
            };
        }
        let eye = DVec3::new(v[0], v[1], v[2]);
        let target = DVec3::new(v[3], v[4], v[5]);
        let mut camera = Camera {
            eye,
            target,
            ..*base
        };
        if with_fov {
            if !(v[6] > 0.0 && v[6] < 180.0) {
                return Err(Error::parse(
                    path,
                    line,
                    format!("fov {}: want degrees between 0 and 180", v[6]),
                ));
            }
            camera.projection = Projection::Perspective {
                fov_y_degrees: v[6],
            };
        }
        if let Some(b) = fit {
            camera.fit_depth_range(b);
        }
        camera
            .validate()
            .map_err(|e| Error::parse(path, line, e.to_string()))?;
        out.push(Frame0 { line, camera });
    }
    if out.is_empty() {
        return Err(Error::parse(
            path,
            hline,
            "the walk has a header but no camera",
        ));
    }
    Ok(out)
}

/// The library's options for a method and the flags.
fn options(args: &CullArgs, method: CullMethod) -> CullOptions {
    let mut o = CullOptions::with_method(method);
    o.clusters = !args.no_clusters;
    o.portal_bounding_box = args.portal_bounding_box;
    if let Some(n) = args.max_occluders {
        o.max_occluders = n;
    }
    // The depth panel of the explain picture.
    o.buffer.keep_image = args.explain.is_some();
    o
}

pub fn run(args: &CullArgs) -> Result<()> {
    let single = args.method.0.len() == 1;
    for (flag, given) in [
        ("--kept", args.kept.is_some()),
        ("--explain", args.explain.is_some()),
    ] {
        if given && !single {
            return Err(Error::option(
                flag,
                "give one --method: with all, the methods keep different faces",
            ));
        }
    }
    if let Some(n) = args.max_occluders
        && n == 0
    {
        return Err(Error::option("--max-occluders", "give at least 1 occluder"));
    }
    let mut outputs = Outputs::stage_with_extensions(
        args.view.scene.as_deref(),
        &[
            ("--stats-json", args.stats_json.as_deref()),
            ("--kept", args.kept.as_deref()),
            ("--explain", args.explain.as_deref()),
        ],
        args.naming,
        &[
            ("--kept", "npy", "NumPy arrays"),
            ("--explain", "png", "PNG images"),
        ],
    )?;
    let loaded = args.view.load()?;
    outputs.check_inputs(loaded.scene.source_files())?;
    let scene = &loaded.scene;
    let viewport = args.view.viewport(scene)?;
    let camera = args.view.camera(scene, viewport)?;
    let frames = match &args.walk {
        Some(path) => {
            let fit = (args.view.near.is_none() && args.view.far.is_none()).then(|| scene.bounds());
            let base = Camera {
                up: args.view.up.unwrap_or_else(|| scene.up()),
                ..camera
            };
            read_walk(path, &base, fit.as_ref())?
        }
        None => vec![Frame0 { line: 0, camera }],
    };
    let prep = args.view.prepare_options();
    let index = SceneIndex::new(scene);
    // Built once, outside the first frame's times.
    let start = Instant::now();
    let _ = index.clusters();
    let clusters_ms = start.elapsed().as_secs_f64() * 1e3;
    // The PVS (portals, on a scene with cells), with a progress bar on a terminal.
    if args.method.0.contains(&CullMethod::Portals) && scene.cells().is_some() {
        if std::io::stderr().is_terminal() {
            let (pb, feed) = crate::common::progress_bar("PVS");
            let _ = index.pvs_with_progress(&|done, total| feed(done as f64 / total.max(1) as f64));
            pb.finish_and_clear();
        } else {
            let _ = index.pvs();
        }
    }
    let bar = (frames.len() > 1 && std::io::stderr().is_terminal()).then(|| {
        let pb = indicatif::ProgressBar::new(frames.len() as u64);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} {msg:<10} [{bar:30}] {pos}/{len} {elapsed}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        pb.set_message("frames");
        pb
    });

    let mut report = String::new();
    let mut json_frames = Vec::new();
    let mut totals = vec![Totals::default(); args.method.0.len()];
    let mut kept_faces: Vec<bool> = Vec::new();
    let mut explain: Option<RgbImage> = None;
    let runs = args.view.with_threads(|| -> Result<()> {
        for (fi, frame) in frames.iter().enumerate() {
            let mut rows = Vec::new();
            for (mi, &method) in args.method.0.iter().enumerate() {
                let culling = index
                    .cull(&frame.camera, viewport, &options(args, method))
                    .map_err(|e| at_line(e, args.walk.as_deref(), frame.line))?;
                totals[mi].add(&culling);
                if args.kept.is_some() {
                    merge_kept(scene, &culling, &mut kept_faces);
                }
                if fi == 0 && args.explain.is_some() {
                    explain = Some(explain_image(
                        &index,
                        &frame.camera,
                        viewport,
                        &prep,
                        &culling,
                    )?);
                }
                rows.push(culling);
            }
            report.push_str(&frame_report(fi, frame, &rows, args.stats));
            json_frames.push(json!({
                "frame": fi,
                "line": frame.line,
                "eye": frame.camera.eye.to_array(),
                "target": frame.camera.target.to_array(),
                "methods": rows.iter().map(|c| json!({
                    "method": c.method.name(),
                    "stats": c.stats,
                    "occluders": c.occluders.len(),
                    "notes": c.notes,
                })).collect::<Vec<_>>(),
            }));
            if let Some(pb) = &bar {
                pb.inc(1);
            }
        }
        Ok(())
    })?;
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    runs?;

    if args.kept.is_some() {
        let ids: Vec<i32> = kept_faces
            .iter()
            .enumerate()
            .filter(|(_, k)| **k)
            .map(|(f, _)| i32::try_from(f).unwrap_or(i32::MAX))
            .collect();
        outputs.write("--kept", |p| write_i32_npy(p, &ids))?;
    }
    if let Some(img) = &explain {
        outputs.write("--explain", |p| img.write_png(p))?;
    }
    if args.stats_json.is_some() {
        let doc = json!({
            "scene": loaded.spec,
            "width": viewport.width,
            "height": viewport.height,
            "objects": scene.objects().len(),
            "faces": scene.face_count(),
            "clusters": index.clusters().len(),
            "clusters_ms": clusters_ms,
            "load_ms": loaded.load_ms,
            "methods": args.method.0.iter().map(|m| m.name()).collect::<Vec<_>>(),
            "frames": json_frames,
            "summary": args.method.0.iter().zip(&totals).map(|(m, t)| t.json(*m)).collect::<Vec<_>>(),
        });
        let text = serde_json::to_string_pretty(&doc).expect("JSON of plain values");
        outputs.write("--stats-json", |p| {
            std::fs::write(p, text + "\n").map_err(|e| Error::io(p, e))
        })?;
    }
    outputs.commit()?;

    if args.stats {
        outln!(
            "scene {} : {} objects, {} faces, {} clusters (built in {:.1} ms); loaded in {:.1} ms; {}x{}",
            loaded.spec,
            scene.objects().len(),
            scene.face_count(),
            index.clusters().len(),
            clusters_ms,
            loaded.load_ms,
            viewport.width,
            viewport.height
        );
    }
    crate::out::out!("{report}");
    if frames.len() > 1 {
        outln!("walk of {} frames:", frames.len());
        outln!(
            "  {:<15} {:>12} {:>12} {:>10} {:>10}",
            "method",
            "objects cul%",
            "faces cul%",
            "mean ms",
            "max ms"
        );
        for (m, t) in args.method.0.iter().zip(&totals) {
            outln!(
                "  {:<15} {:>12.1} {:>12.1} {:>10.3} {:>10.3}",
                m.name(),
                t.object_percent(),
                t.face_percent(),
                t.mean_ms(),
                t.max_ms
            );
        }
    }
    if let Some(p) = &args.kept {
        let n = kept_faces.iter().filter(|k| **k).count();
        outln!("wrote {} ({n} face ids)", p.display());
    }
    if let Some(p) = &args.explain {
        outln!(
            "wrote {} (culled: frustum blue, portal green, occluder orange, buffer magenta; \
             kept: grey)",
            p.display()
        );
    }
    Ok(())
}

/// An error of a walk's frame named by its file and line.
fn at_line(e: Error, walk: Option<&Path>, line: usize) -> Error {
    match walk {
        Some(p) if line > 0 => Error::parse(p, line, e.to_string()),
        _ => e,
    }
}

/// The sums of a method over a walk.
#[derive(Clone, Debug, Default)]
struct Totals {
    frames: u64,
    objects_tested: u64,
    objects_culled: u64,
    faces_tested: u64,
    faces_culled: u64,
    ms: f64,
    max_ms: f64,
}

impl Totals {
    fn add(&mut self, c: &Culling) {
        let s = &c.stats;
        self.frames += 1;
        self.objects_tested += s.objects_tested;
        self.objects_culled += s.objects_culled;
        self.faces_tested += s.faces_tested;
        self.faces_culled += s.faces_culled;
        self.ms += s.total_ms;
        self.max_ms = self.max_ms.max(s.total_ms);
    }

    fn object_percent(&self) -> f64 {
        percent(self.objects_culled, self.objects_tested)
    }

    fn face_percent(&self) -> f64 {
        percent(self.faces_culled, self.faces_tested)
    }

    fn mean_ms(&self) -> f64 {
        if self.frames == 0 {
            0.0
        } else {
            self.ms / self.frames as f64
        }
    }

    fn json(&self, m: CullMethod) -> serde_json::Value {
        json!({
            "method": m.name(),
            "frames": self.frames,
            "objects_culled_percent": self.object_percent(),
            "faces_culled_percent": self.face_percent(),
            "mean_ms": self.mean_ms(),
            "max_ms": self.max_ms,
        })
    }
}

fn percent(a: u64, b: u64) -> f64 {
    if b == 0 {
        0.0
    } else {
        100.0 * a as f64 / b as f64
    }
}

/// The report of one frame: a row per method (objects, clusters and faces tested,
/// culled and drawn; the total time), and with `detail` the culled ones by reason and
/// the time of each stage.
fn frame_report(fi: usize, frame: &Frame0, rows: &[Culling], detail: bool) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let e = frame.camera.eye;
    let t = frame.camera.target;
    let _ = writeln!(
        s,
        "frame {fi}{}: eye {},{},{} target {},{},{}",
        if frame.line > 0 {
            format!(" (line {})", frame.line)
        } else {
            String::new()
        },
        r(e.x),
        r(e.y),
        r(e.z),
        r(t.x),
        r(t.y),
        r(t.z)
    );
    let _ = writeln!(
        s,
        "  {:<15} {:>28} {:>29} {:>27} {:>9}",
        "method",
        "objects tested/culled/drawn",
        "clusters tested/culled/drawn",
        "faces tested/culled/drawn",
        "ms"
    );
    for c in rows {
        let st = &c.stats;
        let triple = |a: u64, b: u64| format!("{a}/{b}/{}", a - b.min(a));
        let _ = writeln!(
            s,
            "  {:<15} {:>28} {:>29} {:>27} {:>9.3}",
            c.method.name(),
            triple(st.objects_tested, st.objects_culled),
            triple(st.clusters_tested, st.clusters_culled),
            triple(st.faces_tested, st.faces_culled),
            st.total_ms
        );
    }
    if detail {
        for c in rows {
            let st = &c.stats;
            let o = st.objects_by_reason;
            let k = st.clusters_by_reason;
            let _ = writeln!(
                s,
                "  {:<15} culled objects: frustum {} portal {} occluder {} buffer {}; clusters: frustum {} portal {} occluder {} buffer {}; occluders used {}",
                c.method.name(),
                o.frustum,
                o.portal,
                o.occluder,
                o.buffer,
                k.frustum,
                k.portal,
                k.occluder,
                k.buffer,
                c.occluders.len()
            );
            let stages: Vec<String> = st
                .stages
                .iter()
                .map(|(n, ms)| format!("{n} {ms:.3} ms"))
                .collect();
            let _ = writeln!(
                s,
                "  {:<15} stages: {}",
                "",
                if stages.is_empty() {
                    "none".to_string()
                } else {
                    stages.join(", ")
                }
            );
            for n in &c.notes {
                let _ = writeln!(s, "  {:<15} note: {n}", "");
            }
        }
    } else {
        for c in rows {
            for n in &c.notes {
                errln!("note: {}: {n}", c.method.name());
            }
        }
    }
    s
}

fn r(x: f64) -> String {
    crate::common::readable(x)
}

/// The `--stats` rows of `render` for its culling stage.
pub fn print_stage_rows(c: &Culling) {
    let st = &c.stats;
    outln!(
        "{:<48} {:>9} {:>12} {:>12} {:>9.2}",
        format!("culling: {} (objects)", c.method.name()),
        "objects",
        st.objects_tested,
        st.objects_tested - st.objects_culled.min(st.objects_tested),
        st.total_ms
    );
    outln!(
        "{:<48} {:>9} {:>12} {:>12} {:>9}",
        "culling: clusters",
        "clusters",
        st.clusters_tested,
        st.clusters_tested - st.clusters_culled.min(st.clusters_tested),
        ""
    );
    outln!(
        "{:<48} {:>9} {:>12} {:>12} {:>9}",
        "culling: faces",
        "faces",
        st.faces_tested,
        st.faces_tested - st.faces_culled.min(st.faces_tested),
        ""
    );
    for (name, ms) in &st.stages {
        outln!("  {:<46} {:>45.2}", format!("culling stage: {name}"), ms);
    }
}

/// Marks in `kept` (per face id) the faces of polygons the run kept.
fn merge_kept(scene: &Scene, c: &Culling, kept: &mut Vec<bool>) {
    kept.resize(scene.face_count() as usize, false);
    let mut p = 0usize;
    for o in scene.objects() {
        for i in 0..o.mesh.polygon_count() {
            if !c.faces[p] {
                kept[(o.first_face + o.mesh.polygon_face(i)) as usize] = true;
            }
            p += 1;
        }
    }
}

/// Writes a one-dimensional int32 NumPy array (version 1.0, little endian).
pub fn write_i32_npy(path: &Path, values: &[i32]) -> Result<()> {
    let mut header = format!(
        "{{'descr': '<i4', 'fortran_order': False, 'shape': ({},), }}",
        values.len()
    );
    // Magic (6) + version (2) + length (2) + header + '\n', a multiple of 64.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.next_multiple_of(64) - total));
    header.push('\n');
    let mut data = Vec::with_capacity(10 + header.len() + 4 * values.len());
    data.extend_from_slice(b"\x93NUMPY\x01\x00");
    data.extend_from_slice(&(header.len() as u16).to_le_bytes());
    data.extend_from_slice(header.as_bytes());
    for v in values {
        data.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, data).map_err(|e| Error::io(path, e))
}

/// The colour of a reason in the explain picture.
fn reason_colour(r: CullReason) -> [u8; 3] {
    match r {
        CullReason::Frustum => [60, 110, 235],
        CullReason::Portal => [40, 185, 70],
        CullReason::Occluder(_) => [245, 140, 30],
        CullReason::Buffer => [220, 50, 200],
        _ => [255, 255, 0],
    }
}

/// The explain picture: the whole scene's z-buffer, shaded (what is kept), with the
/// culled objects and clusters drawn through it in the colour of their reason (they
/// are hidden or outside the view: a z-buffer of the culled part alone, blended over
/// the kept picture), a legend at the bottom left; and, to the right, the occlusion
/// buffer's depth (near white, far dark, uncovered black) when the run kept one.
pub fn explain_image(
    index: &SceneIndex<'_>,
    camera: &Camera,
    viewport: Viewport,
    prep: &obscura::PrepareOptions,
    culling: &Culling,
) -> Result<RgbImage> {
    let scene = index.scene();
    let o = RenderOptions::default();
    let plain = View::new(scene, camera, viewport, prep)?;
    let (full, _) = index.render_view(&plain, Algorithm::ZBuffer, &o)?;
    // The culled part alone: the decisions inverted (kept objects and clusters culled).
    let clusters = index.clusters();
    let mut inverse = Culling::keep_all(index, culling.method);
    for (k, r) in culling.objects.iter().enumerate() {
        if r.is_none() {
            for cl in clusters.of_object(k) {
                if culling.clusters[cl].is_none() {
                    inverse.cull_cluster(cl, CullReason::Frustum);
                }
            }
        }
    }
    inverse.finish(index);
    let culled_view = View::new_culled(scene, camera, viewport, prep, inverse)?;
    let (hidden, _) = index.render_view(&culled_view, Algorithm::ZBuffer, &o)?;
    let reasons = face_reasons(index, culling);
    let mut left = full.shade(scene, camera);
    for (k, px) in left.pixels.iter_mut().enumerate() {
        let id = hidden.ids[k];
        if id == BACKGROUND {
            if full.ids[k] != BACKGROUND {
                let g = (u32::from(px[0]) + u32::from(px[1]) + u32::from(px[2])) / 3;
                *px = [g as u8; 3];
            }
            continue;
        }
        let Some(r) = reasons.get(id as usize).copied().flatten() else {
            continue;
        };
        let c = reason_colour(r);
        *px = if full.ids[k] == BACKGROUND {
            c
        } else {
            // Seen through what hides it.
            let g = (u32::from(px[0]) + u32::from(px[1]) + u32::from(px[2])) / 3;
            [0, 1, 2].map(|i| ((u32::from(c[i]) * 3 + g * 2) / 5) as u8)
        };
    }
    draw_legend(&mut left);
    let Some(buffer) = &culling.buffer_image else {
        return Ok(left);
    };
    let right = buffer_picture(buffer, viewport);
    let (w, h) = (viewport.width, viewport.height);
    let mut out = RgbImage::new(2 * w, h);
    for y in 0..h as usize {
        let row = y * 2 * w as usize;
        out.pixels[row..row + w as usize]
            .copy_from_slice(&left.pixels[y * w as usize..(y + 1) * w as usize]);
        out.pixels[row + w as usize..row + 2 * w as usize]
            .copy_from_slice(&right.pixels[y * w as usize..(y + 1) * w as usize]);
    }
    Ok(out)
}

/// Per face id, the reason of the culled object or cluster it belongs to (the first
/// culled polygon's; `None` if any of its polygons is kept).
fn face_reasons(index: &SceneIndex<'_>, c: &Culling) -> Vec<Option<CullReason>> {
    let scene = index.scene();
    let clusters = index.clusters();
    let mut out: Vec<Option<CullReason>> = vec![None; scene.face_count() as usize];
    let mut kept = vec![false; scene.face_count() as usize];
    for (k, o) in scene.objects().iter().enumerate() {
        for cl in clusters.of_object(k) {
            let r = c.objects[k].or(c.clusters[cl]);
            for &p in clusters.polygons(cl) {
                let f = (o.first_face + o.mesh.polygon_face(p as usize)) as usize;
                match r {
                    None => kept[f] = true,
                    Some(r) => {
                        out[f].get_or_insert(r);
                    }
                }
            }
        }
    }
    for (f, k) in kept.iter().enumerate() {
        if *k {
            out[f] = None;
        }
    }
    out
}

/// The occlusion buffer's depth scaled to the viewport: near white, far dark grey,
/// uncovered black.
fn buffer_picture(b: &BufferImage, viewport: Viewport) -> RgbImage {
    let (w, h) = (viewport.width, viewport.height);
    let mut img = RgbImage::new(w, h);
    let finite = b.depth.iter().copied().filter(|d| d.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    if b.width == 0 || b.height == 0 || b.depth.len() != (b.width * b.height) as usize {
        return img;
    }
    for y in 0..h {
        let by = (u64::from(y) * u64::from(b.height) / u64::from(h)) as u32;
        for x in 0..w {
            let bx = (u64::from(x) * u64::from(b.width) / u64::from(w)) as u32;
            let d = b.depth[(by * b.width + bx) as usize];
            let v = if d.is_finite() {
                let t = if hi > lo { (d - lo) / (hi - lo) } else { 0.0 };
                (235.0 - 180.0 * t) as u8
            } else {
                0
            };
            img.pixels[(y * w + x) as usize] = [v, v, v];
        }
    }
    img
}

/// Glyphs of a 3x5 pixel font for the legend's words (rows top to bottom, bit 2 the
/// left column).
fn glyph(c: char) -> [u8; 5] {
    match c {
        'a' => [0b010, 0b101, 0b111, 0b101, 0b101],
        'b' => [0b110, 0b101, 0b110, 0b101, 0b110],
        'c' => [0b011, 0b100, 0b100, 0b100, 0b011],
        'd' => [0b110, 0b101, 0b101, 0b101, 0b110],
        'e' => [0b111, 0b100, 0b110, 0b100, 0b111],
        'f' => [0b111, 0b100, 0b110, 0b100, 0b100],
        'k' => [0b101, 0b101, 0b110, 0b101, 0b101],
        'l' => [0b100, 0b100, 0b100, 0b100, 0b111],
        'm' => [0b101, 0b111, 0b111, 0b101, 0b101],
        'o' => [0b010, 0b101, 0b101, 0b101, 0b010],
        'p' => [0b110, 0b101, 0b110, 0b100, 0b100],
        'r' => [0b110, 0b101, 0b110, 0b101, 0b101],
        's' => [0b011, 0b100, 0b010, 0b001, 0b110],
        't' => [0b111, 0b010, 0b010, 0b010, 0b010],
        'u' => [0b101, 0b101, 0b101, 0b101, 0b111],
        _ => [0; 5],
    }
}

/// The legend: a swatch and a word per reason, bottom left (left out on pictures too
/// small for it).
fn draw_legend(img: &mut RgbImage) {
    let scale = if img.height >= 400 { 2 } else { 1 };
    let entries = [
        ("kept", [170u8, 170, 170]),
        ("frustum", reason_colour(CullReason::Frustum)),
        ("portal", reason_colour(CullReason::Portal)),
        ("occluder", reason_colour(CullReason::Occluder(0))),
        ("buffer", reason_colour(CullReason::Buffer)),
    ];
    let line = 7 * scale;
    let width = 4 * 9 * scale + 10 * scale;
    let height = entries.len() as u32 * line + 2 * scale;
    if img.width < width + 4 || img.height < height + 4 {
        return;
    }
    let (x0, y0) = (2, img.height - height - 2);
    let mut put = |x: u32, y: u32, c: [u8; 3]| {
        if x < img.width && y < img.height {
            img.pixels[(y * img.width + x) as usize] = c;
        }
    };
    for y in 0..height {
        for x in 0..width {
            put(x0 + x, y0 + y, [20, 20, 20]);
        }
    }
    for (i, (word, colour)) in entries.iter().enumerate() {
        let top = y0 + scale + i as u32 * line;
        for y in 0..5 * scale {
            for x in 0..5 * scale {
                put(x0 + scale + x, top + y, *colour);
            }
        }
        for (j, ch) in word.chars().enumerate() {
            let g = glyph(ch);
            let left = x0 + 8 * scale + j as u32 * 4 * scale;
            for (row, bits) in g.iter().enumerate() {
                for col in 0..3u32 {
                    if bits & (0b100 >> col) != 0 {
                        for dy in 0..scale {
                            for dx in 0..scale {
                                put(
                                    left + col * scale + dx,
                                    top + row as u32 * scale + dy,
                                    [235, 235, 235],
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Camera {
        Camera::perspective(DVec3::ZERO, DVec3::Z, DVec3::Y, 60.0, 0.1, 100.0)
    }

    #[test]
    fn a_walk_reads_its_cameras_and_names_bad_lines() {
        let p = Path::new("walk.csv");
        let ok = "eye_x,eye_y,eye_z,target_x,target_y,target_z,fov\n# a comment\n\n1,2,3,4,5,6,70\n0,0,0,0,0,1,45\n";
        let w = parse_walk(p, ok, &base(), None).unwrap();
        assert_eq!(w.len(), 2);
        assert_eq!(w[0].line, 4);
        assert_eq!(w[0].camera.eye, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(
            w[0].camera.projection,
            Projection::Perspective {
                fov_y_degrees: 70.0
            }
        );
        let bad = [
            ("", "walk.csv:1:"),
            ("x,y,z\n", "walk.csv:1: the header"),
            (
                "eye_x,eye_y,eye_z,target_x,target_y,target_z\n1,2,3,4,5\n",
                "walk.csv:2: 5 values",
            ),
            (
                "eye_x,eye_y,eye_z,target_x,target_y,target_z\n1,2,3,4,5,6\n1,2,3,4,5,nan\n",
                "walk.csv:3: target_z",
            ),
            (
                "eye_x,eye_y,eye_z,target_x,target_y,target_z,fov\n1,2,3,4,5,6,200\n",
                "walk.csv:2: fov",
            ),
            (
                "eye_x,eye_y,eye_z,target_x,target_y,target_z\n1,2,3,1,2,3\n",
                "walk.csv:2:",
            ),
            (
                "eye_x,eye_y,eye_z,target_x,target_y,target_z\n",
                "no camera",
            ),
        ];
        for (text, want) in bad {
            let e = parse_walk(p, text, &base(), None).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }

    /// The explain picture colours a culled object by its reason where it lies, and
    /// keeps the kept ones grey: a cube culled (on purpose, against the rule) by the
    /// buffer shows magenta through the floor's picture.
    #[test]
    fn explain_colours_culled_objects_by_reason() {
        let scene = obscura::scene::demo::default_scene();
        let index = SceneIndex::new(&scene);
        let vp = Viewport::new(96, 64).unwrap();
        let camera = scene.default_camera(vp.aspect());
        let prep = obscura::PrepareOptions::default();
        let mut c = index
            .cull(&camera, vp, &CullOptions::with_method(CullMethod::Frustum))
            .unwrap();
        let cube = scene
            .objects()
            .iter()
            .position(|o| o.name == "cube")
            .unwrap();
        let img = explain_image(&index, &camera, vp, &prep, &c).unwrap();
        // Magenta (the buffer's colour), pure or blended over grey.
        let count = |img: &RgbImage| {
            img.pixels
                .iter()
                .filter(|p| {
                    let [r, g, b] = p.map(i32::from);
                    r > g + 40 && b > g + 40
                })
                .count()
        };
        // The legend's swatch alone.
        let legend = 5 * 5;
        assert_eq!((img.width, img.height), (96, 64));
        assert_eq!(count(&img), legend);
        c.cull_object(cube, CullReason::Buffer);
        c.finish(&index);
        let img = explain_image(&index, &camera, vp, &prep, &c).unwrap();
        assert!(count(&img) > legend, "{}", count(&img));
        // With the buffer's depths the picture doubles its width.
        c.buffer_image = Some(BufferImage {
            width: 4,
            height: 2,
            depth: vec![1.0, 2.0, f32::INFINITY, 3.0, 1.0, 1.0, 1.0, 1.0],
        });
        let img = explain_image(&index, &camera, vp, &prep, &c).unwrap();
        assert_eq!((img.width, img.height), (192, 64));
        // Uncovered buffer pixels are black, the nearest white-ish.
        assert_eq!(img.pixels[96 + 2 * 24 + 1], [0, 0, 0]);
        assert_eq!(img.pixels[96 + 1], [235, 235, 235]);
    }

    #[test]
    fn npy_of_i32_has_an_aligned_header_and_the_values() {
        let dir = std::env::temp_dir().join(format!("obscura-cull-npy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("k.npy");
        write_i32_npy(&p, &[3, -1, 7]).unwrap();
        let b = std::fs::read(&p).unwrap();
        assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
        let hl = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + hl) % 64, 0);
        let h = std::str::from_utf8(&b[10..10 + hl]).unwrap();
        assert!(h.contains("'shape': (3,)"), "{h}");
        let v: Vec<i32> = b[10 + hl..]
            .chunks(4)
            .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(v, [3, -1, 7]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
