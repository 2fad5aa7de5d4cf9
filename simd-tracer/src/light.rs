//! Emissive triangles and their sampling for next-event estimation.
//!
//! A light is chosen with probability proportional to its power
//! `Φ ∝ A · π · mean(L_e)` (doubled if two-sided), then a point uniformly on
//! the triangle (`b0 = 1 − √u`, `b1 = v √u`; Turk 1990). The solid-angle pdf
//! of a point `y` seen from `x` is `P(light) · |x − y|² / (A cos θ_y)`, the
//! same expression MIS uses when a BSDF-sampled ray hits the light.

use crate::packet::{LANES, LaneMask};
use crate::simd::Vec3x8;
use crate::spectra::SceneSpectrum;
use crate::surface::{NO_ID, Surface, SurfacePacket};
use glam::Vec3;
use std::f32::consts::PI;
use wide::f32x8;

/// No light on this triangle.
const NOT_A_LIGHT: u32 = u32::MAX;

/// One emissive triangle as light sampling reads it: its vertices and its
/// shading record (normal, emission, sides, selection probability, area),
/// in one place so a lane's sample is one record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Triangle index in the scene.
    pub triangle: u32,
    /// Vertices.
    pub vertices: [Vec3; 3],
    /// The triangle's shading record.
    pub surface: Surface,
}

/// The emissive triangles of a scene.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LightSet {
    lights: Vec<Light>,
    cdf: Vec<f32>,
    light_of_triangle: Vec<u32>,
}

/// A sampled point on a light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    /// The point.
    pub point: Vec3,
    /// The triangle.
    pub triangle: u32,
    /// The triangle's shading record (normal, emission, probability of
    /// having chosen it, area).
    pub surface: Surface,
}

impl LightSet {
    /// Collects every triangle whose record emits with positive power and
    /// fills in the records' [`Surface::light_pmf`] (power-proportional).
    pub fn new(
        triangles: &[[Vec3; 3]],
        surfaces: &mut [Surface],
        spectra: &[SceneSpectrum],
    ) -> Self {
        let mut set = Self {
            light_of_triangle: vec![NOT_A_LIGHT; surfaces.len()],
            ..Self::default()
        };
        let mut powers = Vec::new();
        for (index, (vertices, surface)) in (0u32..).zip(triangles.iter().zip(surfaces.iter_mut()))
        {
            surface.light_pmf = 0.0;
            if surface.emission == NO_ID {
                continue;
            }
            let mean = spectra
                .get(surface.emission as usize)
                .map_or(0.0, SceneSpectrum::mean);
            let sides = if surface.two_sided { 2.0 } else { 1.0 };
            let power = f64::from(surface.area) * PI as f64 * mean * sides;
            if power > 0.0 && power.is_finite() {
                set.light_of_triangle[index as usize] = set.lights.len() as u32;
                set.lights.push(Light {
                    triangle: index,
                    vertices: *vertices,
                    surface: *surface,
                });
                powers.push(power);
            }
        }
        let total: f64 = powers.iter().sum();
        let mut running = 0.0;
        for (light, p) in set.lights.iter_mut().zip(&powers) {
            running += p;
            set.cdf.push((running / total) as f32);
            let pmf = (p / total) as f32;
            light.surface.light_pmf = pmf;
            if let Some(surface) = surfaces.get_mut(light.triangle as usize) {
                surface.light_pmf = pmf;
            }
        }
        if let Some(last) = set.cdf.last_mut() {
            *last = 1.0;
        }
        set
    }

    /// Number of emissive triangles.
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    /// Whether the scene has no emissive triangle.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Probability that next-event estimation picks triangle `triangle`.
    pub fn pmf_of_triangle(&self, triangle: u32) -> f32 {
        match self.light_of_triangle.get(triangle as usize) {
            Some(&light) if light != NOT_A_LIGHT => self
                .lights
                .get(light as usize)
                .map_or(0.0, |l| l.surface.light_pmf),
            _ => 0.0,
        }
    }

    /// The light `u_light` picks (inverting the CDF).
    fn choose(&self, u_light: f32) -> Option<&Light> {
        let last = self.lights.len().checked_sub(1)?;
        let light = self.cdf.partition_point(|&c| c <= u_light).min(last);
        self.lights.get(light)
    }

    /// Picks a light with `u_light` and a point on it with `(u, v)`.
    pub fn sample(&self, u_light: f32, u: f32, v: f32) -> Option<LightSample> {
        let light = self.choose(u_light)?;
        let [a, b, c] = light.vertices;
        let su = u.sqrt();
        let (b0, b1) = (1.0 - su, v * su);
        let point = a * b0 + b * b1 + c * (1.0 - b0 - b1);
        Some(LightSample {
            point,
            triangle: light.triangle,
            surface: light.surface,
        })
    }

    /// [`LightSet::sample`] for the active lanes of a packet: the light
    /// choice per lane, the point on it 8-wide (the same operations, so the
    /// same bits lane by lane).
    pub fn sample_packet(
        &self,
        active: LaneMask,
        u_light: &[f32; LANES],
        u: f32x8,
        v: f32x8,
    ) -> LightSamplePacket {
        let mut corners = [[Vec3::ZERO; LANES]; 3];
        let mut records = [Surface::NONE; LANES];
        let mut triangle = [0u32; LANES];
        let mut valid = LaneMask::NONE;
        for lane in active.iter() {
            if let Some(light) = self.choose(u_light[lane]) {
                for (corner, &vertex) in corners.iter_mut().zip(&light.vertices) {
                    corner[lane] = vertex;
                }
                records[lane] = light.surface;
                triangle[lane] = light.triangle;
                valid = valid.with(lane);
            }
        }
        let su = u.sqrt();
        let b0 = f32x8::ONE - su;
        let b1 = v * su;
        let b2 = f32x8::ONE - b0 - b1;
        let [a, b, c] = corners.map(|lanes| Vec3x8::from_lanes(&lanes));
        LightSamplePacket {
            point: a * b0 + b * b1 + c * b2,
            triangle,
            surface: SurfacePacket::from_records(&records),
            valid,
        }
    }
}

/// Light samples for a packet.
#[derive(Debug, Clone, Copy)]
pub struct LightSamplePacket {
    /// Points on the lights.
    pub point: Vec3x8,
    /// Chosen triangles.
    pub triangle: [u32; LANES],
    /// Their shading records ([`Surface::NONE`] in lanes without a sample).
    pub surface: SurfacePacket,
    /// Lanes with a sample.
    pub valid: LaneMask,
}

/// Solid-angle pdf of sampling `point` on a light of area `area` chosen with
/// `pmf`, seen along a segment of squared length `distance_sq` that makes
/// cosine `cos_light` with the light's normal (0 if the cosine is 0).
pub fn light_pdf_solid_angle(pmf: f32, area: f32, distance_sq: f32, cos_light: f32) -> f32 {
    let cos = cos_light.abs();
    if cos <= 0.0 || area <= 0.0 {
        return 0.0;
    }
    pmf * distance_sq / (area * cos)
}

/// Whether a light with this material emits towards a viewer on the side
/// given by `cos_light = normal · (to viewer)`.
pub fn emits_towards(two_sided: bool, cos_light: f32) -> bool {
    cos_light > 0.0 || (two_sided && cos_light < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::rng::Rng;
    use crate::spectra::SpectrumSource;
    use spectral_core::SpectralRange;

    /// Three triangles: a dim light, a grey non-emitter, a bright light
    /// (three times the dim one's radiance).
    fn lights() -> (Vec<[Vec3; 3]>, Vec<Surface>, LightSet) {
        let range = SpectralRange::VISIBLE;
        let spectra: Vec<SceneSpectrum> = [1.0, 3.0]
            .iter()
            .filter_map(|&c| SceneSpectrum::new(SpectrumSource::Constant(c), range).ok())
            .collect();
        assert_eq!(spectra.len(), 2);
        let mut dim = Material::lambert("dim", 0);
        dim.emission = Some(0);
        let mut bright = Material::lambert("bright", 0);
        bright.emission = Some(1);
        let grey = Material::lambert("grey", 0);
        let tri = |x: f32| {
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
            ]
        };
        let triangles = vec![tri(0.0), tri(2.0), tri(4.0)];
        let mut surfaces: Vec<Surface> = [dim, grey, bright]
            .iter()
            .zip(0..)
            .map(|(m, id)| Surface::new(Vec3::Z, 0.5, id, m))
            .collect();
        let set = LightSet::new(&triangles, &mut surfaces, &spectra);
        (triangles, surfaces, set)
    }

    #[test]
    fn power_weighted_selection() {
        let (_, surfaces, set) = lights();
        assert_eq!(set.len(), 2);
        assert!((set.pmf_of_triangle(0) - 0.25).abs() < 1e-6);
        assert_eq!(set.pmf_of_triangle(1), 0.0);
        assert!((set.pmf_of_triangle(2) - 0.75).abs() < 1e-6);
        for (index, surface) in (0u32..).zip(&surfaces) {
            assert_eq!(surface.light_pmf, set.pmf_of_triangle(index));
        }
        let Some(s) = set.sample(0.5, 0.3, 0.6) else {
            panic!("no light sample");
        };
        assert_eq!(s.triangle, 2);
        assert_eq!(s.surface, surfaces[2]);
        assert!(s.point.x >= 4.0 && s.point.x <= 5.0 && s.point.y >= 0.0);
        assert!((light_pdf_solid_angle(0.5, 2.0, 4.0, 0.5) - 2.0).abs() < 1e-6);
        assert_eq!(light_pdf_solid_angle(0.5, 2.0, 4.0, 0.0), 0.0);
        assert!(
            emits_towards(false, 0.1) && !emits_towards(false, -0.1) && emits_towards(true, -0.1)
        );
        assert!(LightSet::default().sample(0.5, 0.5, 0.5).is_none());
    }

    /// Each active lane of a packet sample equals the scalar sample drawn
    /// with the lane's numbers, bit for bit.
    #[test]
    fn packet_samples_equal_scalar_samples() {
        let (_, _, set) = lights();
        let mut rng = Rng::new(11, 5);
        for _ in 0..1000 {
            let active = LaneMask((rng.next_u32() & 0xff) as u8);
            let u_light: [f32; LANES] = core::array::from_fn(|_| rng.next_f32());
            let (u, v): ([f32; LANES], [f32; LANES]) = (
                core::array::from_fn(|_| rng.next_f32()),
                core::array::from_fn(|_| rng.next_f32()),
            );
            let packet = set.sample_packet(active, &u_light, f32x8::new(u), f32x8::new(v));
            assert_eq!(packet.valid, active);
            for lane in 0..LANES {
                let record = &packet.surface;
                if !active.contains(lane) {
                    assert_eq!(record.emission[lane], NO_ID);
                    continue;
                }
                let Some(s) = set.sample(u_light[lane], u[lane], v[lane]) else {
                    panic!("no scalar sample");
                };
                assert_eq!(
                    packet.point.lane(lane).to_array().map(f32::to_bits),
                    s.point.to_array().map(f32::to_bits)
                );
                assert_eq!(packet.triangle[lane], s.triangle);
                assert_eq!(record.normal.lane(lane), s.surface.normal);
                assert_eq!(record.emission[lane], s.surface.emission);
                assert_eq!(record.light_pmf.to_array()[lane], s.surface.light_pmf);
                assert_eq!(record.area.to_array()[lane], s.surface.area);
            }
        }
        let empty =
            LightSet::default().sample_packet(LaneMask::ALL, &[0.5; LANES], f32x8::ONE, f32x8::ONE);
        assert!(empty.valid.is_empty());
    }
}
