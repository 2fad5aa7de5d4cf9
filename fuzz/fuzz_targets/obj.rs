//! Arbitrary OBJ and MTL text through the tracer's OBJ loader and the scene build.
//! The body is `simd_tracer::fuzzing::obj`, which
//! `simd-tracer/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/obj`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    simd_tracer::fuzzing::obj(data);
});
