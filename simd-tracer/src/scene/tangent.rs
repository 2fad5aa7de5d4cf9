//! A triangle's `∂p/∂u` and `∂p/∂v`: how its points move as the texture's
//! `u` and `v` grow. A normal map's tangent-space `x` axis follows `∂p/∂u`,
//! and a bump map tilts both by its heights' slopes
//! (`shading/material/normal_map.rs`).
//!
//! With corners `p_0, p_1, p_2`, texture coordinates `t_0, t_1, t_2` and
//! the edges `dp_k = p_k − p_0`, `dt_k = t_k − t_0` (`k = 1, 2`), the
//! affine map from texture coordinates to points has
//!
//! `∂p/∂u = (dt_2.v · dp_1 − dt_1.v · dp_2) / det`,
//! `∂p/∂v = (dt_1.u · dp_2 − dt_2.u · dp_1) / det`,
//! `det = dt_1.u · dt_2.v − dt_1.v · dt_2.u`,
//!
//! Mitsuba 3.9.1's `Mesh::compute_surface_interaction`
//! (src/render/mesh.cpp). It does not depend on the order of the corners,
//! only on the pairing of points with coordinates. Where the texture
//! coordinates are degenerate (`det = 0`) both are zero: the maps then
//! take a unit basis orthogonal to the normal (Mitsuba takes one from the
//! face normal's coordinate system; both are arbitrary). A triangle without
//! texture coordinates has `∂p/∂u = p_1 − p_0`, `∂p/∂v = p_2 − p_0`,
//! Mitsuba's barycentric parameterisation.

use glam::{Vec2, Vec3};

/// `[∂p/∂u, ∂p/∂v]` of a triangle (module docs).
pub fn surface_derivatives(vertices: &[Vec3; 3], uvs: Option<&[Vec2; 3]>) -> [Vec3; 2] {
    let [p0, p1, p2] = *vertices;
    let (dp1, dp2) = (p1 - p0, p2 - p0);
    let Some(&[t0, t1, t2]) = uvs else {
        return [dp1, dp2];
    };
    let (dt1, dt2) = (t1 - t0, t2 - t0);
    let det = dt1.x * dt2.y - dt1.y * dt2.x;
    if det == 0.0 {
        return [Vec3::ZERO; 2];
    }
    let dp_du = (dt2.y * dp1 - dt1.y * dp2) / det;
    let dp_dv = (dt1.x * dp2 - dt2.x * dp1) / det;
    if dp_du.is_finite() && dp_dv.is_finite() {
        [dp_du, dp_dv]
    } else {
        [Vec3::ZERO; 2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a parallelogram mapped affinely, `∂p/∂u` (`∂p/∂v`) is the edge
    /// along which `u` (`v`) alone changes, divided by that change,
    /// whatever the order of the corners; swapped `u` and `v` swap them.
    /// Negative control: the other edge is not the answer.
    #[test]
    fn the_derivatives_follow_u_and_v_across_the_triangle() {
        let (origin, along_u, along_v) = (
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(2.0, 0.5, 0.0),
            Vec3::new(-0.3, 0.0, 1.5),
        );
        let point = |t: Vec2| origin + t.x * along_u + t.y * along_v;
        let uvs = [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.7, 0.3),
            Vec2::new(0.2, 0.9),
        ];
        let vertices = uvs.map(point);
        let close = |[a, b]: [Vec3; 2], [c, d]: [Vec3; 2]| {
            (a - c).length() < 1e-5 && (b - d).length() < 1e-5
        };
        let derivatives = surface_derivatives(&vertices, Some(&uvs));
        assert!(close(derivatives, [along_u, along_v]), "{derivatives:?}");
        assert!(!close(derivatives, [along_v, along_u]));
        let rotated = [vertices[1], vertices[2], vertices[0]];
        let rotated_uvs = [uvs[1], uvs[2], uvs[0]];
        assert!(close(
            surface_derivatives(&rotated, Some(&rotated_uvs)),
            [along_u, along_v]
        ));
        let swapped = uvs.map(|t| Vec2::new(t.y, t.x));
        assert!(close(
            surface_derivatives(&vertices, Some(&swapped)),
            [along_v, along_u]
        ));
        // Degenerate coordinates, and none at all.
        assert_eq!(
            surface_derivatives(&vertices, Some(&[Vec2::ONE; 3])),
            [Vec3::ZERO; 2]
        );
        assert_eq!(
            surface_derivatives(&vertices, None),
            [vertices[1] - vertices[0], vertices[2] - vertices[0]]
        );
    }
}
