//! A triangle's `∂p/∂u`: how its points move as the texture's `u` grows,
//! the direction a normal map's tangent-space `x` axis follows
//! (`shading/material/normal_map.rs`).
//!
//! With corners `p_0, p_1, p_2`, texture coordinates `t_0, t_1, t_2` and
//! the edges `dp_k = p_k − p_0`, `dt_k = t_k − t_0` (`k = 1, 2`), the
//! affine map from texture coordinates to points has
//!
//! `∂p/∂u = (dt_2.v · dp_1 − dt_1.v · dp_2) / det`,
//! `det = dt_1.u · dt_2.v − dt_1.v · dt_2.u`,
//!
//! Mitsuba 3.9.1's `Mesh::compute_surface_interaction`
//! (src/render/mesh.cpp). It does not depend on the order of the corners,
//! only on the pairing of points with coordinates. Where the texture
//! coordinates are degenerate (`det = 0`) the result is zero: the normal
//! map then takes any tangent orthogonal to the normal (Mitsuba takes one
//! from the face normal's coordinate system; both are arbitrary). A
//! triangle without texture coordinates has `∂p/∂u = p_1 − p_0`, Mitsuba's
//! barycentric parameterisation.

use glam::{Vec2, Vec3};

/// `∂p/∂u` of a triangle (module docs).
pub fn surface_tangent(vertices: &[Vec3; 3], uvs: Option<&[Vec2; 3]>) -> Vec3 {
    let [p0, p1, p2] = *vertices;
    let (dp1, dp2) = (p1 - p0, p2 - p0);
    let Some(&[t0, t1, t2]) = uvs else {
        return dp1;
    };
    let (dt1, dt2) = (t1 - t0, t2 - t0);
    let det = dt1.x * dt2.y - dt1.y * dt2.x;
    if det == 0.0 {
        return Vec3::ZERO;
    }
    let tangent = (dt2.y * dp1 - dt1.y * dp2) / det;
    if tangent.is_finite() {
        tangent
    } else {
        Vec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a parallelogram mapped affinely, `∂p/∂u` is the edge along which
    /// `u` alone changes, divided by that change, whatever the order of
    /// the corners; swapped `u` and `v` give the other edge. Negative
    /// control: the `∂p/∂v` edge is not the answer.
    #[test]
    fn the_tangent_follows_u_across_the_triangle() {
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
        let tangent = surface_tangent(&vertices, Some(&uvs));
        assert!((tangent - along_u).length() < 1e-5, "{tangent}");
        assert!((tangent - along_v).length() > 1.0);
        let rotated = [vertices[1], vertices[2], vertices[0]];
        let rotated_uvs = [uvs[1], uvs[2], uvs[0]];
        assert!((surface_tangent(&rotated, Some(&rotated_uvs)) - along_u).length() < 1e-5);
        let swapped = uvs.map(|t| Vec2::new(t.y, t.x));
        assert!((surface_tangent(&vertices, Some(&swapped)) - along_v).length() < 1e-5);
        // Degenerate coordinates, and none at all.
        assert_eq!(
            surface_tangent(&vertices, Some(&[Vec2::ONE; 3])),
            Vec3::ZERO
        );
        assert_eq!(surface_tangent(&vertices, None), vertices[1] - vertices[0]);
    }
}
