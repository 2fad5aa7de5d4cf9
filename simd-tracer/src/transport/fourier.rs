//! [`FourierTransport<N>`]: `N` Fourier coefficients per lane, one truncated
//! product per bounce; the film keeps coefficient sums or XYZ per sample.

use super::{Transport, excited_ids, id_spectra};
use crate::film::{Buffer, FourierFilm, FourierSample, all_finite};
use crate::ids::SpectrumId;
use crate::sampling::sampler::UniformStream;
use crate::scene::Scene;
use crate::shading::material::{Fluorescence, LaneSpectrum, SpectralRef};
use crate::simd::{LANES, LaneMask};
use crate::spectra::MAX_COEFFS;
use spectral_core::observer::Observer;
use spectral_core::xyz::{XyzConverter, XyzRoute};
use spectral_core::{FourierSpectrum, Lane, SpectralError, SpectralRange};
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

// ---------------------------------------------------------------- Fourier

/// Light as `N` Fourier coefficients per ray lane.
#[derive(Debug, Clone)]
pub struct FourierTransport<const N: usize> {
    pub(super) film: FourierFilm<N>,
    /// `λ1 − λ0`: the integral of a series over the range is `W c_0`.
    pub(super) width_nm: f32,
}

impl<const N: usize> FourierTransport<N> {
    /// A Fourier transport over `range` converting by `route` in `buffer`.
    pub fn new(
        range: SpectralRange,
        buffer: Buffer,
        route: XyzRoute,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            film: FourierFilm::new(range, buffer, route)?,
            width_nm: range.width_nm() as f32,
        })
    }

    /// The same seen by another observer ([`spectral_core::observer`]):
    /// the film's kernel and routes project its curves instead.
    pub fn with_observer(
        range: SpectralRange,
        buffer: Buffer,
        route: XyzRoute,
        observer: &Observer,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            film: FourierFilm::with_observer(range, buffer, route, observer)?,
            width_nm: range.width_nm() as f32,
        })
    }

    /// The XYZ converter (and its kernel).
    pub fn converter(&self) -> &XyzConverter<N> {
        self.film.converter()
    }
}

/// Coefficient chunks of [`LANES`] each in a scene spectrum's
/// [`MAX_COEFFS`] (the gather transposes one `LANES × LANES` block per chunk).
pub(super) const CHUNKS: usize = MAX_COEFFS / LANES;

/// Calls `with` on all [`MAX_COEFFS`] Fourier coefficients of a spectral
/// reference (zeros if the reference dangles). Scene spectra are read in
/// place; textures and angular tables fill a temporary.
pub(super) fn with_reference_fourier<R>(
    scene: &Scene,
    reference: &SpectralRef,
    with: impl FnOnce(&[f32; MAX_COEFFS]) -> R,
) -> R {
    match *reference {
        SpectralRef::Scene(id) => with(
            scene
                .spectra()
                .get(id.index())
                .map_or(&[0.0; MAX_COEFFS], |s| s.coefficients_f32()),
        ),
        SpectralRef::Texture { texture, u, v } => with(
            &scene
                .textures()
                .get(texture.index())
                .map_or([0.0; MAX_COEFFS], |t| t.fourier_at(u, v)),
        ),
        SpectralRef::Environment { uv } => with(
            &scene
                .environment_map()
                .map_or([0.0; MAX_COEFFS], |map| map.fourier_at(uv)),
        ),
        SpectralRef::Angular { id, cos, thickness } => with(
            &scene
                .angular()
                .get(id.index())
                .map_or([0.0; MAX_COEFFS], |a| a.fourier(cos, thickness)),
        ),
    }
}

/// The exact value of a spectral reference at a wavelength.
pub(super) fn reference_value(scene: &Scene, reference: &SpectralRef, lambda_nm: f32) -> f32 {
    match *reference {
        SpectralRef::Scene(id) => scene
            .spectra()
            .get(id.index())
            .map_or(0.0, |s| s.value(lambda_nm)),
        SpectralRef::Texture { texture, u, v } => scene
            .textures()
            .get(texture.index())
            .map_or(0.0, |t| t.value_at(u, v, lambda_nm)),
        SpectralRef::Environment { uv } => scene
            .environment_map()
            .map_or(0.0, |map| map.value_at(uv, lambda_nm)),
        SpectralRef::Angular { id, cos, thickness } => scene
            .angular()
            .get(id.index())
            .map_or(0.0, |a| a.eval(cos, lambda_nm, thickness)),
    }
}

/// The lanes' spectral factors `constant + scale · of` as packet-wide
/// coefficients: per lane, `scale ·` each chunk of [`LANES`] coefficients
/// is one 8-wide product, and a `LANES × LANES` transpose per chunk turns
/// lanes-by-coefficients into coefficients-by-lanes (the same products and
/// sums as lane by lane, so the same bits).
pub(super) fn gather_fourier<const N: usize>(
    scene: &Scene,
    lanes: &[LaneSpectrum; LANES],
) -> FourierSpectrum<f32x8, N> {
    if let Some(spectrum) = gather_from_registers(scene, lanes) {
        return spectrum;
    }
    let chunks = N.div_ceil(LANES);
    debug_assert!(chunks <= CHUNKS);
    // rows[chunk][lane]: coefficients chunk·LANES .. (chunk + 1)·LANES of a lane.
    let mut rows = [[f32x8::ZERO; LANES]; CHUNKS];
    for (lane, spectrum) in lanes.iter().enumerate() {
        if let Some(reference) = &spectrum.of {
            let scale = f32x8::splat(spectrum.scale);
            with_reference_fourier(scene, reference, |coeffs| {
                for (row, block) in rows.iter_mut().zip(coeffs.chunks_exact(LANES)).take(chunks) {
                    row[lane] = scale * f32x8::new(block.try_into().unwrap_or([0.0; LANES]));
                }
            });
        }
    }
    let mut coeffs = [f32x8::ZERO; N];
    // Chunk by chunk of the result (`chunks` of them), the transposed
    // columns stored in place.
    for (chunk, row) in coeffs.chunks_mut(LANES).zip(&rows) {
        let columns = f32x8::transpose(*row);
        for (coefficient, column) in chunk.iter_mut().zip(&columns) {
            *coefficient = *column;
        }
    }
    if let Some(first) = coeffs.first_mut() {
        *first += f32x8::new(lanes.map(|l| l.constant));
    }
    FourierSpectrum::from_coeffs(coeffs)
}

/// [`gather_fourier`] where every lane's spectral part is absent or one of
/// the spectra held in registers ([`Scene::spectrum_registers`]): one
/// permute per coefficient and the same product `scale · c` per lane (so
/// the same bits); `None` for any other lane.
#[inline(always)]
pub(super) fn gather_from_registers<const N: usize>(
    scene: &Scene,
    lanes: &[LaneSpectrum; LANES],
) -> Option<FourierSpectrum<f32x8, N>> {
    let registers = scene.spectrum_registers();
    let mut ids = [0u32; LANES];
    let mut spectral = LaneMask::NONE;
    for (lane, spectrum) in lanes.iter().enumerate() {
        match spectrum.of {
            None => {}
            Some(SpectralRef::Scene(id)) if registers.holds(id.0) => {
                ids[lane] = id.0;
                spectral = spectral.with(lane);
            }
            Some(_) => return None,
        }
    }
    let (ids, live) = (u32x8::new(ids), spectral.to_simd());
    let scale = f32x8::new(lanes.map(|l| l.scale));
    let mut coeffs: [f32x8; N] =
        core::array::from_fn(|j| live.select(scale * registers.coefficient(j, ids), f32x8::ZERO));
    if let Some(first) = coeffs.first_mut() {
        *first += f32x8::new(lanes.map(|l| l.constant));
    }
    Some(FourierSpectrum::from_coeffs(coeffs))
}

impl<const N: usize> Transport for FourierTransport<N> {
    type Wavelengths = ();
    type Spectra = FourierSpectrum<f32x8, N>;
    type Film = FourierFilm<N>;

    fn describe(&self) -> String {
        format!("fourier N={N}")
    }

    fn film(&self) -> &FourierFilm<N> {
        &self.film
    }

    fn sample_wavelengths<R: UniformStream>(&self, _stream: impl Fn(usize) -> R) {}

    fn one(&self) -> Self::Spectra {
        FourierSpectrum::constant(f32x8::splat(1.0))
    }

    fn zero(&self) -> Self::Spectra {
        FourierSpectrum::zero()
    }

    fn gather(
        &self,
        scene: &Scene,
        _wavelengths: &(),
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra {
        gather_fourier(scene, lanes)
    }

    /// Held spectra straight from the registers (one permute per
    /// coefficient, the bits of the general gather of `1 · X + 0`).
    fn gather_ids(
        &self,
        scene: &Scene,
        wavelengths: &(),
        ids: &[SpectrumId; LANES],
        lanes: LaneMask,
    ) -> Self::Spectra {
        let registers = scene.spectrum_registers();
        let live = lanes.to_simd();
        let id_lanes = u32x8::new(SpectrumId::words(*ids));
        if !(registers.holds_x8(id_lanes) | !cast::<f32x8, u32x8>(live)).all() {
            return self.gather(scene, wavelengths, &id_spectra(ids, lanes));
        }
        let ids = cast::<f32x8, u32x8>(live).select(id_lanes, u32x8::ZERO);
        let mut coeffs: [f32x8; N] =
            core::array::from_fn(|j| live.select(registers.coefficient(j, ids), f32x8::ZERO));
        // The general gather adds the constant part (0) to `c_0`: `−0`
        // becomes `+0` there, and here.
        if let Some(first) = coeffs.first_mut() {
            *first += f32x8::ZERO;
        }
        FourierSpectrum::from_coeffs(coeffs)
    }

    // Inlined: a 384-byte product returned from a call is copied again
    // into its destination (`memcpy`), which costs more than the call.
    #[inline(always)]
    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        a.product(b)
    }

    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra {
        a.scale(weight)
    }

    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        *a + *b
    }

    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        a.mean()
    }

    fn select(&self, lanes: LaneMask, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        let mask = lanes.to_simd();
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
            mask.select(a.coeffs[j], b.coeffs[j])
        }))
    }

    fn through_event(
        &self,
        pending: &Self::Spectra,
        excited: &Self::Spectra,
        _wavelengths: &(),
    ) -> Self::Spectra {
        pending.scale(excited.coeffs[0] * f32x8::splat(self.width_nm))
    }

    fn fluoresce(
        &self,
        scene: &Scene,
        wavelengths: &mut (),
        fluorescence: &Fluorescence,
        _u: f32x8,
    ) -> Self::Spectra {
        let ids = excited_ids(scene, fluorescence);
        self.gather_ids(scene, wavelengths, &ids, fluorescence.lanes)
    }

    fn samples(&self, radiance: &Self::Spectra, _wavelengths: &()) -> [FourierSample<N>; LANES] {
        // Coefficients-by-lanes to lanes-by-coefficients, one 8 × 8
        // transpose per chunk of 8 coefficients.
        let mut coeffs = [[0.0f32; N]; LANES];
        for (chunk, planes) in radiance.coeffs.chunks(LANES).enumerate() {
            let block: [f32x8; LANES] =
                core::array::from_fn(|j| planes.get(j).copied().unwrap_or(f32x8::ZERO));
            for (lane, row) in f32x8::transpose(block).iter().enumerate() {
                let row = row.to_array();
                for (c, &value) in coeffs[lane][chunk * LANES..].iter_mut().zip(&row) {
                    *c = value;
                }
            }
        }
        let xyz: [[f32; 3]; LANES] = match (self.film.buffer, self.film.route) {
            (Buffer::Spectral, _) => [[0.0; 3]; LANES],
            (Buffer::Xyz, XyzRoute::Mese) => core::array::from_fn(|lane| {
                let c = radiance.lane(lane);
                self.film.converter.mese(&c).to_array().map(|v| v as f32)
            }),
            (Buffer::Xyz, route) => {
                let xyz = match route {
                    XyzRoute::Series => self.film.converter.series(radiance),
                    XyzRoute::Lut => self.film.converter.lut(radiance),
                    _ => self.film.converter.zeroth(radiance),
                };
                core::array::from_fn(|lane| xyz.map(|v| v.lane(lane) as f32).to_array())
            }
        };
        core::array::from_fn(|lane| FourierSample {
            coeffs: coeffs[lane],
            xyz: xyz[lane],
        })
    }

    /// The coefficients checked 8 lanes at a time on the radiance (a
    /// sample's coefficients are its lane's, moved unchanged); the XYZ per
    /// lane only where the buffer holds XYZ (else it is 0).
    fn finite_lanes(
        &self,
        radiance: &Self::Spectra,
        samples: &[FourierSample<N>; LANES],
    ) -> LaneMask {
        let all = f32x8::ZERO.is_finite();
        let coeffs = radiance
            .coeffs
            .iter()
            .fold(all, |finite, c| finite & c.is_finite());
        let lanes = LaneMask::from_simd(coeffs);
        match self.film.buffer {
            Buffer::Spectral => lanes,
            Buffer::Xyz => (0..LANES)
                .filter(|&lane| all_finite(&samples[lane].xyz))
                .fold(LaneMask::NONE, LaneMask::with)
                .and(lanes),
        }
    }
}
