//! # simd-tracer
//!
//! An 8-wide packet path tracer built on `spectral-core`: a scene (triangle
//! meshes, materials, lights, camera) in, a per-pixel image buffer out, with
//! light carried as Fourier coefficients, sampled wavelengths, or both as
//! control variates. See `ARCHITECTURE.md` for the data flow.

pub mod bvh;
pub mod packet;

pub use spectral_core;
