//! `obscura render`.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use obscura::surface::Algorithm;
use obscura::{Result, SceneIndex};
use serde_json::json;

use crate::common::{AlgoArgs, CullArgs, ViewArgs};
use crate::errln;
use crate::out::outln;
use crate::outputs::{OutputArgs, Outputs};

pub const EXAMPLES: &str = "\
Examples:
  obscura render                                   # the default demo to obscura.png
  obscura render demo:city --size 1920x1080 --stats
  obscura render ../shared/data/sponza.obj --eye 0,-10,2 --target 0,10,4 --up 0,0,1 --fov 60 \\
      --size 1920x1080 --threads 1 --stats-json sponza.json
  obscura render model.obj --algo bsp --ids ids.npy --depth depth.npy
  obscura render demo:seed-task -o task.png --view ids";

/// What the PNG shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ImageView {
    /// Flat-shaded colours.
    Shaded,
    /// A false colour per face id.
    Ids,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Hidden-surface algorithm: zbuffer, scanline, depth-sort, depth-sort-matrix, bsp,
    /// warnock, raycast, raycast-bounds, raycast-bvh, raycast-grid, octree.
    #[arg(long, default_value = "zbuffer", value_parser = crate::common::parse_algo)]
    pub algo: Algorithm,
    #[command(flatten)]
    pub tuning: AlgoArgs,
    #[command(flatten)]
    pub culling: CullArgs,
    /// The PNG to write.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "OUT.png",
        default_value = "obscura.png"
    )]
    pub output: PathBuf,
    /// What the PNG shows.
    #[arg(long = "view", value_enum, default_value = "shaded")]
    pub image: ImageView,
    /// Write face ids as an int32 NumPy array (height, width), -1 for background.
    #[arg(long, value_name = "IDS.npy")]
    pub ids: Option<PathBuf>,
    /// Write eye-space depths as a float32 NumPy array (height, width), +inf for background.
    #[arg(long, value_name = "DEPTH.npy")]
    pub depth: Option<PathBuf>,
    /// Print per-stage counts and times.
    #[arg(long)]
    pub stats: bool,
    /// Write the statistics as JSON (load_ms, render_ms, stages, algorithm stats).
    #[arg(long, value_name = "FILE.json")]
    pub stats_json: Option<PathBuf>,
    #[command(flatten)]
    pub naming: OutputArgs,
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let mut outputs = Outputs::stage(
        args.view.scene.as_deref(),
        &[
            ("-o", Some(&args.output)),
            ("--ids", args.ids.as_deref()),
            ("--depth", args.depth.as_deref()),
            ("--stats-json", args.stats_json.as_deref()),
        ],
        args.naming,
    )?;
    let loaded = args.view.load()?;
    outputs.check_inputs(loaded.scene.source_files())?;
    let scene = &loaded.scene;
    let viewport = args.view.viewport(scene)?;
    let camera = args.view.camera(scene, viewport)?;
    for w in args.tuning.unused_warnings(&[args.algo]) {
        crate::out::errln!("warning: {w}");
    }
    let mut options = args
        .tuning
        .options_with_budget(args.view.memory_limit)
        .with_time_limit(args.view.remaining_time());
    // Slow algorithms on big scenes (brute-force ray casting of a million triangles
    // takes hours) show how far they are, when someone is watching.
    let bar = std::io::stderr()
        .is_terminal()
        .then(|| crate::common::progress_bar(args.algo.name()));
    if let Some((_, progress)) = &bar {
        options = options.with_progress(progress.clone());
    }
    let prep = args.view.prepare_options();
    let threads = args.view.threads.unwrap_or(0);

    let rendered = args.view.with_threads(|| {
        let start = Instant::now();
        // The scene's structures through its index, as `compare` and `bench` take them
        // (one render here, so each is built once either way); the culling stage
        // (`--cull`) decides what the view leaves out before its vertices are
        // transformed.
        let index = SceneIndex::new(scene);
        let view = index.view_culled(&camera, viewport, &prep, &args.culling.options())?;
        let culling = view.culling().cloned();
        let view = view.into_prepared();
        let prepare_ms = start.elapsed().as_secs_f64() * 1e3;
        let (frame, stats) = index
            .render(&view, args.algo, &options)
            .map_err(|e| e.in_input(&loaded.spec))?;
        let render_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok::<_, obscura::Error>((
            view.stats().clone(),
            frame,
            stats,
            render_ms,
            prepare_ms,
            culling,
        ))
    })?;
    if let Some((bar, _)) = &bar {
        bar.finish_and_clear();
    }
    let (stages, frame, stats, render_ms, prepare_ms, culling) = rendered?;
    if let Some(c) = &culling {
        for n in &c.notes {
            errln!("note: culling: {n}");
        }
    }
    if let Some(note) = crate::common::grid_note(&stats) {
        errln!("note: {note}");
    }

    let image = match args.image {
        ImageView::Shaded => frame.shade(scene, &camera),
        ImageView::Ids => frame.id_false_colour(),
    };
    outputs.write("-o", |p| image.write_png(p))?;
    if args.ids.is_some() {
        outputs.write("--ids", |p| frame.write_ids_npy(p))?;
    }
    if args.depth.is_some() {
        outputs.write("--depth", |p| frame.write_depth_npy(p))?;
    }
    if args.stats_json.is_some() {
        let doc = json!({
            "scene": loaded.spec,
            "algorithm": args.algo.name(),
            "cull": args.culling.cull.name(),
            "culling": culling.as_ref().map(|c| &c.stats),
            "width": viewport.width,
            "height": viewport.height,
            "threads": if threads == 0 { rayon::current_num_threads() } else { threads },
            "objects": scene.objects().len(),
            "faces": scene.face_count(),
            "triangles": scene.triangle_count(),
            "load_ms": loaded.load_ms,
            "render_ms": render_ms,
            "prepare_ms": prepare_ms,
            "algorithm_ms": stats.time_ms,
            "covered_pixels": frame.covered_pixels(),
            "stages": stages.stages,
            "stats": stats,
        });
        let text = serde_json::to_string_pretty(&doc).expect("JSON of plain values");
        outputs.write("--stats-json", |p| {
            std::fs::write(p, text + "\n").map_err(|e| obscura::Error::io(p, e))
        })?;
    }
    // Every file is in place before the report, which a closed pipe may cut short.
    outputs.commit()?;

    if args.stats {
        outln!(
            "scene {} : {} objects, {} faces, {} triangles; loaded in {:.1} ms",
            loaded.spec,
            scene.objects().len(),
            scene.face_count(),
            scene.triangle_count(),
            loaded.load_ms
        );
        outln!(
            "{:<48} {:>9} {:>12} {:>12} {:>9}",
            "stage",
            "unit",
            "in",
            "out",
            "ms"
        );
        if let Some(c) = &culling {
            crate::cull::print_stage_rows(c);
        }
        for s in &stages.stages {
            outln!(
                "{:<48} {:>9} {:>12} {:>12} {:>9.2}",
                s.stage,
                s.unit,
                s.input,
                s.output,
                s.ms
            );
        }
        let algo_ms = stats.time_ms;
        outln!(
            "{:<48} {:>9} {:>12} {:>12} {:>9.2}",
            format!("visibility: {}", args.algo),
            "pixels",
            viewport.pixel_count(),
            frame.covered_pixels(),
            algo_ms
        );
        for (k, v) in stats.algorithm.entries() {
            outln!("  {k:<46} {v:>12}");
        }
        outln!(
            "render_ms {render_ms:.2} (prepare {prepare_ms:.2}, {} {algo_ms:.2})",
            args.algo
        );
    }
    outln!(
        "wrote {} ({}x{}, {}, {:.1} ms)",
        args.output.display(),
        viewport.width,
        viewport.height,
        args.algo,
        render_ms
    );
    Ok(())
}
