//! The sensor (camera, film, reconstruction filter, sampler) and the
//! integrator, as Mitsuba 3.9.1 reads them.
//!
//! * `thinlens`: `perspective`'s parameters and the thin lens's
//!   `aperture_radius` (required, as in Mitsuba; 0 is a pinhole) and
//!   `focus_distance` (default: the far clip, 10⁴), the distance of the
//!   plane in focus (`src/sensors/thinlens.cpp`; the lens model is
//!   `simd_tracer::scene::camera`'s).
//! * `orthographic` (`src/sensors/orthographic.cpp`): a film plane
//!   spanning local `x` ∈ [−1, 1] across the film's width and
//!   `y` ∈ [−h/w, h/w], both scaled by `to_world`; rays along local `+z`
//!   from the near clip. Our camera holds the plane's extent along the
//!   smaller axis, `view_size = 2 s_x min(w, h)/w` for the scale `s_x` of
//!   local `x`; a `to_world` that scales `x` and `y` differently
//!   (non-square pixels) is refused.
//! * Every sensor clips: rays start at depth `near_clip` (default 0.01)
//!   and end at depth `far_clip` (default 10⁴); an orthographic sensor's
//!   near depth is scaled by its `to_world`'s `z` scale and its rays run
//!   `far_clip − near_clip` beyond it (`orthographic.cpp`). `perspective`
//!   and `thinlens` refuse a scaled `to_world`, as Mitsuba does.
//!   `src/render/sensor.cpp` refuses `near_clip ≤ 0` and
//!   `near_clip ≥ far_clip`, so does this importer.
//! * `perspective`: `to_world` (local `+z` is the viewing direction, `+y`
//!   up and `+x` the image's left: `src/sensors/perspective.cpp` maps the
//!   film's `x` to local `−x`), `fov` in degrees along `fov_axis` (`x`, the
//!   default, `y`, `diagonal`, `smaller`, `larger`), or `focal_length`
//!   (a string, default `"50mm"`: the diagonal field of view of a
//!   36 × 24 mm film, `2 atan(√(36² + 24²) / 2f)`, applied to the image's
//!   diagonal whatever `fov_axis` says, as Mitsuba's `parse_fov` does). Our camera holds the field
//!   of view along the smaller image axis: `tan(fov_smaller/2) =
//!   tan(fov_axis/2) · min(w, h) / L_axis` with `L_axis` the axis' length
//!   in pixels (`w`, `h` or `√(w² + h²)`). `principal_point_offset_x/y`
//!   (fractions of the film's width and height) shift the film
//!   (`simd_tracer::scene::camera`'s film shift; only `perspective` has
//!   them).
//! * `hdrfilm`: `width` (default 768), `height` (576), `crop_offset_x/y`,
//!   `crop_width/height` (the rendered window), `rfilter` (default
//!   `gaussian`); `pixel_format`, `component_format`, `sample_border` and
//!   `banner` do not change the rendered radiance and are accepted.
//! * `rfilter`: `box`, `tent` (`radius`, default 1 px), `gaussian`
//!   (`stddev`, default 0.5 px, truncated at 4 σ), `mitchell` (`B`, `C`,
//!   default 1/3 each, in [0, 1]), `catmullrom`, `lanczos` (`lobes`,
//!   default 3); the last three have negative lobes and need the
//!   splatting film (the default).
//! * `sampler`: `independent`, `stratified`, `multijitter`, `orthogonal`
//!   and `ldsampler` (`sample_count`, default 4; `seed`, default 0). The
//!   count is rounded as each of Mitsuba's samplers rounds it
//!   (`src/samplers/*.cpp`, [`mitsuba_sample_count`]; a warning when it
//!   changes, as Mitsuba logs one); the numbers come from fspec's own
//!   sampler (`--sampler`, default Owen-scrambled Sobol points), whose
//!   image converges to the same result. Other samplers are unsupported
//!   (an error; `--lenient`: fspec's sampler with the count as given).
//! * integrators: `path` (`max_depth`, default −1 = unlimited, as Mitsuba:
//!   1 shows only emitters, 2 adds direct light; `rr_depth`, default 5;
//!   `hide_emitters`), `direct` (direct lighting only: a path of at most 2
//!   segments with light sampling and BSDF sampling combined by MIS, which
//!   is Mitsuba's `direct` with one emitter and one BSDF sample — the
//!   counts `emitter_samples` and `bsdf_samples` change the noise, not the
//!   image), `volpath`/`volpathmis` on scenes without media render as
//!   `path` (a warning). A scene without an integrator (which Mitsuba
//!   refuses to render) renders with `path`'s defaults, with a warning.

use super::Importer;
use super::document::Element;
use super::properties::Object;
use crate::error::CliError;
use crate::scene_file::{CropWindow, FilterChoice, MAX_IMAGE_EDGE};
use glam::Vec3;
use simd_tracer::film::filter::{
    CATMULL_ROM_B_C, LANCZOS_LOBES, MAX_FILTER_RADIUS_PX, MITCHELL_B_C,
};
use simd_tracer::scene::camera::{Camera, CameraAxes, Projection};

/// Mitsuba's film defaults, px (`src/films/hdrfilm.cpp`).
const DEFAULT_FILM_WIDTH: i64 = 768;
/// Mitsuba's film height default, px.
const DEFAULT_FILM_HEIGHT: i64 = 576;
/// Mitsuba's default focal length, mm, on a 36 × 24 mm film.
const DEFAULT_FOCAL_LENGTH_MM: f64 = 50.0;
/// Width of the 35 mm film that focal lengths refer to, mm.
const FILM_35MM_WIDTH_MM: f64 = 36.0;
/// Height of the 35 mm film, mm.
const FILM_35MM_HEIGHT_MM: f64 = 24.0;
/// Mitsuba's default near clip distance.
const DEFAULT_NEAR_CLIP: f64 = 1e-2;
/// Mitsuba's default far clip distance, also `thinlens`'s default focus
/// distance (`src/render/sensor.cpp`, `ProjectiveCamera`).
const DEFAULT_FAR_CLIP: f64 = 1e4;
/// How far from 1 the length of a `thinlens`'s `to_world` axis may be:
/// room for the rounding of composed rotations, far below any deliberate
/// scale.
const UNIT_AXIS_TOLERANCE: f32 = 1e-3;
/// Mitsuba's default tent radius, px.
const DEFAULT_TENT_RADIUS_PX: f64 = 1.0;
/// Mitsuba's default Gaussian standard deviation, px.
const DEFAULT_GAUSSIAN_STDDEV_PX: f64 = 0.5;
/// Mitsuba's default samples per pixel (`independent`).
const DEFAULT_SAMPLE_COUNT: i64 = 4;
/// Mitsuba's default Russian-roulette depth.
const DEFAULT_RR_DEPTH: i64 = 5;
/// Path length of Mitsuba's `direct` integrator in our depth convention.
const DIRECT_MAX_DEPTH: u32 = 2;

/// The sensors this importer reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SensorKind {
    Perspective,
    ThinLens,
    Orthographic,
}

/// A `perspective` or `thinlens` sensor's field of view along the smaller
/// axis of a `w × h` film, degrees, from `fov` and `fov_axis` or
/// `focal_length` (module docs).
fn perspective_fov_smaller_deg(object: &Object<'_>, w: f64, h: f64) -> Result<f64, CliError> {
    let fov_given = object.float_opt("fov")?;
    let focal = object.string("focal_length")?;
    let axis = object.string("fov_axis")?.unwrap_or("x");
    let axis_px = match axis {
        "x" => w,
        "y" => h,
        "diagonal" => w.hypot(h),
        "smaller" => w.min(h),
        "larger" => w.max(h),
        other => {
            return Err(object.error(format!(
                "fov_axis \"{other}\" is not one of x, y, diagonal, smaller, larger"
            )));
        }
    };
    let tan_half_axis = match (fov_given, focal) {
        (Some(_), Some(_)) => {
            return Err(object.error("give `fov` or `focal_length`, not both"));
        }
        (Some(fov), None) => {
            if !(fov > 0.0 && fov < 180.0) {
                return Err(object.error(format!("fov {fov}: must be between 0 and 180 degrees")));
            }
            (0.5 * fov.to_radians()).tan()
        }
        (None, focal) => {
            let mm = match focal {
                Some(text) => parse_millimetres(text).ok_or_else(|| {
                    object.error(format!("focal_length \"{text}\": expected e.g. \"50mm\""))
                })?,
                None => DEFAULT_FOCAL_LENGTH_MM,
            };
            // The 35 mm film's diagonal, on the image's diagonal.
            FILM_35MM_WIDTH_MM.hypot(FILM_35MM_HEIGHT_MM) / (2.0 * mm)
        }
    };
    let axis_px = if fov_given.is_some() {
        axis_px
    } else {
        w.hypot(h)
    };
    let tan_half_smaller = tan_half_axis * w.min(h) / axis_px;
    let fov_smaller_deg = (2.0 * tan_half_smaller.atan()).to_degrees();
    Ok(fov_smaller_deg)
}

/// The largest `sample_count` accepted: 2²⁰ samples per pixel, far above
/// any render, whose rounded counts (at most `(⌈√n⌉ + 1)²` for the
/// square counts, a power of two's square for `ldsampler`) stay in `u32`.
const MAX_SAMPLE_COUNT: u32 = 1 << 20;

/// The sample count that Mitsuba 3.9.1's sampler `plugin` renders for a
/// requested `spp` (`src/samplers/*.cpp`, `set_sample_count`), `None` for
/// a sampler it does not have:
///
/// * `independent`: `spp`;
/// * `stratified`: the smallest square `r² ≥ spp`;
/// * `multijitter`: `r₀ r₁` with `r₁ = ⌊√spp⌋`, `r₀ = ⌈spp / r₁⌉`;
/// * `orthogonal`: `p²` for the smallest prime `p ≥ 2` with `p² ≥ spp`;
/// * `ldsampler`: `r²` for the smallest power of two `r ≥ 2` with
///   `r² ≥ spp`.
fn mitsuba_sample_count(plugin: &str, spp: u32) -> Option<u32> {
    let smallest_root = |accept: &dyn Fn(u32) -> bool, start: u32| {
        (start..)
            .find(|&r| r.saturating_mul(r) >= spp && accept(r))
            .map(|r| r * r)
    };
    match plugin {
        "independent" => Some(spp),
        "stratified" => smallest_root(&|_| true, 1),
        "multijitter" => {
            let rows = (1u32..)
                .take_while(|r| r.saturating_mul(*r) <= spp)
                .last()?;
            Some(spp.div_ceil(rows) * rows)
        }
        "orthogonal" => smallest_root(
            &|r| (2..r).take_while(|d| d * d <= r).all(|d| r % d != 0),
            2,
        ),
        "ldsampler" => smallest_root(&u32::is_power_of_two, 2),
        _ => None,
    }
}

/// Mitsuba's `path` defaults, for a scene without an integrator.
pub(super) fn path_defaults(render: &mut crate::scene_file::RenderDefaults) {
    render.max_depth = Some(u32::MAX);
    render.rr_depth = Some(DEFAULT_RR_DEPTH as u32);
}

impl<'e> Importer<'e, '_> {
    /// The `<sensor>`: camera and render defaults.
    pub(super) fn sensor(&mut self, e: &'e Element) -> Result<(), CliError> {
        let object = Object::new(e)?;
        let kind = match object.plugin {
            "perspective" => SensorKind::Perspective,
            "thinlens" => SensorKind::ThinLens,
            "orthographic" => SensorKind::Orthographic,
            _ => {
                return Err(object.error("is not supported (perspective, thinlens, orthographic)"));
            }
        };
        // The film first: the field of view depends on its aspect.
        let mut width = DEFAULT_FILM_WIDTH;
        let mut height = DEFAULT_FILM_HEIGHT;
        let films = self.nested_of(&object, "film")?;
        if films.len() > 1 {
            return Err(object.error("has more than one <film>"));
        }
        let mut filter = FilterChoice::Gaussian {
            stddev_px: DEFAULT_GAUSSIAN_STDDEV_PX as f32,
        };
        if let Some(&film) = films.first() {
            (width, height, filter) = self.film(film)?;
        }
        if let Some(&sampler) = self.nested_of(&object, "sampler")?.first() {
            self.sampler(sampler)?;
        }
        let to_world = object.transform("to_world")?;
        let (w, h) = (width as f64, height as f64);
        let near_clip = object.float("near_clip", DEFAULT_NEAR_CLIP)?;
        let far_clip = object.float("far_clip", DEFAULT_FAR_CLIP)?;
        // Mitsuba's checks (`src/render/sensor.cpp`, `ProjectiveCamera`).
        if !(near_clip > 0.0 && near_clip < far_clip) {
            return Err(object.error(format!(
                "near_clip {near_clip}, far_clip {far_clip}: need 0 < near_clip < far_clip"
            )));
        }
        // A pinhole or an orthographic sensor has no focus; Mitsuba reads
        // the value for every projective sensor and ignores it there.
        if kind != SensorKind::ThinLens {
            object.ignore(&["focus_distance"]);
        }
        // Mitsuba's perspective and thinlens sensors refuse a scaled
        // to_world (`src/sensors/perspective.cpp`, `thinlens.cpp`); so
        // does this importer. A mirror (an axis of length 1) is no scale.
        if kind != SensorKind::Orthographic {
            let scaled = [Vec3::X, Vec3::Y, Vec3::Z]
                .into_iter()
                .any(|axis| (to_world.vector(axis).length() - 1.0).abs() > UNIT_AXIS_TOLERANCE);
            if scaled {
                return Err(object.error(format!(
                    "{}: scale factors in to_world are not allowed (as in Mitsuba)",
                    object.plugin
                )));
            }
        }
        let projection = match kind {
            SensorKind::Orthographic => {
                let scale_x = to_world.vector(Vec3::X).length();
                let scale_y = to_world.vector(Vec3::Y).length();
                if (scale_x - scale_y).abs() > UNIT_AXIS_TOLERANCE * scale_x.max(scale_y) {
                    return Err(object.error(format!(
                        "orthographic: to_world scales x by {scale_x} and y by {scale_y}; \
                         unequal scales (non-square pixels) are not supported"
                    )));
                }
                // Mitsuba's film plane spans local x in [−1, 1] across the
                // width: 2 scale_x scene units, over min(w, h)/w of which
                // lies the smaller axis.
                let view_size = 2.0 * f64::from(scale_x) * w.min(h) / w;
                Projection::Orthographic {
                    view_size: view_size as f32,
                }
            }
            SensorKind::Perspective | SensorKind::ThinLens => Projection::Perspective {
                fov_deg: perspective_fov_smaller_deg(&object, w, h)? as f32,
            },
        };
        let axes = CameraAxes {
            position: to_world.point(Vec3::ZERO),
            forward: to_world.vector(Vec3::Z),
            right: -to_world.vector(Vec3::X),
            up: to_world.vector(Vec3::Y),
        };
        // The clip depths. An orthographic sensor's rays start at local
        // z = near_clip, scaled by to_world, and run far_clip − near_clip
        // along their unit direction (`orthographic.cpp`: `maxt = far −
        // near`); the other sensors have no scale.
        let near_depth = near_clip * f64::from(to_world.vector(Vec3::Z).length());
        let far_depth = near_depth + (far_clip - near_clip);
        let camera = Camera::from_axes(axes, projection)
            .and_then(|camera| camera.with_clip(near_depth as f32, far_depth as f32))
            .map_err(|err| object.error(format!("to_world: {err}")))?;
        // Only `perspective` has a principal point; the other sensors
        // leave the parameters unread, so they are refused as unused.
        let camera = if kind == SensorKind::Perspective {
            let shift = [
                object.float("principal_point_offset_x", 0.0)? as f32,
                object.float("principal_point_offset_y", 0.0)? as f32,
            ];
            camera.with_shift(shift).map_err(|err| {
                object.error(format!(
                    "principal_point_offset {} {}: {err}",
                    shift[0], shift[1]
                ))
            })?
        } else {
            camera
        };
        let camera = if kind == SensorKind::ThinLens {
            let aperture_radius = object
                .float_opt("aperture_radius")?
                .ok_or_else(|| object.error("needs `aperture_radius`"))?;
            let focus_distance = object.float("focus_distance", far_clip)?;
            camera
                .with_lens(aperture_radius as f32, focus_distance as f32)
                .map_err(|err| {
                    object.error(format!(
                        "aperture_radius {aperture_radius}, focus_distance {focus_distance}: {err}"
                    ))
                })?
        } else {
            camera
        };
        self.cx.set_camera(camera);
        self.camera_set = true;
        self.render.width = Some(width as u32);
        self.render.height = Some(height as u32);
        self.render.filter = Some(filter);
        self.check_unused(&object)
    }

    /// `hdrfilm`: size, crop window and filter.
    fn film(&mut self, e: &'e Element) -> Result<(i64, i64, FilterChoice), CliError> {
        let object = Object::new(e)?;
        if object.plugin != "hdrfilm" {
            if !self.options.lenient {
                return Err(object.error("is not supported (hdrfilm; --lenient renders it as one)"));
            }
            self.warn_at(
                e,
                format!(
                    "film \"{}\" rendered as an hdrfilm (--lenient)",
                    object.plugin
                ),
            );
        }
        let edge = |name: &str, default: i64| -> Result<i64, CliError> {
            let v = object.integer(name, default)?;
            if !(1..=MAX_IMAGE_EDGE).contains(&v) {
                return Err(object.error(format!("{name} {v}: must be 1 … {MAX_IMAGE_EDGE}")));
            }
            Ok(v)
        };
        let width = edge("width", DEFAULT_FILM_WIDTH)?;
        let height = edge("height", DEFAULT_FILM_HEIGHT)?;
        let crop_x = object.integer("crop_offset_x", 0)?;
        let crop_y = object.integer("crop_offset_y", 0)?;
        let crop_w = object.integer("crop_width", width - crop_x)?;
        let crop_h = object.integer("crop_height", height - crop_y)?;
        let inside = crop_x >= 0
            && crop_y >= 0
            && crop_w >= 1
            && crop_h >= 1
            && crop_x + crop_w <= width
            && crop_y + crop_h <= height;
        if !inside {
            return Err(object.error(format!(
                "crop window ({crop_x}, {crop_y}) + {crop_w} × {crop_h} does not lie inside the {width} × {height} film"
            )));
        }
        if (crop_x, crop_y, crop_w, crop_h) != (0, 0, width, height) {
            self.render.crop = Some(CropWindow {
                x: crop_x as u32,
                y: crop_y as u32,
                width: crop_w as u32,
                height: crop_h as u32,
            });
        }
        object.ignore(&[
            "pixel_format",
            "component_format",
            "sample_border",
            "banner",
            "compensate",
            "file_format",
        ]);
        let mut filter = FilterChoice::Gaussian {
            stddev_px: DEFAULT_GAUSSIAN_STDDEV_PX as f32,
        };
        if let Some(&rfilter) = self.nested_of(&object, "rfilter")?.first() {
            filter = self.rfilter(rfilter)?;
        }
        self.check_unused(&object)?;
        Ok((width, height, filter))
    }

    fn rfilter(&mut self, e: &'e Element) -> Result<FilterChoice, CliError> {
        let object = Object::new(e)?;
        let positive = |name: &str, default: f64| -> Result<f32, CliError> {
            let v = object.float(name, default)?;
            if !(v > 0.0 && v <= f64::from(u16::MAX)) {
                return Err(object.error(format!("{name} {v}: must be > 0")));
            }
            Ok(v as f32)
        };
        let filter = match object.plugin {
            "box" => FilterChoice::Box,
            "tent" => FilterChoice::Tent {
                radius_px: positive("radius", DEFAULT_TENT_RADIUS_PX)?,
            },
            "gaussian" => FilterChoice::Gaussian {
                stddev_px: positive("stddev", DEFAULT_GAUSSIAN_STDDEV_PX)?,
            },
            "mitchell" => {
                let [b, c] = MITCHELL_B_C.map(f64::from);
                let parameter = |name: &str, default: f64| -> Result<f32, CliError> {
                    let v = object.float(name, default)?;
                    if !(0.0..=1.0).contains(&v) {
                        return Err(object.error(format!("{name} {v}: must be in [0, 1]")));
                    }
                    Ok(v as f32)
                };
                FilterChoice::Cubic {
                    b: parameter("B", b)?,
                    c: parameter("C", c)?,
                }
            }
            "catmullrom" => FilterChoice::Cubic {
                b: CATMULL_ROM_B_C[0],
                c: CATMULL_ROM_B_C[1],
            },
            "lanczos" => {
                let lobes = object.integer("lobes", i64::from(LANCZOS_LOBES))?;
                let most = MAX_FILTER_RADIUS_PX as i64;
                if !(1..=most).contains(&lobes) {
                    return Err(object.error(format!("lobes {lobes}: must be 1 … {most}")));
                }
                FilterChoice::Lanczos {
                    lobes: lobes as u32,
                }
            }
            _ => {
                self.unsupported(e, "a Gaussian filter is used")?;
                return Ok(FilterChoice::Gaussian {
                    stddev_px: DEFAULT_GAUSSIAN_STDDEV_PX as f32,
                });
            }
        };
        self.check_unused(&object)?;
        Ok(filter)
    }

    fn sampler(&mut self, e: &'e Element) -> Result<(), CliError> {
        let object = Object::new(e)?;
        let count = object.integer("sample_count", DEFAULT_SAMPLE_COUNT)?;
        if !(1..=i64::from(MAX_SAMPLE_COUNT)).contains(&count) {
            return Err(object.error(format!(
                "sample_count {count}: must be 1 … {MAX_SAMPLE_COUNT}"
            )));
        }
        let seed = object.integer("seed", 0)?;
        if seed < 0 {
            return Err(object.error(format!("seed {seed}: must be >= 0")));
        }
        let Some(rounded) = mitsuba_sample_count(object.plugin, count as u32) else {
            self.unsupported(e, "rendered with fspec's sampler, the same count")?;
            self.render.spp = Some(count as u32);
            self.render.seed = Some(seed as u64);
            return self.check_unused(&object);
        };
        if rounded != count as u32 {
            self.warn_at(e, format!(
                    "sampler \"{}\": sample_count {count} rounded to {rounded}, as Mitsuba rounds it",
                    object.plugin
                ),
            );
        }
        // Parameters of Mitsuba's samplers that shape their patterns, not
        // the image they converge to.
        match object.plugin {
            "stratified" | "multijitter" => object.ignore(&["jitter"]),
            "orthogonal" => object.ignore(&["jitter", "strength"]),
            _ => {}
        }
        self.render.spp = Some(rounded);
        self.render.seed = Some(seed as u64);
        self.check_unused(&object)
    }

    /// `<integrator>`: depth, roulette, hidden emitters.
    pub(super) fn integrator(&mut self, e: &'e Element) -> Result<(), CliError> {
        let object = Object::new(e)?;
        match object.plugin {
            "path" | "volpath" | "volpathmis" => {
                if object.plugin != "path" {
                    self.warn_at(
                        e,
                        format!(
                            "integrator \"{}\" renders as \"path\" (the scene has no media)",
                            object.plugin
                        ),
                    );
                }
                self.path_depths(&object)?;
            }
            "direct" => {
                self.render.max_depth = Some(DIRECT_MAX_DEPTH);
                object.ignore(&["emitter_samples", "bsdf_samples", "shading_samples"]);
            }
            "moment" | "aov" => return self.wrapping_integrator(e, &object),
            "ptracer" => {
                self.warn_at(
                    e,
                    "integrator \"ptracer\" renders as \"path\" (the same image, but that \
                     path also shows what the camera sees through smooth mirrors and glass, \
                     which a particle tracer leaves black)",
                );
                self.path_depths(&object)?;
                object.ignore(&["samples_per_pass"]);
            }
            _ => {
                return Err(object.error("is not supported (path, direct, and volpath, volpathmis, ptracer as path; moment and aov render their nested integrator)"));
            }
        }
        self.render.hide_emitters = Some(object.boolean("hide_emitters", false)?);
        self.check_unused(&object)
    }
}

impl<'e> Importer<'e, '_> {
    /// `max_depth` and `rr_depth` of `path` and the integrators read as it.
    fn path_depths(&mut self, object: &Object<'e>) -> Result<(), CliError> {
        let depth = object.integer("max_depth", -1)?;
        self.render.max_depth = Some(match depth {
            -1 => u32::MAX,
            d if d >= 1 && d <= i64::from(u32::MAX) => d as u32,
            d => {
                return Err(
                    object.error(format!("max_depth {d}: use -1 (unlimited) or a depth >= 1"))
                );
            }
        });
        let rr = object.integer("rr_depth", DEFAULT_RR_DEPTH)?;
        if !(1..=i64::from(u32::MAX)).contains(&rr) {
            return Err(object.error(format!("rr_depth {rr}: must be >= 1")));
        }
        self.render.rr_depth = Some(rr as u32);
        Ok(())
    }

    /// `moment` and `aov`: Mitsuba writes their nested integrator's image
    /// and, beside it, extra channels (the samples' second moment; depth,
    /// normals and the like). fspec renders the nested integrator's image,
    /// the image a user looks at, and warns that the extra channels are
    /// not written. One nested integrator: with several, Mitsuba writes an
    /// image of each, and fspec's output holds one.
    fn wrapping_integrator(&mut self, e: &'e Element, object: &Object<'e>) -> Result<(), CliError> {
        // Named or not (`aov` names its image's integrator, `image`).
        let mut nested = Vec::new();
        for p in object.objects() {
            nested.push(self.object_of(p, &["integrator"])?);
        }
        let [inner] = nested[..] else {
            return Err(object.error(format!(
                "needs exactly one nested <integrator> to render (it has {})",
                nested.len()
            )));
        };
        object.ignore(&["aovs"]);
        self.check_unused(object)?;
        let channels = match object.plugin {
            "moment" => "the second-moment channels",
            _ => "the AOV channels",
        };
        self.warn_at(
            e,
            format!(
                "integrator \"{}\": renders its nested integrator's image; {channels} are not written",
                object.plugin
            ),
        );
        self.integrator(inner)
    }
}

/// `"50mm"` or `"50"` as millimetres (> 0).
fn parse_millimetres(text: &str) -> Option<f64> {
    let t = text.trim();
    let t = t.strip_suffix("mm").unwrap_or(t).trim();
    t.parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0)
}

#[cfg(test)]
mod tests {
    use super::mitsuba_sample_count;

    /// Mitsuba's roundings, case by case (`src/samplers/*.cpp`).
    #[test]
    fn sample_counts_round_as_mitsubas_samplers_do() {
        for (plugin, spp, expected) in [
            ("independent", 5, 5),
            ("stratified", 16, 16),
            ("stratified", 17, 25),
            ("stratified", 1, 1),
            ("multijitter", 10, 12), // rows 3, columns ⌈10/3⌉ = 4
            ("multijitter", 16, 16),
            ("multijitter", 2, 2),
            ("orthogonal", 4, 4),
            ("orthogonal", 5, 9),
            ("orthogonal", 10, 25), // 4 is not prime
            ("orthogonal", 26, 49),
            ("orthogonal", 1, 4),
            ("ldsampler", 4, 4),
            ("ldsampler", 5, 16),
            ("ldsampler", 64, 64),
            ("ldsampler", 65, 256),
            ("ldsampler", 1, 4),
        ] {
            assert_eq!(
                mitsuba_sample_count(plugin, spp),
                Some(expected),
                "{plugin} {spp}"
            );
        }
        assert_eq!(mitsuba_sample_count("sobol", 4), None);
        // The largest count accepted rounds without overflow.
        for plugin in ["stratified", "multijitter", "orthogonal", "ldsampler"] {
            assert!(mitsuba_sample_count(plugin, super::MAX_SAMPLE_COUNT).is_some());
        }
    }
}
