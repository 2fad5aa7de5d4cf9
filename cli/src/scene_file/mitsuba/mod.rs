//! The Mitsuba 3 front end: `fspec render scene.xml` renders a Mitsuba 3
//! scene file as Mitsuba 3.9.1's spectral variants do.
//!
//! # Flow
//!
//! 1. `document`: the XML is read (`roxmltree`, which reports line and
//!    column), `<include>`s spliced in, `<default>`s and `-D name=value`
//!    substituted for `$name`, `<path>`s collected: one [`Element`] tree
//!    whose elements know their file and line.
//! 2. `properties`: each object's child elements become typed properties
//!    ([`Object`]); `transforms` reads `<transform>`.
//! 3. This module walks the scene: ids are collected first (so a `<ref>`
//!    may point forward), then the sensor (camera, film, filter, sampler),
//!    the integrator, the shapes (with their BSDFs and area emitters) and
//!    the other emitters are built through the format-independent
//!    `construction` (shared with the TOML front end). Objects are built
//!    when something uses them: a BSDF, texture or spectrum that is defined
//!    but never referenced costs nothing and gets a warning.
//! 4. `sensor`, `shapes`, `bsdfs`, `emitters`, `textures`, `spectra`: one
//!    file per kind of plugin, each with the parameters and the Mitsuba
//!    semantics it follows in its docs; `named_ior` and `conductors` hold
//!    Mitsuba's tables of indices of refraction and measured metals.
//!
//! # Errors, warnings, `--lenient`
//!
//! Every error is one line `file:line: message` (exit code 2): malformed
//! XML, unknown references, cyclic includes, a `$name` without a value,
//! wrong property types, missing files, absurd sizes. A plugin outside the
//! supported subset is an error naming it (`scene.xml:42: bsdf type "hair"
//! is not supported`); so is a parameter that the plugin does not know or
//! that the importer cannot honour (Mitsuba too refuses unreferenced
//! properties). With `--lenient` an unsupported BSDF becomes a grey
//! diffuse one, an unsupported emitter is skipped and an unknown parameter
//! ignored, each with one warning line.

mod bsdfs;
mod conductors;
mod document;
mod emitters;
mod named_ior;
mod principled;
mod properties;
mod sensor;
mod shapes;
mod spectra;
mod textures;
mod transforms;

use super::construction::Construction;
use super::source::{Source, Spot};
use super::{LoadedScene, RenderDefaults};
use crate::error::CliError;
use document::{Element, Input, read_scene};
use properties::{Object, Value};
use simd_tracer::ids::MaterialId;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// Options of the Mitsuba importer (`fspec render scene.xml …`).
#[derive(Debug, Clone, Default)]
pub struct MitsubaOptions {
    /// `-D name=value` parameters, in order; they win over `<default>`s.
    pub defines: Vec<(String, String)>,
    /// Unsupported BSDFs become grey diffuse, unsupported emitters and
    /// parameters are skipped, each with a warning (else they are errors).
    pub lenient: bool,
}

/// Loads the Mitsuba 3 scene file `path` (module docs).
pub fn load_mitsuba_scene(path: &Path, options: &MitsubaOptions) -> Result<LoadedScene, CliError> {
    load(Input::File(path), options)
}

/// Fuzz entry point: arbitrary bytes as a Mitsuba scene file, every file
/// reference refused. Checks that nothing panics, that errors and warnings
/// are one line each, and that an accepted scene builds or gives `Err`.
pub fn fuzz_scene_xml(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    for options in [
        MitsubaOptions::default(),
        MitsubaOptions {
            lenient: true,
            ..MitsubaOptions::default()
        },
    ] {
        let loaded = match load(
            Input::Text {
                name: "fuzz.xml",
                text,
            },
            &options,
        ) {
            Ok(loaded) => loaded,
            Err(e) => {
                let message = e.to_string();
                assert!(!message.contains('\n'), "multi-line error: {message:?}");
                continue;
            }
        };
        for warning in &loaded.warnings {
            assert!(!warning.contains('\n'), "multi-line warning: {warning:?}");
        }
        match loaded.builder.build() {
            Ok(scene) => assert!(
                scene.bvh().validate(&scene.triangles()).is_ok(),
                "{:?}",
                scene.bvh().validate(&scene.triangles())
            ),
            Err(simd_tracer::scene::SceneError::Bvh(message)) => {
                panic!("BVH validation failed: {message}")
            }
            Err(_) => {}
        }
    }
}

fn load(input: Input<'_>, options: &MitsubaOptions) -> Result<LoadedScene, CliError> {
    let read = read_scene(input, &options.defines)?;
    let root = read.root;
    check_version(&root)?;
    let shown = root.place.file.to_string();
    let mut importer = Importer {
        cx: Construction::new(
            Source {
                file: shown.clone(),
                text: "",
            },
            None,
        ),
        ids: HashMap::new(),
        used: HashSet::new(),
        options,
        bsdfs: HashMap::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        fraction_textures: HashMap::new(),
        vector_textures: HashMap::new(),
        render: RenderDefaults::default(),
        camera_set: false,
        root_spot: Importer::spot(&root, String::new()),
        environment_set: false,
        integrator_set: false,
    };
    for warning in read.warnings {
        importer.cx.push_warning(warning);
    }
    importer.collect_ids(&root, false)?;
    importer.scene(&root)?;
    importer.finish(&root)
}

/// Refuses files of Mitsuba 0.x, whose parameter names differ.
fn check_version(root: &Element) -> Result<(), CliError> {
    let Some(version) = root.attr("version") else {
        return Err(root.error("<scene> needs a `version` attribute (e.g. \"3.0.0\")"));
    };
    let major = version
        .split('.')
        .next()
        .and_then(|m| m.trim().parse::<u32>().ok())
        .ok_or_else(|| {
            root.error(format!(
                "<scene version=\"{version}\">: not a version number"
            ))
        })?;
    if major < 2 {
        return Err(root.error(format!(
            "<scene version=\"{version}\">: Mitsuba 0.x files are not supported (convert with Mitsuba 3's upgrade, version 2.0 or later)"
        )));
    }
    Ok(())
}

/// A material is one BSDF with one (or no) area emitter; keyed by the
/// elements' addresses (the tree is not changed while the scene is built,
/// so an address names one element).
type MaterialKey = (usize, usize);

/// The walk over one scene.
pub(super) struct Importer<'e, 's> {
    cx: Construction<'s>,
    /// Objects by `id`.
    ids: HashMap<&'e str, &'e Element>,
    /// Ids referenced.
    used: HashSet<&'e str>,
    options: &'e MitsubaOptions,
    /// BSDFs built, by element address.
    bsdfs: HashMap<usize, bsdfs::BuiltBsdf>,
    /// Materials added, by BSDF and emitter.
    materials: HashMap<MaterialKey, MaterialId>,
    /// Textures added, by element address.
    textures: HashMap<usize, simd_tracer::ids::TextureId>,
    /// Scalar textures added (`mask`'s opacity, `blendbsdf`'s weight), by
    /// element address.
    /// (and bump maps' heights, unclamped: `true` in the key's second
    /// place).
    fraction_textures: HashMap<(usize, bool), simd_tracer::ids::TextureId>,
    /// Normal maps' textures (`normalmap`), by element address.
    vector_textures: HashMap<usize, simd_tracer::ids::TextureId>,
    render: RenderDefaults,
    camera_set: bool,
    /// The scene element's spot, for what no element states.
    root_spot: Spot,
    /// An environment emitter was added.
    environment_set: bool,
    /// An integrator was read.
    integrator_set: bool,
}

/// The address of an element, its identity in caches.
fn address(e: &Element) -> usize {
    std::ptr::from_ref(e) as usize
}

impl<'e> Importer<'e, '_> {
    /// The spot of `e` for construction messages, named `key`.
    fn spot(e: &Element, key: String) -> Spot {
        Spot::in_file(key, e.place.file.clone(), e.place.line)
    }

    /// A warning at element `e`.
    fn warn_at(&mut self, e: &Element, message: impl std::fmt::Display) {
        let spot = Self::spot(e, String::new());
        self.cx.warn(&spot, message);
    }

    /// Collects every object with an `id` (duplicates are errors, as in
    /// Mitsuba).
    /// An object nested in another is used where it stands, so only the
    /// scene's own children can be unused.
    fn collect_ids(&mut self, e: &'e Element, nested: bool) -> Result<(), CliError> {
        for child in &e.children {
            if child.tag != "ref"
                && let Some(id) = child.attr("id")
            {
                if let Some(first) = self.ids.insert(id, child) {
                    return Err(child.error(format!(
                        "id \"{id}\" is defined twice (first at line {})",
                        first.place.line
                    )));
                }
                if nested {
                    self.used.insert(id);
                }
            }
            self.collect_ids(child, true)?;
        }
        Ok(())
    }

    /// The element that `<ref id>` names, marked used.
    fn resolve_ref(&mut self, at: &Element, id: &str) -> Result<&'e Element, CliError> {
        let (&key, &target) = self
            .ids
            .get_key_value(id)
            .ok_or_else(|| at.error(format!("<ref id=\"{id}\">: no object has this id")))?;
        self.used.insert(key);
        Ok(target)
    }

    /// The object of a property that is a nested object or a reference, with
    /// its tag checked against `tags`.
    fn object_of(
        &mut self,
        property: &properties::Property<'e>,
        tags: &[&str],
    ) -> Result<&'e Element, CliError> {
        let element = match property.value {
            Value::Object(e) => e,
            Value::Ref(id) => self.resolve_ref(property.element, id)?,
            ref other => return Err(property.wrong_type(&tags.join(" or "), other)),
        };
        if !tags.contains(&element.tag.as_str()) {
            return Err(property.error(format!(
                "expected a {}, got a <{}>",
                tags.join(" or "),
                element.tag
            )));
        }
        Ok(element)
    }

    /// The unnamed nested objects of `object` with tag `tag`, references
    /// resolved (a reference to another kind of object is left alone).
    fn nested_of(&mut self, object: &Object<'e>, tag: &str) -> Result<Vec<&'e Element>, CliError> {
        let properties = object.nested(tag, |p, id| {
            Ok(self.resolve_ref(p.element, id)?.tag.as_str())
        })?;
        properties
            .into_iter()
            .map(|p| self.object_of(p, &[tag]))
            .collect()
    }

    /// Reports the properties of `object` that nothing read: an error, or
    /// a warning with `--lenient`.
    fn check_unused(&mut self, object: &Object<'e>) -> Result<(), CliError> {
        let unused: Vec<_> = object.unused().collect();
        for p in unused {
            let what = if p.name.is_empty() {
                format!("nested <{}>", p.element.tag)
            } else {
                format!("parameter \"{}\"", p.name)
            };
            let message = format!("{}: {what} is not supported", object.describe());
            if self.options.lenient {
                self.warn_at(p.element, format!("{message}; ignored (--lenient)"));
            } else {
                return Err(p.element.error(format!("{message} (--lenient ignores it)")));
            }
        }
        Ok(())
    }

    /// An unsupported plugin: an error, or with `--lenient` a warning and
    /// `Ok(false)` (the caller substitutes or skips).
    fn unsupported(&mut self, e: &Element, what: &str) -> Result<bool, CliError> {
        let plugin = e.attr("type").unwrap_or("");
        let message = format!("{} type \"{plugin}\" is not supported", e.tag);
        if self.options.lenient {
            self.warn_at(e, format!("{message}; {what} (--lenient)"));
            Ok(false)
        } else {
            Err(e.error(format!("{message} (--lenient: {what})")))
        }
    }

    /// The scene's top-level objects, in document order (the sensor first,
    /// so that shapes and emitters see the film size).
    fn scene(&mut self, root: &'e Element) -> Result<(), CliError> {
        let mut sensors = root.children.iter().filter(|c| c.tag == "sensor");
        if let Some(sensor) = sensors.next() {
            self.sensor(sensor)?;
        }
        if let Some(second) = sensors.next() {
            self.warn_at(
                second,
                "a second <sensor> is ignored (the first one renders)",
            );
        }
        for child in &root.children {
            match child.tag.as_str() {
                "sensor" => {}
                "integrator" => {
                    if self.integrator_set {
                        return Err(child.error("a scene takes one <integrator>"));
                    }
                    self.integrator_set = true;
                    self.integrator(child)?;
                }
                "shape" => self.shape(child)?,
                "emitter" => self.emitter(child)?,
                // Built when referenced; unused ones are warned about.
                // (A sensor may name its sampler, film or filter by id.)
                "bsdf" | "texture" | "spectrum" | "sampler" | "film" | "rfilter" => {
                    if child.attr("id").is_none() {
                        self.warn_at(
                            child,
                            format!("<{}> without `id` cannot be referenced: unused", child.tag),
                        );
                    }
                }
                "medium" | "phase" | "volume" => {
                    if !self.options.lenient {
                        return Err(child.error(format!(
                            "<{}>: participating media are not supported (--lenient ignores them)",
                            child.tag
                        )));
                    }
                    self.warn_at(child, format!("<{}> ignored (--lenient)", child.tag));
                }
                other => {
                    return Err(child.error(format!(
                        "<{other}> is not a scene-level element (integer, float, … are properties of objects)"
                    )));
                }
            }
        }
        Ok(())
    }

    fn finish(mut self, root: &Element) -> Result<LoadedScene, CliError> {
        if !self.camera_set {
            return Err(root.error("the scene has no <sensor>"));
        }
        if !self.integrator_set {
            sensor::path_defaults(&mut self.render);
            self.cx.warn(
                &self.root_spot.clone(),
                "the scene has no <integrator> (Mitsuba refuses to render it): rendering with path's defaults (max_depth -1, rr_depth 5)",
            );
        }
        if let Some(message) = self.cx.mesher().no_geometry("the scene has no shape") {
            return Err(root.error(message));
        }
        let mut unused: Vec<(&str, &Element)> = self
            .ids
            .iter()
            .filter(|(id, e)| !self.used.contains(*id) && is_referable(e))
            .map(|(id, e)| (*id, *e))
            .collect();
        unused.sort_by_key(|(_, e)| (e.place.file.clone(), e.place.line));
        for (id, e) in unused {
            self.warn_at(
                e,
                format!("<{} id=\"{id}\"> is defined but never used", e.tag),
            );
        }
        let unlit = self.cx.is_unlit();
        let instances = self.cx.instances();
        let render = self.render;
        let (builder, mut warnings) = self.cx.finish();
        if unlit {
            warnings.push(root.place.message(
                "the scene has no light (no area, point, spot, directional or environment emitter): it renders black",
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

/// Objects that only matter when referenced (a shape or emitter with an id
/// is placed whether referenced or not).
fn is_referable(e: &Element) -> bool {
    matches!(
        e.tag.as_str(),
        "bsdf" | "texture" | "spectrum" | "sampler" | "film" | "rfilter"
    ) || e.attr("type") == Some("shapegroup")
        || (e.tag == "emitter" && e.attr("type") == Some("area"))
}
