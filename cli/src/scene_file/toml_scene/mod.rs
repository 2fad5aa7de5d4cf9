//! The TOML front end: walks a scene file's sections and hands their values
//! to the format-independent construction.
//!
//! [`load_toml_scene`] parses the text ([`toml_reader`]),
//! refuses unknown top-level keys and reads the sections in a fixed order —
//! `[render]`, `[camera]`, `[spectra]`, `[materials]`, `[environment]`,
//! `[[meshes]]`, `[[quads]]` — so that names are defined before they are
//! used. Each section checks its keys and types and words the errors that
//! name TOML sections; what the values mean (spectra, BSDFs, meshes) is
//! built by [`Construction`]. The
//! format reference is the module docs of `scene_file`.
//!
//! * `settings`: `[render]`, `[camera]`, `[environment]`.
//! * `spectra`: `[spectra]` and spectrum references.
//! * `materials`: `[materials]`, one function per material type.
//! * `geometry`: `[[meshes]]` and `[[quads]]`.
//! * `textures`: texture references (a file, or a table with the sampling
//!   keys; checkerboards).

mod geometry;
mod lights;
mod materials;
mod settings;
mod spectra;
mod textures;
mod transform;

use super::LoadedScene;
use super::construction::Construction;
use super::source::Source;
use super::toml_reader::{self, Item, Table};
use crate::error::CliError;
use std::path::PathBuf;

/// Loads the scene described by the TOML text of `src`, with file
/// references relative to `dir` (or refused when `None`).
pub(crate) fn load_toml_scene(
    src: Source<'_>,
    dir: Option<PathBuf>,
) -> Result<LoadedScene, CliError> {
    let document = toml_reader::parse(&src)?;
    let root = Table::root(&document);
    Loader {
        cx: Construction::new(src.clone(), dir),
        src,
    }
    .load(&root)
}

/// The TOML walk over one scene file.
struct Loader<'s> {
    /// For the messages of TOML values (the construction has its own copy).
    src: Source<'s>,
    cx: Construction<'s>,
}

impl Loader<'_> {
    /// The path of a file reference `item` (a string, relative to the scene
    /// file's directory).
    fn file(&self, item: &Item<'_, '_>) -> Result<PathBuf, CliError> {
        let name = item.string(&self.src)?;
        self.cx.resolve_file(&item.spot(), name)
    }

    fn load(mut self, root: &Table<'_, '_>) -> Result<LoadedScene, CliError> {
        root.allow(
            &self.src,
            &[
                "render",
                "camera",
                "spectra",
                "materials",
                "meshes",
                "shapes",
                "instances",
                "quads",
                "lights",
                "environment",
            ],
            "a scene file",
        )?;
        let render = match root.get("render") {
            Some(item) => self.render_section(&item)?,
            None => Default::default(),
        };
        let camera = root.require(&self.src, "camera", "a scene needs a [camera] table")?;
        self.camera_section(&camera)?;
        if let Some(item) = root.get("spectra") {
            self.spectra_section(&item)?;
        }
        if let Some(item) = root.get("materials") {
            self.materials_section(&item)?;
        }
        if let Some(item) = root.get("environment") {
            self.environment_section(&item)?;
        }
        if let Some(item) = root.get("meshes") {
            self.meshes_section(&item)?;
        }
        if let Some(item) = root.get("shapes") {
            self.shapes_section(&item)?;
        }
        if let Some(item) = root.get("instances") {
            self.instances_section(&item)?;
        }
        if let Some(item) = root.get("quads") {
            self.quads_section(&item)?;
        }
        if let Some(item) = root.get("lights") {
            self.lights_section(&item)?;
        }
        if let Some(message) = self
            .cx
            .mesher()
            .no_geometry("the scene has no geometry (add [[meshes]], [[shapes]] or [[quads]])")
        {
            return Err(self.src.error(&root.span, "meshes", message));
        }
        let unlit = self.cx.is_unlit();
        let instances = self.cx.instances();
        let (builder, mut warnings) = self.cx.finish();
        if unlit {
            warnings.push(format!(
                "{}: the scene has no light (no emissive triangle, [[lights]] or [environment]): it renders black",
                self.src.file
            ));
        }
        Ok(LoadedScene {
            builder,
            render,
            warnings,
            instances,
        })
    }
}
