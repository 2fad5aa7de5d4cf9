//! Scene construction that no file format owns: what a front end hands
//! over once it has read a value, and what it gets back.
//!
//! [`Construction`] wraps the [`SceneBuilder`] together with everything a
//! scene description refers to by name or by file: named spectra (with the
//! built-in fallback, shadowing and scaling), named materials, the BSDFs'
//! angular functions, textures (image files cached per file, use and
//! sampling; checkerboards of two spectra), OBJ meshes and
//! quads (degenerate triangles counted), the camera and environment, and
//! the warnings (unused names, albedos above 1, skipped triangles). Every
//! error and warning is reported at a [`Spot`] of the [`Source`], so the
//! messages read `file:line: key: message` whatever the format.
//!
//! The seam: a front end (the TOML one in `toml_scene`, a future Mitsuba
//! XML importer) parses its syntax, checks its keys and types, and calls
//! these methods with plain values (a `SpectrumSource`, an `Ior`, a
//! path, vertices) and the spot to blame. It never touches TOML types or the
//! builder's bookkeeping here; wording that names a format's sections
//! (`[spectra]`, `[[meshes]]`) stays in the front end, which is why name
//! look-ups return `None` instead of an error.
//!
//! * `spectra`: named and built-in spectra, scaling, spectrum errors.
//! * `materials`: named materials, albedo checks, BSDFs and their angular
//!   functions.
//! * `meshes`: triangles, quads, OBJ/MTL, PLY and serialized files,
//!   analytic shapes, transforms and instances.
//! * `lights`: point, spot and directional lights, environment maps.
//! * `textures`: image textures and checkerboards with their sampling.

mod lights;
mod materials;
mod meshes;
mod spectra;
mod textures;

pub(crate) use lights::MapSettings;
pub(crate) use materials::{ConductorIndex, ThinFilm, coated};
pub(crate) use meshes::{
    FaceMaterials, MeshFormat, MeshParts, Mesher, Placement, load_obj_geometry,
};
pub(crate) use spectra::{builtin_error, tabulated_message};

use super::source::{Source, Spot};
use crate::error::CliError;
use materials::NamedMaterial;
use simd_tracer::ids::{SpectrumId, TextureId};
use simd_tracer::scene::SceneBuilder;
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::instances::InstancedMeshId;
use spectra::NamedSpectrum;
use spectral_core::SpectralRange;
use std::collections::HashMap;
use std::path::PathBuf;
use textures::TextureKey;

/// A scene under construction (module docs).
pub(crate) struct Construction<'s> {
    src: Source<'s>,
    /// Directory that file references are relative to; `None` refuses every
    /// file reference (the fuzz entry point reads no file).
    dir: Option<PathBuf>,
    range: SpectralRange,
    builder: SceneBuilder,
    warnings: Vec<String>,
    spectra: HashMap<String, NamedSpectrum>,
    spectrum_order: Vec<String>,
    /// Built-in spectra added so far, by lower-case name.
    builtins: HashMap<String, SpectrumId>,
    materials: HashMap<String, NamedMaterial>,
    material_order: Vec<String>,
    textures: HashMap<TextureKey, TextureId>,
    mesher: Mesher,
    has_environment: bool,
    /// Meshes kept for instances, by name.
    named_meshes: HashMap<String, MeshParts>,
    /// The builder's id of each named mesh that an instance placed.
    instanced_meshes: HashMap<String, InstancedMeshId>,
    /// The instances placed so far.
    instances: InstanceCount,
    /// Point and directional lights added.
    lights: usize,
}

/// Instances placed (kept as instances or flattened when the scene is
/// built: `simd_tracer::scene::instances`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct InstanceCount {
    /// Copies placed.
    pub copies: u32,
    /// Triangles they place (degenerate ones included).
    pub triangles: u64,
}

impl<'s> Construction<'s> {
    /// An empty scene over 360–830 nm described by `src`, with file
    /// references relative to `dir` (or refused when `None`).
    pub(crate) fn new(src: Source<'s>, dir: Option<PathBuf>) -> Self {
        let range = SpectralRange::VISIBLE;
        Self {
            src,
            dir,
            range,
            builder: SceneBuilder::new(range),
            warnings: Vec::new(),
            spectra: HashMap::new(),
            spectrum_order: Vec::new(),
            builtins: HashMap::new(),
            materials: HashMap::new(),
            material_order: Vec::new(),
            textures: HashMap::new(),
            mesher: Mesher::default(),
            has_environment: false,
            named_meshes: HashMap::new(),
            instanced_meshes: HashMap::new(),
            instances: InstanceCount::default(),
            lights: 0,
        }
    }

    /// Adds a warning at `at`.
    pub(crate) fn warn(&mut self, at: &Spot, message: impl std::fmt::Display) {
        let warning = self.src.warning_at(at, message);
        self.warnings.push(warning);
    }

    /// Adds a warning line as it is (a front end's own, already located).
    pub(crate) fn push_warning(&mut self, warning: String) {
        self.warnings.push(warning);
    }

    /// The path of the file reference `name` made at `at` (relative to the
    /// scene file's directory).
    pub(crate) fn resolve_file(&self, at: &Spot, name: &str) -> Result<PathBuf, CliError> {
        match &self.dir {
            Some(dir) => Ok(dir.join(name)),
            None => Err(self
                .src
                .error_at(at, "file references are not available here")),
        }
    }

    /// Sets the camera.
    pub(crate) fn set_camera(&mut self, camera: Camera) {
        self.builder.set_camera(camera);
    }

    /// Sets the constant environment radiance.
    pub(crate) fn set_environment(&mut self, spectrum: SpectrumId) {
        self.builder.set_environment(Some(spectrum));
        self.has_environment = true;
    }

    /// The triangles added so far.
    pub(crate) fn mesher(&self) -> &Mesher {
        &self.mesher
    }

    /// Whether nothing lights the scene (no emissive triangle and no
    /// environment).
    pub(crate) fn is_unlit(&self) -> bool {
        self.mesher.emissive_triangles == 0 && !self.has_environment && self.lights == 0
    }

    /// The instances placed so far.
    pub(crate) fn instances(&self) -> InstanceCount {
        self.instances
    }

    /// The builder and the warnings, with the unused spectra and materials
    /// warned about (in definition order).
    pub(crate) fn finish(mut self) -> (SceneBuilder, Vec<String>) {
        self.warn_unused_spectra();
        self.warn_unused_materials();
        (self.builder, self.warnings)
    }
}
