#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let mut warnings = Vec::new();
    let mats = obscura::scene::load::mtl::parse(std::path::Path::new("fuzz.mtl"), &text, &mut warnings);
    for (name, c) in &mats {
        assert!(
            c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
            "material {name:?} has colour {c:?} outside 0..=1"
        );
    }
});
