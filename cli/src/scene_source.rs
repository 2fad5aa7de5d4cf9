//! Resolving the scene argument of `fspec render`: a built-in name, a TOML
//! scene file, a Mitsuba 3 XML scene file or a bare OBJ.

use crate::error::CliError;
use crate::spectrum_file::{SpectrumSource as CliSpectrum, resolve};
use simd_tracer::scene::SceneBuilder;
use simd_tracer::scene::builtin::{SCENES, SceneOptions, builtin_scene};
use simd_tracer::spectra::SpectrumSource;
use spectral_core::SpectralRange;
use std::path::Path;

/// Render settings a scene file may set (CLI flags override them).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneDefaults {
    /// What the channels measure.
    pub observer: Option<crate::sensor_file::ObserverChoice>,
    /// Width, pixels.
    pub width: Option<u32>,
    /// Height, pixels.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Max depth.
    pub max_depth: Option<u32>,
    /// Seed.
    pub seed: Option<u64>,
    /// Camera rays do not see emitters.
    pub hide_emitters: Option<bool>,
    /// How samples reach pixels.
    pub film: Option<simd_tracer::film::FilmMode>,
    /// Independent or Sobol numbers.
    pub sampler: Option<simd_tracer::sampling::sampler::SamplerKind>,
    /// Depth from which Russian roulette may end paths.
    pub rr_depth: Option<u32>,
    /// Pixel filter.
    pub filter: Option<crate::scene_file::FilterChoice>,
    /// The part of the film rendered.
    pub crop: Option<crate::scene_file::CropWindow>,
    /// Instances placed (kept as instances or flattened at build).
    pub instances: crate::scene_file::InstanceCount,
    /// The transport's name (`[render] transport`).
    pub transport: Option<String>,
    /// The wavelength sampling's name (`[render] sampling`).
    pub sampling: Option<String>,
    /// Fourier coefficients, a number or `auto`.
    pub coeffs: Option<crate::coefficient_choice::CoeffsChoice>,
}

/// The builder, defaults and warnings of the scene named by `argument`.
pub fn resolve_scene(
    argument: &str,
    options: &SceneOptions,
    mitsuba: &crate::scene_file::MitsubaOptions,
) -> Result<(SceneBuilder, SceneDefaults, Vec<String>), CliError> {
    if SCENES.iter().any(|s| s.name == argument) {
        let builder = builtin_scene(argument, SpectralRange::VISIBLE, options)
            .map_err(|e| CliError::input(e.to_string()))?;
        return Ok((builder, SceneDefaults::default(), Vec::new()));
    }
    let path = Path::new(argument);
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let loaded = match extension.as_deref() {
        Some("toml") => crate::scene_file::load_scene_file(path)?,
        Some("xml") => crate::scene_file::load_mitsuba_scene(path, mitsuba)?,
        Some("obj") => crate::scene_file::load_obj_scene(path)?,
        _ if path.exists() => {
            return Err(CliError::input(format!(
                "{argument}: unknown scene format (use .toml, .xml or .obj)"
            )));
        }
        _ => {
            let names: Vec<&str> = SCENES.iter().map(|s| s.name).collect();
            return Err(CliError::input(format!(
                "`{argument}` is neither a built-in scene ({}) nor a .toml/.xml/.obj file",
                names.join(", ")
            )));
        }
    };
    let defaults = SceneDefaults {
        observer: loaded.render.observer.clone(),
        width: loaded.render.width,
        height: loaded.render.height,
        spp: loaded.render.spp,
        max_depth: loaded.render.max_depth,
        seed: loaded.render.seed,
        hide_emitters: loaded.render.hide_emitters,
        film: loaded.render.film,
        sampler: loaded.render.sampler,
        rr_depth: loaded.render.rr_depth,
        filter: loaded.render.filter,
        crop: loaded.render.crop,
        instances: loaded.instances,
        transport: loaded.render.transport.clone(),
        sampling: loaded.render.sampling.clone(),
        coeffs: loaded.render.coeffs,
    };
    Ok((loaded.builder, defaults, loaded.warnings))
}

/// The spectrum of `--illuminant`: a built-in name or a CSV file.
pub fn illuminant_source(argument: &str) -> Result<SpectrumSource, CliError> {
    Ok(match resolve(argument)? {
        CliSpectrum::Builtin(b) => SpectrumSource::Builtin(b),
        CliSpectrum::File(data) => SpectrumSource::Tabulated {
            lambda_nm: data.lambda_nm,
            values: data.values,
        },
    })
}

/// `fspec scenes`: the built-in scenes, one per line.
pub fn list_scenes() -> String {
    SCENES
        .iter()
        .map(|s| format!("{:<14} {}\n", s.name, s.description))
        .collect()
}
