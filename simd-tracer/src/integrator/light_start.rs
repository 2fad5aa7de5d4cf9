//! Where a light path starts (`light_paths.rs`): a point of an emissive
//! triangle of the light set, or a point or spot light.
//!
//! **Why point lights.** A camera path can never hit a point light, and a
//! shadow ray does not pass glass, so the light a point or spot light
//! sends through dispersive glass onto a wall reaches no camera path at
//! all: without light paths that caustic is simply missing from the
//! image (in every transport, and in Mitsuba's path tracer). Light paths
//! leave the light itself, so they carry it; camera paths keep every path
//! they can form, and the two still count disjoint paths.
//!
//! **The choice.** A light is chosen with the light sampler's
//! probabilities (`shading::light_sampler`: half by power, half uniform)
//! restricted to the lights light paths start from, the triangles' share
//! `P_tri` and each point light's `P_k`, divided by their sum `S`; a
//! triangle then has `P = P_light / S` (its absolute NEE probability over
//! `S`), a point light `P_k / S`, and likewise a sphere light. Without
//! point and sphere lights `S = P_tri` and the choice is the triangles' as
//! before, number for number.
//!
//! **Sphere lights.** A camera path can hit a sphere light's triangles
//! through glass, so the camera side leaves those paths out as it does a
//! lamp triangle's (`caustics.rs`). A light path starts on the analytic
//! sphere (a uniform point, density `1/(4πρ²)`, the cosine about its
//! outward normal), the sphere next-event estimation integrates
//! (`shading::sphere_light`): the tessellation lies inside it, so the
//! first ray never meets the light's own triangles, and the two differ by
//! the band between the silhouettes that next-event estimation already
//! counts (a relative `2·10⁻³` at the default sag).
//!
//! **The start.** `β = L_e(λ) |cos θ| A / (P p(ω))` on a triangle (the
//! point uniform on it, density `1/A`), `β = s I(λ) f(θ) / (P p(ω))` at a
//! point light of intensity `s I` and spot profile `f` (1 without a
//! cone), `p(ω)` the first direction's density (`light_aim.rs`), and on a
//! sphere light `β = L_e(λ) cos θ 4πρ² / (P p(ω))`.
//!
//! **Directional lights** (the sun) are out of every camera path's reach
//! as point lights are. Their light crosses the scene as a beam: a path
//! starts on a disk across it, of the radius of the sphere around the
//! scene and a diameter before its centre, at a point drawn per unit area
//! (`light_aim.rs`, [`Beam`]), and travels along the light's direction:
//! `β = s E(λ) / (P p(x))`, `E` the irradiance on a surface facing the
//! light. The environment starts none (its light would need a beam per
//! direction).
//!
//! **Far lights.** A path from a point light far outside the scene starts
//! where its ray enters the sphere around the scene
//! ([`LightStarts::enter`]): no geometry lies before it, and a hit point
//! computed as `o + t d` with `t` in the thousands carries rounding errors
//! larger than the offset that lifts the next ray off the surface.

use super::light_aim::{Beam, Emitting, uniform_sphere};
use super::packet_shading::offset;
use super::path::ONE_BELOW;
use crate::ids::SpectrumId;
use crate::scene::Scene;
use crate::shading::light_sampler::{DirectionalLight, PointLight};
use crate::shading::sphere_light::SphereLight;
use crate::shading::spot_cone::SpotCone;
use glam::Vec3;
use std::f32::consts::PI;

/// The lights light paths start from and their probabilities (module
/// docs).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LightStarts {
    /// `P_tri`, 0 where no path starts on a triangle.
    triangle_share: f32,
    /// The point and spot lights with their absolute probabilities `P_k`.
    points: Vec<(PointLight, f32)>,
    /// The sphere lights with theirs.
    spheres: Vec<(SphereLight, f32)>,
    /// The directional lights with theirs, each as the beam it sends
    /// across the scene.
    beams: Vec<(DirectionalLight, Beam, f32)>,
    /// The sphere around the scene's geometry: centre and radius.
    bounding: Option<(Vec3, f32)>,
    /// `S = P_tri + Σ P_k`.
    total: f32,
}

/// Where a light path leaves from.
#[derive(Debug, Clone, Copy)]
pub(super) enum Place {
    /// A lamp's point and how it emits there.
    At {
        /// The point.
        origin: Vec3,
        /// How the light emits there.
        emitting: Emitting,
    },
    /// Parallel light across the scene (a directional light).
    Beam(Beam),
}

/// A light path's first vertex (module docs).
#[derive(Debug, Clone, Copy)]
pub(super) struct LightStart {
    /// Where the path leaves from.
    pub place: Place,
    /// `L_e`, `I` or `E`.
    pub emission: SpectrumId,
    /// `A` or `s`.
    pub measure: f32,
    /// `P`.
    pub pmf: f32,
    /// A spot's cone.
    cone: Option<SpotCone>,
}

/// The relative (and, in scene units, absolute) margin by which
/// [`LightStarts::enter`] grows the sphere around the scene.
const BOUNDING_MARGIN: f32 = 1e-3;

impl LightStarts {
    /// The starts of `scene`, or `None` where it has no light to start from.
    pub(super) fn new(scene: &Scene) -> Option<Self> {
        let sampler = scene.light_sampler();
        let triangle_share = if scene.lights().is_empty() {
            0.0
        } else {
            sampler.triangle_share()
        };
        let points: Vec<(PointLight, f32)> = sampler
            .point_lights()
            .filter(|(_, pmf)| *pmf > 0.0)
            .map(|(light, pmf)| (*light, pmf))
            .collect();
        let spheres: Vec<(SphereLight, f32)> = sampler
            .spheres_with_pmf()
            .filter(|(_, pmf)| *pmf > 0.0)
            .map(|(light, pmf)| (light.clone(), pmf))
            .collect();
        // The beams cross the sphere around the scene's box.
        let bounding = scene
            .world_bounds()
            .map(|(min, max)| (0.5 * (min + max), 0.5 * (max - min).length()));
        let beams: Vec<(DirectionalLight, Beam, f32)> = bounding
            .map(|(center, radius)| {
                sampler
                    .directional_lights()
                    .filter(|(_, pmf)| *pmf > 0.0)
                    .filter_map(|(light, pmf)| {
                        let travel = light.direction.try_normalize()?;
                        let beam = Beam {
                            travel,
                            center,
                            radius,
                        };
                        Some((*light, beam, pmf))
                    })
                    .collect()
            })
            .unwrap_or_default();
        let total = triangle_share
            + points.iter().map(|(_, pmf)| pmf).sum::<f32>()
            + spheres.iter().map(|(_, pmf)| pmf).sum::<f32>()
            + beams.iter().map(|(_, _, pmf)| pmf).sum::<f32>();
        (total > 0.0).then_some(Self {
            triangle_share,
            points,
            spheres,
            beams,
            bounding,
            total,
        })
    }

    /// The start chosen by `u_light`, its point on a triangle or a sphere
    /// by `(u, v)` (all in `[0, 1)`); `None` where the light emits nothing
    /// there.
    pub(super) fn choose(&self, scene: &Scene, u_light: f32, u: f32, v: f32) -> Option<LightStart> {
        let x = u_light * self.total;
        let triangles_only =
            self.points.is_empty() && self.spheres.is_empty() && self.beams.is_empty();
        if triangles_only || x < self.triangle_share {
            // With triangles alone `u_light` is the triangles' own number,
            // unscaled, so their paths are those of before, bit for bit.
            let u_triangle = if triangles_only {
                u_light
            } else {
                (x / self.triangle_share).min(ONE_BELOW)
            };
            let light = scene.lights().sample(u_triangle, u, v)?;
            let surface = light.surface;
            let pmf = surface.light_pmf / self.total;
            return (pmf > 0.0 && surface.area > 0.0).then_some(LightStart {
                place: Place::At {
                    origin: light.point,
                    emitting: Emitting::Surface {
                        normal: surface.normal,
                        two_sided: surface.two_sided,
                    },
                },
                emission: surface.emission,
                measure: surface.area,
                pmf,
                cone: None,
            });
        }
        let mut end = self.triangle_share;
        for (light, pmf) in &self.points {
            end += pmf;
            if x < end {
                return Some(self.point_start(light, *pmf));
            }
        }
        for (light, pmf) in &self.spheres {
            end += pmf;
            if x < end {
                return Some(self.sphere_start(light, *pmf, (u, v)));
            }
        }
        for (light, beam, pmf) in &self.beams {
            end += pmf;
            if x < end {
                return Some(self.beam_start(light, *beam, *pmf));
            }
        }
        // Rounding left `x` past the last end: the last light.
        if let Some((light, beam, pmf)) = self.beams.last() {
            return Some(self.beam_start(light, *beam, *pmf));
        }
        match (self.spheres.last(), self.points.last()) {
            (Some((light, pmf)), _) => Some(self.sphere_start(light, *pmf, (u, v))),
            (None, Some((light, pmf))) => Some(self.point_start(light, *pmf)),
            (None, None) => None,
        }
    }

    /// Where a ray from `origin` along the unit `direction` enters the
    /// sphere around the scene: `origin` itself inside it, `None` where the
    /// ray misses it (and so all geometry). A far point light's ray then
    /// starts near what it can hit: from thousands of units away, a hit
    /// point `origin + t d` would carry rounding errors of `ulp(t)`, larger
    /// than the offset that moves the next ray off the surface (the light
    /// paths of a point 2 000 units away brought a quarter more light
    /// through a wedge than those of a point 200 away before).
    pub(super) fn enter(&self, origin: Vec3, direction: Vec3) -> Option<Vec3> {
        let Some((center, radius)) = self.bounding else {
            return Some(origin);
        };
        // A hair larger, so that no geometry lies outside it.
        let radius = radius * (1.0 + BOUNDING_MARGIN) + BOUNDING_MARGIN;
        let to_origin = origin - center;
        let beyond = to_origin.length_squared() - radius * radius;
        if beyond <= 0.0 {
            return Some(origin);
        }
        let along = to_origin.dot(direction);
        // `r²` less the squared distance of the centre from the ray's line
        // (not `along² − beyond`: from far away both are huge and their
        // difference is rounding).
        let discriminant = radius * radius - (to_origin - along * direction).length_squared();
        if along >= 0.0 || discriminant < 0.0 {
            return None;
        }
        // The nearer root, as the product of the roots over the farther.
        let t = beyond / (-along + discriminant.sqrt());
        Some(origin + t * direction)
    }

    /// The start of directional light `light`, chosen with `pmf`: its
    /// `beam`.
    fn beam_start(&self, light: &DirectionalLight, beam: Beam, pmf: f32) -> LightStart {
        LightStart {
            place: Place::Beam(beam),
            emission: light.irradiance,
            measure: light.scale,
            pmf: pmf / self.total,
            cone: None,
        }
    }

    /// The start at point light `light`, chosen with `P_k = pmf`.
    fn point_start(&self, light: &PointLight, pmf: f32) -> LightStart {
        LightStart {
            place: Place::At {
                origin: light.position,
                emitting: Emitting::Point,
            },
            emission: light.intensity,
            measure: light.scale,
            pmf: pmf / self.total,
            cone: light.cone,
        }
    }

    /// The start on sphere light `light`, chosen with `pmf`, at the point
    /// of the uniforms `(u, v)` (module docs).
    fn sphere_start(&self, light: &SphereLight, pmf: f32, (u, v): (f32, f32)) -> LightStart {
        let normal = uniform_sphere(u, v);
        LightStart {
            place: Place::At {
                origin: light.center + light.radius * normal,
                emitting: Emitting::Surface {
                    normal,
                    two_sided: false,
                },
            },
            emission: light.emission,
            measure: 4.0 * PI * light.radius * light.radius,
            pmf: pmf / self.total,
            cone: None,
        }
    }
}

impl LightStart {
    /// `β = L_e |cos θ| A / (P p)`, `s I f(θ) / (P p)` or `s E / (P p)` at
    /// one wavelength (module docs), from the emission there, the unit
    /// `direction` and its `density` (per steradian from a lamp, per area
    /// of the beam's cross-section for parallel light).
    pub(super) fn beta(&self, emission: f32, direction: Vec3, density: f32) -> f32 {
        let angular = match self.place {
            Place::At {
                emitting: Emitting::Surface { normal, .. },
                ..
            } => direction.dot(normal).abs(),
            Place::At {
                emitting: Emitting::Point,
                ..
            } => self.cone.map_or(1.0, |cone| cone.falloff(direction)),
            Place::Beam(_) => 1.0,
        };
        emission * angular * self.measure / (self.pmf * density)
    }
}

/// Where a lamp's first ray leaves `origin` towards `direction`: off the
/// triangle's side it leaves by, or a point light's own position.
pub(super) fn departure(origin: Vec3, emitting: &Emitting, direction: Vec3) -> Vec3 {
    match *emitting {
        Emitting::Surface { normal, .. } => {
            let side = if direction.dot(normal) >= 0.0 {
                normal
            } else {
                -normal
            };
            offset(origin, side)
        }
        Emitting::Point => origin,
    }
}
