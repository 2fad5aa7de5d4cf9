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
use crate::scene_file::source::{Spot, read_bytes};
use glam::{Vec2, Vec3};
use simd_tracer::ids::MaterialId;
use simd_tracer::scene::instances::InstancePlacement;
use simd_tracer::scene::mesh::MeshData;
use simd_tracer::scene::obj::{
    ObjError, add_default_material, load_obj_file, load_options, mtl_material,
};
use simd_tracer::scene::obj_parallel::parallel_obj_meshes;
use simd_tracer::scene::ply::parse_ply;
use simd_tracer::scene::serialized::parse_serialized;
use simd_tracer::scene::transform::Transform;
use simd_tracer::scene::{MeshPlacement, SceneBuilder};
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
    /// Why the scene cannot render when no triangle was kept (`empty` says
    /// what to add, in the front end's words); `None` when some were.
    pub(crate) fn no_geometry(&self, empty: &str) -> Option<String> {
        if self.triangles > 0 {
            return None;
        }
        Some(if self.degenerate > 0 {
            format!(
                "the scene has no usable triangle ({} degenerate ones skipped)",
                self.degenerate
            )
        } else {
            empty.to_string()
        })
    }

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

/// How a mesh is placed: its transform and Mitsuba's `flip_normals` and
/// `face_normals`.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Placement {
    /// Object to world.
    pub(crate) transform: Transform,
    /// Turn the front face over.
    pub(crate) flip_normals: bool,
    /// Shade flat, ignoring vertex normals.
    pub(crate) face_normals: bool,
    /// The mesh is the unit sphere's tessellation
    /// ([`simd_tracer::scene::MeshPlacement::sphere`]).
    pub(crate) sphere: bool,
}

/// A mesh's parts, each with its material, as read from a file or made by
/// a shape, before placement (what an instance places again).
pub(crate) type MeshParts = Vec<(MeshData, MaterialId)>;

impl Mesher {
    /// Adds `parts` placed by `placement`; the degenerate triangles skipped.
    pub(crate) fn place(
        &mut self,
        builder: &mut SceneBuilder,
        parts: &[(MeshData, MaterialId)],
        placement: &Placement,
    ) -> Result<usize, String> {
        let mut degenerate = 0;
        for (mesh, material) in parts {
            let added = builder
                .add_mesh_data(
                    mesh,
                    &MeshPlacement {
                        transform: &placement.transform,
                        material: *material,
                        flip_normals: placement.flip_normals,
                        face_normals: placement.face_normals,
                        sphere: placement.sphere,
                    },
                )
                .map_err(|e| e.to_string())?;
            self.triangles += added.triangles;
            self.degenerate += added.degenerate;
            degenerate += added.degenerate;
            if self.emissive.contains(material) {
                self.emissive_triangles += added.triangles;
            }
            if added.triangles > 0 {
                let (lo, hi) = mesh.positions.iter().fold(
                    self.bounds.unwrap_or((Vec3::INFINITY, Vec3::NEG_INFINITY)),
                    |(lo, hi), &p| {
                        let w = placement.transform.point(p);
                        (lo.min(w), hi.max(w))
                    },
                );
                self.bounds = Some((lo, hi));
            }
        }
        Ok(degenerate)
    }
}

/// Largest mesh file read (PLY, serialized), bytes (4 GiB): a mesh of
/// tens of millions of triangles; anything larger is refused before it is
/// read.
pub(crate) const MAX_MESH_FILE_BYTES: u64 = 4 << 30;

/// Which format a mesh file is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MeshFormat {
    /// Wavefront OBJ, every object and group merged into one mesh, the MTL
    /// ignored (Mitsuba's `obj` shape).
    Obj,
    /// Stanford PLY.
    Ply,
    /// Mitsuba's `serialized`, one shape of the file.
    Serialized {
        /// The shape's index in the file.
        shape_index: u32,
    },
}

/// Reads a PLY or serialized mesh (errors: `path: message`).
pub(crate) fn load_mesh_file(path: &Path, format: MeshFormat) -> Result<MeshData, String> {
    let bytes = read_bytes(path, MAX_MESH_FILE_BYTES).map_err(|e| e.to_string())?;
    let mesh = match format {
        MeshFormat::Obj => return merged_obj_mesh(path, &bytes),
        MeshFormat::Ply => parse_ply(&bytes),
        MeshFormat::Serialized { shape_index } => parse_serialized(&bytes, shape_index),
    };
    mesh.map_err(|e| format!("{}: {e}", path.display()))
}

/// Every object of the OBJ file `path` (read as `bytes`) as one mesh (its MTL ignored);
/// triangles with non-finite values are dropped (errors: `path: message`).
fn merged_obj_mesh(path: &Path, bytes: &[u8]) -> Result<MeshData, String> {
    let shown = path.display();
    // The MTL is not read: Mitsuba ignores it. Text outside the parallel
    // reader's grammar, errors included, goes to tobj (same meshes).
    let meshes = match parallel_obj_meshes(bytes) {
        Some(meshes) => meshes,
        None => tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &load_options(), |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| format!("{shown}: {e} (OBJ syntax)"))?
        .0
        .into_iter()
        .map(|model| model.mesh)
        .collect(),
    };
    let mut merged = MeshData::default();
    for mesh in &meshes {
        let (data, _dropped) = obj_mesh(mesh).map_err(|e| format!("{shown}: {e}"))?;
        let base = u32::try_from(merged.positions.len())
            .map_err(|_| format!("{shown}: too many vertices"))?;
        let with_normals = !data.normals.is_empty();
        let with_uvs = !data.uvs.is_empty();
        // Keep per-vertex arrays aligned when models differ in what they carry.
        if with_normals && merged.normals.len() < merged.positions.len() {
            merged.normals.resize(merged.positions.len(), Vec3::ZERO);
        }
        if with_uvs && merged.uvs.len() < merged.positions.len() {
            merged.uvs.resize(merged.positions.len(), Vec2::ZERO);
        }
        merged.positions.extend_from_slice(&data.positions);
        if with_normals || !merged.normals.is_empty() {
            if with_normals {
                merged.normals.extend_from_slice(&data.normals);
            } else {
                merged.normals.resize(merged.positions.len(), Vec3::ZERO);
            }
        }
        if with_uvs || !merged.uvs.is_empty() {
            if with_uvs {
                merged.uvs.extend_from_slice(&data.uvs);
            } else {
                merged.uvs.resize(merged.positions.len(), Vec2::ZERO);
            }
        }
        merged
            .triangles
            .extend(data.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    merged.validate().map_err(|e| format!("{shown}: {e}"))?;
    Ok(merged)
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

/// One `tobj` model as a [`MeshData`]: its vertex normals (`vn`) and
/// texture coordinates (`vt`) where every vertex has one. Triangles with a
/// non-finite vertex or texture coordinate are dropped and counted (the
/// second value), as the builder drops degenerate ones; a non-finite normal
/// becomes zero (its triangles shade flat).
fn obj_mesh(mesh: &tobj::Mesh) -> Result<(MeshData, usize), String> {
    let vertices = mesh.positions.len() / 3;
    let triples = |values: &[f32]| -> Vec<Vec3> {
        values
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let mut normals = if mesh.normals.len() == 3 * vertices {
        triples(&mesh.normals)
    } else {
        Vec::new()
    };
    for n in &mut normals {
        if !n.is_finite() {
            *n = Vec3::ZERO;
        }
    }
    let mut uvs: Vec<Vec2> = if mesh.texcoords.len() == 2 * vertices {
        mesh.texcoords
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], c[1]))
            .collect()
    } else {
        Vec::new()
    };
    let mut positions = triples(&mesh.positions);
    let finite = |i: u32| {
        positions.get(i as usize).is_none_or(|p| p.is_finite())
            && uvs.get(i as usize).is_none_or(|t| t.is_finite())
    };
    let all: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let triangles: Vec<[u32; 3]> = all
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&i| finite(i)))
        .collect();
    let dropped = all.len() - triangles.len();
    // The dropped triangles' non-finite values are unreferenced now.
    for p in &mut positions {
        if !p.is_finite() {
            *p = Vec3::ZERO;
        }
    }
    for t in &mut uvs {
        if !t.is_finite() {
            *t = Vec2::ZERO;
        }
    }
    let data = MeshData {
        positions,
        normals,
        uvs,
        triangles,
    };
    data.validate().map_err(|e| {
        if e.contains("refers to vertex") {
            // OBJ counts from 1.
            format!("face vertex index out of range ({e})")
        } else {
            e
        }
    })?;
    Ok((data, dropped))
}

/// Loads the triangles of an OBJ file, placed by `placement` (errors:
/// `path: message`).
pub(crate) fn load_obj_geometry(
    builder: &mut SceneBuilder,
    mesher: &mut Mesher,
    path: &Path,
    faces: &FaceMaterials,
    placement: &Placement,
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
    let mut parts = Vec::with_capacity(models.len());
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
        let (data, dropped) = obj_mesh(mesh).map_err(|e| format!("{shown}: {e}"))?;
        mesher.degenerate += dropped;
        builder.count_skipped(dropped);
        parts.push((data, material));
    }
    mesher.place(builder, &parts, placement)?;
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
        placement: &Placement,
    ) -> Result<ObjInfo, CliError> {
        let info = load_obj_geometry(&mut self.builder, &mut self.mesher, path, faces, placement)
            .map_err(|e| self.src.error_at(at, e))?;
        self.warn_degenerate(at, info.degenerate);
        Ok(info)
    }

    fn warn_degenerate(&mut self, at: &Spot, degenerate: usize) {
        if degenerate > 0 {
            self.warn(
                at,
                format!(
                    "{degenerate} degenerate triangle(s) (zero area or non-finite) are skipped"
                ),
            );
        }
    }

    /// Reads the mesh file `path` named at `at` (errors follow `at`'s key).
    pub(crate) fn read_mesh(
        &self,
        at: &Spot,
        path: &Path,
        format: MeshFormat,
    ) -> Result<MeshData, CliError> {
        load_mesh_file(path, format).map_err(|e| self.src.error_at(at, e))
    }

    /// Places `parts` (a mesh read from a file or a shape) and, if `name`
    /// is given, keeps them for instances.
    pub(crate) fn place(
        &mut self,
        at: &Spot,
        parts: MeshParts,
        placement: &Placement,
        name: Option<&str>,
    ) -> Result<(), CliError> {
        let degenerate = self
            .mesher
            .place(&mut self.builder, &parts, placement)
            .map_err(|e| self.src.error_at(at, e))?;
        self.warn_degenerate(at, degenerate);
        if let Some(name) = name {
            self.named_meshes.insert(name.to_string(), parts);
        }
        Ok(())
    }

    /// Keeps `parts` for instances without placing them (Mitsuba's
    /// `shapegroup`).
    pub(crate) fn keep_for_instances(&mut self, name: &str, parts: MeshParts) {
        self.named_meshes.insert(name.to_string(), parts);
    }

    /// Whether a mesh of this name is kept for instances.
    pub(crate) fn has_named_mesh(&self, name: &str) -> bool {
        self.named_meshes.contains_key(name)
    }

    /// Places the named mesh again as an instance (the builder keeps it an
    /// instance or flattens it when the scene is built; the copies and
    /// their triangles are counted in [`Construction::instances`]), every
    /// part in `material` if given. `false` if there is no mesh of that
    /// name.
    pub(crate) fn instance(
        &mut self,
        at: &Spot,
        name: &str,
        placement: &Placement,
        material: Option<MaterialId>,
    ) -> Result<bool, CliError> {
        let Some(parts) = self.named_meshes.get(name) else {
            return Ok(false);
        };
        let triangles: usize = parts.iter().map(|(mesh, _)| mesh.triangles.len()).sum();
        let emissive = parts
            .iter()
            .any(|(_, own)| self.mesher.emissive.contains(&material.unwrap_or(*own)));
        let id = match self.instanced_meshes.get(name) {
            Some(&id) => id,
            None => {
                let id = self
                    .builder
                    .add_instanced_mesh(parts.clone())
                    .map_err(|e| self.src.error_at(at, e.to_string()))?;
                self.instanced_meshes.insert(name.to_string(), id);
                id
            }
        };
        self.builder
            .add_instance(
                id,
                InstancePlacement {
                    transform: placement.transform,
                    material,
                    flip_normals: placement.flip_normals,
                    face_normals: placement.face_normals,
                },
            )
            .map_err(|e| self.src.error_at(at, e.to_string()))?;
        self.mesher.triangles += triangles;
        if emissive {
            self.mesher.emissive_triangles += triangles;
        }
        self.instances.copies += 1;
        self.instances.triangles += triangles as u64;
        Ok(true)
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
