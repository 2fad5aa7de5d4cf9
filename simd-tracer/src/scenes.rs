//! Built-in scenes.
//!
//! * [`cornell_box`]: the scene of `scenes/cornell/` — Mitsuba 3's
//!   `mi.cornell_box()` geometry, camera (pinhole at (0, 0, 3.9) looking
//!   along −z, up +y, 39.3077° along the smaller axis) and materials (linear
//!   sRGB `Kd` upsampled, `Ke` an RGB illuminant).

use crate::camera::Camera;
use crate::obj::{ObjError, ObjSource, load_obj};
use crate::scene::{Scene, SceneBuilder, SceneError};
use glam::Vec3;
use spectral_core::SpectralRange;

/// The Cornell box OBJ (also at `scenes/cornell/cornell.obj`).
pub const CORNELL_OBJ: &str = include_str!("../../scenes/cornell/cornell.obj");
/// The Cornell box MTL.
pub const CORNELL_MTL: &str = include_str!("../../scenes/cornell/cornell.mtl");
/// Field of view of the Cornell box camera, degrees (smaller axis).
pub const CORNELL_FOV_DEG: f32 = 39.3077;

/// The Cornell box camera.
pub fn cornell_camera() -> Result<Camera, SceneError> {
    Camera::look_at(
        Vec3::new(0.0, 0.0, 3.9),
        Vec3::ZERO,
        Vec3::Y,
        CORNELL_FOV_DEG,
    )
    .map_err(|e| SceneError::Bvh(e.to_string()))
}

/// The Cornell box builder (before `build`), over `range`.
pub fn cornell_builder(range: SpectralRange) -> Result<SceneBuilder, ObjError> {
    let mut builder = SceneBuilder::new(range);
    let source = ObjSource::Text {
        name: "cornell.obj",
        obj: CORNELL_OBJ,
        mtl: CORNELL_MTL,
    };
    load_obj(&mut builder, source, &|_| None)?;
    builder.set_camera(cornell_camera().map_err(ObjError::Scene)?);
    Ok(builder)
}

/// The Cornell box over `range`.
pub fn cornell_box(range: SpectralRange) -> Result<Scene, ObjError> {
    cornell_builder(range)?.build().map_err(ObjError::Scene)
}
