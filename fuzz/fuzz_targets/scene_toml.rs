//! Arbitrary bytes as a TOML scene file (file references refused), then the scene build.
//! The body is `fspec_cli::scene_file::fuzz_scene_toml`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/scene_toml`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::scene_file::fuzz_scene_toml(data);
});
