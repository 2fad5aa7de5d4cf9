//! # simd-tracer
//!
//! An 8-wide packet path tracer built on `spectral-core`: a scene (triangle
//! meshes, materials, lights, camera) in, a per-pixel image buffer out, with
//! light carried as Fourier coefficients, sampled wavelengths, or both as
//! control variates. See `ARCHITECTURE.md` for the layout (one module per
//! stage) and the data flow.
//!
//! ```text
//! scene::Scene -> render (tiles) -> packet::RayPacket (8 rays, f32x8)
//!   -> integrator (groups of packets) -> accel::Bvh -> PacketHit
//!   -> shading::surface records (normal, emission, light pdf, albedo; 8-wide)
//!   -> shading::material BSDF eval/sample (8-wide for Lambert packets, else per lane)
//!   -> transport (FourierSpectrum<f32x8, N> products)
//!   -> NEE + MIS -> film (coefficients or XYZ per pixel) -> XYZ image
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
