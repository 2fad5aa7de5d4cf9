//! Instances: placed copies of shared meshes, found through a two-level
//! tree.
//!
//! Each distinct mesh has one bottom-level [`Bvh`] built in its own
//! (object) coordinates; each instance is a world-to-object affine map
//! `W` and the index of its mesh. The top-level tree is an obvhs [`Bvh2`]
//! over the instances' world bounds (the box of the mesh's vertices mapped
//! into the world, padded by [`BOUNDS_PAD`]). A ray `o + t d` reaches an
//! instance's mesh as `W o + t (W_lin d)`: the direction is not
//! normalised, so the object-space `t` *is* the world `t`, and the hit
//! found in the mesh's tree is the world hit with the same barycentric
//! weights. Rays are mapped component by component in one fixed order
//! (`x' = w00 x + w01 y + w02 z + w03`, no fused operations), the same for
//! one ray and for 8 lanes, so the packet and per-ray paths hand the mesh
//! identical rays.
//!
//! Queries mirror those of the flat soup ([`Bvh`]) and continue a hit the
//! soup already found (`t_max` is the soup's `t`, so ties go to the soup):
//!
//! * coherent packets ([`InstanceBvh::intersect_packet`], camera rays):
//!   the 8 rays traverse the top-level tree together (the same node loop as
//!   the soup's packets, [`traverse_nodes`], on a stack of its own), and
//!   each instance leaf maps the packet's live lanes into the object and
//!   runs the mesh's traversal with the lanes' current `t_max`: as a
//!   packet through its binary tree for meshes up to
//!   [`super::WIDE_MIN_TRIANGLES`], one lane at a time through its 8-wide
//!   tree above (as its bounce rays go). An instanced mesh is small on the
//!   screen for its detail, so a packet's rays part early in its tree:
//!   on the instanced bunnies (69 453 triangles each) the wide tree made
//!   the whole render 4 % faster (`docs/performance.md`);
//! * incoherent rays ([`InstanceBvh::intersect_lanes`],
//!   [`InstanceBvh::occluded_lanes`], bounces and shadows): one ray at a
//!   time through the top level collapsed to an 8-wide tree
//!   ([`super::top_level`]: 8 instance boxes per slab test, nearest first,
//!   early exit for shadows) and each mesh's 8-wide tree, as the soup's
//!   large trees answer them;
//! * the oracle ([`InstanceBvh::intersect`], [`InstanceBvh::occluded`]):
//!   obvhs' per-ray traversal at both levels with the scalar triangle test.
//!
//! # One instance per leaf
//!
//! obvhs' presets end their builds by collapsing subtrees of up to 8
//! primitives into one leaf wherever its cost model prices the leaf below
//! the subtree. For triangles, tested 8 at a time, that is right; for
//! instances it is not: the instances of a leaf are visited one after the
//! other without a box test of their own, each with a change of
//! coordinates and a walk through its mesh from the root. With the preset
//! the 36 instanced bunnies of the benchmark scenes sat in leaves of
//! several instances, and a bounce ray entered 5.76 instances and visited
//! 10.27 mesh nodes; with one instance per leaf ([`TOP_LEVEL_BUILD`]) every
//! instance's box is tested in its parent's slab test and a ray enters
//! 1.02 instances and visits 5.45 mesh nodes, for 2.22 top-level nodes
//! instead of 1.00 (`docs/performance.md`, "One instance per top-level
//! leaf"). The hits are the same: leaves change which instances are
//! visited, not what a visited instance answers, and every instance the
//! ray meets before its closest hit is still visited.
//!
//! Why two levels instead of copying the mesh into the world per instance:
//! the memory of a copy grows with its triangles (hundreds of bytes each),
//! an instance's with one record; the price is a change of coordinates per
//! instance a ray visits, and a normal mapped back per hit (by the
//! inverse transpose, in [`crate::scene`]).

use super::build::tree_depth;
use super::packet_traversal::{PacketRays, traverse_nodes};
use super::top_level::TopLevel;
use super::{Bvh, InlineStack, NodeStack, Traversal, WideStack};
use crate::packet::{PacketHit, Ray, RayPacket};
use crate::simd::LaneMask;
use core::ops::{Add, Mul};
use glam::{Affine3A, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use obvhs::ray::RayHit;
use rayon::prelude::*;
use std::cell::RefCell;
use std::time::Duration;
use wide::f32x8;

/// Relative padding of an instance's world box: its extent and the
/// magnitude of its corners times this. The box is the image of the mesh's
/// vertices computed in `f32`; a ray that meets the mesh in object space
/// right at an extreme vertex could miss the unpadded box by a rounding
/// step of the forward map. 16 `f32` epsilons cover the three rounded
/// products and sums of each coordinate with room to spare.
pub const BOUNDS_PAD: f32 = 16.0 * f32::EPSILON;

/// The top-level tree's build: obvhs' medium preset with one instance per
/// leaf (module docs, "One instance per leaf").
const TOP_LEVEL_BUILD: BvhBuildParams = BvhBuildParams {
    max_prims_per_leaf: 1,
    ..BvhBuildParams::medium_build()
};

/// One instance as the top level holds it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Placed {
    /// World to object, row by row (`x' = r0 · (x, y, z, 1)`).
    rows: [[f32; 4]; 3],
    /// Index of its mesh in [`InstanceBvh::meshes`].
    mesh: u32,
}

/// An instance to place: its mesh and its world-to-object map.
#[derive(Debug, Clone, Copy)]
pub struct InstanceInput {
    /// Index of the mesh in the list given to [`InstanceBvh::build`].
    pub mesh: u32,
    /// Object to world.
    pub object_to_world: Affine3A,
}

/// A closest hit on an instance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstanceHit {
    /// Hit distance in units of the world ray's direction.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
    /// The triangle, in the order of its mesh's input.
    pub triangle: u32,
    /// The instance, in the order given to [`InstanceBvh::build`].
    pub instance: u32,
}

/// The two-level structure: meshes, instances, top-level tree.
#[derive(Clone)]
pub struct InstanceBvh {
    /// One bottom-level tree per distinct mesh, in object coordinates.
    meshes: Vec<Bvh>,
    /// The instances, in the caller's order.
    placed: Vec<Placed>,
    /// Object to world of each instance (for validation and bounds).
    object_to_world: Vec<Affine3A>,
    /// The top-level tree: leaves index `top.primitive_indices`, which
    /// index `placed`.
    top: Bvh2,
    /// `top` collapsed to 8 children per node, for single rays.
    top_wide: TopLevel,
}

/// `m · (x, y, z) (+ m3 if `point`)`, one fixed order of operations for
/// `f32` and `f32x8` alike.
#[inline(always)]
fn map<T>(rows: &[[f32; 4]; 3], v: [T; 3], point: bool) -> [T; 3]
where
    T: Copy + Mul<Output = T> + Add<Output = T> + From<f32>,
{
    rows.map(|r| {
        let linear = v[0] * T::from(r[0]) + v[1] * T::from(r[1]) + v[2] * T::from(r[2]);
        if point {
            linear + T::from(r[3])
        } else {
            linear
        }
    })
}

/// The rows of `affine`'s matrix with its translation as the fourth column.
fn rows_of(affine: &Affine3A) -> [[f32; 4]; 3] {
    let (m, t) = (affine.matrix3, affine.translation);
    core::array::from_fn(|i| [m.x_axis[i], m.y_axis[i], m.z_axis[i], t[i]])
}

/// The world box of `mesh`'s kept triangles under `object_to_world`,
/// padded by [`BOUNDS_PAD`] (`None` for a mesh without triangles).
fn world_box(mesh: &[[Vec3; 3]], object_to_world: &Affine3A) -> Option<Aabb> {
    let mut found = false;
    let mut aabb = Aabb::INVALID;
    for v in mesh.iter().flatten() {
        aabb.extend(Vec3A::from(object_to_world.transform_point3(*v)));
        found = true;
    }
    found.then(|| {
        let magnitude = aabb.min.abs().max(aabb.max.abs());
        let pad = (aabb.max - aabb.min + magnitude) * BOUNDS_PAD;
        Aabb::new(aabb.min - pad, aabb.max + pad)
    })
}

impl core::fmt::Debug for InstanceBvh {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("InstanceBvh")
            .field("meshes", &self.meshes)
            .field("instances", &self.placed.len())
            .field("top_nodes", &self.top.nodes.len())
            .finish()
    }
}

type TopStack = NodeStack;

thread_local! {
    /// The top-level packet traversal's stack (the mesh traversals inside
    /// its leaves use the soup's per-thread stack).
    static TOP_STACK: RefCell<TopStack> = RefCell::new(InlineStack::new((0, f32x8::ZERO)));
}

impl InstanceBvh {
    /// Builds the top level over `instances` of `meshes` (each mesh's tree
    /// built from `mesh_triangles` of the same index, which give the
    /// instances' world bounds). `Err` for an instance of a mesh that does
    /// not exist, a map that is not finite or not invertible, or meshes and
    /// triangle lists of different counts.
    pub fn build(
        meshes: Vec<Bvh>,
        mesh_triangles: &[&[[Vec3; 3]]],
        instances: &[InstanceInput],
    ) -> Result<Self, String> {
        if meshes.len() != mesh_triangles.len() {
            return Err(format!(
                "{} meshes and {} triangle lists",
                meshes.len(),
                mesh_triangles.len()
            ));
        }
        let mut placed = Vec::with_capacity(instances.len());
        let mut meshes_of = Vec::with_capacity(instances.len());
        for (k, instance) in instances.iter().enumerate() {
            let triangles = mesh_triangles.get(instance.mesh as usize).ok_or_else(|| {
                format!(
                    "instance {k} refers to mesh {}, which does not exist",
                    instance.mesh
                )
            })?;
            let inverse = instance.object_to_world.inverse();
            if !(instance.object_to_world.is_finite()
                && inverse.is_finite()
                && instance.object_to_world.matrix3.determinant().is_normal())
            {
                return Err(format!("instance {k}: its transform is not invertible"));
            }
            placed.push(Placed {
                rows: rows_of(&inverse),
                mesh: instance.mesh,
            });
            meshes_of.push(*triangles);
        }
        // An instance of an empty mesh gets an empty box: never hit. Every
        // box maps all of its mesh's vertices: in parallel.
        let boxes: Vec<Aabb> = meshes_of
            .par_iter()
            .zip(instances)
            .map(|(triangles, instance)| {
                world_box(triangles, &instance.object_to_world).unwrap_or(Aabb::INVALID)
            })
            .collect();
        let top = if boxes.is_empty() {
            Bvh2::default()
        } else {
            let mut build_time = Duration::ZERO;
            let mut top = build_bvh2(&boxes, TOP_LEVEL_BUILD, &mut build_time);
            top.max_depth = (tree_depth(&top.nodes) + 1).max(DEFAULT_MAX_STACK_DEPTH);
            top
        };
        Ok(Self {
            meshes,
            placed,
            object_to_world: instances.iter().map(|i| i.object_to_world).collect(),
            top_wide: TopLevel::build(&top),
            top,
        })
    }

    /// Number of instances.
    pub fn len(&self) -> usize {
        self.placed.len()
    }

    /// Whether there is no instance.
    pub fn is_empty(&self) -> bool {
        self.placed.is_empty()
    }

    /// The bottom-level trees, one per distinct mesh.
    pub fn meshes(&self) -> &[Bvh] {
        &self.meshes
    }

    /// The mesh of instance `instance`.
    pub fn mesh_of(&self, instance: u32) -> Option<u32> {
        self.placed.get(instance as usize).map(|p| p.mesh)
    }

    /// The object-to-world map of instance `instance`.
    pub fn object_to_world(&self, instance: u32) -> Option<Affine3A> {
        self.object_to_world.get(instance as usize).copied()
    }

    /// Bounds of every instance together (`None` without instances).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.top
            .nodes
            .first()
            .map(|root| (Vec3::from(root.aabb().min), Vec3::from(root.aabb().max)))
    }

    /// Bytes held: the meshes' trees once each, the instance records and
    /// the top-level tree (vector capacities).
    pub fn memory_bytes(&self) -> usize {
        fn vec_bytes<T>(v: &Vec<T>) -> usize {
            v.capacity() * size_of::<T>()
        }
        let top = vec_bytes(&self.top.nodes)
            + vec_bytes(&self.top.primitive_indices)
            + vec_bytes(&self.top.primitive_indices_freelist)
            + vec_bytes(&self.top.primitives_to_nodes)
            + vec_bytes(&self.top.parents);
        size_of::<Self>()
            + self.meshes.iter().map(Bvh::memory_bytes).sum::<usize>()
            + self.instance_memory_bytes()
            + top
            + self.top_wide.memory_bytes()
    }

    /// Bytes held per instance (its record and world map), without the
    /// top-level tree.
    pub fn instance_memory_bytes(&self) -> usize {
        self.placed.capacity() * size_of::<Placed>()
            + self.object_to_world.capacity() * size_of::<Affine3A>()
    }

    /// Checks the invariants: every mesh's tree against its triangles
    /// ([`Bvh::validate`]); every instance's mesh exists and its record is
    /// the inverse of its world map; every top-level node bounds its
    /// children, every leaf its instances' world boxes (`world_box` of
    /// the mesh's triangles), and every instance sits in exactly one leaf;
    /// the 8-wide top level likewise (`TopLevel::validate`).
    pub fn validate(&self, mesh_triangles: &[&[[Vec3; 3]]]) -> Result<(), String> {
        if mesh_triangles.len() != self.meshes.len() {
            return Err(format!(
                "{} triangle lists for {} meshes",
                mesh_triangles.len(),
                self.meshes.len()
            ));
        }
        for (k, (bvh, triangles)) in self.meshes.iter().zip(mesh_triangles).enumerate() {
            bvh.validate(triangles)
                .map_err(|e| format!("mesh {k}: {e}"))?;
        }
        if self.object_to_world.len() != self.placed.len() {
            return Err("one world map per instance expected".to_owned());
        }
        for (k, (placed, to_world)) in self.placed.iter().zip(&self.object_to_world).enumerate() {
            if placed.mesh as usize >= self.meshes.len() {
                return Err(format!("instance {k} refers to a missing mesh"));
            }
            if placed.rows != rows_of(&to_world.inverse()) {
                return Err(format!("instance {k}: its world-to-object map is stale"));
            }
        }
        let nodes = &self.top.nodes;
        if self.placed.is_empty() {
            return if nodes.is_empty() {
                Ok(())
            } else {
                Err("a top-level tree without instances".to_owned())
            };
        }
        if self.top.primitive_indices.len() != self.placed.len() {
            return Err(format!(
                "{} top-level primitives for {} instances",
                self.top.primitive_indices.len(),
                self.placed.len()
            ));
        }
        // Each instance's world box once (every vertex of its mesh mapped),
        // in parallel, for both top levels' checks.
        let world_boxes: Vec<Option<Aabb>> = self
            .placed
            .par_iter()
            .zip(&self.object_to_world)
            .map(|(placed, to_world)| {
                mesh_triangles
                    .get(placed.mesh as usize)
                    .and_then(|triangles| world_box(triangles, to_world))
            })
            .collect();
        let mut seen = vec![false; self.placed.len()];
        let mut reached = vec![false; nodes.len()];
        let mut stack = vec![0usize];
        let contains = |outer: &Aabb, inner: &Aabb| {
            inner.min.cmpge(outer.min).all() && inner.max.cmple(outer.max).all()
        };
        while let Some(index) = stack.pop() {
            let node = nodes.get(index).ok_or("a top-level child out of range")?;
            let visited = reached
                .get_mut(index)
                .ok_or("a top-level node out of range")?;
            if *visited {
                return Err(format!("top-level node {index} is reached twice"));
            }
            *visited = true;
            let first = node.first_index as usize;
            if node.is_leaf() {
                for slot in first..first + node.prim_count as usize {
                    let instance = *self
                        .top
                        .primitive_indices
                        .get(slot)
                        .ok_or("a top-level leaf out of range")?
                        as usize;
                    let flag = seen
                        .get_mut(instance)
                        .ok_or("a top-level leaf names no instance")?;
                    if *flag {
                        return Err(format!("instance {instance} sits in two leaves"));
                    }
                    *flag = true;
                    if let Some(aabb) = world_boxes.get(instance).copied().flatten() {
                        if !contains(node.aabb(), &aabb) {
                            return Err(format!(
                                "a top-level leaf does not bound instance {instance}"
                            ));
                        }
                    }
                }
            } else {
                for child in [first, first + 1] {
                    let child_node = nodes.get(child).ok_or("a top-level child out of range")?;
                    if child_node.aabb().valid() && !contains(node.aabb(), child_node.aabb()) {
                        return Err(format!(
                            "top-level node {index} does not bound node {child}"
                        ));
                    }
                    stack.push(child);
                }
            }
        }
        if let Some(missing) = seen.iter().position(|&s| !s) {
            return Err(format!("instance {missing} is in no top-level leaf"));
        }
        if tree_depth(nodes) >= self.top.max_depth {
            return Err("the top-level tree is deeper than its traversal stack".to_owned());
        }
        self.top_wide.validate(&self.top, |slot| {
            let (instance, _) = self.at_slot(slot)?;
            *world_boxes.get(instance as usize)?
        })
    }

    /// `ray` in the object coordinates of `placed` (same `t`).
    #[inline(always)]
    fn object_ray(placed: &Placed, ray: &Ray, t_max: f32) -> Ray {
        Ray {
            origin: Vec3::from(map(&placed.rows, ray.origin.to_array(), true)),
            direction: Vec3::from(map(&placed.rows, ray.direction.to_array(), false)),
            t_max,
        }
    }

    /// The instance in top-level slot `slot` with its record.
    #[inline(always)]
    fn at_slot(&self, slot: usize) -> Option<(u32, &Placed)> {
        let instance = *self.top.primitive_indices.get(slot)?;
        Some((instance, self.placed.get(instance as usize)?))
    }

    /// Scalar closest hit (the oracle: obvhs' traversal at both levels and
    /// the scalar triangle test), nearer than `ray.t_max`.
    pub fn intersect(&self, ray: &Ray) -> Option<InstanceHit> {
        let mut best = None;
        let mut hit = RayHit::none();
        self.top
            .ray_traverse(Bvh::obvhs_ray(ray), &mut hit, |current, slot| {
                let Some((instance, placed)) = self.at_slot(slot) else {
                    return f32::INFINITY;
                };
                let Some(mesh) = self.meshes.get(placed.mesh as usize) else {
                    return f32::INFINITY;
                };
                let local = Self::object_ray(placed, ray, current.tmax);
                match mesh.intersect(&local) {
                    Some(h) => {
                        best = Some(InstanceHit {
                            t: h.t,
                            u: h.u,
                            v: h.v,
                            triangle: h.triangle,
                            instance,
                        });
                        h.t
                    }
                    None => f32::INFINITY,
                }
            });
        best
    }

    /// Closest hit of one ray through the 8-wide top level and the meshes'
    /// 8-wide trees (`top` and `mesh` are their scratch stacks).
    pub fn intersect_wide(
        &self,
        ray: &Ray,
        top: &mut WideStack,
        mesh: &mut WideStack,
    ) -> Option<InstanceHit> {
        let mut best = None;
        self.top_wide.intersect(ray, top, |slot, t_max| {
            let (instance, placed) = self.at_slot(slot)?;
            let tree = self.meshes.get(placed.mesh as usize)?;
            let h = tree.intersect_wide(&Self::object_ray(placed, ray, t_max), mesh)?;
            best = Some(InstanceHit {
                t: h.t,
                u: h.u,
                v: h.v,
                triangle: h.triangle,
                instance,
            });
            Some(h.t)
        });
        best
    }

    /// Occlusion of one ray through the 8-wide top level and the meshes'
    /// 8-wide trees (`top` and `mesh` are their scratch stacks).
    pub fn occluded_wide(&self, ray: &Ray, top: &mut WideStack, mesh: &mut WideStack) -> bool {
        self.top_wide.occluded(ray, top, |slot| {
            self.at_slot(slot).is_some_and(|(_, placed)| {
                self.meshes.get(placed.mesh as usize).is_some_and(|tree| {
                    tree.occluded_wide(&Self::object_ray(placed, ray, ray.t_max), mesh)
                })
            })
        })
    }

    /// Scalar occlusion for `t ∈ (0, ray.t_max)` (the oracle: obvhs'
    /// traversal at both levels and the scalar triangle test).
    pub fn occluded(&self, ray: &Ray) -> bool {
        !self
            .top
            .ray_traverse_miss(Bvh::obvhs_ray(ray), |current, slot| {
                let found = self.at_slot(slot).is_some_and(|(_, placed)| {
                    self.meshes.get(placed.mesh as usize).is_some_and(|mesh| {
                        mesh.occluded(&Self::object_ray(placed, ray, current.tmax))
                    })
                });
                // Any positive distance below `tmax` ends the traversal.
                if found { 0.0 } else { f32::INFINITY }
            })
    }

    /// Continues `hit` (the soup's hits of `packet`, [`PacketHit`]
    /// convention) with the instances, one ray at a time through the 8-wide
    /// top level and the meshes' 8-wide trees: lanes with a nearer instance
    /// hit take it.
    pub fn intersect_lanes(&self, packet: &RayPacket, hit: &mut PacketHit) {
        let (mut top, mut mesh) = (WideStack::new(), WideStack::new());
        let t = hit.t.to_array();
        for lane in packet.active.iter() {
            let ray = Ray {
                t_max: t[lane],
                ..packet.ray(lane)
            };
            if let Some(found) = self.intersect_wide(&ray, &mut top, &mut mesh) {
                set_lane(hit, lane, &found);
            }
        }
    }

    /// The lanes of `packet.active` blocked by an instance, one ray at a
    /// time through the 8-wide top level and the meshes' 8-wide trees.
    pub fn occluded_lanes(&self, packet: &RayPacket) -> LaneMask {
        let (mut top, mut mesh) = (WideStack::new(), WideStack::new());
        packet
            .active
            .iter()
            .filter(|&lane| self.occluded_wide(&packet.ray(lane), &mut top, &mut mesh))
            .fold(LaneMask::NONE, LaneMask::with)
    }

    /// Continues `hit` with the instances for a coherent packet: the top
    /// level as a packet, each instance's mesh in its object coordinates,
    /// as a packet or lane by lane through its wide tree (module docs).
    pub fn intersect_packet(&self, packet: &RayPacket, hit: &mut PacketHit) {
        if packet.active.is_empty() || self.placed.is_empty() {
            return;
        }
        let rays = PacketRays::new(packet);
        let active = packet.active.to_simd();
        let mut t_max = active.select(hit.t, f32x8::NEG_INFINITY);
        let mut leaf = |first: usize, count: usize, lanes: f32x8, t_max: &mut f32x8| {
            for slot in first..first.saturating_add(count) {
                let Some((instance, placed)) = self.at_slot(slot) else {
                    continue;
                };
                let Some(mesh) = self.meshes.get(placed.mesh as usize) else {
                    continue;
                };
                let live = LaneMask::from_simd(lanes & t_max.simd_gt(f32x8::NEG_INFINITY));
                if live.is_empty() {
                    continue;
                }
                let local = RayPacket {
                    origin: map(&placed.rows, packet.origin, true),
                    direction: map(&placed.rows, packet.direction, false),
                    t_max: *t_max,
                    active: live,
                };
                let found = match mesh.bounce_traversal() {
                    Traversal::Wide => mesh.intersect_packet_wide(&local),
                    Traversal::Packet | Traversal::Flat => mesh.intersect_packet(&local),
                };
                if found.hit.is_empty() {
                    continue;
                }
                let found_simd = found.hit.to_simd();
                *t_max = found_simd.select(found.t, *t_max);
                hit.t = found_simd.select(found.t, hit.t);
                hit.u = found_simd.select(found.u, hit.u);
                hit.v = found_simd.select(found.v, hit.v);
                for lane in found.hit.iter() {
                    hit.triangle[lane] = found.triangle[lane];
                    hit.instance[lane] = instance;
                }
                hit.hit = hit.hit.or(found.hit);
            }
            true
        };
        TOP_STACK.with(|cell| match cell.try_borrow_mut() {
            Ok(mut stack) => {
                stack.clear();
                traverse_nodes(&self.top.nodes, &rays, &mut t_max, &mut stack, &mut leaf);
            }
            Err(_) => {
                let mut stack = InlineStack::new((0, f32x8::ZERO));
                traverse_nodes(&self.top.nodes, &rays, &mut t_max, &mut stack, &mut leaf);
            }
        });
    }
}

/// Writes `found` into `hit`'s lane `lane`.
fn set_lane(hit: &mut PacketHit, lane: usize, found: &InstanceHit) {
    hit.t.as_mut_array()[lane] = found.t;
    hit.u.as_mut_array()[lane] = found.u;
    hit.v.as_mut_array()[lane] = found.v;
    hit.triangle[lane] = found.triangle;
    hit.instance[lane] = found.instance;
    hit.hit = hit.hit.with(lane);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<[Vec3; 3]> {
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let quads = [
            [
                c(-1., -1., -1.),
                c(-1., 1., -1.),
                c(-1., 1., 1.),
                c(-1., -1., 1.),
            ],
            [
                c(1., -1., -1.),
                c(1., -1., 1.),
                c(1., 1., 1.),
                c(1., 1., -1.),
            ],
            [
                c(-1., -1., -1.),
                c(-1., -1., 1.),
                c(1., -1., 1.),
                c(1., -1., -1.),
            ],
            [
                c(-1., 1., -1.),
                c(1., 1., -1.),
                c(1., 1., 1.),
                c(-1., 1., 1.),
            ],
            [
                c(-1., -1., -1.),
                c(1., -1., -1.),
                c(1., 1., -1.),
                c(-1., 1., -1.),
            ],
            [
                c(-1., -1., 1.),
                c(-1., 1., 1.),
                c(1., 1., 1.),
                c(1., -1., 1.),
            ],
        ];
        quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    fn two_level() -> (InstanceBvh, Vec<[Vec3; 3]>) {
        two_level_of(cube())
    }

    /// Each triangle split into four at its edges' midpoints (shared edges
    /// get the same midpoints, so the mesh stays closed).
    fn subdivided(triangles: &[[Vec3; 3]]) -> Vec<[Vec3; 3]> {
        triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect()
    }

    /// Five placed instances of the mesh `triangles`.
    fn two_level_of(triangles: Vec<[Vec3; 3]>) -> (InstanceBvh, Vec<[Vec3; 3]>) {
        let instances: Vec<InstanceInput> = (0..5)
            .map(|k| InstanceInput {
                mesh: 0,
                object_to_world: Affine3A::from_scale_rotation_translation(
                    Vec3::new(1.0, 0.5 + k as f32 * 0.2, 1.5),
                    glam::Quat::from_rotation_y(0.3 * k as f32),
                    Vec3::new(4.0 * k as f32, 0.0, -1.0),
                ),
            })
            .collect();
        let bvh = InstanceBvh::build(vec![Bvh::build(&triangles)], &[&triangles], &instances);
        (bvh.unwrap_or_else(|e| panic!("{e}")), triangles)
    }

    #[test]
    fn validates_and_detects_corruption() {
        let (bvh, triangles) = two_level();
        let lists: [&[[Vec3; 3]]; 1] = [&triangles];
        bvh.validate(&lists).unwrap();
        assert_eq!(bvh.len(), 5);
        // Another mesh's triangles.
        assert!(bvh.validate(&[&triangles[2..]]).is_err());
        assert!(bvh.validate(&[]).is_err());
        // A stale world-to-object map.
        let mut broken = bvh.clone();
        broken.placed[2].rows[0][3] += 0.5;
        assert!(broken.validate(&lists).is_err());
        // An instance of a mesh that does not exist.
        let mut broken = bvh.clone();
        broken.placed[1].mesh = 4;
        assert!(broken.validate(&lists).is_err());
        // A leaf box that no longer bounds its instance.
        let mut broken = bvh.clone();
        let leaf = broken.top.nodes.iter().position(|n| n.is_leaf()).unwrap();
        let mut aabb = *broken.top.nodes[leaf].aabb();
        aabb.max = aabb.min;
        broken.top.nodes[leaf].set_aabb(aabb);
        assert!(broken.validate(&lists).is_err());
        // An instance in two leaves (and another in none).
        let mut broken = bvh.clone();
        broken.top.primitive_indices.swap(0, 1);
        broken.top.primitive_indices[1] = broken.top.primitive_indices[0];
        assert!(broken.validate(&lists).is_err());
        // The 8-wide top level: a leaf box that no longer bounds its
        // instance, a leaf dropped (its instance in no leaf), a stale
        // collapse (built from another tree).
        let mut broken = bvh.clone();
        broken.top_wide.shrink_a_leaf_box();
        assert!(broken.validate(&lists).unwrap_err().contains("bound"));
        let mut broken = bvh.clone();
        broken.top_wide.drop_a_leaf();
        assert!(broken.validate(&lists).unwrap_err().contains("no leaf"));
        let mut broken = bvh.clone();
        broken.top_wide = TopLevel::default();
        assert!(broken.validate(&lists).is_err());
        // Refused at build: a singular map and a missing mesh.
        let singular = InstanceInput {
            mesh: 0,
            object_to_world: Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)),
        };
        assert!(
            InstanceBvh::build(vec![Bvh::build(&triangles)], &[&triangles], &[singular]).is_err()
        );
        let missing = InstanceInput {
            mesh: 1,
            object_to_world: Affine3A::IDENTITY,
        };
        assert!(
            InstanceBvh::build(vec![Bvh::build(&triangles)], &[&triangles], &[missing]).is_err()
        );
    }

    /// A field of `side × side` cubes, scaled, rotated and some
    /// overlapping, with a top level several 8-wide nodes deep.
    fn field(side: usize) -> (InstanceBvh, Vec<[Vec3; 3]>) {
        let triangles = cube();
        let instances: Vec<InstanceInput> = (0..side * side)
            .map(|k| {
                let (i, j) = ((k % side) as f32, (k / side) as f32);
                InstanceInput {
                    mesh: 0,
                    object_to_world: Affine3A::from_scale_rotation_translation(
                        Vec3::new(0.4 + 0.05 * i, 0.3 + 0.04 * j, 0.5),
                        glam::Quat::from_rotation_y(0.37 * k as f32)
                            * glam::Quat::from_rotation_x(0.21 * k as f32),
                        Vec3::new(1.6 * i, 0.2 * ((3 * k) % 5) as f32, -1.6 * j),
                    ),
                }
            })
            .collect();
        let bvh = InstanceBvh::build(vec![Bvh::build(&triangles)], &[&triangles], &instances);
        (bvh.unwrap_or_else(|e| panic!("{e}")), triangles)
    }

    /// Every instance of a field of 144 has a top-level leaf of its own,
    /// in the binary tree and in the 8-wide one; obvhs' preset alone
    /// (the negative control) puts several instances of the same boxes in
    /// one leaf.
    #[test]
    fn every_instance_has_a_top_level_leaf_of_its_own() {
        let (bvh, triangles) = field(12);
        let leaf_sizes = |tree: &Bvh2| -> Vec<u32> {
            let leaves = tree.nodes.iter().filter(|n| n.is_leaf());
            leaves.map(|n| n.prim_count).collect()
        };
        let sizes = leaf_sizes(&bvh.top);
        assert_eq!(sizes.len(), bvh.len());
        assert!(sizes.iter().all(|&n| n == 1), "{sizes:?}");
        assert!(bvh.top_wide.leaf_counts().all(|n| n == 1));
        let boxes: Vec<Aabb> = bvh
            .object_to_world
            .iter()
            .map(|to_world| world_box(&triangles, to_world).unwrap())
            .collect();
        let mut build_time = Duration::ZERO;
        let preset = build_bvh2(&boxes, BvhBuildParams::medium_build(), &mut build_time);
        assert!(leaf_sizes(&preset).iter().any(|&n| n > 1));
    }

    /// A field of 144 instances: the 8-wide top level has several levels,
    /// validates, and the single-ray queries through it give the oracle's
    /// hits bit for bit (same instance and triangle) and its occlusion.
    #[test]
    fn wide_top_level_equals_the_oracle_on_a_field() {
        let side = 12;
        let (bvh, triangles) = field(side);
        bvh.validate(&[&triangles]).unwrap();
        // More binary leaves than one node's 8 children: several levels.
        assert!(bvh.top_wide.node_count() > 1);
        let mut state = 7u32;
        let mut unit = || {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let extent = 1.6 * side as f32;
        let (mut hits, mut blocked, mut rays) = (0, 0, 0);
        let (mut top, mut mesh) = (WideStack::new(), WideStack::new());
        for _ in 0..4000 {
            // From above the field at a slant, or along it at grazing
            // heights, towards a random point of it.
            let target = Vec3::new(extent * unit(), 0.8 * unit() - 0.2, -extent * unit());
            let origin = if unit() < 0.5 {
                Vec3::new(extent * unit(), 6.0, -extent * unit())
            } else {
                Vec3::new(-2.0, 1.0 * unit(), -extent * unit())
            };
            let ray = Ray {
                origin,
                direction: target - origin,
                t_max: if unit() < 0.3 { 0.7 } else { f32::INFINITY },
            };
            let oracle = bvh.intersect(&ray);
            let wide = bvh.intersect_wide(&ray, &mut top, &mut mesh);
            let key = |h: Option<InstanceHit>| {
                h.map(|h| {
                    (
                        h.t.to_bits(),
                        h.u.to_bits(),
                        h.v.to_bits(),
                        h.triangle,
                        h.instance,
                    )
                })
            };
            assert_eq!(key(wide), key(oracle), "{ray:?}");
            let occluded = bvh.occluded_wide(&ray, &mut top, &mut mesh);
            assert_eq!(occluded, bvh.occluded(&ray), "{ray:?}");
            assert_eq!(occluded, oracle.is_some());
            hits += usize::from(oracle.is_some());
            blocked += usize::from(occluded);
            rays += 1;
        }
        assert!(hits > rays / 5 && hits < rays, "{hits} of {rays}");
        assert!(blocked > rays / 5, "{blocked} of {rays}");
    }

    /// Every query path gives the scalar oracle's hits: the same mapped
    /// rays and triangle tests, so the same bits.
    #[test]
    fn packet_and_wide_paths_equal_the_scalar_oracle() {
        // The cube's mesh takes packets inside instances, the subdivided
        // one (192 triangles) its wide tree.
        let fine = subdivided(&subdivided(&cube()));
        assert!(fine.len() > super::super::WIDE_MIN_TRIANGLES);
        for (bvh, _) in [two_level(), two_level_of(fine)] {
            paths_equal_the_scalar_oracle(&bvh);
        }
    }

    fn paths_equal_the_scalar_oracle(bvh: &InstanceBvh) {
        let mut state = 1u32;
        let mut unit = || {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let (mut hits, mut blocked) = (0, 0);
        for _ in 0..200 {
            let rays: Vec<Ray> = (0..8)
                .map(|_| Ray {
                    origin: Vec3::new(8.0 * unit(), 6.0, 6.0),
                    direction: Vec3::new(16.0 * unit() - 8.0, -6.0 - unit(), -7.0 + 2.0 * unit()),
                    t_max: if unit() < 0.5 {
                        f32::INFINITY
                    } else {
                        0.9 + 0.2 * unit()
                    },
                })
                .collect();
            let packet = RayPacket::from_rays(&rays);
            let mut coherent = PacketHit::misses(&packet);
            bvh.intersect_packet(&packet, &mut coherent);
            let mut incoherent = PacketHit::misses(&packet);
            bvh.intersect_lanes(&packet, &mut incoherent);
            let occluded = bvh.occluded_lanes(&packet);
            for (lane, ray) in rays.iter().enumerate() {
                let oracle = bvh.intersect(ray);
                for found in [&coherent, &incoherent] {
                    assert_eq!(found.hit.contains(lane), oracle.is_some());
                    if let Some(o) = oracle {
                        assert_eq!(found.t.to_array()[lane].to_bits(), o.t.to_bits());
                        assert_eq!(found.u.to_array()[lane].to_bits(), o.u.to_bits());
                        assert_eq!(found.v.to_array()[lane].to_bits(), o.v.to_bits());
                        assert_eq!(
                            (found.triangle[lane], found.instance[lane]),
                            (o.triangle, o.instance)
                        );
                    }
                }
                assert_eq!(occluded.contains(lane), bvh.occluded(ray));
                assert_eq!(bvh.occluded(ray), oracle.is_some());
                hits += usize::from(oracle.is_some());
                blocked += usize::from(occluded.contains(lane));
            }
        }
        assert!(
            hits > 200 && blocked > 200 && hits < 1500,
            "{hits} {blocked}"
        );
    }
}
