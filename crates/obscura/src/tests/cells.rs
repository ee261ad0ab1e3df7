//! The cell model of cells-and-portals culling: validation (each kind of problem found
//! with its place), the BSP locator against a linear scan, floor plans (door holes
//! exactly where the portals are), the seed's five-cell example checked by sampled lines
//! of sight, the demo levels, PRT1 import.

use std::collections::BTreeSet;
use std::path::Path;

use glam::{DVec2, DVec3};

use crate::Error;
use crate::cull::portals::floorplan::{level_plan, plan_walk};
use crate::cull::portals::prt::{parse_prt, write_prt};
use crate::cull::portals::segment_hits_scene;
use crate::cull::portals::{
    Cell, CellGraph, CellIssueKind, Door, FloorPlan, Portal, Room, seed_example,
};
use crate::geom::Plane;
use crate::index::SceneIndex;
use crate::rng::SplitMix64;
use crate::scene::{Camera, Scene, Viewport, demo};
use crate::surface::{Algorithm, RenderOptions};
use crate::view::{PrepareOptions, View};

const A: usize = 0;
const B: usize = 1;
const C: usize = 2;
const D: usize = 3;
const E: usize = 4;

/// A random point strictly inside an axis-aligned cell (from its planes' box).
fn random_in(graph: &CellGraph, c: usize, rng: &mut SplitMix64, y: (f64, f64)) -> DVec3 {
    let shape = crate::cull::portals::CellShape::new(&graph.cells[c].planes);
    let b = shape.bounds();
    loop {
        let p = DVec3::new(
            rng.range(b.min.x + 1e-3, b.max.x - 1e-3),
            rng.range(y.0, y.1),
            rng.range(b.min.z + 1e-3, b.max.z - 1e-3),
        );
        if graph.cells[c]
            .planes
            .iter()
            .all(|pl| pl.signed_distance(p) < -1e-4)
        {
            return p;
        }
    }
}

#[test]
fn seed_example_is_valid_and_sampled_sight_lines_give_the_seed_table() {
    let (graph, scene) = seed_example();
    assert_eq!(graph.cells.len(), 5);
    assert_eq!(graph.portals.len(), 4);
    let names: Vec<&str> = graph.cells.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["A", "B", "C", "D", "E"]);
    let report = graph.validate_with_scene(&scene).unwrap();
    assert_eq!(report.issues, vec![], "no warning either");
    assert!(scene.cells().is_some());
    // Lines of sight sampled between random points of two cells (above the furniture,
    // which is 0.8 high): a pair is visible when some segment crosses no scene face.
    let mut rng = SplitMix64(5);
    let mut seen = vec![BTreeSet::new(); 5];
    for a in 0..5 {
        seen[a].insert(a);
        for b in a + 1..5 {
            for _ in 0..40_000 {
                let p = random_in(&graph, a, &mut rng, (1.0, 2.9));
                let q = random_in(&graph, b, &mut rng, (1.0, 2.9));
                if !segment_hits_scene(&scene, p, q, 1e-9) {
                    seen[a].insert(b);
                    seen[b].insert(a);
                    break;
                }
            }
        }
    }
    let table: Vec<BTreeSet<usize>> = vec![
        [A, D, E].into(),
        [B, C, E].into(),
        [B, C, D, E].into(),
        [A, C, D, E].into(),
        [A, B, C, D, E].into(),
    ];
    assert_eq!(seen, table);
    // The documented witness of A-E through AD and DE.
    let (p, q) = (DVec3::new(-0.75, 1.5, 5.0), DVec3::new(2.25, 1.5, 1.0));
    assert_eq!(graph.locate(p), Some(A as u32));
    assert_eq!(graph.locate(q), Some(E as u32));
    assert!(!segment_hits_scene(&scene, p, q, 1e-9));
}

fn issue_kinds(graph: &CellGraph, scene: Option<&Scene>) -> Vec<CellIssueKind> {
    graph
        .diagnose(scene)
        .issues
        .into_iter()
        .map(|i| i.kind)
        .collect()
}

#[test]
fn validation_finds_each_problem_with_its_place() {
    let (good, scene) = seed_example();
    // A portal moved off the wall D and E share (z = 2) by 0.5.
    let mut g = good.clone();
    for v in &mut g.portals[1].polygon {
        v.z += 0.5;
    }
    let r = g.diagnose(None);
    let off: Vec<_> = r
        .errors()
        .filter_map(|i| match i.kind {
            CellIssueKind::PortalOffBoundary {
                portal,
                cell,
                distance,
            } => Some((portal, cell, distance, i.message.clone(), i.place)),
            _ => None,
        })
        .collect();
    // Off E's boundary (E ends at z = 2), and inside D (0.5 from its wall).
    assert_eq!(off.len(), 2, "{off:?}");
    for (portal, _, distance, message, place) in &off {
        assert_eq!(*portal, 1);
        assert!((distance - 0.5).abs() < 1e-9, "{distance}");
        assert!(
            message.contains("\"D\"") && message.contains("\"E\""),
            "{message}"
        );
        assert!((place.z - 2.5).abs() < 1e-9 && (place.x - 1.5).abs() < 1e-9);
    }
    let err = g.validate().unwrap_err();
    assert!(matches!(err, Error::InvalidCells { .. }));
    assert!(err.to_string().contains("portal 1"), "{err}");

    // Degenerate, non-planar, non-convex portals.
    let mut g = good.clone();
    g.portals[0].polygon.truncate(2);
    assert!(issue_kinds(&g, None).contains(&CellIssueKind::DegeneratePortal { portal: 0 }));
    let mut g = good.clone();
    g.portals[1].polygon[2].z += 0.3;
    assert!(
        issue_kinds(&g, None)
            .iter()
            .any(|k| matches!(k, CellIssueKind::NonPlanarPortal { portal: 1, .. }))
    );
    let mut g = good.clone();
    // An arrow on the wall z = 2: (1,0) (2,0) (2,2) (1.5,0.5) (1,2).
    g.portals[1].polygon = vec![
        DVec3::new(1.0, 0.0, 2.0),
        DVec3::new(2.0, 0.0, 2.0),
        DVec3::new(2.0, 2.0, 2.0),
        DVec3::new(1.5, 0.5, 2.0),
        DVec3::new(1.0, 2.0, 2.0),
    ];
    assert_eq!(
        issue_kinds(&g, None),
        vec![CellIssueKind::NonConvexPortal { portal: 1 }]
    );
    // A portal naming a cell that does not exist.
    let mut g = good.clone();
    g.portals[2].cells = [4, 9];
    assert!(issue_kinds(&g, None).contains(&CellIssueKind::BadPortalCells { portal: 2 }));

    // An open cell: A without its wall x = -3 runs off to x = -infinity.
    let mut g = good.clone();
    let west = g.cells[A]
        .planes
        .iter()
        .position(|p| p.normal.x < -0.5)
        .unwrap();
    g.cells[A].planes.remove(west);
    let r = g.diagnose(None);
    let open: Vec<_> = r
        .errors()
        .filter(|i| i.kind == CellIssueKind::OpenCell { cell: A })
        .collect();
    assert_eq!(open.len(), 1);
    assert!(open[0].place.x < -1e6, "{:?}", open[0].place);
    assert!(open[0].message.contains("\"A\""));

    // An empty cell: D also behind x <= -1 (D is x in [0, 3]).
    let mut g = good.clone();
    g.cells[D].planes.push(Plane::from_point_normal(
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::X,
    ));
    assert!(issue_kinds(&g, None).contains(&CellIssueKind::EmptyCell { cell: D }));

    // Overlapping cells: a sixth cell over the corner of D and E.
    let mut g = good.clone();
    let plan = FloorPlan::new(vec![Room::rect("F", 2.0, 1.0, 4.0, 3.0)], vec![], 3.0);
    let (f, _) = plan.build().unwrap();
    g.cells.push(f.cells[0].clone());
    let r = g.diagnose(None);
    let overlaps: Vec<_> = r
        .errors()
        .filter_map(|i| match i.kind {
            CellIssueKind::Overlap { a, b } => Some((a, b, i.place)),
            _ => None,
        })
        .collect();
    assert_eq!(overlaps.len(), 2, "{overlaps:?}");
    assert_eq!((overlaps[0].0, overlaps[0].1), (D, 5));
    assert_eq!((overlaps[1].0, overlaps[1].1), (E, 5));
    // The place is inside both.
    for &(a, b, p) in &overlaps {
        for c in [a, b] {
            assert!(
                g.cells[c]
                    .planes
                    .iter()
                    .all(|pl| pl.signed_distance(p) < 0.0)
            );
        }
    }

    // A leak: the door D-E without its portal.
    let mut g = good.clone();
    g.portals.remove(1);
    let r = g.diagnose(Some(&scene));
    let leaks: Vec<_> = r
        .errors()
        .filter_map(|i| match i.kind {
            CellIssueKind::Leak { cell, plane } => Some((cell, plane, i.place)),
            _ => None,
        })
        .collect();
    let cells: BTreeSet<usize> = leaks.iter().map(|l| l.0).collect();
    assert_eq!(cells, [D, E].into(), "{leaks:?}");
    for &(cell, plane, p) in &leaks {
        // On the wall z = 2, in the door x in [1, 2] below its top.
        assert!((p.z - 2.0).abs() < 1e-9, "{p}");
        assert!(p.x > 1.0 && p.x < 2.0 && p.y < 3.0, "{p}");
        assert!(g.cells[cell].planes[plane].signed_distance(p).abs() < 1e-9);
    }
    assert!(g.validate().is_ok(), "without the scene no leak is seen");
    assert!(g.validate_with_scene(&scene).is_err());

    // Objects: an index the scene does not have (error), an object outside its cell
    // (a warning).
    let mut g = good.clone();
    g.cells[A].objects.push(10_000);
    assert!(
        issue_kinds(&g, Some(&scene)).contains(&CellIssueKind::BadObject {
            cell: A,
            object: 10_000
        })
    );
    let mut g = good.clone();
    let box_b = scene
        .objects()
        .iter()
        .position(|o| o.name == "box B")
        .unwrap() as u32;
    g.cells[A].objects.push(box_b);
    let r = g.validate_with_scene(&scene).unwrap();
    let w: Vec<_> = r.warnings().collect();
    assert_eq!(w.len(), 1);
    assert_eq!(
        w[0].kind,
        CellIssueKind::ObjectOutside {
            cell: A,
            object: box_b
        }
    );
    assert!(w[0].message.contains("box B"));
}

/// Wedge cells around the origin: general (not axis-aligned) planes, many cells
/// sharing an edge.
fn wedges(n: usize) -> CellGraph {
    let mut rooms = Vec::new();
    for k in 0..n {
        let a0 = std::f64::consts::TAU * k as f64 / n as f64;
        let a1 = std::f64::consts::TAU * (k + 1) as f64 / n as f64;
        rooms.push(Room {
            name: format!("wedge {k}"),
            polygon: vec![
                DVec2::ZERO,
                DVec2::new(10.0 * a0.cos(), 10.0 * a0.sin()),
                DVec2::new(10.0 * a1.cos(), 10.0 * a1.sin()),
            ],
        });
    }
    FloorPlan::new(rooms, vec![], 3.0).build().unwrap().0
}

#[test]
fn locate_matches_a_linear_scan() {
    let level = demo::level_grid(10);
    let grid = level.cells().unwrap().as_ref().clone();
    assert_eq!(grid.cells.len(), 100);
    let (seed, _) = seed_example();
    let graphs = [grid, wedges(24), seed];
    let mut rng = SplitMix64(77);
    for g in &graphs {
        let shapes: Vec<_> = g
            .cells
            .iter()
            .map(|c| crate::cull::portals::CellShape::new(&c.planes))
            .collect();
        let bounds = shapes
            .iter()
            .map(|s| s.bounds())
            .reduce(|a, b| a.union(b))
            .unwrap();
        let lo = bounds.min - DVec3::splat(0.5);
        let hi = bounds.max + DVec3::splat(0.5);
        // Balanced: depth within a few times log2(n).
        let depth = g.cell_index().depth();
        let log = (g.cells.len() as f64).log2().ceil() as usize;
        assert!(
            depth <= 3 * log + 2,
            "depth {depth} for {} cells",
            g.cells.len()
        );
        let vertices: Vec<DVec3> = shapes.iter().flat_map(|s| s.vertices.clone()).collect();
        let (mut inside, mut outside) = (0, 0);
        for i in 0..4000 {
            let mut p = DVec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            );
            // A third of the points on cell boundaries: a coordinate taken from a
            // cell vertex (shared walls, corners).
            if i % 3 == 0 {
                let v =
                    vertices[(rng.next_f64() * vertices.len() as f64) as usize % vertices.len()];
                match i % 4 {
                    0 => p.x = v.x,
                    1 => p.z = v.z,
                    2 => p.y = v.y,
                    _ => p = v,
                }
            }
            let got = g.locate(p);
            assert_eq!(got, g.locate_linear(p), "at {p}");
            if got.is_some() {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(inside > 1000 && outside > 100, "{inside} {outside}");
    }
    // Far outside: nothing.
    assert_eq!(graphs[0].locate(DVec3::splat(1e6)), None);
    assert_eq!(graphs[0].locate(DVec3::new(f64::NAN, 0.0, 0.0)), None);
}

#[test]
fn demo_levels_are_valid_and_the_walk_stays_in_cells() {
    let level = demo::level();
    let graph = level.cells().unwrap();
    assert_eq!(graph.cells.len(), 35);
    let report = graph.validate_with_scene(&level).unwrap();
    assert_eq!(report.issues, vec![]);
    assert!(level.objects().len() > 60, "{}", level.objects().len());
    // Furniture: each room holds some closed objects.
    let furniture = level.objects().iter().filter(|o| o.closed).count();
    assert!(furniture >= 15, "{furniture}");
    let walk = demo::level_walk();
    assert!(walk.len() >= 60, "{}", walk.len());
    let mut visited = BTreeSet::new();
    for cam in &walk {
        let c = graph.locate(cam.eye);
        assert!(c.is_some(), "eye {} outside every cell", cam.eye);
        visited.insert(c.unwrap());
    }
    assert!(visited.len() >= 8, "{visited:?}");
    let cam = level.camera().unwrap();
    assert!(graph.locate(cam.eye).is_some());
    let grid = demo::level_grid(10);
    let g = grid.cells().unwrap();
    assert_eq!(g.cells.len(), 100);
    assert!(g.validate().is_ok());
    for name in ["level", "cells5", "level-grid"] {
        assert!(demo::NAMES.contains(&name));
        assert!(Scene::demo(name).unwrap().cells().is_some());
    }
}

#[test]
fn walls_have_holes_exactly_where_the_portals_are() {
    let plan = level_plan(5, 5, 3);
    let (graph, scene) = plan.build().unwrap();
    assert_eq!(graph.portals.len(), plan.doors.len());
    let mut rng = SplitMix64(9);
    for (door, portal) in plan.doors.iter().zip(&graph.portals) {
        let [a, b] = door.rooms;
        // The door's wall: its direction, the normal towards room b.
        let dir = (door.b - door.a).normalize();
        let mut n = DVec2::new(-dir.y, dir.x);
        let cb = plan.rooms[b].polygon.iter().copied().sum::<DVec2>() / 4.0;
        if (cb - door.a).dot(n) < 0.0 {
            n = -n;
        }
        let at = |p: DVec2, y: f64| DVec3::new(p.x, y, p.y);
        for _ in 0..20 {
            let t = rng.range(0.02, 0.98);
            let y = rng.range(0.05, door.height - 0.05);
            let m = door.a + (door.b - door.a) * t;
            let (p, q) = (at(m - n * 0.1, y), at(m + n * 0.1, y));
            assert_eq!(graph.locate(p), Some(a as u32));
            assert_eq!(graph.locate(q), Some(b as u32));
            assert!(
                !segment_hits_scene(&scene, p, q, 1e-9),
                "door {door:?} closed at {m}"
            );
            // Above the lintel, and beside the door: wall.
            if door.height < plan.height - 0.1 {
                let y2 = rng.range(door.height + 0.05, plan.height - 0.05);
                assert!(segment_hits_scene(
                    &scene,
                    at(m - n * 0.1, y2),
                    at(m + n * 0.1, y2),
                    1e-9
                ));
            }
        }
        assert_eq!(portal.polygon[0], at(door.a, 0.0));
    }
    // Across every wall two rooms share, at random places: open exactly inside a door
    // of the two rooms, below its lintel (short segments across the wall).
    let rect = |r: &Room| {
        let p = &r.polygon;
        (p[0].x, p[0].y, p[2].x, p[2].y)
    };
    let mut crossings = (0, 0);
    for (i, ra) in plan.rooms.iter().enumerate() {
        for (j, rb) in plan.rooms.iter().enumerate() {
            let (ax0, az0, ax1, az1) = rect(ra);
            let (bx0, bz0, bx1, bz1) = rect(rb);
            // b east of a (wall x = ax1) or north of a (wall z = az1).
            let wall = if ax1 == bx0 && az0.max(bz0) < az1.min(bz1) {
                Some((
                    DVec2::new(ax1, az0.max(bz0)),
                    DVec2::new(ax1, az1.min(bz1)),
                    DVec2::X,
                ))
            } else if az1 == bz0 && ax0.max(bx0) < ax1.min(bx1) {
                Some((
                    DVec2::new(ax0.max(bx0), az1),
                    DVec2::new(ax1.min(bx1), az1),
                    DVec2::Y,
                ))
            } else {
                None
            };
            let Some((w0, w1, n)) = wall else { continue };
            for _ in 0..40 {
                let m = w0 + (w1 - w0) * rng.range(0.0, 1.0);
                let y = rng.range(0.05, plan.height - 0.05);
                let (p, q) = (
                    DVec3::new(m.x - n.x * 0.1, y, m.y - n.y * 0.1),
                    DVec3::new(m.x + n.x * 0.1, y, m.y + n.y * 0.1),
                );
                let mut near_edge = false;
                let in_door = plan.doors.iter().any(|d| {
                    if !(d.rooms.contains(&i) && d.rooms.contains(&j)) {
                        return false;
                    }
                    let len = d.a.distance(d.b);
                    let t = (m - d.a).dot((d.b - d.a) / len);
                    let off = (m - d.a).perp_dot((d.b - d.a) / len).abs();
                    near_edge |= off < 1e-9
                        && (t.abs() < 0.01
                            || (t - len).abs() < 0.01
                            || (y - d.height).abs() < 0.01);
                    off < 1e-9 && t > 0.0 && t < len && y < d.height
                });
                if near_edge {
                    continue;
                }
                let hit = segment_hits_scene(&scene, p, q, 1e-9);
                assert_eq!(!hit, in_door, "rooms {i}, {j} at {m}, y {y}");
                if in_door {
                    crossings.0 += 1;
                } else {
                    crossings.1 += 1;
                }
            }
        }
    }
    assert!(crossings.0 > 20 && crossings.1 > 500, "{crossings:?}");
}

#[test]
fn every_visible_face_lies_in_a_cell_connected_to_the_viewer() {
    // The cells' object lists are conservative: from any eye, what the z-buffer shows
    // belongs to cells reachable through portals from the eye's cell.
    let level = demo::level();
    let graph = level.cells().unwrap().clone();
    let index = SceneIndex::new(&level);
    let vp = Viewport::new(160, 90).unwrap();
    let opts = PrepareOptions::default();
    let walk = demo::level_walk();
    for cam in walk.iter().step_by(4) {
        let start = graph.locate(cam.eye).unwrap() as usize;
        // Cells reachable through portals.
        let mut reach = vec![false; graph.cells.len()];
        let mut stack = vec![start];
        reach[start] = true;
        while let Some(c) = stack.pop() {
            for p in &graph.portals {
                for (x, y) in [(p.cells[0], p.cells[1]), (p.cells[1], p.cells[0])] {
                    if x as usize == c && !reach[y as usize] {
                        reach[y as usize] = true;
                        stack.push(y as usize);
                    }
                }
            }
        }
        let view = View::new(&level, cam, vp, &opts).unwrap();
        let (frame, _) = index
            .render_view(&view, Algorithm::ZBuffer, &RenderOptions::default())
            .unwrap();
        for &id in &frame.ids {
            if id == crate::frame::BACKGROUND {
                continue;
            }
            let (obj, _) = level.locate_face(id).unwrap();
            let ok = graph
                .cells
                .iter()
                .enumerate()
                .any(|(c, cell)| reach[c] && cell.objects.contains(&(obj as u32)));
            assert!(
                ok,
                "object {} seen from {} is in no reachable cell",
                level.objects()[obj].name,
                cam.eye
            );
        }
    }
}

#[test]
fn prt1_round_trip_and_errors() {
    let (graph, _) = seed_example();
    let text = write_prt(&graph);
    let path = Path::new("seed.prt");
    let g = parse_prt(&text, path).unwrap();
    assert_eq!(g.cells.len(), 5);
    // Each leaf is the hull of its portals: the seed's cells have one or two portals,
    // on different walls for D, E, C (a volume) and alone for A and B (flat).
    assert!(g.cells.iter().all(|c| c.objects.is_empty()));
    let flat: Vec<bool> = g.cells.iter().map(|c| c.planes.is_empty()).collect();
    assert_eq!(flat, [true, true, false, false, false]);
    assert_eq!(g.portals, graph.portals);
    // Between DE (z = 2, x in [1, 2]) and EC (z = 0, x in [9, 10]), inside E's hull.
    assert_eq!(g.locate(DVec3::new(6.0, 1.0, 1.0)), Some(E as u32));
    // In A, away from its only portal: no geometry there, no cell.
    assert_eq!(g.locate(DVec3::new(-2.0, 1.0, 4.0)), None);
    let r = g.diagnose(None);
    assert!(r.is_valid());
    assert_eq!(r.warnings().count(), 2);
    // Quake III: a faces count line, a hint flag, and solid faces.
    let q3 = "PRT1\n3\n2\n1\n4 0 1 0 (0 0 0) (0 1 0) (0 1 1) (0 0 1)\n\
              3 1 2 1 (1 0 0) (1 1 0) (1 0 1)\n3 2 (5 5 5) (6 5 5) (5 6 5)\n";
    let g = parse_prt(q3, path).unwrap();
    assert_eq!(g.portals.len(), 2);
    assert_eq!(g.portals[1].cells, [1, 2]);
    assert_eq!(g.portals[0].polygon[2], DVec3::new(0.0, 1.0, 1.0));
    // Errors: each names the file and the line.
    let cases: [(&str, usize, &str); 9] = [
        ("PRT2\n1\n0\n", 1, "only the PRT1"),
        ("", 1, "empty"),
        ("PRT1\nx\n0\n", 2, "number of leafs"),
        (
            "PRT1\n2\n3\n3 0 1 (0 0 0) (1 0 0) (0 1 0)\n",
            4,
            "announces 3 portals",
        ),
        ("PRT1\n2\n1\n3 0 1 (0 0 0) (1 NaN 0) (0 1 0)\n", 4, "finite"),
        (
            "PRT1\n2\n1\n3 0 5 (0 0 0) (1 0 0) (0 1 0)\n",
            4,
            "out of range",
        ),
        (
            "PRT1\n2\n1\n4 0 1 (0 0 0) (1 0 0) (0 1 0)\n",
            4,
            "4 points announced",
        ),
        ("PRT1\n99999999999999\n1\n", 2, "more than the file"),
        ("PRT1\n2\n1\n3 0 1 (0 0 0) (1 0 0) (0 1\n", 4, "closing"),
    ];
    for (text, line, what) in cases {
        match parse_prt(text, path) {
            Err(Error::Parse {
                path: p,
                line: l,
                message,
            }) => {
                assert_eq!(p, path);
                assert_eq!(l, line, "{text:?}: {message}");
                assert!(message.contains(what), "{text:?}: {message}");
            }
            other => panic!("{text:?}: {other:?}"),
        }
    }
    // A billion portals announced: an error, nothing allocated for them.
    assert!(parse_prt("PRT1\n2\n1000000000\n", path).is_err());
    assert!(parse_prt("PRT1\n2\n18446744073709551616\n", path).is_err());
    // A file on disk.
    let dir = std::env::temp_dir().join(format!("obscura-prt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("seed.prt");
    std::fs::write(&file, &text).unwrap();
    assert_eq!(
        crate::cull::portals::prt::read_prt(&file)
            .unwrap()
            .portals
            .len(),
        4
    );
    std::fs::remove_dir_all(&dir).ok();
    assert!(matches!(
        crate::cull::portals::prt::read_prt(dir.join("missing.prt")),
        Err(Error::Io { .. })
    ));
}

#[test]
fn bad_floor_plans_are_refused_by_name() {
    let concave = Room {
        name: "L".into(),
        polygon: vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 2.0),
            DVec2::new(0.0, 2.0),
        ],
    };
    let e = FloorPlan::new(vec![concave], vec![], 3.0)
        .build()
        .unwrap_err();
    assert!(
        e.to_string().contains("room \"L\"") && e.to_string().contains("convex"),
        "{e}"
    );
    let rooms = vec![
        Room::rect("a", 0., 0., 1., 1.),
        Room::rect("b", 1., 0., 2., 1.),
    ];
    let door = Door {
        rooms: [0, 7],
        a: DVec2::new(1.0, 0.2),
        b: DVec2::new(1.0, 0.8),
        height: 2.0,
    };
    let e = FloorPlan::new(rooms.clone(), vec![door.clone()], 3.0)
        .build()
        .unwrap_err();
    assert!(e.to_string().contains("door 0"), "{e}");
    let tall = Door {
        rooms: [0, 1],
        height: 4.0,
        ..door
    };
    assert!(
        FloorPlan::new(rooms.clone(), vec![tall], 3.0)
            .build()
            .is_err()
    );
    assert!(FloorPlan::new(rooms, vec![], f64::NAN).build().is_err());
    // A hand-made graph with a cell of no planes and a portal: validate says so.
    let g = CellGraph::new(
        vec![
            Cell {
                name: "x".into(),
                planes: vec![],
                objects: vec![],
            };
            2
        ],
        vec![Portal {
            cells: [0, 1],
            polygon: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
        }],
    );
    assert!(g.validate().is_ok());
    let _ = Camera::perspective(DVec3::ZERO, DVec3::X, DVec3::Y, 60.0, 0.1, 10.0);
    let _ = plan_walk(&level_plan(2, 2, 1), 3, 2);
}

/// A scene file with cells of the three kinds (box, floor polygon, planes), portals,
/// and objects assigned by name or by their bounds.
#[cfg(feature = "toml-scene")]
const TOML_CELLS: &str = r#"
[camera]
eye = [1, 1.5, 1]
target = [5, 1.5, 1]

[[object]]
name = "crate"
primitive = "box"
size = [0.5, 0.5, 0.5]
translate = [1, 0.25, 1]

[[object]]
name = "barrel"
primitive = "box"
size = [0.5, 0.5, 0.5]
translate = [5, 0.25, 1]
cells = ["east", "north"]

[[cell]]
name = "west"
min = [0, 0, 0]
max = [2, 3, 2]

[[cell]]
name = "east"
floor = [[2, 0], [6, 0], [6, 2], [2, 2]]
height = 3

[[cell]]
name = "north"
planes = [[1, 0, 0, -2], [-1, 0, 0, 0], [0, 1, 0, -3], [0, -1, 0, 0], [0, 0, 1, -4], [0, 0, -1, 2]]

[[portal]]
cells = ["west", "east"]
polygon = [[2, 0, 0], [2, 0, 2], [2, 3, 2], [2, 3, 0]]

[[portal]]
cells = ["north", "west"]
polygon = [[0, 0, 2], [2, 0, 2], [2, 3, 2], [0, 3, 2]]
"#;

#[cfg(feature = "toml-scene")]
fn load_toml(name: &str, text: &str) -> crate::Result<Scene> {
    let dir = std::env::temp_dir().join(format!("obscura-cells-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.toml");
    std::fs::write(&file, text).unwrap();
    let r = Scene::load(&file);
    std::fs::remove_dir_all(&dir).ok();
    r
}

/// The 1-based line of the first occurrence of `needle` in `text`.
#[cfg(feature = "toml-scene")]
fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).unwrap()].matches('\n').count() + 1
}

#[test]
#[cfg(feature = "toml-scene")]
fn scene_files_describe_cells_and_portals() {
    let scene = load_toml("ok", TOML_CELLS).unwrap();
    let g = scene.cells().unwrap();
    let names: Vec<&str> = g.cells.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["west", "east", "north"]);
    assert_eq!(g.portals.len(), 2);
    assert_eq!(g.portals[1].cells, [2, 0]);
    // The three kinds describe the boxes they should: a point of each.
    assert_eq!(g.locate(DVec3::new(1.0, 1.0, 1.0)), Some(0));
    assert_eq!(g.locate(DVec3::new(4.0, 1.0, 1.0)), Some(1));
    assert_eq!(g.locate(DVec3::new(1.0, 1.0, 3.0)), Some(2));
    assert_eq!(g.locate(DVec3::new(4.0, 1.0, 3.0)), None);
    assert_eq!(g.locate(DVec3::new(4.0, 3.5, 1.0)), None);
    // "crate" by its bounds (in west only), "barrel" where its table says.
    assert_eq!(g.cells[0].objects, vec![0]);
    assert_eq!(g.cells[1].objects, vec![1]);
    assert_eq!(g.cells[2].objects, vec![1]);
    // "barrel" lies outside "north": a warning in the scene's report.
    assert!(
        scene
            .report()
            .messages
            .iter()
            .any(|m| m.contains("barrel") && m.contains("north"))
    );

    // Errors, each at its line.
    let cases: Vec<(String, &str, &str)> = vec![
        // The portal west-east shrunk: the rest of the shared face leaks.
        (
            TOML_CELLS.replace(
                "[2, 0, 0], [2, 0, 2], [2, 3, 2], [2, 3, 0]",
                "[2, 0, 0], [2, 0, 1], [2, 3, 1], [2, 3, 0]",
            ),
            "name = \"west\"",
            "leak",
        ),
        // A portal off the boundary.
        (
            TOML_CELLS.replace(
                "[2, 0, 0], [2, 0, 2], [2, 3, 2], [2, 3, 0]",
                "[2.5, 0, 0], [2.5, 0, 2], [2.5, 3, 2], [2.5, 3, 0]",
            ),
            "cells = [\"west\", \"east\"]",
            "boundary",
        ),
        (
            TOML_CELLS.replace("cells = [\"east\", \"north\"]", "cells = [\"attic\"]"),
            "cells = [\"attic\"]",
            "attic",
        ),
        (
            TOML_CELLS.replace("name = \"north\"", "name = \"west\""),
            "name = \"west\"\nplanes",
            "second cell",
        ),
        (
            TOML_CELLS.replace(
                "[[2, 0], [6, 0], [6, 2], [2, 2]]",
                "[[2, 0], [6, 0], [4, 1], [6, 2], [2, 2]]",
            ),
            "floor =",
            "convex",
        ),
        // An open cell: north without its plane z <= 4.
        (
            TOML_CELLS.replace(", [0, 0, 1, -4]", ""),
            "name = \"north\"",
            "open",
        ),
        (
            TOML_CELLS.replace("height = 3\n", ""),
            "name = \"east\"",
            "height",
        ),
    ];
    for (text, at, what) in &cases {
        let e = load_toml("bad", text).unwrap_err();
        let line = line_of(text, at);
        match &e {
            Error::Parse {
                line: l, message, ..
            } => {
                assert!(message.contains(what), "{what}: {message}");
                assert!(
                    *l == line || *l + 1 == line || *l == line + 1,
                    "{what}: line {l}, expected about {line}: {message}"
                );
            }
            other => panic!("{what}: {other:?}"),
        }
    }
    // Cells named without [[cell]] tables, and portals without cells.
    let no_cells = "[[object]]\nprimitive = \"box\"\ncells = [\"a\"]\n";
    assert!(
        load_toml("nc", no_cells)
            .unwrap_err()
            .to_string()
            .contains("no [[cell]]")
    );
}
