#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = obscura_fuzz::temp_dir("gltf");
    // .glb when it starts with the magic, else .gltf: the loader decides by content.
    let name = if data.starts_with(b"glTF") { "fuzz.glb" } else { "fuzz.gltf" };
    let path = dir.join(name);
    if let Ok(loaded) = obscura::scene::load::gltf::load(&path, data) {
        obscura_fuzz::check_loaded("gltf", data, loaded);
    }
});
