#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-fuzz-dir/fuzz.stl");
    if let Ok(loaded) = obscura::scene::load::stl::load(path, data.to_vec()) {
        obscura_fuzz::check_loaded("stl", data, loaded);
    }
});
