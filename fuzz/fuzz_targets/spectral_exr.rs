//! Arbitrary bytes as a spectral OpenEXR (Fichet et al. 2021), read in
//! memory as emissive and as reflective channels and projected. The body
//! is `fspec_cli::spectral_image::fuzz_spectral_exr`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/spectral_exr`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::spectral_image::fuzz_spectral_exr(data);
});
