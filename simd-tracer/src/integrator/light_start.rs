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
//! `S`), a point light `P_k / S`. Without point lights `S = P_tri` and the
//! choice is the triangles' as before, number for number.
//!
//! **The start.** `β = L_e(λ) |cos θ| A / (P p(ω))` on a triangle (the
//! point uniform on it, density `1/A`), `β = s I(λ) f(θ) / (P p(ω))` at a
//! point light of intensity `s I` and spot profile `f` (1 without a
//! cone), `p(ω)` the first direction's density (`light_aim.rs`). The
//! environment, directional lights and spherical lights start none: a
//! camera path can hit a sphere light through glass, which would need the
//! camera side's partition to know it, and the others have no position.

use super::light_aim::Emitting;
use super::packet_shading::offset;
use super::path::ONE_BELOW;
use crate::ids::SpectrumId;
use crate::scene::Scene;
use crate::shading::light_sampler::PointLight;
use crate::shading::spot_cone::SpotCone;
use glam::Vec3;

/// The lights light paths start from and their probabilities (module
/// docs).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LightStarts {
    /// `P_tri`, 0 where no path starts on a triangle.
    triangle_share: f32,
    /// The point and spot lights with their absolute probabilities `P_k`.
    points: Vec<(PointLight, f32)>,
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
        let total = triangle_share + points.iter().map(|(_, pmf)| pmf).sum::<f32>();
        (total > 0.0).then_some(Self {
            triangle_share,
            points,
            total,
        })
    }

    /// The start chosen by `u_light`, its point on a triangle by `(u, v)`
    /// (all in `[0, 1)`); `None` where the light emits nothing there.
    pub(super) fn choose(&self, scene: &Scene, u_light: f32, u: f32, v: f32) -> Option<LightStart> {
        let x = u_light * self.total;
        if self.points.is_empty() || x < self.triangle_share {
            // Without point lights `u_light` is the triangles' own number,
            // unscaled, so their paths are those of before, bit for bit.
            let u_triangle = if self.points.is_empty() {
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
        let (light, pmf) = self
            .points
            .iter()
            .find(|(_, pmf)| {
                end += pmf;
                x < end
            })
            .or(self.points.last())?;
        Some(LightStart {
            origin: light.position,
            emitting: Emitting::Point,
            emission: light.intensity,
            measure: light.scale,
            pmf: pmf / self.total,
            cone: light.cone,
        })
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
