//! A pinhole camera with the field of view along the smaller image axis
//! (Mitsuba's `fov_axis = "smaller"`, the convention of the Cornell box
//! notes).
//!
//! For a film of `w × h` pixels and image-plane coordinates `(x, y)` in
//! pixels (origin top-left, y down), the direction is
//! `forward + ((x − w/2) s) right − ((y − h/2) s) up` with
//! `s = 2 tan(fov/2) / min(w, h)`.

use crate::simd::Vec3x8;
use glam::Vec3;
use wide::f32x8;

/// A pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    fov_deg: f32,
    /// `tan(fov/2)`, computed once (not per packet).
    tan_half_fov: f32,
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
}

impl core::fmt::Display for CameraError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Degenerate => "camera position/target/up must be finite and target != position",
            Self::UpParallel => "camera up vector is parallel to the viewing direction",
            Self::FieldOfView => "field of view must be between 0 and 180 degrees",
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
        })
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
