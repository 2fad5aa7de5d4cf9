//! Resolving the scene argument of `fspec render`: a built-in name, a TOML
//! scene file, a Mitsuba 3 XML scene file or a bare OBJ.

use crate::error::CliError;
use crate::scene_file::{InstanceCount, RenderDefaults};
use crate::spectrum_file::{SpectrumSource as CliSpectrum, resolve};
use simd_tracer::scene::SceneBuilder;
use simd_tracer::scene::builtin::{SCENES, SceneOptions, builtin_scene};
use simd_tracer::spectra::SpectrumSource;
use spectral_core::SpectralRange;
use std::path::Path;

/// What a scene file sets for a render: its `[render]` defaults, which
/// command-line flags override, and the instances it places (a built-in
/// scene sets nothing).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneDefaults {
    /// The file's `[render]` settings.
    pub render: RenderDefaults,
    /// Instances placed (kept as instances or flattened at build).
    pub instances: InstanceCount,
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
        render: loaded.render,
        instances: loaded.instances,
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
