//! Shading: per-triangle surface records, lights, microfacet maths and materials.

pub mod light;
pub mod light_sampler;
pub mod material;
pub mod microfacet;
pub mod surface;
