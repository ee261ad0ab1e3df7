//! `obscura compare`: every algorithm on one view, checked against the z-buffer.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use obscura::SceneIndex;
use obscura::frame::{available_memory, check_frames_fit};
use obscura::surface::{Algorithm, Stats};
use obscura::{Frame, Result, RgbImage, Viewport};
use serde_json::json;

use crate::common::{AlgoArgs, CullArgs, ViewArgs, progress_bar};
use crate::grid;
use crate::out::out;
use crate::outputs::{OutputArgs, Outputs};

pub const EXAMPLES: &str = "\
Examples:
  obscura compare                                  # every algorithm on the default demo
  obscura compare demo:city --size 480x270 --algos zbuffer,scanline,bsp,raycast-bvh
  obscura compare model.obj --eye 3,2,5 --target 0,0,0 -o grid.png --json compare.json";

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Comma-separated algorithms (default: all). The z-buffer always runs as reference.
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = crate::common::parse_algo)]
    pub algos: Option<Vec<Algorithm>>,
    #[command(flatten)]
    pub tuning: AlgoArgs,
    #[command(flatten)]
    pub culling: CullArgs,
    /// The grid image (PNG): each algorithm's picture and its difference mask.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "GRID.png",
        default_value = "compare.png"
    )]
    pub output: PathBuf,
    /// Also write the table as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub naming: OutputArgs,
}

/// Why an algorithm has no frame.
enum Failure {
    /// Over the memory budget: skipped, the others go on.
    Skipped(String),
    /// Any other error.
    Error(String),
}

/// One row of the table.
struct Row {
    algorithm: Algorithm,
    result: std::result::Result<(Frame, Stats, f64), Failure>,
}

/// The stats worth a column: everything but the time, compactly.
fn summary(stats: &Stats) -> String {
    stats
        .algorithm
        .entries()
        .into_iter()
        .take(5)
        .map(|(k, v)| {
            if v.fract() == 0.0 {
                format!("{k}={v:.0}")
            } else {
                format!("{k}={v:.2}")
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The picture dimmed, with pixels that differ from the reference in red and pixels
/// where only one of them shows a face in yellow.
fn difference_mask(picture: &RgbImage, frame: &Frame, reference: &Frame) -> RgbImage {
    let mut out = picture.clone();
    for (k, p) in out.pixels.iter_mut().enumerate() {
        let (a, b) = (frame.ids[k], reference.ids[k]);
        *p = if a == b {
            p.map(|c| (u16::from(c) * 2 / 5) as u8)
        } else if a == obscura::BACKGROUND || b == obscura::BACKGROUND {
            [255, 220, 0]
        } else {
            [255, 40, 40]
        };
    }
    out
}

/// Frames' worth of memory (a frame and its shaded image, 11 bytes a pixel) that
/// comparing `algorithms` holds at its peak: each algorithm's frame (8 bytes a pixel),
/// picture and difference mask (3 each) and their two tiles in the grid (6), plus one
/// for the algorithm being run.
fn frames_held(algorithms: usize) -> u64 {
    2 * algorithms as u64 + 1
}

/// Refuses a comparison whose frames would not fit in `available` bytes, before any
/// rendering (it aborted allocating after minutes at 16384x16384).
fn check_memory(viewport: Viewport, algorithms: usize, available: Option<u64>) -> Result<()> {
    check_frames_fit(viewport, frames_held(algorithms), available).map_err(|e| {
        obscura::Error::option(
            "--size",
            format!(
                "{e}: compare keeps the frame, picture and difference mask of each of its \
                 {algorithms} algorithms; try a smaller --size or fewer --algos"
            ),
        )
    })
}

pub fn run(args: &CompareArgs) -> Result<()> {
    let mut outputs = Outputs::stage(
        args.view.scene.as_deref(),
        &[("-o", Some(&args.output)), ("--json", args.json.as_deref())],
        args.naming,
    )?;
    let loaded = args.view.load()?;
    outputs.check_inputs(loaded.scene.source_files())?;
    let scene = &loaded.scene;
    let viewport = args.view.viewport_or(scene, (480, 270))?;
    let camera = args.view.camera(scene, viewport)?;
    let prep = args.view.prepare_options();
    let mut algos: Vec<Algorithm> = args
        .algos
        .clone()
        .unwrap_or_else(|| Algorithm::ALL.to_vec());
    algos.insert(0, Algorithm::ZBuffer);
    let mut seen = Vec::new();
    algos.retain(|a| {
        let first = !seen.contains(a);
        seen.push(*a);
        first
    });
    check_memory(viewport, algos.len(), available_memory())?;
    for w in args.tuning.unused_warnings(&algos) {
        crate::out::errln!("warning: {w}");
    }

    let rows = args.view.with_threads(|| {
        // One index for all algorithms: the triangles, the BVH (and the grid, the BSP
        // tree, the octree) are built once and shared by the algorithms that use them.
        // The culling stage (`--cull`) runs once: every algorithm gets the same view.
        let index = SceneIndex::new(scene);
        let view = index
            .view_culled(&camera, viewport, &prep, &args.culling.options())?
            .into_prepared();
        let mut rows = Vec::new();
        // One time limit for the run: the cheap algorithms first, so that on a heavy
        // scene the costly ones are the ones skipped for the time left.
        let mut order: Vec<usize> = (0..algos.len()).collect();
        order.sort_by_key(|&i| (i != 0, cost_rank(algos[i])));
        for &algorithm in order.iter().map(|&i| &algos[i]) {
            let (pb, progress) = progress_bar(algorithm.name());
            let options = args
                .tuning
                .options_with_budget(args.view.memory_limit)
                .with_progress(progress)
                .with_time_limit(args.view.remaining_time());
            let start = Instant::now();
            let result = index
                .render(&view, algorithm, &options)
                .map(|(f, s)| (f, s, start.elapsed().as_secs_f64() * 1e3))
                .map_err(|e| {
                    let skipped = crate::common::is_over_budget(&e);
                    let text = crate::common::cli_error(e).to_string();
                    if skipped {
                        Failure::Skipped(text)
                    } else {
                        Failure::Error(text)
                    }
                });
            pb.finish_and_clear();
            rows.push(Row { algorithm, result });
        }
        // Shown in the order asked for.
        rows.sort_by_key(|r| algos.iter().position(|&a| a == r.algorithm));
        Ok::<_, obscura::Error>(rows)
    })??;

    let reference = match &rows[0].result {
        Ok((f, _, _)) => f,
        Err(Failure::Skipped(e) | Failure::Error(e)) => {
            return Err(obscura::Error::option(
                "--algos",
                format!("the z-buffer failed: {e}"),
            ));
        }
    };
    let pixels = viewport.pixel_count() as f64;
    // The table is printed once the files are in place: a closed pipe may cut it short.
    let mut report = format!(
        "{} at {}x{}: {} faces, {} triangles\n",
        loaded.spec,
        viewport.width,
        viewport.height,
        scene.face_count(),
        scene.triangle_count()
    );
    report += &format!(
        "{:<18} {:>10} {:>10} {:>9}  structure\n",
        "algorithm", "time ms", "differ", "agree %"
    );
    let mut tiles = Vec::new();
    let mut table = Vec::new();
    for row in &rows {
        match &row.result {
            Ok((frame, stats, ms)) => {
                let differ = frame.differences(reference).len();
                let agree = 100.0 * (1.0 - differ as f64 / pixels);
                report += &format!(
                    "{:<18} {:>10.2} {:>10} {:>9.3}  {}\n",
                    row.algorithm.name(),
                    ms,
                    differ,
                    agree,
                    summary(stats)
                );
                let picture = frame.shade(scene, &camera);
                let mask = difference_mask(&picture, frame, reference);
                tiles.push((row.algorithm.name().to_string(), picture));
                tiles.push((format!("{} diff: {differ} px", row.algorithm.name()), mask));
                table.push(json!({
                    "algorithm": row.algorithm.name(), "time_ms": ms, "differing_pixels": differ,
                    "agree_percent": agree, "stats": stats,
                }));
            }
            Err(failure) => {
                // An error or a skip: a row without figures, and its reason under the
                // JSON key of its kind.
                let (kind, e) = match failure {
                    Failure::Error(e) => ("error", e),
                    Failure::Skipped(e) => ("skipped", e),
                };
                report += &format!(
                    "{:<18} {:>10} {:>10} {:>9}  {kind}: {e}\n",
                    row.algorithm.name(),
                    "-",
                    "-",
                    "-"
                );
                table.push(json!({ "algorithm": row.algorithm.name(), kind: e }));
            }
        }
    }
    let grid = grid::compose(&tiles, tiles.len().clamp(1, 4));
    outputs.write("-o", |p| grid.write_png(p))?;
    if args.json.is_some() {
        let doc = json!({
            "scene": loaded.spec, "width": viewport.width, "height": viewport.height,
            "load_ms": loaded.load_ms, "algorithms": table,
        });
        let text = serde_json::to_string_pretty(&doc).expect("JSON of plain values");
        outputs.write("--json", |p| {
            std::fs::write(p, text + "\n").map_err(|e| obscura::Error::io(p, e))
        })?;
    }
    outputs.commit()?;
    out!(
        "{report}wrote {} (each algorithm's picture and its differences from the z-buffer in red)\n",
        args.output.display()
    );
    Ok(())
}

/// Where an algorithm runs in `compare`'s order, cheapest first on heavy scenes (the
/// z-buffer, the reference, always runs first): the image-order algorithms and the
/// hierarchies, then the structures that grow with overlaps, then the painters and
/// the ray casters without a hierarchy.
// `_`: the library may add algorithms (the enum is to become non-exhaustive).
#[allow(unreachable_patterns)]
fn cost_rank(a: Algorithm) -> u8 {
    match a {
        Algorithm::ZBuffer => 0,
        Algorithm::Scanline => 1,
        Algorithm::RaycastBvh => 2,
        Algorithm::Warnock => 3,
        Algorithm::RaycastGrid => 4,
        Algorithm::Octree => 5,
        Algorithm::DepthSortMatrix => 6,
        Algorithm::Bsp => 7,
        Algorithm::DepthSort => 8,
        Algorithm::RaycastBounds => 9,
        Algorithm::Raycast => 10,
        _ => 11,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comparisons_larger_than_memory_are_refused_naming_the_size() {
        let big = Viewport::new(16384, 16384).unwrap();
        let e = check_memory(big, 11, Some(16 << 30))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--size") && e.contains("16384x16384") && e.contains("23 frames"),
            "{e}"
        );
        // One algorithm's frames fit where eleven do not.
        assert!(check_memory(big, 1, Some(16 << 30)).is_ok());
        assert!(check_memory(Viewport::new(480, 270).unwrap(), 11, Some(1 << 30)).is_ok());
        assert!(check_memory(big, 11, None).is_ok());
    }
}
