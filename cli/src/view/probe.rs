//! A clicked pixel's spectrum, for any transport: the pixel traced again
//! on request, once with a Fourier transport (its coefficients, the curve
//! on the page) and once with the sampled transport binned by wavelength
//! (`simd_tracer::film::BinnedFilm`: the mean radiance of each
//! [`PROBE_BIN_WIDTH_NM`] bin with its standard error), each for at most
//! [`PROBE_PATHS`] paths and [`PROBE_TIME_LIMIT`].
//!
//! Why trace again rather than read the film: the sampled films keep XYZ
//! sums only (a spectrum per pixel would multiply their memory by dozens),
//! and a pixel of the image holds a few passes where a spectrum needs
//! thousands of paths. Both probes render a one-pixel window of the
//! frame's own scene, camera and settings (`render_passes`, the renderer's
//! packets: the window's packet of 4 × 2 pixels is traced, one pixel
//! kept), on one thread of their own, so the render's threads go on and
//! a probe costs at most twice [`PROBE_TIME_LIMIT`] of one core. The two
//! estimates agree within the bars when the Fourier series represents the
//! pixel's spectrum (`simd-tracer`'s `transport::binned` test); where they
//! do not, the gap is the series' truncation.

use crate::error::CliError;
use crate::render_cmd::{self, BufferKind, Sampling, ToColor, TransportSpec, TransportTask};
use simd_tracer::film::{BinnedEstimate, SpectralBins};
use simd_tracer::render::{PassJob, PixelWindow, RenderSettings, render_passes};
use simd_tracer::scene::Scene;
use simd_tracer::scene::camera::Camera;
use simd_tracer::transport::emission_density::emission_density;
use simd_tracer::transport::{BinnedSampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use std::sync::{Arc, PoisonError, RwLock};
use std::time::Duration;

/// Paths per probe: a few thousand put about 350 wavelength samples in
/// each 10 nm bin with four wavelengths per path (a standard error of a
/// few percent where the radiance is smooth).
pub const PROBE_PATHS: u32 = 4096;

/// Longest a probe's render may take (each of the two): a click is
/// answered within about twice this on any scene.
pub const PROBE_TIME_LIMIT: Duration = Duration::from_secs(2);

/// Width of the sampled estimate's bins, nm: 47 bins over 360–830 nm,
/// twice the CIE tables' 5 nm, so each bin gets enough samples.
pub const PROBE_BIN_WIDTH_NM: f64 = 10.0;

/// Wavelengths per path of the sampled probe (hero rotations unless the
/// image's sampled transport draws otherwise): `fspec render`'s default.
pub const PROBE_WAVELENGTHS: usize = 4;

/// Coefficients of the Fourier probe when the image's transport has none
/// (sampled): the viewer's default transport's.
pub const PROBE_DEFAULT_COEFFS: usize = 12;

/// What a probe needs of a frame: its scene and camera, render settings
/// and transport, and the observer of its colours.
#[derive(Debug)]
pub struct ProbeScene {
    /// The scene, shared with the render driver (read beside the render;
    /// the driver writes only the camera, between renders).
    pub scene: Arc<RwLock<Scene>>,
    /// The frame's camera: a probe of a frame whose camera has moved since
    /// is refused.
    pub camera: Camera,
    /// The render's settings (size, seed, filter, depth).
    pub settings: RenderSettings,
    /// The image's transport (the probes' sizes and sampling follow it).
    pub transport: TransportSpec,
    /// The observer of the image.
    pub observer: Arc<Observer>,
}

/// A pixel's two spectra.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelSpectrum {
    /// The Fourier probe's mean coefficients.
    pub coefficients: Vec<f32>,
    /// Paths of the Fourier probe.
    pub fourier_paths: u32,
    /// The bins of the sampled probe.
    pub bins: SpectralBins,
    /// The sampled probe's estimate per bin.
    pub sampled: BinnedEstimate,
    /// The sampled probe's wavelength sampling.
    pub sampling: Sampling,
}

impl ProbeScene {
    /// The Fourier transport of the probe: the image's when it has
    /// coefficients, else [`PROBE_DEFAULT_COEFFS`].
    fn fourier_spec(&self) -> TransportSpec {
        let coeffs = match self.transport {
            TransportSpec::Fourier { coeffs, .. }
            | TransportSpec::Cv { coeffs, .. }
            | TransportSpec::Hybrid { coeffs, .. } => coeffs,
            TransportSpec::Sampled { .. } => PROBE_DEFAULT_COEFFS,
        };
        TransportSpec::Fourier {
            coeffs,
            buffer: BufferKind::Spectral,
            to_color: ToColor::Zeroth,
        }
    }

    /// The sampling of the sampled probe: the image's when it samples
    /// wavelengths, else hero.
    fn sampling(&self) -> Sampling {
        match self.transport {
            TransportSpec::Sampled { sampling, .. }
            | TransportSpec::Cv { sampling, .. }
            | TransportSpec::Hybrid { sampling, .. } => sampling,
            TransportSpec::Fourier { .. } => Sampling::Hero,
        }
    }

    /// The settings of a probe of pixel `(x, y)`.
    fn probe_settings(&self, x: u32, y: u32) -> RenderSettings {
        RenderSettings {
            spp: PROBE_PATHS,
            threads: Some(1),
            time_limit: Some(PROBE_TIME_LIMIT),
            window: Some(PixelWindow {
                x,
                y,
                width: 1,
                height: 1,
            }),
            film: simd_tracer::film::FilmMode::Sample,
            ..self.settings.clone()
        }
    }

    /// Whether the scene still has this frame's camera (the render has not
    /// moved on to another view).
    pub fn is_current(&self) -> bool {
        *self
            .scene
            .read()
            .unwrap_or_else(PoisonError::into_inner)
            .camera()
            == self.camera
    }

    /// Traces pixel `(x, y)` both ways (module docs).
    pub fn trace(&self, x: u32, y: u32) -> Result<PixelSpectrum, CliError> {
        if x >= self.settings.width || y >= self.settings.height {
            return Err(CliError::input(format!(
                "pixel ({x}, {y}) is outside the {}×{} image",
                self.settings.width, self.settings.height
            )));
        }
        let scene = self.scene.read().unwrap_or_else(PoisonError::into_inner);
        if *scene.camera() != self.camera {
            return Err(CliError::input(
                "the camera has moved since this image: click the new one",
            ));
        }
        let settings = self.probe_settings(x, y);
        let range = scene.range();
        let basis = render_cmd::TransportBasis {
            range,
            observer: &self.observer,
            density: None,
        };
        let (coefficients, fourier_paths) = render_cmd::with_transport(
            &self.fourier_spec(),
            basis,
            CoefficientProbe {
                scene: &scene,
                settings: &settings,
            },
        )?;
        let bins = probe_bins(range)?;
        let sampling = self.sampling();
        let density = match sampling {
            Sampling::Lights => Some(Arc::new(
                emission_density(&scene, &self.observer).map_err(CliError::input)?,
            )),
            _ => None,
        };
        let transport = BinnedSampledTransport::<PROBE_WAVELENGTHS>::new(
            range,
            render_cmd::strategy(sampling),
            Arc::clone(&self.observer),
            bins,
        )
        .map_err(CliError::input)?
        .with_density(density);
        let job = PassJob {
            keep_state: true,
            ..PassJob::default()
        };
        let (_, state) = render_passes(&transport, &scene, &settings, &job, &mut |_| true)
            .map_err(|e| CliError::input(e.to_string()))?;
        let sampled = state
            .and_then(|state| transport.film().estimate(state.pixel(0)))
            .ok_or_else(|| CliError::input("the sampled probe kept no pixel"))?;
        Ok(PixelSpectrum {
            coefficients,
            fourier_paths,
            bins,
            sampled,
            sampling,
        })
    }
}

/// Equal bins over `range`, [`PROBE_BIN_WIDTH_NM`] wide or a little
/// wider where that width does not divide the range.
pub fn probe_bins(range: SpectralRange) -> Result<SpectralBins, CliError> {
    let count = ((range.width_nm() / PROBE_BIN_WIDTH_NM).floor() as usize).max(1);
    SpectralBins::new(range, count).map_err(CliError::input)
}

/// The Fourier probe: the window's mean coefficients and its paths.
struct CoefficientProbe<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
}

impl TransportTask for CoefficientProbe<'_> {
    type Output = (Vec<f32>, u32);

    fn run<T: Transport>(self, transport: &T) -> Result<Self::Output, CliError> {
        let (result, _) = render_passes(
            transport,
            self.scene,
            self.settings,
            &PassJob::default(),
            &mut |_| true,
        )
        .map_err(|e| CliError::input(e.to_string()))?;
        let (_, coefficients) = result
            .coefficients
            .ok_or_else(|| CliError::input("the Fourier probe kept no coefficients"))?;
        Ok((coefficients, result.passes))
    }
}
