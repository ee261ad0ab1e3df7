#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();

/// A scene directory with a few small meshes the fuzzed scene file may reference.
fn dir() -> &'static std::path::PathBuf {
    DIR.get_or_init(|| {
        let d = obscura_fuzz::temp_dir("toml");
        std::fs::write(
            d.join("cube.obj"),
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
             f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
        )
        .unwrap();
        std::fs::write(
            d.join("tri.ply"),
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        )
        .unwrap();
        std::fs::write(
            d.join("tri.stl"),
            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
        )
        .unwrap();
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let path = dir().join("scene.toml");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(scene) = obscura::scene::load::toml_scene::load(&path) {
        obscura_fuzz::check_scene("toml_scene", data, &scene);
    }
});
