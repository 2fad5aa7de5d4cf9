//! MESE and bounded MESE from arbitrary finite coefficients.
//! The body is `spectral_core::fuzzing::mese`, which
//! `spectral-core/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/mese`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    spectral_core::fuzzing::mese(data);
});
