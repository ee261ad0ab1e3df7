//! How far the scanline's time on a scene is from the bare bones of its per-row work.
//!
//! ```text
//! cargo bench -p obscura --bench scanline_bounds [-- SCENE [RUNS]]
//! ```
//!
//! SCENE defaults to `../shared/data/sponza.obj` seen from the atrium camera of that
//! folder's README, 1920x1080 (any other scene: its default camera). One thread,
//! minimum of RUNS runs (default 10). It prints:
//!
//! 1. the scanline's time and its stages (`table_ms`, `enter_ms`, `sweep_ms`,
//!    `sort_ms`, `walk_ms`), and the z-buffer's time on the same view;
//! 2. the face-rows (a face's span on a row) of the view;
//! 3. the skeleton of the per-row work: every face-row's span given beforehand (exact,
//!    from the shared coverage rule), each row's crossings emitted, sorted by the same
//!    counting sort and walked with the same in/out bookkeeping (a set of faces with
//!    a position per face), but no edge stepping, no setup of faces and no depth
//!    decision. Every scanline does at least this much per row; the rest of its time
//!    is the setup of faces, the crossings found from the edges, and the spans'
//!    depth decisions.

use std::time::Instant;

mod common;
mod lean_scanline;

use obscura::raster::FillRule;
use obscura::surface::{Algorithm, RenderOptions, render};
use obscura::{PrepareOptions, prepare};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let common::Measured {
        path,
        scene,
        camera,
        viewport,
        runs,
    } = common::from_args(10)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    Ok(pool.install(|| -> Result<(), obscura::Error> {
        let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
        let options = RenderOptions::default();
        // 1. The scanline and the z-buffer as they are.
        let stages = ["table_ms", "enter_ms", "sweep_ms", "sort_ms", "walk_ms"];
        let mut best = [f64::INFINITY; 5];
        let (mut scanline_ms, mut zbuffer_ms) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..runs {
            let t = Instant::now();
            let (_, stats) = render(Algorithm::Scanline, &view, &options)?;
            scanline_ms = scanline_ms.min(t.elapsed().as_secs_f64() * 1e3);
            let s = stats.scanline().expect("the scanline's stats");
            let measured = [s.table_ms, s.enter_ms, s.sweep_ms, s.sort_ms, s.walk_ms];
            for (b, ms) in best.iter_mut().zip(measured) {
                *b = b.min(ms);
            }
            let t = Instant::now();
            render(Algorithm::ZBuffer, &view, &options)?;
            zbuffer_ms = zbuffer_ms.min(t.elapsed().as_secs_f64() * 1e3);
        }
        println!("scene {path}, 1920x1080, one thread, minimum of {runs} runs (after prepare)");
        println!(
            "scanline {scanline_ms:8.2} ms ({:.2}x the z-buffer's {zbuffer_ms:.2} ms)",
            scanline_ms / zbuffer_ms
        );
        for (name, b) in stages.iter().zip(best) {
            println!("  {name:10} {b:8.2}");
        }

        // 2. The face-rows: per row, the span `x0..x1` of every polygon, exact.
        let height = viewport.height as usize;
        let mut rows: Vec<Vec<(u32, u32, u32)>> = vec![Vec::new(); height];
        let mut face_rows = 0usize;
        for (p, poly) in view.polygons().enumerate() {
            let Some(c) = poly.coverage(FillRule::TopLeft, viewport.width, viewport.height) else {
                continue;
            };
            for (y, x0, x1) in c.spans() {
                rows[y as usize].push((x0, x1, p as u32));
                face_rows += 1;
            }
        }
        println!("face-rows with a span {face_rows}");

        // 3. The skeleton of the per-row work.
        let (ms, spans) = skeleton(&rows, view.polygon_count(), viewport.width, runs);
        println!(
            "skeleton: crossings emitted, sorted, walked {ms:8.2} ms ({spans} spans with faces)"
        );

        // 4. The same structure, lean and not exact.
        let (zframe, _) = render(Algorithm::ZBuffer, &view, &options)?;
        let n = zframe.ids.len();
        let (mut ids, mut keys) = (vec![0u32; n], vec![0f32; n]);
        let mut lean = lean_scanline::Lean::default();
        let mut lean_ms = f64::INFINITY;
        let mut lean_spans = 0;
        for _ in 0..runs {
            let t = Instant::now();
            lean_spans = lean_scanline::render(&mut lean, &view, &mut ids, &mut keys);
            lean_ms = lean_ms.min(t.elapsed().as_secs_f64() * 1e3);
        }
        let differ = ids.iter().zip(&zframe.ids).filter(|(a, b)| a != b).count();
        println!(
            "lean scanline (not exact) {lean_ms:8.2} ms ({:.2}x the z-buffer's {zbuffer_ms:.2} ms; {lean_spans} spans with faces; {differ} pixels differ from the z-buffer)",
            lean_ms / zbuffer_ms
        );
        let [setup, sweep, sort, walk] = lean.seconds.map(|s| s * 1e3 / runs as f64);
        println!(
            "  mean per run: setup {setup:.2}, sweep {sweep:.2}, sort {sort:.2}, walk {walk:.2} ms"
        );
        Ok(())
    })?)
}

/// Per row, the crossings of the given spans emitted (entering at `x0`, leaving at
/// `x1`), sorted by a counting sort over the columns (leaving before entering at a
/// pixel), and walked, each flipping its face in or out of a set; returns the minimum
/// milliseconds over `runs` and the spans with faces in.
fn skeleton(rows: &[Vec<(u32, u32, u32)>], faces: usize, width: u32, runs: usize) -> (f64, u64) {
    let mut best = f64::INFINITY;
    let mut spans = 0;
    for _ in 0..runs {
        let t = Instant::now();
        let mut position = vec![u32::MAX; faces];
        let mut set: Vec<u32> = Vec::new();
        let (mut unsorted, mut sorted) = (Vec::new(), Vec::new());
        let mut starts = vec![0u32; width as usize + 2];
        spans = 0u64;
        for row in rows {
            unsorted.clear();
            for &(x0, x1, f) in row {
                unsorted.push((x0, f << 1 | 1));
                unsorted.push((x1, f << 1));
            }
            starts.fill(0);
            for c in &unsorted {
                starts[c.0 as usize + 1] += 1;
            }
            let mut before = 0;
            for s in starts.iter_mut() {
                before += *s;
                *s = before;
            }
            sorted.resize(unsorted.len(), (0, 0));
            for side in [1, 0] {
                for pair in unsorted.chunks_exact(2) {
                    let c: (u32, u32) = pair[side];
                    let at = &mut starts[c.0 as usize];
                    sorted[*at as usize] = c;
                    *at += 1;
                }
            }
            let mut x = 0;
            for &(cx, data) in &sorted {
                if cx > x {
                    spans += u64::from(!set.is_empty());
                    x = cx;
                }
                let f = (data >> 1) as usize;
                if data & 1 != 0 {
                    position[f] = set.len() as u32;
                    set.push(f as u32);
                } else {
                    let i = position[f] as usize;
                    position[f] = u32::MAX;
                    set.swap_remove(i);
                    if let Some(&moved) = set.get(i) {
                        position[moved as usize] = i as u32;
                    }
                }
            }
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    (best, spans)
}
