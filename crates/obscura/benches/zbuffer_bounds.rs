//! How far the z-buffer's time on a scene is from what its visible work costs.
//!
//! ```text
//! cargo bench -p obscura --bench zbuffer_bounds [-- SCENE [RUNS]]
//! ```
//!
//! SCENE defaults to `../shared/data/sponza.obj` seen from the atrium camera of that
//! folder's README (`--eye 0,-10,2 --target 0,10,4 --up 0,0,1 --fov 60`, 1920x1080);
//! any other scene is seen from its default camera. Everything runs on one thread and
//! each figure is the minimum of RUNS runs (default 20). It prints:
//!
//! 1. `prepare` and the z-buffer (`render_with(.., 1)`) with the z-buffer's phases: every
//!    polygon set up and the small ones (at most 64 pixels on a side) drawn at once, the
//!    big ones binned, the tiles drawn and the frame resolved;
//! 2. how many faces the finished frame shows;
//! 3. the small triangles drawn alone with the z-buffer's block rasterizer (set up
//!    beforehand, so the time is the drawing only), into a cleared frame;
//! 4. the same for only the small triangles that an *oracle* occlusion culler would
//!    keep: those not hidden, by their nearest key, in every 8x4 block of the finished
//!    frame they overlap (the frame's keys taken a millionth nearer, so the oracle
//!    culls at least what an exact one would). No real culler knows the finished frame
//!    while drawing, and none culls for free, so this time bounds from below what the
//!    small triangles cost with any occlusion culling;
//! 5. a lower bound of the frame time: (4) plus the tiles phase (the big polygons, which
//!    culling the small ones cannot make cheaper, and the resolve of the frame), leaving
//!    out `prepare`, the setup of every polygon and the binning.
//!
//! This is the measurement behind the speed figures of `docs/performance.md`
//! ("Where the z-buffer's time goes", "Coverage") and the closing notes of the
//! z-buffer's issue.

use std::time::Instant;

mod common;

use obscura::bench_support::SmallTriangles;
use obscura::surface::RenderOptions;
use obscura::surface::zbuffer::{Kernel, render_with};
use obscura::{PrepareOptions, prepare};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let common::Measured {
        path,
        scene,
        camera,
        viewport,
        runs,
    } = common::from_args(20)?;
    let options = RenderOptions::default();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    Ok(pool.install(|| -> Result<(), obscura::Error> {
        // 1. The z-buffer as it is.
        let (mut prepare_ms, mut render_ms) = (f64::INFINITY, f64::INFINITY);
        let mut phases = [f64::INFINITY; 3];
        for _ in 0..runs {
            let t0 = Instant::now();
            let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
            let t1 = Instant::now();
            let (_, stats) = render_with(&view, &options, Kernel::detect(), 1)?;
            prepare_ms = prepare_ms.min((t1 - t0).as_secs_f64() * 1e3);
            render_ms = render_ms.min(t1.elapsed().as_secs_f64() * 1e3);
            let measured = stats.fast.map_or([f64::NAN; 3], |f| {
                [f.setup_and_small_ms, f.binning_ms, f.tiles_ms]
            });
            for (p, ms) in phases.iter_mut().zip(measured) {
                *p = p.min(ms);
            }
        }
        println!("scene {path}, 1920x1080, one thread, minimum of {runs} runs");
        println!("prepare                                  {prepare_ms:8.2} ms");
        println!("z-buffer                                 {render_ms:8.2} ms");
        println!(
            "  setup of every polygon, small drawn    {:8.2} ms",
            phases[0]
        );
        println!(
            "  big polygons binned                    {:8.2} ms",
            phases[1]
        );
        println!(
            "  tiles (big polygons, resolve)          {:8.2} ms",
            phases[2]
        );

        // 2. What the finished frame shows.
        let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
        let (frame, _) = render_with(&view, &options, Kernel::detect(), 1)?;
        let mut shown: Vec<u32> = frame.ids.clone();
        shown.sort_unstable();
        shown.dedup();
        shown.retain(|&id| id != obscura::BACKGROUND);

        // 3. and 4. The small triangles drawn alone, all of them and the oracle's.
        let small = SmallTriangles::of(&view);
        let kept = small.oracle_kept(&view, &frame);
        let all_ms = small.draw_ms(runs);
        let kept_ms = kept.draw_ms(runs);
        println!(
            "faces drawn {}, shown in the frame {}",
            view.polygon_count(),
            shown.len()
        );
        println!(
            "small triangles drawn alone             {all_ms:8.2} ms  ({} triangles)",
            small.len()
        );
        println!(
            "  only those an oracle culler keeps     {kept_ms:8.2} ms  ({} triangles)",
            kept.len()
        );
        println!(
            "lower bound: oracle's small + tiles     {:8.2} ms",
            kept_ms + phases[2]
        );
        Ok(())
    })?)
}
