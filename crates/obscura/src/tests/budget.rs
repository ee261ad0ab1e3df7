//! The memory budget (issue 21, section 3): every structure that grows with the input is
//! refused before it is allocated, or stopped while it grows, with an error naming it.
//! Every input is generated here.

#[cfg(all(feature = "obj", feature = "toml-scene"))]
use std::path::PathBuf;

#[cfg(all(feature = "obj", feature = "toml-scene"))]
use crate::scene::load::LoadOptions;
#[cfg(all(feature = "obj", feature = "toml-scene"))]
use crate::scene::load::toml_scene::{MAX_PLACED_FACES, PLACED_FACE_BYTES, PLACED_VERTEX_BYTES};
use crate::scene::random::random_triangles;
use crate::scene::{Scene, Viewport, demo};
use crate::surface::{Algorithm, RenderOptions, render};
use crate::{Error, PrepareOptions, prepare};

#[cfg(all(feature = "obj", feature = "toml-scene"))]
fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("obscura-budget-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The fields of a budget error, or a failure naming what came instead.
/// The scene seen from its default camera, prepared with the default options.
fn default_view(scene: &Scene, vp: Viewport) -> crate::PreparedView<'_> {
    prepare(
        scene,
        &scene.default_camera(vp.aspect()),
        vp,
        &PrepareOptions::default(),
    )
    .unwrap()
}

fn budget_fields(r: Result<impl Sized, Error>) -> (String, u64, u64, u64, String, Option<String>) {
    match r {
        Err(Error::Budget {
            structure,
            count,
            bytes,
            limit,
            option,
            at,
        }) => (structure, count, bytes, limit, option, at),
        Err(e) => panic!("expected a budget error, got: {e}"),
        Ok(_) => panic!("expected a budget error, got a result"),
    }
}

#[test]
fn bsp_on_random_large_triangles_stops_at_the_budget_naming_its_fragments() {
    // 400 triangles as large as the scene: they cut each other everywhere.
    let scene = random_triangles(400, 7, 10.0, 10.0);
    let vp = Viewport::new(80, 60).unwrap();
    let view = default_view(&scene, vp);
    let limit = 2 << 20;
    let options = RenderOptions::default().with_memory_limit(Some(limit));
    let (structure, count, bytes, got_limit, option, _) =
        budget_fields(render(Algorithm::Bsp, &view, &options));
    assert_eq!(structure, "BSP fragments");
    assert_eq!(option, "memory_limit");
    assert_eq!(got_limit, limit);
    assert!(bytes > limit, "{bytes} <= {limit}");
    // Stopped soon after passing it: within one node's growth and one doubling of
    // the largest vector, far below ten times the limit.
    assert!(bytes < 10 * limit, "{bytes}");
    // More fragments than polygons: splitting had begun.
    assert!(count > 400, "{count}");
    let text = render(Algorithm::Bsp, &view, &options)
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("BSP fragments") && text.contains("memory_limit") && text.contains("2.0 MiB"),
        "{text}"
    );
    // The other algorithms render the same view within the same budget.
    for a in [
        Algorithm::ZBuffer,
        Algorithm::Scanline,
        Algorithm::RaycastBvh,
    ] {
        assert!(render(a, &view, &options).is_ok(), "{a}");
    }
}

#[test]
fn octree_depth_10_is_refused_before_building_and_its_estimate_bounds_the_tree() {
    let scene = demo::cube();
    let vp = Viewport::new(32, 24).unwrap();
    let view = default_view(&scene, vp);
    let small = RenderOptions::default()
        .with_octree_depth(10)
        .with_memory_limit(Some(16 << 20));
    let (structure, nodes, bytes, _, _, _) =
        budget_fields(render(Algorithm::Octree, &view, &small));
    assert!(
        structure.contains("octree nodes") && structure.contains("depth 10"),
        "{structure}"
    );
    assert!(bytes > 16 << 20 && nodes > 0);
    // The check is the one the entry point runs before any node is made.
    assert!(matches!(
        crate::surface::octree::check_budget(&scene, &small),
        Err(Error::Budget { .. })
    ));
    // The estimate is an upper bound of what the build makes: at depths 3 to 6 the
    // tree's own memory figure is below it.
    for depth in 3..=6 {
        let estimate = match crate::surface::octree::check_budget(
            &scene,
            &RenderOptions::default()
                .with_octree_depth(depth)
                .with_memory_limit(Some(1)),
        ) {
            Err(Error::Budget { bytes, .. }) => bytes,
            other => panic!("{other:?}"),
        };
        let (_, stats) = render(
            Algorithm::Octree,
            &view,
            &RenderOptions::default().with_octree_depth(depth),
        )
        .unwrap();
        let actual = stats.octree().expect("the octree's stats").memory_bytes;
        assert!(
            actual > 0 && actual <= estimate,
            "depth {depth}: built {actual} bytes, estimated {estimate}"
        );
    }
}

#[test]
fn a_frame_larger_than_the_budget_is_refused_before_it_is_allocated() {
    let scene = demo::cube();
    let vp = Viewport::new(16384, 16384).unwrap();
    let view = default_view(&scene, vp);
    let options = RenderOptions::default().with_memory_limit(Some(64 << 20));
    for a in Algorithm::ALL {
        let (structure, count, bytes, _, _, _) = budget_fields(render(a, &view, &options));
        assert_eq!(structure, crate::surface::FRAME_STRUCTURE, "{a}");
        assert_eq!(count, 16384 * 16384, "{a}");
        // At least the ids and depths: 8 bytes a pixel.
        assert!(bytes >= 8 * 16384 * 16384, "{a}: {bytes}");
    }
}

#[test]
fn a_prepared_view_over_the_budget_is_refused() {
    let scene = random_triangles(2000, 3, 10.0, 1.0);
    let vp = Viewport::new(64, 48).unwrap();
    let options = PrepareOptions::default().with_memory_limit(Some(10_000));
    let (structure, count, bytes, ..) = budget_fields(prepare(
        &scene,
        &scene.default_camera(vp.aspect()),
        vp,
        &options,
    ));
    assert_eq!(structure, crate::view::BUDGET_STRUCTURE);
    assert_eq!(count, 2000);
    // At least 3 vertices of 4 f64 a triangle.
    assert!(bytes >= 2000 * 3 * 32, "{bytes}");
}

#[cfg(all(feature = "obj", feature = "toml-scene"))]
/// An OBJ of a flat grid of `n x n` quads as `2 n^2` triangles; returns (faces,
/// vertices).
fn write_grid_obj(path: &PathBuf, n: usize) -> (u64, u64) {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            s += &format!("v {i} 0 {j}\n");
        }
    }
    let at = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            s += &format!("f {} {} {}\n", at(i, j), at(i + 1, j), at(i + 1, j + 1));
            s += &format!("f {} {} {}\n", at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
    std::fs::write(path, s).unwrap();
    (2 * (n * n) as u64, ((n + 1) * (n + 1)) as u64)
}

#[cfg(all(feature = "obj", feature = "toml-scene"))]
/// A scene file placing `mesh` `count` times, one table of 3 lines each after a
/// 1-line header comment: table `k` (0-based) starts on line `2 + 3 k`.
fn write_placements(path: &PathBuf, mesh: &str, count: usize) {
    let mut s = String::from("# many placements of one mesh\n");
    for k in 0..count {
        s += &format!("[[object]]\nmesh = \"{mesh}\"\ntranslate = [{k}, 0, 0]\n");
    }
    std::fs::write(path, s).unwrap();
}

#[cfg(all(feature = "obj", feature = "toml-scene"))]
#[test]
fn scene_file_placements_over_the_face_cap_are_refused_at_their_line() {
    let dir = tempdir("toml-cap");
    let (faces, _) = write_grid_obj(&dir.join("grid.obj"), 100);
    assert_eq!(faces, 20_000);
    let crossing = (MAX_PLACED_FACES / faces) as usize + 1;
    write_placements(&dir.join("many.toml"), "grid.obj", crossing + 10);
    let options = LoadOptions {
        memory_limit: Some(u64::MAX),
        ..LoadOptions::default()
    };
    let spec = dir.join("many.toml");
    let e = Scene::load_with(spec.to_str().unwrap(), &options).unwrap_err();
    let line = 2 + 3 * (crossing - 1);
    match &e {
        Error::Parse {
            path,
            line: l,
            message,
        } => {
            assert_eq!(path, &spec);
            assert_eq!(*l, line, "{e}");
            assert!(
                message.contains(&(crossing as u64 * faces).to_string())
                    && message.contains(&MAX_PLACED_FACES.to_string()),
                "{message}"
            );
        }
        other => panic!("{other}"),
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[cfg(all(feature = "obj", feature = "toml-scene"))]
#[test]
fn scene_file_placements_over_the_budget_are_refused_naming_the_file_and_line() {
    let dir = tempdir("toml-budget");
    let (faces, vertices) = write_grid_obj(&dir.join("grid.obj"), 10);
    let per = faces * PLACED_FACE_BYTES + vertices * PLACED_VERTEX_BYTES;
    let limit = 1 << 20;
    // The first placement whose total passes the limit.
    let crossing = (limit / per) as usize + 1;
    write_placements(&dir.join("many.toml"), "grid.obj", crossing + 5);
    let spec = dir.join("many.toml");
    let mut options = LoadOptions {
        memory_limit: Some(limit),
        ..LoadOptions::default()
    };
    let (structure, count, bytes, got_limit, option, at) =
        budget_fields(Scene::load_with(spec.to_str().unwrap(), &options));
    assert!(structure.contains("faces placed"), "{structure}");
    assert_eq!(count, crossing as u64 * faces);
    assert_eq!(bytes, crossing as u64 * per);
    assert_eq!(got_limit, limit);
    assert_eq!(option, "memory_limit");
    assert_eq!(
        at.as_deref(),
        Some(format!("{}:{}", spec.display(), 2 + 3 * (crossing - 1)).as_str())
    );
    // Within the budget, the same file loads.
    options.memory_limit = Some(crossing as u64 * per * 2);
    let scene = Scene::load_with(spec.to_str().unwrap(), &options).unwrap();
    assert_eq!(scene.polygon_count() as u64, (crossing as u64 + 5) * faces);
    std::fs::remove_dir_all(&dir).ok();
}
