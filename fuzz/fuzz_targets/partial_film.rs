//! Arbitrary bytes as a partial film (`.fspart`), parsed in memory. The body
//! is `fspec_cli::partial_file::fuzz_partial_film`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/partial_film`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::partial_file::fuzz_partial_film(data);
});
