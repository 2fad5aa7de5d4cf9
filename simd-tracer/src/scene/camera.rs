//! A camera: perspective (a pinhole or a thin lens) or orthographic, with
//! its film's extent given along the smaller image axis (Mitsuba's
//! `fov_axis = "smaller"`, the convention of the Cornell box notes).
//!
//! For a film of `w × h` pixels and image-plane coordinates `(x, y)` in
//! pixels (origin top-left, y down), both projections share the film
//! offset `o(x, y) = ((x − w/2) s) right − ((y − h/2) s) up` with
//! `s = 2 e / min(w, h)`, where `e` is half the film's extent along the
//! smaller axis:
//!
//! * **perspective**: `e = tan(fov/2)` at unit distance; the ray starts at
//!   `position` with direction `d = forward + o(x, y)`;
//! * **orthographic**: `e = view_size/2` in scene units; the ray starts at
//!   `position + o(x, y)` with direction `forward` (Mitsuba's
//!   `orthographic` sensor: a planar sensor measuring radiance along its
//!   normal, `src/sensors/orthographic.cpp`). Every pixel sees the scene
//!   along the same direction, so sizes do not shrink with distance.
//!
//! **Shift.** A film shift `(a, b)`, in fractions of the film's width and
//! height, moves the film under the projection's centre: film point
//! `(x, y)` takes the ray of `(x + a w, y + b h)`, so the image content
//! moves left by `a w` and up by `b h` pixels while perspective lines stay
//! parallel (a view camera's shift; Mitsuba's `principal_point_offset_x/y`
//! of `perspective`, `src/sensors/perspective.cpp`, the same fractions).
//!
//! **Clip planes.** With a near clip `c_n` and a far clip `c_f` (depths
//! along `forward`), a ray `o + t d` starts where its depth has grown by
//! `c_n`, at `o + d c_n/(d · forward)`, and ends at
//! `t_max = (c_f − c_n)/(d · forward)`, as Mitsuba's projective cameras
//! clip (`near_t = near_clip / d_z` in `perspective.cpp`, `thinlens.cpp`
//! and `orthographic.cpp`). Without clip planes (the default) rays start
//! at the camera and never end.
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
//! the aperture too). Only a perspective camera has a lens.

use crate::simd::Vec3x8;
use glam::Vec3;
use wide::f32x8;

/// A camera: perspective or orthographic (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    projection: Projection,
    /// Half the film's extent along the smaller image axis, `e` of the
    /// module docs, computed once (not per packet).
    half_extent: f32,
    /// The lens; `None` is a pinhole (always `None` when orthographic).
    lens: Option<ThinLens>,
    /// Film shift in fractions of the film's width and height (module
    /// docs).
    shift: [f32; 2],
    /// Clip planes; `None`: none.
    clip: Option<ClipRange>,
}

/// A point of the film and the camera's importance there
/// ([`Camera::project`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilmPoint {
    /// Column, px from the film's left edge.
    pub x: f32,
    /// Row, px from the film's top edge.
    pub y: f32,
    /// Film area, px², per steradian of directions at the pinhole there.
    pub density_per_sr: f32,
}

/// A camera's clip planes (module docs): depths along the viewing
/// direction, `0 ≤ near < far` (`far` may be infinite).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClipRange {
    /// Depth of the near clip plane.
    pub near: f32,
    /// Depth of the far clip plane.
    pub far: f32,
}

/// How a camera maps film points to rays (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Rays from one point; the field of view along the smaller image
    /// axis, degrees, in (0, 180).
    Perspective {
        /// Field of view along the smaller image axis, degrees.
        fov_deg: f32,
    },
    /// Parallel rays along the viewing direction from a film plane of
    /// `view_size` scene units along the smaller image axis.
    Orthographic {
        /// The film plane's extent along the smaller image axis, scene
        /// units, finite and above 0.
        view_size: f32,
    },
}

impl Projection {
    /// Half the film's extent along the smaller axis (module docs), or
    /// why the projection is invalid.
    fn half_extent(self) -> Result<f32, CameraError> {
        match self {
            Self::Perspective { fov_deg } => {
                if !(fov_deg > 0.0 && fov_deg < 180.0) {
                    return Err(CameraError::FieldOfView);
                }
                Ok((0.5 * fov_deg.to_radians()).tan())
            }
            Self::Orthographic { view_size } => {
                if !(view_size > 0.0 && view_size.is_finite()) {
                    return Err(CameraError::ViewSize);
                }
                Ok(0.5 * view_size)
            }
        }
    }
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
    /// Centre of projection (orthographic: the film plane's centre).
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
    /// An orthographic view size is not finite and above 0.
    ViewSize,
    /// A lens's aperture radius is negative or its focus distance not
    /// above 0 (or either is not finite).
    Lens,
    /// A lens on an orthographic camera.
    OrthographicLens,
    /// Clip planes not `0 ≤ near < far` (near finite).
    Clip,
    /// A film shift that is not finite or beyond ±[`MAX_SHIFT`] films.
    Shift,
}

/// The largest film shift, in films: far beyond any use (a shift of 1
/// already shows only what lies outside the unshifted film), small enough
/// that pixel coordinates stay exact in single precision.
pub const MAX_SHIFT: f32 = 16.0;

impl core::fmt::Display for CameraError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Degenerate => "camera position/target/up must be finite and target != position",
            Self::UpParallel => "camera up vector is parallel to the viewing direction",
            Self::FieldOfView => "field of view must be between 0 and 180 degrees",
            Self::ViewSize => "an orthographic view size must be finite and > 0",
            Self::Lens => {
                "the lens's aperture radius must be finite and >= 0 and its focus distance finite and > 0"
            }
            Self::OrthographicLens => "an orthographic camera has no lens (aperture_radius)",
            Self::Clip => "clip planes need 0 <= near < far (near finite)",
            Self::Shift => "a film shift must be finite and within ±16 films",
        })
    }
}

impl std::error::Error for CameraError {}

impl Camera {
    /// A perspective pinhole camera at `position` looking at `target`.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov_deg: f32,
    ) -> Result<Self, CameraError> {
        Self::look_at_with(position, target, up, Projection::Perspective { fov_deg })
    }

    /// A camera of `projection` at `position` looking at `target`.
    pub fn look_at_with(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        projection: Projection,
    ) -> Result<Self, CameraError> {
        if !(position.is_finite() && target.is_finite() && up.is_finite()) || position == target {
            return Err(CameraError::Degenerate);
        }
        let half_extent = projection.half_extent()?;
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
            projection,
            half_extent,
            lens: None,
            shift: [0.0; 2],
            clip: None,
        })
    }

    /// A camera of `projection` at `position` with the given axes
    /// (Mitsuba's sensor `to_world`: `forward` its local `+z`, `up` its
    /// `+y`, `right` its `−x`). The axes are normalised but kept otherwise,
    /// so a mirroring `to_world` mirrors the image; they must be finite and
    /// non-zero.
    pub fn from_axes(axes: CameraAxes, projection: Projection) -> Result<Self, CameraError> {
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
        Ok(Self {
            position,
            forward,
            right,
            up,
            projection,
            half_extent: projection.half_extent()?,
            lens: None,
            shift: [0.0; 2],
            clip: None,
        })
    }

    /// This camera with a thin lens of `aperture_radius` focused at
    /// `focus_distance` (module docs); an aperture of 0 is a pinhole. An
    /// orthographic camera takes only an aperture of 0.
    pub fn with_lens(self, aperture_radius: f32, focus_distance: f32) -> Result<Self, CameraError> {
        if !(aperture_radius.is_finite()
            && aperture_radius >= 0.0
            && focus_distance.is_finite()
            && focus_distance > 0.0)
        {
            return Err(CameraError::Lens);
        }
        if aperture_radius > 0.0 && matches!(self.projection, Projection::Orthographic { .. }) {
            return Err(CameraError::OrthographicLens);
        }
        Ok(Self {
            lens: (aperture_radius > 0.0).then_some(ThinLens {
                aperture_radius,
                focus_distance,
            }),
            ..self
        })
    }

    /// This camera moved to `axes` (normalised, as [`Camera::from_axes`]),
    /// with everything else kept: what a viewer does when the user moves
    /// the camera.
    pub fn with_axes(self, axes: CameraAxes) -> Result<Self, CameraError> {
        let moved = Self::from_axes(axes, self.projection)?;
        Ok(Self {
            position: moved.position,
            forward: moved.forward,
            right: moved.right,
            up: moved.up,
            ..self
        })
    }

    /// This camera with its film shifted by `(a, b)` of its width and
    /// height (module docs).
    pub fn with_shift(self, shift: [f32; 2]) -> Result<Self, CameraError> {
        if !shift.iter().all(|s| s.abs() <= MAX_SHIFT) {
            return Err(CameraError::Shift);
        }
        Ok(Self { shift, ..self })
    }

    /// This camera with clip planes at depths `near` and `far` (module
    /// docs); `near = 0` and `far = ∞` is no clipping.
    pub fn with_clip(self, near: f32, far: f32) -> Result<Self, CameraError> {
        if !(near >= 0.0 && near.is_finite() && far > near) {
            return Err(CameraError::Clip);
        }
        let clip = (near > 0.0 || far < f32::INFINITY).then_some(ClipRange { near, far });
        Ok(Self { clip, ..self })
    }

    /// The film shift, fractions of the film's width and height.
    pub fn shift(&self) -> [f32; 2] {
        self.shift
    }

    /// The clip planes, `None` for none.
    pub fn clip(&self) -> Option<ClipRange> {
        self.clip
    }

    /// The thin lens, `None` for a pinhole or an orthographic camera.
    pub fn lens(&self) -> Option<ThinLens> {
        self.lens
    }

    /// The projection.
    pub fn projection(&self) -> Projection {
        self.projection
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

    /// The film point, px, whose ray is the projection's axis: the film's
    /// centre moved by the shift (module docs).
    fn film_centre(&self, width: u32, height: u32) -> [f32; 2] {
        [
            (0.5 - self.shift[0]) * width as f32,
            (0.5 - self.shift[1]) * height as f32,
        ]
    }

    /// Film-plane size of one pixel, `2 e / min(w, h)` (module docs).
    fn pixel_scale(&self, width: u32, height: u32) -> f32 {
        2.0 * self.half_extent / width.min(height) as f32
    }

    /// The ray through film point `(x, y)` in pixels: its origin and its
    /// (unnormalised) direction (module docs). For a perspective camera
    /// the direction is the pinhole's, which [`Camera::lens_ray`] takes.
    pub fn film_ray(&self, x: f32, y: f32, width: u32, height: u32) -> (Vec3, Vec3) {
        let scale = self.pixel_scale(width, height);
        let [cx, cy] = self.film_centre(width, height);
        let dx = (x - cx) * scale;
        let dy = (y - cy) * scale;
        match self.projection {
            Projection::Perspective { .. } => {
                (self.position, self.forward + dx * self.right - dy * self.up)
            }
            Projection::Orthographic { .. } => {
                (self.position + dx * self.right - dy * self.up, self.forward)
            }
        }
    }

    /// [`Camera::film_ray`] for 8 film points: the same operations in the
    /// same order, so each lane equals the scalar ray bit for bit.
    pub fn film_ray_x8(&self, x: f32x8, y: f32x8, width: u32, height: u32) -> (Vec3x8, Vec3x8) {
        let scale = f32x8::splat(self.pixel_scale(width, height));
        let [cx, cy] = self.film_centre(width, height);
        let dx = (x - f32x8::splat(cx)) * scale;
        let dy = (y - f32x8::splat(cy)) * scale;
        match self.projection {
            Projection::Perspective { .. } => (
                Vec3x8::splat(self.position),
                Vec3x8::splat(self.forward) + Vec3x8::splat(self.right) * dx
                    - Vec3x8::splat(self.up) * dy,
            ),
            Projection::Orthographic { .. } => (
                Vec3x8::splat(self.position) + Vec3x8::splat(self.right) * dx
                    - Vec3x8::splat(self.up) * dy,
                Vec3x8::splat(self.forward),
            ),
        }
    }

    /// Where a pinhole camera sees `point` (a light path's connection to
    /// the camera, `integrator::light_paths`): the film point, px, whose
    /// ray ([`Camera::film_ray`]) passes through it, and the factor that
    /// turns radiance arriving at the pinhole along that ray into density
    /// over the film, `dA_px/dω = 1/(k² cos³θ)` (`k` the film-plane size of
    /// a pixel at distance 1, `θ` the angle to the viewing direction: the
    /// film plane at distance 1 holds `1/k²` pixels per unit area, and a
    /// unit area there subtends `cos³θ` sr). `None` for an orthographic or
    /// thin-lens camera, a point behind the camera or outside the clip
    /// planes.
    pub fn project(&self, point: Vec3, width: u32, height: u32) -> Option<FilmPoint> {
        if self.lens.is_some() || !matches!(self.projection, Projection::Perspective { .. }) {
            return None;
        }
        self.film_point(self.position, point, point, (width, height))
    }

    /// Where a perspective camera sees `point` through the point `(p, q)`
    /// of its lens's unit disk (the pinhole for a camera without a lens):
    /// the film point whose lens ray ([`Camera::lens_ray`]) from that point
    /// passes through `point`, with the density `1/(k² cos³θ)` of
    /// [`Camera::project`], `θ` now the angle of the ray from the lens point
    /// to the viewing direction, and the lens point. At a fixed lens point
    /// the film maps to the focal plane by a constant `1/(k² f²)` per unit
    /// area, and a unit area of the focal plane subtends `cos³θ/f²` sr
    /// from the lens point: so the pinhole's density holds at every lens
    /// point. A light path's connection draws `(p, q)` uniformly, as the
    /// camera rays do (`integrator::light_paths`). `None` for an
    /// orthographic camera, a point behind the lens or outside the clip
    /// planes.
    pub fn project_through_lens(
        &self,
        point: Vec3,
        (p, q): (f32, f32),
        width: u32,
        height: u32,
    ) -> Option<(FilmPoint, Vec3)> {
        let Some(lens) = self.lens else {
            return self
                .project(point, width, height)
                .map(|f| (f, self.position));
        };
        let eye = self.position
            + self.right * (lens.aperture_radius * p)
            + self.up * (lens.aperture_radius * q);
        let to_point = point - eye;
        let depth = to_point.dot(self.forward);
        if depth.is_nan() || depth <= 0.0 {
            return None;
        }
        let focus = eye + to_point * (lens.focus_distance / depth);
        self.film_point(eye, point, focus, (width, height))
            .map(|film| (film, eye))
    }

    /// The film point of the pinhole ray towards `aim`, with the density
    /// of the direction from `eye` to `point` (module docs of
    /// [`Camera::project`]); `None` where `point` is behind `eye` or
    /// outside the clip planes.
    fn film_point(
        &self,
        eye: Vec3,
        point: Vec3,
        aim: Vec3,
        (width, height): (u32, u32),
    ) -> Option<FilmPoint> {
        let to_point = point - eye;
        let depth = to_point.dot(self.forward);
        let in_clip = self
            .clip
            .is_none_or(|clip| depth >= clip.near && depth <= clip.far);
        let to_aim = aim - self.position;
        let aim_depth = to_aim.dot(self.forward);
        if !(depth > 0.0 && aim_depth > 0.0 && in_clip) {
            return None;
        }
        let scale = self.pixel_scale(width, height);
        let [cx, cy] = self.film_centre(width, height);
        let dx = to_aim.dot(self.right) / aim_depth;
        let dy = -to_aim.dot(self.up) / aim_depth;
        let cos = depth / to_point.length();
        Some(FilmPoint {
            x: cx + dx / scale,
            y: cy + dy / scale,
            density_per_sr: 1.0 / (scale * scale * cos * cos * cos),
        })
    }

    /// The ray of the pinhole direction `d` ([`Camera::film_ray`])
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

    /// A ray `(origin, direction)` of this camera cut to `clip` (module
    /// docs): its new origin and its `t_max` in units of `direction`.
    pub fn clip_ray(&self, clip: ClipRange, (origin, direction): (Vec3, Vec3)) -> (Vec3, f32) {
        let inv_depth_rate = 1.0 / direction.dot(self.forward);
        (
            origin + direction * (clip.near * inv_depth_rate),
            (clip.far - clip.near) * inv_depth_rate,
        )
    }

    /// [`Camera::clip_ray`] of 8 lanes: the same operations in the same
    /// order, lane by lane.
    pub fn clip_ray_x8(
        &self,
        clip: ClipRange,
        (origin, direction): (Vec3x8, Vec3x8),
    ) -> (Vec3x8, f32x8) {
        let inv_depth_rate = f32x8::ONE / direction.dot(Vec3x8::splat(self.forward));
        (
            origin + direction * (f32x8::splat(clip.near) * inv_depth_rate),
            f32x8::splat(clip.far - clip.near) * inv_depth_rate,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tests' camera: at (0.3, 1, 3.9) looking down the −z axis,
    /// slightly down, with `projection`.
    fn test_camera(projection: Projection) -> Result<Camera, CameraError> {
        Camera::look_at_with(
            Vec3::new(0.3, 1.0, 3.9),
            Vec3::new(0.1, 0.9, 0.0),
            Vec3::Y,
            projection,
        )
    }

    #[test]
    fn packet_rays_equal_scalar_rays_bit_for_bit() {
        let mut rng = crate::sampling::rng::Rng::new(3, 5);
        for projection in [
            Projection::Perspective { fov_deg: 39.3 },
            Projection::Orthographic { view_size: 2.7 },
        ] {
            let cam = test_camera(projection).unwrap();
            for (width, height) in [(512, 512), (640, 360), (1, 1), (37, 1000)] {
                for _ in 0..500 {
                    let x: [f32; 8] =
                        core::array::from_fn(|_| rng.next_f32() * (width as f32 + 4.0) - 2.0);
                    let y: [f32; 8] =
                        core::array::from_fn(|_| rng.next_f32() * (height as f32 + 4.0) - 2.0);
                    let (o, d) = cam.film_ray_x8(f32x8::new(x), f32x8::new(y), width, height);
                    for lane in 0..8 {
                        let (origin, scalar) = cam.film_ray(x[lane], y[lane], width, height);
                        assert_eq!(
                            d.lane(lane).to_array().map(f32::to_bits),
                            scalar.to_array().map(f32::to_bits)
                        );
                        assert_eq!(
                            o.lane(lane).to_array().map(f32::to_bits),
                            origin.to_array().map(f32::to_bits)
                        );
                    }
                }
            }
        }
    }

    /// A point on a film ray projects back to that film point, shifted or
    /// not; the density is the film area per solid angle, measured by the
    /// solid angle of a small square of pixels (the negative control: the
    /// density with `cos²θ` instead of `cos³θ` is off by 10 % at the
    /// film's corner). Points behind the camera or outside its clip planes,
    /// and orthographic or thin-lens cameras, have no film point.
    #[test]
    fn points_project_to_the_film_points_whose_rays_meet_them() -> Result<(), CameraError> {
        let cam = test_camera(Projection::Perspective { fov_deg: 50.0 })?;
        let (width, height) = (640, 360);
        for cam in [cam, cam.with_shift([0.1, -0.2])?] {
            for &(x, y) in &[
                (320.0f32, 180.0f32),
                (3.5, 7.25),
                (639.0, 359.0),
                (100.0, 300.0),
            ] {
                let (origin, direction) = cam.film_ray(x, y, width, height);
                let Some(point) = cam.project(origin + 2.7 * direction, width, height) else {
                    panic!("no film point");
                };
                assert!(
                    (point.x - x).abs() < 1e-3 && (point.y - y).abs() < 1e-3,
                    "{point:?}"
                );
                // A square of h × h pixels around (x, y) subtends Ω ≈ the
                // solid angle of its corners' directions' parallelogram.
                let h = 0.5f32;
                let unit =
                    |dx: f32, dy: f32| cam.film_ray(x + dx, y + dy, width, height).1.normalize();
                let (a, b, c) = (unit(-h, -h), unit(h, -h), unit(-h, h));
                let solid_angle = (b - a).cross(c - a).length();
                let expected = (2.0 * h) * (2.0 * h) / solid_angle;
                assert!(
                    (point.density_per_sr / expected - 1.0).abs() < 2e-3,
                    "{} vs {expected}",
                    point.density_per_sr
                );
                let cos = direction.normalize().dot(cam.forward);
                if (x, y) == (3.5, 7.25) {
                    assert!((point.density_per_sr * cos / expected - 1.0).abs() > 0.1);
                }
            }
        }
        assert!(
            cam.project(cam.position - cam.forward, width, height)
                .is_none()
        );
        let clipped = cam.with_clip(1.0, 3.0)?;
        for (depth, seen) in [(0.5, false), (2.0, true), (3.5, false)] {
            let point = cam.position + depth * cam.forward;
            assert_eq!(
                clipped.project(point, width, height).is_some(),
                seen,
                "{depth}"
            );
        }
        let lens = cam.with_lens(0.1, 2.0)?;
        assert!(
            lens.project(cam.position + cam.forward, width, height)
                .is_none()
        );
        let ortho = Camera::look_at_with(
            Vec3::ZERO,
            Vec3::Z,
            Vec3::Y,
            Projection::Orthographic { view_size: 2.0 },
        )?;
        assert!(ortho.project(Vec3::Z, width, height).is_none());
        Ok(())
    }

    /// Through a thin lens, a point on the lens ray of film point `x` from
    /// lens point `(p, q)` projects back to `x` and that lens point; the
    /// density at the lens point equals the film area per solid angle of a
    /// small square of pixels seen from it (`cos²θ` instead of `cos³θ` is
    /// off by more than 10 % at a corner: negative control); without a
    /// lens it is [`Camera::project`]; points behind the lens, outside the
    /// clip planes and an orthographic camera give none.
    #[test]
    fn points_project_through_the_lens_to_the_film_points_whose_rays_meet_them()
    -> Result<(), CameraError> {
        let pinhole = test_camera(Projection::Perspective { fov_deg: 50.0 })?;
        let (width, height) = (640, 360);
        let cam = pinhole.with_lens(0.2, 3.0)?.with_shift([0.05, 0.1])?;
        let lens = cam.lens().ok_or(CameraError::Lens)?;
        for &(x, y) in &[(320.0f32, 180.0f32), (3.5, 7.25), (639.0, 359.0)] {
            for &(p, q) in &[(0.0f32, 0.0f32), (0.7, -0.2), (-0.5, 0.6)] {
                let (_, pinhole_direction) = cam.film_ray(x, y, width, height);
                let (origin, direction) = cam.lens_ray(lens, pinhole_direction, (p, q));
                for distance in [1.5f32, 3.0, 7.0] {
                    let Some((point, eye)) = cam.project_through_lens(
                        origin + distance * direction,
                        (p, q),
                        width,
                        height,
                    ) else {
                        panic!("no film point");
                    };
                    assert!((eye - origin).length() < 1e-5, "{eye} vs {origin}");
                    assert!(
                        (point.x - x).abs() < 2e-2 && (point.y - y).abs() < 2e-2,
                        "{point:?} vs ({x}, {y})"
                    );
                }
                // The square of h × h pixels around (x, y), its rays from the
                // lens point: their solid angle against the density.
                let h = 0.5f32;
                let unit = |dx: f32, dy: f32| {
                    let (_, d) = cam.film_ray(x + dx, y + dy, width, height);
                    cam.lens_ray(lens, d, (p, q)).1
                };
                let (a, b, c) = (unit(-h, -h), unit(h, -h), unit(-h, h));
                let solid_angle = (b - a).cross(c - a).length();
                let expected = (2.0 * h) * (2.0 * h) / solid_angle;
                let Some((point, _)) =
                    cam.project_through_lens(origin + 2.0 * direction, (p, q), width, height)
                else {
                    panic!("no film point");
                };
                assert!(
                    (point.density_per_sr / expected - 1.0).abs() < 5e-3,
                    "{} vs {expected}",
                    point.density_per_sr
                );
                if (x, y) == (3.5, 7.25) {
                    let cos = direction.dot(cam.forward);
                    assert!((point.density_per_sr * cos / expected - 1.0).abs() > 0.1);
                }
            }
        }
        let point = pinhole.position + 2.0 * pinhole.forward + 0.3 * pinhole.right;
        assert_eq!(
            pinhole.project_through_lens(point, (0.5, 0.5), width, height),
            pinhole
                .project(point, width, height)
                .map(|f| (f, pinhole.position))
        );
        assert!(
            cam.project_through_lens(cam.position - cam.forward, (0.1, 0.1), width, height)
                .is_none()
        );
        let clipped = cam.with_clip(1.0, 3.0)?;
        for (depth, seen) in [(0.5, false), (2.0, true), (3.5, false)] {
            let point = cam.position + depth * cam.forward;
            assert_eq!(
                clipped
                    .project_through_lens(point, (0.3, 0.0), width, height)
                    .is_some(),
                seen,
                "{depth}"
            );
        }
        let ortho = test_camera(Projection::Orthographic { view_size: 2.0 })?;
        let ahead = ortho.position + ortho.forward;
        assert!(
            ortho
                .project_through_lens(ahead, (0.0, 0.0), width, height)
                .is_none()
        );
        Ok(())
    }

    /// Orthographic rays: all parallel to the view, from a film plane
    /// through the position, perpendicular to the view, `view_size` wide
    /// along the smaller axis (a 200 × 100 film of view size 3 spans 6 × 3
    /// scene units), the image's top-left corner up and to the left.
    #[test]
    fn orthographic_rays_are_parallel_and_span_the_view_size() {
        let position = Vec3::new(1.0, 2.0, 5.0);
        let cam = Camera::look_at_with(
            position,
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::Y,
            Projection::Orthographic { view_size: 3.0 },
        )
        .unwrap();
        let (width, height) = (200, 100);
        let (centre, d) = cam.film_ray(100.0, 50.0, width, height);
        assert!((centre - position).length() < 1e-6);
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        let (corner, d) = cam.film_ray(0.0, 0.0, width, height);
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        // Looking down −z with +y up, image right is +x.
        assert!(
            (corner - (position + Vec3::new(-3.0, 1.5, 0.0))).length() < 1e-5,
            "{corner}"
        );
        let (far, _) = cam.film_ray(200.0, 100.0, width, height);
        assert!((far - corner - Vec3::new(6.0, -3.0, 0.0)).length() < 1e-5);
        // The perspective camera of the same axes differs in both parts.
        let perspective = Camera::look_at_with(
            position,
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::Y,
            Projection::Perspective { fov_deg: 40.0 },
        )
        .unwrap();
        let (o, d) = perspective.film_ray(0.0, 0.0, width, height);
        assert!(o == position && (d.normalize() - Vec3::NEG_Z).length() > 0.1);
    }

    #[test]
    fn projections_refuse_invalid_sizes_and_an_orthographic_lens() {
        let at = |projection| Camera::look_at_with(Vec3::Z, Vec3::ZERO, Vec3::Y, projection);
        for view_size in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(
                at(Projection::Orthographic { view_size }),
                Err(CameraError::ViewSize),
                "{view_size}"
            );
        }
        let ortho = at(Projection::Orthographic { view_size: 2.0 }).unwrap();
        assert_eq!(
            ortho.with_lens(0.1, 3.0),
            Err(CameraError::OrthographicLens)
        );
        assert_eq!(ortho.with_lens(0.0, 3.0), Ok(ortho));
        assert_eq!(
            at(Projection::Perspective { fov_deg: 180.0 }),
            Err(CameraError::FieldOfView)
        );
    }

    /// A shifted film: pixel `(x, y)` takes the unshifted camera's ray of
    /// `(x + a w, y + b h)`, for both projections; lanes equal the scalar
    /// rays bit for bit. Clip planes: origins at depth `near` (lanes
    /// against the scalar oracle), `t_max` ending at depth `far`.
    #[test]
    fn shifted_films_and_clip_planes() {
        let mut rng = crate::sampling::rng::Rng::new(9, 2);
        let (width, height) = (64u32, 40u32);
        let shift = [0.25f32, -0.125];
        for projection in [
            Projection::Perspective { fov_deg: 50.0 },
            Projection::Orthographic { view_size: 3.0 },
        ] {
            let plain =
                Camera::look_at_with(Vec3::new(0.5, 1.0, 4.0), Vec3::ZERO, Vec3::Y, projection)
                    .unwrap();
            let shifted = plain.with_shift(shift).unwrap();
            let clipped = shifted.with_clip(0.75, 6.0).unwrap();
            for _ in 0..200 {
                let x: [f32; 8] = core::array::from_fn(|_| rng.next_f32() * width as f32);
                let y: [f32; 8] = core::array::from_fn(|_| rng.next_f32() * height as f32);
                let rays = shifted.film_ray_x8(f32x8::new(x), f32x8::new(y), width, height);
                let (o8, t8) = clipped.clip_ray_x8(clipped.clip().unwrap(), rays);
                for lane in 0..8 {
                    let (o, d) = shifted.film_ray(x[lane], y[lane], width, height);
                    let (po, pd) = plain.film_ray(
                        x[lane] + shift[0] * width as f32,
                        y[lane] + shift[1] * height as f32,
                        width,
                        height,
                    );
                    assert!((o - po).length() < 1e-5 && (d - pd).length() < 1e-5);
                    assert_eq!(rays.1.lane(lane).to_array(), d.to_array());
                    let (clipped_origin, t_max) = clipped.clip_ray(clipped.clip().unwrap(), (o, d));
                    assert!((o8.lane(lane) - clipped_origin).length() < 1e-6);
                    assert!((t8.to_array()[lane] - t_max).abs() <= 1e-6 * t_max);
                    let depth = |p: Vec3| (p - clipped.position).dot(clipped.forward);
                    assert!((depth(clipped_origin) - 0.75).abs() < 1e-5);
                    assert!((depth(clipped_origin + d * t_max) - 6.0).abs() < 1e-4);
                }
            }
        }
        // Shifted by half a film, the left edge's ray is the centre's.
        let plain = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let half = plain.with_shift([-0.5, 0.0]).unwrap();
        assert_eq!(
            half.film_ray(32.0, 20.0, 64, 40).1,
            plain.film_ray(0.0, 20.0, 64, 40).1
        );
        for (near, far) in [
            (-0.1, 2.0),
            (1.0, 1.0),
            (f32::INFINITY, f32::INFINITY),
            (0.0, f32::NAN),
        ] {
            assert_eq!(
                plain.with_clip(near, far),
                Err(CameraError::Clip),
                "{near} {far}"
            );
        }
        assert_eq!(plain.with_clip(0.0, f32::INFINITY).unwrap().clip(), None);
        for shift in [[f32::NAN, 0.0], [0.0, 17.0]] {
            assert_eq!(plain.with_shift(shift), Err(CameraError::Shift));
        }
    }

    /// A moved camera keeps its projection, lens, shift and clip planes.
    #[test]
    fn moving_a_camera_keeps_everything_but_its_axes() {
        let lensed = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0)
            .unwrap()
            .with_lens(0.1, 3.0)
            .unwrap()
            .with_shift([0.1, -0.2])
            .unwrap()
            .with_clip(0.5, 9.0)
            .unwrap();
        let other = Camera::look_at(Vec3::new(2.0, 1.0, 0.0), Vec3::ZERO, Vec3::Y, 70.0).unwrap();
        let moved = lensed.with_axes(other.axes()).unwrap();
        let (a, b) = (moved.axes(), other.axes());
        for (u, v) in [
            (a.position, b.position),
            (a.forward, b.forward),
            (a.right, b.right),
            (a.up, b.up),
        ] {
            assert!((u - v).length() < 1e-6, "{u} vs {v}");
        }
        assert_eq!(moved.projection(), lensed.projection());
        assert_eq!(moved.lens(), lensed.lens());
        assert_eq!(moved.shift(), [0.1, -0.2]);
        assert_eq!(
            moved.clip(),
            Some(ClipRange {
                near: 0.5,
                far: 9.0
            })
        );
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
            let (_, d) = cam.film_ray_x8(f32x8::new(x), f32x8::new(y), width, height);
            let (o8, w8) = cam.lens_ray_x8(lens, d, (f32x8::new(p), f32x8::new(q)));
            for lane in 0..8 {
                let (_, dl) = cam.film_ray(x[lane], y[lane], width, height);
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
        let d = cam.film_ray(50.0, 50.0, 100, 100).1;
        assert!((d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // fov 90° along the smaller axis: the left edge is at 45°.
        let d = cam.film_ray(0.0, 50.0, 100, 100).1.normalize();
        assert!((d.x + std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
        let d = cam.film_ray(100.0, 0.0, 200, 100).1.normalize();
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
