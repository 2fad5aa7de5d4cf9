//! # simd-tracer
//!
//! The packet path tracer of the project (issue 4). Until it lands this crate
//! only re-exports the spectral core it will be built on.

pub use spectral_core;
