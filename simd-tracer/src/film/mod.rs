//! The film: pixel filters (and, per transport, the pixel accumulators).

pub mod filter;
