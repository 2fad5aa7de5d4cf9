//! Arbitrary bytes as the manifest of `fspec experiment equal-time`. The
//! body is `fspec_cli::experiment::equal_time::fuzz_manifest`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/equal_time_manifest`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::experiment::equal_time::fuzz_manifest(data);
});
