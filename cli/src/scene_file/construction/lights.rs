//! Lights that are not emissive surfaces: point, spot and directional
//! lights (delta lights with an intensity or irradiance spectrum and a
//! scale; a spot's cone is `simd_tracer::shading::spot_cone`),
//! and equirectangular environment maps (RGBE, OpenEXR or PNG images of
//! linear radiance, upsampled per texel as RGB illuminants:
//! `simd_tracer::spectra::environment`; spectral OpenEXRs and coefficient
//! OpenEXRs as spectral maps, `crate::spectral_image`).

use super::Construction;
use crate::error::CliError;
use crate::hdr_image::load_rgb_image;
use crate::scene_file::source::Spot;
use crate::spectral_image::load_environment_coefficients;
use glam::{Mat3, Vec3};
use simd_tracer::ids::SpectrumId;
use simd_tracer::shading::light_sampler::{DirectionalLight, PointLight};
use simd_tracer::shading::spot_cone::SpotCone;
use simd_tracer::spectra::environment::{
    EnvironmentImage, EnvironmentMap, SpectralEnvironmentImage,
};
use std::path::Path;

/// What an environment map is made of.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MapSettings<'a> {
    /// The image file.
    pub(crate) path: &'a Path,
    /// Multiplier of the radiance.
    pub(crate) scale: f32,
    /// Local to world (a rotation).
    pub(crate) to_world: Mat3,
}

impl Construction<'_> {
    /// Adds a point light.
    pub(crate) fn point_light(&mut self, position: Vec3, intensity: SpectrumId, scale: f32) {
        self.builder.add_point_light(PointLight {
            position,
            intensity,
            scale,
            cone: None,
        });
        self.lights += 1;
    }

    /// Adds a spot light at `position` with its cone.
    pub(crate) fn spot_light(
        &mut self,
        position: Vec3,
        emission: (SpectrumId, f32),
        cone: SpotCone,
    ) {
        let (intensity, scale) = emission;
        self.builder.add_point_light(PointLight {
            position,
            intensity,
            scale,
            cone: Some(cone),
        });
        self.lights += 1;
    }

    /// Adds a directional light travelling along `direction` (refused at
    /// `at` when it has zero length).
    pub(crate) fn directional_light(
        &mut self,
        at: &Spot,
        direction: Vec3,
        irradiance: SpectrumId,
        scale: f32,
    ) -> Result<(), CliError> {
        let direction = direction
            .try_normalize()
            .ok_or_else(|| self.src.error_at(at, "the direction has zero length"))?;
        self.builder.add_directional_light(DirectionalLight {
            direction,
            irradiance,
            scale,
        });
        self.lights += 1;
        Ok(())
    }

    /// Loads and sets an environment map (errors and the clamping warning
    /// at `at`).
    pub(crate) fn environment_map(
        &mut self,
        at: &Spot,
        settings: &MapSettings<'_>,
    ) -> Result<(), CliError> {
        if let Some(texels) = load_environment_coefficients(settings.path, &self.range)
            .map_err(|e| self.src.error_at(at, e))?
        {
            let map = EnvironmentMap::spectral(
                &SpectralEnvironmentImage {
                    width: texels.width,
                    height: texels.height,
                    n: texels.n,
                    coeffs: &texels.coeffs,
                    luminance: &texels.luminance,
                    scale: settings.scale,
                    to_world: settings.to_world,
                },
                self.range,
            )
            .map_err(|e| {
                self.src
                    .error_at(at, format!("{}: {e}", settings.path.display()))
            })?;
            self.builder.set_environment_map(map);
            self.has_environment = true;
            return Ok(());
        }
        let image = load_rgb_image(settings.path).map_err(|e| self.src.error_at(at, e))?;
        if image.negative_clamped > 0 {
            self.warn(
                at,
                format!(
                    "{}: {} negative texel value(s) clamped to 0",
                    settings.path.display(),
                    image.negative_clamped
                ),
            );
        }
        let map = EnvironmentMap::new(
            &EnvironmentImage {
                width: image.width,
                height: image.height,
                rgb: &image.texels,
                scale: settings.scale,
                to_world: settings.to_world,
            },
            self.range,
        )
        .map_err(|e| {
            self.src
                .error_at(at, format!("{}: {e}", settings.path.display()))
        })?;
        self.builder.set_environment_map(map);
        self.has_environment = true;
        Ok(())
    }
}
