//! Small facts of the BSP tree; the cross-checks against the z-buffer are in
//! `src/tests/bsp.rs`.

use super::*;
use crate::scene::{ObjectDesc, demo};

#[test]
fn empty_scene_gives_empty_tree() {
    let t = BspTree::build(&Scene::new(), &BspOptions::default()).unwrap();
    assert_eq!(t.root(), None);
    assert!(
        t.paint_order(Viewpoint::Point(DVec3::Z), BspTraversal::BackToFront)
            .is_empty()
    );
    assert_eq!(t.stats().depth, 0);
}

#[test]
fn bad_options_are_refused() {
    let s = demo::cube();
    let nan = BspOptions::default().with_weights(f64::NAN, 1.0);
    assert!(BspTree::build(&s, &nan).is_err());
    let negative = BspOptions::default().with_weights(1.0, -1.0);
    assert!(BspTree::build(&s, &negative).is_err());
    // Zero candidates is read as one.
    assert!(BspTree::build(&s, &BspOptions::default().with_candidates(0)).is_ok());
}

#[test]
fn crossing_quads_split_once_and_keep_their_area() {
    // Two 2x2 squares crossing at right angles through each other's middle.
    let mut s = Scene::new();
    let quad = |pts: [DVec3; 4]| {
        let mut b = crate::scene::MeshBuilder::new();
        for p in pts {
            b.push_position(p);
        }
        b.push_face(&[0, 1, 2, 3], None).unwrap();
        b.finish().0
    };
    s.add(ObjectDesc::new(
        "a",
        quad([
            DVec3::new(-1., -1., 0.),
            DVec3::new(1., -1., 0.),
            DVec3::new(1., 1., 0.),
            DVec3::new(-1., 1., 0.),
        ]),
    ))
    .unwrap();
    s.add(ObjectDesc::new(
        "b",
        quad([
            DVec3::new(0., -1., -1.),
            DVec3::new(0., -1., 1.),
            DVec3::new(0., 1., 1.),
            DVec3::new(0., 1., -1.),
        ]),
    ))
    .unwrap();
    let t = BspTree::build(&s, &BspOptions::default()).unwrap();
    // a is the root; b's halves go to either side.
    assert_eq!(t.stats().splits, 1);
    assert_eq!(t.stats().fragments, 3);
    assert_eq!(t.stats().nodes, 3);
    assert_eq!(t.stats().depth, 2);
    let total: f64 = (0..t.node_count() as u32)
        .flat_map(|n| t.node_fragments(n).to_vec())
        .map(|f| crate::geom::polygon_area(&t.fragment_points(f)))
        .sum();
    assert!((total - 8.0).abs() < 1e-12);
    // The two new vertices are shared by both pieces.
    let made = t
        .vertices()
        .iter()
        .filter(|v| v.mesh_vertex().is_none())
        .count();
    assert_eq!(made, 2);
}
