//! Arbitrary bytes as an OpenEXR coefficient texture, read in memory.
//! The body is `fspec_cli::texture_file::fuzz_coefficient_exr`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/coefficient_exr`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::texture_file::fuzz_coefficient_exr(data);
});
