//! Shading: per-triangle surface records, lights (and spot lights' cones),
//! microfacet maths and materials.

pub mod light;
pub mod light_sampler;
pub mod material;
pub mod microfacet;
pub mod spot_cone;
pub mod surface;
