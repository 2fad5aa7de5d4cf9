//! Arbitrary bytes through the tracer's Mitsuba serialized mesh parser,
//! every shape of the file's table. The body is
//! `simd_tracer::fuzzing::serialized`, which
//! `simd-tracer/tests/fuzz_corpus.rs` also replays over
//! `fuzz/corpus/serialized`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    simd_tracer::fuzzing::serialized(data);
});
