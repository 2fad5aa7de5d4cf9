//! Emitters as Mitsuba 3.9.1 defines them (`src/emitters/*.cpp`).
//!
//! * `area` (inside a shape): `radiance`, emitted from the front face only
//!   (where the shape's normals point).
//! * `constant`: `radiance` from every direction.
//! * `envmap`: `filename` (OpenEXR, Radiance RGBE; linear RGB radiance),
//!   `scale` (1), `to_world` (a rotation); the lookup conventions are
//!   `simd_tracer::spectra::environment`'s.
//! * `point`: `intensity` (W/sr), at `position` or at `to_world`'s origin.
//! * `spot`: `intensity` (W/sr, at the centre of the cone), `cutoff_angle`
//!   (20°), `beam_width` (¾ of the cutoff), at `to_world`'s origin and
//!   along its local `+z` (`src/emitters/spot.cpp`; the profile is
//!   `simd_tracer::shading::spot_cone`'s). No projection `texture`.
//! * `directional`: `irradiance` (W/m²), travelling along `direction` or
//!   along `to_world`'s local `+z`.
//!
//! The radiance spectra are read as emission (`spectra`: `<rgb>` is an RGB
//! illuminant, a uniform value a multiple of D65); their defaults are 1.
//! One environment (constant or map) per scene. Unsupported emitters are
//! errors, skipped with `--lenient`.

use super::Importer;
use super::document::Element;
use super::properties::Object;
use super::spectra::{SpectrumUse, d65_times};
use crate::error::CliError;
use crate::scene_file::construction::MapSettings;
use glam::{Mat3, Vec3};
use simd_tracer::ids::SpectrumId;
use simd_tracer::shading::spot_cone::{SpotCone, SpotConeSettings};

/// Mitsuba's default emitted quantity (radiance, intensity, irradiance).
const DEFAULT_EMISSION: f64 = 1.0;

/// `spot`'s default cutoff angle in degrees (`src/emitters/spot.cpp`).
const SPOT_DEFAULT_CUTOFF_DEG: f64 = 20.0;

/// `spot`'s default beam width as a share of its cutoff angle (ibid.).
const SPOT_DEFAULT_BEAM_SHARE: f64 = 0.75;

impl<'e> Importer<'e, '_> {
    /// The radiance of an `area` emitter nested in a shape.
    pub(super) fn area_emission(&mut self, e: &'e Element) -> Result<Option<SpectrumId>, CliError> {
        let object = Object::new(e)?;
        if object.plugin != "area" {
            self.unsupported(e, "the emitter is skipped")?;
            return Ok(None);
        }
        let radiance = self.spectrum_id(
            &object,
            "radiance",
            SpectrumUse::Emission,
            d65_times(DEFAULT_EMISSION),
        )?;
        self.check_unused(&object)?;
        Ok(Some(radiance))
    }

    /// A top-level `<emitter>`.
    pub(super) fn emitter(&mut self, e: &'e Element) -> Result<(), CliError> {
        let object = Object::new(e)?;
        let spot = Self::spot(e, object.describe());
        let default = d65_times(DEFAULT_EMISSION);
        match object.plugin {
            "constant" => {
                self.one_environment(&object)?;
                let radiance =
                    self.spectrum_id(&object, "radiance", SpectrumUse::Emission, default)?;
                self.cx.set_environment(radiance);
            }
            "envmap" => {
                self.one_environment(&object)?;
                let path = object.filename()?;
                let scale = object.float("scale", 1.0)?;
                if scale < 0.0 {
                    return Err(object.error(format!("scale {scale}: must be >= 0")));
                }
                let to_world = object.transform("to_world")?;
                let m = to_world.affine().matrix3;
                let settings = MapSettings {
                    path: &path,
                    scale: scale as f32,
                    to_world: Mat3::from_cols(m.x_axis.into(), m.y_axis.into(), m.z_axis.into()),
                };
                self.cx.environment_map(&spot, &settings)?;
            }
            "point" => {
                let intensity =
                    self.spectrum_id(&object, "intensity", SpectrumUse::Emission, default)?;
                let position = match object.vector("position")? {
                    Some(p) => {
                        if object.get("to_world").is_some() {
                            return Err(object.error("give `position` or `to_world`, not both"));
                        }
                        p
                    }
                    None => object.transform("to_world")?.point(Vec3::ZERO),
                };
                self.cx.point_light(position, intensity, 1.0);
            }
            "spot" => {
                let intensity =
                    self.spectrum_id(&object, "intensity", SpectrumUse::Emission, default)?;
                let to_world = object.transform("to_world")?;
                let m = to_world.affine().matrix3;
                let local_to_world =
                    Mat3::from_cols(m.x_axis.into(), m.y_axis.into(), m.z_axis.into());
                let cutoff_deg = object.float("cutoff_angle", SPOT_DEFAULT_CUTOFF_DEG)?;
                let beam_width_deg =
                    object.float("beam_width", SPOT_DEFAULT_BEAM_SHARE * cutoff_deg)?;
                let cone = SpotCone::new(&SpotConeSettings {
                    world_to_local: local_to_world.inverse(),
                    cutoff_deg,
                    beam_width_deg,
                })
                .map_err(|e| object.error(e))?;
                self.cx
                    .spot_light(to_world.point(Vec3::ZERO), (intensity, 1.0), cone);
            }
            "directional" => {
                let irradiance =
                    self.spectrum_id(&object, "irradiance", SpectrumUse::Emission, default)?;
                let direction = match object.vector("direction")? {
                    Some(d) => {
                        if object.get("to_world").is_some() {
                            return Err(object.error("give `direction` or `to_world`, not both"));
                        }
                        d
                    }
                    None => object.transform("to_world")?.vector(Vec3::Z),
                };
                self.cx
                    .directional_light(&spot, direction, irradiance, 1.0)?;
            }
            // Referenced from shapes (`<ref id>`); built there.
            "area" if e.attr("id").is_some() => return Ok(()),
            "area" => {
                return Err(object.error("an area emitter belongs inside a <shape>"));
            }
            _ => {
                self.unsupported(e, "the emitter is skipped")?;
                return Ok(());
            }
        }
        self.check_unused(&object)
    }

    /// Refuses a second environment.
    fn one_environment(&mut self, object: &Object<'e>) -> Result<(), CliError> {
        if self.environment_set {
            return Err(object.error(
                "a scene takes one environment emitter (constant or envmap); this is the second",
            ));
        }
        self.environment_set = true;
        Ok(())
    }
}
