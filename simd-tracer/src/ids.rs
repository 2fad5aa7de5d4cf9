//! Indices into a scene's tables and the sentinels that mean "none".
//!
//! A leaf module: every stage (scene, tree, shading, transport) names
//! spectra, materials and triangles by these indices, so they live below
//! all of them and no stage imports another just for an index type.

/// Index of a spectrum in the scene's spectra ([`crate::scene::Scene::spectra`]).
pub type SpectrumId = u32;
/// Index of a material in the scene's materials ([`crate::scene::Scene::materials`]).
pub type MaterialId = u32;
/// Index of an angular spectrum in [`crate::scene::Scene::angular`].
pub type AngularId = u32;
/// Index of a texture in [`crate::scene::Scene::textures`].
pub type TextureId = u32;

/// "None" for the id fields of a shading record
/// ([`crate::shading::surface::Surface`]): no material, no emission.
pub const NO_ID: u32 = u32::MAX;

/// Triangle index of packet lanes that hit nothing.
pub const NO_TRIANGLE: u32 = u32::MAX;
