//! Shading: per-triangle surface records, lights (spot lights' cones,
//! spherical lights' sampling),
//! microfacet maths and materials.

pub mod light;
pub mod light_sampler;
pub mod material;
pub mod microfacet;
pub mod sphere_light;
pub mod spot_cone;
pub mod surface;
