//! Wavefront OBJ + MTL loading with `tobj` (triangulated, single index).
//!
//! MTL mapping when the scene does not define a material itself: `Kd` is a
//! linear-sRGB reflectance upsampled by Jakob–Hanika (default 0.5 grey),
//! `Ke` a linear-sRGB radiance upsampled as an illuminant (times D65, the
//! convention of Mitsuba's and pbrt-v4's spectral modes); the face without a
//! material gets the default grey. Degenerate faces are skipped by the scene
//! builder and counted.

use crate::ids::MaterialId;
use crate::scene::{SceneBuilder, SceneError};
use crate::shading::material::Material;
use crate::spectra::SpectrumSource;
use glam::Vec3;
use std::collections::HashMap;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// Reflectance of faces without a material.
pub const DEFAULT_ALBEDO: f64 = 0.5;

/// Why an OBJ could not be loaded.
#[derive(Debug, Clone, PartialEq)]
pub enum ObjError {
    /// The OBJ file or its MTL could not be read or parsed.
    Load(PathBuf, String),
    /// A value in the file is invalid (NaN, negative colour, …).
    Invalid(PathBuf, String),
    /// The scene rejected something.
    Scene(SceneError),
}

impl core::fmt::Display for ObjError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Load(path, e) => write!(f, "{}: {e}", path.display()),
            Self::Invalid(path, e) => write!(f, "{}: {e}", path.display()),
            Self::Scene(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ObjError {}

/// What was loaded.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LoadedObj {
    /// Triangles read (before dropping degenerate ones).
    pub triangles: usize,
    /// Material of each MTL name.
    pub materials: HashMap<String, MaterialId>,
}

/// Where the OBJ comes from.
#[derive(Debug, Clone, Copy)]
pub enum ObjSource<'a> {
    /// A file; `mtllib` paths are relative to it.
    File(&'a Path),
    /// In-memory text (built-in scenes), with the text of its one MTL.
    Text {
        /// Name used in messages.
        name: &'a str,
        /// OBJ text.
        obj: &'a str,
        /// MTL text.
        mtl: &'a str,
    },
}

/// The `tobj` options of every OBJ load: triangulated, one index per
/// vertex, points and lines dropped.
pub fn load_options() -> tobj::LoadOptions {
    tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    }
}

/// `tobj::load_mtl_buf` on MTL text, after refusing the `Ka`, `Kd`, `Ks`
/// and `Ke` lines with fewer than three values: tobj 4.0.5 unwraps those
/// and panics (found by the `obj` fuzz target).
pub fn load_mtl_text(text: &str) -> tobj::MTLLoadResult {
    for line in text.lines() {
        let mut words = line.split_whitespace();
        if matches!(words.next(), Some("Ka" | "Kd" | "Ks" | "Ke")) && words.count() < 3 {
            return Err(tobj::LoadError::MaterialParseError);
        }
    }
    tobj::load_mtl_buf(&mut text.as_bytes())
}

/// `tobj::load_obj` of a file, with its `mtllib` files (relative to the
/// OBJ's directory) read through [`load_mtl_text`].
pub fn load_obj_file(path: &Path, options: &tobj::LoadOptions) -> tobj::LoadResult {
    let file = std::fs::File::open(path).map_err(|_| tobj::LoadError::OpenFileFailed)?;
    let directory = path.parent().unwrap_or(Path::new(""));
    tobj::load_obj_buf(&mut BufReader::new(file), options, |mtl_path| {
        let bytes =
            std::fs::read(directory.join(mtl_path)).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        let text = String::from_utf8(bytes).map_err(|_| tobj::LoadError::ReadError)?;
        load_mtl_text(&text)
    })
}

fn describe(e: &tobj::LoadError) -> String {
    format!("{e} (OBJ/MTL syntax)")
}

/// Loads an OBJ into `builder`. `material_override(name)` may supply the
/// material of an MTL name (scene-file definitions); otherwise the MTL's
/// `Kd`/`Ke` are used.
pub fn load_obj(
    builder: &mut SceneBuilder,
    source: ObjSource<'_>,
    material_override: &dyn Fn(&str) -> Option<MaterialId>,
) -> Result<LoadedObj, ObjError> {
    let (label, result) = match source {
        ObjSource::File(path) => (path.to_path_buf(), load_obj_file(path, &load_options())),
        ObjSource::Text { name, obj, mtl } => {
            let mut reader = BufReader::new(obj.as_bytes());
            let result = tobj::load_obj_buf(&mut reader, &load_options(), |_| load_mtl_text(mtl));
            (PathBuf::from(name), result)
        }
    };
    let (models, materials) = result.map_err(|e| ObjError::Load(label.clone(), describe(&e)))?;
    let materials = materials.map_err(|e| {
        ObjError::Load(label.clone(), format!("material library: {}", describe(&e)))
    })?;
    let mut loaded = LoadedObj::default();
    let mut ids: Vec<MaterialId> = Vec::with_capacity(materials.len());
    for m in &materials {
        let id = match material_override(&m.name) {
            Some(id) => id,
            None => mtl_material(builder, m)
                .map(|material| builder.add_material(material))
                .map_err(|e| match e {
                    ObjError::Invalid(_, message) => ObjError::Invalid(label.clone(), message),
                    other => other,
                })?,
        };
        loaded.materials.insert(m.name.clone(), id);
        ids.push(id);
    }
    let mut default_material = None;
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id.and_then(|i| ids.get(i).copied()) {
            Some(id) => id,
            None => match default_material {
                Some(id) => id,
                None => {
                    let id = add_default_material(builder).map_err(ObjError::Scene)?;
                    default_material = Some(id);
                    id
                }
            },
        };
        let positions: Vec<Vec3> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect();
        loaded.triangles += mesh.indices.len() / 3;
        builder
            .add_mesh(&positions, &mesh.indices, material)
            .map_err(ObjError::Scene)?;
    }
    Ok(loaded)
}

fn check_colour(name: &str, key: &str, rgb: [f32; 3]) -> Result<[f64; 3], ObjError> {
    if rgb.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(ObjError::Invalid(
            PathBuf::new(),
            format!("material `{name}`: {key} {rgb:?} must be finite and non-negative"),
        ));
    }
    Ok(rgb.map(f64::from))
}

/// Adds the material of faces without an MTL material (module docs).
pub fn add_default_material(builder: &mut SceneBuilder) -> Result<MaterialId, SceneError> {
    let albedo = builder.add_spectrum("default grey", SpectrumSource::Constant(DEFAULT_ALBEDO))?;
    Ok(builder.add_material(Material::lambert("default", albedo)))
}

/// The material an MTL entry describes (module docs), with its spectra
/// added to `builder`; the caller adds the material. An invalid colour is
/// [`ObjError::Invalid`] with an empty path (the caller names the file).
pub fn mtl_material(builder: &mut SceneBuilder, m: &tobj::Material) -> Result<Material, ObjError> {
    let kd = check_colour(
        &m.name,
        "Kd",
        m.diffuse.unwrap_or([DEFAULT_ALBEDO as f32; 3]),
    )?;
    let albedo = builder
        .add_spectrum(
            &format!("{} Kd", m.name),
            SpectrumSource::RgbReflectance(kd),
        )
        .map_err(ObjError::Scene)?;
    let mut material = Material::lambert(&m.name, albedo);
    if let Some(ke) = m.emissive {
        let ke = check_colour(&m.name, "Ke", ke)?;
        if ke.iter().any(|&v| v > 0.0) {
            let emission = builder
                .add_spectrum(&format!("{} Ke", m.name), SpectrumSource::RgbIlluminant(ke))
                .map_err(ObjError::Scene)?;
            material.emission = Some(emission);
        }
    }
    Ok(material)
}
