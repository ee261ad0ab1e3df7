//! A mesh already in memory (as an engine or NumPy holds it) rendered through a camera
//! given as pinhole intrinsics, the way vision and robotics code describes cameras.
//!
//! ```text
//! cargo run --release -p obscura --example from_arrays
//! ```

use glam::DVec3;
use obscura::scene::{Faces, Intrinsics};
use obscura::{Algorithm, BACKGROUND, Camera, PrepareOptions, Scene, prepare, render};

fn main() -> Result<(), obscura::Error> {
    // A square pyramid: four triangles and a square base (polygons in CSR form).
    let positions = [
        [-1.0, 0.0, -1.0],
        [1.0, 0.0, -1.0],
        [1.0, 0.0, 1.0],
        [-1.0, 0.0, 1.0],
        [0.0, 1.5, 0.0],
    ];
    let offsets = [0, 3, 6, 9, 12, 16];
    let indices = [3, 2, 4, 2, 1, 4, 1, 0, 4, 0, 3, 4, 0, 1, 2, 3];
    let scene = Scene::from_arrays(
        &positions,
        Faces::Polygons {
            offsets: &offsets,
            indices: &indices,
        },
    )?;

    // A calibrated 640x480 camera, as a vision library reports it: focal lengths of
    // about 500 pixels, not quite equal, and a principal point a little off the image
    // centre (obscura puts pixel centres at half-integers: from OpenCV, add 0.5 to cx
    // and cy). The camera's lens holds both; it is placed by a look-at pose.
    let k = Intrinsics {
        fx: 502.3,
        fy: 498.7,
        cx: 318.2 + 0.5,
        cy: 243.9 + 0.5,
        width: 640,
        height: 480,
    };
    let pose = Camera::perspective(
        DVec3::new(2.0, 2.0, 4.0),
        DVec3::new(0.0, 0.5, 0.0),
        DVec3::Y,
        45.0,
        0.1,
        100.0,
    );
    let camera = Camera::from_intrinsics(pose.view_matrix(), &k, 0.1, 100.0)?;

    let view = prepare(&scene, &camera, k.viewport()?, &PrepareOptions::default())?;
    let (frame, _) = render(Algorithm::ZBuffer, &view, &Default::default())?;
    let mut seen = vec![0usize; scene.face_count() as usize];
    for &id in frame.ids.iter().filter(|&&id| id != BACKGROUND) {
        seen[id as usize] += 1;
    }
    for (face, pixels) in seen.iter().enumerate() {
        println!("face {face}: {pixels} pixels");
    }
    Ok(())
}
