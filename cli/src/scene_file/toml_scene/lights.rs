//! `[[lights]]`: point lights (`position`, `intensity`), spot lights
//! (`position`, `direction` or `target`, `intensity`, `cutoff_deg`,
//! `beam_width_deg`: Mitsuba 3's `spot`, whose defaults they take) and
//! directional lights (`direction`, `irradiance`), each spectrum a spectrum
//! reference with an optional `scale`.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::toml_reader::{Item, Table};
use glam::Mat3;
use simd_tracer::shading::spot_cone::{SpotCone, SpotConeError, SpotConeSettings};

/// A spot light's cutoff angle when none is given (Mitsuba 3's `spot`).
const DEFAULT_CUTOFF_DEG: f64 = 20.0;

/// A spot light's beam width as a share of its cutoff angle when none is
/// given (Mitsuba 3's `spot`: three quarters).
const DEFAULT_BEAM_SHARE: f64 = 0.75;

impl Loader<'_> {
    /// `[[lights]]` (module docs).
    pub(super) fn lights_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for light in item.array(&self.src)? {
            let table = light.table(&self.src)?;
            let kind_item =
                table.require(&self.src, "type", "\"point\", \"spot\" or \"directional\"")?;
            let kind = kind_item.string(&self.src)?;
            let scale = match table.get("scale") {
                Some(s) => s.non_negative(&self.src)? as f32,
                None => 1.0,
            };
            match kind {
                "point" => {
                    table.allow(
                        &self.src,
                        &["type", "position", "intensity", "scale"],
                        "a point light",
                    )?;
                    let position = table
                        .require(
                            &self.src,
                            "position",
                            "a point light needs `position = [x, y, z]`",
                        )?
                        .vec3(&self.src)?;
                    let spectrum = table.require(
                        &self.src,
                        "intensity",
                        "a point light needs `intensity` (a spectrum, W/(sr nm))",
                    )?;
                    let id = self.spectrum_ref(&spectrum, 1.0)?;
                    self.cx.point_light(position, id, scale);
                }
                "spot" => self.spot_light(&table, scale)?,
                "directional" => {
                    table.allow(
                        &self.src,
                        &["type", "direction", "irradiance", "scale"],
                        "a directional light",
                    )?;
                    let direction_item = table.require(
                        &self.src,
                        "direction",
                        "the direction the light travels in, [x, y, z]",
                    )?;
                    let direction = direction_item.vec3(&self.src)?;
                    let spectrum = table.require(
                        &self.src,
                        "irradiance",
                        "a directional light needs `irradiance` (a spectrum, W/(m² nm))",
                    )?;
                    let id = self.spectrum_ref(&spectrum, 1.0)?;
                    self.cx
                        .directional_light(&direction_item.spot(), direction, id, scale)?;
                }
                other => {
                    return Err(kind_item.err(
                        &self.src,
                        format!("unknown light type \"{other}\" (point, spot, directional)"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// A `type = "spot"` entry of `[[lights]]` with its `scale`.
    fn spot_light(&mut self, table: &Table<'_, '_>, scale: f32) -> Result<(), CliError> {
        table.allow(
            &self.src,
            &[
                "type",
                "position",
                "direction",
                "target",
                "intensity",
                "scale",
                "cutoff_deg",
                "beam_width_deg",
            ],
            "a spot light",
        )?;
        let position = table
            .require(
                &self.src,
                "position",
                "a spot light needs `position = [x, y, z]`",
            )?
            .vec3(&self.src)?;
        let (axis_item, axis) = match (table.get("direction"), table.get("target")) {
            (Some(d), None) => {
                let v = d.vec3(&self.src)?;
                (d, v)
            }
            (None, Some(t)) => {
                let v = t.vec3(&self.src)? - position;
                (t, v)
            }
            (Some(_), Some(t)) => {
                return Err(t.err(&self.src, "give `direction` or `target`, not both"));
            }
            (None, None) => {
                return Err(table.missing(
                    &self.src,
                    "direction",
                    "a spot light needs `direction = [x, y, z]` or `target = [x, y, z]`",
                ));
            }
        };
        let axis = axis.try_normalize().ok_or_else(|| {
            axis_item.err(
                &self.src,
                "the spot light's axis has zero length or is not finite",
            )
        })?;
        let cutoff_item = table.get("cutoff_deg");
        let beam_item = table.get("beam_width_deg");
        let cutoff_deg = match &cutoff_item {
            Some(c) => c.number(&self.src)?,
            None => DEFAULT_CUTOFF_DEG,
        };
        let beam_width_deg = match &beam_item {
            Some(b) => b.number(&self.src)?,
            None => DEFAULT_BEAM_SHARE * cutoff_deg,
        };
        let spectrum = table.require(
            &self.src,
            "intensity",
            "a spot light needs `intensity` (a spectrum, W/(sr nm), at the cone's centre)",
        )?;
        let id = self.spectrum_ref(&spectrum, 1.0)?;
        // Only the local z matters to the profile: any frame around the axis.
        let (x, y) = axis.any_orthonormal_pair();
        let cone = SpotCone::new(&SpotConeSettings {
            world_to_local: Mat3::from_cols(x, y, axis).transpose(),
            cutoff_deg,
            beam_width_deg,
        })
        .map_err(|e| {
            let item = match e {
                SpotConeError::BeamWidth { .. } => beam_item.as_ref().or(cutoff_item.as_ref()),
                _ => cutoff_item.as_ref(),
            };
            match item {
                Some(item) => item.err(&self.src, e),
                None => table.err(&self.src, e),
            }
        })?;
        self.cx.spot_light(position, (id, scale), cone);
        Ok(())
    }
}
