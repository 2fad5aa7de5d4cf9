//! Arbitrary bytes as an environment map or bitmap file (Radiance RGBE,
//! OpenEXR, PNG or JPEG, recognised by its first bytes), read in memory.
//! The body is `fspec_cli::hdr_image::fuzz_rgb_image`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/rgb_image`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::hdr_image::fuzz_rgb_image(data);
});
