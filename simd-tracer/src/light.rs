//! Emissive triangles and their sampling for next-event estimation.
//!
//! A light is chosen with probability proportional to its power
//! `Φ ∝ A · π · mean(L_e)` (doubled if two-sided), then a point uniformly on
//! the triangle (`b0 = 1 − √u`, `b1 = v √u`; Turk 1990). The solid-angle pdf
//! of a point `y` seen from `x` is `P(light) · |x − y|² / (A cos θ_y)`, the
//! same expression MIS uses when a BSDF-sampled ray hits the light.

use crate::material::Material;
use crate::packet::{LANES, LaneMask};
use crate::simd::Vec3x8;
use crate::spectra::SceneSpectrum;
use glam::Vec3;
use std::f32::consts::PI;
use wide::f32x8;

/// No light on this triangle.
const NOT_A_LIGHT: u32 = u32::MAX;

/// The emissive triangles of a scene.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LightSet {
    triangles: Vec<u32>,
    areas: Vec<f32>,
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    light_of_triangle: Vec<u32>,
}

/// A sampled point on a light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    /// The point.
    pub point: Vec3,
    /// The light's unit geometric normal there.
    pub normal: Vec3,
    /// The triangle.
    pub triangle: u32,
    /// Probability of having chosen this light.
    pub pmf: f32,
    /// Area of the triangle.
    pub area: f32,
}

impl LightSet {
    /// Collects every triangle whose material emits.
    pub fn new(
        triangles: &[[Vec3; 3]],
        triangle_material: &[u32],
        materials: &[Material],
        spectra: &[SceneSpectrum],
    ) -> Self {
        let mut set = Self {
            light_of_triangle: vec![NOT_A_LIGHT; triangles.len()],
            ..Self::default()
        };
        let mut powers = Vec::new();
        for (index, (tri, &material)) in triangles.iter().zip(triangle_material).enumerate() {
            let Some(material) = materials.get(material as usize) else {
                continue;
            };
            let Some(emission) = material.emission else {
                continue;
            };
            let mean = spectra
                .get(emission as usize)
                .map_or(0.0, SceneSpectrum::mean);
            let area = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
            let sides = if material.two_sided { 2.0 } else { 1.0 };
            let power = f64::from(area) * PI as f64 * mean * sides;
            if power > 0.0 && power.is_finite() {
                set.light_of_triangle[index] = set.triangles.len() as u32;
                set.triangles.push(index as u32);
                set.areas.push(area);
                powers.push(power);
            }
        }
        let total: f64 = powers.iter().sum();
        let mut running = 0.0;
        for p in &powers {
            running += p;
            set.cdf.push((running / total) as f32);
            set.pmf.push((p / total) as f32);
        }
        if let Some(last) = set.cdf.last_mut() {
            *last = 1.0;
        }
        set
    }

    /// Number of emissive triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the scene has no emissive triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Probability that next-event estimation picks triangle `triangle`.
    pub fn pmf_of_triangle(&self, triangle: u32) -> f32 {
        match self.light_of_triangle.get(triangle as usize) {
            Some(&light) if light != NOT_A_LIGHT => self.pmf[light as usize],
            _ => 0.0,
        }
    }

    /// Picks a light with `u_light` and a point on it with `(u, v)`.
    pub fn sample(
        &self,
        triangles: &[[Vec3; 3]],
        normals: &[Vec3],
        u_light: f32,
        u: f32,
        v: f32,
    ) -> Option<LightSample> {
        if self.triangles.is_empty() {
            return None;
        }
        let light = self
            .cdf
            .partition_point(|&c| c <= u_light)
            .min(self.triangles.len() - 1);
        let triangle = self.triangles[light];
        let [a, b, c] = *triangles.get(triangle as usize)?;
        let su = u.sqrt();
        let (b0, b1) = (1.0 - su, v * su);
        let point = b0 * a + b1 * b + (1.0 - b0 - b1) * c;
        Some(LightSample {
            point,
            normal: *normals.get(triangle as usize)?,
            triangle,
            pmf: self.pmf[light],
            area: self.areas[light],
        })
    }
}

/// Light samples for a packet.
#[derive(Debug, Clone, Copy)]
pub struct LightSamplePacket {
    /// Points on the lights.
    pub point: Vec3x8,
    /// Unit normals there.
    pub normal: Vec3x8,
    /// Probabilities of the chosen lights.
    pub pmf: f32x8,
    /// Areas of the chosen triangles.
    pub area: f32x8,
    /// Chosen triangles.
    pub triangle: [u32; LANES],
    /// Lanes with a sample.
    pub valid: LaneMask,
}

impl LightSet {
    /// [`LightSet::sample`] for the active lanes of a packet: the light
    /// choice per lane, the point on it 8-wide.
    pub fn sample_packet(
        &self,
        triangles: &[[Vec3; 3]],
        normals: &[Vec3],
        active: LaneMask,
        u_light: &[f32; LANES],
        u: f32x8,
        v: f32x8,
    ) -> LightSamplePacket {
        let mut corners = [[Vec3::ZERO; LANES]; 3];
        let mut normal = [Vec3::Z; LANES];
        let mut pmf = [0.0f32; LANES];
        let mut area = [0.0f32; LANES];
        let mut triangle = [0u32; LANES];
        let mut valid = LaneMask::NONE;
        if !self.triangles.is_empty() {
            for lane in active.iter() {
                let light = self
                    .cdf
                    .partition_point(|&c| c <= u_light[lane])
                    .min(self.triangles.len() - 1);
                let index = self.triangles[light];
                if let (Some(tri), Some(&n)) =
                    (triangles.get(index as usize), normals.get(index as usize))
                {
                    for (corner, &vertex) in corners.iter_mut().zip(tri) {
                        corner[lane] = vertex;
                    }
                    normal[lane] = n;
                    pmf[lane] = self.pmf[light];
                    area[lane] = self.areas[light];
                    triangle[lane] = index;
                    valid = valid.with(lane);
                }
            }
        }
        let su = u.sqrt();
        let b0 = f32x8::ONE - su;
        let b1 = v * su;
        let b2 = f32x8::ONE - b0 - b1;
        let [a, b, c] = corners.map(|lanes| Vec3x8::from_lanes(&lanes));
        LightSamplePacket {
            point: a * b0 + b * b1 + c * b2,
            normal: Vec3x8::from_lanes(&normal),
            pmf: f32x8::new(pmf),
            area: f32x8::new(area),
            triangle,
            valid,
        }
    }
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
    use crate::spectra::SpectrumSource;
    use spectral_core::SpectralRange;

    #[test]
    fn power_weighted_selection() {
        let range = SpectralRange::VISIBLE;
        let spectra = vec![
            SceneSpectrum::new(SpectrumSource::Constant(1.0), range).unwrap(),
            SceneSpectrum::new(SpectrumSource::Constant(3.0), range).unwrap(),
        ];
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
        let set = LightSet::new(&triangles, &[0, 1, 2], &[dim, grey, bright], &spectra);
        assert_eq!(set.len(), 2);
        assert!((set.pmf_of_triangle(0) - 0.25).abs() < 1e-6);
        assert_eq!(set.pmf_of_triangle(1), 0.0);
        assert!((set.pmf_of_triangle(2) - 0.75).abs() < 1e-6);
        let normals = vec![Vec3::Z; 3];
        let s = set.sample(&triangles, &normals, 0.5, 0.3, 0.6).unwrap();
        assert_eq!(s.triangle, 2);
        assert!(s.point.x >= 4.0 && s.point.x <= 5.0 && s.point.y >= 0.0);
        assert!((light_pdf_solid_angle(0.5, 2.0, 4.0, 0.5) - 2.0).abs() < 1e-6);
        assert_eq!(light_pdf_solid_angle(0.5, 2.0, 4.0, 0.0), 0.0);
        assert!(
            emits_towards(false, 0.1) && !emits_towards(false, -0.1) && emits_towards(true, -0.1)
        );
    }
}
