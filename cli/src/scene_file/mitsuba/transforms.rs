//! `<transform>`: its operations composed in Mitsuba's order, each after
//! the ones before it (`to_world = op_n ∘ … ∘ op_1`, Mitsuba 3.9.1
//! `xml.cpp`, where each operation left-multiplies the matrix so far).
//!
//! * `<translate x y z/>` or `value="x y z"`;
//! * `<rotate x y z angle/>` or `axis="x y z" angle`, degrees, right-handed
//!   about the axis. Mitsuba (Dr.Jit's `rotate`) does **not** normalise the
//!   axis: `M = cos θ I + sin θ [a]ₓ + (1 − cos θ) a aᵀ` with the axis as
//!   given, which also scales when `|a| ≠ 1`. The importer builds the same
//!   matrix, so such files render as in Mitsuba;
//! * `<scale value="s"/>` (uniform), `value="x y z"`, or `x y z` (missing
//!   ones 1);
//! * `<matrix value="16 numbers"/>` row by row, or 9 (a 3 × 3 linear part);
//! * `<lookat origin target up/>` (`up` optional: Mitsuba then picks a
//!   perpendicular one; here `+y`, or `+z` when the view is vertical).

use super::document::Element;
use super::properties::{parse_number, parse_numbers, parse_vector};
use crate::error::CliError;
use glam::Vec3;
use simd_tracer::scene::transform::Transform;

/// The transform of a `<transform>` element.
pub(crate) fn read_transform(e: &Element) -> Result<Transform, CliError> {
    let mut transform = Transform::IDENTITY;
    for op in &e.children {
        let step = operation(op)?;
        transform = transform
            .then(&step)
            .map_err(|err| op.error(format!("<{}>: {err}", op.tag)))?;
    }
    Ok(transform)
}

fn vec_attr(e: &Element, name: &str) -> Result<Option<Vec3>, CliError> {
    let Some(text) = e.attr(name) else {
        return Ok(None);
    };
    let n = parse_numbers(e, text)?;
    match n.as_slice() {
        [x, y, z] => Ok(Some(Vec3::new(*x as f32, *y as f32, *z as f32))),
        _ => Err(e.error(format!(
            "<{}> `{name}` needs 3 numbers, got {}",
            e.tag,
            n.len()
        ))),
    }
}

fn operation(op: &Element) -> Result<Transform, CliError> {
    let fail = |err: simd_tracer::scene::transform::TransformError| {
        op.error(format!("<{}>: {err}", op.tag))
    };
    match op.tag.as_str() {
        "translate" => Transform::translate(parse_vector(op)?).map_err(fail),
        "rotate" => {
            let axis = match vec_attr(op, "axis")? {
                Some(axis) => axis,
                None => parse_vector(op)?,
            };
            let angle = op.attr("angle").map_or(Ok(0.0), |a| parse_number(op, a))?;
            if axis == Vec3::ZERO {
                return Err(op.error("<rotate>: the axis is zero"));
            }
            let (sin, cos) = (angle as f32).to_radians().sin_cos();
            let a = axis;
            let cross = [[0.0, -a.z, a.y], [a.z, 0.0, -a.x], [-a.y, a.x, 0.0]];
            let rows: [[f32; 4]; 4] = core::array::from_fn(|r| {
                core::array::from_fn(|c| match (r, c) {
                    (3, 3) => 1.0,
                    (3, _) | (_, 3) => 0.0,
                    _ => {
                        let identity = if r == c { cos } else { 0.0 };
                        identity + sin * cross[r][c] + (1.0 - cos) * a[r] * a[c]
                    }
                })
            });
            Transform::matrix_rows(rows).map_err(fail)
        }
        "scale" => {
            let factors = match op.attr("value") {
                Some(_) => parse_vector(op)?,
                None => {
                    let axis = |name: &str| -> Result<f32, CliError> {
                        op.attr(name)
                            .map_or(Ok(1.0), |t| parse_number(op, t).map(|v| v as f32))
                    };
                    Vec3::new(axis("x")?, axis("y")?, axis("z")?)
                }
            };
            Transform::scale(factors).map_err(fail)
        }
        "matrix" => {
            let text = op
                .attr("value")
                .ok_or_else(|| op.error("<matrix> needs `value`"))?;
            let m = parse_numbers(op, text)?;
            let rows: [[f32; 4]; 4] = match m.len() {
                16 => core::array::from_fn(|r| core::array::from_fn(|c| m[4 * r + c] as f32)),
                9 => core::array::from_fn(|r| {
                    core::array::from_fn(|c| match (r, c) {
                        (3, 3) => 1.0,
                        (3, _) | (_, 3) => 0.0,
                        _ => m[3 * r + c] as f32,
                    })
                }),
                n => {
                    return Err(op.error(format!("<matrix> needs 16 or 9 numbers, got {n}")));
                }
            };
            Transform::matrix_rows(rows).map_err(fail)
        }
        "lookat" => {
            let origin =
                vec_attr(op, "origin")?.ok_or_else(|| op.error("<lookat> needs `origin`"))?;
            let target =
                vec_attr(op, "target")?.ok_or_else(|| op.error("<lookat> needs `target`"))?;
            let up = match vec_attr(op, "up")? {
                Some(up) => up,
                None => {
                    let dir = (target - origin).normalize_or_zero();
                    if dir.cross(Vec3::Y).length_squared() > 1e-6 {
                        Vec3::Y
                    } else {
                        Vec3::Z
                    }
                }
            };
            Transform::look_at(origin, target, up).map_err(fail)
        }
        other => Err(op.error(format!(
            "unknown transform operation <{other}> (translate, rotate, scale, matrix, lookat)"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_file::mitsuba::document::{Input, read_scene};

    fn transform(ops: &str) -> Result<Transform, CliError> {
        let text =
            format!("<scene version=\"3.0.0\"><transform name=\"t\">{ops}</transform></scene>");
        let scene = read_scene(
            Input::Text {
                name: "t.xml",
                text: &text,
            },
            &[],
        )?
        .root;
        read_transform(&scene.children[0])
    }

    fn assert_rows(t: &Transform, expected: [[f32; 4]; 3]) {
        let m = t.affine();
        for (r, row) in expected.iter().enumerate() {
            for (c, &e) in row.iter().enumerate() {
                let got = if c == 3 {
                    m.translation[r]
                } else {
                    m.matrix3.col(c)[r]
                };
                assert!((got - e).abs() < 1e-5, "({r}, {c}): {got} vs {e}");
            }
        }
    }

    /// Matrices printed by Mitsuba 3.9.1 (`mi.ScalarTransform4f().rotate(…)`
    /// and the XML parser's composition order).
    #[test]
    fn operations_match_mitsuba() -> Result<(), CliError> {
        // An axis of length √2 is not normalised.
        assert_rows(
            &transform(r#"<rotate x="1" y="1" angle="35"/>"#)?,
            [
                [1.0, 0.180848, 0.573576, 0.0],
                [0.180848, 1.0, -0.573576, 0.0],
                [-0.573576, 0.573576, 0.819152, 0.0],
            ],
        );
        assert_rows(
            &transform(r#"<rotate value="0 0 2" angle="90"/>"#)?,
            [
                [0.0, -2.0, 0.0, 0.0],
                [2.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 4.0, 0.0],
            ],
        );
        // Each operation applies after the ones before it.
        assert_rows(
            &transform(r#"<translate x="1"/><scale value="2"/>"#)?,
            [
                [2.0, 0.0, 0.0, 2.0],
                [0.0, 2.0, 0.0, 0.0],
                [0.0, 0.0, 2.0, 0.0],
            ],
        );
        assert_rows(
            &transform(r#"<matrix value="2 0 0 0 3 1 0 0 4"/>"#)?,
            [
                [2.0, 0.0, 0.0, 0.0],
                [0.0, 3.0, 1.0, 0.0],
                [0.0, 0.0, 4.0, 0.0],
            ],
        );
        assert!(transform(r#"<rotate angle="10"/>"#).is_err());
        assert!(transform(r#"<matrix value="1 2 3"/>"#).is_err());
        assert!(transform(r#"<shear value="1"/>"#).is_err());
        Ok(())
    }
}
