//! The built-in scene `prism`: a beam of white light through an SF11
//! dense-flint prism spreads into a spectrum on a wall, beside a diffuse
//! sphere lit by an FL11 tri-band fluorescent lamp. It shows both halves of
//! the hybrid transport (`transport::HybridTransport`): the caustic needs
//! wavelength-dependent refraction (sampled wavelengths), the sphere a
//! line spectrum carried smoothly (Fourier coefficients).
//!
//! Geometry (top view, `x` right, `z` towards the camera): the lamp sits at
//! the end of a black tube (a slit projector) and shines along `−x`; the
//! prism, an equilateral triangle extruded along `y`, is turned so that the
//! beam passes at minimum deviation for 550 nm, `δ = 2 asin(n sin(A/2)) −
//! A` with apex angle `A = 60°`: the symmetric path, whose deviation
//! changes least with the point of entry. SF11's `n` runs from 1.845 at
//! 400 nm to 1.772 at 700 nm, so `δ` runs from 74.7° to 64.7°, a spread of
//! about 0.19 scene units on the back wall 1 unit behind the prism; the
//! tube's slit (its width over its length) blurs that by about ±0.04 rad.
//! The beam's rays from the wall back to the lamp can only be found by BSDF
//! sampling (shadow rays do not pass glass), which makes the caustic the
//! noisy part of the image in every transport.

use super::{emitter, lambert, patch};
use crate::ids::MaterialId;
use crate::scene::camera::Camera;
use crate::scene::shapes::{add_quad_uv, add_sphere};
use crate::scene::{SceneBuilder, SceneError};
use crate::shading::material::{Bsdf, Material};
use crate::shading::microfacet::Microfacet;
use crate::spectra::SpectrumSource;
use crate::spectra::angular::{AngularFunction, Ior};
use glam::{Vec2, Vec3};
use spectral_core::SpectralRange;
use spectral_core::registry::Builtin;

use super::BuiltinError;

/// Schott N-SF11 (dense flint), Sellmeier coefficients of the Schott data
/// sheet (as listed by refractiveindex.info): `n_d = 1.78472`.
pub const SF11: Ior = Ior::Sellmeier {
    b: [1.737_596_95, 0.313_747_346, 1.898_781_01],
    c: [0.013_188_707, 0.062_306_814_2, 155.236_29],
};
/// The wavelength whose minimum-deviation path the prism is turned for, nm.
const DESIGN_WAVELENGTH_NM: f64 = 550.0;
/// The prism's apex angle (equilateral), radians.
const APEX_ANGLE: f32 = core::f32::consts::FRAC_PI_3;
/// Side of the prism's triangle and its centre in the floor plane (x, z).
const PRISM_SIDE: f32 = 0.6;
const PRISM_CENTRE_XZ: Vec2 = Vec2::new(0.5, -0.05);
/// The prism's bottom and top (it floats a hair above the floor so that
/// its base and the floor are not coplanar).
const PRISM_Y: [f32; 2] = [-0.99, -0.1];
/// The beam tube: from its mouth to the lamp along `+x`, its slit's
/// height (y) and width (z); the lamp fills the tube's far end.
const TUBE_X: [f32; 2] = [1.2, 2.2];
const TUBE_Y: [f32; 2] = [-0.75, -0.35];
const SLIT_WIDTH: f32 = 0.06;
/// Luminance of the white lamp (equal energy): bright, because only the
/// tube's narrow beam leaves it.
const WHITE_LUMINANCE: f64 = 1500.0;
/// Luminance of the FL11 lamp (as the `lamps` scene's).
const FL11_LUMINANCE: f64 = 8.0;
/// The FL11 lamp's centre (x, z), half-size and height.
const FL11_CENTRE_XZ: Vec2 = Vec2::new(-0.8, 0.1);
const FL11_HALF_SIZE: f32 = 0.25;
const FL11_Y: f32 = 1.2;
/// The diffuse sphere: centre and radius, and its ColorChecker patch
/// (7, orange).
const SPHERE_CENTRE: Vec3 = Vec3::new(-0.8, -0.6, 0.1);
const SPHERE_RADIUS: f32 = 0.4;
const SPHERE_PATCH: usize = 7;
/// The room: floor at `y = −1`, back wall at `z = −1`, their extent.
const FLOOR_Y: f32 = -1.0;
const WALL_Z: f32 = -1.0;
const ROOM_HALF_WIDTH: f32 = 2.5;
const ROOM_FRONT_Z: f32 = 2.5;
const WALL_TOP_Y: f32 = 2.0;
/// Albedo of the floor and the wall (grey, so the spectrum shows).
const ROOM_ALBEDO: f64 = 0.7;
/// Camera: position, target, field of view (degrees).
const CAMERA_POSITION: Vec3 = Vec3::new(0.0, 0.4, 3.0);
const CAMERA_TARGET: Vec3 = Vec3::new(0.0, -0.45, -0.5);
const CAMERA_FOV_DEG: f32 = 40.0;

/// The corners of the prism's triangle in the floor plane (x, z): the
/// apex first, then the two base corners, for a beam along `−x` bent
/// towards `−z` by `deviation` radians (the base's normal is the inside
/// direction rotated by a right angle, the inside direction the beam
/// turned by half the deviation).
fn prism_corners(deviation: f32) -> [Vec2; 3] {
    let half = 0.5 * deviation;
    let apex_direction = Vec2::new(-half.sin(), half.cos());
    let circumradius = PRISM_SIDE / 3.0f32.sqrt();
    let turn = 2.0 * core::f32::consts::FRAC_PI_3;
    let at = |angle: f32| {
        PRISM_CENTRE_XZ + circumradius * Vec2::from_angle(angle).rotate(apex_direction)
    };
    [at(0.0), at(turn), at(-turn)]
}

/// The prism's minimum deviation at the design wavelength, radians.
fn design_deviation() -> f32 {
    let n = SF11.at(DESIGN_WAVELENGTH_NM) as f32;
    2.0 * (n * (0.5 * APEX_ANGLE).sin()).asin() - APEX_ANGLE
}

/// The quad between corners `a` and `c` (x, z) from height `y[0]` to
/// `y[1]`; its normal is `(c − a) × ŷ`.
fn side(b: &mut SceneBuilder, a: Vec2, c: Vec2, y: [f32; 2], material: MaterialId) {
    add_quad_uv(
        b,
        [
            Vec3::new(a.x, y[0], a.y),
            Vec3::new(c.x, y[0], c.y),
            Vec3::new(c.x, y[1], c.y),
            Vec3::new(a.x, y[1], a.y),
        ],
        material,
    );
}

/// The prism's glass: a smooth SF11 dielectric (its Fresnel tables seen
/// from either side), added to `b`. Public so tests build their own
/// dispersive shapes from the same glass.
pub fn add_sf11_glass(b: &mut SceneBuilder) -> Result<MaterialId, SceneError> {
    let outside = b.add_angular(
        "SF11 out",
        AngularFunction::Dielectric {
            ior: SF11,
            from_inside: false,
        },
    )?;
    let inside = b.add_angular(
        "SF11 in",
        AngularFunction::Dielectric {
            ior: SF11,
            from_inside: true,
        },
    )?;
    Ok(b.add_material(Material::new(
        "SF11",
        Bsdf::Dielectric {
            outside,
            inside,
            ior: SF11,
            microfacet: Microfacet::ggx(0.0),
            tints: None,
        },
    )))
}

fn add_prism(b: &mut SceneBuilder) -> Result<[Vec2; 3], SceneError> {
    let glass = add_sf11_glass(b)?;
    // `(p1 − p0) × (p2 − p0)` of the corners points along `−y`: the walls
    // run from corner `i + 1` to `i` and the top cap is reversed, so every
    // normal points out of the glass, which is how a dielectric tells
    // entering from leaving.
    let corners = prism_corners(design_deviation());
    for (a, c) in [(1, 0), (2, 1), (0, 2)] {
        side(b, corners[a], corners[c], PRISM_Y, glass);
    }
    let at = |p: Vec2, y: f32| Vec3::new(p.x, y, p.y);
    let [bottom, top] = PRISM_Y;
    b.add_triangle(corners.map(|p| at(p, bottom)), glass);
    b.add_triangle(
        [corners[0], corners[2], corners[1]].map(|p| at(p, top)),
        glass,
    );
    Ok(corners)
}

/// The slit projector: a black tube along `x` whose slit is centred on
/// `z_centre`, the white lamp at its far end facing `−x`.
fn add_beam(b: &mut SceneBuilder, z_centre: f32) -> Result<(), SceneError> {
    let black = lambert(b, "tube", SpectrumSource::Constant(0.0))?;
    let white = emitter(
        b,
        "white lamp",
        SpectrumSource::Builtin(Builtin::EqualEnergy),
        WHITE_LUMINANCE,
    )?;
    let [x0, x1] = TUBE_X;
    let [y0, y1] = TUBE_Y;
    let (z0, z1) = (z_centre - 0.5 * SLIT_WIDTH, z_centre + 0.5 * SLIT_WIDTH);
    let corner = Vec3::new;
    for quad in [
        [
            corner(x0, y0, z0),
            corner(x1, y0, z0),
            corner(x1, y0, z1),
            corner(x0, y0, z1),
        ],
        [
            corner(x0, y1, z0),
            corner(x1, y1, z0),
            corner(x1, y1, z1),
            corner(x0, y1, z1),
        ],
        [
            corner(x0, y0, z0),
            corner(x1, y0, z0),
            corner(x1, y1, z0),
            corner(x0, y1, z0),
        ],
        [
            corner(x0, y0, z1),
            corner(x1, y0, z1),
            corner(x1, y1, z1),
            corner(x0, y1, z1),
        ],
    ] {
        add_quad_uv(b, quad, black);
    }
    // (v1 − v0) × (v2 − v0) points along −x: the lamp faces the mouth.
    add_quad_uv(
        b,
        [
            corner(x1, y0, z0),
            corner(x1, y0, z1),
            corner(x1, y1, z1),
            corner(x1, y1, z0),
        ],
        white,
    );
    Ok(())
}

/// The `prism` scene over `range` (module docs).
pub fn prism(range: SpectralRange) -> Result<SceneBuilder, BuiltinError> {
    let mut b = SceneBuilder::new(range);
    let grey = lambert(&mut b, "room", SpectrumSource::Constant(ROOM_ALBEDO))?;
    let (w, front) = (ROOM_HALF_WIDTH, ROOM_FRONT_Z);
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-w, FLOOR_Y, front),
            Vec3::new(w, FLOOR_Y, front),
            Vec3::new(w, FLOOR_Y, WALL_Z),
            Vec3::new(-w, FLOOR_Y, WALL_Z),
        ],
        grey,
    );
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-w, FLOOR_Y, WALL_Z),
            Vec3::new(w, FLOOR_Y, WALL_Z),
            Vec3::new(w, WALL_TOP_Y, WALL_Z),
            Vec3::new(-w, WALL_TOP_Y, WALL_Z),
        ],
        grey,
    );
    let corners = add_prism(&mut b)?;
    // The beam enters the face between the apex and the base corner on
    // the lamp's side, at its middle.
    add_beam(&mut b, 0.5 * (corners[0].y + corners[2].y))?;
    let fl11 = SpectrumSource::Builtin(
        Builtin::lookup("fl11").map_err(|e| SceneError::Spectrum("fl11".into(), e))?,
    );
    let lamp = emitter(&mut b, "fl11", fl11, FL11_LUMINANCE)?;
    let (c, h) = (FL11_CENTRE_XZ, FL11_HALF_SIZE);
    add_quad_uv(
        &mut b,
        [
            Vec3::new(c.x - h, FL11_Y, c.y - h),
            Vec3::new(c.x + h, FL11_Y, c.y - h),
            Vec3::new(c.x + h, FL11_Y, c.y + h),
            Vec3::new(c.x - h, FL11_Y, c.y + h),
        ],
        lamp,
    );
    let orange = lambert(&mut b, "sphere", patch(SPHERE_PATCH)?)?;
    add_sphere(&mut b, SPHERE_CENTRE, SPHERE_RADIUS, 24, 48, orange);
    b.set_camera(
        Camera::look_at(CAMERA_POSITION, CAMERA_TARGET, Vec3::Y, CAMERA_FOV_DEG)
            .map_err(|e| SceneError::Bvh(e.to_string()))?,
    );
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The turned prism passes the design wavelength symmetrically: the
    /// beam (along −x) meets the entrance face and leaves the exit face
    /// at the same angle, `(δ + A)/2`, and the deviation spreads by
    /// several degrees over the visible range.
    #[test]
    fn the_beam_passes_at_minimum_deviation() {
        let deviation = design_deviation();
        let corners = prism_corners(deviation);
        let outward = |a: Vec2, c: Vec2| {
            let edge = c - a;
            let normal = Vec2::new(edge.y, -edge.x).normalize();
            let middle = 0.5 * (a + c);
            if normal.dot(middle - PRISM_CENTRE_XZ) > 0.0 {
                normal
            } else {
                -normal
            }
        };
        let incidence = 0.5 * (deviation + APEX_ANGLE);
        let entrance = outward(corners[2], corners[0]);
        assert!((entrance.dot(Vec2::X) - incidence.cos()).abs() < 1e-5);
        let out = Vec2::new(-deviation.cos(), -deviation.sin());
        let exit = outward(corners[0], corners[1]);
        assert!((exit.dot(out) - incidence.cos()).abs() < 1e-5);
        let spread = |l: f64| {
            let n = SF11.at(l) as f32;
            2.0 * (n * (0.5 * APEX_ANGLE).sin()).asin() - APEX_ANGLE
        };
        let degrees = (spread(400.0) - spread(700.0)).to_degrees();
        assert!((9.0..11.0).contains(&degrees), "{degrees}");
        assert!((SF11.at(587.6) - 1.78472).abs() < 1e-4);
    }
}
