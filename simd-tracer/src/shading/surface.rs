//! Per-triangle shading records: everything a bounce reads about the
//! triangle a ray hit (or a light sample landed on), in one record, so a
//! packet gathers 8 records instead of chasing triangle → material →
//! emission → light set per lane.
//!
//! Per lane the record gives the geometric normal, the emission and its
//! sides, the light-selection probability and area that the MIS weight of
//! an emitter hit needs,
//! `p_light = P(light) · d² / (A |cos θ_y|)` (see [`crate::shading::light`]),
//! whether the BSDF is Lambert with a spectrum albedo (the packet path
//! that needs neither texture coordinates nor a per-lane material call),
//! and whether only the front face scatters
//! ([`Material::front_only`]: the bounce ends lanes that see such a
//! surface from behind, [`scatters_towards`]).
//! The 8-wide emission mask and pdf here are checked lane by lane against
//! the scalar [`emits_towards`] and [`light_pdf_solid_angle`].
//!
//! Packets read the records from [`PackedSurfaces`], the same records as
//! eight 32-bit words each: one 32-byte load per lane and one `8 × 8`
//! transpose give the packet's eight fields. The scene keeps only the
//! packed form (at a million triangles a second layout cost 36 MB); a
//! [`Surface`] is unpacked from it, bit for bit, where one is wanted
//! ([`PackedSurfaces::unpack`]).

use crate::ids::{MaterialId, NO_ID, SpectrumId};
use crate::shading::material::{Albedo, Bsdf, Material};
use crate::simd::Vec3x8;
use crate::simd::{LANES, LaneMask};
use glam::Vec3;
use rayon::prelude::*;
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// What shading reads of one triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// Unit geometric normal (right-handed, CCW front).
    pub normal: Vec3,
    /// Material, or [`NO_ID`] (only in [`Surface::NONE`]).
    pub material: MaterialId,
    /// Emission spectrum, or [`NO_ID`].
    pub emission: SpectrumId,
    /// Whether the emission leaves both faces.
    pub two_sided: bool,
    /// Whether only the front face scatters ([`Material::front_only`]).
    pub front_only: bool,
    /// Probability that light sampling picks this triangle (0 if it is not
    /// in the light set).
    pub light_pmf: f32,
    /// Area.
    pub area: f32,
    /// The albedo spectrum if the BSDF is Lambert with a spectrum albedo,
    /// else [`NO_ID`].
    pub lambert_albedo: SpectrumId,
}

impl Surface {
    /// The record of an unknown triangle: normal `+z`, no material, no emission.
    pub const NONE: Self = Self {
        normal: Vec3::Z,
        material: MaterialId::NONE,
        emission: SpectrumId::NONE,
        two_sided: false,
        front_only: false,
        light_pmf: 0.0,
        area: 0.0,
        lambert_albedo: SpectrumId::NONE,
    };

    /// The record of a triangle with this normal, area and material; its
    /// light-selection probability is 0 until
    /// [`LightSet::new`](crate::shading::light::LightSet::new) fills it in.
    pub fn new(normal: Vec3, area: f32, material_id: MaterialId, material: &Material) -> Self {
        Self {
            normal,
            material: material_id,
            emission: material.emission.unwrap_or(SpectrumId::NONE),
            two_sided: material.two_sided,
            front_only: material.front_only(),
            light_pmf: 0.0,
            area,
            lambert_albedo: match material.bsdf {
                Bsdf::Lambert {
                    albedo: Albedo::Spectrum(id),
                } => id,
                _ => SpectrumId::NONE,
            },
        }
    }
}

/// The records of the 8 lanes of a packet, structure of arrays.
#[derive(Debug, Clone, Copy)]
pub struct SurfacePacket {
    /// Geometric normals (`+z` in lanes without a record).
    pub normal: Vec3x8,
    /// Emission spectra ([`NO_ID`] where none).
    pub emission: [SpectrumId; LANES],
    /// Lanes whose emission is two-sided.
    pub two_sided: LaneMask,
    /// Lanes where only the front face scatters.
    pub front_only: LaneMask,
    /// Light-selection probabilities.
    pub light_pmf: f32x8,
    /// Areas.
    pub area: f32x8,
    /// Lambert albedo spectra ([`NO_ID`] where the BSDF is something else).
    pub lambert_albedo: [SpectrumId; LANES],
}

/// The shading records as eight 32-bit words each, in the order of
/// [`SurfacePacket`]'s fields: normal x, y, z, emission, the sides and the
/// material (bit 31, the sign bit that lane masks read: two-sided emission;
/// bit 0: front-only scattering; bits 1–30: the material,
/// [`MAX_PACKED_MATERIALS`]), light-selection probability, area, Lambert
/// albedo (ids as their integer bits). The records are the scene's only
/// per-triangle store of the material ([`PackedSurfaces::material`]).
#[derive(Debug, Clone, Default)]
pub struct PackedSurfaces(Vec<u32x8>);

/// The word of a packed record holding the sides and the material.
const SIDES_WORD: usize = 4;
/// The word of a packed record holding [`Surface::light_pmf`].
const LIGHT_PMF_WORD: usize = 5;

/// The materials a packed record can name: the 30 bits between the two
/// side flags, all ones kept for [`MaterialId::NONE`].
pub const MAX_PACKED_MATERIALS: usize =
    (SideFlags::MATERIAL_MASK >> SideFlags::MATERIAL_SHIFT) as usize;

/// The sides-and-material word of a packed record ([`PackedSurfaces`]).
pub(crate) struct SideFlags;

impl SideFlags {
    /// Two-sided emission: the sign bit, so the word is its own lane mask.
    const TWO_SIDED: u32 = 1 << 31;
    /// Front-only scattering.
    const FRONT_ONLY: u32 = 1;
    /// Where the material's index starts.
    const MATERIAL_SHIFT: u32 = 1;
    /// The material's bits (1–30).
    const MATERIAL_MASK: u32 = !(Self::TWO_SIDED | Self::FRONT_ONLY);

    /// The material's bits of a record ([`MaterialId::NONE`] and indices
    /// from [`MAX_PACKED_MATERIALS`] on as all ones; the scene refuses that
    /// many materials).
    fn pack_material(material: MaterialId) -> u32 {
        debug_assert!(material.is_none() || material.index() < MAX_PACKED_MATERIALS);
        if material.index() >= MAX_PACKED_MATERIALS {
            Self::MATERIAL_MASK
        } else {
            material.0 << Self::MATERIAL_SHIFT
        }
    }

    /// The material of a record's word.
    fn material(word: u32) -> MaterialId {
        match word & Self::MATERIAL_MASK {
            Self::MATERIAL_MASK => MaterialId::NONE,
            bits => MaterialId(bits >> Self::MATERIAL_SHIFT),
        }
    }

    /// The word of a record.
    pub(crate) fn pack(surface: &Surface) -> u32 {
        let two_sided = if surface.two_sided {
            Self::TWO_SIDED
        } else {
            0
        };
        let front_only = if surface.front_only {
            Self::FRONT_ONLY
        } else {
            0
        };
        two_sided | front_only | Self::pack_material(surface.material)
    }

    /// The lanes with two-sided emission and the lanes with front-only
    /// scattering, from 8 words.
    #[inline(always)]
    pub(crate) fn unpack(words: u32x8) -> (LaneMask, LaneMask) {
        let flag = u32x8::splat(Self::FRONT_ONLY);
        let front_only: f32x8 = cast((words & flag).simd_eq(flag));
        (
            LaneMask::from_simd(cast(words)),
            LaneMask::from_simd(front_only),
        )
    }
}

impl PackedSurfaces {
    /// The packed form of `surfaces`.
    pub fn new(surfaces: &[Surface]) -> Self {
        Self(surfaces.iter().map(Self::pack).collect())
    }

    /// The packed form of the records `surfaces` yields, made in parallel
    /// without a vector of the unpacked records (36 bytes a triangle more
    /// at the peak of a large scene's build).
    pub fn collect(surfaces: impl IndexedParallelIterator<Item = Surface>) -> Self {
        Self(surfaces.map(|surface| Self::pack(&surface)).collect())
    }

    /// Sets the selection probability of record `index` (no change for an
    /// index out of range).
    pub fn set_light_pmf(&mut self, index: usize, light_pmf: f32) {
        if let Some(words) = self.0.get_mut(index) {
            let mut array = words.to_array();
            array[LIGHT_PMF_WORD] = light_pmf.to_bits();
            *words = u32x8::new(array);
        }
    }

    fn pack(surface: &Surface) -> u32x8 {
        u32x8::new([
            surface.normal.x.to_bits(),
            surface.normal.y.to_bits(),
            surface.normal.z.to_bits(),
            surface.emission.0,
            SideFlags::pack(surface),    // SIDES_WORD
            surface.light_pmf.to_bits(), // LIGHT_PMF_WORD
            surface.area.to_bits(),
            surface.lambert_albedo.0,
        ])
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there is no record.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The record of triangle `index`: the packed words bit for bit.
    pub fn unpack(&self, index: usize) -> Option<Surface> {
        let [x, y, z, emission, sides, light_pmf, area, lambert_albedo] =
            self.0.get(index)?.to_array();
        Some(Surface {
            normal: Vec3::new(f32::from_bits(x), f32::from_bits(y), f32::from_bits(z)),
            material: SideFlags::material(sides),
            emission: SpectrumId(emission),
            two_sided: sides & SideFlags::TWO_SIDED != 0,
            front_only: sides & SideFlags::FRONT_ONLY != 0,
            light_pmf: f32::from_bits(light_pmf),
            area: f32::from_bits(area),
            lambert_albedo: SpectrumId(lambert_albedo),
        })
    }

    /// The geometric normal of record `index`.
    #[inline]
    pub fn normal(&self, index: usize) -> Option<Vec3> {
        let words = self.0.get(index)?.to_array();
        Some(Vec3::new(
            f32::from_bits(words[0]),
            f32::from_bits(words[1]),
            f32::from_bits(words[2]),
        ))
    }

    /// The material of record `index`.
    #[inline]
    pub fn material(&self, index: usize) -> Option<MaterialId> {
        self.0
            .get(index)
            .map(|words| SideFlags::material(words.to_array()[SIDES_WORD]))
    }

    /// The area of record `index`.
    pub fn area(&self, index: usize) -> Option<f32> {
        self.0
            .get(index)
            .map(|words| f32::from_bits(words.to_array()[6]))
    }

    /// Whether record `index` emits.
    pub fn emits(&self, index: usize) -> bool {
        self.0
            .get(index)
            .is_some_and(|words| words.to_array()[3] != NO_ID)
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.0.capacity() * size_of::<u32x8>()
    }

    /// The records of `triangles` in the lanes of `active`
    /// ([`Surface::NONE`] elsewhere and for unknown indices).
    #[inline]
    pub fn gather(&self, triangles: &[u32; LANES], active: LaneMask) -> SurfacePacket {
        let none: f32x8 = cast(Self::pack(&Surface::NONE));
        let rows: [f32x8; LANES] =
            core::array::from_fn(|lane| match self.0.get(triangles[lane] as usize) {
                Some(&words) if active.contains(lane) => cast(words),
                _ => none,
            });
        let [x, y, z, emission, sides, light_pmf, area, lambert_albedo] = f32x8::transpose(rows);
        let (two_sided, front_only) = SideFlags::unpack(cast(sides));
        SurfacePacket {
            normal: Vec3x8::new(x, y, z),
            emission: SpectrumId::from_words(cast::<f32x8, u32x8>(emission).to_array()),
            two_sided,
            front_only,
            light_pmf,
            area,
            lambert_albedo: SpectrumId::from_words(cast::<f32x8, u32x8>(lambert_albedo).to_array()),
        }
    }
}

impl SurfacePacket {
    /// Eight records in structure-of-arrays form.
    pub fn from_records(records: &[Surface; LANES]) -> Self {
        Self {
            normal: Vec3x8::from_fn(|lane| records[lane].normal),
            emission: records.map(|r| r.emission),
            two_sided: (0..LANES)
                .filter(|&lane| records[lane].two_sided)
                .fold(LaneMask::NONE, LaneMask::with),
            front_only: (0..LANES)
                .filter(|&lane| records[lane].front_only)
                .fold(LaneMask::NONE, LaneMask::with),
            light_pmf: f32x8::new(records.map(|r| r.light_pmf)),
            area: f32x8::new(records.map(|r| r.area)),
            lambert_albedo: records.map(|r| r.lambert_albedo),
        }
    }

    /// Lanes with an emission towards a viewer at cosine `cos_light`
    /// (normal · to viewer): [`emits_towards`] lane-wise.
    #[inline(always)]
    pub fn emits_towards(&self, cos_light: f32x8) -> LaneMask {
        let zero = f32x8::ZERO;
        let front = LaneMask::from_simd(cos_light.simd_gt(zero));
        let back = LaneMask::from_simd(cos_light.simd_lt(zero)).and(self.two_sided);
        let none: f32x8 =
            cast(u32x8::new(SpectrumId::words(self.emission)).simd_eq(u32x8::splat(NO_ID)));
        let emissive = LaneMask::ALL.and_not(LaneMask::from_simd(none));
        front.or(back).and(emissive)
    }

    /// Lanes that scatter light seen at cosine `cos_view` (geometric
    /// normal · to viewer): [`scatters_towards`] lane-wise.
    #[inline(always)]
    pub fn scatters_towards(&self, cos_view: f32x8) -> LaneMask {
        let in_front = LaneMask::from_simd(cos_view.simd_gt(f32x8::ZERO));
        in_front.or(LaneMask::ALL.and_not(self.front_only))
    }

    /// The solid-angle pdf with which light sampling would have produced
    /// each lane's point, seen along a segment of squared length
    /// `distance_sq` at cosine `cos_light`: [`light_pdf_solid_angle`]
    /// lane-wise (the same operations, so the same bits).
    #[inline(always)]
    pub fn light_pdf(&self, distance_sq: f32x8, cos_light: f32x8) -> f32x8 {
        let cos = cos_light.abs();
        let zero = f32x8::ZERO;
        let none = cos.simd_le(zero) | self.area.simd_le(zero);
        none.select(zero, self.light_pmf * distance_sq / (self.area * cos))
    }

    /// Whether every lane in `active` is Lambert with a spectrum albedo
    /// (then [`SurfacePacket::lambert_albedo`] names the albedos).
    #[inline(always)]
    pub fn all_lambert(&self, active: LaneMask) -> bool {
        active
            .iter()
            .all(|lane| !self.lambert_albedo[lane].is_none())
    }
}

/// Area of a triangle, `|(b − a) × (c − a)| / 2`.
pub fn triangle_area([a, b, c]: &[Vec3; 3]) -> f32 {
    0.5 * (*b - *a).cross(*c - *a).length()
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

/// Whether a surface scatters light seen at `cos_view = normal · (to
/// viewer)`: always, unless only its front scatters
/// ([`Material::front_only`]) and the viewer is not in front of it
/// (`cos_view ≤ 0`, Mitsuba's `cos θ_i ≤ 0`).
pub fn scatters_towards(front_only: bool, cos_view: f32) -> bool {
    !front_only || cos_view > 0.0
}

/// Whether a light with this material emits towards a viewer on the side
/// given by `cos_light = normal · (to viewer)`.
pub fn emits_towards(two_sided: bool, cos_light: f32) -> bool {
    cos_light > 0.0 || (two_sided && cos_light < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use crate::scene::camera::Camera;
    use crate::scene::{Scene, SceneBuilder};
    use crate::shading::material::CoatParams;
    use crate::shading::microfacet::Microfacet;

    use crate::shading::material::Sides;
    use crate::spectra::SpectrumSource;
    use spectral_core::SpectralRange;

    /// A glass's relative index.
    const GLASS_ETA: f32 = 1.5;

    /// Triangles: a one-sided light, a two-sided light, a Lambert
    /// triangle, a coated one and an emissive coated one; the Lambert and
    /// the emissive coated triangles scatter from the front only, and a
    /// front-only dielectric (which transmits) from both faces.
    fn scene() -> Result<Scene, Box<dyn std::error::Error>> {
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
        let white = b.add_spectrum("white", SpectrumSource::Constant(2.0))?;
        let mut one_sided = Material::lambert("one-sided light", grey);
        one_sided.emission = Some(white);
        let mut two_sided = one_sided.clone();
        two_sided.two_sided = true;
        let coated = Material::new(
            "coated",
            Bsdf::Coated {
                albedo: Albedo::Spectrum(grey),
                ior: 1.5,
                microfacet: Microfacet::ggx(0.0),
                fdr_inside: 0.5,
                params: CoatParams::default(),
            },
        );
        let mut glowing = coated.clone();
        glowing.emission = Some(grey);
        glowing.sides = Sides::Front;
        let mut front_lambert = Material::lambert("grey", grey);
        front_lambert.sides = Sides::Front;
        let mut glass = Material::new(
            "glass",
            Bsdf::ThinDielectric {
                eta: GLASS_ETA,
                tints: None,
            },
        );
        glass.sides = Sides::Front;
        let materials = [
            b.add_material(one_sided),
            b.add_material(two_sided),
            b.add_material(front_lambert),
            b.add_material(coated),
            b.add_material(glowing),
            b.add_material(glass),
        ];
        for (i, &m) in materials.iter().enumerate() {
            let x = 2.0 * i as f32;
            let size = 1.0 + i as f32;
            b.add_triangle(
                [
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x + size, 0.0, 0.0),
                    Vec3::new(x, size, 0.5 * i as f32),
                ],
                m,
            );
        }
        b.set_camera(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0)?);
        Ok(b.build()?)
    }

    #[test]
    fn records_match_their_sources() -> Result<(), Box<dyn std::error::Error>> {
        let scene = scene()?;
        scene.validate_surfaces()?;
        let s: Vec<Surface> = (0..scene.triangle_count())
            .filter_map(|index| scene.surface(index))
            .collect();
        assert_eq!(s.len(), 6);
        let front_only: Vec<bool> = s.iter().map(|r| r.front_only).collect();
        assert_eq!(front_only, [false, false, true, false, true, false]);
        assert_eq!((s[0].emission, s[0].two_sided), (SpectrumId(1), false));
        assert_eq!((s[1].emission, s[1].two_sided), (SpectrumId(1), true));
        assert_eq!(
            [s[2].emission, s[3].emission, s[4].emission, s[5].emission],
            [
                SpectrumId::NONE,
                SpectrumId::NONE,
                SpectrumId(0),
                SpectrumId::NONE
            ]
        );
        let lambert: Vec<u32> = s.iter().map(|r| r.lambert_albedo.0).collect();
        assert_eq!(lambert, [0, 0, 0, NO_ID, NO_ID, NO_ID]);
        for (index, surface) in s.iter().enumerate() {
            assert_eq!(Some(surface.normal), scene.normal(index));
            assert_eq!(surface.area, triangle_area(&scene.triangles()[index]));
            assert_eq!(scene.area(index), surface.area);
            assert_eq!(Some(surface.material), scene.material_of(index));
            assert_eq!(
                surface.light_pmf,
                scene.lights().pmf_of_triangle(index as u32)
            );
        }
        assert!(s[0].light_pmf > 0.0 && s[1].light_pmf > 0.0 && s[4].light_pmf > 0.0);
        assert_eq!(s[2].light_pmf, 0.0);
        // The emitter subset: triangles 0, 1 and 4; a stale one is caught.
        assert_eq!(scene.emitters(), &scene.bvh().subset(&[0, 1, 4]));

        // Each kind of corruption is caught (a record with another material
        // whose derived fields were not remade among them).
        let check = |surfaces: &[Surface]| {
            crate::scene::validate_surface_records(
                &PackedSurfaces::new(surfaces),
                &scene.triangles(),
                scene.materials(),
                scene.lights(),
            )
        };
        check(&s)?;
        assert!(check(&s[..4]).is_err());
        let corruptions: [fn(&mut Surface); 8] = [
            |r| r.normal = -r.normal,
            |r| r.material = MaterialId(3),
            |r| r.emission = SpectrumId::NONE,
            |r| r.two_sided = !r.two_sided,
            |r| r.front_only = !r.front_only,
            |r| r.light_pmf *= 0.5,
            |r| r.area += 1.0,
            |r| r.lambert_albedo = SpectrumId::NONE,
        ];
        for corrupt in corruptions {
            let mut bad = s.clone();
            corrupt(&mut bad[0]);
            assert!(check(&bad).is_err());
            // The packed words round-trip bit for bit.
            let packed = PackedSurfaces::new(&bad);
            assert_eq!(packed.unpack(0), Some(bad[0]));
        }
        Ok(())
    }

    /// The sides word keeps both flags and the material apart: every flag
    /// pair with the first, a middle and the last material a record can
    /// name, and none; the lane masks read only their flags.
    #[test]
    fn the_sides_word_round_trips_flags_and_material() {
        let last = MaterialId((MAX_PACKED_MATERIALS - 1) as u32);
        for material in [MaterialId(0), MaterialId(12_345), last, MaterialId::NONE] {
            for (two_sided, front_only) in
                [(false, false), (true, false), (false, true), (true, true)]
            {
                let surface = Surface {
                    material,
                    two_sided,
                    front_only,
                    ..Surface::NONE
                };
                let word = SideFlags::pack(&surface);
                assert_eq!(SideFlags::material(word), material);
                let (sides, front) = SideFlags::unpack(u32x8::splat(word));
                assert_eq!(sides == LaneMask::ALL, two_sided, "{word:#x}");
                assert_eq!(front == LaneMask::ALL, front_only, "{word:#x}");
                let packed = PackedSurfaces::new(&[surface]);
                assert_eq!(packed.unpack(0), Some(surface));
                assert_eq!(packed.material(0), Some(material));
            }
        }
    }

    /// The packet's records, masks and pdfs equal the scalar code's, lane by
    /// lane (bits), over random triangles (unknown ones included), active
    /// masks, cosines (zeros and both signs) and distances.
    #[test]
    fn packet_matches_scalar_oracle() -> Result<(), Box<dyn std::error::Error>> {
        let scene = scene()?;
        let mut rng = Rng::new(3, 7);
        for _ in 0..2000 {
            let triangles: [u32; LANES] = core::array::from_fn(|_| match rng.next_u32() % 8 {
                7 => u32::MAX,
                i => i,
            });
            let active = LaneMask((rng.next_u32() & 0xff) as u8);
            let cos: [f32; LANES] = core::array::from_fn(|_| match rng.next_u32() % 5 {
                0 => 0.0,
                1 => -0.0,
                _ => 2.0 * rng.next_f32() - 1.0,
            });
            let distance_sq: [f32; LANES] = core::array::from_fn(|_| 10.0 * rng.next_f32());
            let packet = scene.packed_surfaces().gather(&triangles, active);
            let emits = packet.emits_towards(f32x8::new(cos));
            let scatters = packet.scatters_towards(f32x8::new(cos));
            let pdf = packet
                .light_pdf(f32x8::new(distance_sq), f32x8::new(cos))
                .to_array();
            let lambert = packet.all_lambert(active);
            for lane in 0..LANES {
                let record = match scene.surface(triangles[lane] as usize) {
                    Some(r) if active.contains(lane) => r,
                    _ => Surface::NONE,
                };
                assert_eq!(packet.normal.lane(lane), record.normal);
                assert_eq!(packet.emission[lane], record.emission);
                assert_eq!(packet.two_sided.contains(lane), record.two_sided);
                assert_eq!(packet.front_only.contains(lane), record.front_only);
                assert_eq!(
                    scatters.contains(lane),
                    scatters_towards(record.front_only, cos[lane])
                );
                assert_eq!(packet.light_pmf.to_array()[lane], record.light_pmf);
                assert_eq!(packet.area.to_array()[lane], record.area);
                assert_eq!(packet.lambert_albedo[lane], record.lambert_albedo);
                assert_eq!(
                    emits.contains(lane),
                    record.emission != SpectrumId::NONE
                        && emits_towards(record.two_sided, cos[lane])
                );
                let expected = light_pdf_solid_angle(
                    record.light_pmf,
                    record.area,
                    distance_sq[lane],
                    cos[lane],
                );
                assert_eq!(pdf[lane].to_bits(), expected.to_bits());
            }
            let all_lambert = active
                .iter()
                .all(|lane| packet.lambert_albedo[lane] != SpectrumId::NONE);
            assert_eq!(lambert, all_lambert);
        }
        Ok(())
    }
}
