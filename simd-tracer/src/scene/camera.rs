//! A perspective camera, a pinhole or a thin lens, with the field of view
//! along the smaller image axis (Mitsuba's `fov_axis = "smaller"`, the
//! convention of the Cornell box notes).
//!
//! For a film of `w × h` pixels and image-plane coordinates `(x, y)` in
//! pixels (origin top-left, y down), the pinhole's direction is
//! `d = forward + ((x − w/2) s) right − ((y − h/2) s) up` with
//! `s = 2 tan(fov/2) / min(w, h)`.
//!
//! # Thin lens
//!
//! A thin lens of aperture radius `A` focused at distance `f` (along
//! `forward`, a plane, as Mitsuba's `thinlens` and pbrt's `perspective`
//! cameras focus) starts the ray of film point `(x, y)` at a point of the
//! lens disk, `o = position + A (p right + q up)` with `(p, q)` uniform on
//! the unit disk, towards the point that the pinhole ray meets on the focal
//! plane, `position + d · f / (d · forward)`. Points on that plane are
//! sharp; a point at depth `z` spreads into a disk of radius
//! `A |1/f − 1/z|` in the units of `s` (tangent of the angle), the circle of
//! confusion. The lens is ideal: every ray carries the same weight (the
//! image is that of Mitsuba's `thinlens`, whose importance is uniform over
//! the aperture too).

use crate::simd::Vec3x8;
use glam::Vec3;
use wide::f32x8;

/// A perspective camera: a pinhole, or a thin lens (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    fov_deg: f32,
    /// `tan(fov/2)`, computed once (not per packet).
    tan_half_fov: f32,
    /// The lens; `None` is a pinhole.
    lens: Option<ThinLens>,
}

/// A thin lens (module docs), in scene units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinLens {
    /// Radius of the aperture, `A > 0`.
    pub aperture_radius: f32,
    /// Distance of the plane in focus along the viewing direction, `f > 0`.
    pub focus_distance: f32,
}

/// A camera's position and axes ([`Camera::from_axes`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraAxes {
    /// Centre of projection.
    pub position: Vec3,
    /// Viewing direction.
    pub forward: Vec3,
    /// Image right.
    pub right: Vec3,
    /// Image up.
    pub up: Vec3,
}

/// Why a camera is invalid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraError {
    /// Position, target or up is not finite, or target equals position.
    Degenerate,
    /// `up` is parallel to the viewing direction.
    UpParallel,
    /// The field of view is not in (0°, 180°).
    FieldOfView,
    /// A lens's aperture radius is negative or its focus distance not
    /// above 0 (or either is not finite).
    Lens,
}

impl core::fmt::Display for CameraError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Degenerate => "camera position/target/up must be finite and target != position",
            Self::UpParallel => "camera up vector is parallel to the viewing direction",
            Self::FieldOfView => "field of view must be between 0 and 180 degrees",
            Self::Lens => {
                "the lens's aperture radius must be finite and >= 0 and its focus distance finite and > 0"
            }
        })
    }
}

impl std::error::Error for CameraError {}

impl Camera {
    /// A camera at `position` looking at `target`.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov_deg: f32,
    ) -> Result<Self, CameraError> {
        if !(position.is_finite() && target.is_finite() && up.is_finite()) || position == target {
            return Err(CameraError::Degenerate);
        }
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CameraError::FieldOfView);
        }
        let forward = (target - position).normalize();
        let right = forward.cross(up);
        if right.length_squared() < 1e-12 {
            return Err(CameraError::UpParallel);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        Ok(Self {
            position,
            forward,
            right,
            up,
            fov_deg,
            tan_half_fov: (0.5 * fov_deg.to_radians()).tan(),
            lens: None,
        })
    }

    /// A camera at `position` with the given axes (Mitsuba's sensor
    /// `to_world`: `forward` its local `+z`, `up` its `+y`, `right` its
    /// `−x`). The axes are normalised but kept otherwise, so a mirroring
    /// `to_world` mirrors the image; they must be finite and non-zero.
    pub fn from_axes(axes: CameraAxes, fov_deg: f32) -> Result<Self, CameraError> {
        let CameraAxes {
            position,
            forward,
            right,
            up,
        } = axes;
        let (Some(forward), Some(right), Some(up)) = (
            forward.try_normalize(),
            right.try_normalize(),
            up.try_normalize(),
        ) else {
            return Err(CameraError::Degenerate);
        };
        if !position.is_finite() {
            return Err(CameraError::Degenerate);
        }
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CameraError::FieldOfView);
        }
        Ok(Self {
            position,
            forward,
            right,
            up,
            fov_deg,
            tan_half_fov: (0.5 * fov_deg.to_radians()).tan(),
            lens: None,
        })
    }

    /// This camera with a thin lens of `aperture_radius` focused at
    /// `focus_distance` (module docs); an aperture of 0 is a pinhole.
    pub fn with_lens(self, aperture_radius: f32, focus_distance: f32) -> Result<Self, CameraError> {
        if !(aperture_radius.is_finite()
            && aperture_radius >= 0.0
            && focus_distance.is_finite()
            && focus_distance > 0.0)
        {
            return Err(CameraError::Lens);
        }
        Ok(Self {
            lens: (aperture_radius > 0.0).then_some(ThinLens {
                aperture_radius,
                focus_distance,
            }),
            ..self
        })
    }

    /// The thin lens, `None` for a pinhole.
    pub fn lens(&self) -> Option<ThinLens> {
        self.lens
    }

    /// The camera's position and unit axes ([`Camera::from_axes`] makes
    /// the same camera from them).
    pub fn axes(&self) -> CameraAxes {
        CameraAxes {
            position: self.position,
            forward: self.forward,
            right: self.right,
            up: self.up,
        }
    }

    /// The camera position.
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// Field of view along the smaller image axis, degrees.
    pub fn fov_deg(&self) -> f32 {
        self.fov_deg
    }

    /// Film-plane size of one pixel at unit distance, `2 tan(fov/2) / min(w, h)`.
    fn pixel_scale(&self, width: u32, height: u32) -> f32 {
        2.0 * self.tan_half_fov / width.min(height) as f32
    }

    /// The (unnormalised) ray direction through film point `(x, y)` in pixels.
    pub fn direction(&self, x: f32, y: f32, width: u32, height: u32) -> Vec3 {
        let scale = self.pixel_scale(width, height);
        let dx = (x - 0.5 * width as f32) * scale;
        let dy = (y - 0.5 * height as f32) * scale;
        self.forward + dx * self.right - dy * self.up
    }

    /// [`Camera::direction`] for 8 film points: the same operations in the
    /// same order, so each lane equals the scalar direction bit for bit.
    pub fn direction_x8(&self, x: f32x8, y: f32x8, width: u32, height: u32) -> Vec3x8 {
        let scale = f32x8::splat(self.pixel_scale(width, height));
        let dx = (x - f32x8::splat(0.5 * width as f32)) * scale;
        let dy = (y - f32x8::splat(0.5 * height as f32)) * scale;
        Vec3x8::splat(self.forward) + Vec3x8::splat(self.right) * dx - Vec3x8::splat(self.up) * dy
    }

    /// The ray of the pinhole direction `d` ([`Camera::direction`])
    /// through `lens`, from the point `(p, q)` of the unit disk: its origin
    /// on the lens and its unit direction towards `d`'s point on the focal
    /// plane (module docs).
    pub fn lens_ray(&self, lens: ThinLens, d: Vec3, (p, q): (f32, f32)) -> (Vec3, Vec3) {
        let focus = self.position + d * (lens.focus_distance / d.dot(self.forward));
        let origin = self.position
            + self.right * (lens.aperture_radius * p)
            + self.up * (lens.aperture_radius * q);
        (origin, (focus - origin).normalize())
    }

    /// [`Camera::lens_ray`] of 8 lanes: the same operations in the same
    /// order, lane by lane.
    pub fn lens_ray_x8(
        &self,
        lens: ThinLens,
        d: Vec3x8,
        (p, q): (f32x8, f32x8),
    ) -> (Vec3x8, Vec3x8) {
        let position = Vec3x8::splat(self.position);
        let focus =
            position + d * (f32x8::splat(lens.focus_distance) / d.dot(Vec3x8::splat(self.forward)));
        let radius = f32x8::splat(lens.aperture_radius);
        let origin = position
            + Vec3x8::splat(self.right) * (radius * p)
            + Vec3x8::splat(self.up) * (radius * q);
        (origin, (focus - origin).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packet_directions_equal_scalar_directions_bit_for_bit() {
        let cam = Camera::look_at(
            Vec3::new(0.3, 1.0, 3.9),
            Vec3::new(0.1, 0.9, 0.0),
            Vec3::Y,
            39.3,
        )
        .unwrap();
        let mut rng = crate::sampling::rng::Rng::new(3, 5);
        for (width, height) in [(512, 512), (640, 360), (1, 1), (37, 1000)] {
            for _ in 0..500 {
                let x: [f32; 8] =
                    core::array::from_fn(|_| rng.next_f32() * (width as f32 + 4.0) - 2.0);
                let y: [f32; 8] =
                    core::array::from_fn(|_| rng.next_f32() * (height as f32 + 4.0) - 2.0);
                let d = cam.direction_x8(f32x8::new(x), f32x8::new(y), width, height);
                for lane in 0..8 {
                    let scalar = cam.direction(x[lane], y[lane], width, height);
                    assert_eq!(
                        d.lane(lane).to_array().map(f32::to_bits),
                        scalar.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }

    /// Lens rays: every lane against the scalar oracle; all rays of one
    /// film point, whatever their aperture point, meet on the focal plane
    /// at the pinhole ray's point; origins lie on the aperture disk.
    #[test]
    fn lens_rays_match_the_scalar_oracle_and_meet_on_the_focal_plane() {
        let cam = Camera::look_at(
            Vec3::new(0.3, 1.0, 3.9),
            Vec3::new(0.1, 0.9, 0.0),
            Vec3::Y,
            39.3,
        )
        .unwrap()
        .with_lens(0.2, 2.5)
        .unwrap();
        let lens = cam.lens().unwrap();
        let mut rng = crate::sampling::rng::Rng::new(7, 1);
        let (width, height) = (64, 48);
        for _ in 0..500 {
            let x: [f32; 8] = core::array::from_fn(|_| rng.next_f32() * width as f32);
            let y: [f32; 8] = core::array::from_fn(|_| rng.next_f32() * height as f32);
            let p: [f32; 8] = core::array::from_fn(|_| 2.0 * rng.next_f32() - 1.0);
            let q: [f32; 8] =
                core::array::from_fn(|k| (1.0 - p[k] * p[k]).sqrt() * (2.0 * rng.next_f32() - 1.0));
            let d = cam.direction_x8(f32x8::new(x), f32x8::new(y), width, height);
            let (o8, w8) = cam.lens_ray_x8(lens, d, (f32x8::new(p), f32x8::new(q)));
            for lane in 0..8 {
                let dl = cam.direction(x[lane], y[lane], width, height);
                let (o, w) = cam.lens_ray(lens, dl, (p[lane], q[lane]));
                assert!((o8.lane(lane) - o).length() < 1e-5 && (w8.lane(lane) - w).length() < 1e-5);
                assert!((w.length() - 1.0).abs() < 1e-5);
                let offset = o - cam.position;
                assert!(offset.dot(cam.forward).abs() < 1e-5);
                assert!(offset.length() <= lens.aperture_radius * (1.0 + 1e-5));
                // Where the ray crosses the focal plane...
                let t = (lens.focus_distance - offset.dot(cam.forward)) / w.dot(cam.forward);
                let on_plane = o + w * t;
                // ... the pinhole ray crosses it too.
                let pinhole = cam.position + dl * (lens.focus_distance / dl.dot(cam.forward));
                assert!(
                    (on_plane - pinhole).length() < 1e-4,
                    "{on_plane} vs {pinhole}"
                );
            }
        }
    }

    #[test]
    fn a_lens_needs_a_finite_aperture_and_a_positive_focus() {
        let cam = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        assert_eq!(cam.with_lens(0.0, 3.0).unwrap().lens(), None);
        assert!(cam.with_lens(0.1, 3.0).unwrap().lens().is_some());
        for (a, f) in [
            (-0.1, 3.0),
            (f32::NAN, 3.0),
            (0.1, 0.0),
            (0.1, -1.0),
            (0.1, f32::INFINITY),
        ] {
            assert_eq!(cam.with_lens(a, f), Err(CameraError::Lens), "{a} {f}");
        }
    }

    #[test]
    fn centre_and_edges() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, Vec3::Y, 90.0).unwrap();
        let d = cam.direction(50.0, 50.0, 100, 100);
        assert!((d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // fov 90° along the smaller axis: the left edge is at 45°.
        let d = cam.direction(0.0, 50.0, 100, 100).normalize();
        assert!((d.x + std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
        let d = cam.direction(100.0, 0.0, 200, 100).normalize();
        assert!((d.y - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6, "{d}");
        assert_eq!(
            Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0),
            Err(CameraError::UpParallel)
        );
        assert_eq!(
            Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0),
            Err(CameraError::Degenerate)
        );
        assert_eq!(
            Camera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, 180.0),
            Err(CameraError::FieldOfView)
        );
    }
}
