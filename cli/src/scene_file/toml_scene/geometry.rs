//! `[[meshes]]`, `[[shapes]]`, `[[instances]]` and `[[quads]]`: mesh files
//! (OBJ with their material mapping, PLY, Mitsuba `serialized`), Mitsuba's
//! analytic shapes, copies of named meshes, and quads given by their
//! corners; meshes and shapes placed by a `transform`.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::construction::{FaceMaterials, MeshFormat, Placement};
use crate::scene_file::toml_reader::{Item, Table};
use glam::Vec3;
use simd_tracer::ids::MaterialId;
use simd_tracer::scene::analytic::{
    DEFAULT_SAG, cube_mesh, cylinder_mesh, cylinder_placement, disk_mesh, rectangle_mesh,
    segments_for_sag, sphere_mesh,
};
use simd_tracer::scene::transform::Transform;
use std::collections::HashMap;

/// The mesh-file keys: exactly one of them names the file.
const MESH_FILES: &[&str] = &["obj", "ply", "serialized"];

impl Loader<'_> {
    /// `transform`, `flip_normals` and `face_normals` of a mesh or shape,
    /// with `local` (the shape's own placement) applied first.
    fn placement(&self, table: &Table<'_, '_>, local: Transform) -> Result<Placement, CliError> {
        let src = &self.src;
        let flag = |key: &str| -> Result<bool, CliError> {
            table.get(key).map_or(Ok(false), |i| i.boolean(src))
        };
        let transform = match table.get("transform") {
            Some(item) => local
                .then(&self.transform(&item)?)
                .map_err(|e| item.err(src, e))?,
            None => local,
        };
        Ok(Placement {
            transform,
            flip_normals: flag("flip_normals")?,
            face_normals: flag("face_normals")?,
            sphere: false,
        })
    }

    /// `name`, if given (unique among the meshes kept for instances), and
    /// `instanced_only` (which needs `name`).
    fn instancing<'t>(&self, table: &Table<'t, '_>) -> Result<(Option<&'t str>, bool), CliError> {
        let name = match table.get("name") {
            Some(item) => {
                let name = item.string(&self.src)?;
                if self.cx.has_named_mesh(name) {
                    return Err(
                        item.err(&self.src, format!("a mesh named \"{name}\" exists already"))
                    );
                }
                Some(name)
            }
            None => None,
        };
        let only = match table.get("instanced_only") {
            Some(i) => {
                let only = i.boolean(&self.src)?;
                if only && name.is_none() {
                    return Err(i.err(&self.src, "needs `name` (instances refer to it)"));
                }
                only
            }
            None => false,
        };
        Ok((name, only))
    }

    /// `[[meshes]]`: each one mesh file (`obj`, `ply` or `serialized` with
    /// `shape_index`), placed by `transform`; an OBJ with `material` (every
    /// face) or `materials` (per MTL name, the rest converted from the
    /// MTL), a PLY or serialized mesh with `material`. `name` keeps it for
    /// `[[instances]]`; `instanced_only = true` keeps it without placing it.
    pub(super) fn meshes_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for mesh in item.array(&self.src)? {
            let table = mesh.table(&self.src)?;
            table.allow(
                &self.src,
                &[
                    "obj",
                    "ply",
                    "serialized",
                    "shape_index",
                    "material",
                    "materials",
                    "transform",
                    "flip_normals",
                    "face_normals",
                    "name",
                    "instanced_only",
                ],
                "a mesh",
            )?;
            let files: Vec<(&str, Item<'_, '_>)> = MESH_FILES
                .iter()
                .filter_map(|&key| table.get(key).map(|i| (key, i)))
                .collect();
            let [(kind, file_item)] = files.as_slice() else {
                return Err(table.err(
                    &self.src,
                    "a mesh needs exactly one of `obj`, `ply`, `serialized` (the file)",
                ));
            };
            let path = self.file(file_item)?;
            let placement = self.placement(&table, Transform::IDENTITY)?;
            let (name, instanced_only) = self.instancing(&table)?;
            if let (Some(index), false) = (table.get("shape_index"), *kind == "serialized") {
                return Err(index.err(&self.src, "only a `serialized` mesh has shapes"));
            }
            if *kind == "obj" {
                if name.is_some() {
                    return Err(table.err(
                        &self.src,
                        "`name` (instancing) is for PLY and serialized meshes and shapes",
                    ));
                }
                self.obj_mesh(&table, file_item, &path, &placement)?;
                continue;
            }
            if let Some(map) = table.get("materials") {
                return Err(map.err(&self.src, "per-MTL `materials` only apply to OBJ files"));
            }
            let format = match *kind {
                "ply" => MeshFormat::Ply,
                _ => MeshFormat::Serialized {
                    shape_index: match table.get("shape_index") {
                        Some(i) => i.integer(&self.src, 0, i64::from(u32::MAX))? as u32,
                        None => 0,
                    },
                },
            };
            let material = self.material_ref(&table.require(
                &self.src,
                "material",
                "a PLY or serialized mesh needs `material`",
            )?)?;
            let mut data = self.cx.read_mesh(&file_item.spot(), &path, format)?;
            // As Mitsuba: smooth unless `face_normals`, from the file's
            // normals or, without them, from the faces.
            if !placement.face_normals {
                data.compute_vertex_normals();
            }
            let parts = vec![(data, material)];
            match name {
                Some(name) if instanced_only => self.cx.keep_for_instances(name, parts),
                _ => self.cx.place(&file_item.spot(), parts, &placement, name)?,
            }
        }
        Ok(())
    }

    /// An OBJ of `[[meshes]]` with its material mapping.
    fn obj_mesh(
        &mut self,
        table: &Table<'_, '_>,
        obj_item: &Item<'_, '_>,
        path: &std::path::Path,
        placement: &Placement,
    ) -> Result<(), CliError> {
        let faces = match (table.get("material"), table.get("materials")) {
            (Some(_), Some(map)) => {
                return Err(map.err(
                    &self.src,
                    "give either `material` (every face) or `materials` (per MTL name), not both",
                ));
            }
            (Some(material), None) => FaceMaterials::All(self.material_ref(&material)?),
            (None, map) => {
                let mut mapped = HashMap::new();
                let mut spans = Vec::new();
                if let Some(map) = map {
                    for (mtl, target) in map.table(&self.src)?.entries() {
                        mapped.insert(mtl.to_string(), self.material_ref(&target)?);
                        spans.push((mtl.to_string(), target));
                    }
                }
                let info = self.cx.load_obj(
                    &obj_item.spot(),
                    path,
                    &FaceMaterials::Mapped(mapped),
                    placement,
                )?;
                for (mtl, target) in spans {
                    if !info.mtl_names.contains(&mtl) {
                        self.cx.warn(
                            &target.spot(),
                            format!("the MTL of {} has no material \"{mtl}\"", path.display()),
                        );
                    }
                }
                return Ok(());
            }
        };
        self.cx
            .load_obj(&obj_item.spot(), path, &faces, placement)?;
        Ok(())
    }

    /// `[[shapes]]`: Mitsuba's analytic shapes, tessellated
    /// (`simd_tracer::scene::analytic`): `type = "sphere"` (`center`,
    /// `radius`), `"rectangle"`, `"cube"`, `"disk"`, `"cylinder"` (`p0`,
    /// `p1`, `radius`: an open tube along `p0 → p1`), each with `material`,
    /// `transform`, `flip_normals`, and `sag` (sphere, disk and cylinder:
    /// the largest distance of the tessellation from the surface, in
    /// radii).
    pub(super) fn shapes_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for shape in item.array(&self.src)? {
            let src = &self.src;
            let table = shape.table(src)?;
            table.allow(
                src,
                &[
                    "type",
                    "center",
                    "radius",
                    "p0",
                    "p1",
                    "sag",
                    "material",
                    "transform",
                    "flip_normals",
                    "name",
                    "instanced_only",
                ],
                "a shape",
            )?;
            let kind_item =
                table.require(src, "type", "sphere, rectangle, cube, disk or cylinder")?;
            let kind = kind_item.string(src)?;
            let curved = matches!(kind, "sphere" | "disk" | "cylinder");
            let sag = match table.get("sag") {
                Some(i) if curved => {
                    let sag = i.number(src)?;
                    if !(sag > 0.0 && sag < 1.0) {
                        return Err(
                            i.err(src, "must be between 0 and 1 (a fraction of the radius)")
                        );
                    }
                    sag as f32
                }
                Some(i) => {
                    return Err(i.err(src, "only a sphere, a disk or a cylinder is tessellated"));
                }
                None => DEFAULT_SAG,
            };
            // Each shape's own keys, refused on the others.
            let owners: [(&str, &[&str]); 4] = [
                ("center", &["sphere"]),
                ("radius", &["sphere", "cylinder"]),
                ("p0", &["cylinder"]),
                ("p1", &["cylinder"]),
            ];
            for (key, kinds) in owners {
                if let (Some(i), false) = (table.get(key), kinds.contains(&kind)) {
                    return Err(i.err(
                        src,
                        "only a sphere has `center`, a cylinder `p0` and `p1`, and those two `radius`",
                    ));
                }
            }
            let radius = match table.get("radius") {
                Some(r) => {
                    let value = r.number(src)?;
                    if value <= 0.0 || (value as f32) <= 0.0 {
                        return Err(r.err(src, "must be > 0"));
                    }
                    if !(value as f32).is_finite() {
                        return Err(r.err(src, "too large for single precision"));
                    }
                    value as f32
                }
                None => 1.0,
            };
            let (mesh, local) = match kind {
                "sphere" => {
                    let center = table
                        .get("center")
                        .map_or(Ok(Vec3::ZERO), |c| c.vec3(src))?;
                    let local = Transform::scale(Vec3::splat(radius))
                        .and_then(|s| s.then(&Transform::translate(center)?))
                        .map_err(|e| table.err(src, e))?;
                    (sphere_mesh(segments_for_sag(sag)), local)
                }
                "disk" => (disk_mesh(segments_for_sag(sag)), Transform::IDENTITY),
                "cylinder" => {
                    let p0_item = table.get("p0");
                    let p0 = p0_item.as_ref().map_or(Ok(Vec3::ZERO), |p| p.vec3(src))?;
                    let p1_item = table.get("p1");
                    let p1 = p1_item.as_ref().map_or(Ok(Vec3::Z), |p| p.vec3(src))?;
                    let local = cylinder_placement(p0, p1, radius).map_err(|e| match &p1_item {
                        Some(p) => p.err(src, e),
                        None => table.err(src, e),
                    })?;
                    (cylinder_mesh(segments_for_sag(sag)), local)
                }
                "rectangle" => (rectangle_mesh(), Transform::IDENTITY),
                "cube" => (cube_mesh(), Transform::IDENTITY),
                other => {
                    return Err(kind_item.err(
                        src,
                        format!(
                            "unknown shape \"{other}\" (sphere, rectangle, cube, disk, cylinder)"
                        ),
                    ));
                }
            };
            let material = self.material_ref(&table.require(
                &self.src,
                "material",
                "a shape needs `material`",
            )?)?;
            // A coarse sphere stays triangles (`MeshPlacement::sphere`).
            let placement = Placement {
                sphere: kind == "sphere" && sag <= DEFAULT_SAG,
                ..self.placement(&table, local)?
            };
            let (name, only) = self.instancing(&table)?;
            let parts = vec![(mesh, material)];
            match name {
                Some(name) if only => self.cx.keep_for_instances(name, parts),
                _ => self.cx.place(&kind_item.spot(), parts, &placement, name)?,
            }
        }
        Ok(())
    }

    /// `[[instances]]`: `mesh` (the `name` of a mesh or shape), placed by
    /// `transform` (after the mesh's own file coordinates; the named mesh's
    /// transform is not applied), optionally all in `material`.
    pub(super) fn instances_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for instance in item.array(&self.src)? {
            let table = instance.table(&self.src)?;
            table.allow(
                &self.src,
                &[
                    "mesh",
                    "transform",
                    "material",
                    "flip_normals",
                    "face_normals",
                ],
                "an instance",
            )?;
            let mesh_item = table.require(&self.src, "mesh", "the `name` of a mesh or shape")?;
            let name = mesh_item.string(&self.src)?;
            let material: Option<MaterialId> = match table.get("material") {
                Some(m) => Some(self.material_ref(&m)?),
                None => None,
            };
            let placement = self.placement(&table, Transform::IDENTITY)?;
            if !self
                .cx
                .instance(&mesh_item.spot(), name, &placement, material)?
            {
                return Err(mesh_item.err(
                    &self.src,
                    format!(
                        "no mesh or shape named \"{name}\" (give it `name` before the instances)"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `[[quads]]`: four corners and a material.
    pub(super) fn quads_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for quad in item.array(&self.src)? {
            let table = quad.table(&self.src)?;
            table.allow(&self.src, &["vertices", "material"], "a quad")?;
            let vertices_item = table.require(&self.src, "vertices", "four [x, y, z] corners")?;
            let corners = vertices_item.array(&self.src)?;
            if corners.len() != 4 {
                return Err(vertices_item.err(
                    &self.src,
                    format!("a quad needs 4 vertices, found {}", corners.len()),
                ));
            }
            let mut v = [Vec3::ZERO; 4];
            for (slot, corner) in v.iter_mut().zip(&corners) {
                *slot = corner.vec3(&self.src)?;
            }
            let material = self.material_ref(&table.require(
                &self.src,
                "material",
                "a quad needs `material`",
            )?)?;
            self.cx.quad(&vertices_item.spot(), v, material);
        }
        Ok(())
    }
}
