//! Roberts' algorithm (`lines::roberts`) on 100 boxes at 1920x1080: the city demo's
//! 10 x 10 buildings without the ground (boxes side by side, many hiding each other)
//! and 100 boxes at random places and angles, many piercing each other (intersection
//! lines). The view is prepared once; the drawing is what is measured. The algorithm
//! runs on one thread.
//!
//! `cargo bench -p obscura --bench roberts` (the brief: at most 20 ms).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DMat4, DQuat, DVec3};
use obscura::bench_support::SplitMix64;
use obscura::lines::roberts::{RobertsOptions, draw};
use obscura::scene::{Camera, ObjectDesc, Scene, Viewport, demo};
use obscura::view::{PrepareOptions, View};

/// The city demo's buildings (every object but the ground).
fn city() -> (Scene, Camera) {
    let city = demo::city(10, 10, 7);
    let mut s = Scene::new();
    for o in city.objects().iter().filter(|o| o.name != "ground") {
        s.add(ObjectDesc {
            name: o.name.clone(),
            mesh: o.mesh.clone(),
            transform: o.transform,
            color: o.color,
            closed: Some(o.closed),
            convex: Some(o.convex),
        })
        .unwrap();
    }
    let camera = *city.camera().unwrap();
    (s, camera)
}

/// 100 boxes at random places and angles in a cube of side 20.
fn scattered() -> (Scene, Camera) {
    let mut rng = SplitMix64(100);
    let mut s = Scene::new();
    for i in 0..100 {
        let half = DVec3::new(
            rng.range(0.4, 2.0),
            rng.range(0.4, 2.0),
            rng.range(0.4, 2.0),
        );
        let rotation = DQuat::from_euler(
            glam::EulerRot::XYZ,
            rng.range(0.0, 6.3),
            rng.range(0.0, 6.3),
            rng.range(0.0, 6.3),
        );
        let centre = DVec3::new(
            rng.range(-10.0, 10.0),
            rng.range(-10.0, 10.0),
            rng.range(-10.0, 10.0),
        );
        s.add(
            ObjectDesc::new(format!("box {i}"), demo::box_mesh(-half, half))
                .with_transform(DMat4::from_rotation_translation(rotation, centre)),
        )
        .unwrap();
    }
    let camera = Camera::perspective(
        DVec3::new(30.0, 20.0, 40.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        1.0,
        200.0,
    );
    (s, camera)
}

fn roberts(c: &mut Criterion) {
    let vp = Viewport::new(1920, 1080).unwrap();
    let mut g = c.benchmark_group("roberts/100 boxes 1920x1080");
    g.sample_size(20);
    g.measurement_time(Duration::from_secs(4));
    for (name, (scene, camera)) in [("city", city()), ("scattered", scattered())] {
        let view = View::new(&scene, &camera, vp, &PrepareOptions::default()).unwrap();
        let (d, stats) = draw(&view, &RobertsOptions::default()).unwrap();
        eprintln!(
            "{name}: {} edges, {} pieces ({} visible), {} intersection lines, {} edge-body tests",
            d.edges.len(),
            d.pieces.len(),
            stats.visible_pieces,
            stats.intersection_lines,
            stats.edge_body_tests
        );
        g.bench_function(name, |b| {
            b.iter(|| draw(black_box(&view), &RobertsOptions::default()).unwrap())
        });
        let mut counting = RobertsOptions::default();
        counting.quantitative = true;
        g.bench_function(format!("{name}, quantitative"), |b| {
            b.iter(|| draw(black_box(&view), &counting).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, roberts);
criterion_main!(benches);
