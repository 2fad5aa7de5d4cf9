//! Affine transforms of shapes: translate, rotate, scale, a matrix, look-at,
//! composed in Mitsuba's order (each operation applies after the ones
//! before it: `to_world = op_n ∘ … ∘ op_1`).
//!
//! Points map by `M p + t`, direction vectors by `M v`, normals by the
//! inverse transpose `M⁻ᵀ n` (then normalised), which keeps them
//! perpendicular to transformed tangents under non-uniform scale. A
//! transform with `det M < 0` (a mirror) reverses the winding of every
//! triangle it maps; [`Transform::flips_handedness`] tells the mesh
//! builder to swap two vertices so that the front face stays on the side
//! the shape's normals point to.
//!
//! Look-at follows Mitsuba's `lookat(origin, target, up)`: the local `+z`
//! axis points from `origin` to `target` and `+y` is `up` made
//! perpendicular: `dir = normalize(target − origin)`,
//! `left = normalize(up × dir)`, `new_up = dir × left`, and the columns of
//! `M` are `(left, new_up, dir)` with translation `origin`.

use glam::{Affine3A, Mat3, Mat3A, Vec3, Vec3A};

/// An affine map of shapes into the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    to_world: Affine3A,
    /// `M⁻ᵀ`, for normals.
    normal_matrix: Mat3A,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// Relative tolerance of [`Transform::uniform_scale`] on `MᵀM = s² I`:
/// axes equal in length within about 5·10⁻⁵ and orthogonal within as much,
/// a tenth of the default sag of tessellated spheres
/// ([`crate::scene::analytic::DEFAULT_SAG`], 10⁻³ radii): a transform within
/// it deforms a sphere less than its tessellation does, while rotations and
/// scalings composed in `f32` (errors of a few 10⁻⁷) pass.
pub const SIMILARITY_TOLERANCE: f32 = 1e-4;

/// Why a transform is refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TransformError(pub &'static str);

impl core::fmt::Display for TransformError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.0)
    }
}

impl std::error::Error for TransformError {}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        to_world: Affine3A::IDENTITY,
        normal_matrix: Mat3A::IDENTITY,
    };

    /// The transform of `to_world`; refused if it is not finite or not
    /// invertible.
    pub fn new(to_world: Affine3A) -> Result<Self, TransformError> {
        let m = Mat3::from(to_world.matrix3);
        let det = m.determinant();
        if !to_world.is_finite() {
            return Err(TransformError("the transform is not finite"));
        }
        if !det.is_normal() {
            return Err(TransformError("the transform is singular (determinant 0)"));
        }
        let normal_matrix = Mat3A::from(m.inverse().transpose());
        if !normal_matrix.is_finite() {
            return Err(TransformError("the transform is singular (determinant 0)"));
        }
        Ok(Self {
            to_world,
            normal_matrix,
        })
    }

    /// The affine map.
    pub fn affine(&self) -> Affine3A {
        self.to_world
    }

    /// `self` followed by `next` (Mitsuba's order: later operations apply last).
    pub fn then(&self, next: &Self) -> Result<Self, TransformError> {
        Self::new(next.to_world * self.to_world)
    }

    /// A translation.
    pub fn translate(offset: Vec3) -> Result<Self, TransformError> {
        Self::new(Affine3A::from_translation(offset))
    }

    /// A rotation by `angle_deg` about `axis` (right-handed).
    pub fn rotate(axis: Vec3, angle_deg: f32) -> Result<Self, TransformError> {
        let axis = axis.try_normalize().ok_or(TransformError(
            "the rotation axis has zero length or is not finite",
        ))?;
        Self::new(Affine3A::from_axis_angle(axis, angle_deg.to_radians()))
    }

    /// A scale per axis.
    pub fn scale(factors: Vec3) -> Result<Self, TransformError> {
        Self::new(Affine3A::from_scale(factors))
    }

    /// A 4 × 4 matrix given row by row; the last row must be `0 0 0 1`.
    pub fn matrix_rows(rows: [[f32; 4]; 4]) -> Result<Self, TransformError> {
        if rows[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(TransformError(
                "the matrix's last row must be 0 0 0 1 (no projection)",
            ));
        }
        let column = |j: usize| Vec3::new(rows[0][j], rows[1][j], rows[2][j]);
        Self::new(Affine3A::from_mat3_translation(
            Mat3::from_cols(column(0), column(1), column(2)),
            column(3),
        ))
    }

    /// Mitsuba's look-at (module docs).
    pub fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Result<Self, TransformError> {
        let dir = (target - origin)
            .try_normalize()
            .ok_or(TransformError("look-at: the target equals the origin"))?;
        let left = up.cross(dir).try_normalize().ok_or(TransformError(
            "look-at: `up` is parallel to the view direction",
        ))?;
        let new_up = dir.cross(left);
        Self::new(Affine3A::from_mat3_translation(
            Mat3::from_cols(left, new_up, dir),
            origin,
        ))
    }

    /// A point into the world.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.to_world.transform_point3(p)
    }

    /// A direction vector into the world (not normalised).
    #[inline]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.to_world.transform_vector3(v)
    }

    /// A normal into the world: `M⁻ᵀ n`, normalised (`None` if it has zero
    /// length or is not finite).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Option<Vec3> {
        Vec3::from(self.normal_matrix * Vec3A::from(n)).try_normalize()
    }

    /// Whether the transform mirrors (`det M < 0`).
    pub fn flips_handedness(&self) -> bool {
        self.to_world.matrix3.determinant() < 0.0
    }

    /// The scale `s` if the linear part is `s` times a rotation or a
    /// mirroring (a similarity: spheres stay spheres), within a relative
    /// [`SIMILARITY_TOLERANCE`] on `MᵀM = s² I`; `None` otherwise.
    pub fn uniform_scale(&self) -> Option<f32> {
        let m = self.to_world.matrix3;
        let gram = m.transpose() * m;
        let scale_sq = (gram.x_axis.x + gram.y_axis.y + gram.z_axis.z) / 3.0;
        if !(scale_sq > 0.0 && scale_sq.is_finite()) {
            return None;
        }
        let off = (gram - Mat3A::from_diagonal(Vec3::splat(scale_sq))).to_cols_array();
        let worst = off.iter().fold(0.0f32, |w, x| w.max(x.abs()));
        (worst <= SIMILARITY_TOLERANCE * scale_sq).then(|| scale_sq.sqrt())
    }

    /// The factor by which areas of a surface with unit normal `n` (before
    /// the transform) grow: `|det M| · |M⁻ᵀ n|`.
    pub fn area_scale(&self, n: Vec3) -> f32 {
        self.to_world.matrix3.determinant().abs()
            * Vec3::from(self.normal_matrix * Vec3A::from(n)).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn similarities_have_a_uniform_scale() {
        let scaled = Transform::scale(Vec3::splat(2.5))
            .and_then(|s| s.then(&Transform::rotate(Vec3::new(1.0, 2.0, 3.0), 37.0)?))
            .and_then(|s| s.then(&Transform::translate(Vec3::new(4.0, 5.0, 6.0))?))
            .expect("valid");
        assert!((scaled.uniform_scale().expect("similarity") - 2.5).abs() < 1e-5);
        let mirrored = Transform::scale(Vec3::new(-3.0, 3.0, 3.0)).expect("valid");
        assert!((mirrored.uniform_scale().expect("similarity") - 3.0).abs() < 1e-5);
        let stretched = Transform::scale(Vec3::new(1.0, 1.0, 1.01)).expect("valid");
        assert_eq!(stretched.uniform_scale(), None);
        let sheared = Transform::matrix_rows([
            [1.0, 0.1, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ])
        .expect("valid");
        assert_eq!(sheared.uniform_scale(), None);
    }

    #[test]
    fn operations_compose_in_mitsubas_order() -> Result<(), TransformError> {
        // Scale, then rotate 90° about z, then translate.
        let t = Transform::scale(Vec3::new(2.0, 1.0, 1.0))?
            .then(&Transform::rotate(Vec3::Z, 90.0)?)?
            .then(&Transform::translate(Vec3::new(0.0, 0.0, 5.0))?)?;
        // x → 2x → 2y → 2y + 5z.
        assert!(close(t.point(Vec3::X), Vec3::new(0.0, 2.0, 5.0)));
        assert!(close(t.vector(Vec3::X), Vec3::new(0.0, 2.0, 0.0)));
        Ok(())
    }

    #[test]
    fn normals_stay_perpendicular_under_non_uniform_scale() -> Result<(), TransformError> {
        let t = Transform::scale(Vec3::new(4.0, 1.0, 0.5))?
            .then(&Transform::rotate(Vec3::new(1.0, 2.0, 3.0), 33.0)?)?;
        // A plane with normal n contains the tangents u, v.
        let n = Vec3::new(1.0, 1.0, 1.0).normalize();
        let (u, v) = (Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, -1.0));
        let Some(nw) = t.normal(n) else {
            panic!("no normal");
        };
        assert!(nw.dot(t.vector(u)).abs() < 1e-5 && nw.dot(t.vector(v)).abs() < 1e-5);
        assert!((nw.length() - 1.0).abs() < 1e-6);
        // The normal of the mapped parallelogram u × v agrees in direction and size.
        let mapped = t.vector(u).cross(t.vector(v));
        assert!(close(mapped.normalize(), nw));
        let scale = mapped.length() / u.cross(v).length();
        assert!((scale - t.area_scale(n)).abs() < 1e-4 * scale);
        Ok(())
    }

    #[test]
    fn mirrors_are_detected_and_bad_transforms_refused() -> Result<(), TransformError> {
        assert!(Transform::scale(Vec3::new(-1.0, 1.0, 1.0))?.flips_handedness());
        assert!(!Transform::rotate(Vec3::Y, 180.0)?.flips_handedness());
        assert!(Transform::scale(Vec3::new(1.0, 0.0, 1.0)).is_err());
        assert!(Transform::scale(Vec3::new(1.0, f32::NAN, 1.0)).is_err());
        assert!(Transform::rotate(Vec3::ZERO, 10.0).is_err());
        assert!(Transform::look_at(Vec3::ONE, Vec3::ONE, Vec3::Y).is_err());
        assert!(Transform::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y).is_err());
        let mut rows = [[0.0; 4]; 4];
        rows[3] = [0.0, 0.0, 1.0, 0.0];
        assert!(Transform::matrix_rows(rows).is_err());
        Ok(())
    }

    #[test]
    fn look_at_points_local_z_at_the_target() -> Result<(), TransformError> {
        let origin = Vec3::new(1.0, 2.0, 3.0);
        let target = Vec3::new(1.0, 2.0, -7.0);
        let t = Transform::look_at(origin, target, Vec3::Y)?;
        assert!(close(t.point(Vec3::ZERO), origin));
        assert!(close(t.vector(Vec3::Z), -Vec3::Z));
        assert!(close(t.vector(Vec3::Y), Vec3::Y));
        // Mitsuba: left = up × dir = y × (−z) = −x.
        assert!(close(t.vector(Vec3::X), -Vec3::X));
        let rows = [
            [1.0, 0.0, 0.0, 3.0],
            [0.0, 0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let m = Transform::matrix_rows(rows)?;
        assert!(close(m.point(Vec3::Y), Vec3::new(3.0, 0.0, 1.0)));
        Ok(())
    }
}
