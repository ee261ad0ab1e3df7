//! `obscura bench`: each algorithm over a sweep of face counts, with the fitted growth
//! exponent, to check the seeds' complexity table (seed 000, "Περίληψη").

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use obscura::bench_support::scaled_triangles;
use obscura::scene::{MeshBuilder, ObjectDesc};
use obscura::surface::Algorithm;
use obscura::{Renderer, Result, Scene, SceneIndex};
use serde_json::json;

use crate::common::{AlgoArgs, CullArgs, ViewArgs};
use crate::out::{errln, out, outln};
use crate::outputs::{OutputArgs, Outputs};

pub const EXAMPLES: &str = "\
Examples:
  obscura bench                                    # generated triangles, 100 to 1,000,000 faces
  obscura bench --algos zbuffer,raycast-bvh,bsp --budget 20
  obscura bench ../shared/data/sponza.obj --eye 0,-10,2 --target 0,10,4 --up 0,0,1 --fov 60 --threads 1

Without SCENE the sweep uses generated scenes whose triangles tile a fixed screen area
four layers deep (each triangle shrinks as their number grows). With SCENE it renders
evenly spread subsets of the scene's faces.";

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Comma-separated algorithms (default: all).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = crate::common::parse_algo)]
    pub algos: Option<Vec<Algorithm>>,
    /// The largest face count of the sweep, 1 to 10,000,000.
    #[arg(long, default_value_t = 1_000_000, value_parser = parse_max_faces, allow_hyphen_values = true)]
    pub max_faces: usize,
    /// Seconds an algorithm may take for one size (a positive number); sizes predicted to
    /// take longer are skipped.
    #[arg(long, default_value_t = 60.0, value_parser = parse_budget, allow_hyphen_values = true)]
    pub budget: f64,
    #[command(flatten)]
    pub tuning: AlgoArgs,
    #[command(flatten)]
    pub culling: CullArgs,
    /// Also write the results as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub naming: OutputArgs,
}

/// The largest `--max-faces`: ten times the default sweep. A generated scene, its
/// prepared view and the z-buffer take about 300 bytes a face (3 GB at this maximum),
/// and several algorithms need many times that, so beyond it a sweep would run out of
/// memory (a billion faces asked for 72 GB before any check) or time.
pub const MAX_FACES: usize = 10_000_000;

fn parse_max_faces(s: &str) -> std::result::Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a whole number of faces"))?;
    if !(1..=MAX_FACES).contains(&n) {
        return Err(format!("{n} faces: give 1 to {MAX_FACES}"));
    }
    Ok(n)
}

fn parse_budget(s: &str) -> std::result::Result<f64, String> {
    let t: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a number of seconds"))?;
    if !(t.is_finite() && t > 0.0) {
        return Err(format!(
            "{s} s: the budget must be a positive number of seconds"
        ));
    }
    Ok(t)
}

/// Whether an algorithm with these measured `(faces, ms)` points is still run at `n`
/// faces: not after an error, nor when the time predicted from the last two points (or
/// quadratic growth from one) exceeds the budget.
fn worth_running(points: &[(usize, f64)], n: usize, budget_s: f64) -> bool {
    let predicted = match points {
        [.., (n0, t0), (n1, t1)] if *t0 > 0.0 && *t1 > 0.0 => {
            let e = ((t1 / t0).ln() / (*n1 as f64 / *n0 as f64).ln()).clamp(0.0, 3.0);
            t1 * (n as f64 / *n1 as f64).powf(e)
        }
        [.., (n1, t1)] => t1 * (n as f64 / *n1 as f64).powi(2),
        [] => 0.0,
    };
    predicted <= budget_s * 1e3 && !points.last().is_some_and(|p| p.1.is_nan())
}

/// What the seeds' table predicts for the exponent in P (faces) at a fixed image size.
fn expected(a: Algorithm) -> &'static str {
    match a {
        Algorithm::ZBuffer => "O(Ps) ~ O(p): ~0..1",
        Algorithm::Scanline => "~0..1",
        Algorithm::DepthSort | Algorithm::DepthSortMatrix => "O(P log P) .. O(P^2)",
        Algorithm::Bsp => "build O(P^2) worst",
        Algorithm::Warnock => "~0..1",
        Algorithm::Raycast => "O(pP): 1",
        Algorithm::RaycastBounds => "O(pP)/objects: 1",
        Algorithm::RaycastBvh => "O(p log P): ~0",
        Algorithm::RaycastGrid => "~0",
        Algorithm::Octree => "~0..1",
        // `Algorithm` is non-exhaustive: an algorithm added later has no prediction
        // until one is written here.
        _ => "?",
    }
}

/// Faces `0, k, 2k, ...` of the scene so that about `n` remain, keeping each object's
/// transform and flags (the subset is no longer closed).
fn subset(scene: &Scene, n: usize) -> Scene {
    let total = scene.polygon_count();
    let mut out = Scene::new();
    let mut g = 0usize;
    let mut taken = 0usize;
    for o in scene.objects() {
        let mut b = MeshBuilder::new();
        for &p in o.mesh.positions() {
            b.push_position(p);
        }
        for p in 0..o.mesh.polygon_count() {
            // take polygon g when floor(g * n / total) steps
            if (g + 1) * n / total > g * n / total && taken < n {
                b.push_face(o.mesh.polygon(p), None)
                    .expect("indices of a valid mesh");
                taken += 1;
            }
            g += 1;
        }
        if b.face_count() > 0 {
            let desc = ObjectDesc::new(o.name.clone(), b.finish().0)
                .with_transform(o.transform)
                .with_color(o.color)
                .with_closed(false)
                .with_convex(false);
            out.add(desc).expect("subset of a valid object");
        }
    }
    out.set_camera(scene.camera().copied());
    out
}

/// Least-squares slope of log(time) against log(n), over points above 1 ms.
fn growth_exponent(points: &[(usize, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.1 >= 1.0)
        .map(|&(n, t)| ((n as f64).ln(), t.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let m = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / m, sy / m);
    let (num, den) = pts.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx) * (p.0 - mx))
    });
    (den > 0.0).then(|| num / den)
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let mut outputs = Outputs::stage(
        args.view.scene.as_deref(),
        &[("--json", args.json.as_deref())],
        args.naming,
    )?;
    let base = match &args.view.scene {
        Some(_) => Some(args.view.load()?),
        None => None,
    };
    if let Some(l) = &base {
        outputs.check_inputs(l.scene.source_files())?;
    }
    let max = match &base {
        Some(l) => args.max_faces.min(l.scene.polygon_count()),
        None => args.max_faces,
    };
    let mut sizes: Vec<usize> = [
        100, 300, 1_000, 3_000, 10_000, 30_000, 100_000, 300_000, 1_000_000,
    ]
    .into_iter()
    .filter(|&n| n < max)
    .collect();
    sizes.push(max);
    let mut algos = args
        .algos
        .clone()
        .unwrap_or_else(|| Algorithm::ALL.to_vec());
    let mut seen = Vec::new();
    algos.retain(|a| {
        let first = !seen.contains(a);
        seen.push(*a);
        first
    });
    let scene_for = |n: usize| -> Scene {
        match &base {
            Some(l) if n >= l.scene.polygon_count() => l.scene.clone(),
            Some(l) => subset(&l.scene, n),
            None => scaled_triangles(n, 1),
        }
    };
    outln!(
        "sweep over {} ({} threads); times in ms of cull ({}) + prepare + render (each scene structure built once per size, by its first user); sizes predicted to exceed {} s are skipped",
        base.as_ref()
            .map_or("generated scaled triangles", |l| l.spec.as_str()),
        args.view
            .threads
            .map_or_else(|| "all".to_string(), |t| t.to_string()),
        args.culling.cull.name(),
        crate::common::readable(args.budget)
    );
    let mut results: Vec<(Algorithm, Vec<(usize, f64)>)> =
        algos.iter().map(|&a| (a, Vec::new())).collect();
    for w in args.tuning.unused_warnings(&algos) {
        errln!("warning: {w}");
    }
    // A bench runs for minutes by design: `--time-limit` bounds each render here, and
    // so does the bench's own budget.
    let per_render =
        std::time::Duration::try_from_secs_f64(args.budget).unwrap_or(std::time::Duration::MAX);
    let options = args
        .tuning
        .options_with_budget(args.view.memory_limit)
        .with_time_limit(Some(
            args.view
                .time_limit
                .0
                .map_or(per_render, |l| l.min(per_render)),
        ));
    // Per algorithm, the sizes skipped for the memory or time budget, with the reason.
    let mut skipped: Vec<(Algorithm, usize, String)> = Vec::new();
    for &n in &sizes {
        // No scene is built for a size that every algorithm skips.
        if !results
            .iter()
            .any(|(_, points)| worth_running(points, n, args.budget))
        {
            continue;
        }
        let scene = scene_for(n);
        let viewport = args.view.viewport_or(&scene, (640, 360))?;
        let camera = args.view.camera(&scene, viewport)?;
        let prep = args.view.prepare_options();
        let cull = args.culling.options();
        // One index per scene, shared by every algorithm and repetition: each structure
        // (triangles, BVH, grid, BSP tree, octree) is built by the first run that needs
        // it (a run under 200 ms is repeated and its best kept: the traversal's time).
        let index = SceneIndex::new(&scene);
        // One renderer for the repetitions, as a viewer keeps its frame: the z-buffer
        // draws into the kept frame (the first run pays for its memory, the best of the
        // repetitions does not); the other algorithms make a frame per run as before.
        let mut renderer = Renderer::new();
        for (algorithm, points) in &mut results {
            if !worth_running(points, n, args.budget) {
                continue;
            }
            let mut measure = || {
                args.view.with_threads(|| {
                    let start = Instant::now();
                    let view = index
                        .view_culled(&camera, viewport, &prep, &cull)?
                        .into_prepared();
                    index.render_into(&mut renderer, &view, *algorithm, &options)?;
                    Ok::<f64, obscura::Error>(start.elapsed().as_secs_f64() * 1e3)
                })?
            };
            let mut best = match measure() {
                Ok(t) => t,
                Err(e) if crate::common::is_over_budget(&e) => {
                    let reason = crate::common::cli_error(e).to_string();
                    errln!("{algorithm} at {n} faces: skipped: {reason}");
                    points.push((n, f64::NAN));
                    skipped.push((*algorithm, n, reason));
                    continue;
                }
                Err(e) => {
                    let e = crate::common::cli_error(e);
                    errln!("{algorithm} at {n} faces: {e}");
                    points.push((n, f64::NAN));
                    continue;
                }
            };
            // Small runs are noisy: keep the best of a few.
            let mut repeats = 0;
            while best < 200.0 && repeats < 4 {
                match measure() {
                    Ok(t) => best = best.min(t),
                    Err(_) => break,
                }
                repeats += 1;
            }
            points.push((n, best));
            errln!("  {:<18} {n:>9} faces {best:>10.2} ms", algorithm.name());
        }
    }
    // The table is printed once the JSON is in place: a closed pipe may cut it short.
    let mut table = format!("\n{:<18}", "algorithm");
    for n in &sizes {
        table += &format!(" {n:>9}");
    }
    table += &format!(" {:>8}  seed 000 expects\n", "exponent");
    let mut doc = Vec::new();
    for (algorithm, points) in &results {
        table += &format!("{:<18}", algorithm.name());
        for n in &sizes {
            table += &match points.iter().find(|p| p.0 == *n) {
                Some((_, t)) if t.is_finite() => format!(" {t:>9.1}"),
                Some(_) if skipped.iter().any(|s| s.0 == *algorithm && s.1 == *n) => {
                    format!(" {:>9}", "skipped")
                }
                Some(_) => format!(" {:>9}", "error"),
                None => format!(" {:>9}", "-"),
            };
        }
        let valid: Vec<(usize, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
        let e = growth_exponent(&valid);
        table += &format!(
            " {:>8}  {}\n",
            e.map_or("-".to_string(), |e| format!("{e:.2}")),
            expected(*algorithm)
        );
        doc.push(json!({
            "algorithm": algorithm.name(),
            "points": valid.iter().map(|(n, t)| json!({"faces": n, "ms": t})).collect::<Vec<_>>(),
            "exponent": e,
            "skipped": skipped
                .iter()
                .filter(|s| s.0 == *algorithm)
                .map(|s| json!({"faces": s.1, "reason": s.2}))
                .collect::<Vec<_>>(),
        }));
    }
    if args.json.is_some() {
        let text = serde_json::to_string_pretty(&json!({ "sizes": sizes, "algorithms": doc }))
            .expect("plain JSON");
        outputs.write("--json", |p| {
            std::fs::write(p, text + "\n").map_err(|e| obscura::Error::io(p, e))
        })?;
    }
    outputs.commit()?;
    for (algorithm, n, reason) in &skipped {
        table += &format!("skipped: {algorithm} at {n} faces: {reason}\n");
    }
    out!("{table}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_of_power_laws() {
        let lin: Vec<(usize, f64)> = [100, 1000, 10000]
            .iter()
            .map(|&n| (n, n as f64 * 0.5))
            .collect();
        assert!((growth_exponent(&lin).unwrap() - 1.0).abs() < 1e-9);
        let quad: Vec<(usize, f64)> = [100, 1000, 10000]
            .iter()
            .map(|&n| (n, (n * n) as f64 * 1e-3))
            .collect();
        assert!((growth_exponent(&quad).unwrap() - 2.0).abs() < 1e-9);
        // points under 1 ms are noise and ignored
        assert!(growth_exponent(&[(10, 0.1), (100, 5.0)]).is_none());
    }

    #[test]
    fn subsets_spread_over_the_scene() {
        let s = obscura::scene::demo::default_scene();
        let total = s.polygon_count();
        for n in [1, 10, 100, total / 2, total] {
            assert_eq!(subset(&s, n).polygon_count(), n, "n = {n}");
        }
    }
}
