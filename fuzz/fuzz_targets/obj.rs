#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = obscura_fuzz::temp_dir("obj");
    let path = dir.join("fuzz.obj");
    if let Ok(loaded) = obscura::scene::load::obj::load(&path, data) {
        obscura_fuzz::check_loaded("obj", data, loaded);
    }
});
