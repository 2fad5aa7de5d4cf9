//! Random numbers and sampling.

pub mod cone;
pub mod disk;
pub mod distribution;
pub mod rng;
pub mod sampler;
pub mod sobol;
