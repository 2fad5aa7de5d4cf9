//! Emissive triangles and their sampling for next-event estimation.
//!
//! The triangles form groups, each a run of consecutive triangles of one
//! material (a lamp's mesh, a quad): the light selection
//! ([`crate::shading::light_sampler`]) gives each group its probability
//! and, within a group, a triangle is chosen with probability
//! proportional to its power `Φ ∝ A · π · mean(L_e)` (doubled if
//! two-sided); with one group, in proportion to its power alone. Then a
//! point uniformly on the triangle (`b0 = 1 − √u`, `b1 = v √u`; Turk 1990). The solid-angle pdf
//! of a point `y` seen from `x` is `P(light) · |x − y|² / (A cos θ_y)`, the
//! same expression MIS uses when a BSDF-sampled ray hits the light.
//!
//! Scenes with at most [`LANES`] emissive triangles (a quad lamp is two)
//! also hold the lights field by field in registers (`LightRegisters`):
//! a packet then chooses its lights with one comparison per light and
//! reads their records with one permute per field, instead of a search and
//! a record copy per lane. Both paths give the scalar sample bit for bit.

use crate::ids::SpectrumId;
use crate::shading::surface::{SideFlags, Surface, SurfacePacket};
use crate::simd::{LANES, LaneMask};
use crate::simd::{Vec3x8, lookup_f32x8, lookup_u32x8};
use crate::spectra::SceneSpectrum;
use glam::Vec3;
use std::f32::consts::PI;
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

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
    /// In strictly ascending triangle order: a triangle's light is found
    /// by bisection (no per-triangle index: 4 bytes a triangle for the few
    /// that emit).
    lights: Vec<Light>,
    cdf: Vec<f32>,
    /// Triangles of the scene.
    triangle_count: usize,
    /// The lights in registers, if there are 1 to [`LANES`] of them.
    registers: Option<LightRegisters>,
    /// `Σ A π L̄` (doubled when two-sided) over the lights.
    total_power: f64,
    /// Per group (module docs): the end of its lights in `lights`.
    group_ends: Vec<u32>,
    /// Per group: its power.
    group_powers: Vec<f64>,
}

/// Up to [`LANES`] lights, each field in one register (lane `l`: light
/// `l`; lanes past the last light repeat it), for
/// [`LightSet::sample_packet`].
#[derive(Debug, Clone, Copy, PartialEq)]
struct LightRegisters {
    /// `cdf[l]` for the lights but the last (the search's comparisons).
    cdf: [f32; LANES - 1],
    /// Number of comparisons: lights − 1.
    comparisons: usize,
    /// Vertex `i`, component `axis`: `vertices[i][axis]`.
    vertices: [[f32x8; 3]; 3],
    normal: [f32x8; 3],
    light_pmf: f32x8,
    area: f32x8,
    emission: u32x8,
    lambert_albedo: u32x8,
    triangle: u32x8,
    /// The records' sides words ([`SideFlags`]).
    sides: u32x8,
}

impl LightRegisters {
    /// The registers of `lights` with CDF `cdf`, if there are 1 to
    /// [`LANES`] lights.
    fn new(lights: &[Light], cdf: &[f32]) -> Option<Self> {
        let last = lights.len().checked_sub(1)?;
        if lights.len() > LANES || cdf.len() != lights.len() {
            return None;
        }
        let light = |l: usize| &lights[l.min(last)];
        let floats = |f: &dyn Fn(&Light) -> f32| f32x8::new(core::array::from_fn(|l| f(light(l))));
        let words = |f: &dyn Fn(&Light) -> u32| u32x8::new(core::array::from_fn(|l| f(light(l))));
        Some(Self {
            cdf: core::array::from_fn(|l| cdf.get(l).copied().unwrap_or(1.0)),
            comparisons: last,
            vertices: core::array::from_fn(|i| {
                core::array::from_fn(|axis| floats(&|light| light.vertices[i][axis]))
            }),
            normal: core::array::from_fn(|axis| floats(&|light| light.surface.normal[axis])),
            light_pmf: floats(&|light| light.surface.light_pmf),
            area: floats(&|light| light.surface.area),
            emission: words(&|light| light.surface.emission.0),
            lambert_albedo: words(&|light| light.surface.lambert_albedo.0),
            triangle: words(&|light| light.triangle),
            sides: words(&|light| SideFlags::pack(&light.surface)),
        })
    }

    /// [`LightSet::sample_packet`] with the lights in registers.
    fn sample_packet(
        &self,
        active: LaneMask,
        u_light: &[f32; LANES],
        u: f32x8,
        v: f32x8,
    ) -> LightSamplePacket {
        // `partition_point(c <= u)` over a sorted CDF, capped at the last
        // light: the number of the first `lights − 1` entries `<= u`.
        let u_light = f32x8::new(*u_light);
        let mut index = u32x8::ZERO;
        for &c in &self.cdf[..self.comparisons] {
            // A true comparison is all ones: −1 as a wrapping integer.
            index -= cast::<f32x8, u32x8>(f32x8::splat(c).simd_le(u_light));
        }
        let lanes = active.to_simd();
        let live: u32x8 = cast(lanes);
        let float =
            |table: f32x8, none: f32| lanes.select(lookup_f32x8(table, index), f32x8::splat(none));
        let word =
            |table: u32x8, none: u32| live.select(lookup_u32x8(table, index), u32x8::splat(none));
        let corner =
            |[x, y, z]: [f32x8; 3]| Vec3x8::new(float(x, 0.0), float(y, 0.0), float(z, 0.0));
        let [a, b, c] = self.vertices;
        let (a, b, c) = (corner(a), corner(b), corner(c));
        let none = Surface::NONE;
        let (two_sided, front_only) = SideFlags::unpack(word(self.sides, 0));
        LightSamplePacket {
            point: point_on_triangle_x8([a, b, c], u, v),
            triangle: word(self.triangle, 0).to_array(),
            surface: SurfacePacket {
                normal: Vec3x8::new(
                    float(self.normal[0], none.normal.x),
                    float(self.normal[1], none.normal.y),
                    float(self.normal[2], none.normal.z),
                ),
                emission: SpectrumId::from_words(word(self.emission, none.emission.0).to_array()),
                two_sided,
                front_only,
                light_pmf: float(self.light_pmf, none.light_pmf),
                area: float(self.area, none.area),
                lambert_albedo: SpectrumId::from_words(
                    word(self.lambert_albedo, none.lambert_albedo.0).to_array(),
                ),
            },
            valid: active,
        }
    }
}

/// The point `(u, v)` picks on the triangles `[a, b, c]`, lane by lane:
/// [`LightSet::sample`]'s formula with the same operations in the same
/// order, so the same bits.
#[inline(always)]
fn point_on_triangle_x8([a, b, c]: [Vec3x8; 3], u: f32x8, v: f32x8) -> Vec3x8 {
    let su = u.sqrt();
    let b0 = f32x8::ONE - su;
    let b1 = v * su;
    let b2 = f32x8::ONE - b0 - b1;
    a * b0 + b * b1 + c * b2
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
    /// The lights among `candidates` (triangles of `triangle_count` whose
    /// records emit, in ascending triangle order): those with positive
    /// power, with [`Surface::light_pmf`] filled in (power-proportional).
    /// [`LightSet::pmfs`] gives the probabilities to write back into the
    /// scene's records.
    pub fn new(triangle_count: usize, candidates: Vec<Light>, spectra: &[SceneSpectrum]) -> Self {
        let mut set = Self {
            triangle_count,
            ..Self::default()
        };
        let mut powers = Vec::new();
        for mut light in candidates {
            let surface = &mut light.surface;
            surface.light_pmf = 0.0;
            let ascending = set
                .lights
                .last()
                .is_none_or(|l| l.triangle < light.triangle);
            if !ascending || light.triangle as usize >= triangle_count {
                continue;
            }
            if surface.emission.is_none() {
                continue;
            }
            let mean = spectra
                .get(surface.emission.index())
                .map_or(0.0, SceneSpectrum::mean);
            let sides = if surface.two_sided { 2.0 } else { 1.0 };
            let power = f64::from(surface.area) * PI as f64 * mean * sides;
            if power > 0.0 && power.is_finite() {
                set.lights.push(light);
                powers.push(power);
            }
        }
        for (index, pair) in set.lights.windows(2).enumerate() {
            let [a, b] = [&pair[0], &pair[1]];
            if a.triangle + 1 != b.triangle || a.surface.material != b.surface.material {
                set.group_ends.push(index as u32 + 1);
            }
        }
        if !set.lights.is_empty() {
            set.group_ends.push(set.lights.len() as u32);
        }
        let mut start = 0;
        for &end in &set.group_ends {
            set.group_powers
                .push(powers[start..end as usize].iter().sum());
            start = end as usize;
        }
        let total: f64 = powers.iter().sum();
        set.total_power = total;
        let mut running = 0.0;
        for (light, p) in set.lights.iter_mut().zip(&powers) {
            running += p;
            set.cdf.push((running / total) as f32);
            light.surface.light_pmf = (p / total) as f32;
        }
        if let Some(last) = set.cdf.last_mut() {
            *last = 1.0;
        }
        set.registers = LightRegisters::new(&set.lights, &set.cdf);
        set
    }

    /// Each light's triangle and selection probability, for the scene's
    /// records (every other triangle's probability is 0).
    pub fn pmfs(&self) -> impl Iterator<Item = (u32, f32)> + '_ {
        self.lights
            .iter()
            .map(|light| (light.triangle, light.surface.light_pmf))
    }

    /// `Σ A π L̄` over the emissive triangles (doubled when two-sided).
    pub fn total_power(&self) -> f64 {
        self.total_power
    }

    /// The power of each group of lights (module docs).
    pub fn group_powers(&self) -> &[f64] {
        &self.group_powers
    }

    /// Gives group `g` the selection probability `shares[g]` (absolute:
    /// their sum is the probability that next-event estimation samples a
    /// triangle at all, [`crate::shading::light_sampler`]), shared among
    /// its lights in proportion to their power, in the lights and their
    /// registers ([`LightSet::pmfs`] then gives the new ones). The CDF is
    /// conditional on choosing a triangle: the caller rescales its light
    /// number. Applied once, to the probabilities [`LightSet::new`] made;
    /// `shares` of another length than the groups leave the set as it is.
    pub fn select_groups(&mut self, shares: &[f64]) {
        if shares.len() != self.group_ends.len() || self.total_power <= 0.0 {
            return;
        }
        let triangle_share: f64 = shares.iter().sum();
        let mut start = 0;
        for ((&end, &share), &power) in self.group_ends.iter().zip(shares).zip(&self.group_powers) {
            let lights = &mut self.lights[start..end as usize];
            start = end as usize;
            // Each light's probability by power is p/total; within its group
            // it is (p/total)/(P_g/total).
            let scale = if power > 0.0 {
                share * self.total_power / power
            } else {
                0.0
            };
            for light in lights {
                light.surface.light_pmf = (f64::from(light.surface.light_pmf) * scale) as f32;
            }
        }
        let mut running = 0.0f64;
        for (light, cdf) in self.lights.iter().zip(&mut self.cdf) {
            running += f64::from(light.surface.light_pmf);
            *cdf = (running / triangle_share) as f32;
        }
        if let Some(last) = self.cdf.last_mut() {
            *last = 1.0;
        }
        self.registers = LightRegisters::new(&self.lights, &self.cdf);
    }

    /// Checks the invariants sampling relies on: one CDF entry per light,
    /// non-decreasing, ending at 1; the lights' triangles in strictly
    /// ascending order (their bisection) and within the scene; the registers holding exactly the lights (present
    /// for 1 to [`LANES`] lights).
    pub fn validate(&self) -> Result<(), String> {
        if self.cdf.len() != self.lights.len() {
            return Err(format!(
                "{} CDF entries for {} lights",
                self.cdf.len(),
                self.lights.len()
            ));
        }
        if self.cdf.windows(2).any(|pair| pair[0] > pair[1]) {
            return Err("the light CDF decreases".to_owned());
        }
        if self.cdf.last().is_some_and(|&last| last != 1.0) {
            return Err("the light CDF does not end at 1".to_owned());
        }
        if let Some(pair) = self
            .lights
            .windows(2)
            .find(|pair| pair[0].triangle >= pair[1].triangle)
        {
            return Err(format!(
                "light triangles {} and {} are not in ascending order",
                pair[0].triangle, pair[1].triangle
            ));
        }
        if let Some(light) = self
            .lights
            .last()
            .filter(|l| l.triangle as usize >= self.triangle_count)
        {
            return Err(format!(
                "light triangle {} of {} triangles",
                light.triangle, self.triangle_count
            ));
        }
        let ends_rise = self.group_ends.windows(2).all(|pair| pair[0] < pair[1]);
        let last_end = self.group_ends.last().map_or(0, |&end| end as usize);
        if !ends_rise
            || last_end != self.lights.len()
            || self.group_ends.first() == Some(&0)
            || self.group_powers.len() != self.group_ends.len()
        {
            return Err(format!(
                "{} light groups ending at {:?} for {} lights",
                self.group_powers.len(),
                self.group_ends,
                self.lights.len()
            ));
        }
        if self.registers != LightRegisters::new(&self.lights, &self.cdf) {
            return Err("the light registers do not hold the lights".to_owned());
        }
        Ok(())
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
        self.lights
            .binary_search_by_key(&triangle, |l| l.triangle)
            .ok()
            .and_then(|at| self.lights.get(at))
            .map_or(0.0, |l| l.surface.light_pmf)
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
    #[inline(always)]
    pub fn sample_packet(
        &self,
        active: LaneMask,
        u_light: &[f32; LANES],
        u: f32x8,
        v: f32x8,
    ) -> LightSamplePacket {
        if let Some(registers) = &self.registers {
            return registers.sample_packet(active, u_light, u, v);
        }
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
        LightSamplePacket {
            point: point_on_triangle_x8(corners.map(|lanes| Vec3x8::from_lanes(&lanes)), u, v),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::MaterialId;
    use crate::sampling::rng::Rng;
    use crate::shading::material::{Material, Sides};
    use crate::shading::surface::{emits_towards, light_pdf_solid_angle};
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
        let mut dim = Material::lambert("dim", SpectrumId(0));
        dim.emission = Some(SpectrumId(0));
        let mut bright = Material::lambert("bright", SpectrumId(0));
        bright.emission = Some(SpectrumId(1));
        let grey = Material::lambert("grey", SpectrumId(0));
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
            .map(|(m, id)| Surface::new(Vec3::Z, 0.5, MaterialId(id), m))
            .collect();
        let set = light_set(&triangles, &mut surfaces, &spectra);
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

    /// The dim and the bright light are two groups (their triangles are not
    /// consecutive, and their materials differ); given probabilities 0.6
    /// and 0.4 they keep them, and the set stays valid. Shares of the wrong
    /// length change nothing.
    #[test]
    fn groups_take_their_probabilities() {
        let (_, _, mut set) = lights();
        assert_eq!(set.group_powers().len(), 2);
        let [dim, bright] = [set.group_powers()[0], set.group_powers()[1]];
        assert!((bright / dim - 3.0).abs() < 1e-9, "{dim} {bright}");
        let before = set.clone();
        set.select_groups(&[1.0]);
        assert_eq!(set, before);
        set.select_groups(&[0.6, 0.4]);
        assert!((set.pmf_of_triangle(0) - 0.6).abs() < 1e-6);
        assert!((set.pmf_of_triangle(2) - 0.4).abs() < 1e-6);
        assert_eq!(set.validate(), Ok(()));
        // The CDF is conditional on choosing a triangle: 0.6 of [0, 1).
        let pick = |u: f32| set.sample(u, 0.3, 0.3).map(|s| s.triangle);
        assert_eq!((pick(0.59), pick(0.61)), (Some(0), Some(2)));
    }

    /// `count` lights of powers 1, 2, … (emission spectra `i + 1`), at
    /// different places, and a grey triangle among them.
    fn many_lights(count: usize) -> LightSet {
        let range = SpectralRange::VISIBLE;
        let spectra: Vec<SceneSpectrum> = (0..count)
            .filter_map(|i| {
                SceneSpectrum::new(SpectrumSource::Constant(i as f64 + 1.0), range).ok()
            })
            .collect();
        assert_eq!(spectra.len(), count);
        let mut triangles = Vec::new();
        let mut surfaces = Vec::new();
        for i in 0..=count {
            let x = i as f32 * 1.5;
            triangles.push([
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.5, 0.0),
                Vec3::new(x, 1.0, 0.25 * i as f32),
            ]);
            let mut material = Material::lambert("m", SpectrumId(0));
            // Triangle 1 is grey; the others emit, every third two-sided;
            // every other one scatters from its front only.
            if i != 1 {
                material.emission = Some(SpectrumId(surfaces.len().min(count - 1) as u32));
                material.two_sided = i % 3 == 0;
            }
            if i % 2 == 0 {
                material.sides = Sides::Front;
            }
            surfaces.push(Surface::new(
                Vec3::Z,
                0.5 + i as f32,
                MaterialId(i as u32),
                &material,
            ));
        }
        light_set(&triangles, &mut surfaces, &spectra)
    }

    /// The light set of `triangles` with records `surfaces`, as the scene
    /// builds it: candidates are the emitting records, and the
    /// probabilities are written back into the records.
    fn light_set(
        triangles: &[[Vec3; 3]],
        surfaces: &mut [Surface],
        spectra: &[SceneSpectrum],
    ) -> LightSet {
        let candidates = (0u32..)
            .zip(triangles.iter().zip(surfaces.iter()))
            .filter(|(_, (_, surface))| !surface.emission.is_none())
            .map(|(triangle, (vertices, surface))| Light {
                triangle,
                vertices: *vertices,
                surface: *surface,
            })
            .collect();
        let set = LightSet::new(triangles.len(), candidates, spectra);
        for (triangle, pmf) in set.pmfs() {
            surfaces[triangle as usize].light_pmf = pmf;
        }
        set
    }

    /// Each lane of a packet sample equals the scalar sample drawn with the
    /// lane's numbers, bit for bit, and inactive lanes hold no light;
    /// with the lights in registers (2 and 8 lights) and without (11).
    #[test]
    fn packet_samples_equal_scalar_samples() {
        let (_, _, two) = lights();
        let sets = [two, many_lights(8), many_lights(11)];
        assert!(sets[0].registers.is_some() && sets[1].registers.is_some());
        assert!(sets[2].registers.is_none());
        for set in &sets {
            assert_eq!(set.validate(), Ok(()));
            packet_samples_equal_scalar_samples_in(set);
        }
    }

    fn packet_samples_equal_scalar_samples_in(set: &LightSet) {
        let mut rng = Rng::new(11, 5);
        for round in 0..2000 {
            let active = LaneMask((rng.next_u32() & 0xff) as u8);
            let mut u_light: [f32; LANES] = core::array::from_fn(|_| rng.next_f32());
            if round == 0 {
                // The CDF's own values and the ends.
                for (lane, u) in u_light.iter_mut().enumerate() {
                    *u = set.cdf.get(lane).copied().unwrap_or(0.0);
                }
                u_light[LANES - 1] = 1.0 - f32::EPSILON;
            }
            let (u, v): ([f32; LANES], [f32; LANES]) = (
                core::array::from_fn(|_| rng.next_f32()),
                core::array::from_fn(|_| rng.next_f32()),
            );
            let packet = set.sample_packet(active, &u_light, f32x8::new(u), f32x8::new(v));
            assert_eq!(packet.valid, active);
            for lane in 0..LANES {
                let record = &packet.surface;
                if !active.contains(lane) {
                    assert_eq!(record.emission[lane], SpectrumId::NONE);
                    assert_eq!(record.lambert_albedo[lane], SpectrumId::NONE);
                    assert_eq!(record.normal.lane(lane), Surface::NONE.normal);
                    assert_eq!(record.area.to_array()[lane], 0.0);
                    assert!(!record.two_sided.contains(lane));
                    assert!(!record.front_only.contains(lane));
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
                assert_eq!(record.two_sided.contains(lane), s.surface.two_sided);
                assert_eq!(record.front_only.contains(lane), s.surface.front_only);
                assert_eq!(record.lambert_albedo[lane], s.surface.lambert_albedo);
            }
        }
    }

    /// `validate` finds a stale register table, a decreasing CDF and a
    /// broken triangle map.
    #[test]
    fn validate_finds_corruption() {
        let set = many_lights(5);
        assert_eq!(set.validate(), Ok(()));
        let mut stale = set.clone();
        if let Some(registers) = &mut stale.registers {
            registers.area = f32x8::splat(9.0);
        }
        assert!(stale.validate().is_err());
        let mut decreasing = set.clone();
        decreasing.cdf.swap(0, 1);
        assert!(decreasing.validate().is_err());
        let mut unordered = set.clone();
        unordered.lights.swap(0, 1);
        unordered.registers = LightRegisters::new(&unordered.lights, &unordered.cdf);
        assert!(unordered.validate().is_err());
        let mut outside = set;
        outside.triangle_count = 0;
        assert!(outside.validate().is_err());
    }

    #[test]
    fn an_empty_set_samples_nothing() {
        let empty =
            LightSet::default().sample_packet(LaneMask::ALL, &[0.5; LANES], f32x8::ONE, f32x8::ONE);
        assert!(empty.valid.is_empty());
    }
}
