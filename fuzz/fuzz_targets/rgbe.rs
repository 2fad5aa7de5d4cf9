//! Arbitrary bytes as a Radiance RGBE (`.hdr`) file, parsed in memory.
//! The body is `fspec_cli::hdr_image::fuzz_rgbe`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/rgbe`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::hdr_image::fuzz_rgbe(data);
});
