//! PRT1 import with cell geometry (issue 24, "import of PRT1 so real level data can be
//! used"): each leaf's cell is the convex hull of its portals. A floor-plan level
//! exported to PRT1 and read back locates the viewer where the original cells do
//! (wherever a hull holds it), and portal culling with the imported cells leaves every
//! picture as it was; flat hulls (one portal, coplanar portals) give cells that never
//! hold the viewer; a viewer in no hull, or near its hull's boundary, is not
//! portal-culled, and a note says so.

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;

use super::cull::same_picture;
use crate::SceneIndex;
use crate::cull::occlusion::{CullMethod, CullOptions, CullReason};
use crate::cull::portals::floorplan::level_plan;
use crate::cull::portals::prt::{
    assign_objects_inside, flat_leaves, hull_planes, parse_prt, write_prt,
};
use crate::cull::portals::{CellGraph, CellIssueKind};
use crate::geom::Plane;
use crate::rng::SplitMix64;
use crate::scene::{Camera, Scene, Viewport};

fn inside(planes: &[Plane], p: DVec3, eps: f64) -> bool {
    planes.iter().all(|pl| pl.signed_distance(p) <= eps)
}

#[test]
fn hull_planes_of_simple_point_sets() {
    // A unit cube's corners, an interior point and repeated corners: its six faces.
    let mut pts: Vec<DVec3> = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    pts.push(DVec3::splat(0.5));
    pts.extend(pts.clone());
    let planes = hull_planes(&pts).unwrap();
    assert_eq!(planes.len(), 6, "{planes:?}");
    for pl in &planes {
        assert!((pl.normal.length() - 1.0).abs() < 1e-12);
        // Axis-aligned, through 0 or 1.
        let axis = pl.normal.abs().max_element();
        assert!((axis - 1.0).abs() < 1e-12, "{pl:?}");
        assert!(pl.d.abs() < 1e-12 || (pl.d + 1.0).abs() < 1e-12, "{pl:?}");
    }
    assert!(inside(&planes, DVec3::splat(0.5), -0.49));
    assert!(!inside(&planes, DVec3::new(1.01, 0.5, 0.5), 1e-9));
    // Every point on or inside.
    assert!(pts.iter().all(|&p| inside(&planes, p, 0.0)));
    // A square pyramid with its apex: five planes, the square's four coplanar corners
    // merged into one.
    let pyr = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 2.0),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, 0.0, 1.0),
    ];
    assert_eq!(hull_planes(&pyr).unwrap().len(), 5);
    // Flat and degenerate sets: no volume.
    let square = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.5, 0.5, 0.0),
    ];
    assert_eq!(hull_planes(&square), None);
    let line: Vec<DVec3> = (0..6).map(|i| DVec3::splat(f64::from(i))).collect();
    assert_eq!(hull_planes(&line), None);
    assert_eq!(hull_planes(&square[..3]), None);
    assert_eq!(hull_planes(&[DVec3::ONE; 5]), None);
    let mut nan = pts.clone();
    nan.push(DVec3::new(f64::NAN, 0.0, 0.0));
    assert_eq!(hull_planes(&nan), None);
}

/// Random points against the brute-force hull: a point is inside the hull exactly when
/// no plane through three of the points separates it from them all.
#[test]
fn hull_planes_agree_with_brute_force() {
    let mut rng = SplitMix64(7);
    for _ in 0..20 {
        let n = 4 + (rng.next_u64() % 12) as usize;
        let pts: Vec<DVec3> = (0..n)
            .map(|_| {
                DVec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-1.0, 1.0),
                    rng.range(0.0, 3.0),
                )
            })
            .collect();
        let planes = hull_planes(&pts).unwrap();
        assert!(pts.iter().all(|&p| inside(&planes, p, 1e-12)));
        // Brute force: supporting planes of triples.
        let mut brute = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                for c in b + 1..n {
                    let nrm = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
                    if nrm.length() < 1e-9 {
                        continue;
                    }
                    let nrm = nrm.normalize();
                    let ds: Vec<f64> = pts.iter().map(|&p| nrm.dot(p - pts[a])).collect();
                    if ds.iter().all(|&d| d <= 1e-12) {
                        brute.push(Plane::from_point_normal(pts[a], nrm));
                    } else if ds.iter().all(|&d| d >= -1e-12) {
                        brute.push(Plane::from_point_normal(pts[a], -nrm));
                    }
                }
            }
        }
        for _ in 0..200 {
            let q = DVec3::new(
                rng.range(-2.5, 2.5),
                rng.range(-1.5, 1.5),
                rng.range(-0.5, 3.5),
            );
            let margin = brute
                .iter()
                .map(|pl| pl.signed_distance(q))
                .fold(f64::MIN, f64::max);
            if margin.abs() < 1e-6 {
                continue;
            }
            assert_eq!(inside(&planes, q, 0.0), margin < 0.0, "{q}");
        }
    }
}

/// The leaves' portal vertices.
fn leaf_points(graph: &CellGraph, c: usize) -> Vec<DVec3> {
    graph
        .portals
        .iter()
        .filter(|p| p.cells.contains(&(c as u32)))
        .flat_map(|p| p.polygon.iter().copied())
        .collect()
}

/// Whether points lie in one plane (within `eps`), found by brute force.
fn coplanar(pts: &[DVec3], eps: f64) -> bool {
    let n = pts.len();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                let nrm = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
                if nrm.length() > 1e-6 {
                    let nrm = nrm.normalize();
                    return pts.iter().all(|&p| nrm.dot(p - pts[a]).abs() <= eps);
                }
            }
        }
    }
    true
}

#[test]
fn floor_plan_exported_to_prt1_locates_where_the_cells_do() {
    let (graph, _) = level_plan(4, 4, 3).build().unwrap();
    let g = parse_prt(&write_prt(&graph), Path::new("level.prt")).unwrap();
    assert!(g.partial_cells);
    assert_eq!(g.cells.len(), graph.cells.len());
    let mut rng = SplitMix64(5);
    let mut volumes = 0;
    for c in 0..g.cells.len() {
        let pts = leaf_points(&g, c);
        if g.cells[c].planes.is_empty() {
            // Flat: one portal or coplanar portals.
            assert!(coplanar(&pts, 1e-9), "leaf {c} has volume but no planes");
            assert!(flat_leaves(&g).contains(&(c as u32)));
            continue;
        }
        volumes += 1;
        assert!(!coplanar(&pts, 1e-6));
        // Random points strictly inside the hull: positive combinations of its vertices.
        for _ in 0..30 {
            let w: Vec<f64> = pts.iter().map(|_| rng.range(0.1, 1.0)).collect();
            let s: f64 = w.iter().sum();
            let p = pts.iter().zip(&w).map(|(&p, &w)| p * w).sum::<DVec3>() / s;
            assert_eq!(g.locate(p), Some(c as u32), "{p}");
            assert_eq!(graph.locate(p), Some(c as u32), "{p}");
        }
    }
    assert!(
        volumes * 2 > g.cells.len(),
        "{volumes} of {}",
        g.cells.len()
    );
    // Anywhere in the level: where a hull holds the point, the original cell does.
    let b = graph
        .cells
        .iter()
        .map(|c| crate::cull::portals::CellShape::new(&c.planes).bounds())
        .fold(crate::geom::Aabb::EMPTY, |a, b| a.union(b));
    let (mut located, mut samples) = (0, 0);
    while samples < 3000 {
        let p = DVec3::new(
            rng.range(b.min.x, b.max.x),
            rng.range(b.min.y, b.max.y),
            rng.range(b.min.z, b.max.z),
        );
        samples += 1;
        if let Some(c) = g.locate(p) {
            located += 1;
            assert!(
                inside(&graph.cells[c as usize].planes, p, 1e-9),
                "{p} in the hull of leaf {c}, outside its cell"
            );
        }
    }
    assert!(located > samples / 10, "{located} of {samples}");
    // The diagnosis warns of each flat leaf, and finds no error.
    let r = g.diagnose(None);
    assert!(r.is_valid(), "{:?}", r.errors().collect::<Vec<_>>());
    let no_geometry = r
        .warnings()
        .filter(|i| matches!(i.kind, CellIssueKind::NoGeometry { .. }))
        .count();
    assert_eq!(no_geometry, flat_leaves(&g).len());
}

#[test]
fn portal_culling_with_imported_cells_keeps_every_picture() {
    let (graph, mut scene) = level_plan(3, 3, 8).build().unwrap();
    let mut g = parse_prt(&write_prt(&graph), Path::new("level.prt")).unwrap();
    // A small box at the middle of each hull (in that leaf only), in the level's cells too.
    let mut graph = graph;
    for c in 0..g.cells.len() {
        if g.cells[c].planes.is_empty() {
            continue;
        }
        let pts = leaf_points(&g, c);
        let m = pts.iter().sum::<DVec3>() / pts.len() as f64;
        let k = scene
            .add(crate::scene::ObjectDesc::new(
                format!("crate {c}"),
                crate::scene::demo::box_mesh(m - DVec3::splat(0.1), m + DVec3::splat(0.1)),
            ))
            .unwrap();
        graph.cells[c].objects.push(k as u32);
    }
    // Two object assignments: the level's own (as a geometry file beside the PRT1 file
    // would give), and the conservative one from the hulls alone.
    let mut by_hull = g.clone();
    assign_objects_inside(&mut by_hull, &scene);
    for (c, cell) in g.cells.iter_mut().enumerate() {
        cell.objects.clone_from(&graph.cells[c].objects);
    }
    let mut rng = SplitMix64(13);
    let b = scene.bounds();
    let mut cameras = Vec::new();
    while cameras.len() < 24 {
        let eye = DVec3::new(
            rng.range(b.min.x, b.max.x),
            rng.range(0.2, 2.0),
            rng.range(b.min.z, b.max.z),
        );
        if g.locate(eye).is_none() {
            continue;
        }
        let a = rng.range(0.0, std::f64::consts::TAU);
        let dir = DVec3::new(a.cos(), rng.range(-0.3, 0.3), a.sin());
        cameras.push(Camera::perspective(
            eye,
            eye + dir,
            DVec3::Y,
            rng.range(50.0, 90.0),
            0.05,
            200.0,
        ));
    }
    for (name, cells) in [("level's objects", g), ("objects inside hulls", by_hull)] {
        scene.set_cells(Some(Arc::new(cells)));
        let index = SceneIndex::new(&scene);
        for method in [CullMethod::Portals, CullMethod::ScreenPortals] {
            let options = CullOptions::with_method(method);
            let mut by_portal = 0;
            let mut fallbacks = 0;
            for cam in &cameras {
                let c = same_picture(&scene, &index, cam, &options);
                by_portal += c
                    .objects
                    .iter()
                    .filter(|r| **r == Some(CullReason::Portal))
                    .count();
                fallbacks += usize::from(!c.notes.is_empty());
            }
            println!(
                "{name}, {method:?}: {by_portal} objects culled by portals, {fallbacks} views not portal-culled"
            );
            assert!(by_portal > 0, "{name} {method:?}");
            assert!(fallbacks < cameras.len() / 2);
        }
    }
}

#[test]
fn flat_leaves_and_viewers_outside_the_hulls_are_said() {
    let path = Path::new("t.prt");
    // One portal: both leaves flat. Two coplanar portals of leaf 0: flat too; leaf 1
    // and leaf 2 each have one portal.
    let one = "PRT1\n2\n1\n4 0 1 (0 0 0) (0 1 0) (0 1 1) (0 0 1)\n";
    let g = parse_prt(one, path).unwrap();
    assert_eq!(flat_leaves(&g), vec![0, 1]);
    assert_eq!(g.locate(DVec3::new(0.0, 0.5, 0.5)), None);
    let coplanar = "PRT1\n3\n2\n4 0 1 (0 0 0) (0 1 0) (0 1 1) (0 0 1)\n\
                    4 0 2 (0 0 2) (0 1 2) (0 1 3) (0 0 3)\n";
    assert_eq!(
        flat_leaves(&parse_prt(coplanar, path).unwrap()),
        vec![0, 1, 2]
    );
    // Two walls of a room: leaf 0 between x = 0 and x = 4 has a volume.
    let room = "PRT1\n3\n2\n4 0 1 (0 0 0) (0 2 0) (0 2 2) (0 0 2)\n\
                4 0 2 (4 0 0) (4 2 0) (4 2 2) (4 0 2)\n";
    let g = parse_prt(room, path).unwrap();
    assert_eq!(flat_leaves(&g), vec![1, 2]);
    assert_eq!(g.cells[0].planes.len(), 6);
    assert_eq!(g.locate(DVec3::new(2.0, 1.0, 1.0)), Some(0));
    assert_eq!(g.locate(DVec3::new(2.0, 1.0, 3.0)), None);
    // A scene: a box in leaf 0, one beyond each portal.
    let mut scene = Scene::new();
    for (name, x) in [("in", 2.0), ("west", -2.0), ("east", 6.0)] {
        scene
            .add(crate::scene::ObjectDesc::new(
                name,
                crate::scene::demo::box_mesh(
                    DVec3::new(x - 0.2, 0.5, 0.8),
                    DVec3::new(x + 0.2, 0.9, 1.2),
                ),
            ))
            .unwrap();
    }
    let mut g2 = g.clone();
    assign_objects_inside(&mut g2, &scene);
    assert_eq!(g2.cells[0].objects, vec![0]);
    assert!(g2.cells[1].objects.is_empty() && g2.cells[2].objects.is_empty());
    scene.set_cells(Some(Arc::new(g2)));
    let index = SceneIndex::new(&scene);
    let vp = Viewport::new(64, 36).unwrap();
    let options = CullOptions::with_method(CullMethod::Portals);
    let cull_from = |eye: DVec3, target: DVec3| {
        let cam = Camera::perspective(eye, target, DVec3::Y, 60.0, 0.05, 100.0);
        index.cull(&cam, vp, &options).unwrap()
    };
    // Outside every hull.
    let c = cull_from(DVec3::new(2.0, 1.0, 3.0), DVec3::new(2.0, 1.0, 0.0));
    assert!(
        c.notes.iter().any(|n| n.contains("outside every cell")),
        "{:?}",
        c.notes
    );
    assert!(
        c.objects
            .iter()
            .all(|r| r.is_none_or(|r| r == CullReason::Frustum))
    );
    // Inside, near the hull's boundary (the top at y = 2).
    let c = cull_from(DVec3::new(2.0, 1.99, 1.0), DVec3::new(2.0, 1.99, 0.0));
    assert!(
        c.notes.iter().any(|n| n.contains("portals' hull")),
        "{:?}",
        c.notes
    );
    // Inside: located, no note; looking at the "in" box culls nothing it sees.
    let c = cull_from(DVec3::new(1.0, 1.0, 1.0), DVec3::new(2.0, 0.7, 1.0));
    assert!(c.notes.is_empty(), "{:?}", c.notes);
    assert_eq!(c.objects[0], None);
}

#[test]
#[cfg(feature = "toml-scene")]
fn scene_files_take_a_prt1_file_for_their_cells() {
    use crate::Error;
    let dir = std::env::temp_dir().join(format!("obscura-prt-toml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let room = "PRT1\n3\n2\n4 0 1 (0 0 0) (0 2 0) (0 2 2) (0 0 2)\n\
                4 0 2 (4 0 0) (4 2 0) (4 2 2) (4 0 2)\n";
    std::fs::write(dir.join("room.prt"), room).unwrap();
    std::fs::write(
        dir.join("bad.prt"),
        "PRT1\n2\n1\n3 0 9 (0 0 0) (1 0 0) (0 1 0)\n",
    )
    .unwrap();
    let load = |text: &str| {
        let file = dir.join("scene.toml");
        std::fs::write(&file, text).unwrap();
        Scene::load(&file)
    };
    let objects = "[[object]]\nname = \"in\"\nprimitive = \"box\"\nsize = [0.4, 0.4, 0.4]\n\
                   translate = [2, 1, 1]\n\n[[object]]\nname = \"out\"\nprimitive = \"box\"\n\
                   translate = [-2, 1, 1]\n";
    let s = load(&format!("prt = \"room.prt\"\n\n{objects}")).unwrap();
    let g = s.cells().unwrap();
    assert!(g.partial_cells);
    assert_eq!(g.cells.len(), 3);
    assert_eq!(g.cells[0].objects, vec![0]);
    assert_eq!(g.locate(DVec3::new(2.0, 1.5, 1.0)), Some(0));
    // Errors: with [[cell]] tables (at the table's line); a bad PRT1 file (its own
    // name and line); a missing one.
    let both = format!(
        "prt = \"room.prt\"\n{objects}\n[[cell]]\nname = \"a\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n"
    );
    match load(&both) {
        Err(Error::Parse { line, message, .. }) => {
            assert_eq!(
                line,
                both[..both.find("[[cell]]").unwrap()].matches('\n').count() + 1
            );
            assert!(message.contains("not both"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    match load(&format!("prt = \"bad.prt\"\n{objects}")) {
        Err(Error::Parse {
            path,
            line,
            message,
        }) => {
            assert!(path.ends_with("bad.prt"), "{path:?}");
            assert_eq!(line, 4);
            assert!(message.contains("out of range"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        load(&format!("prt = \"missing.prt\"\n{objects}")),
        Err(Error::Io { .. })
    ));
    std::fs::remove_dir_all(&dir).ok();
}
