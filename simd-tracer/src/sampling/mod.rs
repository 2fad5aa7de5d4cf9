//! Random numbers and sampling.

pub mod distribution;
pub mod rng;
