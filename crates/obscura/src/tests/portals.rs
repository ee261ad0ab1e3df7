//! Cells and portals (issue 24, items 1 and 2): the seed's PVS table and portal walk
//! (`ALGORITHMS.md`, worked example 4) on a five-room floor plan built here; the PVS
//! against sampled lines of sight; portal rendering and screen-space portals against
//! the full z-buffer (nothing visible culled, the same picture) from many viewpoints.

use std::sync::Arc;

use glam::DVec3;

use crate::bench_support::SplitMix64;
use crate::cull::occlusion::{CullMethod, CullOptions, CullReason, Culling};
use crate::cull::portals::render::view_frustum;
use crate::cull::portals::{Cell, CellGraph, Portal, PvsOptions, portal_walk, pvs};
use crate::geom::Plane;
use crate::scene::demo::box_mesh;
use crate::scene::{Camera, ObjectDesc, Scene, Viewport};
use crate::surface::{Algorithm, RenderOptions};
use crate::view::{PrepareOptions, View, ViewTransform};
use crate::{BACKGROUND, SceneIndex};

/// Room height of the levels.
const H: f64 = 3.0;
/// Half the thickness of the wall boxes.
const W: f64 = 0.01;

/// A box cell: six planes, normals out.
fn box_cell(name: &str, min: DVec3, max: DVec3) -> Cell {
    let pl = |n: DVec3, p: DVec3| Plane::from_point_normal(p, n);
    Cell {
        name: name.to_owned(),
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

/// A door in the wall `x = x` (z from `z0` to `z1`, y from 0 to `top`).
fn door_x(x: f64, z0: f64, z1: f64, top: f64, cells: [u32; 2]) -> Portal {
    Portal {
        cells,
        polygon: vec![
            DVec3::new(x, 0.0, z0),
            DVec3::new(x, 0.0, z1),
            DVec3::new(x, top, z1),
            DVec3::new(x, top, z0),
        ],
    }
}

/// A door in the wall `z = z` (x from `x0` to `x1`, y from 0 to `top`).
fn door_z(z: f64, x0: f64, x1: f64, top: f64, cells: [u32; 2]) -> Portal {
    Portal {
        cells,
        polygon: vec![
            DVec3::new(x0, 0.0, z),
            DVec3::new(x1, 0.0, z),
            DVec3::new(x1, top, z),
            DVec3::new(x0, top, z),
        ],
    }
}

fn add_box(scene: &mut Scene, name: &str, min: DVec3, max: DVec3, color: [f32; 3]) -> u32 {
    scene
        .add(ObjectDesc::new(name, box_mesh(min, max)).with_color(color))
        .unwrap() as u32
}

/// The wall on the plane `axis = at` (0: x, 2: z) over `[from, to]` along the other
/// horizontal axis, with door holes `(lo, hi, top)`: thin boxes around the holes.
fn wall(scene: &mut Scene, axis: usize, at: f64, from: f64, to: f64, holes: &[(f64, f64, f64)]) {
    let pt = |along: f64, y: f64, off: f64| {
        if axis == 0 {
            DVec3::new(at + off, y, along)
        } else {
            DVec3::new(along, y, at + off)
        }
    };
    let mut piece = |a0: f64, a1: f64, y0: f64, y1: f64| {
        if a1 - a0 > 1e-9 && y1 - y0 > 1e-9 {
            let (p, q) = (pt(a0, y0, -W), pt(a1, y1, W));
            add_box(scene, "wall", p.min(q), p.max(q), [0.7, 0.7, 0.65]);
        }
    };
    let mut holes = holes.to_vec();
    holes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut a = from;
    for &(lo, hi, top) in &holes {
        piece(a, lo, 0.0, H);
        piece(lo, hi, top, H);
        a = hi;
    }
    piece(a, to, 0.0, H);
}

/// Floor and ceiling slabs over `[x0, x1] x [z0, z1]`.
fn slabs(scene: &mut Scene, x1: f64, z1: f64) {
    add_box(
        scene,
        "floor",
        DVec3::new(-W, -2.0 * W, -W),
        DVec3::new(x1 + W, 0.0, z1 + W),
        [0.5, 0.5, 0.5],
    );
    add_box(
        scene,
        "ceiling",
        DVec3::new(-W, H, -W),
        DVec3::new(x1 + W, H + 2.0 * W, z1 + W),
        [0.6, 0.6, 0.6],
    );
}

/// Puts `n` random boxes in a room (kept clear of its walls) and lists them in the
/// cell.
fn furnish(
    scene: &mut Scene,
    cell: &mut Cell,
    min: DVec3,
    max: DVec3,
    n: usize,
    rng: &mut SplitMix64,
) {
    for _ in 0..n {
        let s = DVec3::new(
            rng.range(0.2, 0.7),
            rng.range(0.2, 1.6),
            rng.range(0.2, 0.7),
        );
        let x = rng.range(min.x + 0.1, max.x - 0.1 - s.x);
        let z = rng.range(min.z + 0.1, max.z - 0.1 - s.z);
        let y = rng.range(0.0, 1.0);
        let c = [rng.next_f64() as f32, 0.6, rng.next_f64() as f32];
        let k = add_box(
            scene,
            "thing",
            DVec3::new(x, y, z),
            DVec3::new(x, y, z) + s,
            c,
        );
        cell.objects.push(k);
    }
}

/// The seed's five cells as a row of rooms along x (A, D, E, C, B, 4 wide and 4 deep),
/// doors alternately low and high in z: two doors can always be looked through, three
/// never. Cells in the order A, B, C, D, E. Expected PVS: A:{A,D,E} B:{B,C,E}
/// C:{B,C,D,E} D:{A,C,D,E} E:{all}.
fn five_cells(furnished: usize) -> Scene {
    const A: u32 = 0;
    const B: u32 = 1;
    const C: u32 = 2;
    const D: u32 = 3;
    const E: u32 = 4;
    let mut scene = Scene::new();
    let mut rng = SplitMix64(5);
    let room = |i: f64| {
        (
            DVec3::new(4.0 * i, 0.0, 0.0),
            DVec3::new(4.0 * i + 4.0, H, 4.0),
        )
    };
    // Room order along x: A D E C B.
    let order = [(A, "A"), (D, "D"), (E, "E"), (C, "C"), (B, "B")];
    let mut cells: Vec<Cell> = vec![box_cell("", DVec3::ZERO, DVec3::ONE); 5];
    for (i, &(id, name)) in order.iter().enumerate() {
        let (lo, hi) = room(i as f64);
        cells[id as usize] = box_cell(name, lo, hi);
    }
    slabs(&mut scene, 20.0, 4.0);
    wall(&mut scene, 0, 0.0, 0.0, 4.0, &[]);
    wall(&mut scene, 0, 20.0, 0.0, 4.0, &[]);
    wall(&mut scene, 2, 0.0, 0.0, 20.0, &[]);
    wall(&mut scene, 2, 4.0, 0.0, 20.0, &[]);
    let mut portals = Vec::new();
    for i in 0..4 {
        let x = 4.0 * (i + 1) as f64;
        let (z0, z1) = if i % 2 == 0 { (0.0, 1.5) } else { (2.5, 4.0) };
        wall(&mut scene, 0, x, 0.0, 4.0, &[(z0, z1, H)]);
        portals.push(door_x(x, z0, z1, H, [order[i].0, order[i + 1].0]));
    }
    for (i, &(id, _)) in order.iter().enumerate() {
        let (lo, hi) = room(i as f64);
        furnish(
            &mut scene,
            &mut cells[id as usize],
            lo,
            hi,
            furnished,
            &mut rng,
        );
    }
    if furnished > 0 {
        // A bench through the door between A and D, in both cells.
        let k = add_box(
            &mut scene,
            "bench",
            DVec3::new(2.0, 0.8, 0.4),
            DVec3::new(6.0, 1.0, 0.6),
            [0.9, 0.3, 0.2],
        );
        cells[A as usize].objects.push(k);
        cells[D as usize].objects.push(k);
    }
    scene.set_cells(Some(Arc::new(CellGraph::new(cells, portals))));
    scene
}

/// A grid of `nx x nz` rooms 4 x 4, each joined to its right and back neighbours by a
/// door 1 wide and 2.2 high at a random place in the wall, furnished.
fn grid_level(nx: usize, nz: usize, furnished: usize, seed: u64) -> Scene {
    let mut scene = Scene::new();
    let mut rng = SplitMix64(seed);
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut cells = Vec::new();
    for j in 0..nz {
        for i in 0..nx {
            let lo = DVec3::new(4.0 * i as f64, 0.0, 4.0 * j as f64);
            cells.push(box_cell(
                &format!("{i},{j}"),
                lo,
                lo + DVec3::new(4.0, H, 4.0),
            ));
        }
    }
    let (xmax, zmax) = (4.0 * nx as f64, 4.0 * nz as f64);
    slabs(&mut scene, xmax, zmax);
    let mut portals = Vec::new();
    // Walls x = 4 i, one door per room along it.
    for i in 0..=nx {
        let x = 4.0 * i as f64;
        let mut holes = Vec::new();
        if i > 0 && i < nx {
            for j in 0..nz {
                let z0 = 4.0 * j as f64 + rng.range(0.1, 2.9);
                holes.push((z0, z0 + 1.0, 2.2));
                portals.push(door_x(x, z0, z0 + 1.0, 2.2, [id(i - 1, j), id(i, j)]));
            }
        }
        wall(&mut scene, 0, x, 0.0, zmax, &holes);
    }
    for j in 0..=nz {
        let z = 4.0 * j as f64;
        let mut holes = Vec::new();
        if j > 0 && j < nz {
            for i in 0..nx {
                let x0 = 4.0 * i as f64 + rng.range(0.1, 2.9);
                holes.push((x0, x0 + 1.0, 2.2));
                portals.push(door_z(z, x0, x0 + 1.0, 2.2, [id(i, j - 1), id(i, j)]));
            }
        }
        wall(&mut scene, 2, z, 0.0, xmax, &holes);
    }
    for j in 0..nz {
        for i in 0..nx {
            let lo = DVec3::new(4.0 * i as f64, 0.0, 4.0 * j as f64);
            let c = &mut cells[id(i, j) as usize];
            furnish(
                &mut scene,
                c,
                lo,
                lo + DVec3::new(4.0, H, 4.0),
                furnished,
                &mut rng,
            );
        }
    }
    scene.set_cells(Some(Arc::new(CellGraph::new(cells, portals))));
    scene
}

fn table(t: &pvs::Pvs, names: &[&str]) -> Vec<String> {
    (0..t.len() as u32)
        .map(|a| t.row(a).map(|b| names[b as usize]).collect::<String>())
        .collect()
}

#[test]
fn seed_five_cells_give_the_seed_pvs_table() {
    let scene = five_cells(0);
    let graph = scene.cells().unwrap();
    let t = pvs::compute(graph, &PvsOptions::default(), &|_, _| {}).unwrap();
    assert_eq!(
        table(&t, &["A", "B", "C", "D", "E"]),
        ["ADE", "BCE", "BCDE", "ACDE", "ABCDE"]
    );
    assert!(t.is_symmetric());
    assert!(t.incomplete.is_empty());
}

#[test]
fn seed_portal_walk_from_e_goes_to_d_then_a_and_stops() {
    let scene = five_cells(0);
    let graph = scene.cells().unwrap();
    // In E near its door to D, looking through it and on through the door to A.
    let camera = Camera::perspective(
        DVec3::new(9.0, 1.5, 3.5),
        DVec3::new(4.0, 1.5, 0.75),
        DVec3::Y,
        60.0,
        0.05,
        100.0,
    );
    let t = ViewTransform::new(&camera, Viewport::new(160, 90).unwrap());
    let walk = portal_walk(graph, camera.eye, &view_frustum(&t));
    let cells: Vec<&str> = walk
        .iter()
        .map(|v| graph.cells[v.cell as usize].name.as_str())
        .collect();
    assert_eq!(cells, ["E", "D", "A"]);
    assert_eq!(walk[0].portal, None);
    assert_eq!(walk[1].parent, Some(0));
    assert_eq!(walk[2].parent, Some(1));
    // Each frustum shrinks: f1 (the view's 6 planes), f2 adds the 4 planes of the door
    // E|D, f3 the 4 of the door D|A.
    assert_eq!(
        walk.iter().map(|v| v.frustum.len()).collect::<Vec<_>>(),
        [6, 10, 14]
    );
    // Looking the other way (at C's door) the walk never enters D.
    let back = Camera::perspective(
        DVec3::new(9.0, 1.5, 3.5),
        DVec3::new(16.0, 1.5, 0.75),
        DVec3::Y,
        60.0,
        0.05,
        100.0,
    );
    let t = ViewTransform::new(&back, Viewport::new(160, 90).unwrap());
    let walk = portal_walk(graph, back.eye, &view_frustum(&t));
    let cells: Vec<&str> = walk
        .iter()
        .map(|v| graph.cells[v.cell as usize].name.as_str())
        .collect();
    assert!(!cells.contains(&"D") && cells.contains(&"C"), "{cells:?}");
}

/// The library's own five-cell plan (`portals::seed_example`, the floor plan of the
/// seed's figure, designed independently of `five_cells` above): the same table, and
/// the seed's walk E -> D -> A from a viewer in E looking through the door to D.
#[test]
fn seed_example_plan_gives_the_seed_table_and_walk() {
    let (graph, scene) = crate::cull::portals::seed_example();
    let t = pvs::compute(&graph, &PvsOptions::default(), &|_, _| {}).unwrap();
    assert_eq!(
        table(&t, &["A", "B", "C", "D", "E"]),
        ["ADE", "BCE", "BCDE", "ACDE", "ABCDE"]
    );
    assert!(t.is_symmetric());
    // In E = [0,12]x[0,2] at (2.5, 0.5), looking at (0, 4): through DE (z = 2, x in
    // [1, 2]) at x = 1.43, then through AD (x = 0, z in [3.5, 4.5]) at z = 4.
    let camera = Camera::perspective(
        DVec3::new(2.5, 1.5, 0.5),
        DVec3::new(0.0, 1.5, 4.0),
        DVec3::Y,
        60.0,
        0.05,
        100.0,
    );
    let vt = ViewTransform::new(&camera, Viewport::new(160, 90).unwrap());
    let walk = portal_walk(&graph, camera.eye, &view_frustum(&vt));
    let cells: Vec<&str> = walk
        .iter()
        .map(|v| graph.cells[v.cell as usize].name.as_str())
        .collect();
    assert_eq!(cells, ["E", "D", "A"]);
    // Culling by portals keeps the picture (checked view by view inside) and, with the
    // frustum, removes most hidden objects (1240 of 1391 when written).
    let c = conservative_on(
        &scene,
        &CullOptions::with_method(CullMethod::Portals),
        20,
        5,
    );
    assert!(c > 0.8, "{c}");
}

/// Lines through random points of random portal pairs, followed through the level:
/// each run of cells the line joins through portals only is mutually visible, and must
/// be in the PVS. Returns how many pairs the lines found.
fn sampled_lines_in_pvs(scene: &Scene, t: &pvs::Pvs, lines: usize, seed: u64) -> usize {
    let graph = scene.cells().unwrap();
    let mut rng = SplitMix64(seed);
    let planes: Vec<Plane> = graph
        .cells
        .iter()
        .flat_map(|c| c.planes.iter().map(|p| p.normalized()))
        .collect();
    let bounds = scene.bounds();
    let inside_portal = |p: DVec3, portal: &Portal| {
        let poly = &portal.polygon;
        let n = (poly[1] - poly[0]).cross(poly[2] - poly[0]).normalize();
        (0..poly.len()).all(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            n.dot((b - a).cross(p - a)) >= -1e-9
        }) && n.dot(p - poly[0]).abs() < 1e-7
    };
    let mut found = std::collections::HashSet::new();
    let random_on = |rng: &mut SplitMix64, poly: &[DVec3]| {
        // A random convex combination of the corners (all portals here are rectangles).
        let (u, v) = (rng.next_f64(), rng.next_f64());
        poly[0] + (poly[1] - poly[0]) * u + (poly[3] - poly[0]) * v
    };
    for _ in 0..lines {
        let p = &graph.portals[(rng.next_u64() % graph.portals.len() as u64) as usize];
        let q = &graph.portals[(rng.next_u64() % graph.portals.len() as u64) as usize];
        let (u, v) = (
            random_on(&mut rng, &p.polygon),
            random_on(&mut rng, &q.polygon),
        );
        let dir = v - u;
        if dir.length() < 1e-6 {
            continue;
        }
        let Some((t0, t1)) = bounds.ray_interval(u, dir) else {
            continue;
        };
        let mut ts: Vec<f64> = planes
            .iter()
            .filter_map(|pl| {
                let den = pl.normal.dot(dir);
                (den.abs() > 1e-12).then(|| -(pl.normal.dot(u) + pl.d) / den)
            })
            .filter(|&s| s > t0 && s < t1)
            .collect();
        ts.push(t0);
        ts.push(t1);
        ts.sort_by(f64::total_cmp);
        ts.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let mut run: Vec<u32> = Vec::new();
        let mut close = |run: &mut Vec<u32>| {
            for &a in run.iter() {
                for &b in run.iter() {
                    assert!(t.contains(a, b), "a line of sight joins cells {a} and {b}");
                    found.insert((a, b));
                }
            }
            run.clear();
        };
        for w in ts.windows(2) {
            let mid = u + dir * (0.5 * (w[0] + w[1]));
            let Some(cell) = graph.locate(mid) else {
                close(&mut run);
                continue;
            };
            if let Some(&last) = run.last()
                && last != cell
            {
                let x = u + dir * w[0];
                let through = graph.portals.iter().any(|pt| {
                    (pt.cells == [last, cell] || pt.cells == [cell, last]) && inside_portal(x, pt)
                });
                if !through {
                    close(&mut run);
                }
            }
            if run.last() != Some(&cell) {
                run.push(cell);
            }
        }
        close(&mut run);
    }
    found.len()
}

#[test]
fn pvs_holds_every_sampled_line_of_sight_and_is_symmetric() {
    let scene = five_cells(0);
    let t = pvs::compute(scene.cells().unwrap(), &PvsOptions::default(), &|_, _| {}).unwrap();
    // Every pair of the table but the self pairs is met by some line.
    let found = sampled_lines_in_pvs(&scene, &t, 20_000, 1);
    let pairs: usize = (0..5).map(|a| t.count(a)).sum();
    assert_eq!(found, pairs, "sampled pairs against the table");

    let scene = grid_level(4, 4, 0, 7);
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let t = pvs::compute(
        scene.cells().unwrap(),
        &PvsOptions::default(),
        &|done, total| {
            assert!(done <= total && total == 16);
            calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        },
    )
    .unwrap();
    assert_eq!(calls.into_inner(), 16);
    assert!(t.is_symmetric());
    assert!(t.incomplete.is_empty());
    let found = sampled_lines_in_pvs(&scene, &t, 20_000, 2);
    let pairs: usize = (0..16).map(|a| t.count(a)).sum();
    println!("grid 4x4: sampled lines found {found} of the {pairs} pairs of the PVS");
    // Over-estimated, but little: the lines find nearly every pair of the table (this
    // open level's rooms see most of it; 400,000 lines find 226 of its 228 pairs).
    assert!(
        found <= pairs && found * 100 >= pairs * 95,
        "{found} of {pairs}"
    );
}

#[test]
fn pvs_budget_falls_back_to_reachable_and_deadline_stops() {
    let scene = grid_level(3, 3, 0, 3);
    let graph = scene.cells().unwrap();
    let opts = PvsOptions {
        max_sequences: 3,
        ..PvsOptions::default()
    };
    let t = pvs::compute(graph, &opts, &|_, _| {}).unwrap();
    assert_eq!(t.incomplete.len(), 9);
    assert!((0..9).all(|a| t.count(a) == 9));
    let opts = PvsOptions {
        deadline: crate::work::Deadline::new(Some(std::time::Duration::ZERO), None),
        max_sequences: u64::MAX,
    };
    // A zero time limit ends the computation once a walk checks it.
    let big = grid_level(6, 6, 0, 3);
    let r = pvs::compute(big.cells().unwrap(), &opts, &|_, _| {});
    assert!(matches!(r, Err(crate::Error::TimeLimit { .. })), "{r:?}");
}

/// Per view: culls with `options`, checks every face the full z-buffer shows survives
/// and that the culled view draws the same ids and depths. Returns (hidden objects of
/// cells, of them culled).
fn check_view(
    scene: &Scene,
    index: &SceneIndex<'_>,
    camera: &Camera,
    options: &CullOptions,
) -> (usize, usize, Culling) {
    let vp = Viewport::new(160, 90).unwrap();
    let opts = PrepareOptions::default();
    let ro = RenderOptions::default();
    let plain = View::new(scene, camera, vp, &opts).unwrap();
    let (full, _) = index.render_view(&plain, Algorithm::ZBuffer, &ro).unwrap();
    let culling = index.cull(camera, vp, options).unwrap();
    let mut base = Vec::new();
    let mut b = 0;
    for o in scene.objects() {
        base.push(b);
        b += o.mesh.polygon_count();
    }
    let mut visible = vec![false; scene.objects().len()];
    for &id in &full.ids {
        if id == BACKGROUND {
            continue;
        }
        let (k, face) = scene.locate_face(id).unwrap();
        visible[k] = true;
        assert!(
            culling.objects[k].is_none(),
            "visible object {k} culled ({:?}) from {:?}",
            culling.objects[k],
            camera.eye
        );
        for p in scene.objects()[k].mesh.polygons_of_face(face) {
            assert!(
                !culling.faces[base[k] + p],
                "visible face {id} culled from {:?}",
                camera.eye
            );
        }
    }
    let culled = View::new_culled(scene, camera, vp, &opts, culling.clone()).unwrap();
    let (f, _) = index.render_view(&culled, Algorithm::ZBuffer, &ro).unwrap();
    assert_eq!(f.ids, full.ids, "ids from {:?}", camera.eye);
    assert_eq!(f.depth, full.depth, "depth from {:?}", camera.eye);
    let graph = scene.cells().unwrap();
    let in_cells: std::collections::HashSet<u32> = graph
        .cells
        .iter()
        .flat_map(|c| c.objects.iter().copied())
        .collect();
    let hidden: Vec<u32> = in_cells
        .into_iter()
        .filter(|&k| !visible[k as usize])
        .collect();
    let culled_hidden = hidden
        .iter()
        .filter(|&&k| culling.objects[k as usize].is_some())
        .count();
    (hidden.len(), culled_hidden, culling)
}

/// Random viewpoints inside the rooms of a level (some right against walls and in
/// doorways), looking anywhere roughly level.
fn viewpoints(scene: &Scene, n: usize, seed: u64) -> Vec<Camera> {
    let graph = scene.cells().unwrap();
    let b = scene.bounds();
    let mut rng = SplitMix64(seed);
    let mut v = Vec::new();
    while v.len() < n {
        let eye = DVec3::new(
            rng.range(b.min.x + 0.03, b.max.x - 0.03),
            rng.range(0.2, H - 0.2),
            rng.range(b.min.z + 0.03, b.max.z - 0.03),
        );
        if graph.locate(eye).is_none() {
            continue;
        }
        let a = rng.range(0.0, std::f64::consts::TAU);
        let dir = DVec3::new(a.cos(), rng.range(-0.4, 0.4), a.sin());
        let fov = rng.range(40.0, 100.0);
        v.push(Camera::perspective(
            eye,
            eye + dir,
            DVec3::Y,
            fov,
            0.05,
            200.0,
        ));
    }
    // Eyes exactly on portals (the whole frustum passes) and on walls, looking both ways
    // along x and along z.
    for p in &graph.portals {
        let c = p.polygon.iter().sum::<DVec3>() / p.polygon.len() as f64;
        let on_wall = c + (p.polygon[1] - p.polygon[0]).normalize() * 1.2;
        for eye in [c, on_wall]
            .into_iter()
            .filter(|&e| graph.locate(e).is_some())
        {
            for dir in [
                DVec3::X,
                -DVec3::X,
                DVec3::new(0.3, 0.0, 1.0),
                DVec3::new(-0.3, 0.1, -1.0),
            ] {
                v.push(Camera::perspective(
                    eye,
                    eye + dir,
                    DVec3::Y,
                    70.0,
                    0.05,
                    200.0,
                ));
            }
        }
    }
    v
}

fn conservative_on(scene: &Scene, options: &CullOptions, views: usize, seed: u64) -> f64 {
    let index = SceneIndex::new(scene);
    let (mut hidden, mut culled, mut by_portal) = (0, 0, 0);
    for camera in viewpoints(scene, views, seed) {
        let (h, c, culling) = check_view(scene, &index, &camera, options);
        hidden += h;
        culled += c;
        // Culled as hidden by the method itself (the frustum stage runs first and
        // gives its own reason), all hidden as checked above.
        by_portal += culling
            .objects
            .iter()
            .filter(|r| **r == Some(CullReason::Portal))
            .count();
        assert!(culling.notes.is_empty(), "{:?}", culling.notes);
    }
    assert!(hidden > 0);
    println!(
        "  {:?}: of {hidden} hidden objects (all views), {culled} culled, {by_portal} of them by portals (the rest by the frustum)",
        options.method,
    );
    assert!(by_portal > 0);
    culled as f64 / hidden as f64
}

#[test]
fn portal_culling_is_conservative_and_effective() {
    for (name, scene) in [
        ("five cells", five_cells(3)),
        ("grid 4x4", grid_level(4, 4, 3, 11)),
    ] {
        for bbox in [false, true] {
            let options = CullOptions {
                portal_bounding_box: bbox,
                ..CullOptions::with_method(CullMethod::Portals)
            };
            let f = conservative_on(&scene, &options, 30, 21);
            println!(
                "{name}, portals (bounding box {bbox}): {:.0}% of hidden objects culled",
                100.0 * f
            );
            assert!(f > 0.5, "{name}: {f}");
        }
    }
}

#[test]
fn screen_portals_are_conservative_and_effective() {
    for (name, scene) in [
        ("five cells", five_cells(3)),
        ("grid 4x4", grid_level(4, 4, 3, 11)),
    ] {
        let options = CullOptions::with_method(CullMethod::ScreenPortals);
        let f = conservative_on(&scene, &options, 30, 22);
        println!(
            "{name}, screen portals: {:.0}% of hidden objects culled",
            100.0 * f
        );
        assert!(f > 0.5, "{name}: {f}");
    }
}

/// Hundreds of viewpoints for each method (`cargo test --release -p obscura --lib
/// portals -- --ignored`).
#[test]
#[ignore = "hundreds of viewpoints: run by hand"]
fn portal_methods_conservative_on_hundreds_of_viewpoints() {
    let scene = grid_level(6, 6, 4, 99);
    for (method, bbox) in [
        (CullMethod::Portals, false),
        (CullMethod::Portals, true),
        (CullMethod::ScreenPortals, false),
    ] {
        let options = CullOptions {
            portal_bounding_box: bbox,
            ..CullOptions::with_method(method)
        };
        let f = conservative_on(&scene, &options, 400, 5);
        println!(
            "{method:?} bbox {bbox}: {:.1}% of hidden objects culled",
            100.0 * f
        );
    }
}

#[test]
fn viewer_outside_every_cell_culls_nothing_by_portals_and_says_so() {
    let scene = five_cells(2);
    let index = SceneIndex::new(&scene);
    let camera = Camera::perspective(
        DVec3::new(-6.0, 1.5, 2.0),
        DVec3::new(10.0, 1.5, 2.0),
        DVec3::Y,
        70.0,
        0.05,
        200.0,
    );
    for method in [CullMethod::Portals, CullMethod::ScreenPortals] {
        let (_, _, c) = check_view(&scene, &index, &camera, &CullOptions::with_method(method));
        assert!(
            c.notes.iter().any(|n| n.contains("outside every cell")),
            "{:?}",
            c.notes
        );
        assert!(c.objects.iter().all(|r| *r != Some(CullReason::Portal)));
        assert_eq!(c.stats.objects_by_reason.portal, 0);
    }
    // A scene without cells: a note, no portal culling.
    let plain = crate::scene::demo::city(3, 3, 1);
    let index = SceneIndex::new(&plain);
    let c = index
        .cull(
            &camera,
            Viewport::new(64, 36).unwrap(),
            &CullOptions::with_method(CullMethod::Portals),
        )
        .unwrap();
    assert!(
        c.notes.iter().any(|n| n.contains("no cells")),
        "{:?}",
        c.notes
    );
}

#[test]
fn portal_culling_reasons_and_the_cached_pvs() {
    let scene = five_cells(3);
    let index = SceneIndex::new(&scene);
    // From A looking down the row: B and C are outside A's PVS, so their furniture
    // goes by portal (or frustum), never drawn.
    let camera = Camera::perspective(
        DVec3::new(1.0, 1.5, 1.0),
        DVec3::new(19.0, 1.5, 3.0),
        DVec3::Y,
        90.0,
        0.05,
        200.0,
    );
    let (_, _, c) = check_view(
        &scene,
        &index,
        &camera,
        &CullOptions::with_method(CullMethod::Portals),
    );
    let graph = scene.cells().unwrap();
    for cell in [1usize, 2] {
        for &k in &graph.cells[cell].objects {
            assert!(c.objects[k as usize].is_some(), "object {k} of cell {cell}");
        }
    }
    assert!(c.stats.objects_by_reason.portal > 0);
    assert!(c.stats.stages.iter().any(|(s, _)| s == "portals"));
    let p1 = index.pvs().unwrap() as *const _;
    let p2 = index.pvs().unwrap() as *const _;
    assert_eq!(p1, p2, "the PVS is built once");
}

/// The issue: "in the demo level the PVS removes most cells from any viewpoint". From
/// every camera of the level's walk (96 viewpoints), the portal walk (the viewer's
/// cell, its PVS row, the frustum shrunk through each portal) enters fewer than a
/// third of the cells; each cell's PVS row holds fewer than half of them on average
/// (a row is the union over every viewpoint of the cell and every direction).
#[test]
fn the_demo_levels_pvs_removes_most_cells_from_every_viewpoint() {
    let scene = crate::scene::demo::level();
    let graph = scene.cells().unwrap();
    let index = SceneIndex::new(&scene);
    let t = index.pvs().unwrap();
    let n = t.len();
    let mean = (0..n as u32).map(|c| t.count(c)).sum::<usize>() as f64 / n as f64;
    assert!(mean < 0.5 * n as f64, "{mean} of {n}");
    let mut worst = 0;
    for camera in crate::scene::demo::level_walk() {
        let vt = ViewTransform::new(&camera, Viewport::new(160, 90).unwrap());
        let walk = portal_walk(graph, camera.eye, &view_frustum(&vt));
        let mut cells: Vec<u32> = walk.iter().map(|v| v.cell).collect();
        cells.sort_unstable();
        cells.dedup();
        worst = worst.max(cells.len());
    }
    println!("  demo:level: {n} cells, PVS rows {mean:.1} on average; walks enter at most {worst}");
    assert!(3 * worst < n, "a walk entered {worst} of {n} cells");
}
