//! `[render]`, `[camera]` and `[environment]`: the sections that set one
//! thing each.

use super::Loader;
use crate::coefficient_choice::{CoeffsChoice, SUPPORTED_COEFFS};
use crate::coeffs::MAX_COEFFS;
use crate::error::CliError;
use crate::scene_file::construction::MapSettings;
use crate::scene_file::toml_reader::Item;
use crate::scene_file::{
    FILTER_NAMES, FilterChoice, MAX_IMAGE_EDGE, RenderDefaults, SAMPLING_NAMES, TRANSPORT_NAMES,
};
use crate::sensor_file::{ObserverChoice, load_sensor_csv};
use glam::{Mat3, Vec3};
use simd_tracer::film::FilmMode;
use simd_tracer::sampling::sampler::SamplerKind;
use simd_tracer::scene::camera::{Camera, CameraError, Projection};
use simd_tracer::spectra::environment::EnvironmentMap;

impl Loader<'_> {
    /// `[render]`: the defaults that command-line flags override.
    pub(super) fn render_section(&self, item: &Item<'_, '_>) -> Result<RenderDefaults, CliError> {
        let src = &self.src;
        let table = item.table(src)?;
        table.allow(
            src,
            &[
                "width",
                "height",
                "spp",
                "max_depth",
                "seed",
                "hide_emitters",
                "film",
                "filter",
                "transport",
                "sampling",
                "coeffs",
                "sampler",
                "observer",
                "sensor",
            ],
            "[render]",
        )?;
        let observer = match (table.get("observer"), table.get("sensor")) {
            (Some(_), Some(sensor)) => {
                return Err(sensor.err(src, "give `observer` or `sensor`, not both"));
            }
            (Some(name), None) => Some(
                ObserverChoice::standard(name.string(src)?)
                    .map_err(|e| name.err(src, e.to_string()))?,
            ),
            (None, Some(sensor)) => {
                let path = self.file(&sensor)?;
                Some(ObserverChoice::Sensor(
                    load_sensor_csv(&path).map_err(|e| sensor.err(src, e.to_string()))?,
                ))
            }
            (None, None) => None,
        };
        let get = |key: &str, min: i64, max: i64| -> Result<Option<i64>, CliError> {
            table.get(key).map(|i| i.integer(src, min, max)).transpose()
        };
        // A string that must be one of `names`, kept as written for the
        // command line's parser (an unknown one is refused here, not
        // ignored there).
        let named = |key: &str, names: &[&str]| -> Result<Option<String>, CliError> {
            table
                .get(key)
                .map(|i| {
                    let name = i.string(src)?;
                    names
                        .contains(&name)
                        .then(|| name.to_string())
                        .ok_or_else(|| {
                            i.err(src, format!("{key} `{name}`: use {}", names.join(", ")))
                        })
                })
                .transpose()
        };
        let u32_max = i64::from(u32::MAX);
        Ok(RenderDefaults {
            observer,
            width: get("width", 1, MAX_IMAGE_EDGE)?.map(|v| v as u32),
            height: get("height", 1, MAX_IMAGE_EDGE)?.map(|v| v as u32),
            spp: get("spp", 1, u32_max)?.map(|v| v as u32),
            max_depth: get("max_depth", 1, u32_max)?.map(|v| v as u32),
            seed: get("seed", 0, i64::MAX)?.map(|v| v as u64),
            hide_emitters: table
                .get("hide_emitters")
                .map(|i| i.boolean(src))
                .transpose()?,
            film: table
                .get("film")
                .map(|i| {
                    let name = i.string(src)?;
                    FilmMode::from_name(name)
                        .ok_or_else(|| i.err(src, format!("film `{name}`: use sample or splat")))
                })
                .transpose()?,
            filter: table
                .get("filter")
                .map(|i| {
                    let name = i.string(src)?;
                    FilterChoice::named(name).ok_or_else(|| {
                        i.err(
                            src,
                            format!("filter `{name}`: use {}", FILTER_NAMES.join(", ")),
                        )
                    })
                })
                .transpose()?,
            transport: named("transport", &TRANSPORT_NAMES)?,
            sampling: named("sampling", &SAMPLING_NAMES)?,
            coeffs: table
                .get("coeffs")
                .map(|i| match i.string(src) {
                    Ok(name) => CoeffsChoice::parse(name).map_err(|e| i.err(src, e)),
                    Err(_) => match i.integer(src, 1, MAX_COEFFS as i64)? as usize {
                        n if SUPPORTED_COEFFS.contains(&n) => Ok(CoeffsChoice::Fixed(n)),
                        n => Err(i.err(
                            src,
                            format!(
                                "{n} coefficients: use \"auto\" or one of {SUPPORTED_COEFFS:?}"
                            ),
                        )),
                    },
                })
                .transpose()?,
            sampler: table
                .get("sampler")
                .map(|i| {
                    let name = i.string(src)?;
                    SamplerKind::from_name(name).ok_or_else(|| {
                        i.err(src, format!("sampler `{name}`: use independent or sobol"))
                    })
                })
                .transpose()?,
            ..RenderDefaults::default()
        })
    }

    /// `[camera]`: a perspective camera, a pinhole or a thin lens with
    /// `aperture_radius` (scene units, default 0: a pinhole) focused at
    /// `focus_distance` (default: the distance to `target`, so that the
    /// target is sharp); or, with `projection = "orthographic"`, parallel
    /// rays from a film plane `view_size` scene units across along the
    /// smaller image axis, centred at `position`. Either takes a film
    /// `shift` (fractions of the film's width and height) and clip planes
    /// `near_clip` and `far_clip` (depths along the view; default none).
    pub(super) fn camera_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let src = &self.src;
        let table = item.table(src)?;
        table.allow(
            src,
            &[
                "position",
                "target",
                "up",
                "projection",
                "fov_deg",
                "view_size",
                "aperture_radius",
                "focus_distance",
                "shift",
                "near_clip",
                "far_clip",
            ],
            "[camera]",
        )?;
        let position_item =
            table.require(src, "position", "the camera needs `position = [x, y, z]`")?;
        let target_item = table.require(src, "target", "the camera needs `target = [x, y, z]`")?;
        let orthographic = match table.get("projection") {
            Some(p) => match p.string(src)? {
                "perspective" => false,
                "orthographic" => true,
                other => {
                    return Err(p.err(
                        src,
                        format!("projection `{other}`: use perspective or orthographic"),
                    ));
                }
            },
            None => false,
        };
        // Each projection's keys, and the other's refused.
        let (size_key, other_keys): (&str, &[&str]) = if orthographic {
            (
                "view_size",
                &["fov_deg", "aperture_radius", "focus_distance"],
            )
        } else {
            ("fov_deg", &["view_size"])
        };
        for key in other_keys {
            if let Some(extra) = table.get(key) {
                let projection = if orthographic {
                    "an orthographic"
                } else {
                    "a perspective"
                };
                return Err(extra.err(
                    src,
                    format!("`{key}` does not apply to {projection} camera"),
                ));
            }
        }
        let size_item = table.require(src, size_key, &format!("the camera needs `{size_key}`"))?;
        let position = position_item.vec3(src)?;
        let target = target_item.vec3(src)?;
        let up_item = table.get("up");
        let up = match &up_item {
            Some(up) => up.vec3(src)?,
            None => Vec3::Y,
        };
        let size = size_item.number(src)? as f32;
        let projection = if orthographic {
            Projection::Orthographic { view_size: size }
        } else {
            Projection::Perspective { fov_deg: size }
        };
        let camera =
            Camera::look_at_with(position, target, up, projection).map_err(|e| match e {
                CameraError::FieldOfView => size_item.err(src, "must be between 0 and 180 degrees"),
                CameraError::ViewSize => size_item.err(src, "must be finite and > 0 (scene units)"),
                CameraError::UpParallel => match &up_item {
                    Some(up) => up.err(src, e),
                    None => target_item.err(src, e),
                },
                CameraError::Degenerate
                | CameraError::Lens
                | CameraError::OrthographicLens
                | CameraError::Clip
                | CameraError::Shift => target_item.err(src, e),
            })?;
        let camera = match table.get("shift") {
            Some(item) => {
                let shift = item.numbers(src, 2)?;
                camera
                    .with_shift([shift[0] as f32, shift[1] as f32])
                    .map_err(|e| item.err(src, e))?
            }
            None => camera,
        };
        let near = match table.get("near_clip") {
            Some(item) => {
                let depth = item.non_negative(src)? as f32;
                if !depth.is_finite() {
                    return Err(item.err(src, "too large for single precision"));
                }
                Some((depth, item))
            }
            None => None,
        };
        let far = match table.get("far_clip") {
            Some(item) => Some((item.number(src)? as f32, item)),
            None => None,
        };
        let camera = match (near, far) {
            (None, None) => camera,
            (near, far) => {
                let near_value = near.as_ref().map_or(0.0, |n| n.0);
                let far_value = far.as_ref().map_or(f32::INFINITY, |f| f.0);
                let blamed = far.or(near).map(|(_, item)| item);
                camera
                    .with_clip(near_value, far_value)
                    .map_err(|e| match blamed {
                        Some(item) => item.err(src, e),
                        None => table.err(src, e),
                    })?
            }
        };
        if orthographic {
            self.cx.set_camera(camera);
            return Ok(());
        }
        let aperture_radius = match table.get("aperture_radius") {
            Some(a) => {
                let radius = a.non_negative(src)? as f32;
                if !radius.is_finite() {
                    return Err(a.err(src, "too large for single precision"));
                }
                radius
            }
            None => 0.0,
        };
        let focus_distance = match table.get("focus_distance") {
            Some(f) => {
                let distance = f.number(src)? as f32;
                if !(distance > 0.0 && distance.is_finite()) {
                    return Err(f.err(src, "must be a distance > 0"));
                }
                distance
            }
            None => position.distance(target),
        };
        let camera = camera
            .with_lens(aperture_radius, focus_distance)
            .map_err(|e| table.err(src, e))?;
        self.cx.set_camera(camera);
        Ok(())
    }

    /// `[environment]`: a constant radiance from every direction
    /// (`spectrum`), or an equirectangular map (`map`, with `transform`, a
    /// rotation), times `scale`.
    pub(super) fn environment_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let table = item.table(&self.src)?;
        table.allow(
            &self.src,
            &["spectrum", "map", "transform", "scale"],
            "[environment]",
        )?;
        let scale = match table.get("scale") {
            Some(s) => s.non_negative(&self.src)?,
            None => 1.0,
        };
        match (table.get("spectrum"), table.get("map")) {
            (Some(spectrum), None) => {
                if let Some(t) = table.get("transform") {
                    return Err(t.err(&self.src, "a constant environment has no `transform`"));
                }
                let id = self.spectrum_ref(&spectrum, scale)?;
                self.cx.set_environment(id);
            }
            (None, Some(map)) => {
                let path = self.file(&map)?;
                let to_world = match table.get("transform") {
                    Some(t) => {
                        let affine = self.transform(&t)?.affine();
                        let linear = Mat3::from(affine.matrix3);
                        if !EnvironmentMap::is_rotation(linear) || affine.translation.length() > 0.0
                        {
                            return Err(t.err(
                                &self.src,
                                "an environment map's transform must be a rotation",
                            ));
                        }
                        linear
                    }
                    None => Mat3::IDENTITY,
                };
                self.cx.environment_map(
                    &map.spot(),
                    &MapSettings {
                        path: &path,
                        scale: scale as f32,
                        to_world,
                    },
                )?;
            }
            _ => {
                return Err(table.err(
                    &self.src,
                    "the environment needs exactly one of `spectrum` (constant) and `map` (an image file)",
                ));
            }
        }
        Ok(())
    }
}
