//! Inputs the fuzzing campaigns found (`fuzz/README.md`), kept as regression tests.
//!
//! Each test writes the (minimized) input the fuzzer reported, as it was found, to a
//! fresh folder under the system temp dir, loads it as the fuzz target did, and checks
//! that the load ends (the test returning is that check) with a clean error naming the
//! file, or with a scene whose default camera is valid and which renders. No timing is
//! asserted.
// Files the fuzzers wrote: built with every file format (the default features).
#![cfg(all(
    feature = "obj",
    feature = "gltf",
    feature = "stl",
    feature = "ply",
    feature = "toml-scene"
))]

use std::path::Path;

mod common;

use common::TempDir;
use obscura::scene::load::load_file;
use obscura::{Algorithm, PrepareOptions, Scene, Viewport};

/// What the fuzz targets check of a scene that loaded: its default camera is valid and
/// the z-buffer renders it at 64x48.
fn frame_and_render(path: &Path, scene: &Scene) {
    let viewport = Viewport::new(64, 48).unwrap();
    let camera = match scene.automatic_camera(viewport.aspect()) {
        Ok(camera) => camera,
        Err(e) => {
            // A scene no camera within range can frame must say so, not leave an
            // invalid camera for `prepare` to refuse without a word about why.
            let m = e.to_string();
            assert!(
                m.contains("the automatic camera cannot frame the scene"),
                "{}: {m}",
                path.display()
            );
            return;
        }
    };
    let view = obscura::prepare(scene, &camera, viewport, &PrepareOptions::default())
        .unwrap_or_else(|e| panic!("{}: prepare failed: {e}", path.display()));
    obscura::render(Algorithm::ZBuffer, &view, &Default::default())
        .unwrap_or_else(|e| panic!("{}: render failed: {e}", path.display()));
}

/// Loads `path`: either a clean error that names the file, or a scene that is framed
/// and rendered.
fn load_or_refuse(path: &Path) -> Option<Scene> {
    match load_file(path) {
        Ok(scene) => {
            frame_and_render(path, &scene);
            Some(scene)
        }
        Err(e) => {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            assert!(
                e.to_string().contains(&name),
                "the error does not name {name}: {e}"
            );
            None
        }
    }
}

// ---------------------------------------------------------------------------------
// Campaign of 2026-11-28

/// `stl` (soft finding, about 4,500 inputs): a mesh inside the largest coordinate
/// accepted (1e30) but close to it loaded, and then the default camera that frames it
/// was refused ("invalid camera: eye ... beyond the largest coordinate accepted", or
/// "near ... or far ... beyond the largest distance accepted"), naming neither the file
/// nor anything the user gave. The fuzzer found binary STLs; this is the same class
/// as an ASCII file of one triangle. Now the automatic camera frames it from the
/// origin's side where that stays in range, and otherwise `Scene::automatic_camera`
/// says that no camera in range frames the scene (the CLI adds the scene's name).
#[test]
fn a_mesh_near_the_coordinate_limit_is_framed_or_refused_by_name() {
    let dir = TempDir::new("stl-far");
    let path = dir.write(
        "far.stl",
        b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 9e29 0 0\n\
          vertex 0 9e29 0\nendloop\nendfacet\nendsolid t\n",
    );
    load_or_refuse(&path);
    // The binary form the fuzzer found: one facet whose x reaches -6.3e29.
    let mut stl = vec![b' '; 80];
    stl.extend_from_slice(&1u32.to_le_bytes());
    for v in [
        0.0f32, 0.0, 1.0, 0.0, 0.0, 0.0, -6.3e29, 0.0, 0.0, 0.0, 1.0, 0.0,
    ] {
        stl.extend_from_slice(&v.to_le_bytes());
    }
    stl.extend_from_slice(&[0, 0]);
    let path = dir.write("far_binary.stl", stl);
    load_or_refuse(&path);
}
