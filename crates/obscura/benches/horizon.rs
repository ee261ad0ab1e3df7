//! The floating horizon on a 1000 x 1000 grid at 1920 x 1080, single thread (the
//! algorithm has no parallel part): the `ripple` and `peaks` functions seen by the
//! field's default perspective camera, curves of constant z only and both families,
//! visible pieces only (as `obscura lines --algo horizon` draws by default).
//!
//! `cargo bench -p obscura --bench horizon`; issue 23 asks for at most 100 ms.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use obscura::Viewport;
use obscura::lines::horizon::{Curves, HeightField, HorizonOptions, draw};

fn horizon(c: &mut Criterion) {
    let vp = Viewport::new(1920, 1080).unwrap();
    let mut g = c.benchmark_group("horizon_1000x1000_1920x1080");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    for name in ["ripple", "peaks"] {
        let field = HeightField::function(name, 1000, 1000).unwrap();
        let camera = field.default_camera(vp.aspect());
        for (label, curves) in [("z", Curves::ConstantZ), ("both", Curves::Both)] {
            let options = HorizonOptions::default().with_curves(curves);
            let (d, s) = draw(&field, &camera, vp, &options).unwrap();
            // CPU time per draw, read from the kernel's accounting: wall-clock times of
            // a shared machine overstate it.
            let runs = 10;
            let before = cpu_seconds();
            for _ in 0..runs {
                black_box(draw(&field, &camera, vp, &options).unwrap());
            }
            let per_draw = (cpu_seconds() - before) / f64::from(runs);
            eprintln!(
                "{name}/{label}: {} edges, {} visible pieces, horizon up to {} spans; \
                 {:.0} ms of CPU time per draw",
                d.edges.len(),
                s.visible_pieces,
                s.horizon_spans,
                per_draw * 1e3
            );
            g.bench_function(format!("{name}/{label}"), |b| {
                b.iter(|| draw(black_box(&field), &camera, vp, &options).unwrap())
            });
        }
    }
    g.finish();
}

/// User plus system CPU time of this process so far, in seconds (Linux; 0 elsewhere),
/// at the kernel's clock-tick resolution (usually 10 ms).
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which ends with ')'): utime is the 12th, stime
    // the 13th.
    let rest = stat.rsplit_once(')').map_or("", |r| r.1);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    f.iter().sum::<f64>() / 100.0
}

criterion_group!(benches, horizon);
criterion_main!(benches);
