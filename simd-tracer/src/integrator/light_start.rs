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
//! sphere light `β = L_e(λ) cos θ 4πρ² / (P p(ω))`. The environment and
//! directional lights start none: they have no position to start from.

use super::light_aim::{Emitting, uniform_sphere};
use super::packet_shading::offset;
use super::path::ONE_BELOW;
use crate::ids::SpectrumId;
use crate::scene::Scene;
use crate::shading::light_sampler::PointLight;
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
    /// `S = P_tri + Σ P_k`.
    total: f32,
}

/// A light path's first vertex (module docs).
#[derive(Debug, Clone, Copy)]
pub(super) struct LightStart {
    /// Where the path leaves.
    pub origin: Vec3,
    /// How the light emits.
    pub emitting: Emitting,
    /// `L_e` or `I`.
    pub emission: SpectrumId,
    /// `A` or `s`.
    pub measure: f32,
    /// `P`.
    pub pmf: f32,
    /// A spot's cone.
    cone: Option<SpotCone>,
}

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
        let others = points.iter().map(|(_, pmf)| pmf);
        let total = triangle_share
            + others
                .chain(spheres.iter().map(|(_, pmf)| pmf))
                .sum::<f32>();
        (total > 0.0).then_some(Self {
            triangle_share,
            points,
            spheres,
            total,
        })
    }

    /// The start chosen by `u_light`, its point on a triangle or a sphere
    /// by `(u, v)` (all in `[0, 1)`); `None` where the light emits nothing
    /// there.
    pub(super) fn choose(&self, scene: &Scene, u_light: f32, u: f32, v: f32) -> Option<LightStart> {
        let x = u_light * self.total;
        let triangles_only = self.points.is_empty() && self.spheres.is_empty();
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
                origin: light.point,
                emitting: Emitting::Surface {
                    normal: surface.normal,
                    two_sided: surface.two_sided,
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
        // Rounding left `x` past the last end: the last light.
        match (self.spheres.last(), self.points.last()) {
            (Some((light, pmf)), _) => Some(self.sphere_start(light, *pmf, (u, v))),
            (None, Some((light, pmf))) => Some(self.point_start(light, *pmf)),
            (None, None) => None,
        }
    }

    /// The start at point light `light`, chosen with `P_k = pmf`.
    fn point_start(&self, light: &PointLight, pmf: f32) -> LightStart {
        LightStart {
            origin: light.position,
            emitting: Emitting::Point,
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
            origin: light.center + light.radius * normal,
            emitting: Emitting::Surface {
                normal,
                two_sided: false,
            },
            emission: light.emission,
            measure: 4.0 * PI * light.radius * light.radius,
            pmf: pmf / self.total,
            cone: None,
        }
    }
}

impl LightStart {
    /// `β = L_e |cos θ| A / (P p)` or `s I f(θ) / (P p)` at one wavelength
    /// (module docs), from the emission there, the unit `direction` and its
    /// density `pdf_sr`.
    pub(super) fn beta(&self, emission: f32, direction: Vec3, pdf_sr: f32) -> f32 {
        let angular = match self.emitting {
            Emitting::Surface { normal, .. } => direction.dot(normal).abs(),
            Emitting::Point => self.cone.map_or(1.0, |cone| cone.falloff(direction)),
        };
        emission * angular * self.measure / (self.pmf * pdf_sr)
    }

    /// Where the first ray leaves towards `direction`: off the triangle's
    /// side it leaves by, or the light's own position.
    pub(super) fn departure(&self, direction: Vec3) -> Vec3 {
        match self.emitting {
            Emitting::Surface { normal, .. } => {
                let side = if direction.dot(normal) >= 0.0 {
                    normal
                } else {
                    -normal
                };
                offset(self.origin, side)
            }
            Emitting::Point => self.origin,
        }
    }
}
