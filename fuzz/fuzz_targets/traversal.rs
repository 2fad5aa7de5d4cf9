//! Packet vs scalar BVH traversal on arbitrary triangles and rays.
//! The body is `simd_tracer::fuzzing::traversal`, which
//! `simd-tracer/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/traversal`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    simd_tracer::fuzzing::traversal(data);
});
