//! Truncated products and every XYZ route on arbitrary finite coefficients.
//! The body is `spectral_core::fuzzing::product_and_xyz` (here with its
//! converter built once, through `product_and_xyz_with`), which
//! `spectral-core/tests/fuzz_corpus.rs` also replays over
//! `fuzz/corpus/product_xyz`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use spectral_core::FourierBasis;
use spectral_core::xyz::XyzConverter;
use std::sync::OnceLock;

static CONVERTER: OnceLock<Option<XyzConverter<12>>> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let converter = CONVERTER.get_or_init(|| XyzConverter::new(&FourierBasis::VISIBLE).ok());
    spectral_core::fuzzing::product_and_xyz_with(converter.as_ref(), data);
});
