//! Which light next-event estimation samples: the groups of emissive
//! triangles ([`crate::shading::light::LightSet`]: a run of triangles of
//! one material, such as a lamp's mesh), and the lights that are not
//! triangles — point lights, directional lights, spherical lights and an
//! environment map. Each of these lights (a group counting as one) is
//! chosen with a defensive mixture of two probabilities: half
//! proportional to its power (pbrt-v4's power light sampler), half uniform
//! (Mitsuba 3's choice),
//!
//! `P_k = (1 − β) Φ_k / Σ Φ + β / K`, `β` = [`UNIFORM_SHARE`],
//!
//! over the `K` lights of positive power. Why both: by power alone, a
//! lamp of small power that lights a glossy highlight (Veach's
//! multiple-importance test scene: four small spheres of power 1 beside a
//! distant one of 200) gets 0.5 % of the samples and its highlights are
//! noise; uniform alone wastes samples on dim lights beside a bright one.
//! The mixture's probability is at least half of either, so each light's
//! estimate has at most twice the variance it has under the better of the
//! two. The powers:
//!
//! * triangles: `Σ A π L̄` (doubled when two-sided);
//! * point light of intensity `I`: `4π Ī`; a spot light `Ω Ī`, `Ω` its
//!   cone's integrated profile ([`SpotCone::solid_angle_sr`]);
//! * directional light of irradiance `E`: `π r² Ē`, `r` the radius of the
//!   scene's bounding sphere (the power crossing the scene);
//! * environment map: `π r² · 4π L̄`, `L̄` its mean radiance over the sphere;
//! * spherical area light of radius `ρ`: `4π ρ² · π L̄`, sampled in the cone
//!   it subtends ([`crate::shading::sphere_light`]); its triangles are not
//!   among the emissive triangles, and a BSDF sample that hits one is
//!   MIS-weighted with [`LightSampler::sphere_pdf`].
//!
//! Bars are means over the spectral range. The groups' probabilities
//! become their triangles' ([`LightSet::select_groups`], stored in the
//! surface records for MIS); their sum is the triangles' share `P_tri`. A
//! lane whose light number `ξ ≥ P_tri` samples the other lights with
//! `(ξ − P_tri)/(1 − P_tri)`. With one group and no other light
//! `P_tri = 1` and the triangles keep their probabilities by power.
//!
//! [`LightSet::select_groups`]: crate::shading::light::LightSet::select_groups
//!
//! Point and directional lights are delta lights: reached only by NEE
//! (no MIS; their sample's "pdf" is the selection probability and the
//! emission factor carries `1/d²` for points, times the cone's profile
//! for spots: a spot sample outside its cone is `None`, no shadow ray).
//! The environment map is
//! sampled from its piecewise-constant luminance distribution
//! ([`EnvironmentMap::sampling_weights`]) with the solid-angle pdf
//! `P · p(u, v) / (2π² sin θ)`, combined with BSDF sampling by MIS when a
//! path escapes.

use crate::ids::SpectrumId;
use crate::sampling::distribution::Distribution2D;
use crate::shading::sphere_light::{SphereLight, sphere_holding};
use crate::shading::spot_cone::SpotCone;
use crate::spectra::SceneSpectrum;
use crate::spectra::environment::EnvironmentMap;
use glam::Vec3;
use std::f64::consts::PI;

/// The uniform part `β` of the selection probabilities (module docs): a
/// half, which bounds each light's variance to twice that of the better of
/// the power and the uniform choice.
pub const UNIFORM_SHARE: f64 = 0.5;

/// A point light: radiant intensity `scale · I(λ)` in every direction, or
/// `scale · I(λ) · f(θ)` within a spot light's cone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Intensity spectrum `I` (the peak intensity of a spot).
    pub intensity: SpectrumId,
    /// Multiplier.
    pub scale: f32,
    /// The cone of a spot light; `None` emits equally in every direction.
    pub cone: Option<SpotCone>,
}

/// A directional light: irradiance `scale · E(λ)` on surfaces facing it,
/// arriving along `direction`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels.
    pub direction: Vec3,
    /// Irradiance spectrum `E`.
    pub irradiance: SpectrumId,
    /// Multiplier.
    pub scale: f32,
}

/// A light that is not a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
enum OtherLight {
    Point(PointLight),
    Directional(DirectionalLight),
    Environment,
    /// Index in [`LightSampler::spheres`].
    Sphere(usize),
}

/// What a lane's light sample emits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightEmission {
    /// A scene spectrum.
    Spectrum(SpectrumId),
    /// The environment map at these coordinates.
    Environment([f32; 2]),
}

/// A sample of a light that is not a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtherLightSample {
    /// Unit direction towards the light.
    pub wi: Vec3,
    /// Distance to the light ([`f32::INFINITY`] for directional and
    /// environment lights).
    pub distance: f32,
    /// Solid-angle pdf including the selection probability, or for a delta
    /// light the selection probability alone.
    pub pdf: f32,
    /// Whether the light is a delta light (no MIS).
    pub delta: bool,
    /// Multiplier of the emission: `scale / d²` (point; times `f(θ)` for
    /// a spot), `scale`
    /// (directional), 1 (environment).
    pub factor: f32,
    /// The emission.
    pub emission: LightEmission,
}

/// The light selection of a scene (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LightSampler {
    triangle_share: f32,
    others: Vec<OtherLight>,
    /// Absolute selection probability of each other light.
    pmf: Vec<f32>,
    /// CDF over the other lights (conditional on not choosing triangles).
    cdf: Vec<f32>,
    environment: Option<Distribution2D>,
    environment_pmf: f32,
    /// Absolute selection probability of each group of triangles.
    group_shares: Vec<f64>,
    /// The spherical lights, in ascending order of their triangles.
    spheres: Vec<SphereLight>,
    /// Absolute selection probability of each sphere.
    sphere_pmf: Vec<f32>,
}

impl Default for LightSampler {
    fn default() -> Self {
        Self {
            triangle_share: 1.0,
            others: Vec::new(),
            pmf: Vec::new(),
            cdf: Vec::new(),
            environment: None,
            environment_pmf: 0.0,
            group_shares: Vec::new(),
            spheres: Vec::new(),
            sphere_pmf: Vec::new(),
        }
    }
}

/// The lights of a scene as [`LightSampler::new`] reads them.
#[derive(Debug, Clone, Copy)]
pub struct SceneLights<'a> {
    /// Power of each group of emissive triangles (`Σ A π L̄`,
    /// [`crate::shading::light::LightSet::group_powers`]).
    pub triangle_groups: &'a [f64],
    /// Point lights.
    pub points: &'a [PointLight],
    /// Directional lights.
    pub directional: &'a [DirectionalLight],
    /// The environment map.
    pub environment: Option<&'a EnvironmentMap>,
    /// Spherical area lights, in ascending order of their triangles (which
    /// are not among the groups of `triangle_groups`).
    pub spheres: &'a [SphereLight],
    /// Radius of the scene's bounding sphere.
    pub scene_radius: f32,
    /// The scene's spectra (for the mean emissions).
    pub spectra: &'a [SceneSpectrum],
}

impl LightSampler {
    /// The selection of `lights`; an error names a light whose power is not
    /// finite or a spectrum that does not exist.
    pub fn new(lights: &SceneLights<'_>) -> Result<Self, String> {
        let mean = |id: SpectrumId| {
            lights
                .spectra
                .get(id.index())
                .map(SceneSpectrum::mean)
                .ok_or_else(|| format!("light spectrum {} does not exist", id.0))
        };
        let radius = f64::from(lights.scene_radius.max(0.0));
        let mut others = Vec::new();
        let mut powers = Vec::new();
        for light in lights.points {
            others.push(OtherLight::Point(*light));
            let solid_angle_sr = light
                .cone
                .map_or(4.0 * PI, |cone| f64::from(cone.solid_angle_sr()));
            powers.push(solid_angle_sr * f64::from(light.scale) * mean(light.intensity)?);
        }
        for light in lights.directional {
            others.push(OtherLight::Directional(*light));
            powers.push(PI * radius * radius * f64::from(light.scale) * mean(light.irradiance)?);
        }
        let mut environment = None;
        if let Some(map) = lights.environment {
            let (width, height) = map.size();
            let weights = map.sampling_weights();
            // A black map emits nothing and is never sampled.
            if weights.iter().any(|&w| w > 0.0) {
                environment = Some(Distribution2D::new(
                    width as usize,
                    height as usize,
                    &weights,
                )?);
                others.push(OtherLight::Environment);
                powers.push(PI * radius * radius * 4.0 * PI * map.mean_radiance());
            }
        }
        for (index, sphere) in lights.spheres.iter().enumerate() {
            sphere.validate()?;
            if index > 0 && lights.spheres[index - 1].triangles.end > sphere.triangles.start {
                return Err("sphere lights overlap or are not in triangle order".into());
            }
            others.push(OtherLight::Sphere(index));
            powers.push(sphere.area() * PI * mean(sphere.emission)?);
        }
        if let Some(bad) = powers.iter().position(|p| !(p.is_finite() && *p >= 0.0)) {
            return Err(format!("light {bad}: power is not finite"));
        }
        let groups: Vec<f64> = lights.triangle_groups.iter().map(|p| p.max(0.0)).collect();
        let triangle_power: f64 = groups.iter().sum();
        let other_power: f64 = powers.iter().sum();
        let total = triangle_power + other_power;
        if (others.is_empty() && groups.len() <= 1) || total.is_nan() || total <= 0.0 {
            return Ok(Self::default());
        }
        let lit = powers.iter().chain(&groups).filter(|&&p| p > 0.0).count();
        let share = |power: f64| {
            if power > 0.0 {
                (1.0 - UNIFORM_SHARE) * power / total + UNIFORM_SHARE / lit as f64
            } else {
                0.0
            }
        };
        let group_shares: Vec<f64> = groups.iter().map(|&p| share(p)).collect();
        let triangle_share: f64 = if others.is_empty() {
            1.0
        } else {
            group_shares.iter().sum()
        };
        let other_share = 1.0 - triangle_share;
        let mut sampler = Self {
            triangle_share: triangle_share as f32,
            others,
            group_shares,
            ..Self::default()
        };
        let mut running = 0.0;
        for &p in &powers {
            running += share(p);
            sampler.cdf.push((running / other_share) as f32);
            sampler.pmf.push(share(p) as f32);
        }
        if let Some(last) = sampler.cdf.last_mut() {
            *last = 1.0;
        }
        sampler.environment_pmf = sampler
            .others
            .iter()
            .zip(&sampler.pmf)
            .find(|(l, _)| matches!(l, OtherLight::Environment))
            .map_or(0.0, |(_, &p)| p);
        sampler.environment = environment;
        sampler.spheres = lights.spheres.to_vec();
        sampler.sphere_pmf = sampler
            .others
            .iter()
            .zip(&sampler.pmf)
            .filter(|(l, _)| matches!(l, OtherLight::Sphere(_)))
            .map(|(_, &p)| p)
            .collect();
        Ok(sampler)
    }

    /// Checks the invariants: one probability and CDF entry per light, the
    /// CDF non-decreasing to 1, probabilities summing with the triangles'
    /// share to 1, the groups' probabilities to that share, a distribution
    /// exactly when an environment is sampled, one probability per valid
    /// sphere light.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.others.len();
        if self.sphere_pmf.len() != self.spheres.len() {
            return Err(format!(
                "{} sphere lights, {} probabilities",
                self.spheres.len(),
                self.sphere_pmf.len()
            ));
        }
        for sphere in &self.spheres {
            sphere.validate()?;
        }
        if self.pmf.len() != n || self.cdf.len() != n {
            return Err(format!(
                "{n} lights, {} pmf, {} cdf entries",
                self.pmf.len(),
                self.cdf.len()
            ));
        }
        if self.cdf.windows(2).any(|w| w[0] > w[1]) || self.cdf.last().is_some_and(|&c| c != 1.0) {
            return Err("the CDF of the other lights is not a CDF".into());
        }
        let sum: f32 = self.pmf.iter().sum::<f32>() + self.triangle_share;
        if (sum - 1.0).abs() > 1e-4 {
            return Err(format!("selection probabilities sum to {sum}"));
        }
        let groups: f64 = self.group_shares.iter().sum();
        if !self.group_shares.is_empty() && (groups - f64::from(self.triangle_share)).abs() > 1e-4 {
            return Err(format!(
                "the groups' probabilities sum to {groups}, the triangles' share is {}",
                self.triangle_share
            ));
        }
        let sampled = self.others.contains(&OtherLight::Environment);
        match (&self.environment, sampled) {
            (Some(d), true) => d.validate(),
            (None, false) => Ok(()),
            _ => Err("environment distribution without the light, or the reverse".into()),
        }
    }

    /// The probability that NEE samples the emissive triangles.
    #[inline]
    pub fn triangle_share(&self) -> f32 {
        self.triangle_share
    }

    /// The absolute selection probability of each group of triangles
    /// (empty when the triangles keep their probabilities by power: one
    /// group and no other light).
    pub fn group_shares(&self) -> &[f64] {
        &self.group_shares
    }

    /// Whether there are lights besides triangles.
    #[inline]
    pub fn has_others(&self) -> bool {
        !self.others.is_empty()
    }

    /// Number of lights besides triangles.
    pub fn other_count(&self) -> usize {
        self.others.len()
    }

    /// The emission spectra of the point (and spot) and directional lights (the
    /// environment's spectrum is [`crate::scene::Scene::environment`]).
    pub fn emission_spectra(&self) -> impl Iterator<Item = SpectrumId> + '_ {
        self.others.iter().filter_map(|light| match light {
            OtherLight::Point(p) => Some(p.intensity),
            OtherLight::Directional(d) => Some(d.irradiance),
            OtherLight::Sphere(index) => self.spheres.get(*index).map(|s| s.emission),
            OtherLight::Environment => None,
        })
    }

    /// Whether some lights are spheres.
    #[inline]
    pub fn has_spheres(&self) -> bool {
        !self.spheres.is_empty()
    }

    /// The spherical lights.
    pub fn spheres(&self) -> &[SphereLight] {
        &self.spheres
    }

    /// The spherical lights, each with its absolute selection probability.
    pub fn spheres_with_pmf(&self) -> impl Iterator<Item = (&SphereLight, f32)> + '_ {
        self.spheres.iter().zip(self.sphere_pmf.iter().copied())
    }

    /// Whether triangle `triangle` belongs to a sphere light that NEE
    /// chooses with a positive probability.
    pub fn in_chosen_sphere(&self, triangle: u32) -> bool {
        sphere_holding(&self.spheres, triangle)
            .and_then(|index| self.sphere_pmf.get(index))
            .is_some_and(|&pmf| pmf > 0.0)
    }

    /// The directional lights, each with its absolute selection
    /// probability.
    pub fn directional_lights(&self) -> impl Iterator<Item = (&DirectionalLight, f32)> + '_ {
        self.others_with_pmf()
            .filter_map(|(light, pmf)| match light {
                OtherLight::Directional(directional) => Some((directional, pmf)),
                _ => None,
            })
    }

    /// The point and spot lights, each with its absolute selection
    /// probability.
    pub fn point_lights(&self) -> impl Iterator<Item = (&PointLight, f32)> + '_ {
        self.others_with_pmf()
            .filter_map(|(light, pmf)| match light {
                OtherLight::Point(point) => Some((point, pmf)),
                _ => None,
            })
    }

    /// The lights that are not triangles, each with its absolute
    /// selection probability.
    fn others_with_pmf(&self) -> impl Iterator<Item = (&OtherLight, f32)> + '_ {
        self.others.iter().zip(self.pmf.iter().copied())
    }

    /// The solid-angle pdf (with the selection probability) with which NEE
    /// samples the sphere light that triangle `triangle` belongs to, seen
    /// from `origin`: the MIS weight of a BSDF sample that hits it. `None`
    /// if the triangle is not a sphere light's.
    pub fn sphere_pdf(&self, triangle: u32, origin: Vec3) -> Option<f32> {
        let index = sphere_holding(&self.spheres, triangle)?;
        Some(self.sphere_pmf.get(index)? * self.spheres.get(index)?.pdf_sr(origin))
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.others.capacity() * size_of::<OtherLight>()
            + (self.pmf.capacity() + self.cdf.capacity() + self.sphere_pmf.capacity())
                * size_of::<f32>()
            + self.spheres.capacity() * size_of::<SphereLight>()
            + self
                .environment
                .as_ref()
                .map_or(0, Distribution2D::memory_bytes)
    }

    /// Samples one of the other lights: `u_light` (the rescaled light
    /// number in [0, 1)) picks it, `(u, v)` the direction or point on it,
    /// seen from `origin`. `None` if there is no other light or the sample is
    /// unusable (zero pdf, a point light at the origin).
    pub fn sample(
        &self,
        u_light: f32,
        uv: [f32; 2],
        origin: Vec3,
        map: Option<&EnvironmentMap>,
    ) -> Option<OtherLightSample> {
        let index = self.pick(u_light)?;
        let point = match self.others.get(index)? {
            OtherLight::Environment => self.environment.as_ref()?.sample(uv),
            _ => (uv, 0.0),
        };
        self.finish(index, point, origin, map)
    }

    /// [`Self::sample`] of every `Some((u_light, uv, origin))` of
    /// `requests`, bit for bit: the environment's points are drawn for all
    /// of them at once ([`Distribution2D::sample_batch`], whose loads
    /// overlap), then each sample is finished as [`Self::sample`] does.
    pub fn sample_batch<const L: usize>(
        &self,
        requests: [Option<(f32, [f32; 2], Vec3)>; L],
        map: Option<&EnvironmentMap>,
    ) -> [Option<OtherLightSample>; L] {
        let picks = requests.map(|r| r.and_then(|(u_light, _, _)| self.pick(u_light)));
        let points = core::array::from_fn(|k| match (picks[k], requests[k]) {
            (Some(index), Some((_, uv, _)))
                if matches!(self.others.get(index), Some(OtherLight::Environment)) =>
            {
                Some(uv)
            }
            _ => None,
        });
        let environment = self
            .environment
            .as_ref()
            .map_or([None; L], |d| d.sample_batch(points));
        core::array::from_fn(|k| {
            let index = picks[k]?;
            let (_, uv, origin) = requests[k]?;
            let point = match self.others.get(index)? {
                OtherLight::Environment => environment[k]?,
                _ => (uv, 0.0),
            };
            self.finish(index, point, origin, map)
        })
    }

    /// The other light that `u_light` picks.
    fn pick(&self, u_light: f32) -> Option<usize> {
        let last = self.others.len().checked_sub(1)?;
        Some(self.cdf.partition_point(|&c| c <= u_light).min(last))
    }

    /// The sample of light `index` seen from `origin`, with the point
    /// `(uv, pdf_uv)` drawn from the environment's distribution when it is
    /// the environment, the sample's own `(uv, 0)` for a sphere (ignored
    /// for the delta lights).
    fn finish(
        &self,
        index: usize,
        (uv, pdf_uv): ([f32; 2], f32),
        origin: Vec3,
        map: Option<&EnvironmentMap>,
    ) -> Option<OtherLightSample> {
        let pmf = *self.pmf.get(index)?;
        match *self.others.get(index)? {
            OtherLight::Sphere(sphere) => {
                let sphere = self.spheres.get(sphere)?;
                let sample = sphere.sample(origin, uv)?;
                Some(OtherLightSample {
                    wi: sample.wi,
                    distance: sample.distance,
                    pdf: pmf * sample.pdf_sr,
                    delta: false,
                    factor: 1.0,
                    emission: LightEmission::Spectrum(sphere.emission),
                })
            }
            OtherLight::Point(light) => {
                let to = light.position - origin;
                let distance_sq = to.length_squared();
                let distance = distance_sq.sqrt();
                if !(distance_sq > 0.0 && distance_sq.is_finite()) {
                    return None;
                }
                let falloff = light.cone.map_or(1.0, |cone| cone.falloff(-to));
                (falloff > 0.0).then(|| OtherLightSample {
                    wi: to / distance,
                    distance,
                    pdf: pmf,
                    delta: true,
                    factor: light.scale * falloff / distance_sq,
                    emission: LightEmission::Spectrum(light.intensity),
                })
            }
            OtherLight::Directional(light) => Some(OtherLightSample {
                wi: -light.direction,
                distance: f32::INFINITY,
                pdf: pmf,
                delta: true,
                factor: light.scale,
                emission: LightEmission::Spectrum(light.irradiance),
            }),
            OtherLight::Environment => {
                let map = map?;
                let (wi, sin_theta) = map.direction_of(uv);
                let pdf = pmf * pdf_uv / (2.0 * std::f32::consts::PI.powi(2) * sin_theta);
                (sin_theta > 0.0 && pdf > 0.0 && pdf.is_finite()).then_some(OtherLightSample {
                    wi,
                    distance: f32::INFINITY,
                    pdf,
                    delta: false,
                    factor: 1.0,
                    emission: LightEmission::Environment(uv),
                })
            }
        }
    }

    /// The solid-angle pdf (with the selection probability) with which NEE
    /// samples the environment towards `direction`: the MIS weight of a
    /// BSDF sample that escapes. 0 without an environment map.
    pub fn environment_pdf(&self, map: &EnvironmentMap, direction: Vec3) -> f32 {
        let (uv, sin_theta) = map.uv_and_sin_theta(direction);
        self.environment_pdf_at(uv, sin_theta)
    }

    /// [`LightSampler::environment_pdf`] at map coordinates `uv` with
    /// their `sin θ` ([`EnvironmentMap::uv_and_sin_theta`]).
    pub fn environment_pdf_at(&self, uv: [f32; 2], sin_theta: f32) -> f32 {
        let Some(distribution) = &self.environment else {
            return 0.0;
        };
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.environment_pmf * distribution.pdf(uv)
            / (2.0 * std::f32::consts::PI.powi(2) * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use crate::spectra::SpectrumSource;
    use crate::spectra::environment::EnvironmentImage;
    use glam::Mat3;
    use spectral_core::SpectralRange;
    use std::f32::consts::PI as PI32;

    /// A map brightest towards `+x` and up, dark below, rotated.
    fn map(sun_gain: f32) -> EnvironmentMap {
        let (w, h) = (32u32, 16u32);
        let mut rgb = Vec::new();
        for r in 0..h {
            for c in 0..w {
                let (u, v) = ((c as f32 + 0.5) / w as f32, (r as f32 + 0.5) / h as f32);
                let lobe = (0.5 + 0.5 * (2.0 * PI32 * u).sin()).powi(3);
                let sky = if v < 0.5 { 1.0 } else { 0.05 };
                rgb.push([0.2 + sun_gain * lobe * sky, 0.3 * sky, 0.1]);
            }
        }
        let image = EnvironmentImage {
            width: w,
            height: h,
            rgb: &rgb,
            scale: 1.0,
            to_world: Mat3::from_rotation_y(0.4),
        };
        match EnvironmentMap::new(&image, SpectralRange::VISIBLE) {
            Ok(m) => m,
            Err(e) => panic!("{e}"),
        }
    }

    fn sampler(map: &EnvironmentMap) -> LightSampler {
        let spectra = [];
        match LightSampler::new(&SceneLights {
            triangle_groups: &[],
            points: &[],
            directional: &[],
            environment: Some(map),
            spheres: &[],
            scene_radius: 1.0,
            spectra: &spectra,
        }) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        }
    }

    /// Direction bins: `PHI` longitudes × `Z` bands of equal `cos θ` about
    /// the world `+y` axis (not the map's rows: the map is rotated).
    const PHI: usize = 12;
    const Z: usize = 8;

    fn bin(d: Vec3) -> usize {
        let z = ((d.y + 1.0) / 2.0 * Z as f32).clamp(0.0, Z as f32 - 1.0) as usize;
        let phi = (d.z.atan2(d.x) / std::f32::consts::TAU).rem_euclid(1.0);
        let p = ((phi * PHI as f32) as usize).min(PHI - 1);
        z * PHI + p
    }

    /// The probability of each bin under `environment_pdf` of `map`, by a
    /// midpoint rule over 64 × 64 points per bin.
    fn expected(sampler: &LightSampler, map: &EnvironmentMap) -> Vec<f64> {
        const FINE: usize = 64;
        let mut p = vec![0.0f64; PHI * Z];
        let cell = (2.0 / (Z * FINE) as f64) * (std::f64::consts::TAU / (PHI * FINE) as f64);
        for zi in 0..Z * FINE {
            let y = -1.0 + (zi as f64 + 0.5) * 2.0 / (Z * FINE) as f64;
            let s = (1.0 - y * y).sqrt();
            for pi in 0..PHI * FINE {
                let phi = (pi as f64 + 0.5) * std::f64::consts::TAU / (PHI * FINE) as f64;
                let d = Vec3::new((s * phi.cos()) as f32, y as f32, (s * phi.sin()) as f32);
                p[bin(d)] += f64::from(sampler.environment_pdf(map, d)) * cell;
            }
        }
        p
    }

    /// χ² of sampled directions against the bins' expected counts; the
    /// critical value for p = 10⁻⁴ by the Wilson–Hilferty approximation
    /// `k (1 − 2/9k + z √(2/9k))³`, `z = 3.719` (the normal quantile).
    fn chi_squared(counts: &[u64], probabilities: &[f64], n: u64) -> (f64, f64) {
        let mut chi2 = 0.0;
        let mut bins = 0;
        for (&c, &p) in counts.iter().zip(probabilities) {
            let e = p * n as f64;
            if e > 5.0 {
                chi2 += (c as f64 - e).powi(2) / e;
                bins += 1;
            }
        }
        let k = f64::from(bins - 1);
        let z = 3.719;
        let a = 2.0 / (9.0 * k);
        (chi2, k * (1.0 - a + z * a.sqrt()).powi(3))
    }

    #[test]
    fn sampled_environment_directions_follow_their_pdf() {
        let env = map(4.0);
        let s = sampler(&env);
        assert_eq!(s.validate(), Ok(()));
        assert_eq!(s.triangle_share(), 0.0);
        let p = expected(&s, &env);
        let total: f64 = p.iter().sum();
        assert!((total - 1.0).abs() < 2e-3, "pdf integrates to {total}");
        let n = 200_000u64;
        let mut rng = Rng::new(5, 9);
        let mut counts = vec![0u64; PHI * Z];
        for _ in 0..n {
            let u = [rng.next_f32(), rng.next_f32()];
            let Some(sample) = s.sample(rng.next_f32(), u, Vec3::ZERO, Some(&env)) else {
                panic!("no sample");
            };
            // The sample's pdf is the pdf of its direction.
            let pdf = s.environment_pdf(&env, sample.wi);
            assert!(
                (pdf - sample.pdf).abs() <= 1e-3 * pdf,
                "{pdf} vs {} at {:?} {:?}",
                sample.pdf,
                sample.wi,
                env.uv_and_sin_theta(sample.wi)
            );
            counts[bin(sample.wi)] += 1;
        }
        let (chi2, critical) = chi_squared(&counts, &p, n);
        assert!(chi2 < critical, "χ² {chi2} ≥ {critical}");
        // Negative control: the expected counts of a map with a weaker sun.
        let other = map(3.0);
        let q = expected(&sampler(&other), &other);
        let (chi2_wrong, critical_wrong) = chi_squared(&counts, &q, n);
        assert!(
            chi2_wrong > critical_wrong,
            "a wrong map passes: {chi2_wrong}"
        );
    }

    /// Each request of a batch gets the sample that [`LightSampler::sample`]
    /// draws for it alone, bit for bit (absent requests none), with an
    /// environment, a point light and a directional light to pick from, and
    /// without a map (no environment sample). The numbers include the ends
    /// of `[0, 1)` and values past them, which both clamp.
    #[test]
    fn a_batch_samples_what_each_request_samples_alone() {
        let env = map(4.0);
        let range = SpectralRange::VISIBLE;
        let spectra: Vec<SceneSpectrum> = [1.0, 2.0]
            .iter()
            .filter_map(|&c| SceneSpectrum::new(SpectrumSource::Constant(c), range).ok())
            .collect();
        let sampler = match LightSampler::new(&SceneLights {
            triangle_groups: &[1.0],
            points: &[PointLight {
                position: Vec3::new(0.5, 2.0, -1.0),
                intensity: SpectrumId(0),
                scale: 3.0,
                cone: None,
            }],
            directional: &[DirectionalLight {
                direction: Vec3::new(0.0, -1.0, 0.0),
                irradiance: SpectrumId(1),
                scale: 0.5,
            }],
            environment: Some(&env),
            spheres: &[SphereLight {
                center: Vec3::new(0.0, 3.0, 0.5),
                radius: 0.5,
                emission: SpectrumId(1),
                triangles: 4..20,
            }],
            scene_radius: 2.0,
            spectra: &spectra,
        }) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(sampler.validate(), Ok(()));
        assert_eq!(sampler.other_count(), 4);
        let mut rng = Rng::new(17, 3);
        let ends = [0.0, 1.0 - f32::EPSILON / 2.0, 1.0, -0.25, f32::NAN];
        let number = |rng: &mut Rng| {
            if rng.next_f32() < 0.1 {
                ends[(rng.next_u32() % ends.len() as u32) as usize]
            } else {
                rng.next_f32()
            }
        };
        let mut environment_samples = 0;
        for round in 0..3000 {
            let requests: [Option<(f32, [f32; 2], Vec3)>; 8] = core::array::from_fn(|_| {
                (rng.next_f32() < 0.8).then(|| {
                    let origin = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                    (rng.next_f32(), [number(&mut rng), number(&mut rng)], origin)
                })
            });
            let map = (round % 5 != 0).then_some(&env);
            let batch = sampler.sample_batch(requests, map);
            for (request, got) in requests.iter().zip(batch) {
                let alone = request
                    .and_then(|(u_light, uv, origin)| sampler.sample(u_light, uv, origin, map));
                let bits = |s: Option<OtherLightSample>| {
                    s.map(|s| {
                        let emission = match s.emission {
                            LightEmission::Spectrum(id) => [id.0, 0, 0],
                            LightEmission::Environment(uv) => {
                                [u32::MAX, uv[0].to_bits(), uv[1].to_bits()]
                            }
                        };
                        (
                            s.wi.to_array().map(f32::to_bits),
                            [s.distance, s.pdf, s.factor].map(f32::to_bits),
                            s.delta,
                            emission,
                        )
                    })
                };
                assert_eq!(bits(got), bits(alone), "{request:?}");
                if matches!(alone, Some(s) if matches!(s.emission, LightEmission::Environment(_))) {
                    environment_samples += 1;
                }
            }
        }
        assert!(
            environment_samples > 1000,
            "{environment_samples} environment samples"
        );
    }

    /// The selection mixes power and uniform choice (module docs) over the
    /// lights of positive power, the triangles counting as one; a sphere
    /// light's MIS pdf is its selection probability over its cone's solid
    /// angle, for its own triangles only.
    #[test]
    fn selection_mixes_power_and_uniform_choice() {
        let range = SpectralRange::VISIBLE;
        let spectra: Vec<SceneSpectrum> = [1.0, 0.0]
            .iter()
            .filter_map(|&c| SceneSpectrum::new(SpectrumSource::Constant(c), range).ok())
            .collect();
        let point = |scale: f32| PointLight {
            position: Vec3::new(0.0, 1.0, 0.0),
            intensity: SpectrumId(0),
            scale,
            cone: None,
        };
        let sphere = |triangles: std::ops::Range<u32>, radius: f32| SphereLight {
            center: Vec3::new(0.0, 0.0, 5.0),
            radius,
            emission: SpectrumId(0),
            triangles,
        };
        let spheres = [sphere(10..30, 0.5), sphere(30..40, 2.0)];
        let points = [point(1.0), point(0.0)];
        let lights = SceneLights {
            triangle_groups: &[1.0, 2.0],
            points: &points,
            directional: &[],
            environment: None,
            spheres: &spheres,
            scene_radius: 10.0,
            spectra: &spectra,
        };
        let sampler = LightSampler::new(&lights).expect("valid lights");
        assert_eq!(sampler.validate(), Ok(()));
        // Powers: two groups of triangles 1 and 2, points 4π and 0, spheres
        // 4π² ρ²; five lights of positive power.
        let pi = PI;
        let powers = [1.0, 2.0, 4.0 * pi, 0.0, pi * pi, 16.0 * pi * pi];
        let total: f64 = powers.iter().sum();
        let expected: Vec<f64> = powers
            .iter()
            .map(|&p| {
                if p > 0.0 {
                    0.5 * p / total + 0.5 / 5.0
                } else {
                    0.0
                }
            })
            .collect();
        let close = |a: f64, b: f64| (a - b).abs() < 1e-6;
        assert!(close(sampler.group_shares()[0], expected[0]));
        assert!(close(sampler.group_shares()[1], expected[1]));
        let share = f64::from(sampler.triangle_share());
        assert!(close(share, expected[0] + expected[1]), "{share}");
        for (k, &want) in expected[2..].iter().enumerate() {
            let got = f64::from(sampler.pmf[k]);
            assert!(close(got, want), "light {k}: {got}");
        }
        // The MIS pdf of a sphere's triangle: its probability over Ω.
        let origin = Vec3::ZERO;
        let want = sampler.pmf[2] * spheres[0].pdf_sr(origin);
        assert_eq!(sampler.sphere_pdf(10, origin), Some(want));
        assert_eq!(sampler.sphere_pdf(29, origin), Some(want));
        let want = sampler.pmf[3] * spheres[1].pdf_sr(origin);
        assert_eq!(sampler.sphere_pdf(30, origin), Some(want));
        assert_eq!(sampler.sphere_pdf(9, origin), None);
        assert_eq!(sampler.sphere_pdf(40, origin), None);
        // Samples come from the cone: every direction towards the sphere.
        let mut rng = Rng::new(5, 1);
        let mut sphere_samples = 0;
        for _ in 0..2000 {
            let u_light = rng.next_f32();
            let uv = [rng.next_f32(), rng.next_f32()];
            if let Some(s) = sampler.sample(u_light, uv, origin, None)
                && !s.delta
            {
                sphere_samples += 1;
                let to_center = Vec3::new(0.0, 0.0, 5.0) - origin;
                assert!(s.wi.dot(to_center.normalize()) > 0.9, "{:?}", s.wi);
                assert!(s.pdf > 0.0 && s.distance > 2.9 && s.distance < 5.0);
            }
        }
        assert!(sphere_samples > 800, "{sphere_samples}");
        // Negative control: spheres out of triangle order are refused.
        let swapped = [spheres[1].clone(), spheres[0].clone()];
        let refused = LightSampler::new(&SceneLights {
            spheres: &swapped,
            ..lights
        });
        assert!(refused.is_err());
    }
}
