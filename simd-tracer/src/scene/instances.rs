//! Instanced meshes: one copy of a mesh's triangles and shading data in
//! its own (object) coordinates, shared by every instance that places it,
//! and a small record per instance.
//!
//! A hit on an instance carries the instance's index beside the triangle's
//! index in its mesh ([`crate::packet::PacketHit::instance`]); shading reads
//! the mesh's data and maps it into the world:
//!
//! * geometric normal `n = normalize(s · M⁻ᵀ ((b − a) × (c − a)))`, with `M`
//!   the linear part of the object-to-world map and `s = −1` for
//!   `flip_normals`, else `1`. A mirroring map (`det M < 0`) needs no
//!   winding swap here: the inverse transpose keeps a normal on the side it
//!   pointed to, where the cross product of mapped edges would turn over
//!   (why [`crate::scene::SceneBuilder::add_mesh_data`] swaps two vertices
//!   when it copies a mirrored mesh);
//! * shading normal `normalize(s · M⁻ᵀ (b₀ n₀ + b₁ n₁ + b₂ n₂))`: the
//!   mesh's unit vertex normals interpolated in object space at the hit's
//!   barycentrics, then mapped once (none with `face_normals`). Mitsuba's
//!   `instance` does the same: it maps the shape group's normalized
//!   shading normal, the same direction. One map and one normalization a
//!   hit instead of one a vertex; for maps that are not a rotation times
//!   a uniform scale it is not the interpolation of the mapped vertex
//!   normals, and Mitsuba's is the one matched;
//! * area `½ |det M| · |M⁻ᵀ ((b − a) × (c − a))|` (the area of a surface
//!   element grows by `|det M| · |M⁻ᵀ n̂|`);
//! * material: the instance's own if it has one, else the mesh's per
//!   triangle.
//!
//! # When a mesh is instanced, and when copied
//!
//! [`crate::scene::SceneBuilder::add_instance`] records a placement; at
//! build time an instance is kept as an instance when its mesh is placed by
//! at least [`MIN_INSTANCE_USES`] instances that qualify, and copied into
//! the scene's own triangles (flattened) otherwise. An instance qualifies
//! unless one of its materials emits: light sampling picks emitting
//! triangles by power from a list of world-space triangles, which an
//! instance does not have. A mesh placed once gains nothing from a shared
//! copy (it is stored once either way) and would pay a change of
//! coordinates per ray and a second tree level, so it is flattened.
//! [`Instancing::Flatten`] flattens everything (the flattened twin the
//! tests compare with).

use crate::accel::InstanceBvh;
use crate::ids::MaterialId;
use crate::shading::material::Material;
use crate::shading::surface::Surface;
use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::SceneBuilder;
use super::attributes::{SparseAttribute, VertexNormals};
use super::mesh::MeshData;
use super::transform::Transform;

/// A mesh is instanced when at least this many qualifying instances place
/// it (module docs: a single placement is flattened).
pub const MIN_INSTANCE_USES: usize = 2;

/// What [`crate::scene::SceneBuilder::build`] does with instances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Instancing {
    /// Instances of meshes placed [`MIN_INSTANCE_USES`] times or more stay
    /// instances; the rest are flattened (module docs).
    #[default]
    Auto,
    /// Every instance is copied into the scene's own triangles.
    Flatten,
}

/// Index of a mesh kept for instances
/// ([`crate::scene::SceneBuilder::add_instanced_mesh`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InstancedMeshId(pub u32);

/// How an instance places its mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstancePlacement {
    /// Object to world.
    pub transform: Transform,
    /// One material for every triangle (else each part's own).
    pub material: Option<MaterialId>,
    /// Turn the front face over (Mitsuba's `flip_normals`).
    pub flip_normals: bool,
    /// Ignore the vertex normals (Mitsuba's `face_normals`).
    pub face_normals: bool,
}

/// An instance recorded by the builder, resolved at build time.
#[derive(Debug, Clone, Copy)]
pub(super) struct InstanceRequest {
    pub(super) mesh: InstancedMeshId,
    pub(super) placement: InstancePlacement,
}

/// One distinct mesh in object coordinates: its non-degenerate triangles
/// (the scene builder's rules, [`SceneBuilder::add_mesh_data`] with the
/// identity), their materials, texture coordinates and unit vertex normals,
/// laid out as the scene's own triangles are.
#[derive(Debug, Clone, PartialEq)]
pub struct InstancedMesh {
    triangles: Vec<[Vec3; 3]>,
    triangle_material: Vec<MaterialId>,
    /// Those of the triangles with non-zero ones.
    uvs: SparseAttribute<[Vec2; 3]>,
    /// Those of the smooth triangles.
    vertex_normals: VertexNormals,
}

impl InstancedMesh {
    /// The mesh of `parts` in object coordinates (each part in its material),
    /// and the number of triangles skipped as degenerate.
    pub(super) fn new(
        builder_range: spectral_core::SpectralRange,
        parts: &[(MeshData, MaterialId)],
    ) -> Result<(Self, usize), super::SceneError> {
        let mut object = SceneBuilder::new(builder_range);
        for (mesh, material) in parts {
            object.add_mesh_data(
                mesh,
                &super::MeshPlacement {
                    transform: &Transform::IDENTITY,
                    material: *material,
                    flip_normals: false,
                    face_normals: false,
                    sphere: false,
                },
            )?;
        }
        let mut mesh = Self {
            triangles: object.triangles,
            triangle_material: object.triangle_material,
            uvs: object.uvs,
            vertex_normals: object.vertex_normals,
        };
        let n = mesh.triangles.len();
        mesh.triangles.shrink_to_fit();
        mesh.triangle_material.shrink_to_fit();
        mesh.uvs.finish(n);
        mesh.vertex_normals.finish(n);
        Ok((mesh, object.skipped))
    }

    /// The triangles, in object coordinates.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// Each triangle's material, in the order of [`Self::triangles`].
    pub fn materials(&self) -> &[MaterialId] {
        &self.triangle_material
    }

    /// Bytes held (vector capacities).
    fn memory_bytes(&self) -> usize {
        fn vec_bytes<T>(v: &Vec<T>) -> usize {
            v.capacity() * size_of::<T>()
        }
        vec_bytes(&self.triangles)
            + vec_bytes(&self.triangle_material)
            + self.uvs.memory_bytes()
            + self.vertex_normals.memory_bytes()
    }
}

/// What shading needs of one instance.
#[derive(Debug, Clone, Copy, PartialEq)]
struct InstanceShading {
    /// Index of its mesh.
    mesh: u32,
    /// `s · M⁻ᵀ` (module docs).
    normal_matrix: Mat3,
    /// `|det M|`.
    det_abs: f32,
    /// Its own material, or [`MaterialId::NONE`] for the mesh's.
    material: MaterialId,
    /// Whether it ignores the vertex normals.
    face_normals: bool,
}

impl InstanceShading {
    fn new(mesh: u32, placement: &InstancePlacement) -> Self {
        let to_world = placement.transform.affine();
        let m = Mat3::from(to_world.matrix3);
        let sign = if placement.flip_normals { -1.0 } else { 1.0 };
        Self {
            mesh,
            normal_matrix: m.inverse().transpose() * sign,
            det_abs: m.determinant().abs(),
            material: placement.material.unwrap_or(MaterialId::NONE),
            face_normals: placement.face_normals,
        }
    }
}

/// An instanced triangle's vertices and material as
/// [`Instances::fetch`] read them; [`FetchedTriangle::surface`] makes its
/// shading record. Two steps so that a packet reads all its lanes'
/// triangles before it computes with any (`Scene::hit_surfaces`).
#[derive(Debug, Clone, Copy)]
pub(super) struct FetchedTriangle<'a> {
    shading: &'a InstanceShading,
    vertices: [Vec3; 3],
    material: MaterialId,
}

impl FetchedTriangle<'_> {
    /// [`Instances::surface`] of the fetched triangle.
    pub(super) fn surface(&self, materials: &[Material]) -> Option<Surface> {
        let [a, b, c] = self.vertices;
        let mapped = self.shading.normal_matrix * (b - a).cross(c - a);
        let normal = mapped.try_normalize()?;
        let area = 0.5 * self.shading.det_abs * mapped.length();
        Some(Surface::new(
            normal,
            area,
            self.material,
            materials.get(self.material.index())?,
        ))
    }
}

/// Where a smooth triangle's vertex normals are: its table, its entries
/// in it, and for an instance the map of their interpolation into the
/// world (`Scene::hit_smooth_normals`).
#[derive(Debug, Clone, Copy)]
pub(super) struct SmoothCorners<'a> {
    pub(super) table: &'a VertexNormals,
    pub(super) entries: [u32; 3],
    /// `s · M⁻ᵀ` of an instance; `None` for the scene's own triangles,
    /// whose normals are in the world already.
    pub(super) normal_matrix: Option<Mat3>,
}

/// The instances of a scene: the distinct meshes, a record per instance
/// and the two-level tree ([`InstanceBvh`]).
#[derive(Debug, Clone)]
pub struct Instances {
    meshes: Vec<InstancedMesh>,
    shading: Vec<InstanceShading>,
    /// The placements (for validation and the scene's fingerprint).
    placements: Vec<InstancePlacement>,
    bvh: InstanceBvh,
}

impl Instances {
    /// Builds the meshes' trees and the top level.
    pub(super) fn new(
        meshes: Vec<InstancedMesh>,
        instances: Vec<(u32, InstancePlacement)>,
    ) -> Result<Self, String> {
        let trees = meshes
            .iter()
            .map(|m| crate::accel::Bvh::build(&m.triangles))
            .collect();
        let lists: Vec<&[[Vec3; 3]]> = meshes.iter().map(|m| m.triangles.as_slice()).collect();
        let inputs: Vec<crate::accel::InstanceInput> = instances
            .iter()
            .map(|(mesh, p)| crate::accel::InstanceInput {
                mesh: *mesh,
                object_to_world: p.transform.affine(),
            })
            .collect();
        let bvh = InstanceBvh::build(trees, &lists, &inputs)?;
        Ok(Self {
            shading: instances
                .iter()
                .map(|(mesh, p)| InstanceShading::new(*mesh, p))
                .collect(),
            placements: instances.into_iter().map(|(_, p)| p).collect(),
            meshes,
            bvh,
        })
    }

    /// The two-level tree.
    pub fn bvh(&self) -> &InstanceBvh {
        &self.bvh
    }

    /// The distinct meshes.
    pub fn meshes(&self) -> &[InstancedMesh] {
        &self.meshes
    }

    /// Number of instances.
    pub fn len(&self) -> usize {
        self.shading.len()
    }

    /// Whether there is no instance.
    pub fn is_empty(&self) -> bool {
        self.shading.is_empty()
    }

    /// Triangles placed by all instances together (what flattening them
    /// would have copied).
    pub fn instanced_triangles(&self) -> usize {
        self.shading
            .iter()
            .filter_map(|s| self.meshes.get(s.mesh as usize))
            .map(|m| m.triangles.len())
            .sum()
    }

    /// The placement of instance `instance`.
    pub fn placement(&self, instance: u32) -> Option<&InstancePlacement> {
        self.placements.get(instance as usize)
    }

    /// The mesh index of each instance, in order.
    pub fn instance_meshes(&self) -> impl Iterator<Item = u32> + '_ {
        self.shading.iter().map(|s| s.mesh)
    }

    fn at(
        &self,
        triangle: u32,
        instance: u32,
    ) -> Option<(&InstanceShading, &InstancedMesh, usize)> {
        let shading = self.shading.get(instance as usize)?;
        let mesh = self.meshes.get(shading.mesh as usize)?;
        let index = triangle as usize;
        (index < mesh.triangles.len()).then_some((shading, mesh, index))
    }

    /// The material of `triangle` (in its mesh) as instance `instance`
    /// shows it.
    pub fn material(&self, triangle: u32, instance: u32) -> Option<MaterialId> {
        let (shading, mesh, index) = self.at(triangle, instance)?;
        if shading.material.is_none() {
            mesh.triangle_material.get(index).copied()
        } else {
            Some(shading.material)
        }
    }

    /// The texture coordinates of `triangle`'s vertices (`None` when the
    /// mesh stores none: all zero).
    pub fn uvs(&self, triangle: u32, instance: u32) -> Option<[Vec2; 3]> {
        let (_, mesh, index) = self.at(triangle, instance)?;
        mesh.uvs.get(index).copied()
    }

    /// The world-space `[∂p/∂u, ∂p/∂v]` of `triangle` in instance
    /// `instance` (`super::tangent`): the object-space ones mapped as
    /// vectors.
    pub fn tangents(&self, triangle: u32, instance: u32) -> Option<[Vec3; 2]> {
        let (_, mesh, index) = self.at(triangle, instance)?;
        let vertices = mesh.triangles.get(index)?;
        let object = super::tangent::surface_derivatives(vertices, mesh.uvs.get(index));
        let to_world = self.placements.get(instance as usize)?.transform.affine();
        Some(object.map(|d| to_world.transform_vector3(d)))
    }

    /// The world-space unit geometric normal of `triangle` in instance
    /// `instance` (module docs).
    pub fn normal(&self, triangle: u32, instance: u32) -> Option<Vec3> {
        let (shading, mesh, index) = self.at(triangle, instance)?;
        let [a, b, c] = mesh.triangles.get(index)?;
        (shading.normal_matrix * (*b - *a).cross(*c - *a)).try_normalize()
    }

    /// Where the vertex normals of a smooth `triangle` in instance
    /// `instance` are (`None` for flat ones and with `face_normals`): the
    /// mesh's table, the triangle's entries in it, and the map `s · M⁻ᵀ`
    /// that takes their interpolation into the world (module docs).
    pub(super) fn smooth_corners(&self, triangle: u32, instance: u32) -> Option<SmoothCorners<'_>> {
        let (shading, mesh, index) = self.at(triangle, instance)?;
        if shading.face_normals {
            return None;
        }
        Some(SmoothCorners {
            table: &mesh.vertex_normals,
            entries: mesh.vertex_normals.corners(index)?,
            normal_matrix: Some(shading.normal_matrix),
        })
    }

    /// Whether any instance can shade with vertex normals.
    pub fn has_vertex_normals(&self) -> bool {
        self.shading.iter().any(|s| {
            !s.face_normals
                && self
                    .meshes
                    .get(s.mesh as usize)
                    .is_some_and(|m| !m.vertex_normals.is_empty())
        })
    }

    /// The shading record of `triangle` in instance `instance`: world
    /// normal and area, the material's emission, sides and Lambert albedo
    /// ([`Surface::new`]); instances never emit, so its light-selection
    /// probability is 0.
    pub fn surface(&self, triangle: u32, instance: u32, materials: &[Material]) -> Option<Surface> {
        self.fetch(triangle, instance)?.surface(materials)
    }

    /// What [`Instances::surface`] reads of `triangle` in instance
    /// `instance`, read from memory and not yet used.
    pub(super) fn fetch(&self, triangle: u32, instance: u32) -> Option<FetchedTriangle<'_>> {
        let (shading, mesh, index) = self.at(triangle, instance)?;
        let material = if shading.material.is_none() {
            *mesh.triangle_material.get(index)?
        } else {
            shading.material
        };
        Some(FetchedTriangle {
            shading,
            vertices: *mesh.triangles.get(index)?,
            material,
        })
    }

    /// Bytes held: each distinct mesh once (triangles, shading data, tree)
    /// and per instance its records and the top-level tree's share.
    pub fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self
                .meshes
                .iter()
                .map(InstancedMesh::memory_bytes)
                .sum::<usize>()
            + self.shading.capacity() * size_of::<InstanceShading>()
            + self.placements.capacity() * size_of::<InstancePlacement>()
            + self.bvh.memory_bytes()
    }

    /// Checks the meshes' layout (one material per triangle, the sparse
    /// texture coordinates and vertex normals as
    /// `SparseAttribute::validate`), that every material exists and none emits, that
    /// each instance's record is the one its placement makes and names the
    /// mesh and map of its tree entry, and the
    /// two-level tree ([`InstanceBvh::validate`]).
    pub fn validate(&self, materials: &[Material]) -> Result<(), String> {
        for (k, mesh) in self.meshes.iter().enumerate() {
            let n = mesh.triangles.len();
            if mesh.triangle_material.len() != n {
                return Err(format!(
                    "instanced mesh {k}: per-triangle lists of different lengths"
                ));
            }
            mesh.uvs
                .validate(n)
                .map_err(|e| format!("instanced mesh {k}: texture coordinates: {e}"))?;
            mesh.vertex_normals
                .validate(n)
                .map_err(|e| format!("instanced mesh {k}: vertex normals: {e}"))?;
        }
        if self.placements.len() != self.shading.len() || self.bvh.len() != self.shading.len() {
            return Err("instance records of different counts".to_owned());
        }
        for (k, (shading, placement)) in self.shading.iter().zip(&self.placements).enumerate() {
            if *shading != InstanceShading::new(shading.mesh, placement) {
                return Err(format!("instance {k}: its shading record is stale"));
            }
            if self.bvh.mesh_of(k as u32) != Some(shading.mesh)
                || self.bvh.object_to_world(k as u32) != Some(placement.transform.affine())
            {
                return Err(format!(
                    "instance {k}: its tree and its records name different meshes or places"
                ));
            }
            let mesh = self
                .meshes
                .get(shading.mesh as usize)
                .ok_or_else(|| format!("instance {k} refers to a missing mesh"))?;
            let ids = mesh.triangle_material.iter().map(|&id| {
                if shading.material.is_none() {
                    id
                } else {
                    shading.material
                }
            });
            for id in ids {
                match materials.get(id.index()) {
                    None => return Err(format!("instance {k}: material {id} does not exist")),
                    Some(m) if m.emission.is_some() => {
                        return Err(format!("instance {k}: an emitting material"));
                    }
                    Some(_) => {}
                }
            }
        }
        let lists: Vec<&[[Vec3; 3]]> = self.meshes.iter().map(|m| m.triangles.as_slice()).collect();
        self.bvh.validate(&lists)
    }

    /// The object-to-world maps (the scene's fingerprint hashes them).
    pub fn transforms(&self) -> impl Iterator<Item = Affine3A> + '_ {
        self.placements.iter().map(|p| p.transform.affine())
    }
}

impl InstancedMesh {
    /// Every per-triangle value as 32-bit words, for the fingerprint: the
    /// same words as when texture coordinates were stored for every
    /// triangle once any had some (zeros for the others), so digests of
    /// earlier partial files stay valid.
    pub(crate) fn words(&self) -> impl Iterator<Item = u32> + '_ {
        let dense_uvs = (0..self.triangles.len())
            .filter(|_| !self.uvs.is_empty())
            .map(|t| self.uvs.get(t).copied().unwrap_or([Vec2::ZERO; 3]));
        let floats = self
            .triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_array())
            .chain(dense_uvs.flatten().flat_map(|v| v.to_array()))
            .chain(
                (0..self.triangles.len())
                    .filter_map(|t| self.vertex_normals.get(t))
                    .flatten()
                    .flat_map(|v| v.to_array()),
            )
            .map(f32::to_bits);
        floats
            .chain(self.triangle_material.iter().map(|m| m.0))
            .chain(self.vertex_normals.index_entries())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::analytic::cube_mesh;
    use crate::scene::camera::Camera;
    use crate::spectra::SpectrumSource;
    use spectral_core::SpectralRange;

    #[test]
    fn stale_instance_records_fail_validation() -> Result<(), Box<dyn std::error::Error>> {
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
        let m = b.add_material(Material::lambert("grey", grey));
        let mesh = b.add_instanced_mesh(vec![(cube_mesh(), m)])?;
        for x in [-2.0, 2.0] {
            b.add_instance(
                mesh,
                InstancePlacement {
                    transform: Transform::translate(Vec3::X * x)?,
                    material: None,
                    flip_normals: false,
                    face_normals: false,
                },
            )?;
        }
        b.set_camera(Camera::look_at(Vec3::Z * 9.0, Vec3::ZERO, Vec3::Y, 40.0)?);
        let scene = b.build()?;
        scene.validate_surfaces()?;
        let instances = scene.instances.as_ref().ok_or("instances")?;
        let materials = scene.materials();
        instances.validate(materials)?;

        let mut broken = instances.clone();
        broken.shading[1].det_abs *= 2.0;
        assert!(broken.validate(materials).is_err());
        let mut broken = instances.clone();
        broken.placements.swap(0, 1);
        assert!(broken.validate(materials).is_err());
        let mut broken = instances.clone();
        broken.meshes[0].triangle_material.pop();
        assert!(broken.validate(materials).is_err());
        let mut broken = instances.clone();
        broken.shading[0].material = MaterialId(7);
        assert!(broken.validate(materials).is_err());
        broken.placements[0].material = Some(MaterialId(7));
        assert!(
            broken.validate(materials).is_err(),
            "a material that does not exist"
        );
        let mut broken = instances.clone();
        broken.shading.pop();
        assert!(broken.validate(materials).is_err());
        Ok(())
    }
}
