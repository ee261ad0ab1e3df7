//! The octree against brute force: voxelization cell by cell, booleans cell by cell,
//! neighbours by index arithmetic, ray order by sorting entry parameters, and the
//! rendered image against the analytic picture and the z-buffer.

use std::collections::HashMap;

use crate::accel::octree::{
    BooleanOp, Cell, Direction, Leaf, NodeKind, Octree, Region, TriangleSoup, front_to_back_order,
    triangle_box_overlap,
};
use crate::frame::BACKGROUND;
use crate::scene::{Camera, ObjectDesc, Scene, Viewport, demo};
use crate::surface::{Algorithm, RenderOptions, render};
use crate::{PrepareOptions, prepare};
use glam::{DMat4, DVec3};

// ---------------------------------------------------------------------------------
// Brute force

/// One object's world triangles with face ids, computed here from the scene (the same
/// arithmetic as the library, so the same bits) and its closed flag.
struct BruteObject {
    triangles: Vec<([DVec3; 3], u32)>,
    closed: bool,
}

fn brute_objects(scene: &Scene) -> Vec<BruteObject> {
    scene
        .objects()
        .iter()
        .map(|o| {
            let mut triangles = Vec::new();
            for p in 0..o.mesh.polygon_count() {
                let w = o.world_polygon(p);
                let face = o.first_face + o.mesh.polygon_face(p);
                for k in 1..w.len() - 1 {
                    triangles.push(([w[0], w[k], w[k + 1]], face));
                }
            }
            BruteObject {
                triangles,
                closed: o.closed,
            }
        })
        .collect()
}

/// Möller-Trumbore: the ray parameter of a hit, if any.
fn ray_triangle(o: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = o - t[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

/// Point in a closed object by ray parity, majority of three rays in unrelated
/// directions (a ray grazing an edge or vertex may miscount; two of three will not).
fn inside_by_parity(p: DVec3, obj: &BruteObject) -> bool {
    let dirs = [
        DVec3::new(0.5724, 0.3181, 0.7548),
        DVec3::new(-0.2861, 0.8911, -0.3523),
        DVec3::new(0.6637, -0.5150, -0.5425),
    ];
    let votes = dirs
        .iter()
        .filter(|&&d| {
            obj.triangles
                .iter()
                .filter(|(t, _)| ray_triangle(p, d, t).is_some())
                .count()
                % 2
                == 1
        })
        .count();
    votes >= 2
}

/// Distance from a point to a triangle: to the plane when the foot is inside, else to
/// the nearest edge segment (a formulation independent of the library's).
fn point_triangle_distance(p: DVec3, t: &[DVec3; 3]) -> f64 {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n.length_squared() > 0.0 {
        let foot = p - n * ((p - t[0]).dot(n) / n.length_squared());
        let inside = (0..3).all(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            (b - a).cross(foot - a).dot(n) >= 0.0
        });
        if inside {
            return (p - foot).length();
        }
    }
    (0..3)
        .map(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let ab = b - a;
            let s = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            (p - (a + ab * s)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// What the brute force knows of one voxel: its kind and, for a partial one, the
/// faces of the triangles meeting it with their distances to the centre.
#[derive(Clone, Debug)]
struct BruteVoxel {
    kind: NodeKind,
    faces: Vec<(f64, u32)>,
}

struct Grid {
    n: u32,
    voxels: Vec<BruteVoxel>,
}

impl Grid {
    fn at(&self, x: u32, y: u32, z: u32) -> &BruteVoxel {
        &self.voxels[(x + self.n * (y + self.n * z)) as usize]
    }
}

/// Every voxel classified on its own: Partial if a triangle meets it, else Full if its
/// centre is inside a closed object by ray parity, else Empty.
fn brute_voxelize(scene: &Scene, region: &Region, depth: u32) -> Grid {
    let objects = brute_objects(scene);
    let n = 1u32 << depth;
    let mut voxels = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let b = region.cell_box(Cell {
                    level: depth,
                    x,
                    y,
                    z,
                });
                let centre = b.center();
                let faces: Vec<(f64, u32)> = objects
                    .iter()
                    .flat_map(|o| o.triangles.iter())
                    .filter(|(t, _)| triangle_box_overlap(t, b.min, b.max))
                    .map(|(t, f)| (point_triangle_distance(centre, t), *f))
                    .collect();
                let kind = if !faces.is_empty() {
                    NodeKind::Partial
                } else if objects
                    .iter()
                    .any(|o| o.closed && inside_by_parity(centre, o))
                {
                    NodeKind::Full
                } else {
                    NodeKind::Empty
                };
                voxels.push(BruteVoxel { kind, faces });
            }
        }
    }
    Grid { n, voxels }
}

/// The number of nodes of the smallest octree of a grid of kinds (8 equal Full or
/// Empty children merge; Partial never does), and the kind of a uniform subtree.
fn minimal_nodes(kind: &dyn Fn(u32, u32, u32) -> NodeKind, depth: u32) -> usize {
    fn rec(
        kind: &dyn Fn(u32, u32, u32) -> NodeKind,
        level: u32,
        depth: u32,
        x: u32,
        y: u32,
        z: u32,
    ) -> (usize, Option<NodeKind>) {
        if level == depth {
            let k = kind(x, y, z);
            return (1, (k != NodeKind::Partial).then_some(k));
        }
        let mut total = 0;
        let mut kinds = Vec::new();
        for o in 0..8 {
            let (n, k) = rec(
                kind,
                level + 1,
                depth,
                2 * x + (o & 1),
                2 * y + ((o >> 1) & 1),
                2 * z + ((o >> 2) & 1),
            );
            total += n;
            kinds.push(k);
        }
        if kinds[0].is_some() && kinds.iter().all(|&k| k == kinds[0]) {
            (1, kinds[0])
        } else {
            (1 + total, None)
        }
    }
    rec(kind, 0, depth, 0, 0, 0).0
}

/// Checks a tree against a brute-force grid, voxel by voxel; the face of a partial
/// voxel must be one of the faces meeting it, at the least distance (within rounding).
fn assert_matches_grid(tree: &Octree, grid: &Grid, what: &str) {
    let n = grid.n;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let want = grid.at(x, y, z);
                let got = tree.voxel(x, y, z).unwrap();
                assert_eq!(got.kind(), want.kind, "{what}: voxel ({x}, {y}, {z})");
                if let Leaf::Partial { face } = got {
                    let best = want.faces.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
                    let mine = want
                        .faces
                        .iter()
                        .filter(|f| f.1 == face)
                        .map(|f| f.0)
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        mine <= best + 1e-9,
                        "{what}: voxel ({x}, {y}, {z}) face {face} at {mine}, nearest {best}"
                    );
                }
            }
        }
    }
    let minimal = minimal_nodes(&|x, y, z| grid.at(x, y, z).kind, tree.depth());
    assert_eq!(tree.node_count(), minimal, "{what}: not the smallest tree");
}

// ---------------------------------------------------------------------------------
// Shapes

fn one_object(mesh: crate::scene::Mesh, transform: DMat4) -> Scene {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("solid", mesh).with_transform(transform))
        .unwrap();
    assert!(s.objects()[0].closed);
    s
}

/// The shape called `name` in [`shapes`].
fn shape(name: &str) -> Scene {
    shapes()
        .into_iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no shape {name}"))
        .1
}

fn shapes() -> Vec<(&'static str, Scene)> {
    vec![
        (
            "cube",
            one_object(
                demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)),
                DMat4::IDENTITY,
            ),
        ),
        (
            "sphere",
            one_object(demo::uv_sphere_mesh(1.0, 16, 8), DMat4::IDENTITY),
        ),
        (
            "torus",
            one_object(
                demo::torus_mesh(1.0, 0.4, 16, 8),
                DMat4::from_rotation_x(0.4) * DMat4::from_rotation_z(0.3),
            ),
        ),
        (
            "rotated box",
            one_object(
                demo::box_mesh(DVec3::new(-0.6, -0.3, -0.2), DVec3::new(0.6, 0.3, 0.2)),
                DMat4::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
            ),
        ),
    ]
}

fn region_of(scene: &Scene) -> Region {
    Region::enclosing(&scene.bounds()).unwrap()
}

// ---------------------------------------------------------------------------------
// Voxelization

#[test]
fn voxelization_equals_brute_force() {
    for (name, scene) in shapes() {
        let region = region_of(&scene);
        let soup = TriangleSoup::from_scene(&scene);
        for depth in 3..=5 {
            let tree = Octree::build(&soup, region, depth).unwrap();
            let grid = brute_voxelize(&scene, &region, depth);
            assert_matches_grid(&tree, &grid, &format!("{name} at depth {depth}"));
            let c = tree.leaf_counts();
            assert!(c.partial > 0, "{name} {depth}");
            if depth >= 4 {
                assert!(c.full > 0, "{name} at depth {depth} has no inside");
            }
        }
    }
}

#[test]
fn a_box_through_voxel_centres_merges_its_core() {
    // Region [0, 8]^3 at depth 3: unit voxels. The box [0.5, 7.5]^3 passes through the
    // middle of the outer voxel layer, so the 296 voxels with a coordinate 0 or 7 are
    // Partial and the 6^3 = 216 others Full. The core [2, 6]^3 is 8 Full cells of
    // level 2; of the 64 level-2 cells the other 56 are subdivided. Nodes:
    // 1 + 8 + 64 + 56 * 8 = 521 (a full tree has 585); leaves: 8 + 152 Full, 296 Partial.
    let scene = one_object(
        demo::box_mesh(DVec3::splat(0.5), DVec3::splat(7.5)),
        DMat4::IDENTITY,
    );
    let region = Region::new(DVec3::ZERO, 8.0).unwrap();
    let tree = Octree::build(&TriangleSoup::from_scene(&scene), region, 3).unwrap();
    let c = tree.leaf_counts();
    assert_eq!((c.partial, c.full, c.empty), (296, 160, 0));
    assert_eq!(tree.node_count(), 521);
    let big_full = tree
        .leaves()
        .filter(|&i| tree.node(i).kind() == NodeKind::Full && tree.node(i).level() == 2)
        .count();
    assert_eq!(big_full, 8);
    // At depth 6 the surface still costs about its area, not the volume.
    let region = Region::new(DVec3::ZERO, 8.0).unwrap();
    let tree = Octree::build(&TriangleSoup::from_scene(&scene), region, 6).unwrap();
    assert!(
        tree.node_count() < 3 * tree.leaf_counts().partial,
        "{} nodes for {} partial voxels",
        tree.node_count(),
        tree.leaf_counts().partial
    );
    // (Here the faces lie on voxel planes, so two layers are Partial.)
}

#[test]
fn open_meshes_make_a_shell_without_inside() {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("floor", demo::grid_mesh(2.0, 2.0, 2, 2)))
        .unwrap();
    // A closed box with one face missing: open, so it has no inside either.
    let mut b = crate::scene::MeshBuilder::new();
    for i in 0..8u32 {
        b.push_position(
            DVec3::new(
                f64::from(i & 1),
                f64::from((i >> 1) & 1) + 0.5,
                f64::from((i >> 2) & 1),
            ) * 0.5,
        );
    }
    for f in [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
    ] {
        b.push_face(&f, None).unwrap();
    }
    s.add(ObjectDesc::new("open box", b.finish().0)).unwrap();
    assert!(!s.objects()[0].closed && !s.objects()[1].closed);
    let region = region_of(&s);
    for depth in [3, 4] {
        let tree = Octree::build(&TriangleSoup::from_scene(&s), region, depth).unwrap();
        assert_eq!(tree.leaf_counts().full, 0);
        assert_matches_grid(&tree, &brute_voxelize(&s, &region, depth), "open meshes");
    }
}

// ---------------------------------------------------------------------------------
// Booleans

/// The documented table, written out independently of the library.
fn expected_kind(op: BooleanOp, a: NodeKind, b: NodeKind) -> NodeKind {
    use NodeKind::{Empty, Full, Partial};
    match op {
        BooleanOp::Union => match (a, b) {
            (Full, _) | (_, Full) => Full,
            (Partial, _) | (_, Partial) => Partial,
            _ => Empty,
        },
        BooleanOp::Intersection => match (a, b) {
            (Empty, _) | (_, Empty) => Empty,
            (Full, Full) => Full,
            _ => Partial,
        },
        BooleanOp::Difference => match (a, b) {
            (Empty, _) | (_, Full) => Empty,
            (x, Empty) => x,
            _ => Partial,
        },
    }
}

fn two_object_cases() -> Vec<(&'static str, Scene, Scene)> {
    let sphere =
        |c: DVec3| one_object(demo::uv_sphere_mesh(1.0, 16, 8), DMat4::from_translation(c));
    vec![
        (
            "two spheres",
            sphere(DVec3::new(-0.45, 0.1, 0.0)),
            sphere(DVec3::new(0.5, -0.1, 0.2)),
        ),
        (
            "box and torus",
            one_object(
                demo::box_mesh(DVec3::new(-0.5, -0.6, -0.5), DVec3::new(0.7, 0.6, 0.5)),
                DMat4::from_rotation_y(0.3),
            ),
            one_object(
                demo::torus_mesh(1.0, 0.35, 16, 8),
                DMat4::from_rotation_x(1.2),
            ),
        ),
    ]
}

#[test]
fn booleans_equal_brute_force() {
    for (name, a, b) in two_object_cases() {
        let region = Region::enclosing(&a.bounds().union(b.bounds())).unwrap();
        for depth in [3, 4] {
            let ta = Octree::build(&TriangleSoup::from_scene(&a), region, depth).unwrap();
            let tb = Octree::build(&TriangleSoup::from_scene(&b), region, depth).unwrap();
            let ga = brute_voxelize(&a, &region, depth);
            let gb = brute_voxelize(&b, &region, depth);
            for op in [
                BooleanOp::Union,
                BooleanOp::Intersection,
                BooleanOp::Difference,
            ] {
                let t = ta.combine(&tb, op).unwrap();
                let n = 1 << depth;
                let want = |x, y, z| expected_kind(op, ga.at(x, y, z).kind, gb.at(x, y, z).kind);
                for z in 0..n {
                    for y in 0..n {
                        for x in 0..n {
                            let got = t.voxel(x, y, z).unwrap();
                            assert_eq!(
                                got.kind(),
                                want(x, y, z),
                                "{name} {op:?} depth {depth} voxel ({x}, {y}, {z})"
                            );
                            // A partial result keeps the face of a partial operand, the
                            // lower one when both are.
                            if let Leaf::Partial { face } = got {
                                let faces: Vec<u32> = [ta.voxel(x, y, z), tb.voxel(x, y, z)]
                                    .into_iter()
                                    .filter_map(|l| match l {
                                        Some(Leaf::Partial { face }) => Some(face),
                                        _ => None,
                                    })
                                    .collect();
                                assert_eq!(Some(face), faces.iter().copied().min());
                            }
                        }
                    }
                }
                assert_eq!(t.node_count(), minimal_nodes(&want, depth), "{name} {op:?}");
            }
            // Both interiors are non-empty and they overlap.
            let i = ta.intersection(&tb).unwrap();
            assert!(i.leaf_counts().partial > 0, "{name}");
        }
    }
}

#[test]
fn boolean_identities() {
    for (name, scene) in shapes() {
        let region = region_of(&scene);
        let a = Octree::build(&TriangleSoup::from_scene(&scene), region, 4).unwrap();
        let empty = Octree::uniform(region, 4, Leaf::Empty).unwrap();
        let full = Octree::uniform(region, 4, Leaf::Full).unwrap();
        assert_eq!(a.union(&a).unwrap().nodes(), a.nodes(), "{name}: A ∪ A");
        assert_eq!(
            a.intersection(&a).unwrap().nodes(),
            a.nodes(),
            "{name}: A ∩ A"
        );
        assert_eq!(a.union(&empty).unwrap().nodes(), a.nodes(), "{name}: A ∪ 0");
        assert_eq!(
            a.intersection(&full).unwrap().nodes(),
            a.nodes(),
            "{name}: A ∩ 1"
        );
        assert_eq!(
            a.intersection(&empty).unwrap().nodes(),
            empty.nodes(),
            "{name}: A ∩ 0"
        );
        assert_eq!(
            a.union(&full).unwrap().nodes(),
            full.nodes(),
            "{name}: A ∪ 1"
        );
        assert_eq!(
            a.difference(&full).unwrap().nodes(),
            empty.nodes(),
            "{name}: A \\ 1"
        );
        assert_eq!(
            a.difference(&empty).unwrap().nodes(),
            a.nodes(),
            "{name}: A \\ 0"
        );
    }
    for (name, a, b) in two_object_cases() {
        let region = Region::enclosing(&a.bounds().union(b.bounds())).unwrap();
        let ta = Octree::build(&TriangleSoup::from_scene(&a), region, 4).unwrap();
        let tb = Octree::build(&TriangleSoup::from_scene(&b), region, 4).unwrap();
        assert_eq!(
            ta.union(&tb).unwrap().nodes(),
            tb.union(&ta).unwrap().nodes(),
            "{name}: commutative union"
        );
        assert_eq!(
            ta.intersection(&tb).unwrap().nodes(),
            tb.intersection(&ta).unwrap().nodes(),
            "{name}: commutative intersection"
        );
    }
}

// ---------------------------------------------------------------------------------
// Neighbours

/// Every node's cell, found top-down by coordinates (no parent links).
fn cells_top_down(tree: &Octree) -> HashMap<Cell, u32> {
    let mut map = HashMap::new();
    let mut stack = vec![(0u32, Cell::ROOT)];
    while let Some((i, c)) = stack.pop() {
        map.insert(c, i);
        for k in 0..8u8 {
            if let Some(child) = tree.node(i).child(k) {
                stack.push((child, c.child(k)));
            }
        }
    }
    map
}

fn random_tree(seed: u64, depth: u32) -> Octree {
    // Coarse blocks in one half, fine noise in the other, so that neighbours of every
    // size meet.
    let hash = |a: u32, b: u32, c: u32, s: u32| {
        let mut r = crate::rng::SplitMix64(
            seed ^ (u64::from(a) << 40 | u64::from(b) << 20 | u64::from(c)) ^ u64::from(s) << 60,
        );
        r.next_u64() % 3
    };
    Octree::from_fn(Region::new(DVec3::ZERO, 1.0).unwrap(), depth, |c| {
        let s = if c.x < (1 << (depth - 1)) { 2 } else { 0 };
        match hash(c.x >> s, c.y >> s, c.z >> s, s) {
            0 => Leaf::Empty,
            1 => Leaf::Full,
            _ => Leaf::Partial { face: c.x },
        }
    })
    .unwrap()
}

#[test]
fn neighbours_equal_index_arithmetic() {
    let torus = &shape("torus");
    let trees = vec![
        ("torus", Octree::from_scene(torus, 4).unwrap()),
        ("random 3", random_tree(1, 3)),
        ("random 4", random_tree(2, 4)),
    ];
    for (name, tree) in trees {
        let cells = cells_top_down(&tree);
        assert_eq!(cells.len(), tree.node_count());
        let mut boundary_nones = 0;
        for (&cell, &node) in &cells {
            assert_eq!(tree.cell(node), cell, "{name}: parent links");
            let side = 1i64 << cell.level;
            for dir in Direction::ALL {
                let [dx, dy, dz] = dir.components().map(i64::from);
                let t = [
                    i64::from(cell.x) + dx,
                    i64::from(cell.y) + dy,
                    i64::from(cell.z) + dz,
                ];
                let got = tree.neighbour(node, dir);
                if t.iter().any(|&c| c < 0 || c >= side) {
                    assert_eq!(got, None, "{name}: {cell:?} {dir:?} is at the boundary");
                    boundary_nones += 1;
                    continue;
                }
                // The deepest node at or above the cell's level containing the target.
                let want = (0..=cell.level)
                    .rev()
                    .find_map(|l| {
                        let s = cell.level - l;
                        cells.get(&Cell {
                            level: l,
                            x: (t[0] as u32) >> s,
                            y: (t[1] as u32) >> s,
                            z: (t[2] as u32) >> s,
                        })
                    })
                    .copied();
                assert_eq!(got, want, "{name}: {cell:?} {dir:?}");
            }
        }
        assert!(boundary_nones > 0);
    }
}

#[test]
fn adjacent_leaves_are_exactly_the_touching_ones() {
    let tree = random_tree(3, 4);
    let n = 1i64 << tree.depth();
    // Each node's cell as integer intervals on the finest grid.
    let span = |i: u32| {
        let c = tree.cell(i);
        let s = 1i64 << (tree.depth() - c.level);
        [c.x, c.y, c.z].map(|v| (i64::from(v) * s, i64::from(v) * s + s))
    };
    let leaves: Vec<u32> = tree.leaves().collect();
    for node in 0..tree.node_count() as u32 {
        let a = span(node);
        for dir in Direction::ALL {
            let d = dir.components();
            let mut want: Vec<u32> = leaves
                .iter()
                .copied()
                .filter(|&l| {
                    let b = span(l);
                    // The leaf overlaps the same-size cell across `dir` and reaches
                    // the plane it shares with the node on every axis of the move.
                    (0..3).all(|k| match d[k] {
                        1 => b[k].0 <= a[k].1 && b[k].1 > a[k].1,
                        -1 => b[k].1 >= a[k].0 && b[k].0 < a[k].0,
                        _ => b[k].0 < a[k].1 && a[k].0 < b[k].1,
                    })
                })
                .collect();
            want.sort_unstable();
            let mut got = tree.adjacent_leaves(node, dir);
            got.sort_unstable();
            assert_eq!(got, want, "node {node} {:?} {dir:?}", tree.cell(node));
            let at_boundary =
                (0..3).any(|k| (d[k] == 1 && a[k].1 == n) || (d[k] == -1 && a[k].0 == 0));
            assert_eq!(got.is_empty(), at_boundary);
        }
    }
}

// ---------------------------------------------------------------------------------
// Ray order and traversal

/// The ray parameters where a ray enters and leaves a box (slab method), if it meets it.
fn slab(o: DVec3, d: DVec3, min: DVec3, max: DVec3) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < min[k] || o[k] > max[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((min[k] - o[k]) / d[k], (max[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1).then_some((t0, t1))
}

#[test]
fn child_order_is_front_to_back_for_every_ray_octant() {
    let mut rng = crate::rng::SplitMix64(5);
    let region = Region::new(DVec3::ZERO, 1.0).unwrap();
    for octant in 0..8u32 {
        let mut checked = 0;
        for _ in 0..2000 {
            let mut comp = |bit: u32| {
                let m = rng.range(0.05, 1.0);
                if octant >> bit & 1 == 1 { -m } else { m }
            };
            let d = DVec3::new(comp(0), comp(1), comp(2));
            // Through a random point of the cube, from outside or inside it.
            let through = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let o = through - d * rng.range(0.0, 2.0);
            let order = front_to_back_order(d);
            let mut sorted = order;
            sorted.sort_unstable();
            assert_eq!(sorted, [0, 1, 2, 3, 4, 5, 6, 7]);
            let entries: Vec<f64> = order
                .iter()
                .filter_map(|&k| {
                    let b = region.cell_box(Cell::ROOT.child(k));
                    slab(o, d, b.min, b.max)
                        .filter(|&(_, t1)| t1 >= 0.0)
                        .map(|(t0, _)| t0)
                })
                .collect();
            assert!(
                entries.windows(2).all(|w| w[0] <= w[1]),
                "octant {octant}: ray {o:?} {d:?} meets children out of order: {entries:?}"
            );
            checked += usize::from(entries.len() >= 3);
        }
        assert!(
            checked > 300,
            "octant {octant}: {checked} rays through 3 children or more"
        );
    }
}

#[test]
fn first_hit_is_the_nearest_partial_voxel() {
    let scene = &shape("torus"); // rays pass through the hole
    let tree = Octree::from_scene(scene, 5).unwrap();
    let region = *tree.region();
    let partial: Vec<(u32, crate::geom::Aabb)> = tree
        .leaves()
        .filter(|&i| tree.node(i).kind() == NodeKind::Partial)
        .map(|i| (i, region.cell_box(tree.cell(i))))
        .collect();
    let mut rng = crate::rng::SplitMix64(9);
    let (mut hits, mut misses) = (0, 0);
    for k in 0..400 {
        let o = region.min()
            + DVec3::new(
                rng.range(-1.0, 2.0),
                rng.range(-1.0, 2.0),
                rng.range(-1.0, 2.0),
            ) * region.side();
        let target = region.min()
            + DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * region.side();
        let mut d = target - o;
        if k % 10 == 0 {
            d.y = 0.0; // axis-parallel components
        }
        let (t_min, t_max) = (0.1, if k % 7 == 0 { 0.6 } else { f64::INFINITY });
        let want = partial
            .iter()
            .filter_map(|&(i, b)| {
                slab(o, d, b.min, b.max)
                    .filter(|&(t0, t1)| t1 >= t_min && t0 <= t_max)
                    .map(|(t0, _)| (t0.max(t_min), i))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let (got, visited) = tree.first_hit(o, d, t_min, t_max);
        match (got, want) {
            (None, None) => misses += 1,
            (Some(h), Some((t, _))) => {
                hits += 1;
                assert!(
                    (h.t - t).abs() <= 1e-9 * (1.0 + t.abs()),
                    "ray {k}: t {} vs {t}",
                    h.t
                );
                let b = region.cell_box(tree.cell(h.node));
                let (t0, _) = slab(o, d, b.min, b.max).unwrap();
                assert!((t0.max(t_min) - t).abs() <= 1e-9 * (1.0 + t.abs()));
                assert_eq!(h.face, tree.node(h.node).face());
                assert!(visited > 0);
            }
            (g, w) => panic!("ray {k}: got {g:?}, brute force {w:?}"),
        }
    }
    assert!(hits > 100 && misses > 20, "{hits} hits, {misses} misses");
    assert_eq!(tree.first_hit(DVec3::NAN, DVec3::X, 0.0, 1.0).0, None);
    assert_eq!(tree.first_hit(DVec3::ZERO, DVec3::ZERO, 0.0, 1.0).0, None);
    // A ray aimed at a Partial voxel's centre hits, but not in an empty interval.
    let o = region.min() - DVec3::ONE;
    let d = partial[0].1.center() - o;
    assert!(tree.first_hit(o, d, 0.0, f64::INFINITY).0.is_some());
    assert_eq!(tree.first_hit(o, d, 2.0, 1.0).0, None);
    assert_eq!(tree.first_hit(o, d, f64::NAN, 1.0).0, None);
}

// ---------------------------------------------------------------------------------
// Rendering

fn render_both(
    scene: &Scene,
    camera: &Camera,
    vp: Viewport,
    depth: u32,
) -> (crate::Frame, crate::Frame) {
    let view = prepare(scene, camera, vp, &PrepareOptions::default()).unwrap();
    let (z, _) = render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap();
    let (o, stats) = render(
        Algorithm::Octree,
        &view,
        &RenderOptions::default().with_octree_depth(depth),
    )
    .unwrap();
    let stats = stats.octree().expect("the octree's stats");
    assert_eq!(stats.depth, depth);
    assert!(stats.nodes_visited_per_ray > 0.0);
    (z, o)
}

#[test]
fn a_cube_head_on_covers_the_expected_square() {
    // Unit cube, eye at z = 2.5, 90 degree field of view, 100 x 100: the front face
    // (z = 0.5, depth 2) spans pixels 37.5 .. 62.5. The voxels a face touches reach at
    // most one voxel v beyond the cube, so the image lies within the projection of the
    // cube grown by v: half-width 50 (0.5 + v) / (2 - v) pixels.
    let scene = demo::cube();
    let camera = Camera::perspective(
        DVec3::new(0., 0., 2.5),
        DVec3::ZERO,
        DVec3::Y,
        90.0,
        0.1,
        10.0,
    );
    let vp = Viewport::new(100, 100).unwrap();
    for depth in [5, 7] {
        let (z, o) = render_both(&scene, &camera, vp, depth);
        let v = region_of(&scene).cell_side(depth);
        let half = 50.0 * (0.5 + v) / (2.0 - v);
        let mut interior = 0;
        for j in 0..100u32 {
            for i in 0..100u32 {
                let (px, py) = (f64::from(i) + 0.5 - 50.0, f64::from(j) + 0.5 - 50.0);
                let id = o.id(i, j);
                let exact = px.abs() < 12.5 && py.abs() < 12.5;
                if exact {
                    assert_ne!(id, BACKGROUND, "depth {depth}: ({i}, {j}) inside the face");
                    assert_eq!(z.id(i, j), 5);
                }
                if id != BACKGROUND {
                    assert!(
                        px.abs() <= half && py.abs() <= half,
                        "depth {depth}: ({i}, {j}) beyond the grown cube"
                    );
                    assert!(id < 6);
                    let d = f64::from(o.depth[o.index(i, j)]);
                    assert!(
                        d >= 2.0 - v - 1e-6 && d <= 2.0 + 4.0 * v + 1e-6,
                        "depth {d}"
                    );
                }
                // Away from the edges by more than a voxel, the front face (id 5) at
                // depth 2 - v at the most.
                let margin = 12.5 - 50.0 * 2.0 * v / 1.9 - 1.0;
                if px.abs() < margin && py.abs() < margin {
                    interior += 1;
                    assert_eq!(id, 5, "depth {depth}: ({i}, {j})");
                    let d = f64::from(o.depth[o.index(i, j)]);
                    assert!(d >= 2.0 - v - 1e-6 && d <= 2.0, "depth {d}");
                }
            }
        }
        assert!(interior > 100);
    }
}

/// The distance in pixels from each pixel to the nearest pixel where `mask` holds
/// (brute force over a small image), capped at `cap`.
fn distance_to(mask: &[bool], w: usize, h: usize, cap: i64) -> Vec<i64> {
    let mut out = vec![cap; w * h];
    for j in 0..h as i64 {
        for i in 0..w as i64 {
            let mut best = cap;
            for dj in -cap..=cap {
                for di in -cap..=cap {
                    let (x, y) = (i + di, j + dj);
                    if x >= 0
                        && y >= 0
                        && (x as usize) < w
                        && (y as usize) < h
                        && mask[y as usize * w + x as usize]
                    {
                        best = best.min(di.abs().max(dj.abs()));
                    }
                }
            }
            out[j as usize * w + i as usize] = best;
        }
    }
    out
}

#[test]
fn the_default_scene_is_plausible_against_the_z_buffer() {
    let scene = demo::default_scene();
    let vp = Viewport::new(160, 120).unwrap();
    let camera = scene.default_camera(vp.aspect());
    let depth = 7;
    let (z, o) = render_both(&scene, &camera, vp, depth);
    let (w, h) = (160, 120);
    let v = region_of(&scene).cell_side(depth);
    // Silhouettes. Every ray the z-buffer sees a face along meets that face inside a
    // Partial voxel, so the octree covers every pixel the z-buffer covers. Conversely an
    // octree pixel's voxel touches a face, so a surface point lies within a voxel
    // diagonal of where the ray enters it: on screen, within the diagonal's projection
    // at that depth (plus a pixel for sampling).
    let zc: Vec<bool> = z.ids.iter().map(|&i| i != BACKGROUND).collect();
    let oc: Vec<bool> = o.ids.iter().map(|&i| i != BACKGROUND).collect();
    let dz = distance_to(&zc, w, h, 8);
    let tan_half = (20.0f64).to_radians().tan(); // the default scene's 40 degree camera
    let mut widest = 0;
    for p in 0..w * h {
        assert!(
            !zc[p] || oc[p],
            "z-buffer pixel {p} not covered by the octree"
        );
        if oc[p] {
            let near = f64::from(o.depth[p]) - 3f64.sqrt() * v;
            let tolerance =
                (3f64.sqrt() * v * h as f64 / (2.0 * tan_half * near)).ceil() as i64 + 1;
            assert!(tolerance < 8);
            assert!(
                dz[p] <= tolerance,
                "octree pixel {p} is {} pixels from the z-buffer's",
                dz[p]
            );
            widest = widest.max(dz[p]);
        }
    }
    assert!(
        widest >= 1,
        "the octree's silhouette should be a little wider"
    );
    // Ids: on pixels inside large faces (the z-buffer shows one face over a 7 x 7
    // square around them) the octree names the same face almost everywhere, and the
    // same object nearly always.
    let (mut interior, mut same_face, mut same_object) = (0, 0, 0);
    for j in 3..h - 3 {
        for i in 3..w - 3 {
            let id = z.ids[j * w + i];
            if id == BACKGROUND {
                continue;
            }
            let uniform = (j - 3..=j + 3).all(|y| (i - 3..=i + 3).all(|x| z.ids[y * w + x] == id));
            if !uniform {
                continue;
            }
            interior += 1;
            let got = o.ids[j * w + i];
            same_face += usize::from(got == id);
            same_object += usize::from(
                got != BACKGROUND
                    && scene.locate_face(got).unwrap().0 == scene.locate_face(id).unwrap().0,
            );
            if got != id {
                continue;
            }
            // Depth: the voxel meets the face, so all of it lies within a voxel diagonal
            // of the face's plane; the ray enters it before meeting the plane, and at
            // most that far before in distance from the plane.
            let (k, local) = scene.locate_face(id).unwrap();
            let object = &scene.objects()[k];
            let polygon = object.mesh.polygons_of_face(local).start;
            let normal = crate::geom::newell_normal(&object.world_polygon(polygon)).normalize();
            let ray = camera.ray(vp, i as f64 + 0.5, j as f64 + 0.5);
            let (dz, dq) = (f64::from(z.depth[j * w + i]), f64::from(o.depth[j * w + i]));
            let bound = 3f64.sqrt() * v / ray.direction.dot(normal).abs();
            assert!(
                dq <= dz + 1e-4 && dq >= dz - bound - 1e-4,
                "pixel ({i}, {j}): octree depth {dq}, z-buffer {dz}, bound {bound}"
            );
        }
    }
    assert!(interior > 2000, "{interior}");
    let face_rate = same_face as f64 / interior as f64;
    let object_rate = same_object as f64 / interior as f64;
    assert!(
        face_rate > 0.97,
        "same face on {face_rate} of interior pixels"
    );
    assert!(
        object_rate > 0.99,
        "same object on {object_rate} of interior pixels"
    );
}

#[test]
fn scenes_without_closed_objects_render_their_shells() {
    // Seed 004's task: two open polygons seen orthographically.
    let scene = demo::seed_task();
    let vp = Viewport::new(32, 32).unwrap();
    let camera = *scene.camera().unwrap();
    let (z, o) = render_both(&scene, &camera, vp, 6);
    let both = z
        .ids
        .iter()
        .zip(&o.ids)
        .filter(|(a, b)| **a != BACKGROUND && **b != BACKGROUND)
        .count();
    assert!(both as f64 > 0.9 * z.covered_pixels() as f64);
    assert!(o.ids.iter().all(|&i| i == BACKGROUND || i < 2));
}

#[test]
fn an_eye_inside_a_solid_sees_its_boundary_from_inside() {
    // The documented behaviour: Full voxels are passed through and the boundary voxels
    // stop every ray, so the whole image shows the cube's faces, at depths up to the
    // cube's far side (the z-buffer, culling back faces, shows nothing here).
    let scene = demo::cube();
    let camera = Camera::perspective(
        DVec3::new(0.1, 0.05, 0.0),
        DVec3::new(0.1, 0.05, -1.0),
        DVec3::Y,
        60.0,
        0.01,
        10.0,
    );
    let vp = Viewport::new(40, 30).unwrap();
    let (z, o) = render_both(&scene, &camera, vp, 5);
    assert_eq!(z.covered_pixels(), 0);
    assert_eq!(o.covered_pixels(), 40 * 30);
    let v = region_of(&scene).cell_side(5);
    for (&id, &d) in o.ids.iter().zip(&o.depth) {
        assert!(id < 6);
        // The back face z = -0.5 is at depth 0.5; its voxels start up to a voxel nearer.
        assert!(
            f64::from(d) >= 0.5 - v - 1e-6 && f64::from(d) <= 0.5 + 1e-6 || id != 4,
            "{id} at {d}"
        );
    }
    assert!(o.ids.iter().filter(|&&i| i == 4).count() > 600);
}

#[test]
fn an_eye_within_a_voxel_of_a_surface_sees_past_it() {
    // A ground square 20 wide and a box on it; the eye 0.05 above the ground, where
    // the voxels (depth 5) are about 0.64 on a side, so the eye's voxel holds ground.
    // Taking that voxel as the first hit made the whole image ground at depth `near`;
    // it is now decided by the ground itself: rays that meet it inside the voxel show
    // it there, the others go on. Rays that leave the voxel upwards reach the sky;
    // those that stay in the layer of ground voxels meet the next one (the documented
    // growth of a surface by its voxels, seen from within the layer).
    let mut scene = Scene::new();
    let mut b = crate::scene::MeshBuilder::new();
    for (x, z) in [(-10.0, -10.0), (-10.0, 10.0), (10.0, 10.0), (10.0, -10.0)] {
        b.push_position(DVec3::new(x, 0.0, z));
    }
    b.push_face(&[0, 1, 2, 3], None).unwrap();
    scene
        .add(ObjectDesc::new("ground", b.finish().0).with_closed(false))
        .unwrap();
    scene
        .add(ObjectDesc::new(
            "box",
            demo::box_mesh(DVec3::new(4.0, 0.0, -1.0), DVec3::new(5.0, 1.5, 1.0)),
        ))
        .unwrap();
    let camera = Camera::perspective(
        DVec3::new(0.0, 0.05, 0.0),
        DVec3::new(5.0, 0.05, 0.0),
        DVec3::Y,
        60.0,
        0.01,
        100.0,
    );
    let vp = Viewport::new(64, 48).unwrap();
    let (z, o) = render_both(&scene, &camera, vp, 5);
    let sky = z.ids.iter().filter(|&&i| i == BACKGROUND).count();
    assert!(sky > 64 * 16, "{sky}");
    let agree = |pick: &dyn Fn(u32) -> bool| {
        let (mut n, mut same) = (0, 0);
        for (&a, &b) in z.ids.iter().zip(&o.ids) {
            if pick(a) {
                n += 1;
                same += usize::from(a == b);
            }
        }
        same as f64 / n as f64
    };
    // Where the ground is seen, its depth is the exact hit or a voxel's entry beyond
    // the eye's, never `near`.
    assert!(
        agree(&|i| i == BACKGROUND) > 0.5,
        "sky {}",
        agree(&|i| i == BACKGROUND)
    );
    // The top rows look up out of the eye's voxel, above the box's voxels.
    assert!(o.ids[..64 * 2].iter().all(|&i| i == BACKGROUND));
    for (k, (&id, &d)) in o.ids.iter().zip(&o.depth).enumerate() {
        if id == 0 && z.ids[k] == 0 {
            assert!(d > 0.05, "pixel {k}: ground at depth {d}");
        }
    }
}
