//! Scenes: triangles with materials, spectra, emitters, a camera, and the
//! acceleration structure, assembled by a [`SceneBuilder`].
//!
//! Emitters are triangles whose material has an emission spectrum; they emit
//! from their front face (counter-clockwise seen from the front) unless the
//! material is two-sided. Degenerate triangles (zero area, non-finite) are
//! dropped at build time and counted in [`Scene::skipped_triangles`].

pub mod analytic;
mod attributes;
pub mod builtin;
pub mod camera;
mod fingerprint;
pub mod instances;
pub mod mesh;
pub mod obj;
pub mod obj_parallel;
pub mod ply;
mod relight;
pub mod serialized;
pub mod shapes;
pub mod tangent;
pub mod transform;
mod triangle_store;

use crate::accel::{Bvh, Hit, InstanceBvh, InstanceHit, TriangleSubset, WideStack};
use crate::ids::NO_INSTANCE;
use crate::ids::{AngularId, FluorophoreId, MaterialId, NO_ID, SpectrumId, TextureId};
use crate::packet::{PacketHit, Ray, RayPacket};
use crate::scene::attributes::{SparseAttribute, VertexNormals};
use crate::scene::camera::Camera;
use crate::scene::instances::{
    FetchedTriangle, InstancePlacement, InstanceRequest, InstancedMesh, InstancedMeshId, Instances,
    Instancing, MIN_INSTANCE_USES, SmoothCorners,
};
use crate::scene::mesh::MeshData;
use crate::scene::transform::{SIMILARITY_TOLERANCE, Transform};
use crate::scene::triangle_store::TriangleStore;
use crate::shading::light::{Light, LightSet};
use crate::shading::light_sampler::{DirectionalLight, LightSampler, PointLight, SceneLights};
use crate::shading::material::{
    Bsdf, Material, MaterialTables, Relief, SceneFluorophore, tabulated_sides,
};
use crate::shading::sphere_light::{SphereLight, sphere_holding};
use crate::shading::surface::SurfacePacket;
use crate::shading::surface::{PackedSurfaces, Surface, triangle_area};
use crate::simd::{LANES, LaneMask};
use crate::spectra::angular::{AngularFunction, AngularSpectrum};
use crate::spectra::environment::EnvironmentMap;
use crate::spectra::texture::{Texture, TextureData};
use crate::spectra::{SceneSpectrum, SpectrumRegisters, SpectrumSource};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use spectral_core::fluorescence::FluorescentLayer;
use spectral_core::{SpectralError, SpectralRange};
use std::borrow::Cow;

/// Why a scene could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum SceneError {
    /// A spectrum (named in the message) is invalid.
    Spectrum(String, SpectralError),
    /// A material (named) refers to something that does not exist.
    Reference(String, &'static str, u32),
    /// A triangle refers to a material that does not exist.
    UnknownMaterial(MaterialId),
    /// More materials than a shading record can name
    /// ([`crate::shading::surface::MAX_PACKED_MATERIALS`]).
    TooManyMaterials(usize),
    /// A mesh index refers to a vertex that does not exist.
    IndexOutOfRange {
        /// The index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// The scene has no (non-degenerate) triangle.
    Empty,
    /// No camera was set.
    NoCamera,
    /// The BVH failed validation.
    Bvh(String),
    /// A mesh is malformed (its [`MeshData::validate`] message).
    Mesh(String),
    /// A light is invalid.
    Light(String),
    /// A material (named) combines what cannot be combined (the message).
    Material(String, &'static str),
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Spectrum(name, e) => write!(f, "spectrum `{name}`: {e}"),
            Self::Reference(name, kind, id) => write!(
                f,
                "material `{name}` refers to {kind} {id}, which does not exist"
            ),
            Self::UnknownMaterial(id) => write!(f, "material {id} does not exist"),
            Self::TooManyMaterials(count) => write!(
                f,
                "{count} materials: a scene holds at most {}",
                crate::shading::surface::MAX_PACKED_MATERIALS
            ),
            Self::IndexOutOfRange { index, vertices } => {
                write!(f, "vertex index {index} out of range ({vertices} vertices)")
            }
            Self::Empty => write!(f, "the scene has no usable triangle"),
            Self::NoCamera => write!(f, "the scene has no camera"),
            Self::Bvh(message) => write!(f, "BVH: {message}"),
            Self::Mesh(message) => write!(f, "mesh: {message}"),
            Self::Light(message) => write!(f, "light: {message}"),
            Self::Material(name, message) => write!(f, "material `{name}`: {message}"),
        }
    }
}

impl std::error::Error for SceneError {}

/// A renderable scene.
#[derive(Debug)]
pub struct Scene {
    /// The spectral range of every spectrum and of the render.
    range: SpectralRange,
    /// Prepared spectra.
    spectra: Vec<SceneSpectrum>,
    /// Angle-dependent spectra (Fresnel, films) with their Fourier tables.
    angular: Vec<AngularSpectrum>,
    /// Textures.
    textures: Vec<Texture>,
    /// Materials.
    materials: Vec<Material>,
    /// Fluorophores of fluorescent materials.
    fluorophores: Vec<SceneFluorophore>,
    /// Whether a material evaluates with the bounce's lobe number (a blend,
    /// [`Bsdf::needs_lobe`]): only then does the integrator draw it before
    /// the light sample.
    needs_lobe: bool,
    /// Whether a material needs tangents: a normal map or an anisotropic
    /// lobe ([`Bsdf::needs_tangent`]).
    needs_tangent: bool,
    /// `[∂p/∂u, ∂p/∂v]` of the triangles whose material needs them
    /// ([`tangent`]); no others.
    tangents: SparseAttribute<[Vec3; 2]>,
    /// Triangle vertices (non-degenerate ones only), in a vector or in the
    /// BVH's 8-wide tree ([`triangle_store`]).
    triangles: TriangleStore,
    /// Texture coordinates of the triangles whose vertices have non-zero
    /// ones (the others' are zero).
    uvs: SparseAttribute<[Vec2; 3]>,
    /// Unit vertex normals of the smooth triangles, on the front side of
    /// their triangle (their mean points the way the winding does), each
    /// mesh vertex's once; the others are shaded flat.
    vertex_normals: VertexNormals,
    /// The camera.
    camera: Camera,
    /// Radiance arriving from every direction that escapes the scene.
    environment: Option<SpectrumId>,
    /// An environment map (instead of the constant environment).
    environment_map: Option<EnvironmentMap>,
    /// Which light NEE samples: triangles, point, directional, environment.
    light_sampler: LightSampler,
    /// The acceleration structure.
    bvh: Bvh,
    /// Emissive triangles and their sampling distribution.
    lights: LightSet,
    /// The emissive triangles in the BVH, for the last segment of a path
    /// (only an emitter hit counts there: [`crate::integrator`]).
    emitters: TriangleSubset,
    /// The first spectra's coefficients in registers (derived from
    /// [`Scene::spectra`]).
    spectrum_registers: SpectrumRegisters,
    /// One shading record per triangle (derived from the fields above),
    /// packed for packet gathers; the only copy of the records and of the
    /// geometric normals ([`Scene::surface`], [`Scene::normal`]).
    packed_surfaces: PackedSurfaces,
    /// Meshes placed by several instances, kept once
    /// ([`instances`]); `None` when every instance was flattened.
    instances: Option<Instances>,
    skipped_triangles: usize,
}

/// The triangles whose records emit, as a subset of `bvh`.
fn emitters(bvh: &Bvh, surfaces: &PackedSurfaces) -> TriangleSubset {
    let emissive: Vec<u32> = (0..surfaces.len())
        .filter(|&k| surfaces.emits(k))
        .filter_map(|k| u32::try_from(k).ok())
        .collect();
    bvh.subset(&emissive)
}

/// Scratch stacks of one ray's walks through the scene's 8-wide trees
/// ([`Scene::intersect_one`]): its own triangles', the instances' top
/// level's and a mesh's.
#[derive(Default)]
pub struct WideStacks {
    own: WideStack,
    top: WideStack,
    mesh: WideStack,
}

impl Scene {
    /// range
    pub fn range(&self) -> SpectralRange {
        self.range
    }

    /// spectra
    pub fn spectra(&self) -> &[SceneSpectrum] {
        &self.spectra
    }

    /// angular
    pub fn angular(&self) -> &[AngularSpectrum] {
        &self.angular
    }

    /// textures
    pub fn fluorophores(&self) -> &[SceneFluorophore] {
        &self.fluorophores
    }

    /// Whether a material's BSDF reads the bounce's lobe number when it is
    /// evaluated ([`Bsdf::needs_lobe`]).
    pub fn needs_lobe(&self) -> bool {
        self.needs_lobe
    }

    /// textures
    pub fn textures(&self) -> &[Texture] {
        &self.textures
    }

    /// materials
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The triangles' vertices in the order they were added: borrowed, or
    /// read back from the BVH in scenes whose 8-wide tree holds the only
    /// copy (a pass over the tree and a vector of 36 bytes a triangle;
    /// `scene/triangle_store.rs`).
    pub fn triangles(&self) -> Cow<'_, [[Vec3; 3]]> {
        self.triangles.all(&self.bvh)
    }

    /// Number of triangles (those of instanced meshes not included).
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The unit geometric normal of triangle `index` (right-handed, CCW
    /// front), from its shading record.
    #[inline]
    pub fn normal(&self, index: usize) -> Option<Vec3> {
        self.packed_surfaces.normal(index)
    }

    /// Every triangle's unit geometric normal, in order.
    pub fn normals(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.packed_surfaces.len()).filter_map(|index| self.normal(index))
    }

    /// The material of triangle `index` (kept in its shading record,
    /// [`PackedSurfaces::material`]).
    #[inline]
    pub fn material_of(&self, index: usize) -> Option<MaterialId> {
        self.packed_surfaces.material(index)
    }

    /// The texture coordinates of triangle `index`'s vertices; `None` when
    /// they are all zero.
    #[inline]
    pub fn uvs(&self, index: usize) -> Option<&[Vec2; 3]> {
        self.uvs.get(index)
    }

    /// Whether any triangle of the scene's own has non-zero texture
    /// coordinates.
    pub fn has_uvs(&self) -> bool {
        !self.uvs.is_empty()
    }

    /// The unit vertex normals of triangle `index`, if it is smooth shaded.
    #[inline]
    pub fn vertex_normals(&self, index: usize) -> Option<[Vec3; 3]> {
        self.vertex_normals.get(index)
    }

    /// Whether any triangle (of the scene's own or of an instance) has
    /// vertex normals.
    #[inline]
    pub fn has_vertex_normals(&self) -> bool {
        !self.vertex_normals.is_empty()
            || self
                .instances
                .as_ref()
                .is_some_and(Instances::has_vertex_normals)
    }

    /// camera
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Replaces the camera (a viewer moving it): nothing else depends on
    /// it, so the scene stays valid and the BVH is kept.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    /// environment
    pub fn environment(&self) -> Option<SpectrumId> {
        self.environment
    }

    /// The environment map, if any.
    #[inline]
    pub fn environment_map(&self) -> Option<&EnvironmentMap> {
        self.environment_map.as_ref()
    }

    /// Whether rays that escape see anything (a constant environment or a map).
    #[inline]
    pub fn has_environment(&self) -> bool {
        self.environment.is_some() || self.environment_map.is_some()
    }

    /// Every emission spectrum of the scene, once each, in index order:
    /// emissive materials', point and directional lights' and the constant
    /// environment's (an environment map's texels have their own spectra
    /// and are not listed).
    pub fn emission_spectra(&self) -> Vec<SpectrumId> {
        let mut ids: Vec<SpectrumId> = self
            .materials
            .iter()
            .filter_map(|material| material.emission)
            .chain(self.light_sampler.emission_spectra())
            .chain(self.environment)
            .filter(|id| !id.is_none())
            .collect();
        ids.sort_unstable_by_key(|id| id.0);
        ids.dedup();
        ids
    }

    /// The light selection of next-event estimation.
    #[inline]
    pub fn light_sampler(&self) -> &LightSampler {
        &self.light_sampler
    }

    /// The tree over the scene's own (flattened) triangles; instances have
    /// theirs in [`Scene::instances`]. Queries that must see everything go
    /// through [`Scene::intersect_packet`], [`Scene::intersect_incoherent`]
    /// and [`Scene::occluded_incoherent`].
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The meshes kept once for several instances, with the instances'
    /// records and tree (`None` when the scene has none).
    pub fn instances(&self) -> Option<&Instances> {
        self.instances.as_ref()
    }

    /// The box around all geometry, instances included (`None` when the
    /// scene has none).
    pub fn world_bounds(&self) -> Option<(Vec3, Vec3)> {
        world_bounds(&self.bvh, self.instances.as_ref())
    }

    /// Closest hits of a coherent packet (camera rays): the triangles'
    /// packet traversal, then the instances' ([`crate::accel::InstanceBvh`]),
    /// which keep a lane's hit unless theirs is nearer.
    pub fn intersect_packet(&self, packet: &RayPacket) -> PacketHit {
        let mut hit = self.bvh.intersect_packet(packet);
        if let Some(instances) = &self.instances {
            instances.bvh().intersect_packet(packet, &mut hit);
        }
        hit
    }

    /// Closest hits of incoherent rays (bounces): [`Bvh::intersect_incoherent`],
    /// then the instances one ray at a time.
    pub fn intersect_incoherent(&self, packet: &RayPacket) -> PacketHit {
        let mut hit = self.bvh.intersect_incoherent(packet);
        if let Some(instances) = &self.instances {
            instances.bvh().intersect_lanes(packet, &mut hit);
        }
        hit
    }

    /// Occlusion of incoherent rays (shadows): [`Bvh::occluded_incoherent`],
    /// then the instances for the lanes still unblocked.
    pub fn occluded_incoherent(&self, packet: &RayPacket) -> LaneMask {
        let blocked = self.bvh.occluded_incoherent(packet);
        match &self.instances {
            Some(instances) => {
                let open = RayPacket {
                    active: packet.active.and_not(blocked),
                    ..*packet
                };
                if open.active.is_empty() {
                    blocked
                } else {
                    blocked.or(instances.bvh().occluded_lanes(&open))
                }
            }
            None => blocked,
        }
    }

    /// The scalar oracle of [`Scene::intersect_packet`] and
    /// [`Scene::intersect_incoherent`]: obvhs' per-ray traversal and the
    /// scalar triangle test at every level. A hit on the scene's own
    /// triangles has instance [`NO_INSTANCE`].
    pub fn intersect(&self, ray: &Ray) -> Option<InstanceHit> {
        self.nearer_instance(ray, self.bvh.intersect(ray), |instances, ray| {
            instances.intersect(ray)
        })
    }

    /// The scene's own hit `own` of `ray` as an instance hit, or the
    /// instances' hit by `walk` where it is nearer.
    fn nearer_instance(
        &self,
        ray: &Ray,
        own: Option<Hit>,
        walk: impl FnOnce(&InstanceBvh, &Ray) -> Option<InstanceHit>,
    ) -> Option<InstanceHit> {
        let own = own.map(|h| InstanceHit {
            t: h.t,
            u: h.u,
            v: h.v,
            triangle: h.triangle,
            instance: NO_INSTANCE,
        });
        let Some(instances) = &self.instances else {
            return own;
        };
        let t_max = own.map_or(ray.t_max, |h| h.t);
        walk(instances.bvh(), &Ray { t_max, ..*ray }).or(own)
    }

    /// Closest hit of one incoherent ray by the 8-wide trees (the walk
    /// [`Scene::intersect_incoherent`] gives each lane, without a packet):
    /// what light paths trace. `stacks` is reusable scratch space.
    pub fn intersect_one(&self, ray: &Ray, stacks: &mut WideStacks) -> Option<InstanceHit> {
        let own = self.bvh.intersect_wide(ray, &mut stacks.own);
        self.nearer_instance(ray, own, |instances, ray| {
            instances.intersect_wide(ray, &mut stacks.top, &mut stacks.mesh)
        })
    }

    /// Occlusion of one incoherent ray by the 8-wide trees.
    pub fn occluded_one(&self, ray: &Ray, stacks: &mut WideStacks) -> bool {
        self.bvh.occluded_wide(ray, &mut stacks.own)
            || self.instances.as_ref().is_some_and(|i| {
                i.bvh()
                    .occluded_wide(ray, &mut stacks.top, &mut stacks.mesh)
            })
    }

    /// The scalar oracle of [`Scene::occluded_incoherent`].
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.bvh.occluded(ray)
            || self
                .instances
                .as_ref()
                .is_some_and(|i| i.bvh().occluded(ray))
    }

    /// The shading record of a hit: triangle `triangle` of the scene's own
    /// triangles ([`NO_INSTANCE`]) or of instance `instance`'s mesh, in
    /// world space.
    pub fn hit_surface(&self, triangle: u32, instance: u32) -> Option<Surface> {
        if instance == NO_INSTANCE {
            return self.surface(triangle as usize);
        }
        self.instances
            .as_ref()?
            .surface(triangle, instance, &self.materials)
    }

    /// The packet's shading records in the lanes of `active`
    /// ([`Surface::NONE`] elsewhere): one gather when no lane hit an
    /// instance, else record by record in two passes: every lane's
    /// triangle read first, then the records made. On a large scene most
    /// of these reads miss the caches; made lane by lane, each record
    /// would wait for its own read, while eight reads issued together
    /// are in flight at once.
    pub fn hit_surfaces(&self, hit: &PacketHit, active: LaneMask) -> SurfacePacket {
        let instanced = active
            .iter()
            .filter(|&lane| hit.instance[lane] != NO_INSTANCE)
            .fold(LaneMask::NONE, LaneMask::with);
        if instanced.is_empty() {
            return self.packed_surfaces.gather(&hit.triangle, active);
        }
        let fetched: [Option<FetchedTriangle>; LANES] = core::array::from_fn(|lane| {
            if !instanced.contains(lane) {
                return None;
            }
            let instances = self.instances.as_ref()?;
            instances.fetch(hit.triangle[lane], hit.instance[lane])
        });
        let records: [Surface; LANES] = core::array::from_fn(|lane| {
            let record = if instanced.contains(lane) {
                fetched[lane].and_then(|f| f.surface(&self.materials))
            } else if active.contains(lane) {
                self.surface(hit.triangle[lane] as usize)
            } else {
                None
            };
            record.unwrap_or(Surface::NONE)
        });
        SurfacePacket::from_records(&records)
    }

    /// The material of a hit ([`Scene::hit_surface`]'s arguments).
    #[inline]
    pub fn hit_material(&self, triangle: u32, instance: u32) -> Option<MaterialId> {
        if instance == NO_INSTANCE {
            return self.packed_surfaces.material(triangle as usize);
        }
        self.instances.as_ref()?.material(triangle, instance)
    }

    /// The texture coordinates of a hit triangle's vertices (`None` when
    /// none are stored: all zero).
    #[inline]
    pub fn hit_uvs(&self, triangle: u32, instance: u32) -> Option<[Vec2; 3]> {
        if instance == NO_INSTANCE {
            return self.uvs.get(triangle as usize).copied();
        }
        self.instances.as_ref()?.uvs(triangle, instance)
    }

    /// Whether a material needs tangents ([`Bsdf::needs_tangent`]: a
    /// normal map or an anisotropic lobe): only then does shading read
    /// [`Scene::hit_tangents`].
    pub fn needs_tangent(&self) -> bool {
        self.needs_tangent
    }

    /// The world-space `[∂p/∂u, ∂p/∂v]` of a hit triangle ([`tangent`]);
    /// zero where its material needs none.
    #[inline]
    pub fn hit_tangents(&self, triangle: u32, instance: u32) -> [Vec3; 2] {
        let tangents = if instance == NO_INSTANCE {
            self.tangents.get(triangle as usize).copied()
        } else {
            self.instances
                .as_ref()
                .and_then(|i| i.tangents(triangle, instance))
        };
        tangents.unwrap_or([Vec3::ZERO; 2])
    }

    /// The unit geometric normal of a hit triangle, in world space.
    #[inline]
    pub fn hit_normal(&self, triangle: u32, instance: u32) -> Option<Vec3> {
        if instance == NO_INSTANCE {
            return self.normal(triangle as usize);
        }
        self.instances.as_ref()?.normal(triangle, instance)
    }

    /// The shading normals of the packet's hits in `lanes` on smooth
    /// triangles: the vertex normals interpolated at the hit's
    /// barycentrics `(1 − u − v, u, v)` and normalized, in the world, on
    /// the triangle's front (for instances mapped after the interpolation,
    /// [`instances`]' docs); `None` in the other lanes and where the
    /// interpolation vanishes. Two passes, as [`Scene::hit_surfaces`]:
    /// every lane's table entries read first, then the normals.
    pub fn hit_smooth_normals(&self, hit: &PacketHit, lanes: LaneMask) -> [Option<Vec3>; LANES] {
        let corners: [Option<SmoothCorners>; LANES] = core::array::from_fn(|lane| {
            let (triangle, instance) = (hit.triangle[lane], hit.instance[lane]);
            if !lanes.contains(lane) {
                None
            } else if instance == NO_INSTANCE {
                Some(SmoothCorners {
                    table: &self.vertex_normals,
                    entries: self.vertex_normals.corners(triangle as usize)?,
                    normal_matrix: None,
                })
            } else {
                self.instances.as_ref()?.smooth_corners(triangle, instance)
            }
        });
        let (u, v) = (hit.u.to_array(), hit.v.to_array());
        core::array::from_fn(|lane| {
            let corners = corners[lane]?;
            let [n0, n1, n2] = corners.entries.map(|e| corners.table.entry(e));
            let (u, v) = (u[lane], v[lane]);
            let interpolated = n0? * (1.0 - u - v) + n1? * u + n2? * v;
            corners
                .normal_matrix
                .map_or(interpolated, |m| m * interpolated)
                .try_normalize()
        })
    }

    /// lights
    pub fn lights(&self) -> &LightSet {
        &self.lights
    }

    /// The shading record of triangle `index`.
    pub fn surface(&self, index: usize) -> Option<Surface> {
        self.packed_surfaces.unpack(index)
    }

    /// emitters
    pub fn emitters(&self) -> &TriangleSubset {
        &self.emitters
    }

    /// The tables materials read (spectra, angular spectra, textures).
    pub fn material_tables(&self) -> MaterialTables<'_> {
        MaterialTables {
            spectra: &self.spectra,
            angular: &self.angular,
            textures: &self.textures,
        }
    }

    /// Triangles dropped at build time as degenerate.
    pub fn skipped_triangles(&self) -> usize {
        self.skipped_triangles
    }

    /// Checks the shading records ([`Scene::surface`]) against the
    /// triangles, materials and lights they were derived from (one record
    /// per triangle, each equal to [`Surface::new`] of its triangle with the
    /// light set's selection probability).
    /// Also checks [`Scene::emitters`] against the records, the light
    /// set's own invariants ([`LightSet::validate`]), the texture
    /// coordinates' count and the spectrum registers against
    /// [`Scene::spectra`].
    pub fn validate_surfaces(&self) -> Result<(), String> {
        self.triangles
            .validate(&self.bvh)
            .map_err(|e| format!("triangles: {e}"))?;
        validate_surface_records(
            &self.packed_surfaces,
            &self.triangles(),
            &self.materials,
            &self.lights,
        )?;
        self.lights.validate()?;
        let triangles = self.triangles.len();
        self.uvs
            .validate(triangles)
            .map_err(|e| format!("texture coordinates: {e}"))?;
        self.vertex_normals
            .validate(triangles)
            .map_err(|e| format!("vertex normals: {e}"))?;
        if self.spectrum_registers != SpectrumRegisters::new(&self.spectra) {
            return Err("the spectrum registers do not hold the scene's spectra".to_owned());
        }
        if self.emitters != emitters(&self.bvh, &self.packed_surfaces) {
            return Err("the emitter subset does not match the shading records".to_owned());
        }
        match &self.instances {
            Some(instances) => instances.validate(&self.materials),
            None => Ok(()),
        }
    }

    /// The first spectra's Fourier coefficients in registers.
    pub fn spectrum_registers(&self) -> &SpectrumRegisters {
        &self.spectrum_registers
    }

    /// The shading records packed for packet gathers.
    pub fn packed_surfaces(&self) -> &PackedSurfaces {
        &self.packed_surfaces
    }

    /// Area of triangle `index` (0 for an unknown index).
    pub fn area(&self, index: usize) -> f32 {
        self.packed_surfaces.area(index).unwrap_or(0.0)
    }

    /// Bytes of memory the scene holds: geometry, BVH, light distribution,
    /// spectra (with their dense tables), angular Fourier tables or network
    /// weights, textures and materials. Exact for the vectors owned here
    /// and the BVH ([`Bvh::memory_bytes`]); instanced meshes count once,
    /// with a record and a top-level tree entry per instance
    /// ([`Instances::memory_bytes`]); the light set is counted per light
    /// ([`LIGHT_BYTES`]).
    pub fn memory_bytes(&self) -> usize {
        let geometry = self.triangles.memory_bytes()
            + self.uvs.memory_bytes()
            + self.tangents.memory_bytes()
            + self.vertex_normals.memory_bytes()
            + self.packed_surfaces.memory_bytes();
        let bvh =
            self.bvh.memory_bytes() + self.instances.as_ref().map_or(0, Instances::memory_bytes);
        let lights = self.lights.len() * LIGHT_BYTES
            + self.emitters.memory_bytes()
            + self.light_sampler.memory_bytes()
            + self
                .environment_map
                .as_ref()
                .map_or(0, EnvironmentMap::memory_bytes);
        let spectra: usize = self.spectra.iter().map(SceneSpectrum::memory_bytes).sum();
        let angular: usize = self
            .angular
            .iter()
            .map(|a| {
                let spectra = match a.function() {
                    AngularFunction::Conductor { n, k, tint, .. } => {
                        n.memory_bytes()
                            + k.memory_bytes()
                            + tint.as_ref().map_or(0, |t| t.memory_bytes())
                    }
                    AngularFunction::Film { layers, .. } => {
                        layers.capacity() * size_of::<crate::spectra::angular::FilmLayer>()
                    }
                    _ => 0,
                };
                size_of::<AngularSpectrum>() + a.table_bytes() + spectra
            })
            .sum();
        let textures: usize = self
            .textures
            .iter()
            .map(|t| size_of::<Texture>() + t.memory_bytes())
            .sum();
        let materials: usize = self
            .materials
            .iter()
            .map(|m| size_of::<Material>() + m.name.capacity())
            .sum();
        size_of::<Self>() + geometry + bvh + lights + spectra + angular + textures + materials
    }
}

/// Checks the packed records against their sources: one record per
/// triangle, each naming a material of the scene and equal to
/// [`Surface::new`] of its triangle (the normal as [`SceneBuilder::build`]
/// computes it) and that material, with the light set's selection
/// probability.
pub(crate) fn validate_surface_records(
    surfaces: &PackedSurfaces,
    triangles: &[[Vec3; 3]],
    materials: &[Material],
    lights: &LightSet,
) -> Result<(), String> {
    if surfaces.len() != triangles.len() {
        return Err(format!(
            "{} surface records for {} triangles",
            surfaces.len(),
            triangles.len()
        ));
    }
    for (index, vertices) in triangles.iter().enumerate() {
        let record = surfaces.unpack(index);
        let expected = record.and_then(|r| {
            let m = materials.get(r.material.index())?;
            Some(Surface {
                light_pmf: lights.pmf_of_triangle(index as u32),
                ..Surface::new(
                    geometric_normal(vertices),
                    triangle_area(vertices),
                    r.material,
                    m,
                )
            })
        });
        if expected.is_none() || expected != record {
            return Err(format!(
                "surface record {index} does not match its triangle"
            ));
        }
    }
    Ok(())
}

/// The unit geometric normal of a triangle, `(b − a) × (c − a)` normalised.
fn geometric_normal([a, b, c]: &[Vec3; 3]) -> Vec3 {
    (*b - *a).cross(*c - *a).normalize()
}

/// The box around the triangles of `bvh` and the instances' world boxes.
fn world_bounds(bvh: &Bvh, instances: Option<&Instances>) -> Option<(Vec3, Vec3)> {
    [bvh.bounds(), instances.and_then(|i| i.bvh().bounds())]
        .into_iter()
        .flatten()
        .reduce(|(min, max), (lo, hi)| (min.min(lo), max.max(hi)))
}

/// Whether triangle `index` belongs to one of `spheres` (in ascending
/// order of their triangles).
fn in_sphere_light(spheres: &[SphereLight], index: usize) -> bool {
    u32::try_from(index).is_ok_and(|triangle| sphere_holding(spheres, triangle).is_some())
}

/// Checks that every vertex of each sphere light's triangles lies on its
/// sphere, within [`SIMILARITY_TOLERANCE`] of the radius (the vertices of
/// [`analytic::sphere_mesh`] are on the unit sphere, placed by a
/// similarity).
fn validate_sphere_lights(spheres: &[SphereLight], triangles: &[[Vec3; 3]]) -> Result<(), String> {
    for sphere in spheres {
        sphere.validate()?;
        let range = sphere.triangles.start as usize..sphere.triangles.end as usize;
        let Some(vertices) = triangles.get(range) else {
            return Err(format!(
                "sphere light triangles {:?} of {}",
                sphere.triangles,
                triangles.len()
            ));
        };
        let bound = 4.0 * SIMILARITY_TOLERANCE * sphere.radius;
        let off = |v: &Vec3| ((*v - sphere.center).length() - sphere.radius).abs();
        if let Some(v) = vertices
            .iter()
            .flatten()
            .find(|v| off(v).is_nan() || off(v) > bound)
        {
            return Err(format!(
                "sphere light at {} radius {}: vertex {v} is off the sphere",
                sphere.center, sphere.radius
            ));
        }
    }
    Ok(())
}

/// The least the BVH keeps per (non-degenerate) triangle
/// ([`crate::accel::BYTES_PER_TRIANGLE`], derived from the BVH's own types).
pub const BVH_TRIANGLE_BYTES: usize = crate::accel::BYTES_PER_TRIANGLE;

/// Bytes the light set keeps per emissive triangle: its [`Light`] record
/// and CDF entry (its per-triangle light index is counted per triangle).
pub const LIGHT_BYTES: usize = size_of::<Light>() + size_of::<f32>();

/// Whether [`SceneBuilder::build`] checks the structures it derives from
/// the input against that input: the tree ([`Bvh::validate`]), the
/// triangle store and the instances' two-level tree.
///
/// Those checks re-derive what the build made (every prepared triangle,
/// the fan pairs, the degenerate set, the bounds of every leaf) and
/// compare: they find defects of the build, not of the input, which the
/// loaders and the builder check on their own (malformed meshes, unknown
/// ids, non-finite or degenerate triangles) whatever this setting. They
/// cost about a sixth of loading a million-triangle mesh
/// (`docs/performance.md`), as much again as parts of the build itself,
/// so, like an internal `debug_assert!`, they run by default in debug
/// builds (every test, every fuzz run) and in release builds only when
/// asked for (`fspec render --validate`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DerivedChecks {
    /// Every derived structure validated against the input.
    Full,
    /// None of those re-derivations.
    Skip,
}

impl Default for DerivedChecks {
    /// [`DerivedChecks::Full`] in debug builds, else
    /// [`DerivedChecks::Skip`].
    fn default() -> Self {
        if cfg!(debug_assertions) {
            Self::Full
        } else {
            Self::Skip
        }
    }
}

/// Incremental construction of a [`Scene`].
#[derive(Debug)]
pub struct SceneBuilder {
    range: SpectralRange,
    spectra: Vec<SceneSpectrum>,
    angular: Vec<AngularSpectrum>,
    textures: Vec<Texture>,
    materials: Vec<Material>,
    fluorophores: Vec<SceneFluorophore>,
    triangles: Vec<[Vec3; 3]>,
    triangle_material: Vec<MaterialId>,
    uvs: SparseAttribute<[Vec2; 3]>,
    vertex_normals: VertexNormals,
    camera: Option<Camera>,
    environment: Option<SpectrumId>,
    environment_map: Option<EnvironmentMap>,
    point_lights: Vec<PointLight>,
    directional_lights: Vec<DirectionalLight>,
    /// Meshes kept for instances ([`SceneBuilder::add_instanced_mesh`]).
    instanced_meshes: Vec<Vec<(MeshData, MaterialId)>>,
    /// Instances, resolved at build ([`instances`]).
    instance_requests: Vec<InstanceRequest>,
    instancing: Instancing,
    skipped: usize,
    checks: DerivedChecks,
    /// Meshes placed as spheres ([`MeshPlacement::sphere`]).
    spheres: Vec<SphereMark>,
}

/// A placed mesh that tessellates a sphere, for [`SceneBuilder::build`]
/// to light as one [`SphereLight`] when its material emits outwards.
#[derive(Debug, Clone)]
struct SphereMark {
    /// The builder's triangles of the mesh.
    triangles: core::ops::Range<usize>,
    center: Vec3,
    radius: f32,
    material: MaterialId,
    /// Whether the front faces point out of the ball (no `flip_normals`).
    outward: bool,
}

/// Where a smooth triangle's vertex normals go in the table
/// ([`VertexNormals`]).
enum NormalEntries<'a> {
    /// Three new entries (normals given per triangle).
    New,
    /// The mesh vertices of the triangle's corners, and per mesh vertex its
    /// entry once added ([`NO_ID`] before): each mesh vertex's normal is
    /// stored once.
    Mesh([u32; 3], &'a mut [u32]),
}

/// Vertex normals within this cosine of the face normal (about 0.08°)
/// count as the face normal.
const FLAT_COSINE: f32 = 1.0 - 1e-6;

/// Triangles of a mesh shaped together before they are stored in order
/// ([`SceneBuilder::add_mesh_data`]): 2¹⁴ (about 2 MiB of shaped
/// triangles) gives a 2-core machine tasks much longer than their
/// scheduling and bounds the buffer.
const MESH_BLOCK_TRIANGLES: usize = 1 << 14;

/// A triangle as the scene keeps it: its vertices and texture coordinates
/// (two swapped when its smooth normals point against its winding) and,
/// when it shades smooth, its unit vertex normals in the input's corner
/// order with the order of the stored corners.
#[derive(Debug, Clone, Copy)]
struct ShapedTriangle {
    vertices: [Vec3; 3],
    uvs: [Vec2; 3],
    smooth: Option<([Vec3; 3], [usize; 3])>,
}

/// The pure part of adding a triangle: `None` when it is degenerate (zero
/// area, or a non-finite vertex or texture coordinate).
///
/// A smooth triangle whose normals point, on average, against its winding
/// is turned over (two vertices swapped): the front face is where the
/// shading normals point, as Mitsuba flips the geometric normal to the
/// shading normal's side. A triangle with a zero or non-finite vertex
/// normal, or whose normals all equal its face normal, is shaded flat.
fn shape_triangle(
    vertices: [Vec3; 3],
    uvs: [Vec2; 3],
    normals: Option<[Vec3; 3]>,
) -> Option<ShapedTriangle> {
    let [a, b, c] = vertices;
    let cross = (b - a).cross(c - a);
    let area2 = cross.length_squared();
    let finite = vertices.iter().all(|v| v.is_finite()) && uvs.iter().all(|t| t.is_finite());
    if !(finite && area2.is_finite() && area2 > 0.0) {
        return None;
    }
    let unit = normals.and_then(|[n0, n1, n2]| {
        Some([
            n0.try_normalize()?,
            n1.try_normalize()?,
            n2.try_normalize()?,
        ])
    });
    // Vertex normals that all equal the face normal shade flat: no
    // interpolation per hit.
    let face = cross.normalize();
    let unit = unit.filter(|n| n.iter().any(|n| n.dot(face) < FLAT_COSINE));
    let (mut vertices, mut uvs, mut order) = (vertices, uvs, [0, 1, 2]);
    if unit.is_some_and(|n| (n[0] + n[1] + n[2]).dot(cross) < 0.0) {
        vertices.swap(1, 2);
        uvs.swap(1, 2);
        order = [0, 2, 1];
    }
    Some(ShapedTriangle {
        vertices,
        uvs,
        smooth: unit.map(|n| (n, order)),
    })
}

/// How [`SceneBuilder::add_mesh_data`] places a mesh.
#[derive(Debug, Clone, Copy)]
pub struct MeshPlacement<'a> {
    /// Object to world.
    pub transform: &'a Transform,
    /// Material of every triangle.
    pub material: MaterialId,
    /// Flip the front face (winding and vertex normals), Mitsuba's
    /// `flip_normals`.
    pub flip_normals: bool,
    /// Ignore the vertex normals (flat shading), Mitsuba's `face_normals`.
    pub face_normals: bool,
    /// The mesh tessellates the unit sphere about the origin, its vertices
    /// on it ([`crate::scene::analytic::sphere_mesh`]), no coarser than
    /// [`crate::scene::analytic::DEFAULT_SAG`]: placed by a similarity with
    /// a material that emits from its front (outer) side alone, it is
    /// sampled as one spherical light ([`crate::shading::sphere_light`]).
    /// A coarser tessellation should not be marked: light sampling counts
    /// the analytic sphere, whose outline exceeds the mesh's by the sag.
    pub sphere: bool,
}

/// What [`SceneBuilder::add_mesh_data`] added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MeshAdded {
    /// Triangles kept.
    pub triangles: usize,
    /// Triangles skipped as degenerate (zero area or non-finite after the
    /// transform).
    pub degenerate: usize,
    /// Kept triangles with vertex normals.
    pub smooth: usize,
}

/// The raw words of a list of ids (for the reference check's messages).
fn words<I: Copy + Into<u32>>(ids: &[I]) -> Vec<u32> {
    ids.iter().map(|&id| id.into()).collect()
}

impl SceneBuilder {
    /// An empty scene over `range`.
    pub fn new(range: SpectralRange) -> Self {
        Self {
            range,
            spectra: Vec::new(),
            angular: Vec::new(),
            textures: Vec::new(),
            materials: Vec::new(),
            fluorophores: Vec::new(),
            triangles: Vec::new(),
            triangle_material: Vec::new(),
            uvs: SparseAttribute::default(),
            vertex_normals: VertexNormals::default(),
            camera: None,
            environment: None,
            environment_map: None,
            point_lights: Vec::new(),
            directional_lights: Vec::new(),
            instanced_meshes: Vec::new(),
            instance_requests: Vec::new(),
            instancing: Instancing::Auto,
            skipped: 0,
            checks: DerivedChecks::default(),
            spheres: Vec::new(),
        }
    }

    /// Sets whether [`Self::build`] validates what it derives
    /// ([`DerivedChecks`]; by default only in debug builds).
    pub fn set_derived_checks(&mut self, checks: DerivedChecks) {
        self.checks = checks;
    }

    /// The spectral range.
    pub fn range(&self) -> SpectralRange {
        self.range
    }

    /// Adds a spectrum; `name` appears in error messages. A source equal to
    /// one added before returns that spectrum's id: preparing a spectrum
    /// (projection and dense table) is the bulk of loading an OBJ/MTL, whose
    /// materials often repeat colours, and shared ids also let the
    /// integrator sum their emission once.
    pub fn add_spectrum(
        &mut self,
        name: &str,
        source: SpectrumSource,
    ) -> Result<SpectrumId, SceneError> {
        if let Some(index) = self.spectra.iter().position(|s| s.source() == &source) {
            return Ok(SpectrumId(index as u32));
        }
        let spectrum = SceneSpectrum::new(source, self.range)
            .map_err(|e| SceneError::Spectrum(name.to_string(), e))?;
        self.spectra.push(spectrum);
        Ok(SpectrumId((self.spectra.len() - 1) as u32))
    }

    /// Adds an angle-dependent spectrum (builds its Fourier tables).
    pub fn add_angular(
        &mut self,
        name: &str,
        function: AngularFunction,
    ) -> Result<AngularId, SceneError> {
        let angular = AngularSpectrum::new(function, &self.range)
            .map_err(|e| SceneError::Spectrum(name.to_string(), e))?;
        self.angular.push(angular);
        Ok(AngularId((self.angular.len() - 1) as u32))
    }

    /// A prepared spectrum added so far (e.g. to build an angular function).
    pub fn spectrum(&self, id: SpectrumId) -> Option<&SceneSpectrum> {
        self.spectra.get(id.index())
    }

    /// The texture `id`, if it was added.
    pub fn texture(&self, id: TextureId) -> Option<&Texture> {
        self.textures.get(id.index())
    }

    /// Adds a texture.
    pub fn add_texture(&mut self, texture: Texture) -> TextureId {
        self.textures.push(texture);
        TextureId((self.textures.len() - 1) as u32)
    }

    /// Adds a fluorophore layer (prepared over the builder's range): its
    /// two kernel sides become scene spectra
    /// ([`crate::shading::material::SceneFluorophore`]).
    pub fn add_fluorophore(
        &mut self,
        name: &str,
        layer: FluorescentLayer,
    ) -> Result<FluorophoreId, SceneError> {
        if layer.range() != &self.range {
            return Err(SceneError::Spectrum(
                name.to_string(),
                SpectralError::InvalidParameter("fluorophore range differs from the scene's"),
            ));
        }
        let (lambda_nm, u, v) = tabulated_sides(&layer);
        let emitted = self.add_spectrum(
            &format!("{name} (emitted side)"),
            SpectrumSource::Tabulated {
                lambda_nm: lambda_nm.clone(),
                values: u,
            },
        )?;
        let excited = self.add_spectrum(
            &format!("{name} (excited side)"),
            SpectrumSource::Tabulated {
                lambda_nm,
                values: v,
            },
        )?;
        let spectrum = self
            .spectra
            .get(excited.index())
            .ok_or(SceneError::Reference(
                name.to_string(),
                "spectrum",
                excited.0,
            ))?;
        let record = SceneFluorophore::new(name, layer, (emitted, excited), spectrum)
            .map_err(SceneError::Light)?;
        self.fluorophores.push(record);
        Ok(FluorophoreId((self.fluorophores.len() - 1) as u32))
    }

    /// The BSDF of `fluorophore`'s layer over a Lambertian base of
    /// reflectance `base`: its elastic reflectance `ρ (1 − a)` becomes a
    /// scene spectrum (sampled on the dense grid).
    pub fn fluorescent_bsdf(
        &mut self,
        name: &str,
        base: SpectrumId,
        fluorophore: FluorophoreId,
    ) -> Result<Bsdf, SceneError> {
        let missing = |kind, id| SceneError::Reference(name.to_string(), kind, id);
        let layer = self
            .fluorophores
            .get(fluorophore.index())
            .ok_or(missing("fluorophore", fluorophore.0))?
            .layer;
        let base_spectrum = self
            .spectra
            .get(base.index())
            .ok_or(missing("spectrum", base.0))?;
        let steps = (self.range.width_nm() / crate::spectra::DENSE_STEP_NM).round() as usize;
        let lambda_nm: Vec<f64> = (0..=steps)
            .map(|i| self.range.min_nm() + i as f64 * crate::spectra::DENSE_STEP_NM)
            .collect();
        let values = lambda_nm
            .iter()
            .map(|&l| f64::from(base_spectrum.value(l as f32)) * (1.0 - layer.absorptance(l)))
            .collect();
        let elastic = self.add_spectrum(
            &format!("{name} (elastic)"),
            SpectrumSource::Tabulated { lambda_nm, values },
        )?;
        Ok(Bsdf::Fluorescent {
            elastic,
            fluorophore,
        })
    }

    /// Adds a non-emissive fluorescent material
    /// ([`SceneBuilder::fluorescent_bsdf`]).
    pub fn add_fluorescent_material(
        &mut self,
        name: &str,
        base: SpectrumId,
        fluorophore: FluorophoreId,
    ) -> Result<MaterialId, SceneError> {
        let bsdf = self.fluorescent_bsdf(name, base, fluorophore)?;
        Ok(self.add_material(Material::new(name, bsdf)))
    }

    /// The elastic spectrum and the fluorophore of a fluorescent material
    /// added so far (`None` for other materials).
    pub fn fluorescent_parts(
        &self,
        material: MaterialId,
    ) -> Option<(SpectrumId, &SceneFluorophore)> {
        match self.materials.get(material.index())?.bsdf {
            Bsdf::Fluorescent {
                elastic,
                fluorophore,
            } => Some((elastic, self.fluorophores.get(fluorophore.index())?)),
            _ => None,
        }
    }

    /// Adds a material.
    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.materials.push(material);
        MaterialId((self.materials.len() - 1) as u32)
    }

    /// Adds one triangle (counter-clockwise seen from its front).
    pub fn add_triangle(&mut self, vertices: [Vec3; 3], material: MaterialId) {
        self.add_triangle_uv(vertices, [Vec2::ZERO; 3], material);
    }

    /// Counts `count` triangles that a loader dropped before adding them
    /// (non-finite values) among [`Scene::skipped_triangles`].
    pub fn count_skipped(&mut self, count: usize) {
        self.skipped += count;
    }

    /// Adds one triangle with texture coordinates.
    pub fn add_triangle_uv(&mut self, vertices: [Vec3; 3], uvs: [Vec2; 3], material: MaterialId) {
        self.add_shaded_triangle(vertices, uvs, None, material);
    }

    /// Adds one triangle with texture coordinates and, if `normals` is
    /// given, smooth shading from these vertex normals (normalised here).
    /// Returns whether it was kept (not degenerate).
    ///
    /// A smooth triangle whose normals point, on average, against its
    /// winding is turned over (two vertices swapped): the front face is
    /// where the shading normals point, as Mitsuba flips the geometric
    /// normal to the shading normal's side. A triangle with a zero or
    /// non-finite vertex normal is shaded flat.
    pub fn add_shaded_triangle(
        &mut self,
        vertices: [Vec3; 3],
        uvs: [Vec2; 3],
        normals: Option<[Vec3; 3]>,
        material: MaterialId,
    ) -> bool {
        self.add_triangle_normals(
            vertices,
            uvs,
            normals.map(|n| (n, NormalEntries::New)),
            material,
        )
    }

    /// [`SceneBuilder::add_shaded_triangle`] with the vertex normals'
    /// table entries coming from `normals`' source.
    fn add_triangle_normals(
        &mut self,
        vertices: [Vec3; 3],
        uvs: [Vec2; 3],
        normals: Option<([Vec3; 3], NormalEntries<'_>)>,
        material: MaterialId,
    ) -> bool {
        let (normals, source) = match normals {
            Some((n, source)) => (Some(n), source),
            None => (None, NormalEntries::New),
        };
        self.store_triangle(shape_triangle(vertices, uvs, normals), source, material)
    }

    /// Stores a triangle shaped by [`shape_triangle`] (its smooth normals'
    /// table entries from `source`); returns whether it was kept.
    fn store_triangle(
        &mut self,
        shape: Option<ShapedTriangle>,
        source: NormalEntries<'_>,
        material: MaterialId,
    ) -> bool {
        let Some(ShapedTriangle {
            vertices,
            uvs,
            smooth,
        }) = shape
        else {
            self.skipped += 1;
            return false;
        };
        let triangle = self.triangles.len();
        if let Some((n, order)) = smooth {
            let entries = match source {
                NormalEntries::New => n.map(|n| self.vertex_normals.push(n)),
                NormalEntries::Mesh(vertex, slots) => {
                    core::array::from_fn(|k| match slots.get_mut(vertex[k] as usize) {
                        Some(slot) if *slot != NO_ID => *slot,
                        Some(slot) => {
                            *slot = self.vertex_normals.push(n[k]);
                            *slot
                        }
                        None => self.vertex_normals.push(n[k]),
                    })
                }
            };
            self.vertex_normals.set(triangle, order.map(|k| entries[k]));
        }
        // Texture coordinates are stored for the triangles that have
        // non-zero ones (bits: a -0 interpolates differently from the 0 of
        // a triangle without).
        let zero_uvs = uvs.iter().all(|t| t.x.to_bits() == 0 && t.y.to_bits() == 0);
        if !zero_uvs {
            self.uvs.set(triangle, uvs);
        }
        self.triangles.push(vertices);
        self.triangle_material.push(material);
        true
    }

    /// Adds a mesh read from a file (or made by [`shapes`]), placed by
    /// `placement`: positions by the transform, vertex normals by its
    /// inverse transpose; a mirroring transform or `flip_normals` swaps the
    /// winding (and `flip_normals` negates the normals) so that the front
    /// face stays outside ([`Transform`]). Triangles missing texture
    /// coordinates get `(0, 0)`.
    pub fn add_mesh_data(
        &mut self,
        mesh: &MeshData,
        placement: &MeshPlacement<'_>,
    ) -> Result<MeshAdded, SceneError> {
        mesh.validate().map_err(SceneError::Mesh)?;
        let first = self.triangles.len();
        self.triangles.reserve(mesh.triangles.len());
        self.triangle_material.reserve(mesh.triangles.len());
        let transform = placement.transform;
        let positions: Vec<Vec3> = mesh
            .positions
            .par_iter()
            .map(|&p| transform.point(p))
            .collect();
        let smooth = !placement.face_normals && !mesh.normals.is_empty();
        let sign = if placement.flip_normals { -1.0 } else { 1.0 };
        let normals: Vec<Vec3> = if smooth {
            mesh.normals
                .par_iter()
                .map(|&n| transform.normal(n).map_or(Vec3::ZERO, |n| sign * n))
                .collect()
        } else {
            Vec::new()
        };
        let swap = transform.flips_handedness() != placement.flip_normals;
        let corner_order = |[i0, i1, i2]: [u32; 3]| if swap { [i0, i2, i1] } else { [i0, i1, i2] };
        // The table entry of each mesh vertex's normal, once a smooth
        // triangle has added it.
        let mut slots = vec![NO_ID; normals.len()];
        let mut added = MeshAdded::default();
        // Blocks of triangles are shaped in parallel (pure), then stored in
        // order: the scene is the same as one triangle at a time.
        let mut shaped: Vec<Option<Option<ShapedTriangle>>> =
            Vec::with_capacity(MESH_BLOCK_TRIANGLES);
        for block in mesh.triangles.chunks(MESH_BLOCK_TRIANGLES) {
            block
                .par_iter()
                .map(|&triangle| {
                    let order = corner_order(triangle);
                    let at = |list: &[Vec3]| order.map(|i| list.get(i as usize).copied());
                    let [Some(a), Some(b), Some(c)] = at(&positions) else {
                        return None;
                    };
                    let uvs =
                        order.map(|i| mesh.uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
                    let vertex_normals = match at(&normals) {
                        [Some(n0), Some(n1), Some(n2)] => Some([n0, n1, n2]),
                        _ => None,
                    };
                    Some(shape_triangle([a, b, c], uvs, vertex_normals))
                })
                .collect_into_vec(&mut shaped);
            for (&triangle, shape) in block.iter().zip(shaped.drain(..)) {
                let shape =
                    shape.ok_or_else(|| SceneError::Mesh("an index out of range".into()))?;
                let source = NormalEntries::Mesh(corner_order(triangle), &mut slots);
                if self.store_triangle(shape, source, placement.material) {
                    added.triangles += 1;
                    if self.vertex_normals.get(self.triangles.len() - 1).is_some() {
                        added.smooth += 1;
                    }
                } else {
                    added.degenerate += 1;
                }
            }
        }
        if let (true, Some(radius)) = (placement.sphere, transform.uniform_scale()) {
            self.spheres.push(SphereMark {
                triangles: first..self.triangles.len(),
                center: transform.point(Vec3::ZERO),
                radius,
                material: placement.material,
                outward: !placement.flip_normals,
            });
        }
        Ok(added)
    }

    /// The meshes placed as spheres ([`MeshPlacement::sphere`]) that are
    /// lit as spherical lights: those whose material emits from the outer
    /// side alone (front faces out, one-sided), in triangle order.
    fn sphere_lights(&self) -> Vec<SphereLight> {
        self.spheres
            .iter()
            .filter_map(|mark| {
                let material = self.materials.get(mark.material.index())?;
                let emission = material.emission.filter(|e| !e.is_none())?;
                let start = u32::try_from(mark.triangles.start).ok()?;
                let end = u32::try_from(mark.triangles.end).ok()?;
                let light = SphereLight {
                    center: mark.center,
                    radius: mark.radius,
                    emission,
                    triangles: start..end,
                };
                // From its outer side only: module docs of `sphere_light`.
                let outside_only = mark.outward && !material.two_sided;
                (outside_only && light.validate().is_ok()).then_some(light)
            })
            .collect()
    }

    /// Adds the quad `a b c d` (counter-clockwise) as two triangles.
    pub fn add_quad(&mut self, quad: [Vec3; 4], material: MaterialId) {
        self.add_triangle([quad[0], quad[1], quad[2]], material);
        self.add_triangle([quad[0], quad[2], quad[3]], material);
    }

    /// Adds an indexed triangle mesh.
    pub fn add_mesh(
        &mut self,
        positions: &[Vec3],
        indices: &[u32],
        material: MaterialId,
    ) -> Result<(), SceneError> {
        for tri in indices.chunks_exact(3) {
            let mut vertices = [Vec3::ZERO; 3];
            for (v, &index) in vertices.iter_mut().zip(tri) {
                *v = *positions
                    .get(index as usize)
                    .ok_or(SceneError::IndexOutOfRange {
                        index,
                        vertices: positions.len(),
                    })?;
            }
            self.add_triangle(vertices, material);
        }
        Ok(())
    }

    /// Sets the camera.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = Some(camera);
    }

    /// Sets a constant environment emission (it replaces an environment map).
    pub fn set_environment(&mut self, spectrum: Option<SpectrumId>) {
        self.environment = spectrum;
        if spectrum.is_some() {
            self.environment_map = None;
        }
    }

    /// Sets an environment map (it replaces a constant environment).
    pub fn set_environment_map(&mut self, map: EnvironmentMap) {
        self.environment = None;
        self.environment_map = Some(map);
    }

    /// Adds a point light.
    pub fn add_point_light(&mut self, light: PointLight) {
        self.point_lights.push(light);
    }

    /// Adds a directional light (its direction is normalised at build).
    pub fn add_directional_light(&mut self, light: DirectionalLight) {
        self.directional_lights.push(light);
    }

    /// Keeps a mesh (its parts, each with its material, in object
    /// coordinates) for [`SceneBuilder::add_instance`]; places nothing.
    pub fn add_instanced_mesh(
        &mut self,
        parts: Vec<(MeshData, MaterialId)>,
    ) -> Result<InstancedMeshId, SceneError> {
        for (mesh, _) in &parts {
            mesh.validate().map_err(SceneError::Mesh)?;
        }
        let id = u32::try_from(self.instanced_meshes.len())
            .map_err(|_| SceneError::Mesh("too many instanced meshes".into()))?;
        self.instanced_meshes.push(parts);
        Ok(InstancedMeshId(id))
    }

    /// Places the mesh `mesh` once more. Whether it stays an instance or
    /// is copied into the scene's triangles is decided at build
    /// ([`instances`]); either way it renders the same.
    pub fn add_instance(
        &mut self,
        mesh: InstancedMeshId,
        placement: InstancePlacement,
    ) -> Result<(), SceneError> {
        if mesh.0 as usize >= self.instanced_meshes.len() {
            return Err(SceneError::Mesh(format!(
                "instance of mesh {}, which does not exist",
                mesh.0
            )));
        }
        self.instance_requests
            .push(InstanceRequest { mesh, placement });
        Ok(())
    }

    /// Sets what [`SceneBuilder::build`] does with instances.
    pub fn set_instancing(&mut self, instancing: Instancing) {
        self.instancing = instancing;
    }

    /// Whether an instance may stay one: its materials exist and none
    /// emits ([`instances`]).
    fn instance_qualifies(&self, request: &InstanceRequest) -> bool {
        let parts = self
            .instanced_meshes
            .get(request.mesh.0 as usize)
            .map_or(&[][..], Vec::as_slice);
        parts.iter().all(|(_, own)| {
            let id = request.placement.material.unwrap_or(*own);
            self.materials
                .get(id.index())
                .is_some_and(|m| m.emission.is_none())
        })
    }

    /// Resolves the instances ([`instances`]): those that stay instances
    /// are returned with their meshes in object coordinates; the others
    /// are copied into the soup, in the order they were added.
    fn resolve_instances(&mut self) -> Result<Option<Instances>, SceneError> {
        let requests = core::mem::take(&mut self.instance_requests);
        let qualifies: Vec<bool> = requests
            .iter()
            .map(|r| self.instancing == Instancing::Auto && self.instance_qualifies(r))
            .collect();
        let parts_of = core::mem::take(&mut self.instanced_meshes);
        let mut uses = vec![0usize; parts_of.len()];
        for (request, &ok) in requests.iter().zip(&qualifies) {
            if ok {
                uses[request.mesh.0 as usize] += 1;
            }
        }
        let mut mesh_index: Vec<Option<u32>> = vec![None; parts_of.len()];
        let mut meshes = Vec::new();
        let mut mesh_skipped = Vec::new();
        let mut kept = Vec::new();
        for (request, ok) in requests.iter().zip(qualifies) {
            let k = request.mesh.0 as usize;
            let parts = parts_of.get(k).map_or(&[][..], Vec::as_slice);
            let placement = &request.placement;
            if ok && uses[k] >= MIN_INSTANCE_USES {
                let index = match mesh_index[k] {
                    Some(index) => index,
                    None => {
                        let (mesh, skipped) = InstancedMesh::new(self.range, parts)?;
                        meshes.push(mesh);
                        mesh_skipped.push(skipped);
                        let index = (meshes.len() - 1) as u32;
                        mesh_index[k] = Some(index);
                        index
                    }
                };
                // Degenerate triangles count once per copy, as flattened.
                self.skipped += mesh_skipped[index as usize];
                kept.push((index, *placement));
            } else {
                for (mesh, own) in parts {
                    self.add_mesh_data(
                        mesh,
                        &MeshPlacement {
                            transform: &placement.transform,
                            material: placement.material.unwrap_or(*own),
                            flip_normals: placement.flip_normals,
                            face_normals: placement.face_normals,
                            sphere: false,
                        },
                    )?;
                }
            }
        }
        if kept.is_empty() {
            return Ok(None);
        }
        Instances::new(meshes, kept)
            .map(Some)
            .map_err(SceneError::Bvh)
    }

    /// `[∂p/∂u, ∂p/∂v]` of every triangle whose material needs them
    /// ([`Bsdf::needs_tangent`], [`tangent`]), none when no material does.
    fn tangents(&self) -> SparseAttribute<[Vec3; 2]> {
        let mut tangents = SparseAttribute::default();
        let mapped: Vec<bool> = self
            .materials
            .iter()
            .map(|m| m.bsdf.needs_tangent())
            .collect();
        if !mapped.contains(&true) {
            return tangents;
        }
        let triangles = self.triangles.iter().zip(&self.triangle_material);
        for (index, (vertices, id)) in triangles.enumerate() {
            if mapped.get(id.index()) == Some(&true) {
                tangents.set(
                    index,
                    tangent::surface_derivatives(vertices, self.uvs.get(index)),
                );
            }
        }
        tangents.finish(self.triangles.len());
        tangents
    }

    /// Builds the BVH and the light distribution.
    pub fn build(mut self) -> Result<Scene, SceneError> {
        let instances = self.resolve_instances()?;
        // Pushes left up to twice the space the soup needs.
        self.triangles.shrink_to_fit();
        self.triangle_material.shrink_to_fit();
        self.uvs.finish(self.triangles.len());
        self.vertex_normals.finish(self.triangles.len());
        let camera = self.camera.ok_or(SceneError::NoCamera)?;
        if self.triangles.is_empty() && instances.is_none() {
            return Err(SceneError::Empty);
        }
        if self.materials.len() > crate::shading::surface::MAX_PACKED_MATERIALS {
            return Err(SceneError::TooManyMaterials(self.materials.len()));
        }
        if let Some(&bad) = self
            .triangle_material
            .iter()
            .find(|&&m| m.index() >= self.materials.len())
        {
            return Err(SceneError::UnknownMaterial(bad));
        }
        for material in &self.materials {
            let references = material.references();
            let checks = [
                ("spectrum", words(&references.spectra), self.spectra.len()),
                (
                    "angular spectrum",
                    words(&references.angular),
                    self.angular.len(),
                ),
                ("texture", words(&references.textures), self.textures.len()),
            ];
            for (kind, ids, available) in checks {
                if let Some(&id) = ids.iter().find(|&&id| id as usize >= available) {
                    return Err(SceneError::Reference(material.name.clone(), kind, id));
                }
            }
        }
        for material in &self.materials {
            for map in material.bsdf.normal_maps() {
                let id = map.relief.texture();
                let texture = self.textures.get(id.index()).map(Texture::data);
                let (fits, kind) = match map.relief {
                    Relief::Normals(_) => (
                        matches!(texture, Some(TextureData::Vector(_))),
                        "vector texture (of a normal map)",
                    ),
                    Relief::Heights { .. } => (
                        matches!(texture, Some(TextureData::Scalar(_))),
                        "scalar texture (of a bump map)",
                    ),
                };
                if !fits {
                    return Err(SceneError::Reference(material.name.clone(), kind, id.0));
                }
            }
        }
        for material in &self.materials {
            for leaf in material.bsdf.leaves() {
                if let Bsdf::Fluorescent { fluorophore, .. } = *leaf
                    && fluorophore.index() >= self.fluorophores.len()
                {
                    return Err(SceneError::Reference(
                        material.name.clone(),
                        "fluorophore",
                        fluorophore.0,
                    ));
                }
                if let Bsdf::Dielectric {
                    ior,
                    tints: Some(_),
                    ..
                } = leaf
                    && ior.is_dispersive()
                {
                    return Err(SceneError::Material(
                        material.name.clone(),
                        "specular tints need a constant index of refraction",
                    ));
                }
            }
        }
        if let Some(env) = self
            .environment
            .filter(|&e| e.index() >= self.spectra.len())
        {
            return Err(SceneError::Reference(
                "environment".into(),
                "spectrum",
                env.0,
            ));
        }
        let tangents = self.tangents();
        let spheres = self.sphere_lights();
        let bvh = Bvh::build(&self.triangles);
        let full = self.checks == DerivedChecks::Full;
        if full {
            bvh.validate(&self.triangles).map_err(SceneError::Bvh)?;
            if let Some(instances) = &instances {
                instances
                    .validate(&self.materials)
                    .map_err(SceneError::Bvh)?;
            }
            validate_sphere_lights(&spheres, &self.triangles).map_err(SceneError::Light)?;
        }
        // Material ids were checked above, so every triangle has a record
        // (`Surface::NONE` is unreachable). The records are packed as they
        // are made: a vector of the unpacked ones took 36 bytes a triangle
        // more at the peak of a large scene's build.
        let record = |vertices: &[Vec3; 3], id: MaterialId| {
            self.materials
                .get(id.index())
                .map_or(Surface::NONE, |material| {
                    Surface::new(
                        geometric_normal(vertices),
                        triangle_area(vertices),
                        id,
                        material,
                    )
                })
        };
        // In scenes whose tree holds the only copy of the triangles the
        // vector is gone before the records are made (`triangle_store`), so
        // the two are never held together at the build's peak.
        let triangles = TriangleStore::new(self.triangles, &bvh);
        if full {
            triangles.validate(&bvh).map_err(SceneError::Bvh)?;
        }
        let reader = triangles.reader(&bvh);
        let vertices_of = |index: usize| reader.get(index).unwrap_or([Vec3::NAN; 3]);
        let mut packed_surfaces = PackedSurfaces::collect(
            (0..triangles.len())
                .into_par_iter()
                .zip(self.triangle_material.par_iter())
                .map(|(index, &id)| record(&vertices_of(index), id)),
        );
        let candidates: Vec<Light> = (0..triangles.len())
            .into_par_iter()
            .filter(|&index| packed_surfaces.emits(index))
            .filter(|&index| !in_sphere_light(&spheres, index))
            .filter_map(|index| {
                let vertices = vertices_of(index);
                let id = *self.triangle_material.get(index)?;
                Some(Light {
                    triangle: u32::try_from(index).ok()?,
                    vertices,
                    surface: record(&vertices, id),
                })
            })
            .collect();
        drop(reader);
        // The records hold the materials from here on.
        drop(std::mem::take(&mut self.triangle_material));
        let mut lights = LightSet::new(triangles.len(), candidates, &self.spectra);
        let mut directional = self.directional_lights;
        for light in &mut directional {
            light.direction = light.direction.try_normalize().ok_or_else(|| {
                SceneError::Light("a directional light's direction has zero length".into())
            })?;
        }
        for point in &self.point_lights {
            if !(point.position.is_finite() && point.scale.is_finite() && point.scale >= 0.0) {
                return Err(SceneError::Light(
                    "a point light's position or scale is not finite".into(),
                ));
            }
        }
        let bounds = world_bounds(&bvh, instances.as_ref());
        let scene_radius = bounds.map_or(1.0, |(min, max)| 0.5 * (max - min).length());
        let light_sampler = LightSampler::new(&SceneLights {
            triangle_groups: lights.group_powers(),
            points: &self.point_lights,
            directional: &directional,
            environment: self.environment_map.as_ref(),
            spheres: &spheres,
            scene_radius,
            spectra: &self.spectra,
        })
        .map_err(SceneError::Light)?;
        light_sampler.validate().map_err(SceneError::Light)?;
        if !light_sampler.group_shares().is_empty() {
            lights.select_groups(light_sampler.group_shares());
        }
        for (triangle, light_pmf) in lights.pmfs() {
            packed_surfaces.set_light_pmf(triangle as usize, light_pmf);
        }
        let emitters = emitters(&bvh, &packed_surfaces);
        let spectrum_registers = SpectrumRegisters::new(&self.spectra);
        let needs_lobe = self.materials.iter().any(|m| m.bsdf.needs_lobe());
        let needs_tangent = self.materials.iter().any(|m| m.bsdf.needs_tangent());
        Ok(Scene {
            range: self.range,
            spectra: self.spectra,
            angular: self.angular,
            textures: self.textures,
            materials: self.materials,
            fluorophores: self.fluorophores,
            needs_lobe,
            needs_tangent,
            tangents,
            triangles,
            uvs: self.uvs,
            vertex_normals: self.vertex_normals,
            camera,
            environment: self.environment,
            environment_map: self.environment_map,
            light_sampler,
            bvh,
            lights,
            emitters,
            spectrum_registers,
            packed_surfaces,
            instances,
            skipped_triangles: self.skipped,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::builtin::cornell_box;
    use crate::shading::surface::{PackedSurfaces, Surface};
    use spectral_core::SpectralRange;

    #[test]
    fn a_mesh_stores_each_vertex_normal_once_and_reads_back_what_each_triangle_would()
    -> Result<(), Box<dyn std::error::Error>> {
        use super::{MeshPlacement, SceneBuilder, camera::Camera, transform::Transform};
        use glam::Vec3;
        // A sphere squashed and mirrored: normals by the inverse transpose,
        // windings swapped, every triangle smooth.
        let mesh = super::analytic::sphere_mesh(24);
        let transform = Transform::scale(Vec3::new(-1.0, 0.5, 2.0))?;
        let scene_with = |per_triangle: bool| -> Result<super::Scene, Box<dyn std::error::Error>> {
            let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
            let grey = b.add_spectrum("grey", crate::spectra::SpectrumSource::Constant(0.5))?;
            let m = b.add_material(crate::shading::material::Material::lambert("grey", grey));
            if per_triangle {
                for &[i0, i1, i2] in &mesh.triangles {
                    // The mirror swaps the winding, as add_mesh_data does.
                    let order = [i0, i2, i1].map(|i| i as usize);
                    let normals = order.map(|i| transform.normal(mesh.normals[i]));
                    let [Some(n0), Some(n1), Some(n2)] = normals else {
                        return Err("a normal did not transform".into());
                    };
                    let vertices = order.map(|i| transform.point(mesh.positions[i]));
                    b.add_shaded_triangle(vertices, [glam::Vec2::ZERO; 3], Some([n0, n1, n2]), m);
                }
            } else {
                b.add_mesh_data(
                    &mesh,
                    &MeshPlacement {
                        transform: &transform,
                        material: m,
                        flip_normals: false,
                        face_normals: false,
                        sphere: false,
                    },
                )?;
            }
            b.set_camera(Camera::look_at(Vec3::Z * 9.0, Vec3::ZERO, Vec3::Y, 40.0)?);
            Ok(b.build()?)
        };
        let (shared, each) = (scene_with(false)?, scene_with(true)?);
        assert_eq!(shared.triangles(), each.triangles());
        for t in 0..shared.triangle_count() {
            assert!(shared.vertex_normals(t).is_some(), "triangle {t} is flat");
            assert_eq!(
                shared.vertex_normals(t),
                each.vertex_normals(t),
                "triangle {t}"
            );
        }
        assert_eq!(shared.validate_surfaces(), Ok(()));
        // Three entries a triangle given one by one, about one a triangle
        // from the mesh (a closed surface has half as many vertices as
        // triangles, plus the sphere's seam).
        let (shared_bytes, each_bytes) = (
            shared.vertex_normals.memory_bytes(),
            each.vertex_normals.memory_bytes(),
        );
        assert!(2 * shared_bytes < each_bytes, "{shared_bytes} {each_bytes}");
        Ok(())
    }

    /// The derived checks run by default in debug builds only, and
    /// skipping them changes neither the scene nor the checks of the input.
    /// Negative control: a triangle of an unknown material is refused with
    /// the checks skipped.
    #[test]
    fn skipping_the_derived_checks_changes_neither_the_scene_nor_the_input_checks()
    -> Result<(), Box<dyn std::error::Error>> {
        use super::{DerivedChecks, SceneBuilder, SceneError, camera::Camera};
        use crate::ids::MaterialId;
        use glam::Vec3;
        assert_eq!(
            DerivedChecks::default() == DerivedChecks::Full,
            cfg!(debug_assertions)
        );
        let cornell = |checks| -> Result<super::Scene, Box<dyn std::error::Error>> {
            let mut b = super::builtin::cornell_builder(SpectralRange::VISIBLE)?;
            b.set_derived_checks(checks);
            Ok(b.build()?)
        };
        let (full, skipped) = (cornell(DerivedChecks::Full)?, cornell(DerivedChecks::Skip)?);
        assert_eq!(full.triangles(), skipped.triangles());
        assert_eq!(full.bvh().node_count(), skipped.bvh().node_count());
        assert_eq!(skipped.bvh().validate(&skipped.triangles()), Ok(()));
        assert_eq!(skipped.validate_surfaces(), Ok(()));
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        b.set_derived_checks(DerivedChecks::Skip);
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], MaterialId(7));
        b.set_camera(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0)?);
        assert!(matches!(
            b.build(),
            Err(SceneError::UnknownMaterial(MaterialId(7)))
        ));
        Ok(())
    }

    #[test]
    fn texture_coordinates_are_stored_from_the_first_non_zero_ones()
    -> Result<(), Box<dyn std::error::Error>> {
        use super::{SceneBuilder, camera::Camera};
        use glam::{Vec2, Vec3};
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let grey = b.add_spectrum("grey", crate::spectra::SpectrumSource::Constant(0.5))?;
        let m = b.add_material(crate::shading::material::Material::lambert("grey", grey));
        let triangle = [Vec3::ZERO, Vec3::X, Vec3::Y];
        b.add_triangle(triangle, m);
        assert!(b.uvs.is_empty());
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        b.add_triangle_uv(triangle.map(|v| v + Vec3::Z), uv, m);
        b.add_triangle(triangle.map(|v| v - Vec3::Z), m);
        b.set_camera(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0)?);
        let scene = b.build()?;
        let stored: Vec<Option<&[Vec2; 3]>> = (0..3).map(|t| scene.uvs(t)).collect();
        assert_eq!(stored, [None, Some(&uv), None]);
        assert!(scene.has_uvs());
        assert_eq!(scene.validate_surfaces(), Ok(()));
        Ok(())
    }

    #[test]
    fn stale_derived_data_fails_validation() -> Result<(), Box<dyn std::error::Error>> {
        let scene = cornell_box(SpectralRange::VISIBLE)?;
        scene.validate_surfaces()?;
        let mut stale = cornell_box(SpectralRange::VISIBLE)?;
        stale.emitters = scene.bvh.subset(&[0, 1]);
        assert!(stale.validate_surfaces().is_err());
        let mut stale = cornell_box(SpectralRange::VISIBLE)?;
        stale.packed_surfaces = PackedSurfaces::new(
            &(0..stale.triangle_count())
                .filter_map(|index| {
                    let record = stale.surface(index)?;
                    // Triangles 0 and 8 exchange their materials.
                    let other = stale.material_of(if index == 0 { 8 } else { 0 })?;
                    Some(if index == 0 || index == 8 {
                        Surface {
                            material: other,
                            ..record
                        }
                    } else {
                        record
                    })
                })
                .collect::<Vec<_>>(),
        );
        assert!(stale.validate_surfaces().is_err());
        let mut stale = cornell_box(SpectralRange::VISIBLE)?;
        stale.uvs.push_unnamed([glam::Vec2::ZERO; 3]);
        assert!(stale.validate_surfaces().is_err());
        let mut stale = cornell_box(SpectralRange::VISIBLE)?;
        stale.vertex_normals.push(glam::Vec3::Z);
        stale.vertex_normals.scale_table(2.0);
        assert!(stale.validate_surfaces().is_err());
        Ok(())
    }
}
