//! Arbitrary bytes through the camera-sensor CSV parser (`--sensor`). The
//! body is `fspec_cli::sensor_file::fuzz_sensor_csv`, which
//! `cli/tests/fuzz_corpus.rs` also replays over `fuzz/corpus/sensor_csv`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fspec_cli::sensor_file::fuzz_sensor_csv(data);
});
