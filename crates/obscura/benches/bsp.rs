//! BSP benchmarks: building the tree of 10,000 random triangles (the split count is
//! printed once), and rendering a view from a built tree with both traversals.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use obscura::accel::bsp::{BspOptions, BspTraversal, BspTree};
use obscura::bench_support::SplitMix64;
use obscura::scene::demo;
use obscura::scene::{MeshBuilder, ObjectDesc, Scene};
use obscura::surface::{RenderOptions, bsp};
use obscura::{PrepareOptions, Viewport, prepare};

/// `n` random triangles of edge about 2 in a cube of side 40, as one open object.
fn random_triangles(n: usize) -> Scene {
    let mut rng = SplitMix64(2024);
    let mut b = MeshBuilder::new();
    for _ in 0..n {
        let c = DVec3::new(
            rng.range(-20., 20.),
            rng.range(-20., 20.),
            rng.range(-20., 20.),
        );
        let base = b.vertex_count() as u32;
        for _ in 0..3 {
            b.push_position(
                c + DVec3::new(rng.range(-1., 1.), rng.range(-1., 1.), rng.range(-1., 1.)),
            );
        }
        let _ = b.push_face(&[base, base + 1, base + 2], None);
    }
    let mut s = Scene::new();
    s.add(ObjectDesc::new("triangles", b.finish().0).with_closed(false))
        .expect("valid");
    s
}

fn bench(c: &mut Criterion) {
    let scene = random_triangles(10_000);
    let options = BspOptions::default();
    let tree = BspTree::build(&scene, &options).expect("valid options");
    let s = tree.stats();
    eprintln!(
        "bsp build, 10k random triangles: {} splits, {} fragments, {} nodes, depth {}, {:.1} ms",
        s.splits, s.fragments, s.nodes, s.depth, s.build_ms
    );
    let mut g = c.benchmark_group("bsp");
    g.sample_size(10);
    g.bench_function("build 10k random triangles", |b| {
        b.iter(|| BspTree::build(&scene, &options).expect("valid options"))
    });
    let demo = demo::default_scene();
    let tree = BspTree::build(&demo, &options).expect("valid options");
    let vp = Viewport::new(640, 480).expect("valid size");
    let cam = demo.default_camera(vp.aspect());
    let view = prepare(&demo, &cam, vp, &PrepareOptions::default()).expect("valid view");
    for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
        let ro = RenderOptions::default().with_bsp(options.with_traversal(t));
        g.bench_function(format!("render demo:default 640x480 {}", t.name()), |b| {
            b.iter(|| bsp::render_with_tree(&tree, &view, &ro).expect("renders"))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
