//! Arbitrary bytes as a Mitsuba 3 XML scene file (file references
//! refused), strict and `--lenient`, then the scene build. The body is
//! `fspec_cli::scene_file::fuzz_scene_xml`, which `cli/tests/fuzz_corpus.rs`
//! also replays over `fuzz/corpus/scene_xml`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::scene_file::fuzz_scene_xml(data);
});
