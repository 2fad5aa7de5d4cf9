//! The sampler: where a path's uniform numbers come from, and which
//! dimension each decision draws.
//!
//! Two kinds ([`SamplerKind`]): independent PCG streams (`rng.rs`: each
//! number fresh, the dimension ignored, numbers taken in call order) and
//! Owen-scrambled Sobol points (`sobol.rs`: point = pass, one scrambled
//! sequence per pixel). A low-discrepancy sampler stratifies each
//! decision over a pixel's passes, so smooth integrands (the pixel
//! footprint, soft shadows, diffuse bounces) converge faster than the
//! independent `O(n^{−1/2})`; measured on the built-in scenes in
//! `docs/results.md`.
//!
//! **Dimension allocation.** A decision's dimension is fixed by what it
//! is and at which bounce, never by how many numbers other lanes or
//! earlier events drew, so a dimension always means the same thing
//! across passes (stratification needs that) and across packet mates:
//!
//! | dimensions | decision |
//! | --- | --- |
//! | 0, 1 | pixel: the filter (or, splatting, the box) offset, x then y |
//! | 2 … 5 | wavelengths: the sampled transports' first [`WAVELENGTH_DIMENSIONS`] numbers (the hybrid transport's at its split: it draws none at the camera, and splits at most once per path) |
//! | `6 + 8 (k − 1)` + 0 | bounce `k` ≤ 15: light selection (bounces past the 15th: `128 + 8 (k − 16)` + 0 …, hashed) |
//! | + 1, + 2 | bounce `k`: the point on the light |
//! | + 3, + 4 | bounce `k`: the BSDF direction |
//! | + 5 | bounce `k`: the BSDF lobe |
//! | + 6 | bounce `k`: Russian roulette |
//! | + 7 | bounce `k`: fluorescent re-emission |
//! | 126, 127 ([`LENS_FIRST`]) | a thin lens's aperture point |
//!
//! The pixel pair is Sobol's dimensions 0 and 1, a (0, 2)-sequence; light
//! and BSDF pairs are consecutive dimensions, whose 2D projections Joe
//! and Kuo optimised. A thin lens draws its aperture point only when the
//! camera has one, from the table's last two dimensions, so that the rest
//! of the allocation stays where it was (the independent sampler takes its
//! numbers in call order, so a pair drawn only with a lens leaves a pinhole
//! render's numbers alone; a pair inserted after the pixel's would have
//! moved every Sobol dimension). Stratified over the passes, the aperture
//! converges faster than with hashed numbers (`docs/results.md`, "Thin
//! lens: the aperture's Sobol dimensions"). (Before the lens, the 16th
//! bounce's light selection and light point had dimensions 126 and 127;
//! they are hashed now, which changes Sobol renders only where paths are
//! longer than 15 bounces.) Wavelength numbers past the first four (only the
//! `uniform`, `stratified` and `visible` strategies with more than four
//! wavelengths use them) and bounces past the 15th ([`SOBOL_BOUNCES`]) go
//! past the 128 Sobol dimensions and get hashed random numbers
//! (`sobol.rs`).

use super::rng::{Purpose, Rng, RngPacket, SampleKey};
use super::sobol::{SOBOL_DIMENSIONS, SobolKey, SobolPacket, SobolStream};
use crate::simd::LANES;
use wide::f32x8;

/// Which sampler drives a render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SamplerKind {
    /// Independent PCG streams per (seed, pixel, pass, purpose).
    Independent,
    /// Owen-scrambled Sobol points per pixel (module docs); the default:
    /// lower error at equal time on the measured scenes (`docs/results.md`).
    #[default]
    Sobol,
}

impl SamplerKind {
    /// Every kind, in the order of their names.
    pub const ALL: [SamplerKind; 2] = [SamplerKind::Independent, SamplerKind::Sobol];

    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        }
    }

    /// The kind of a name ([`SamplerKind::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|kind| kind.name() == name)
    }
}

/// Dimension of the pixel offset's x (y is the next).
pub const PIXEL_X: u32 = 0;
/// Dimension of the pixel offset's y.
pub const PIXEL_Y: u32 = 1;
/// First wavelength dimension.
pub const WAVELENGTH_FIRST: u32 = 2;
/// Wavelength numbers given Sobol dimensions: a hero strategy draws one,
/// four covers the stratified and visible defaults of four wavelengths.
pub const WAVELENGTH_DIMENSIONS: u32 = 4;
/// First dimension of bounce 1.
pub const BOUNCE_FIRST: u32 = WAVELENGTH_FIRST + WAVELENGTH_DIMENSIONS;
/// Dimensions per bounce (module docs' table).
pub const BOUNCE_DIMENSIONS: u32 = 8;
/// Dimensions of a thin lens's aperture point.
pub const LENS_DIMENSIONS: u32 = 2;
/// Bounces whose decisions take Sobol dimensions: as many as fit in the
/// table between the wavelengths' dimensions and the lens's (15); later
/// bounces take hashed dimensions past the table (module docs).
pub const SOBOL_BOUNCES: u32 =
    (SOBOL_DIMENSIONS as u32 - BOUNCE_FIRST - LENS_DIMENSIONS) / BOUNCE_DIMENSIONS;
/// First dimension of a thin lens's aperture point: the table's last two
/// (126 and 127), after the [`SOBOL_BOUNCES`] bounces' (module docs).
pub const LENS_FIRST: u32 = BOUNCE_FIRST + SOBOL_BOUNCES * BOUNCE_DIMENSIONS;

// The lens's pair is inside the Sobol table.
const _: () = assert!(LENS_FIRST + LENS_DIMENSIONS <= SOBOL_DIMENSIONS as u32);

/// The dimensions of one bounce's decisions (module docs' table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BounceDimensions {
    /// Light selection.
    pub light_select: u32,
    /// The point on the light, two dimensions from here.
    pub light_point: u32,
    /// The BSDF direction, two dimensions from here.
    pub bsdf_direction: u32,
    /// The BSDF lobe.
    pub bsdf_lobe: u32,
    /// Russian roulette.
    pub roulette: u32,
    /// Fluorescent re-emission.
    pub fluorescence: u32,
}

impl BounceDimensions {
    /// The dimensions of bounce `depth` (1 for the camera ray's hit).
    pub fn of(depth: u32) -> Self {
        let k = depth.saturating_sub(1);
        let first = if k < SOBOL_BOUNCES {
            BOUNCE_FIRST + k * BOUNCE_DIMENSIONS
        } else {
            (SOBOL_DIMENSIONS as u32)
                .saturating_add((k - SOBOL_BOUNCES).saturating_mul(BOUNCE_DIMENSIONS))
        };
        let at = |offset: u32| first.saturating_add(offset);
        Self {
            light_select: at(0),
            light_point: at(1),
            bsdf_direction: at(3),
            bsdf_lobe: at(5),
            roulette: at(6),
            fluorescence: at(7),
        }
    }
}

/// The seed-derived keys of one pass, shared by every pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassKeys {
    kind: SamplerKind,
    pass: u32,
    path: SampleKey,
    wavelengths: SampleKey,
    sobol: SobolKey,
}

impl PassKeys {
    /// The keys of pass `pass` under `seed`.
    pub fn new(kind: SamplerKind, seed: u64, pass: u32) -> Self {
        Self {
            kind,
            pass,
            path: SampleKey::new(seed, u64::from(pass), Purpose::Path),
            wavelengths: SampleKey::new(seed, u64::from(pass), Purpose::Wavelengths),
            sobol: SobolKey::new(seed),
        }
    }

    /// The path sampler of 8 pixels (lanes without a pixel get indices no
    /// pixel has).
    #[inline]
    pub fn path_sampler(&self, pixels: &[u64; LANES]) -> PathSampler {
        match self.kind {
            SamplerKind::Independent => {
                PathSampler::Independent(RngPacket::for_pixels(pixels, self.path))
            }
            SamplerKind::Sobol => {
                PathSampler::Sobol(SobolPacket::new(self.sobol, pixels, self.pass))
            }
        }
    }

    /// The wavelength numbers of one pixel.
    #[inline]
    pub fn wavelength_stream(&self, pixel: u64) -> WavelengthStream {
        match self.kind {
            SamplerKind::Independent => {
                WavelengthStream::Independent(Rng::for_pixel(pixel, self.wavelengths))
            }
            SamplerKind::Sobol => WavelengthStream::Sobol {
                stream: SobolStream::new(self.sobol, pixel, self.pass),
                drawn: 0,
            },
        }
    }
}

/// The numbers of a packet's 8 paths.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathSampler {
    /// One PCG stream per lane; numbers in call order.
    Independent(RngPacket),
    /// One scrambled Sobol sequence per lane; numbers by dimension.
    Sobol(SobolPacket),
}

impl PathSampler {
    /// The number of every lane for `dimension` (ignored by the
    /// independent sampler, which takes the next number of each stream).
    #[inline]
    pub fn draw(&mut self, dimension: u32) -> f32x8 {
        match self {
            PathSampler::Independent(rngs) => rngs.next_f32x8(),
            PathSampler::Sobol(points) => points.sample_x8(dimension),
        }
    }
}

/// The dimension of a path's wavelength number `index`: Sobol's
/// wavelength dimensions for the first [`WAVELENGTH_DIMENSIONS`], then
/// dimensions past every bounce's, which are hashed (module docs).
pub fn wavelength_dimension(index: u32) -> u32 {
    if index < WAVELENGTH_DIMENSIONS {
        WAVELENGTH_FIRST + index
    } else {
        u32::MAX - index
    }
}

/// Uniform numbers in `[0, 1)`, one after another.
pub trait UniformStream {
    /// The next number.
    fn next_f32(&mut self) -> f32;
}

impl UniformStream for Rng {
    fn next_f32(&mut self) -> f32 {
        Rng::next_f32(self)
    }
}

/// One pixel's wavelength numbers: the first
/// [`WAVELENGTH_DIMENSIONS`] from Sobol's wavelength dimensions, the
/// rest hashed (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WavelengthStream {
    /// The pixel's PCG wavelength stream.
    Independent(Rng),
    /// The pixel's Sobol point and how many numbers it gave.
    Sobol {
        /// The pixel's point.
        stream: SobolStream,
        /// Numbers drawn so far.
        drawn: u32,
    },
}

impl UniformStream for WavelengthStream {
    fn next_f32(&mut self) -> f32 {
        match self {
            WavelengthStream::Independent(rng) => rng.next_f32(),
            WavelengthStream::Sobol { stream, drawn } => {
                let dimension = wavelength_dimension(*drawn);
                *drawn += 1;
                stream.sample(dimension)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The allocation's dimensions are distinct within a bounce and across
    /// bounces, wavelengths and the pixel, and the table's layout holds.
    #[test]
    fn dimensions_are_distinct() {
        let mut all = vec![PIXEL_X, PIXEL_Y];
        all.extend(WAVELENGTH_FIRST..WAVELENGTH_FIRST + WAVELENGTH_DIMENSIONS);
        for depth in 1..40 {
            let b = BounceDimensions::of(depth);
            all.extend([
                b.light_select,
                b.light_point,
                b.light_point + 1,
                b.bsdf_direction,
                b.bsdf_direction + 1,
                b.bsdf_lobe,
                b.roulette,
                b.fluorescence,
            ]);
        }
        all.extend([LENS_FIRST, LENS_FIRST + 1]);
        all.extend((WAVELENGTH_DIMENSIONS..64).map(wavelength_dimension));
        let count = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), count);
        assert_eq!(BounceDimensions::of(1).light_select, 6);
        assert_eq!(BounceDimensions::of(2).light_select, 14);
        // The 15th bounce is the last in the table, the lens takes its end
        // and the 16th bounce starts past it.
        assert_eq!(SOBOL_BOUNCES, 15);
        assert_eq!(BounceDimensions::of(15).fluorescence, LENS_FIRST - 1);
        assert_eq!(LENS_FIRST + LENS_DIMENSIONS, SOBOL_DIMENSIONS as u32);
        assert_eq!(
            BounceDimensions::of(16).light_select,
            SOBOL_DIMENSIONS as u32
        );
    }

    #[test]
    fn names_round_trip() {
        for kind in SamplerKind::ALL {
            assert_eq!(SamplerKind::from_name(kind.name()), Some(kind));
        }
        assert_eq!(SamplerKind::from_name("halton"), None);
    }

    /// The independent sampler is the old streams exactly; the Sobol
    /// wavelength stream takes dimensions 2, 3, … of the pixel's point.
    #[test]
    fn samplers_draw_the_documented_numbers() {
        let keys = PassKeys::new(SamplerKind::Independent, 5, 3);
        let pixels: [u64; LANES] = core::array::from_fn(|l| 100 + l as u64);
        let mut sampler = keys.path_sampler(&pixels);
        let mut rngs = RngPacket::for_pixels(&pixels, SampleKey::new(5, 3, Purpose::Path));
        for dimension in [7, 0, 3] {
            assert_eq!(
                sampler.draw(dimension).to_array(),
                rngs.next_f32x8().to_array()
            );
        }
        let keys = PassKeys::new(SamplerKind::Sobol, 5, 3);
        let mut stream = keys.wavelength_stream(101);
        let point = SobolStream::new(SobolKey::new(5), 101, 3);
        for d in 0..WAVELENGTH_DIMENSIONS {
            assert_eq!(stream.next_f32(), point.sample(WAVELENGTH_FIRST + d));
        }
        assert_eq!(
            stream.next_f32(),
            point.sample(u32::MAX - WAVELENGTH_DIMENSIONS)
        );
        let mut sampler = keys.path_sampler(&pixels);
        assert_eq!(sampler.draw(9).to_array()[1], point.sample(9));
    }
}
