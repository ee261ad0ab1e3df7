//! The scene file with references: the fuzzed bytes are the `scene.toml` of a small
//! folder that also holds fixed mesh files of every format (an OBJ with its MTL, ASCII
//! and binary STL, a glTF with its `.bin` buffer, a GLB, a PLY, a mesh in a subfolder
//! and a symbolic link to one), so references, the read-once cache, transforms,
//! instancing (one file placed many times) and primitives meet in one scene.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();

fn dir() -> &'static std::path::PathBuf {
    DIR.get_or_init(|| {
        let d = obscura_fuzz::temp_dir("toml-refs");
        obscura_fuzz::write_reference_meshes(&d);
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let path = dir().join("scene.toml");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(scene) = obscura::scene::load::toml_scene::load(&path) {
        for o in scene.objects() {
            assert!(
                o.transform.is_finite(),
                "non-finite transform of {:?}",
                o.name
            );
            assert!(
                o.mesh.positions().iter().all(|p| p.is_finite()),
                "non-finite position in {:?}",
                o.name
            );
        }
        obscura_fuzz::check_scene("toml_refs", data, &scene);
    }
});
