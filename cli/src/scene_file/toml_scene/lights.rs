//! `[[lights]]`: point lights (`position`, `intensity`) and directional
//! lights (`direction`, `irradiance`), each spectrum a spectrum reference
//! with an optional `scale`.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::toml_reader::Item;

impl Loader<'_> {
    /// `[[lights]]` (module docs).
    pub(super) fn lights_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for light in item.array(&self.src)? {
            let table = light.table(&self.src)?;
            let kind_item = table.require(&self.src, "type", "\"point\" or \"directional\"")?;
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
                        format!("unknown light type \"{other}\" (point, directional)"),
                    ));
                }
            }
        }
        Ok(())
    }
}
