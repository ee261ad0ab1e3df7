//! The occlusion buffer's speed (issue 24, item 4), single thread.
//!
//! ```text
//! SPONZA=/work/shared/data/sponza.obj RAYON_NUM_THREADS=1 \
//!     cargo bench -p obscura --features obj --bench occlusion [-- RUNS]
//! ```
//!
//! It prints, each figure the minimum (and the median) of RUNS runs (default 30):
//!
//! 1. fill rate: 100,000 random triangles of a 10 x 10 pixel bounding box (area 50)
//!    drawn into an empty 1920x1080 masked buffer, in million triangles per second,
//!    for the portable and the AVX2 build (MSOC's figure on this kind of machine: 25-27);
//! 2. Sponza (`SPONZA`, default `../shared/data/sponza.obj` beside the checkout) from the
//!    atrium camera of that folder's README at 1920x1080: first the ceiling (the
//!    clusters the frustum keeps of which the whole scene's z-buffer shows no face,
//!    and their triangles: the most any method can cull); with `CHOICES=LABEL` (a
//!    substring of the labels, empty for all) the occluder choices instead (order,
//!    smallest triangle, budget, resolution, queries: clusters and triangles culled,
//!    stages, and a check that no culled cluster is seen); else the buffer's whole frame,
//!    occluders selected, rasterized and every cluster's bounds tested (no frustum
//!    stage), with its stages, and how many clusters it culls; both kinds;
//! 3. whether culling pays: Sponza, and the city demo from street level, rendered by
//!    the z-buffer alone and by cull (frustum + buffer) then the z-buffer.

use std::time::Instant;

use glam::DVec3;
use obscura::cull::buffer::{BufferKind, OccluderOrder, OcclusionBuffer};
use obscura::cull::occlusion::{CullMethod, CullOptions, CullReason, Culling};
use obscura::surface::zbuffer::Kernel;
use obscura::surface::{Algorithm, RenderOptions};
use obscura::view::ViewTransform;
use obscura::{Camera, PrepareOptions, Scene, SceneIndex, View, Viewport};

#[path = "common/sponza.rs"]
mod sponza;

/// Min and median of `runs` runs of `f`, in milliseconds.
fn time(runs: usize, mut f: impl FnMut()) -> (f64, f64) {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    (t[0], t[t.len() / 2])
}

/// The generator of the benches (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn fill_rate(runs: usize) {
    let n = 100_000;
    let mut rng = Rng(1);
    let tris: Vec<[[f64; 3]; 3]> = (0..n)
        .map(|_| {
            let (x, y) = (rng.next() * 1910.0, rng.next() * 1070.0);
            let z = 0.01 + rng.next();
            // Two corners of the 10 x 10 box and a point on the opposite side.
            if rng.next() < 0.5 {
                [
                    [x, y, z],
                    [x + 10.0, y, z],
                    [x + rng.next() * 10.0, y + 10.0, z],
                ]
            } else {
                [
                    [x, y + 10.0, z],
                    [x + rng.next() * 10.0, y, z],
                    [x + 10.0, y + 10.0, z],
                ]
            }
        })
        .collect();
    let mut buf = OcclusionBuffer::new();
    for (name, kernel) in [
        ("portable", Kernel::Portable),
        ("avx2", Kernel::Avx2),
        ("avx512", Kernel::Avx512),
    ] {
        if std::env::var("FILL_KERNEL").is_ok_and(|k| k != name) {
            continue;
        }
        if !kernel.is_available() {
            println!("fill rate ({name}): not measured (this processor lacks it)");
            continue;
        }
        let (best, median) = time(runs, || {
            buf.reset(BufferKind::Masked, 1, 1920, 1080);
            buf.draw_screen_triangles(&tris, kernel);
        });
        println!(
            "fill rate ({name}): {n} 10x10 triangles in {best:.2} ms (median {median:.2}): \
             {:.1} M triangles/s",
            n as f64 / best / 1e3
        );
    }
}

fn buffer_frame(name: &str, scene: &Scene, camera: &Camera, runs: usize) {
    let vp = Viewport::new(1920, 1080).unwrap();
    let index = SceneIndex::new(scene);
    let t = ViewTransform::new(camera, vp);
    for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
        let mut o = CullOptions::with_method(CullMethod::Buffer);
        o.buffer.kind = kind;
        let mut buf = OcclusionBuffer::new();
        let mut last = None;
        let (best, median) = time(runs, || {
            let mut c = Culling::keep_all(&index, CullMethod::Buffer);
            buf.cull(&index, &t, &o, &mut c).unwrap();
            last = Some(c);
        });
        let mut c = last.unwrap();
        c.finish(&index);
        let stages: Vec<String> = c
            .stats
            .stages
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.2}"))
            .collect();
        println!(
            "{name} {kind:?}: occluders + raster + tests of {} clusters in {best:.2} ms (median \
             {median:.2}; last run: {}); culled {} clusters, {} of {} faces; {}",
            index.clusters().len(),
            stages.join(", "),
            c.stats.clusters_culled,
            c.stats.faces_culled,
            c.stats.faces_tested,
            c.notes.join("; ")
        );
    }
}

/// The exact answer from one camera: the clusters the frustum stage keeps that the
/// whole scene's z-buffer shows no face of (truly hidden), and their triangles: the
/// most any occlusion method can cull. Returns, per scene polygon, whether it is seen.
fn ceiling(name: &str, index: &SceneIndex<'_>, camera: &Camera, vp: Viewport) -> Vec<bool> {
    let scene = index.scene();
    let view = View::new(scene, camera, vp, &PrepareOptions::default()).unwrap();
    let (frame, _) = index
        .render_view(&view, Algorithm::ZBuffer, &RenderOptions::default())
        .unwrap();
    let faces = scene.face_count() as usize;
    let mut seen_face = vec![false; faces];
    for &id in &frame.ids {
        if id != obscura::BACKGROUND {
            seen_face[id as usize] = true;
        }
    }
    // Per scene polygon (scene order), whether its face is seen.
    let mut seen = Vec::new();
    for o in scene.objects() {
        for p in 0..o.mesh.polygon_count() {
            seen.push(seen_face[(o.first_face + o.mesh.polygon_face(p)) as usize]);
        }
    }
    let frustum = index
        .cull(camera, vp, &CullOptions::with_method(CullMethod::Frustum))
        .unwrap();
    let clusters = index.clusters();
    let mut base = Vec::new();
    let mut b = 0usize;
    for o in scene.objects() {
        base.push(b);
        b += o.mesh.polygon_count();
    }
    let (mut kept, mut kept_tris, mut hidden, mut hidden_tris) = (0, 0u64, 0, 0u64);
    let (mut tris_in, mut tris_seen) = (0u64, 0u64);
    for cl in 0..clusters.len() {
        if frustum.clusters[cl].is_some() {
            continue;
        }
        let k = clusters.object(cl) as usize;
        let o = &scene.objects()[k];
        let tris = u64::from(clusters.triangles(cl));
        kept += 1;
        kept_tris += tris;
        let mut any = false;
        for &p in clusters.polygons(cl) {
            let n = o.mesh.polygon(p as usize).len() as u64 - 2;
            tris_in += n;
            if seen[base[k] + p as usize] {
                any = true;
                tris_seen += n;
            }
        }
        if !any {
            hidden += 1;
            hidden_tris += tris;
        }
    }
    println!(
        "{name} ceiling: of {kept} clusters ({kept_tris} triangles) the frustum keeps, {hidden}          ({hidden_tris} triangles, {:.1}%) are truly hidden (no face in the whole z-buffer);          triangles: {tris_seen} of {tris_in} seen ({:.1}% hidden)",
        100.0 * hidden_tris as f64 / kept_tris.max(1) as f64,
        100.0 * (tris_in - tris_seen) as f64 / tris_in.max(1) as f64
    );
    seen
}

/// The occluder choices of the buffer on one view: culled clusters and triangles,
/// the culling time, and a check that nothing culled is seen.
fn occluder_choices(
    index: &SceneIndex<'_>,
    camera: &Camera,
    vp: Viewport,
    seen: &[bool],
    runs: usize,
) {
    let scene = index.scene();
    let clusters = index.clusters();
    let mut base = Vec::new();
    let mut b = 0usize;
    for o in scene.objects() {
        base.push(b);
        b += o.mesh.polygon_count();
    }
    let orders = [OccluderOrder::Largest, OccluderOrder::Nearest];
    let areas = [0u32, 8, 32, 128, 512];
    let budgets = [1u32 << 12, 1 << 14, 1 << 16];
    let only = std::env::var("CHOICES").ok();
    for order in orders {
        for &area in &areas {
            for &budget in &budgets {
                for (max_width, queries) in [(1024u32, false), (0, false), (1024, true), (0, true)]
                {
                    let label = format!(
                        "{order:?} area>={area} budget {budget} width<={max_width} queries {queries}"
                    );
                    if only.as_deref().is_some_and(|o| !label.contains(o)) {
                        continue;
                    }
                    let mut o = CullOptions::with_method(CullMethod::Buffer);
                    o.buffer.occluder_order = order;
                    o.buffer.occluder_min_area = area;
                    o.buffer.occluder_triangles = budget;
                    o.buffer.max_width = max_width;
                    o.buffer.occluder_queries = queries;
                    let mut last = None;
                    let (best, median) = time(runs, || {
                        last = Some(index.cull(camera, vp, &o).unwrap());
                    });
                    let c = last.unwrap();
                    let (mut n, mut tris, mut leaks) = (0, 0u64, 0);
                    for cl in 0..clusters.len() {
                        if c.clusters[cl] != Some(CullReason::Buffer) {
                            continue;
                        }
                        n += 1;
                        tris += u64::from(clusters.triangles(cl));
                        let k = clusters.object(cl) as usize;
                        if clusters
                            .polygons(cl)
                            .iter()
                            .any(|&p| seen[base[k] + p as usize])
                        {
                            leaks += 1;
                        }
                    }
                    let stages: Vec<String> = c
                        .stats
                        .stages
                        .iter()
                        .map(|(n, ms)| format!("{n} {ms:.2}"))
                        .collect();
                    let note = format!(
                        "{}; last run: {}",
                        c.notes.last().cloned().unwrap_or_default(),
                        stages.join(", ")
                    );
                    println!(
                        "  {label}: {n} clusters ({tris} triangles) culled in {best:.2} ms (median                          {median:.2}){}; {note}",
                        if leaks > 0 {
                            format!(" LEAK: {leaks} seen clusters culled")
                        } else {
                            String::new()
                        }
                    );
                }
            }
        }
    }
}

fn pays(name: &str, scene: &Scene, cameras: &[Camera], vp: Viewport, runs: usize) {
    let index = SceneIndex::new(scene);
    let po = PrepareOptions::default();
    let ro = RenderOptions::default();
    let (mut plain, mut culled) = (0.0, 0.0);
    for camera in cameras {
        plain += time(runs, || {
            let v = View::new(scene, camera, vp, &po).unwrap();
            index.render_view(&v, Algorithm::ZBuffer, &ro).unwrap();
        })
        .0;
        culled += time(runs, || {
            let c = index
                .cull(camera, vp, &CullOptions::with_method(CullMethod::Buffer))
                .unwrap();
            let v = View::new_culled(scene, camera, vp, &po, c).unwrap();
            index.render_view(&v, Algorithm::ZBuffer, &ro).unwrap();
        })
        .0;
    }
    let n = cameras.len() as f64;
    println!(
        "{name}: z-buffer alone {:.2} ms, buffer cull + z-buffer {:.2} ms per view ({:.2}x)",
        plain / n,
        culled / n,
        plain / culled
    );
}

fn main() {
    // `cargo bench` passes `--bench`.
    let runs: usize = std::env::args()
        .skip(1)
        .find(|a| a != "--bench")
        .and_then(|a| a.parse().ok())
        .unwrap_or(30);
    fill_rate(runs);
    if std::env::var("FILL_ONLY").is_ok_and(|v| v == "1") {
        return;
    }
    match sponza::atrium() {
        Ok((sponza, camera)) => {
            let vp = Viewport::new(1920, 1080).unwrap();
            let index = SceneIndex::new(&sponza);
            let seen = ceiling("sponza atrium", &index, &camera, vp);
            if std::env::var("CHOICES").is_ok() {
                occluder_choices(&index, &camera, vp, &seen, runs);
                return;
            }
            buffer_frame("sponza", &sponza, &camera, runs);
            pays(
                "sponza atrium",
                &sponza,
                &[camera],
                Viewport::new(1920, 1080).unwrap(),
                runs.min(10),
            );
        }
        Err(path) => println!("sponza: not measured (no scene at {path})"),
    }
    let city = obscura::scene::demo::city(10, 10, 3);
    let mut rng = Rng(5);
    let cameras: Vec<Camera> = (0..8)
        .map(|_| {
            let line = (rng.next() * 8.0 - 4.0).round();
            let along = rng.next() * 9.6 - 4.8;
            let eye = DVec3::new(line, 1.7, along);
            let a = rng.next() * std::f64::consts::TAU;
            Camera::perspective(
                eye,
                eye + DVec3::new(a.cos(), -0.05, a.sin()),
                DVec3::Y,
                60.0,
                0.05,
                60.0,
            )
        })
        .collect();
    pays(
        "city 10x10 street level",
        &city,
        &cameras,
        Viewport::new(1920, 1080).unwrap(),
        runs.min(10),
    );
}
