//! What the page may change, how a change message is checked, and the
//! `fspec render` command line that renders the same image.
//!
//! The page sends partial settings ([`SettingsPatch`], JSON, unknown
//! fields refused); [`ViewSettings::apply`] checks the result in full
//! before it replaces the current settings, so a bad message changes
//! nothing and gets one error line back. Render settings go through
//! `fspec render`'s own argument parser and defaults
//! ([`ViewSettings::render_args`], `render_cmd::settings_from`): a frame of
//! the viewer and a file render of the printed command share the scene,
//! filter, depth and seed by construction, not by a copy of the defaults.

use crate::error::CliError;
use crate::render_cmd::{
    self, BufferKind, RenderArgs, Sampling, ToColor, ToneKind, TransportSpec, TransportTask,
};
use crate::sensor_file::ObserverChoice;
use clap::ValueEnum;
use serde::{Deserialize, Serialize};
use simd_tracer::scene::builtin::SCENES;
use simd_tracer::scene::camera::Camera;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::{FilmPixel, Transport};
use spectral_core::SpectralRange;
use spectral_core::registry::Builtin;

/// Largest image side the page may ask for, pixels: a 4K screen's width,
/// far below `fspec render`'s limit, so that a frame (one PNG per batch)
/// stays interactive.
pub const MAX_VIEW_SIDE: u32 = 4096;

/// Image side when neither the command line nor the scene gives one
/// (`fspec render`'s default).
pub const DEFAULT_SIDE: u32 = 512;

/// Passes after which a render stops and waits for a change.
pub const DEFAULT_MAX_PASSES: u32 = 1024;

/// Most passes the page may ask for (`fspec render`'s pass counter is a
/// `u32`; a million passes is days of rendering).
pub const MAX_VIEW_PASSES: u32 = 1 << 20;

/// Largest exposure the page may set, stops either way (2^±64 spans any
/// radiance an `f32` film holds).
pub const MAX_EXPOSURE_STOPS: f32 = 64.0;

/// The illuminant names the page offers: illuminant E, the CIE and LED
/// illuminants of the built-in table, and blackbodies (any
/// `blackbody-<kelvin>` is accepted).
pub fn illuminant_names() -> Vec<String> {
    let mut names = vec!["e".to_string()];
    names.extend(
        spectral_core::data::tables::ILLUMINANTS
            .iter()
            .map(|i| i.name.to_string()),
    );
    names.extend(["blackbody-2700", "blackbody-4000", "blackbody-6500"].map(String::from));
    names
}

/// The standard observers the page offers (`--observer`'s names).
pub fn observer_names() -> Vec<&'static str> {
    spectral_core::observer::StandardObserver::ALL
        .iter()
        .map(|o| o.name())
        .collect()
}

/// A built-in illuminant by name (never a file: the page must not make the
/// server read paths).
pub fn illuminant_source(name: &str) -> Result<SpectrumSource, CliError> {
    match Builtin::lookup(name) {
        Ok(b @ (Builtin::EqualEnergy | Builtin::Illuminant(_) | Builtin::Blackbody(_))) => {
            Ok(SpectrumSource::Builtin(b))
        }
        _ => Err(CliError::input(format!(
            "illuminant `{name}`: not a built-in illuminant ({} or blackbody-<kelvin>)",
            illuminant_names().join(", ")
        ))),
    }
}

/// A camera set by the page: a look-at pinhole ([`Camera::look_at`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Centre of projection.
    pub position: [f32; 3],
    /// The point looked at.
    pub target: [f32; 3],
    /// Up direction (need not be orthogonal to the view).
    pub up: [f32; 3],
    /// Field of view along the smaller image axis, degrees.
    pub fov_deg: f32,
}

impl CameraSpec {
    /// The camera, or why it is invalid.
    pub fn camera(&self) -> Result<Camera, CliError> {
        Camera::look_at(
            self.position.into(),
            self.target.into(),
            self.up.into(),
            self.fov_deg,
        )
        .map_err(|e| CliError::input(format!("camera: {e}")))
    }
}

/// Everything the page controls.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewSettings {
    /// A built-in scene or the scene given on the command line.
    pub scene: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The transport and its sizes.
    pub transport: TransportSpec,
    /// Exposure of the displayed image, stops.
    pub exposure_stops: f32,
    /// Tone map of the displayed image.
    pub tone: ToneKind,
    /// Every emitter relit by this built-in illuminant (at its own
    /// luminance); `None`: the scene's own emission.
    pub illuminant: Option<String>,
    /// The page's camera; `None`: the scene's.
    pub camera: Option<CameraSpec>,
    /// Passes after which the render stops.
    pub max_passes: u32,
    /// Split view: the right half rendered with this transport, the left
    /// half with [`ViewSettings::transport`], at equal time
    /// (`driver::render_split`); `None`: the whole image with one.
    pub split: Option<TransportSpec>,
    /// A CIE standard observer by name (`--observer`); `None`: the
    /// scene's, else CIE 1931 2°.
    pub observer: Option<String>,
}

/// A change sent by the page: every field optional, unknown ones refused.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingsPatch {
    /// See [`ViewSettings::scene`] (a scene change resets the camera and
    /// the illuminant).
    pub scene: Option<String>,
    /// See [`ViewSettings::width`].
    pub width: Option<u32>,
    /// See [`ViewSettings::height`].
    pub height: Option<u32>,
    /// See [`ViewSettings::transport`].
    pub transport: Option<TransportSpec>,
    /// See [`ViewSettings::exposure_stops`].
    pub exposure_stops: Option<f32>,
    /// See [`ViewSettings::tone`].
    pub tone: Option<ToneKind>,
    /// A built-in illuminant name, or `"scene"` for the scene's own.
    pub illuminant: Option<String>,
    /// See [`ViewSettings::camera`].
    pub camera: Option<CameraSpec>,
    /// Back to the scene's camera.
    pub reset_camera: Option<bool>,
    /// See [`ViewSettings::max_passes`].
    pub max_passes: Option<u32>,
    /// See [`ViewSettings::split`]: turns the split view on (or changes
    /// its right half's transport).
    pub split: Option<TransportSpec>,
    /// Back to one transport for the whole image.
    pub split_off: Option<bool>,
    /// A standard observer's name, or `"scene"` for the scene's own.
    pub observer: Option<String>,
}

/// The scenes the page may choose: the built-ins and the command line's.
pub fn scene_names(command_line_scene: &str) -> Vec<String> {
    let mut names: Vec<String> = SCENES.iter().map(|s| s.name.to_string()).collect();
    if !names.iter().any(|n| n == command_line_scene) {
        names.insert(0, command_line_scene.to_string());
    }
    names
}

/// What a [`ViewSettings::apply`] changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    /// Nothing.
    None,
    /// Only the display (exposure, tone): the frame is re-encoded, the
    /// render goes on.
    Display,
    /// The image: the render restarts from pass 0.
    Render,
}

/// Checks a transport's sizes by building it, returning the bytes of one
/// film pixel.
struct FilmPixelBytes;

impl TransportTask for FilmPixelBytes {
    type Output = u64;

    fn run<T: Transport>(self, _transport: &T) -> Result<u64, CliError> {
        Ok(size_of::<FilmPixel<T>>() as u64)
    }
}

impl ViewSettings {
    /// The `fspec render` arguments of these settings (scene, size, passes,
    /// transport, exposure, tone; the camera and the illuminant have no
    /// flag and are not among them).
    pub fn render_args(&self) -> Vec<String> {
        let name = |v: &dyn Fn() -> Option<clap::builder::PossibleValue>| {
            v().map_or_else(String::new, |p| p.get_name().to_string())
        };
        let mut args = vec![
            self.scene.clone(),
            "--width".into(),
            self.width.to_string(),
            "--height".into(),
            self.height.to_string(),
            "--spp".into(),
            self.max_passes.to_string(),
        ];
        let sampling = |s: Sampling| name(&|| s.to_possible_value());
        match self.transport {
            TransportSpec::Fourier {
                coeffs,
                buffer,
                to_color,
            } => args.extend([
                "--transport".into(),
                "fourier".into(),
                "--coeffs".into(),
                coeffs.to_string(),
                "--buffer".into(),
                name(&|| buffer.to_possible_value()),
                "--to-color".into(),
                name(&|| to_color.to_possible_value()),
            ]),
            TransportSpec::Sampled {
                wavelengths,
                sampling: s,
            } => args.extend([
                "--transport".into(),
                "sampled".into(),
                "--wavelengths".into(),
                wavelengths.to_string(),
                "--sampling".into(),
                sampling(s),
            ]),
            TransportSpec::Cv {
                wavelengths,
                coeffs,
                sampling: s,
                alpha_per_pixel,
            } => {
                args.extend([
                    "--transport".into(),
                    "cv".into(),
                    "--wavelengths".into(),
                    wavelengths.to_string(),
                    "--coeffs".into(),
                    coeffs.to_string(),
                    "--sampling".into(),
                    sampling(s),
                ]);
                if alpha_per_pixel {
                    args.push("--cv-alpha-per-pixel".into());
                }
            }
            TransportSpec::Hybrid {
                coeffs,
                wavelengths,
                sampling: s,
                buffer,
                to_color,
                paths,
                caustics,
            } => args.extend([
                "--transport".into(),
                "hybrid".into(),
                "--coeffs".into(),
                coeffs.to_string(),
                "--wavelengths".into(),
                wavelengths.to_string(),
                "--sampling".into(),
                sampling(s),
                "--buffer".into(),
                name(&|| buffer.to_possible_value()),
                "--to-color".into(),
                name(&|| to_color.to_possible_value()),
                "--dispersion-paths".into(),
                name(&|| paths.to_possible_value()),
                "--caustics".into(),
                name(&|| caustics.to_possible_value()),
            ]),
        }
        if let Some(observer) = &self.observer {
            args.extend(["--observer".into(), observer.clone()]);
        }
        args.extend([
            "--exposure".into(),
            self.exposure_stops.to_string(),
            "--tone".into(),
            name(&|| self.tone.to_possible_value()),
        ]);
        args
    }

    /// [`ViewSettings::render_args`] parsed by `fspec render`'s parser.
    pub fn parse_render_args(&self) -> Result<RenderArgs, CliError> {
        #[derive(clap::Parser)]
        struct Render {
            #[command(flatten)]
            args: RenderArgs,
        }
        let line = std::iter::once("fspec-render".to_string()).chain(self.render_args());
        <Render as clap::Parser>::try_parse_from(line)
            .map(|r| r.args)
            .map_err(|e| {
                let text = e.to_string();
                CliError::input(text.lines().next().unwrap_or("bad settings").to_string())
            })
    }

    /// Checks everything a render needs of these settings (the scene is
    /// one of `scenes`; sizes, passes, exposure, illuminant, camera,
    /// transport sizes, and the film's memory within `memory_limit_bytes`).
    pub fn validate(&self, scenes: &[String], memory_limit_bytes: u64) -> Result<(), CliError> {
        if !scenes.contains(&self.scene) {
            return Err(CliError::input(format!(
                "unknown scene `{}` (choose one of {})",
                self.scene,
                scenes.join(", ")
            )));
        }
        for (what, side) in [("width", self.width), ("height", self.height)] {
            if !(1..=MAX_VIEW_SIDE).contains(&side) {
                return Err(CliError::input(format!(
                    "{what} {side}: must be 1 to {MAX_VIEW_SIDE} pixels"
                )));
            }
        }
        if !(1..=MAX_VIEW_PASSES).contains(&self.max_passes) {
            return Err(CliError::input(format!(
                "max_passes {}: must be 1 to {MAX_VIEW_PASSES}",
                self.max_passes
            )));
        }
        if !(self.exposure_stops.is_finite() && self.exposure_stops.abs() <= MAX_EXPOSURE_STOPS) {
            return Err(CliError::input(format!(
                "exposure {} stops: must be finite and within ±{MAX_EXPOSURE_STOPS}",
                self.exposure_stops
            )));
        }
        if let Some(name) = &self.illuminant {
            illuminant_source(name)?;
        }
        if let Some(camera) = &self.camera {
            camera.camera()?;
        }
        if let Some(name) = &self.observer {
            ObserverChoice::standard(name)?;
        }
        let observer = std::sync::Arc::new(spectral_core::observer::Observer::default());
        let basis = render_cmd::TransportBasis {
            range: SpectralRange::VISIBLE,
            observer: &observer,
            density: None,
        };
        let mut film_pixel_bytes =
            render_cmd::with_transport(&self.transport, basis, FilmPixelBytes)?;
        if let Some(right) = &self.split {
            self.validate_split(right)?;
            film_pixel_bytes += render_cmd::with_transport(right, basis, FilmPixelBytes)?;
        }
        // The film, the resolved frame beside it (XYZ and coefficients) and
        // the frame being encoded: three film-sized buffers at most (in a
        // split view each half's film and its saved state, counted as two
        // whole films).
        let film_copies = 3;
        let bytes = u64::from(self.width) * u64::from(self.height) * film_pixel_bytes * film_copies;
        if bytes > memory_limit_bytes {
            return Err(CliError::input(format!(
                "{}×{} pixels with this transport would need about {} (limit {})",
                self.width,
                self.height,
                render_cmd::format_bytes(bytes),
                render_cmd::format_bytes(memory_limit_bytes)
            )));
        }
        self.parse_render_args().map(|_| ())
    }

    /// The split view's conditions: both transports' passes can be paused
    /// and resumed (their films are sums; control variates weight each
    /// pass by `α` from all earlier ones, so a half cannot stop and go on),
    /// and the image has two halves.
    fn validate_split(&self, right: &TransportSpec) -> Result<(), CliError> {
        for (side, spec) in [("left", &self.transport), ("right", right)] {
            if matches!(spec, TransportSpec::Cv { .. }) {
                return Err(CliError::input(format!(
                    "split view: the {side} half's transport is cv, whose passes cannot be paused and resumed (use fourier or sampled)"
                )));
            }
        }
        if self.width < 2 {
            return Err(CliError::input(format!(
                "split view: width {} has no two halves",
                self.width
            )));
        }
        Ok(())
    }

    /// These settings with `patch` applied and checked (module docs), and
    /// what changed; `self` is untouched on error.
    pub fn apply(
        &self,
        patch: &SettingsPatch,
        scenes: &[String],
        memory_limit_bytes: u64,
    ) -> Result<(Self, Change), CliError> {
        let mut next = self.clone();
        if let Some(scene) = &patch.scene {
            if *scene != self.scene {
                next.scene = scene.clone();
                next.camera = None;
                next.illuminant = None;
            }
        }
        next.width = patch.width.unwrap_or(next.width);
        next.height = patch.height.unwrap_or(next.height);
        next.transport = patch.transport.unwrap_or(next.transport);
        next.exposure_stops = patch.exposure_stops.unwrap_or(next.exposure_stops);
        next.tone = patch.tone.unwrap_or(next.tone);
        if let Some(name) = &patch.illuminant {
            next.illuminant = (name != "scene").then(|| name.to_ascii_lowercase());
        }
        if patch.reset_camera == Some(true) {
            next.camera = None;
        }
        if patch.camera.is_some() {
            next.camera = patch.camera;
        }
        next.max_passes = patch.max_passes.unwrap_or(next.max_passes);
        if patch.split_off == Some(true) {
            next.split = None;
        }
        if patch.split.is_some() {
            next.split = patch.split;
        }
        if let Some(name) = &patch.observer {
            next.observer = (name != "scene").then(|| name.to_ascii_lowercase());
        }
        next.validate(scenes, memory_limit_bytes)?;
        let display_only = Self {
            exposure_stops: self.exposure_stops,
            tone: self.tone,
            ..next.clone()
        } == *self;
        let change = if next == *self {
            Change::None
        } else if display_only {
            Change::Display
        } else {
            Change::Render
        };
        Ok((next, change))
    }
}

/// The page's defaults: the Fourier transport of `fspec render`.
pub fn default_transport() -> TransportSpec {
    TransportSpec::Fourier {
        coeffs: 12,
        buffer: BufferKind::Spectral,
        to_color: ToColor::Zeroth,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render_cmd::{Caustics, DispersionPaths};

    fn settings() -> ViewSettings {
        ViewSettings {
            scene: "cornell".into(),
            width: 64,
            height: 48,
            transport: default_transport(),
            exposure_stops: 0.0,
            tone: ToneKind::Clamp,
            illuminant: None,
            camera: None,
            max_passes: 16,
            split: None,
            observer: None,
        }
    }

    const LIMIT: u64 = 1 << 30;

    fn scenes() -> Vec<String> {
        scene_names("cornell")
    }

    #[test]
    fn render_args_parse_back_to_the_same_transport() -> Result<(), CliError> {
        for transport in [
            default_transport(),
            TransportSpec::Sampled {
                wavelengths: 8,
                sampling: Sampling::Visible,
            },
            TransportSpec::Cv {
                wavelengths: 4,
                coeffs: 8,
                sampling: Sampling::Hero,
                alpha_per_pixel: true,
            },
            TransportSpec::Hybrid {
                coeffs: 12,
                wavelengths: 8,
                sampling: Sampling::Lights,
                buffer: BufferKind::Rgb,
                to_color: ToColor::Series,
                paths: DispersionPaths::All,
                caustics: Caustics::Camera,
            },
        ] {
            let s = ViewSettings {
                transport,
                ..settings()
            };
            let args = s.parse_render_args()?;
            assert_eq!(TransportSpec::of(&args), transport);
            assert_eq!(
                (args.width, args.height, args.spp),
                (Some(64), Some(48), Some(16))
            );
        }
        Ok(())
    }

    #[test]
    fn a_change_is_classified_and_a_bad_one_changes_nothing() -> Result<(), CliError> {
        let s = settings();
        let exposure = SettingsPatch {
            exposure_stops: Some(1.5),
            ..SettingsPatch::default()
        };
        assert_eq!(s.apply(&exposure, &scenes(), LIMIT)?.1, Change::Display);
        let scene = SettingsPatch {
            scene: Some("lamps".into()),
            ..SettingsPatch::default()
        };
        assert_eq!(s.apply(&scene, &scenes(), LIMIT)?.1, Change::Render);
        assert_eq!(
            s.apply(&SettingsPatch::default(), &scenes(), LIMIT)?.1,
            Change::None
        );
        let bad = [
            SettingsPatch {
                scene: Some("nosuchscene".into()),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                width: Some(MAX_VIEW_SIDE + 1),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                height: Some(0),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                transport: Some(TransportSpec::Fourier {
                    coeffs: 5,
                    buffer: BufferKind::Spectral,
                    to_color: ToColor::Zeroth,
                }),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                exposure_stops: Some(f32::NAN),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                illuminant: Some("/etc/passwd".into()),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                illuminant: Some("gold-n".into()),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                camera: Some(CameraSpec {
                    position: [0.0; 3],
                    target: [0.0; 3],
                    up: [0.0, 1.0, 0.0],
                    fov_deg: 40.0,
                }),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                max_passes: Some(0),
                ..SettingsPatch::default()
            },
        ];
        for patch in bad {
            assert!(s.apply(&patch, &scenes(), LIMIT).is_err(), "{patch:?}");
        }
        // A film too large for the memory limit is refused too.
        let large = SettingsPatch {
            width: Some(MAX_VIEW_SIDE),
            height: Some(MAX_VIEW_SIDE),
            ..SettingsPatch::default()
        };
        assert!(s.apply(&large, &scenes(), LIMIT).is_err());
        Ok(())
    }

    #[test]
    fn a_split_view_needs_two_pausable_transports_and_two_halves() -> Result<(), CliError> {
        let sampled = TransportSpec::Sampled {
            wavelengths: 4,
            sampling: Sampling::Hero,
        };
        let cv = TransportSpec::Cv {
            wavelengths: 4,
            coeffs: 8,
            sampling: Sampling::Hero,
            alpha_per_pixel: false,
        };
        let on = SettingsPatch {
            split: Some(sampled),
            ..SettingsPatch::default()
        };
        let (split, change) = settings().apply(&on, &scenes(), LIMIT)?;
        assert_eq!((split.split, change), (Some(sampled), Change::Render));
        let off = SettingsPatch {
            split_off: Some(true),
            ..SettingsPatch::default()
        };
        assert_eq!(split.apply(&off, &scenes(), LIMIT)?.0.split, None);
        for refused in [
            SettingsPatch {
                split: Some(cv),
                ..SettingsPatch::default()
            },
            SettingsPatch {
                transport: Some(cv),
                ..on.clone()
            },
            SettingsPatch {
                width: Some(1),
                ..on.clone()
            },
        ] {
            assert!(
                settings().apply(&refused, &scenes(), LIMIT).is_err(),
                "{refused:?}"
            );
        }
        // Control variates without a split view stay allowed.
        let cv_alone = SettingsPatch {
            transport: Some(cv),
            ..SettingsPatch::default()
        };
        assert!(settings().apply(&cv_alone, &scenes(), LIMIT).is_ok());
        Ok(())
    }

    #[test]
    fn the_observer_is_a_standard_one_and_reaches_the_render_line() -> Result<(), CliError> {
        let patch = SettingsPatch {
            observer: Some("CIE1964-10".into()),
            ..SettingsPatch::default()
        };
        let (next, change) = settings().apply(&patch, &scenes(), LIMIT)?;
        assert_eq!(change, Change::Render);
        assert_eq!(
            next.parse_render_args()?.observer.as_deref(),
            Some("cie1964-10")
        );
        let back = SettingsPatch {
            observer: Some("scene".into()),
            ..SettingsPatch::default()
        };
        assert_eq!(next.apply(&back, &scenes(), LIMIT)?.0.observer, None);
        let bad = SettingsPatch {
            observer: Some("/etc/passwd".into()),
            ..SettingsPatch::default()
        };
        assert!(settings().apply(&bad, &scenes(), LIMIT).is_err());
        Ok(())
    }

    #[test]
    fn unknown_fields_are_refused() {
        assert!(serde_json::from_str::<SettingsPatch>(r#"{"widht": 5}"#).is_err());
        assert!(serde_json::from_str::<SettingsPatch>(r#"{"width": 5}"#).is_ok());
    }
}
