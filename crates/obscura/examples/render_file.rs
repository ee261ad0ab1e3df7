//! A user's work with obscura: load a mesh file, set a camera, render, read the face id
//! and depth of a pixel, and write a shaded PNG and NumPy arrays of ids and depths.
//!
//! ```text
//! cargo run --release -p obscura --example render_file [-- MESH [OUT_DIR]]
//! ```
//!
//! Without MESH it writes a small OBJ (a box on a floor) into the system temp folder
//! and renders that. Outputs go to OUT_DIR (default: the temp folder):
//! `render.png`, `ids.npy` (int64, -1 for background) and `depth.npy` (float32,
//! eye-space distance, `inf` for background), which `numpy.load` reads.

use std::path::PathBuf;

use glam::DVec3;
use obscura::{Algorithm, BACKGROUND, Camera, PrepareOptions, Scene, Viewport, prepare, render};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out_dir = std::env::temp_dir();
    let mesh = match args.next() {
        Some(path) => PathBuf::from(path),
        None => {
            let path = out_dir.join("obscura-example-box.obj");
            std::fs::write(&path, BOX_ON_A_FLOOR)?;
            path
        }
    };
    let out_dir = args.next().map_or(out_dir, PathBuf::from);

    // Load: errors name the file and the line.
    let scene = Scene::load(&mesh)?;
    for warning in scene.report().warnings() {
        eprintln!("warning: {}: {warning}", mesh.display());
    }
    println!(
        "{}: {} objects, {} faces",
        mesh.display(),
        scene.objects().len(),
        scene.face_count()
    );

    // A camera: looking at the scene's centre from above and to the side, with near
    // and far fitted to its bounds.
    let viewport = Viewport::new(640, 480)?;
    let bounds = scene.bounds();
    let centre = (bounds.min + bounds.max) * 0.5;
    let size = (bounds.max - bounds.min).length().max(1e-6);
    let mut camera = Camera::perspective(
        centre + DVec3::new(1.0, 0.8, 1.5) * size,
        centre,
        DVec3::Y,
        45.0,
        0.01 * size,
        10.0 * size,
    );
    camera.fit_depth_range(&bounds);

    // Render with the z-buffer (any `Algorithm` gives the same ids).
    let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
    let (frame, _stats) = render(Algorithm::ZBuffer, &view, &Default::default())?;

    // Read ids and depths: one per pixel, row 0 at the top.
    let (x, y) = (viewport.width / 2, viewport.height / 2);
    let id = frame.id(x, y);
    if id == BACKGROUND {
        println!("pixel ({x}, {y}) shows the background");
    } else {
        let (object, local) = scene
            .locate_face(id)
            .expect("ids in a frame are the scene's");
        println!(
            "pixel ({x}, {y}) shows face {id} (object \"{}\", its face {local}) at depth {}",
            scene.objects()[object].name,
            frame.depth[frame.index(x, y)]
        );
    }
    println!(
        "{} of {} pixels show a face",
        frame.covered_pixels(),
        frame.ids.len()
    );

    // Write a shaded picture and the arrays.
    let png = out_dir.join("render.png");
    frame.shade(&scene, &camera).write_png(&png)?;
    frame.write_ids_npy(&out_dir.join("ids.npy"))?;
    frame.write_depth_npy(&out_dir.join("depth.npy"))?;
    println!("wrote {}, ids.npy and depth.npy there", png.display());
    Ok(())
}

/// A unit box standing on a 4x4 floor, faces counter-clockwise seen from outside.
const BOX_ON_A_FLOOR: &str = "\
o floor
v -2 0 -2
v 2 0 -2
v 2 0 2
v -2 0 2
f 1 4 3 2
o box
v -0.5 0 -0.5
v 0.5 0 -0.5
v 0.5 1 -0.5
v -0.5 1 -0.5
v -0.5 0 0.5
v 0.5 0 0.5
v 0.5 1 0.5
v -0.5 1 0.5
f 5 8 7 6
f 9 10 11 12
f 5 6 10 9
f 8 12 11 7
f 5 9 12 8
f 6 7 11 10
";
