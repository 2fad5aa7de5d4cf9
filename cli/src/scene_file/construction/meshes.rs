//! Geometry of a scene under construction: triangles, quads and OBJ files.
//!
//! [`Mesher`] adds triangles to the builder and counts what it keeps: the
//! degenerate ones the builder will skip, the emissive ones (for the "no
//! light" warning) and the bounds (to frame a bare OBJ). [`load_obj_geometry`]
//! reads an OBJ with its MTL; an MTL material that the scene does not map to
//! one of its own is converted by `simd_tracer::scene::obj::mtl_material`, the one
//! MTL conversion of the project, so a bare OBJ, an OBJ in a scene file and
//! the built-in scenes shade alike. It takes no [`Spot`]: its errors are
//! `path: message`, which the bare-OBJ entry point reports as they are and
//! [`Construction::load_obj`] places after the key that named the file.

use super::Construction;
use crate::error::CliError;
use crate::scene_file::source::Spot;
use glam::{Vec2, Vec3};
use simd_tracer::ids::MaterialId;
use simd_tracer::scene::SceneBuilder;
use simd_tracer::scene::obj::{
    ObjError, add_default_material, load_obj_file, load_options, mtl_material,
};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// Triangles added so far, with the builder's own degeneracy test.
#[derive(Debug, Default)]
pub(crate) struct Mesher {
    /// Triangles kept.
    pub(crate) triangles: usize,
    /// Triangles the builder skips (zero area or non-finite).
    pub(crate) degenerate: usize,
    /// Kept triangles whose material emits.
    pub(crate) emissive_triangles: usize,
    /// Materials that emit.
    pub(crate) emissive: HashSet<MaterialId>,
    /// Bounding box of the kept triangles.
    pub(crate) bounds: Option<(Vec3, Vec3)>,
}

impl Mesher {
    /// Adds a triangle; `false` if the builder will skip it as degenerate.
    pub(crate) fn triangle(
        &mut self,
        builder: &mut SceneBuilder,
        vertices: [Vec3; 3],
        uvs: [Vec2; 3],
        material: MaterialId,
    ) -> bool {
        builder.add_triangle_uv(vertices, uvs, material);
        let [a, b, c] = vertices;
        let area2 = (b - a).cross(c - a).length_squared();
        let finite = vertices.iter().all(|v| v.is_finite()) && uvs.iter().all(|t| t.is_finite());
        if !(finite && area2.is_finite() && area2 > 0.0) {
            self.degenerate += 1;
            return false;
        }
        self.triangles += 1;
        if self.emissive.contains(&material) {
            self.emissive_triangles += 1;
        }
        let (lo, hi) = vertices.iter().fold(
            self.bounds.unwrap_or((Vec3::INFINITY, Vec3::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        self.bounds = Some((lo, hi));
        true
    }
}

/// Which material the faces of an OBJ get.
pub(crate) enum FaceMaterials {
    /// One material for every face.
    All(MaterialId),
    /// MTL names mapped to scene materials; others from `Kd`/`Ke`.
    Mapped(HashMap<String, MaterialId>),
}

/// What an OBJ contributed.
pub(crate) struct ObjInfo {
    /// Its degenerate triangles (skipped).
    pub(crate) degenerate: usize,
    /// The material names its MTL defines.
    pub(crate) mtl_names: Vec<String>,
}

/// `path: message` of an MTL conversion error.
fn mtl_error(shown: &impl std::fmt::Display, error: ObjError) -> String {
    match error {
        ObjError::Invalid(_, message) => format!("{shown}: {message}"),
        other => format!("{shown}: {other}"),
    }
}

/// Loads the triangles of an OBJ file (errors: `path: message`).
pub(crate) fn load_obj_geometry(
    builder: &mut SceneBuilder,
    mesher: &mut Mesher,
    path: &Path,
    faces: &FaceMaterials,
) -> Result<ObjInfo, String> {
    let shown = path.display();
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => return Err(format!("{shown}: is a directory")),
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(format!("{shown}: no such file"));
        }
        Err(e) => return Err(format!("{shown}: cannot read: {e}")),
    }
    let (models, materials) = load_obj_file(path, &load_options())
        .map_err(|e| format!("{shown}: {e} (OBJ/MTL syntax)"))?;
    let materials = materials.map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => {
            format!("{shown}: its material library (mtllib) cannot be opened")
        }
        e => format!("{shown}: material library: {e} (OBJ/MTL syntax)"),
    })?;
    let mut ids: Vec<MaterialId> = Vec::with_capacity(materials.len());
    if let FaceMaterials::Mapped(map) = faces {
        for m in &materials {
            let id = match map.get(&m.name) {
                Some(&id) => id,
                None => {
                    let material = mtl_material(builder, m).map_err(|e| mtl_error(&shown, e))?;
                    let emits = material.emission.is_some();
                    let id = builder.add_material(material);
                    if emits {
                        mesher.emissive.insert(id);
                    }
                    id
                }
            };
            ids.push(id);
        }
    }
    let mut default_material = None;
    let before = mesher.degenerate;
    for model in &models {
        let mesh = &model.mesh;
        let material = match faces {
            FaceMaterials::All(id) => *id,
            FaceMaterials::Mapped(_) => match mesh.material_id.and_then(|i| ids.get(i).copied()) {
                Some(id) => id,
                None => match default_material {
                    Some(id) => id,
                    None => {
                        let id =
                            add_default_material(builder).map_err(|e| format!("{shown}: {e}"))?;
                        default_material = Some(id);
                        id
                    }
                },
            },
        };
        let position = |index: u32| -> Option<Vec3> {
            let i = index as usize * 3;
            Some(Vec3::new(
                *mesh.positions.get(i)?,
                *mesh.positions.get(i + 1)?,
                *mesh.positions.get(i + 2)?,
            ))
        };
        let uv = |index: u32| -> Vec2 {
            let i = index as usize * 2;
            match (mesh.texcoords.get(i), mesh.texcoords.get(i + 1)) {
                (Some(&u), Some(&v)) => Vec2::new(u, v),
                _ => Vec2::ZERO,
            }
        };
        for face in mesh.indices.chunks_exact(3) {
            let mut vertices = [Vec3::ZERO; 3];
            let mut uvs = [Vec2::ZERO; 3];
            for (k, &index) in face.iter().enumerate() {
                vertices[k] = position(index).ok_or_else(|| {
                    format!("{shown}: face vertex index {} out of range", index + 1)
                })?;
                uvs[k] = uv(index);
            }
            mesher.triangle(builder, vertices, uvs, material);
        }
    }
    Ok(ObjInfo {
        degenerate: mesher.degenerate - before,
        mtl_names: materials.iter().map(|m| m.name.clone()).collect(),
    })
}

impl Construction<'_> {
    /// Loads the OBJ file `path`, named at `at`; its errors and its
    /// degenerate-triangle warning follow `at`'s key.
    pub(crate) fn load_obj(
        &mut self,
        at: &Spot,
        path: &Path,
        faces: &FaceMaterials,
    ) -> Result<ObjInfo, CliError> {
        let info = load_obj_geometry(&mut self.builder, &mut self.mesher, path, faces)
            .map_err(|e| self.src.error_at(at, e))?;
        if info.degenerate > 0 {
            self.warn(
                at,
                format!(
                    "{} degenerate triangle(s) (zero area or non-finite) are skipped",
                    info.degenerate
                ),
            );
        }
        Ok(info)
    }

    /// Adds the quad `v` (counter-clockwise seen from the front) as two
    /// triangles with texture coordinates (0, 0), (1, 0), (1, 1), (0, 1);
    /// degenerate halves are warned about at `at`.
    pub(crate) fn quad(&mut self, at: &Spot, v: [Vec3; 4], material: MaterialId) {
        let uv = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        let before = self.mesher.degenerate;
        self.mesher.triangle(
            &mut self.builder,
            [v[0], v[1], v[2]],
            [uv[0], uv[1], uv[2]],
            material,
        );
        self.mesher.triangle(
            &mut self.builder,
            [v[0], v[2], v[3]],
            [uv[0], uv[2], uv[3]],
            material,
        );
        let skipped = self.mesher.degenerate - before;
        if skipped > 0 {
            self.warn(
                at,
                format!(
                    "{skipped} of the quad's 2 triangles are degenerate (zero area) and skipped"
                ),
            );
        }
    }
}
