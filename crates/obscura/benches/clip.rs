//! Clipping benchmarks: every clipper of `obscura::clip` on batches of 1024 segments or
//! triangles, in three mixes: all inside, all crossing (one endpoint or vertex inside,
//! the rest anywhere), all outside (beyond one boundary of the square or cube:
//! trivially rejected by codes; for the hexagon window outside, but not always beyond
//! a single edge line).
//!
//! `cargo bench -p obscura --bench clip`; criterion reports the time per batch and the
//! throughput in elements per second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec2, DVec3, DVec4};
use obscura::bench_support::SplitMix64;
use obscura::clip::sutherland_hodgman as sh;
use obscura::clip::{ConvexWindow, Rect, cohen_sutherland as cs, liang_barsky as lb, region_codes};
use obscura::geom::Aabb;

const BATCH: usize = 1024;
const MIXES: [&str; 3] = ["inside", "crossing", "outside"];

/// A random point of the clipping region `[-1, 1]^d` in mix `mix` for vertex `k`:
/// inside; for crossing, vertex 0 inside and the others in `[-3, 3]^d`; for outside,
/// every vertex beyond the same random boundary.
fn coords<const D: usize>(rng: &mut SplitMix64, mix: usize, k: usize, side: usize) -> [f64; D] {
    let mut c = [0.0; D];
    for v in &mut c {
        *v = match (mix, k) {
            (0, _) | (1, 0) => rng.range(-0.95, 0.95),
            _ => rng.range(-3.0, 3.0),
        };
    }
    if mix == 2 {
        let axis = side % D;
        c[axis] = if side / D == 0 {
            rng.range(1.05, 3.0)
        } else {
            rng.range(-3.0, -1.05)
        };
    }
    c
}

fn batch<const D: usize, const N: usize>(mix: usize, seed: u64) -> Vec<[[f64; D]; N]> {
    let mut rng = SplitMix64(seed);
    (0..BATCH)
        .map(|_| {
            let side = (rng.next_u64() % (2 * D as u64)) as usize;
            std::array::from_fn(|k| coords::<D>(&mut rng, mix, k, side))
        })
        .collect()
}

fn to2(c: [f64; 2]) -> DVec2 {
    DVec2::from_array(c)
}

fn to3(c: [f64; 3]) -> DVec3 {
    DVec3::from_array(c)
}

/// Clip space: the region point scaled by a random `w` in `[0.5, 2]`, except that
/// crossing segments and triangles put their other vertices at any `w` in `[-2, 2]`
/// (behind the eye too).
fn to4(c: [f64; 3], w: f64) -> DVec4 {
    DVec3::from_array(c).extend(1.0) * w
}

fn homogeneous<const N: usize>(mix: usize, seed: u64) -> Vec<[DVec4; N]> {
    let mut rng = SplitMix64(seed ^ 0x5eed);
    batch::<3, N>(mix, seed)
        .into_iter()
        .map(|vs| {
            let mut k = 0;
            vs.map(|c| {
                let w = if mix == 1 && k > 0 {
                    rng.range(-2.0, 2.0)
                } else {
                    rng.range(0.5, 2.0)
                };
                k += 1;
                to4(c, w)
            })
        })
        .collect()
}

fn hexagon() -> ConvexWindow {
    let v: Vec<DVec2> = (0..6)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 6.0;
            DVec2::new(a.cos(), a.sin())
        })
        .collect();
    ConvexWindow::new(&v).expect("a regular hexagon is convex")
}

fn segments_2d(c: &mut Criterion) {
    let rect = Rect::NDC;
    let window = ConvexWindow::rectangle(&rect);
    let hex = hexagon();
    let mut g = c.benchmark_group("segment 2D");
    g.throughput(Throughput::Elements(BATCH as u64));
    for (mix, name) in MIXES.iter().enumerate() {
        let segs: Vec<(DVec2, DVec2)> = batch::<2, 2>(mix, 1 + mix as u64)
            .into_iter()
            .map(|[a, b]| (to2(a), to2(b)))
            .collect();
        let run = |f: &dyn Fn(DVec2, DVec2) -> Option<(DVec2, DVec2)>| {
            segs.iter()
                .filter_map(|&(a, b)| f(black_box(a), black_box(b)))
                .count()
        };
        g.bench_function(BenchmarkId::new("cohen-sutherland rect", name), |bn| {
            bn.iter(|| run(&|a, b| cs::clip_segment_2d(a, b, &rect)))
        });
        g.bench_function(BenchmarkId::new("liang-barsky rect", name), |bn| {
            bn.iter(|| run(&|a, b| lb::clip_segment_2d(a, b, &rect)))
        });
        g.bench_function(BenchmarkId::new("sutherland-hodgman rect", name), |bn| {
            bn.iter(|| run(&|a, b| sh::clip_segment_2d(a, b, &window)))
        });
        g.bench_function(BenchmarkId::new("region codes rect", name), |bn| {
            bn.iter(|| run(&|a, b| region_codes::clip_segment(&window, a, b)))
        });
        // The hexagon's inscribed circle has radius 0.87: shrink the inside mix to fit.
        let scale = if mix == 0 { 0.6 } else { 1.0 };
        let hex_segs: Vec<(DVec2, DVec2)> =
            segs.iter().map(|&(a, b)| (a * scale, b * scale)).collect();
        let run_hex = |f: &dyn Fn(DVec2, DVec2) -> Option<(DVec2, DVec2)>| {
            hex_segs
                .iter()
                .filter_map(|&(a, b)| f(black_box(a), black_box(b)))
                .count()
        };
        g.bench_function(BenchmarkId::new("region codes hexagon", name), |bn| {
            bn.iter(|| run_hex(&|a, b| region_codes::clip_segment(&hex, a, b)))
        });
        g.bench_function(BenchmarkId::new("sutherland-hodgman hexagon", name), |bn| {
            bn.iter(|| run_hex(&|a, b| sh::clip_segment_2d(a, b, &hex)))
        });
    }
    g.finish();
}

fn segments_3d(c: &mut Criterion) {
    let cube = Aabb {
        min: DVec3::splat(-1.0),
        max: DVec3::ONE,
    };
    let mut g = c.benchmark_group("segment 3D");
    g.throughput(Throughput::Elements(BATCH as u64));
    for (mix, name) in MIXES.iter().enumerate() {
        let segs: Vec<(DVec3, DVec3)> = batch::<3, 2>(mix, 10 + mix as u64)
            .into_iter()
            .map(|[a, b]| (to3(a), to3(b)))
            .collect();
        let run = |f: &dyn Fn(DVec3, DVec3) -> Option<(DVec3, DVec3)>| {
            segs.iter()
                .filter_map(|&(a, b)| f(black_box(a), black_box(b)))
                .count()
        };
        g.bench_function(BenchmarkId::new("cohen-sutherland box", name), |bn| {
            bn.iter(|| run(&|a, b| cs::clip_segment_box(a, b, &cube)))
        });
        g.bench_function(BenchmarkId::new("liang-barsky box", name), |bn| {
            bn.iter(|| run(&|a, b| lb::clip_segment_box(a, b, &cube)))
        });
        g.bench_function(BenchmarkId::new("sutherland-hodgman box", name), |bn| {
            bn.iter(|| run(&|a, b| sh::clip_segment_box(a, b, &cube)))
        });
        let hsegs: Vec<(DVec4, DVec4)> = homogeneous::<2>(mix, 20 + mix as u64)
            .into_iter()
            .map(|[a, b]| (a, b))
            .collect();
        let run_h = |f: &dyn Fn(DVec4, DVec4) -> Option<(DVec4, DVec4)>| {
            hsegs
                .iter()
                .filter_map(|&(a, b)| f(black_box(a), black_box(b)))
                .count()
        };
        g.bench_function(
            BenchmarkId::new("cohen-sutherland homogeneous", name),
            |bn| bn.iter(|| run_h(&cs::clip_segment_homogeneous)),
        );
        g.bench_function(BenchmarkId::new("liang-barsky homogeneous", name), |bn| {
            bn.iter(|| run_h(&lb::clip_segment_homogeneous))
        });
        g.bench_function(
            BenchmarkId::new("sutherland-hodgman homogeneous", name),
            |bn| bn.iter(|| run_h(&sh::clip_segment_homogeneous)),
        );
    }
    g.finish();
}

fn triangles(c: &mut Criterion) {
    let window = ConvexWindow::rectangle(&Rect::NDC);
    let hex = hexagon();
    let cube = Aabb {
        min: DVec3::splat(-1.0),
        max: DVec3::ONE,
    };
    let mut g = c.benchmark_group("triangle");
    g.throughput(Throughput::Elements(BATCH as u64));
    for (mix, name) in MIXES.iter().enumerate() {
        let tris2: Vec<[DVec2; 3]> = batch::<2, 3>(mix, 30 + mix as u64)
            .into_iter()
            .map(|t| t.map(to2))
            .collect();
        // Buffers reused between triangles, as a caller clipping many would.
        let (mut o2, mut s2) = (Vec::new(), Vec::new());
        let (mut o3, mut s3) = (Vec::new(), Vec::new());
        let (mut o4, mut s4) = (Vec::new(), Vec::new());
        g.bench_function(BenchmarkId::new("sutherland-hodgman 2D rect", name), |bn| {
            bn.iter(|| {
                let mut total = 0;
                for t in &tris2 {
                    sh::clip_polygon_2d_into(black_box(t), &window, &mut o2, &mut s2);
                    total += o2.len();
                }
                total
            })
        });
        let scale = if mix == 0 { 0.6 } else { 1.0 };
        let hex_tris: Vec<[DVec2; 3]> = tris2.iter().map(|t| t.map(|v| v * scale)).collect();
        g.bench_function(
            BenchmarkId::new("sutherland-hodgman 2D hexagon", name),
            |bn| {
                bn.iter(|| {
                    let mut total = 0;
                    for t in &hex_tris {
                        sh::clip_polygon_2d_into(black_box(t), &hex, &mut o2, &mut s2);
                        total += o2.len();
                    }
                    total
                })
            },
        );
        let tris3: Vec<[DVec3; 3]> = batch::<3, 3>(mix, 40 + mix as u64)
            .into_iter()
            .map(|t| t.map(to3))
            .collect();
        g.bench_function(BenchmarkId::new("sutherland-hodgman box", name), |bn| {
            bn.iter(|| {
                let mut total = 0;
                for t in &tris3 {
                    sh::clip_polygon_box_into(black_box(t), &cube, &mut o3, &mut s3);
                    total += o3.len();
                }
                total
            })
        });
        let tris4 = homogeneous::<3>(mix, 50 + mix as u64);
        g.bench_function(
            BenchmarkId::new("sutherland-hodgman homogeneous", name),
            |bn| {
                bn.iter(|| {
                    let mut total = 0;
                    for t in &tris4 {
                        sh::clip_polygon_homogeneous_masked(black_box(t), 0x3f, &mut o4, &mut s4);
                        total += o4.len();
                    }
                    total
                })
            },
        );
        // The convenience form, which allocates its result.
        g.bench_function(
            BenchmarkId::new("sutherland-hodgman homogeneous allocating", name),
            |bn| {
                bn.iter(|| {
                    tris4
                        .iter()
                        .map(|t| sh::clip_polygon_homogeneous(black_box(t)).len())
                        .sum::<usize>()
                })
            },
        );
        // The pipeline's form: outcodes first, then only the planes crossed, buffers
        // reused (what view::prepare does).
        g.bench_function(
            BenchmarkId::new("sutherland-hodgman homogeneous outcode-masked", name),
            |bn| {
                let (mut out, mut scratch) = (Vec::new(), Vec::new());
                bn.iter(|| {
                    let mut total = 0;
                    for t in &tris4 {
                        let codes = t.map(obscura::clip::outcode_homogeneous);
                        if codes[0] & codes[1] & codes[2] != 0 {
                            continue;
                        }
                        let mask = codes[0] | codes[1] | codes[2];
                        if mask == 0 {
                            total += 3;
                            continue;
                        }
                        sh::clip_polygon_homogeneous_masked(
                            black_box(t),
                            mask,
                            &mut out,
                            &mut scratch,
                        );
                        total += out.len();
                    }
                    total
                })
            },
        );
    }
    g.finish();
}

fn config() -> Criterion {
    // Many small benches on a shared machine: short but stable runs.
    Criterion::default()
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .sample_size(30)
}

criterion_group! {
    name = benches;
    config = config();
    targets = segments_2d, segments_3d, triangles
}
criterion_main!(benches);
