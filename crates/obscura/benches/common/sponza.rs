//! Sponza for the benches that measure it beside other scenes: its file (`$SPONZA`, else
//! `shared/data/sponza.obj` beside the checkout) seen from the atrium camera of the
//! README (the one `common::from_args` uses for the measuring programs).

use glam::DVec3;
use obscura::{Camera, Scene};

/// The scene and its atrium camera, or the path that held no scene.
pub fn atrium() -> Result<(Scene, Camera), String> {
    let path = std::env::var("SPONZA").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/sponza.obj"
        )
        .to_string()
    });
    let scene = Scene::load(&path).map_err(|_| path)?;
    let mut camera = Camera::perspective(
        DVec3::new(0.0, -10.0, 2.0),
        DVec3::new(0.0, 10.0, 4.0),
        DVec3::Z,
        60.0,
        0.1,
        100.0,
    );
    camera.fit_depth_range(&scene.bounds());
    Ok((scene, camera))
}
