//! What the measuring programs (`zbuffer_bounds`, `scanline_bounds`: benches without a
//! harness) share: the scene and view they measure, from their
//! command line `[SCENE [RUNS]]`.

use glam::DVec3;
use obscura::{Camera, Scene, Viewport};

/// The scene measured, its camera, a 1920x1080 viewport and the number of runs.
pub struct Measured {
    pub path: String,
    pub scene: Scene,
    pub camera: Camera,
    pub viewport: Viewport,
    pub runs: usize,
}

/// SCENE (default `shared/data/sponza.obj` beside the checkout, as the other benches
/// find it; a relative SCENE is taken from `crates/obscura`, where `cargo bench` runs; seen from the atrium camera of that
/// folder's README; any other scene from its default camera) and RUNS (default
/// `default_runs`) from the command line.
pub fn from_args(default_runs: usize) -> Result<Measured, Box<dyn std::error::Error>> {
    // `cargo bench` passes `--bench` to a bench without a harness; it is not SCENE.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let path = args.first().cloned().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/sponza.obj"
        )
        .into()
    });
    let runs: usize = args.get(1).map_or(Ok(default_runs), |s| s.parse())?;
    let scene = Scene::load(&path)?;
    let viewport = Viewport::new(1920, 1080)?;
    let camera = if path.ends_with("sponza.obj") {
        let mut c = Camera::perspective(
            DVec3::new(0.0, -10.0, 2.0),
            DVec3::new(0.0, 10.0, 4.0),
            DVec3::Z,
            60.0,
            0.1,
            100.0,
        );
        c.fit_depth_range(&scene.bounds());
        c
    } else {
        scene.default_camera(viewport.aspect())
    };
    Ok(Measured {
        path,
        scene,
        camera,
        viewport,
        runs,
    })
}
