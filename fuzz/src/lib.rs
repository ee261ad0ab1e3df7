//! Shared checks for the obscura loader fuzz targets: a loaded file must hold finite
//! positions and transforms, and the scene built from it must be framed by its
//! default camera and rendered. Inputs that are accepted but cannot be framed or
//! rendered are saved under `findings/soft/` (not a crash: worth a look).
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use obscura::scene::load::{scene_from, Loaded};
use obscura::{Algorithm, PrepareOptions, Scene, Viewport};

static SOFT: AtomicUsize = AtomicUsize::new(0);

/// Saves an input that did not crash but looks wrong (e.g. an accepted scene the
/// default camera cannot frame), without stopping the fuzzer.
pub fn soft_finding(target: &str, kind: &str, input: &[u8], detail: &str) {
    if SOFT.fetch_add(1, Ordering::Relaxed) > 200 {
        return;
    }
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in input {
        h = (h ^ u64::from(b)).wrapping_mul(0x100000001b3);
    }
    let dir = Path::new("findings/soft");
    let _ = std::fs::create_dir_all(dir);
    let base = dir.join(format!("{target}-{kind}-{h:016x}"));
    let _ = std::fs::write(base.with_extension("bin"), input);
    let _ = std::fs::write(base.with_extension("txt"), detail);
}

/// A private empty directory per process (for loaders that resolve side files).
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("obscura-fuzz-{tag}-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&d);
    d
}

/// Checks what a loader returned, then builds a scene and renders it.
pub fn check_loaded(target: &str, input: &[u8], loaded: Loaded) {
    for o in &loaded.objects {
        assert!(
            o.mesh.positions().iter().all(|p| p.is_finite()),
            "loader returned a non-finite position in object {:?}",
            o.name
        );
        assert!(o.transform.is_finite(), "loader returned a non-finite transform");
    }
    let scene = match scene_from(loaded, "fuzz") {
        Ok(s) => s,
        Err(obscura::Error::EmptyScene(_)) => return,
        Err(e) => {
            soft_finding(target, "scene_from", input, &e.to_string());
            return;
        }
    };
    check_scene(target, input, &scene);
}

/// Frames a scene with its default camera and renders it with the z-buffer.
pub fn check_scene(target: &str, input: &[u8], scene: &Scene) {
    if scene.ensure_not_empty("fuzz").is_err() {
        return;
    }
    let viewport = Viewport::new(64, 48).expect("viewport");
    let camera = scene.default_camera(viewport.aspect());
    if let Err(e) = camera.validate() {
        soft_finding(target, "camera", input, &format!("{e}\nbounds {:?}", scene.bounds()));
        return;
    }
    let view = match obscura::prepare(scene, &camera, viewport, &PrepareOptions::default()) {
        Ok(v) => v,
        Err(e) => {
            soft_finding(target, "prepare", input, &e.to_string());
            return;
        }
    };
    if let Err(e) = obscura::render(Algorithm::ZBuffer, &view, &Default::default()) {
        soft_finding(target, "render", input, &e.to_string());
    }
}
