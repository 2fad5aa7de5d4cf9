//! Random numbers and sampling.

pub mod rng;
