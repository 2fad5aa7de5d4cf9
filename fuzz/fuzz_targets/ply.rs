//! Arbitrary bytes through the tracer's PLY mesh parser.
//! The body is `simd_tracer::fuzzing::ply`, which
//! `simd-tracer/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/ply`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    simd_tracer::fuzzing::ply(data);
});
