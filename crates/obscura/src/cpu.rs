//! Processor features: the crate's only proof that vector instructions exist.
//!
//! Code compiled with `#[target_feature(enable = ...)]` is undefined behaviour on a
//! processor (or a hypervisor's virtual processor) that lacks any one of the enabled
//! features, even one the code never seems to use: the compiler may emit it anywhere.
//! So the crate has one token type per instruction set, [`Avx2`] and [`Avx512`], whose
//! only constructor checks, at run time, every feature in the token's `FEATURES` list,
//! and every `#[target_feature(enable = "...")]` in the crate (and its examples) enables
//! exactly one token's list and takes that token as an argument (or `self`), so it
//! cannot be called without the check having passed. A unit test reads the sources
//! and fails on any enable list that is not a token's list, or on a function that does
//! not take the token.
//!
//! Each list is written once, in the macro that defines the token: the same literals
//! feed `FEATURES` and the run-time checks, so they cannot drift apart.
//!
//! [`Kernel`] names the compiled variants a caller can ask for (the z-buffer's drawing,
//! the BVH's single-ray and packet traversals): one enum for the crate, whose
//! [`Kernel::avx512`] and [`Kernel::avx2`] hand out the tokens a request allows on this
//! processor. Every variant gives the same result bit for bit; they differ in speed.
//!
//! [`simd_test_skipped`] is for tests that compare a vector kernel with its portable
//! twin: it reports the skip and, with `OBSCURA_REQUIRE_SIMD=1` in the environment,
//! turns it into a failure.
//!
//! Source: *The Rust Reference*, "The `target_feature` attribute" (calling such a
//! function on a processor without the features is undefined behaviour).

/// Defines a token type whose `new` checks every listed feature.
macro_rules! token {
    ($(#[$doc:meta])* $name:ident: $($feature:tt),+) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug)]
        pub struct $name {
            _proof: (),
        }

        impl $name {
            /// Every feature the run-time check requires, as written in the
            /// `#[target_feature(enable = "...")]` of the functions that take this token.
            pub const FEATURES: &'static [&'static str] = &[$($feature),+];

            /// The token, if this processor has every feature of [`Self::FEATURES`].
            #[must_use]
            #[inline]
            pub fn new() -> Option<Self> {
                #[cfg(target_arch = "x86_64")]
                {
                    (true $(&& std::arch::is_x86_feature_detected!($feature))+)
                        .then_some($name { _proof: () })
                }
                #[cfg(not(target_arch = "x86_64"))]
                {
                    None
                }
            }

            /// Whether this processor has every feature of [`Self::FEATURES`].
            #[must_use]
            pub fn is_available() -> bool {
                Self::new().is_some()
            }
        }
    };
}

token! {
    /// AVX2 (x86-64): the portable code compiled for 256-bit vectors. A value exists only
    /// on a processor that has it.
    Avx2: "avx2"
}

token! {
    /// AVX-512 F, VL, BW and DQ (x86-64), with AVX2 and the bit-manipulation
    /// instructions (POPCNT, BMI1, BMI2, LZCNT) the AVX-512 kernels are compiled with.
    /// A value exists only on a processor that reports every one of them.
    Avx512: "avx2", "avx512f", "avx512vl", "avx512bw", "avx512dq", "popcnt", "bmi1", "bmi2", "lzcnt"
}

impl Avx512 {
    /// AVX2, which every processor with this token has (it is in [`Avx512::FEATURES`]).
    #[must_use]
    pub fn avx2(self) -> Avx2 {
        Avx2 { _proof: () }
    }
}

/// Which compiled variant of a kernel to run: every variant runs the same operations in
/// the same order, so they give the same results bit for bit (the tests compare them).
/// A variant this processor lacks falls back to the best one below it that it has
/// ([`Kernel::resolve`]); [`Kernel::Auto`] is the best it has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// The fastest this processor runs ([`Kernel::detect`]).
    #[default]
    Auto,
    /// Baseline instructions of the target (SSE2 on x86-64); always available.
    Portable,
    /// The portable code compiled for x86-64 with AVX2 (the compiler vectorizes it).
    Avx2,
    /// AVX-512 F, VL, BW and DQ (the crate's `Avx512` token): the hand-written lanes of the
    /// rasterizer and of the BVH's packets; code without such lanes (single rays) runs
    /// its AVX2 build.
    Avx512,
}

impl Kernel {
    /// The fastest kernel this processor runs (never [`Kernel::Auto`]).
    #[must_use]
    pub fn detect() -> Kernel {
        if Avx512::is_available() {
            Kernel::Avx512
        } else if Avx2::is_available() {
            Kernel::Avx2
        } else {
            Kernel::Portable
        }
    }

    /// Whether this processor runs the kernel itself, without falling back.
    #[must_use]
    pub fn is_available(self) -> bool {
        match self {
            Kernel::Auto | Kernel::Portable => true,
            Kernel::Avx2 => Avx2::is_available(),
            Kernel::Avx512 => Avx512::is_available(),
        }
    }

    /// The kernel that runs for this request on this processor: the request if the
    /// processor has it, else the best one below it that it has (never
    /// [`Kernel::Auto`]).
    #[must_use]
    pub fn resolve(self) -> Kernel {
        match self {
            Kernel::Auto => Kernel::detect(),
            Kernel::Avx512 if Avx512::is_available() => Kernel::Avx512,
            Kernel::Avx512 | Kernel::Avx2 if Avx2::is_available() => Kernel::Avx2,
            _ => Kernel::Portable,
        }
    }

    /// The AVX-512 token, when the request allows AVX-512 ([`Kernel::Auto`],
    /// [`Kernel::Avx512`]) and this processor has it.
    #[must_use]
    #[inline]
    pub fn avx512(self) -> Option<Avx512> {
        match self {
            Kernel::Auto | Kernel::Avx512 => Avx512::new(),
            Kernel::Portable | Kernel::Avx2 => None,
        }
    }

    /// The AVX2 token, when the request allows AVX2 (anything but
    /// [`Kernel::Portable`]) and this processor has it.
    #[must_use]
    #[inline]
    pub fn avx2(self) -> Option<Avx2> {
        match self {
            Kernel::Portable => None,
            Kernel::Auto | Kernel::Avx2 | Kernel::Avx512 => Avx2::new(),
        }
    }
}

/// The environment variable that turns a skipped SIMD comparison into a failure.
#[cfg(test)]
pub const REQUIRE_SIMD_VAR: &str = "OBSCURA_REQUIRE_SIMD";

#[cfg(test)]
/// For tests: reports that the comparison `what` of a vector kernel with its portable
/// twin was skipped because this processor lacks `kernel`'s instructions.
///
/// # Panics
///
/// When [`REQUIRE_SIMD_VAR`] is set to a non-empty value other than `0`: a machine
/// that must test the kernels (CI on a known processor) fails instead of skipping.
pub fn simd_test_skipped(kernel: &str, what: &str) {
    let required = std::env::var(REQUIRE_SIMD_VAR).is_ok_and(|v| !v.is_empty() && v != "0");
    assert!(
        !required,
        "{what}: this processor lacks {kernel}, and {REQUIRE_SIMD_VAR} requires the comparison"
    );
    eprintln!(
        "SKIPPED {what}: this processor lacks {kernel} (set {REQUIRE_SIMD_VAR}=1 to fail instead)"
    );
}

#[cfg(test)]
mod tests {
    use super::{Avx2, Avx512, Kernel};

    #[test]
    fn a_kernel_falls_back_to_the_best_below_it_that_the_processor_has() {
        let (avx2, avx512) = (Avx2::is_available(), Avx512::is_available());
        let below_avx512 = if avx2 { Kernel::Avx2 } else { Kernel::Portable };
        let best = if avx512 { Kernel::Avx512 } else { below_avx512 };
        assert_eq!(Kernel::detect(), best);
        assert_eq!(Kernel::Auto.resolve(), best);
        assert_eq!(Kernel::Portable.resolve(), Kernel::Portable);
        assert_eq!(Kernel::Avx2.resolve(), below_avx512);
        assert_eq!(Kernel::Avx512.resolve(), best);
        assert_eq!(Kernel::default(), Kernel::Auto);
        // The tokens each request hands out.
        for k in [Kernel::Auto, Kernel::Portable, Kernel::Avx2, Kernel::Avx512] {
            let r = k.resolve();
            assert_eq!(k.avx512().is_some(), r == Kernel::Avx512, "{k:?}");
            assert_eq!(k.avx2().is_some(), r != Kernel::Portable, "{k:?}");
            assert!(r.is_available(), "{k:?} resolves to {r:?}");
        }
    }

    /// The sources that contain `#[target_feature]`, with their names.
    const SOURCES: &[(&str, &str)] = &[
        (
            "raster/block/tests.rs",
            include_str!("raster/block/tests.rs"),
        ),
        (
            "surface/zbuffer/fast.rs",
            include_str!("surface/zbuffer/fast.rs"),
        ),
        (
            "accel/bvh/packet_lanes.rs",
            include_str!("accel/bvh/packet_lanes.rs"),
        ),
        ("accel/bvh/packet.rs", include_str!("accel/bvh/packet.rs")),
        (
            "accel/bvh/ray_packet.rs",
            include_str!("accel/bvh/ray_packet.rs"),
        ),
        (
            "accel/bvh/traverse.rs",
            include_str!("accel/bvh/traverse.rs"),
        ),
        (
            "surface/image/resolve.rs",
            include_str!("surface/image/resolve.rs"),
        ),
        ("view/passes.rs", include_str!("view/passes.rs")),
        ("bench_support.rs", include_str!("bench_support.rs")),
        (
            "cull/buffer/masked.rs",
            include_str!("cull/buffer/masked.rs"),
        ),
        ("cull/buffer/hiz.rs", include_str!("cull/buffer/hiz.rs")),
    ];

    /// Every `#[target_feature(enable = "...")]` in `src`: its features, and the
    /// function signature that follows (up to its body).
    fn enables(src: &str) -> Vec<(Vec<String>, String)> {
        const ATTR: &str = "#[target_feature(enable = \"";
        let mut out = Vec::new();
        let mut rest = src;
        while let Some(at) = rest.find(ATTR) {
            rest = &rest[at + ATTR.len()..];
            let end = rest.find('"').expect("a closing quote");
            let features = rest[..end]
                .split(',')
                .map(|f| f.trim().to_owned())
                .collect();
            let body = rest.find('{').expect("a function body");
            out.push((features, rest[end..body].to_owned()));
        }
        out
    }

    /// Whether `signature` takes a value of the token type `name` (as an argument or
    /// as `self` of an impl on it).
    fn takes(signature: &str, name: &str) -> bool {
        signature.contains(&format!(": {name}"))
            || signature.contains(&format!("::{name},"))
            || signature.contains(&format!("::{name})"))
    }

    #[test]
    fn every_enabled_feature_list_is_a_checked_token_and_the_function_takes_it() {
        let tokens = [("Avx2", Avx2::FEATURES), ("Avx512", Avx512::FEATURES)];
        let mut seen = 0;
        for (file, src) in SOURCES {
            // Files that use the attribute under another spelling would escape the test.
            assert_eq!(
                src.matches("target_feature(").count(),
                src.matches("#[target_feature(enable = \"").count(),
                "{file}: every target_feature attribute is written as #[target_feature(enable = \"...\")]"
            );
            for (features, signature) in enables(src) {
                seen += 1;
                let Some((name, _)) = tokens.iter().find(|(_, list)| {
                    list.len() == features.len()
                        && list.iter().all(|f| features.contains(&(*f).to_owned()))
                }) else {
                    panic!(
                        "{file}: #[target_feature(enable = {features:?})] is not the list of a \
                         token of crate::cpu ({tokens:?}); its callers' check would not cover it"
                    );
                };
                assert!(
                    takes(&signature, name),
                    "{file}: the function after #[target_feature(enable = {features:?})] does \
                     not take a cpu::{name} token: {signature}"
                );
            }
        }
        assert!(
            seen >= 15,
            "{seen} target_feature attributes found: the scan broke"
        );
    }

    #[test]
    fn every_source_with_target_feature_is_scanned() {
        // A new file with #[target_feature] must join SOURCES: list the crate's files
        // that the lib and its examples could hold, by searching the known directories.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut found = Vec::new();
        let mut dirs = vec![root.join("src"), root.join("examples")];
        while let Some(dir) = dirs.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    dirs.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    if text.contains("#[target_feature(") && !path.ends_with("cpu.rs") {
                        let rel = path
                            .strip_prefix(root.join("src"))
                            .unwrap_or_else(|_| path.strip_prefix(root).unwrap());
                        found.push(rel.to_string_lossy().replace('\\', "/"));
                    }
                }
            }
        }
        for file in &found {
            assert!(
                SOURCES.iter().any(|(name, _)| name == file),
                "{file} uses #[target_feature] but is not in cpu::tests::SOURCES"
            );
        }
        for (name, src) in SOURCES {
            assert!(
                !enables(src).is_empty(),
                "{name} has no #[target_feature]: drop it from SOURCES"
            );
        }
    }

    #[test]
    fn the_scan_finds_what_it_must_refuse() {
        // The test above must be able to fail: a list that is no token's, and a
        // function that does not take the token.
        let bad = "#[target_feature(enable = \"avx2,popcnt\")]\nfn f(x: u8) {}";
        let (features, _) = &enables(bad)[0];
        assert!(
            ![Avx2::FEATURES, Avx512::FEATURES]
                .iter()
                .any(|l| l.len() == features.len()
                    && l.iter().all(|f| features.contains(&(*f).to_owned())))
        );
        let untaken = "#[target_feature(enable = \"avx2\")]\nfn f(x: u8) {}";
        assert!(!takes(&enables(untaken)[0].1, "Avx2"));
        let taken = "#[target_feature(enable = \"avx2\")]\nfn f(_: Avx2, x: u8) {}";
        assert!(takes(&enables(taken)[0].1, "Avx2"));
    }
}
