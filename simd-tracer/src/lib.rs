//! # simd-tracer
//!
//! An 8-wide packet path tracer built on `spectral-core`: a scene (triangle
//! meshes, materials, lights, camera) in, a per-pixel image buffer out, with
//! light carried as Fourier coefficients, sampled wavelengths, or both as
//! control variates. See `ARCHITECTURE.md` for the data flow.
//!
//! ```text
//! Scene -> Bvh -> RayPacket (8 rays, f32x8) -> PacketHit
//!   -> Surface records (normal, emission, light pdf, albedo; 8-wide)
//!   -> BSDF eval/sample (8-wide for Lambert packets, else per lane)
//!   -> Transport (FourierSpectrum<f32x8, N> products)
//!   -> NEE + MIS -> Film (coefficients or XYZ per pixel) -> XYZ image
//! ```

pub mod accel;
pub mod film;
pub mod fuzzing;
pub mod ids;
pub mod integrator;
pub mod packet;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shading;
pub mod simd;
pub mod spectra;
pub mod transport;

pub use spectral_core;
