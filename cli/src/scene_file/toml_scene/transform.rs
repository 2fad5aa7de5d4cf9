//! `transform = [ … ]`: a list of operations applied in order (Mitsuba's
//! order: each one after the ones before it), each a one-key table:
//! `{ translate = [x, y, z] }`, `{ scale = s }` or `{ scale = [x, y, z] }`,
//! `{ rotate = { axis = [x, y, z], angle_deg = a } }`,
//! `{ matrix = [16 numbers, row by row] }`,
//! `{ look_at = { origin = […], target = […], up = […] } }`.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::toml_reader::Item;
use glam::Vec3;
use simd_tracer::scene::transform::Transform;

const OPERATIONS: &[&str] = &["translate", "scale", "rotate", "matrix", "look_at"];

impl Loader<'_> {
    /// The transform of `item` (module docs).
    pub(super) fn transform(&self, item: &Item<'_, '_>) -> Result<Transform, CliError> {
        let src = &self.src;
        let mut transform = Transform::IDENTITY;
        for step in item.array(src)? {
            let table = step.table(src)?;
            table.allow(src, OPERATIONS, "a transform step")?;
            let entries = table.entries();
            let [(name, value)] = entries.as_slice() else {
                return Err(step.err(
                    src,
                    format!("each step has exactly one of: {}", OPERATIONS.join(", ")),
                ));
            };
            let operation = match *name {
                "translate" => Transform::translate(value.vec3(src)?),
                "scale" => match value.number(src) {
                    Ok(s) => Transform::scale(Vec3::splat(s as f32)),
                    Err(_) => Transform::scale(value.vec3(src)?),
                },
                "rotate" => {
                    let r = value.table(src)?;
                    r.allow(src, &["axis", "angle_deg"], "a rotation")?;
                    let axis = r.require(src, "axis", "the rotation axis [x, y, z]")?;
                    let angle = r.require(src, "angle_deg", "the angle in degrees")?;
                    Transform::rotate(axis.vec3(src)?, angle.number(src)? as f32)
                }
                "matrix" => {
                    let m = value.numbers(src, 16)?;
                    let rows =
                        core::array::from_fn(|r| core::array::from_fn(|c| m[4 * r + c] as f32));
                    Transform::matrix_rows(rows)
                }
                _ => {
                    let l = value.table(src)?;
                    l.allow(src, &["origin", "target", "up"], "a look-at")?;
                    let origin = l.require(src, "origin", "[x, y, z]")?.vec3(src)?;
                    let target = l.require(src, "target", "[x, y, z]")?.vec3(src)?;
                    let up = match l.get("up") {
                        Some(up) => up.vec3(src)?,
                        None => Vec3::Y,
                    };
                    Transform::look_at(origin, target, up)
                }
            }
            .map_err(|e| value.err(src, e))?;
            transform = transform.then(&operation).map_err(|e| step.err(src, e))?;
        }
        Ok(transform)
    }
}
