//! Arbitrary bytes through the CSV spectrum loader, projection and XYZ.
//! The body is `fspec_cli::spectrum_file::fuzz_csv_spectrum`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/csv_spectrum`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::spectrum_file::fuzz_csv_spectrum(data);
});
