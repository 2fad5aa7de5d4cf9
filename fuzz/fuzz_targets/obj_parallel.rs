//! Arbitrary OBJ text through the parallel OBJ reader, checked against tobj.
//! The body is `simd_tracer::fuzzing::obj_parallel`, which
//! `simd-tracer/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/obj_parallel`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    simd_tracer::fuzzing::obj_parallel(data);
});
