//! PVS precomputation (issue 24): the stab trees and the symmetric table of a 10 x 10
//! grid of rooms (100 cells, 180 doors at random places in the walls, 1 wide and 2.2
//! high in rooms 4 x 4 x 3), single thread and with the `parallel` feature's threads.
//! Target: at most 10 s. The table's size and the sequences tested are printed once.

use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use obscura::bench_support::SplitMix64;
use obscura::cull::portals::{Cell, CellGraph, Portal, PvsOptions, pvs};
use obscura::geom::Plane;

fn box_cell(name: String, min: DVec3, max: DVec3) -> Cell {
    let pl = |n: DVec3, p: DVec3| Plane::from_point_normal(p, n);
    Cell {
        name,
        planes: vec![
            pl(-DVec3::X, min),
            pl(DVec3::X, max),
            pl(-DVec3::Y, min),
            pl(DVec3::Y, max),
            pl(-DVec3::Z, min),
            pl(DVec3::Z, max),
        ],
        objects: Vec::new(),
    }
}

/// `n x n` rooms, each joined to its right and back neighbours by a door.
fn grid(n: usize, seed: u64) -> CellGraph {
    let mut rng = SplitMix64(seed);
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut g = CellGraph::default();
    for j in 0..n {
        for i in 0..n {
            let lo = DVec3::new(4.0 * i as f64, 0.0, 4.0 * j as f64);
            g.cells.push(box_cell(
                format!("{i},{j}"),
                lo,
                lo + DVec3::new(4.0, 3.0, 4.0),
            ));
        }
    }
    for j in 0..n {
        for i in 0..n {
            if i + 1 < n {
                let (x, z0) = (4.0 * (i + 1) as f64, 4.0 * j as f64 + rng.range(0.1, 2.9));
                g.portals.push(Portal {
                    cells: [id(i, j), id(i + 1, j)],
                    polygon: vec![
                        DVec3::new(x, 0.0, z0),
                        DVec3::new(x, 0.0, z0 + 1.0),
                        DVec3::new(x, 2.2, z0 + 1.0),
                        DVec3::new(x, 2.2, z0),
                    ],
                });
            }
            if j + 1 < n {
                let (z, x0) = (4.0 * (j + 1) as f64, 4.0 * i as f64 + rng.range(0.1, 2.9));
                g.portals.push(Portal {
                    cells: [id(i, j), id(i, j + 1)],
                    polygon: vec![
                        DVec3::new(x0, 0.0, z),
                        DVec3::new(x0 + 1.0, 0.0, z),
                        DVec3::new(x0 + 1.0, 2.2, z),
                        DVec3::new(x0, 2.2, z),
                    ],
                });
            }
        }
    }
    g
}

fn bench(c: &mut Criterion) {
    let g = grid(10, 2026);
    let options = PvsOptions::default();
    let start = Instant::now();
    let t = pvs::compute(&g, &options, &|_, _| {}).expect("no deadline");
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let visible: usize = (0..100).map(|a| t.count(a)).sum();
    eprintln!(
        "pvs 10x10 rooms: {ms:.0} ms, {} sequences, {:.1} cells visible per cell, {} rows over budget",
        t.sequences,
        visible as f64 / 100.0,
        t.incomplete.len()
    );
    let mut group = c.benchmark_group("pvs");
    group.sample_size(10);
    group.bench_function("100 rooms", |b| {
        b.iter(|| pvs::compute(&g, &options, &|_, _| {}).expect("no deadline"))
    });
    #[cfg(feature = "parallel")]
    {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        group.bench_function("100 rooms, one thread", |b| {
            b.iter(|| pool.install(|| pvs::compute(&g, &options, &|_, _| {}).expect("no deadline")))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
