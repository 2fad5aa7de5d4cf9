//! `fspec render` from Python: the command line's arguments, its scene
//! loading and its render, with the image returned instead of written.
//!
//! The Python half turns keyword arguments into the command line's flags
//! (`spp=64` → `--spp 64`), which are parsed here by the CLI's own
//! `RenderArgs`, so defaults, accepted values and error messages are the
//! command line's, and every scene the CLI renders (built-in names, TOML,
//! Mitsuba 3 XML, OBJ) renders here identically: the same seed gives the
//! same pixels as `fspec render … --out image.exr`, bit for bit (tested).
//!
//! The render runs with the GIL released. After every batch of passes (at
//! most about half a second) it checks for Python signals, so Ctrl-C
//! stops it and raises `KeyboardInterrupt`.

use crate::guarded;
use clap::Parser;
use fspec_cli::CliError;
use fspec_cli::image_out::{Exposure, Tone};
use fspec_cli::render_cmd::{
    self, OutputOptions, RenderArgs, RenderNotice, RenderObserver, RenderedFrame,
};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;
use simd_tracer::scene::builtin::SCENES;
use std::path::Path;
use std::sync::Mutex;

/// The command line of `fspec render`, without the program name.
#[derive(Debug, Parser)]
#[command(name = "fspec.render", no_binary_name = true)]
struct RenderCommand {
    #[command(flatten)]
    render: RenderArgs,
}

/// Collects the render's notices and checks Python's signals between
/// batches of passes.
#[derive(Default)]
struct PythonObserver {
    notices: Mutex<Vec<RenderNotice>>,
    interrupt: Mutex<Option<PyErr>>,
}

impl RenderObserver for PythonObserver {
    fn notice(&self, notice: &RenderNotice) {
        if let Ok(mut notices) = self.notices.lock() {
            notices.push(notice.clone());
        }
    }

    fn keep_going(&self) -> bool {
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => true,
            Err(error) => {
                if let Ok(mut interrupt) = self.interrupt.lock() {
                    *interrupt = Some(error);
                }
                false
            }
        }
    }
}

/// The outputs of a render from Python: nothing is written, so only the
/// image and (when `coefficients`, which makes them) the coefficient planes
/// count in the memory prediction.
fn no_files(coefficients: bool) -> OutputOptions {
    OutputOptions {
        outputs: Vec::new(),
        exr_xyz: false,
        spectral_exr: None,
        spectral_step_nm: 10.0,
        coefficients_exr: None,
        keep_coefficients: coefficients,
        exposure: Exposure { stops: 0.0 },
        tone: Tone::Clamp,
    }
}

/// The exception of a CLI error: `FileNotFoundError` when the scene file
/// itself does not exist, `ValueError` otherwise (the message is the
/// command line's either way).
fn exception(error: &CliError, scene: &str) -> PyErr {
    let is_builtin = SCENES.iter().any(|s| s.name == scene);
    let path = Path::new(scene);
    let names_a_file = path.extension().is_some() || path.components().count() > 1;
    if !is_builtin && names_a_file && !path.exists() {
        PyFileNotFoundError::new_err(error.to_string())
    } else {
        PyValueError::new_err(error.to_string())
    }
}

/// The first line of a clap error, without its `error: ` prefix.
fn argument_error(error: &clap::Error) -> PyErr {
    let text = error.to_string();
    let line = text.lines().next().unwrap_or_default();
    PyValueError::new_err(line.strip_prefix("error: ").unwrap_or(line).to_string())
}

/// How the image's three channels are expressed.
#[derive(Debug, Clone, Copy)]
enum ColorSpace {
    LinearSrgb,
    Xyz,
}

impl ColorSpace {
    fn parse(name: &str) -> PyResult<Self> {
        match name {
            "linear-srgb" => Ok(Self::LinearSrgb),
            "xyz" => Ok(Self::Xyz),
            other => Err(PyValueError::new_err(format!(
                "color {other:?}: use \"linear-srgb\" or \"xyz\""
            ))),
        }
    }
}

/// The image of `frame` as `float32`, row-major, 3 channels per pixel
/// (the narrowing of the CLI's EXR writer).
fn image_f32(frame: &RenderedFrame, space: ColorSpace) -> Vec<f32> {
    let mut image = Vec::with_capacity(frame.result.xyz.len() * 3);
    for xyz in &frame.result.xyz {
        let channels = match space {
            ColorSpace::LinearSrgb => {
                let rgb = xyz.to_linear_srgb();
                [rgb.r, rgb.g, rgb.b]
            }
            ColorSpace::Xyz => xyz.to_array(),
        };
        image.extend(channels.map(|c| c as f32));
    }
    image
}

/// What [`render`] returns: the image `(H, W, 3)`, the coefficient planes
/// `(H, W, N)` if asked for, the spectral range, the passes done, the
/// samples rejected as non-finite and the notices (`(is_warning, text)`).
type RenderOutput<'py> = (
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
    (f64, f64),
    u32,
    u64,
    Vec<(bool, String)>,
);

/// Renders with the command line `arguments` of `fspec render` (without
/// `--out` and the other file options); `color` is `"linear-srgb"` or
/// `"xyz"`; `coefficients` asks for the coefficient planes (a Fourier
/// transport with a spectral buffer keeps them).
#[pyfunction]
fn render<'py>(
    py: Python<'py>,
    arguments: Vec<String>,
    color: &str,
    coefficients: bool,
) -> PyResult<RenderOutput<'py>> {
    guarded(|| {
        let space = ColorSpace::parse(color)?;
        let args = RenderCommand::try_parse_from(&arguments)
            .map_err(|e| argument_error(&e))?
            .render;
        let spec = render_cmd::TransportSpec::of(&args);
        if coefficients && !spec.keeps_coefficients() {
            return Err(PyValueError::new_err(
                "coefficients=True needs transport=\"fourier\" with buffer=\"spectral\"",
            ));
        }
        let observer = PythonObserver::default();
        let output = no_files(coefficients);
        let frame = py.detach(|| {
            guarded(|| {
                render_cmd::render(&args, &output, &observer)
                    .map_err(|e| exception(&e, &args.scene))
            })
        })?;
        if let Some(interrupt) = observer.interrupt.lock().ok().and_then(|mut i| i.take()) {
            return Err(interrupt);
        }
        let (height, width) = (frame.result.height as usize, frame.result.width as usize);
        let image = PyArray1::from_vec(py, image_f32(&frame, space))
            .reshape([height, width, 3])?
            .into_any();
        let planes = match (&frame.result.coefficients, coefficients) {
            (Some((n, planes)), true) => Some(
                PyArray1::from_slice(py, planes)
                    .reshape([height, width, *n])?
                    .into_any(),
            ),
            _ => None,
        };
        let notices = observer
            .notices
            .lock()
            .map(|notices| {
                notices
                    .iter()
                    .map(|n| match n {
                        RenderNotice::Warning(text) => (true, text.clone()),
                        RenderNotice::Note(text) => (false, text.clone()),
                    })
                    .collect()
            })
            .unwrap_or_default();
        Ok((
            image,
            planes,
            (frame.range.min_nm(), frame.range.max_nm()),
            frame.result.passes,
            frame.result.rejected,
            notices,
        ))
    })
}

/// The built-in scenes: `(name, description)`.
#[pyfunction]
fn builtin_scenes() -> Vec<(&'static str, &'static str)> {
    SCENES.iter().map(|s| (s.name, s.description)).collect()
}

/// Adds this module's functions to `module`.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_function(wrap_pyfunction!(render, module)?)?;
    module.add_function(wrap_pyfunction!(builtin_scenes, module)?)?;
    Ok(())
}
