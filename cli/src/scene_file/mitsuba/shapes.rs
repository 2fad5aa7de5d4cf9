//! Shapes as Mitsuba 3.9.1 reads them.
//!
//! * `obj`, `ply`, `serialized` (`shape_index`): one mesh per file (an
//!   OBJ's objects and groups are merged, its MTL ignored, as Mitsuba's
//!   loader does); smooth shading from the file's vertex normals or, when
//!   it has none, from angle-weighted face normals, unless `face_normals`;
//!   `flip_normals`; `to_world`. Texture coordinates keep Mitsuba's
//!   convention (`v = 0` at an image's top row): an OBJ's `v` is flipped
//!   on load (`flip_tex_coords`, default true for OBJ and false for PLY, as
//!   Mitsuba).
//! * `sphere` (`center`, `radius`), `rectangle`, `cube`, `disk`,
//!   `cylinder` (`p0`, `p1`, `radius`; an open tube): Mitsuba's local
//!   shapes (`simd_tracer::scene::analytic`), tessellated finely enough
//!   that the surface is within 10⁻³ radii of the exact one.
//! * `shapegroup` (with an `id`; its shapes are kept, not placed) and
//!   `instance` (a `<ref>` to a shapegroup and `to_world`): a shapegroup
//!   placed by several instances is kept once and instanced, one placed
//!   once is flattened into the triangle list
//!   (`simd_tracer::scene::instances`).
//!
//! Each shape takes a nested or referenced BSDF (default: a one-sided
//! diffuse of reflectance 0.5, as Mitsuba, or of reflectance 0 when the
//! shape emits) and an optional nested or referenced `area` emitter; one
//! BSDF with one emitter is one scene material.

use super::document::Element;
use super::properties::{Object, Property};
use super::{Importer, MaterialKey, address};
use crate::error::CliError;
use crate::scene_file::construction::{MeshFormat, MeshParts, Placement};
use glam::{Vec2, Vec3};
use simd_tracer::ids::MaterialId;
use simd_tracer::scene::analytic::{
    DEFAULT_SAG, cube_mesh, cylinder_mesh, cylinder_placement, disk_mesh, rectangle_mesh,
    segments_for_sag, sphere_mesh,
};
use simd_tracer::scene::mesh::MeshData;
use simd_tracer::scene::transform::Transform;

/// Mesh formats read from files.
const FILE_SHAPES: &[&str] = &["obj", "ply", "serialized"];
/// Shapes built in.
const ANALYTIC_SHAPES: &[&str] = &["sphere", "rectangle", "cube", "disk", "cylinder"];

/// What a shape is attached to: its BSDF and area emitter elements.
struct Attached<'e> {
    bsdf: Option<&'e Element>,
    emitter: Option<&'e Element>,
}

impl<'e> Importer<'e, '_> {
    /// A top-level `<shape>`.
    pub(super) fn shape(&mut self, e: &'e Element) -> Result<(), CliError> {
        let object = Object::new(e)?;
        match object.plugin {
            "shapegroup" => self.shapegroup(&object),
            "instance" => self.instance(&object),
            _ => {
                let Some((parts, placement)) = self.mesh_shape(&object)? else {
                    return Ok(());
                };
                let spot = Self::spot(e, object.describe());
                self.cx.place(&spot, parts, &placement, None)
            }
        }
    }

    /// The BSDF and emitter of a shape (nested or referenced).
    fn attached(&mut self, object: &Object<'e>) -> Result<Attached<'e>, CliError> {
        let mut attached = Attached {
            bsdf: None,
            emitter: None,
        };
        for p in object.objects() {
            let element = self.object_of(p, &["bsdf", "emitter", "medium", "texture", "shape"])?;
            let slot = match element.tag.as_str() {
                "bsdf" => &mut attached.bsdf,
                "emitter" => &mut attached.emitter,
                "medium" if self.options.lenient => {
                    self.warn_at(element, "media are not supported; ignored (--lenient)");
                    continue;
                }
                other => {
                    return Err(p.error(format!(
                        "a <{other}> inside a {} is not supported",
                        object.describe()
                    )));
                }
            };
            if slot.is_some() {
                return Err(p.error(format!(
                    "a shape takes one <{}>, this one has two",
                    element.tag
                )));
            }
            *slot = Some(element);
        }
        Ok(attached)
    }

    /// The material of a shape's BSDF and emitter (one per pair).
    fn shape_material(&mut self, attached: &Attached<'e>) -> Result<MaterialId, CliError> {
        let key: MaterialKey = (
            attached.bsdf.map_or(0, address),
            attached.emitter.map_or(0, address),
        );
        if let Some(&id) = self.materials.get(&key) {
            return Ok(id);
        }
        let built = match (attached.bsdf, attached.emitter) {
            // Mitsuba: an emitter without a BSDF sits on a black diffuse one.
            (None, Some(_)) => self.black_bsdf()?,
            (bsdf, _) => self.bsdf(bsdf)?,
        };
        let emission = match attached.emitter {
            Some(emitter) => self.area_emission(emitter)?,
            None => None,
        };
        let material = built.material(emission);
        let id = self.cx.add_material(material);
        self.materials.insert(key, id);
        Ok(id)
    }

    /// A mesh or analytic shape: its parts and placement (`None`: skipped
    /// under `--lenient`).
    fn mesh_shape(
        &mut self,
        object: &Object<'e>,
    ) -> Result<Option<(MeshParts, Placement)>, CliError> {
        let plugin = object.plugin;
        if !FILE_SHAPES.contains(&plugin) && !ANALYTIC_SHAPES.contains(&plugin) {
            self.unsupported(object.element, "the shape is skipped")?;
            return Ok(None);
        }
        let attached = self.attached(object)?;
        let to_world = object.transform("to_world")?;
        let flip_normals = object.boolean("flip_normals", false)?;
        let face_normals = object.boolean("face_normals", false)?;
        let (mesh, local) = match plugin {
            "sphere" => {
                let center = object.vector("center")?.unwrap_or(Vec3::ZERO);
                let radius = object.float("radius", 1.0)?;
                if radius <= 0.0 {
                    return Err(object.error(format!("radius {radius}: must be > 0")));
                }
                let local = Transform::scale(Vec3::splat(radius as f32))
                    .and_then(|s| s.then(&Transform::translate(center)?))
                    .map_err(|err| object.error(err))?;
                (sphere_mesh(segments_for_sag(DEFAULT_SAG)), local)
            }
            "disk" => (
                disk_mesh(segments_for_sag(DEFAULT_SAG)),
                Transform::IDENTITY,
            ),
            "cylinder" => {
                let p0 = object.vector("p0")?.unwrap_or(Vec3::ZERO);
                let p1 = object.vector("p1")?.unwrap_or(Vec3::Z);
                let radius = object.float("radius", 1.0)?;
                let local = cylinder_placement(p0, p1, radius as f32).map_err(|err| {
                    object.error(format!("p0 {p0}, p1 {p1}, radius {radius}: {err}"))
                })?;
                (cylinder_mesh(segments_for_sag(DEFAULT_SAG)), local)
            }
            "rectangle" => (rectangle_mesh(), Transform::IDENTITY),
            "cube" => (cube_mesh(), Transform::IDENTITY),
            _ => (self.mesh_file(object, face_normals)?, Transform::IDENTITY),
        };
        let transform = local.then(&to_world).map_err(|err| object.error(err))?;
        let material = self.shape_material(&attached)?;
        self.check_unused(object)?;
        Ok(Some((
            vec![(mesh, material)],
            Placement {
                transform,
                flip_normals,
                face_normals,
                sphere: plugin == "sphere",
            },
        )))
    }

    /// The mesh of an `obj`, `ply` or `serialized` shape.
    fn mesh_file(&mut self, object: &Object<'e>, face_normals: bool) -> Result<MeshData, CliError> {
        let path = object.filename()?;
        let format = match object.plugin {
            "obj" => MeshFormat::Obj,
            "ply" => MeshFormat::Ply,
            _ => {
                let index = object.integer("shape_index", 0)?;
                let shape_index = u32::try_from(index)
                    .map_err(|_| object.error(format!("shape_index {index}: must be >= 0")))?;
                MeshFormat::Serialized { shape_index }
            }
        };
        let spot = Self::spot(object.element, object.describe());
        let mut mesh = self.cx.read_mesh(&spot, &path, format)?;
        let flip_v = match object.plugin {
            "obj" => object.boolean("flip_tex_coords", true)?,
            "ply" => object.boolean("flip_tex_coords", false)?,
            _ => false,
        };
        if flip_v {
            for uv in &mut mesh.uvs {
                *uv = Vec2::new(uv.x, 1.0 - uv.y);
            }
        }
        if !face_normals {
            mesh.compute_vertex_normals();
        }
        Ok(mesh)
    }

    /// `shapegroup`: its shapes kept under its id for instances.
    fn shapegroup(&mut self, object: &Object<'e>) -> Result<(), CliError> {
        let Some(id) = object.element.attr("id") else {
            return Err(object.error("needs an `id` (instances refer to it)"));
        };
        let mut parts = MeshParts::new();
        for p in object.objects() {
            let element = self.object_of(p, &["shape"])?;
            let inner = Object::new(element)?;
            if matches!(inner.plugin, "shapegroup" | "instance") {
                return Err(inner.error("cannot be nested in a shapegroup"));
            }
            let Some((inner_parts, placement)) = self.mesh_shape(&inner)? else {
                continue;
            };
            // Bake each shape's own placement into its part: the group is
            // placed again by each instance's transform.
            for (mesh, material) in inner_parts {
                parts.push((bake(mesh, &placement), material));
            }
        }
        self.check_unused(object)?;
        self.cx.keep_for_instances(id, parts);
        Ok(())
    }

    /// `instance`: a shapegroup placed by `to_world`.
    fn instance(&mut self, object: &Object<'e>) -> Result<(), CliError> {
        let refs: Vec<&Property<'e>> = object.objects();
        let [group] = refs.as_slice() else {
            return Err(object.error("needs exactly one <ref id=\"…\"/> to a shapegroup"));
        };
        let element = self.object_of(group, &["shape"])?;
        let id = match (element.attr("type"), element.attr("id")) {
            (Some("shapegroup"), Some(id)) => id,
            _ => return Err(group.error("an instance refers to a shapegroup")),
        };
        let placement = Placement {
            transform: object.transform("to_world")?,
            flip_normals: false,
            face_normals: false,
            sphere: false,
        };
        self.check_unused(object)?;
        let spot = Self::spot(object.element, object.describe());
        if !self.cx.instance(&spot, id, &placement, None)? {
            return Err(group.error(format!(
                "shapegroup \"{id}\" must come before its instances"
            )));
        }
        Ok(())
    }
}

/// `mesh` with `placement` applied to its vertices and normals (for the
/// shapes of a shapegroup, placed again by each instance).
fn bake(mut mesh: MeshData, placement: &Placement) -> MeshData {
    let t = &placement.transform;
    for p in &mut mesh.positions {
        *p = t.point(*p);
    }
    let sign = if placement.flip_normals { -1.0 } else { 1.0 };
    if placement.face_normals {
        mesh.normals.clear();
    }
    for n in &mut mesh.normals {
        *n = t.normal(*n).map_or(Vec3::ZERO, |n| sign * n);
    }
    // A mirroring transform or a flip turns the winding's front face over;
    // keep the front where the normals point by swapping two corners.
    if t.flips_handedness() != placement.flip_normals {
        for tri in &mut mesh.triangles {
            tri.swap(1, 2);
        }
    }
    mesh
}
