//! `[[meshes]]` and `[[quads]]`: OBJ files with their material mapping, and
//! quads given by their corners.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::construction::FaceMaterials;
use crate::scene_file::toml_reader::Item;
use glam::Vec3;
use std::collections::HashMap;

impl Loader<'_> {
    /// `[[meshes]]`: each an OBJ with `material` (every face) or
    /// `materials` (per MTL name, the rest converted from the MTL).
    pub(super) fn meshes_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for mesh in item.array(&self.src)? {
            let table = mesh.table(&self.src)?;
            table.allow(&self.src, &["obj", "material", "materials"], "a mesh")?;
            let obj_item = table.require(&self.src, "obj", "a mesh needs `obj = \"file.obj\"`")?;
            let path = self.file(&obj_item)?;
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
                        &path,
                        &FaceMaterials::Mapped(mapped),
                    )?;
                    for (mtl, target) in spans {
                        if !info.mtl_names.contains(&mtl) {
                            self.cx.warn(
                                &target.spot(),
                                format!("the MTL of {} has no material \"{mtl}\"", path.display()),
                            );
                        }
                    }
                    continue;
                }
            };
            self.cx.load_obj(&obj_item.spot(), &path, &faces)?;
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
