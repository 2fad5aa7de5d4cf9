//! Arbitrary bytes through the neural (SineMlp) weight loader and inference.
//! The body is `spectral_core::fuzzing::sine_mlp`, which
//! `spectral-core/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/sine_mlp`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    spectral_core::fuzzing::sine_mlp(data);
});
