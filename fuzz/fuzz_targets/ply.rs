#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("/nonexistent-fuzz-dir/fuzz.ply");
    if let Ok(loaded) = obscura::scene::load::ply::load(path, data) {
        obscura_fuzz::check_loaded("ply", data, loaded);
    }
});
