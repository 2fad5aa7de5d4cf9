//! Spectral transports: what a path carries, how it is multiplied, and how a
//! finished sample reaches the film.
//!
//! * [`FourierTransport<N>`]: throughput and radiance are
//!   `FourierSpectrum<f32x8, N>` — eight spectra, one per ray lane — and every
//!   spectral product is the core's truncated product across the lanes. The
//!   film keeps per-pixel coefficient sums (spectral buffer, converted once
//!   by the chosen route) or converts every sample to XYZ (XYZ buffer).
//! * [`SampledTransport<C>`]: `C` wavelengths per path; the packet stores
//!   `[f32x8; C]` (wavelength index × lane), i.e. one `SampledSpectrum<C>`
//!   per lane in structure-of-arrays form; products are element-wise. Each
//!   sample reaches the film as the estimate `(1/C) Σ L x̄/p / ∫ȳ`.
//! * [`ControlVariateTransport<C, N>`]: both at once (paper §3): `Y` the
//!   sampled estimate, `C` the path's Fourier spectrum evaluated at the same
//!   wavelengths through the same estimator, `μ` its exact XYZ (3×N kernel);
//!   per pixel and channel a [`ControlVariate`] weighted by `α` from the
//!   earlier passes only — pooled over all pixels ([`AlphaMode::Shared`],
//!   the default: a single pixel's tens of samples give a noisy `α`) or per
//!   pixel ([`AlphaMode::PerPixel`]).

use crate::shading::material::{LaneSpectrum, SpectralRef};
use crate::packet::{LANES, LaneMask};
use crate::sampling::rng::Rng;
use crate::scene::{Scene, SpectrumId};
use crate::spectra::{DensePoint, MAX_COEFFS};
use spectral_core::color::Xyz;
use spectral_core::control_variate::{AlphaStatistics, ControlVariate};
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
use spectral_core::xyz::{XyzConverter, XyzRoute};
use spectral_core::{FourierSpectrum, Lane, SpectralError, SpectralRange};
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// Where Fourier samples are converted to colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Buffer {
    /// Per-pixel coefficient sums, converted once at the end.
    Spectral,
    /// Per-sample conversion to XYZ (the conversion cost is paid per sample).
    Xyz,
}

/// A spectral representation of light paths (module docs).
pub trait Transport: Sync {
    /// Per-packet wavelengths (unit for Fourier).
    type Wavelengths: Copy + Send;
    /// Packet-wide spectral values, 8 lanes.
    type Spectra: Copy;
    /// One finished sample as the film consumes it.
    type Sample: Copy;
    /// Per-pixel accumulator.
    type Pixel: Clone + Send + Sync;
    /// What all pixels share when a pass ends (the pooled `α` of control variates).
    type PassShared: Send + Sync;

    /// A short description, e.g. `fourier N=12`.
    fn describe(&self) -> String;
    /// An empty pixel.
    fn empty_pixel(&self) -> Self::Pixel;
    /// Draws the wavelengths of a packet; `stream(lane)` makes a lane's
    /// wavelength random stream on demand (hashing its key costs about as
    /// much as the camera ray, so transports that draw no wavelengths,
    /// like Fourier, never make one).
    fn sample_wavelengths(&self, stream: impl Fn(usize) -> Rng) -> Self::Wavelengths;
    /// The hero wavelength of a lane (`None` where light is not sampled).
    fn hero_wavelength(&self, _wavelengths: &Self::Wavelengths, _lane: usize) -> Option<f32> {
        None
    }
    /// Keeps only the hero wavelength of a lane (dispersion).
    fn terminate_secondary(&self, _wavelengths: &mut Self::Wavelengths, _lane: usize) {}
    /// 1 in every lane.
    fn one(&self) -> Self::Spectra;
    /// 0 in every lane.
    fn zero(&self) -> Self::Spectra;
    /// The per-lane spectral factors as packet-wide values.
    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra;
    /// [`Transport::gather`] of the scene spectra `ids` in the lanes of
    /// `lanes` and of zero elsewhere (a Lambert packet's albedos).
    fn gather_ids(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        ids: &[SpectrumId; LANES],
        lanes: LaneMask,
    ) -> Self::Spectra {
        self.gather(scene, wavelengths, &id_spectra(ids, lanes))
    }
    /// Spectral product (truncated for Fourier).
    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra;
    /// Multiplies each lane by a scalar.
    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra;
    /// Sum.
    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra;
    /// Mean over wavelengths per lane (the Russian-roulette proxy).
    fn mean(&self, a: &Self::Spectra) -> f32x8;
    /// The finished samples of a packet.
    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [Self::Sample; LANES];
    /// Whether a sample is free of NaN and infinity (else it is rejected).
    fn sample_is_finite(sample: &Self::Sample) -> bool;
    /// The lanes whose samples (made from `radiance`) are free of NaN and
    /// infinity: [`Transport::sample_is_finite`] lane by lane.
    fn finite_lanes(&self, _radiance: &Self::Spectra, samples: &[Self::Sample; LANES]) -> LaneMask {
        (0..LANES)
            .filter(|&lane| Self::sample_is_finite(&samples[lane]))
            .fold(LaneMask::NONE, LaneMask::with)
    }
    /// Adds a sample to a pixel.
    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample);
    /// The shared state for ending the current pass, from every pixel
    /// before any of them ends it.
    fn pass_shared<'a>(
        &self,
        pixels: &mut dyn Iterator<Item = &'a Self::Pixel>,
    ) -> Self::PassShared
    where
        Self::Pixel: 'a;
    /// Ends a pass (a control-variate batch).
    fn end_pass(&self, pixel: &mut Self::Pixel, shared: &Self::PassShared);
    /// Whether ending a pass does anything ([`Transport::end_pass`] reads
    /// state shared by all pixels). When it does not, the renderer may run
    /// several passes per tile in a row (same image, fewer trips of the
    /// film through the caches).
    fn passes_interact(&self) -> bool {
        false
    }
    /// The pixel's XYZ.
    fn resolve(&self, pixel: &Self::Pixel) -> Xyz;
    /// The pixel's mean Fourier coefficients, if the transport keeps them.
    fn coefficients(&self, _pixel: &Self::Pixel) -> Option<Vec<f64>> {
        None
    }
}

/// The lane spectra of [`Transport::gather_ids`]: scene spectrum
/// `ids[lane]` in the lanes of `lanes`, zero elsewhere.
fn id_spectra(ids: &[SpectrumId; LANES], lanes: LaneMask) -> [LaneSpectrum; LANES] {
    core::array::from_fn(|lane| {
        if lanes.contains(lane) {
            LaneSpectrum::scene(ids[lane])
        } else {
            LaneSpectrum::ZERO
        }
    })
}

/// Whether every value is finite (without early exit: the check is a
/// branch-free pass over a few values).
fn all_finite(values: &[f32]) -> bool {
    values.iter().fold(true, |finite, v| finite & v.is_finite())
}
// ---------------------------------------------------------------- Fourier

/// Light as `N` Fourier coefficients per ray lane.
#[derive(Debug, Clone)]
pub struct FourierTransport<const N: usize> {
    converter: Box<XyzConverter<N>>,
    buffer: Buffer,
    route: XyzRoute,
}

impl<const N: usize> FourierTransport<N> {
    /// A Fourier transport over `range` converting by `route` in `buffer`.
    pub fn new(
        range: SpectralRange,
        buffer: Buffer,
        route: XyzRoute,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            converter: Box::new(XyzConverter::new(range)?),
            buffer,
            route,
        })
    }

    /// The XYZ converter (and its kernel).
    pub fn converter(&self) -> &XyzConverter<N> {
        &self.converter
    }
}

/// A finished Fourier sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourierSample<const N: usize> {
    /// Coefficients (spectral buffer).
    pub coeffs: [f32; N],
    /// XYZ (XYZ buffer).
    pub xyz: [f32; 3],
}

/// A Fourier pixel: coefficient sums, XYZ sums and the sample count.
#[derive(Debug, Clone, PartialEq)]
pub struct FourierPixel<const N: usize> {
    coeffs: [f64; N],
    xyz: [f64; 3],
    count: f64,
}

/// Coefficient chunks of [`LANES`] each in a scene spectrum's
/// [`MAX_COEFFS`] (the gather transposes one `LANES × LANES` block per chunk).
const CHUNKS: usize = MAX_COEFFS / LANES;

/// Calls `with` on all [`MAX_COEFFS`] Fourier coefficients of a spectral
/// reference (zeros if the reference dangles). Scene spectra are read in
/// place; textures and angular tables fill a temporary.
fn with_reference_fourier<R>(
    scene: &Scene,
    reference: &SpectralRef,
    with: impl FnOnce(&[f32; MAX_COEFFS]) -> R,
) -> R {
    match *reference {
        SpectralRef::Scene(id) => with(
            scene
                .spectra
                .get(id as usize)
                .map_or(&[0.0; MAX_COEFFS], |s| s.coefficients_f32()),
        ),
        SpectralRef::Texture { texture, u, v } => with(
            &scene
                .textures
                .get(texture as usize)
                .map_or([0.0; MAX_COEFFS], |t| t.fourier_at(u, v)),
        ),
        SpectralRef::Angular { id, cos, thickness } => with(
            &scene
                .angular
                .get(id as usize)
                .map_or([0.0; MAX_COEFFS], |a| a.fourier(cos, thickness)),
        ),
    }
}

/// The exact value of a spectral reference at a wavelength.
fn reference_value(scene: &Scene, reference: &SpectralRef, lambda_nm: f32) -> f32 {
    match *reference {
        SpectralRef::Scene(id) => scene
            .spectra
            .get(id as usize)
            .map_or(0.0, |s| s.value(lambda_nm)),
        SpectralRef::Texture { texture, u, v } => scene
            .textures
            .get(texture as usize)
            .map_or(0.0, |t| t.value_at(u, v, lambda_nm)),
        SpectralRef::Angular { id, cos, thickness } => scene
            .angular
            .get(id as usize)
            .map_or(0.0, |a| a.eval(cos, lambda_nm, thickness)),
    }
}

/// The lanes' spectral factors `constant + scale · of` as packet-wide
/// coefficients: per lane, `scale ·` each chunk of [`LANES`] coefficients
/// is one 8-wide product, and a `LANES × LANES` transpose per chunk turns
/// lanes-by-coefficients into coefficients-by-lanes (the same products and
/// sums as lane by lane, so the same bits).
fn gather_fourier<const N: usize>(
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
    for (chunk, row) in rows.iter().enumerate().take(chunks) {
        let columns = f32x8::transpose(*row);
        for (coefficient, column) in coeffs.iter_mut().skip(chunk * LANES).zip(columns) {
            *coefficient = column;
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
fn gather_from_registers<const N: usize>(
    scene: &Scene,
    lanes: &[LaneSpectrum; LANES],
) -> Option<FourierSpectrum<f32x8, N>> {
    let registers = scene.spectrum_registers();
    let mut ids = [0u32; LANES];
    let mut spectral = LaneMask::NONE;
    for (lane, spectrum) in lanes.iter().enumerate() {
        match spectrum.of {
            None => {}
            Some(SpectralRef::Scene(id)) if registers.holds(id) => {
                ids[lane] = id;
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
    type Sample = FourierSample<N>;
    type Pixel = FourierPixel<N>;
    type PassShared = ();

    fn describe(&self) -> String {
        format!("fourier N={N}")
    }

    fn empty_pixel(&self) -> Self::Pixel {
        FourierPixel {
            coeffs: [0.0; N],
            xyz: [0.0; 3],
            count: 0.0,
        }
    }

    fn sample_wavelengths(&self, _stream: impl Fn(usize) -> Rng) {}

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
        let id_lanes = u32x8::new(*ids);
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

    fn samples(&self, radiance: &Self::Spectra, _wavelengths: &()) -> [Self::Sample; LANES] {
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
        let xyz: [[f32; 3]; LANES] = match (self.buffer, self.route) {
            (Buffer::Spectral, _) => [[0.0; 3]; LANES],
            (Buffer::Xyz, XyzRoute::Mese) => core::array::from_fn(|lane| {
                let c = radiance.lane(lane);
                self.converter.mese(&c).map(|v| v as f32)
            }),
            (Buffer::Xyz, route) => {
                let xyz = match route {
                    XyzRoute::Series => self.converter.series(radiance),
                    XyzRoute::Lut => self.converter.lut(radiance),
                    _ => self.converter.zeroth(radiance),
                };
                core::array::from_fn(|lane| core::array::from_fn(|r| xyz[r].lane(lane) as f32))
            }
        };
        core::array::from_fn(|lane| FourierSample {
            coeffs: coeffs[lane],
            xyz: xyz[lane],
        })
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(&sample.coeffs) && all_finite(&sample.xyz)
    }

    /// The coefficients checked 8 lanes at a time on the radiance (a
    /// sample's coefficients are its lane's, moved unchanged); the XYZ per
    /// lane only where the buffer holds XYZ (else it is 0).
    fn finite_lanes(&self, radiance: &Self::Spectra, samples: &[Self::Sample; LANES]) -> LaneMask {
        let all = f32x8::ZERO.is_finite();
        let coeffs = radiance
            .coeffs
            .iter()
            .fold(all, |finite, c| finite & c.is_finite());
        let lanes = LaneMask::from_simd(coeffs);
        match self.buffer {
            Buffer::Spectral => lanes,
            Buffer::Xyz => (0..LANES)
                .filter(|&lane| all_finite(&samples[lane].xyz))
                .fold(LaneMask::NONE, LaneMask::with)
                .and(lanes),
        }
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        match self.buffer {
            Buffer::Spectral => {
                for (acc, &c) in pixel.coeffs.iter_mut().zip(&sample.coeffs) {
                    *acc += f64::from(c);
                }
            }
            Buffer::Xyz => {
                for (acc, &c) in pixel.xyz.iter_mut().zip(&sample.xyz) {
                    *acc += f64::from(c);
                }
            }
        }
        pixel.count += 1.0;
    }

    fn pass_shared<'a>(
        &self,
        _pixels: &mut dyn Iterator<Item = &'a Self::Pixel>,
    ) -> Self::PassShared
    where
        Self::Pixel: 'a,
    {
    }

    fn end_pass(&self, _pixel: &mut Self::Pixel, _shared: &()) {}

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        if pixel.count == 0.0 {
            return Xyz::default();
        }
        match self.buffer {
            Buffer::Spectral => {
                let mean = FourierSpectrum::from_coeffs(pixel.coeffs.map(|c| c / pixel.count));
                self.converter.convert(self.route, &mean)
            }
            Buffer::Xyz => Xyz::from_array(pixel.xyz.map(|v| v / pixel.count)),
        }
    }

    fn coefficients(&self, pixel: &Self::Pixel) -> Option<Vec<f64>> {
        match self.buffer {
            Buffer::Spectral if pixel.count > 0.0 => {
                Some(pixel.coeffs.iter().map(|c| c / pixel.count).collect())
            }
            Buffer::Spectral => Some(vec![0.0; N]),
            Buffer::Xyz => None,
        }
    }
}

// ---------------------------------------------------------------- sampled

/// Light as `C` sampled wavelengths per path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledTransport<const C: usize> {
    strategy: WavelengthStrategy,
    range: SpectralRange,
}

impl<const C: usize> SampledTransport<C> {
    /// `C` wavelengths per path over `range`, drawn by `strategy`.
    pub fn new(range: SpectralRange, strategy: WavelengthStrategy) -> Self {
        Self { strategy, range }
    }
}

/// A sampled pixel: XYZ sums and the sample count.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct XyzPixel {
    xyz: [f64; 3],
    count: f64,
}

/// The wavelengths of a packet's paths in the sampled transports: each
/// lane's [`SampledWavelengths`] and where they fall on the dense grid of
/// the render range ([`DensePoint`]), placed once per path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PacketWavelengths<const C: usize> {
    lanes: [SampledWavelengths<C>; LANES],
    points: [[DensePoint; C]; LANES],
    /// The range whose grid `points` lie on.
    grid: SpectralRange,
}

impl<const C: usize> PacketWavelengths<C> {
    /// Places the wavelengths of every lane on the dense grid of `range`.
    pub fn new(lanes: [SampledWavelengths<C>; LANES], range: &SpectralRange) -> Self {
        Self {
            points: lanes.map(|w| w.lambda_nm().map(|l| DensePoint::new(range, l))),
            lanes,
            grid: *range,
        }
    }

    /// The wavelengths of ray lane `lane` (taken modulo [`LANES`]).
    pub fn lane(&self, lane: usize) -> &SampledWavelengths<C> {
        &self.lanes[lane % LANES]
    }
}

/// The lanes' spectral factors at their wavelengths (only the hero where
/// the secondaries are terminated). Scene spectra prepared over the range
/// the wavelengths were placed on, the common case, are read from their
/// dense tables at the lanes' points on that grid, placed once per path
/// ([`PacketWavelengths`]); placing every wavelength anew in each lookup
/// (`f64` arithmetic and conversions) had cost 17 % of a 4-hero-wavelength
/// render. Other references go through [`reference_value`]. The same
/// values either way.
fn gather_sampled<const C: usize>(
    scene: &Scene,
    wavelengths: &PacketWavelengths<C>,
    lanes: &[LaneSpectrum; LANES],
) -> [f32x8; C] {
    let mut values = [[0.0f32; LANES]; C];
    for (lane, spectrum) in lanes.iter().enumerate() {
        let w = &wavelengths.lanes[lane];
        let count = if w.secondary_terminated() { 1 } else { C };
        let (constant, scale) = (spectrum.constant, spectrum.scale);
        let on_grid = match &spectrum.of {
            Some(SpectralRef::Scene(id)) => scene
                .spectra
                .get(*id as usize)
                .filter(|s| s.range() == &wavelengths.grid),
            _ => None,
        };
        if let Some(table) = on_grid {
            for (v, &point) in values.iter_mut().zip(&wavelengths.points[lane]).take(count) {
                v[lane] = constant + scale * table.value_at(point);
            }
        } else {
            for (v, &l) in values.iter_mut().zip(w.lambda_nm()).take(count) {
                let x = spectrum
                    .of
                    .as_ref()
                    .map_or(0.0, |r| reference_value(scene, r, l));
                v[lane] = constant + scale * x;
            }
        }
    }
    values.map(f32x8::new)
}

fn sampled_lane<const C: usize>(values: &[f32x8; C], lane: usize) -> SampledSpectrum<C> {
    SampledSpectrum {
        values: core::array::from_fn(|i| values[i].to_array()[lane]),
    }
}

impl<const C: usize> Transport for SampledTransport<C> {
    type Wavelengths = PacketWavelengths<C>;
    type Spectra = [f32x8; C];
    type Sample = [f32; 3];
    type Pixel = XyzPixel;
    type PassShared = ();

    fn describe(&self) -> String {
        format!("sampled C={C} {:?}", self.strategy)
    }

    fn empty_pixel(&self) -> Self::Pixel {
        XyzPixel::default()
    }

    fn sample_wavelengths(&self, stream: impl Fn(usize) -> Rng) -> Self::Wavelengths {
        let lanes = core::array::from_fn(|lane| {
            let mut rng = stream(lane);
            let u: [f32; C] = core::array::from_fn(|_| rng.next_f32());
            SampledWavelengths::sample(self.strategy, &self.range, u)
        });
        PacketWavelengths::new(lanes, &self.range)
    }

    fn hero_wavelength(&self, wavelengths: &Self::Wavelengths, lane: usize) -> Option<f32> {
        wavelengths.lanes.get(lane).map(|w| w.lambda_nm()[0])
    }

    fn terminate_secondary(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        if let Some(w) = wavelengths.lanes.get_mut(lane) {
            w.terminate_secondary();
        }
    }

    fn one(&self) -> Self::Spectra {
        [f32x8::splat(1.0); C]
    }

    fn zero(&self) -> Self::Spectra {
        [f32x8::splat(0.0); C]
    }

    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra {
        gather_sampled(scene, wavelengths, lanes)
    }

    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        core::array::from_fn(|i| a[i] * b[i])
    }

    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra {
        a.map(|v| v * weight)
    }

    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        core::array::from_fn(|i| a[i] + b[i])
    }

    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        a.iter().fold(f32x8::splat(0.0), |acc, &v| acc + v) * f32x8::splat(1.0 / C as f32)
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [Self::Sample; LANES] {
        core::array::from_fn(|lane| {
            sampled_lane(radiance, lane)
                .to_xyz(wavelengths.lane(lane))
                .to_array()
                .map(|v| v as f32)
        })
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(sample)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        for (acc, &v) in pixel.xyz.iter_mut().zip(sample) {
            *acc += f64::from(v);
        }
        pixel.count += 1.0;
    }

    fn pass_shared<'a>(
        &self,
        _pixels: &mut dyn Iterator<Item = &'a Self::Pixel>,
    ) -> Self::PassShared
    where
        Self::Pixel: 'a,
    {
    }

    fn end_pass(&self, _pixel: &mut Self::Pixel, _shared: &()) {}

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        if pixel.count == 0.0 {
            return Xyz::default();
        }
        Xyz::from_array(pixel.xyz.map(|v| v / pixel.count))
    }
}

// ---------------------------------------------------------------- control variate

/// Where the control-variate coefficient `α` comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlphaMode {
    /// Each pixel's own earlier passes (noisy with few samples per pixel).
    PerPixel,
    /// The earlier passes of all pixels pooled, one `α` per XYZ channel.
    Shared,
}

/// Sampled wavelengths with the Fourier estimate as a control variate.
#[derive(Debug, Clone)]
pub struct ControlVariateTransport<const C: usize, const N: usize> {
    fourier: FourierTransport<N>,
    sampled: SampledTransport<C>,
    range: SpectralRange,
    alpha: AlphaMode,
}

impl<const C: usize, const N: usize> ControlVariateTransport<C, N> {
    /// `C` wavelengths by `strategy` plus `N` coefficients over `range`.
    pub fn new(
        range: SpectralRange,
        strategy: WavelengthStrategy,
        alpha: AlphaMode,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            fourier: FourierTransport::new(range, Buffer::Xyz, XyzRoute::Zeroth)?,
            sampled: SampledTransport::new(range, strategy),
            range,
            alpha,
        })
    }
}

/// One control-variate sample: `Y`, `C` and `μ` in XYZ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CvSample {
    /// Sampled estimate.
    pub y: [f32; 3],
    /// Fourier spectrum through the same estimator.
    pub c: [f32; 3],
    /// Exact XYZ of the Fourier spectrum.
    pub mu: [f32; 3],
}

/// A control-variate pixel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CvPixel {
    channels: [ControlVariate; 3],
}

impl<const C: usize, const N: usize> Transport for ControlVariateTransport<C, N> {
    type Wavelengths = PacketWavelengths<C>;
    type Spectra = (FourierSpectrum<f32x8, N>, [f32x8; C]);
    type Sample = CvSample;
    type Pixel = CvPixel;
    type PassShared = Option<[f64; 3]>;

    fn describe(&self) -> String {
        format!("control variate C={C} N={N} {:?}", self.sampled.strategy)
    }

    fn empty_pixel(&self) -> Self::Pixel {
        CvPixel::default()
    }

    fn sample_wavelengths(&self, stream: impl Fn(usize) -> Rng) -> Self::Wavelengths {
        self.sampled.sample_wavelengths(stream)
    }

    fn hero_wavelength(&self, wavelengths: &Self::Wavelengths, lane: usize) -> Option<f32> {
        self.sampled.hero_wavelength(wavelengths, lane)
    }

    fn terminate_secondary(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        self.sampled.terminate_secondary(wavelengths, lane);
    }

    fn one(&self) -> Self::Spectra {
        (self.fourier.one(), self.sampled.one())
    }

    fn zero(&self) -> Self::Spectra {
        (self.fourier.zero(), self.sampled.zero())
    }

    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra {
        (
            gather_fourier(scene, lanes),
            gather_sampled(scene, wavelengths, lanes),
        )
    }

    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        (self.fourier.mul(&a.0, &b.0), self.sampled.mul(&a.1, &b.1))
    }

    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra {
        (
            self.fourier.scale(&a.0, weight),
            self.sampled.scale(&a.1, weight),
        )
    }

    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        (self.fourier.add(&a.0, &b.0), self.sampled.add(&a.1, &b.1))
    }

    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        self.sampled.mean(&a.1)
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [Self::Sample; LANES] {
        let mu = self.fourier.converter.zeroth(&radiance.0);
        core::array::from_fn(|lane| {
            let w = wavelengths.lane(lane);
            let y = sampled_lane(&radiance.1, lane).to_xyz(w);
            let series: FourierSpectrum<f32, N> =
                FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                    radiance.0.coeffs[j].to_array()[lane]
                }));
            let c = SampledSpectrum::from_fourier(&series, &self.range, w).to_xyz(w);
            CvSample {
                y: y.to_array().map(|v| v as f32),
                c: c.to_array().map(|v| v as f32),
                mu: core::array::from_fn(|r| mu[r].lane(lane) as f32),
            }
        })
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(&sample.y) && all_finite(&sample.c) && all_finite(&sample.mu)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        for (r, channel) in pixel.channels.iter_mut().enumerate() {
            channel.add(
                f64::from(sample.y[r]),
                f64::from(sample.c[r]),
                f64::from(sample.mu[r]),
            );
        }
    }

    fn pass_shared<'a>(&self, pixels: &mut dyn Iterator<Item = &'a Self::Pixel>) -> Self::PassShared
    where
        Self::Pixel: 'a,
    {
        match self.alpha {
            AlphaMode::PerPixel => None,
            AlphaMode::Shared => {
                let mut pooled = [AlphaStatistics::default(); 3];
                for pixel in pixels {
                    for (p, channel) in pooled.iter_mut().zip(&pixel.channels) {
                        p.merge(channel.statistics());
                    }
                }
                Some(pooled.map(|p| p.alpha()))
            }
        }
    }

    fn passes_interact(&self) -> bool {
        true
    }

    fn end_pass(&self, pixel: &mut Self::Pixel, shared: &Self::PassShared) {
        for (r, channel) in pixel.channels.iter_mut().enumerate() {
            match shared {
                Some(alpha) => channel.end_batch_with_alpha(alpha[r]),
                None => channel.end_batch(),
            }
        }
    }

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        Xyz::from_array(core::array::from_fn(|r| pixel.channels[r].estimate()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectral_core::SpectralRange;

    /// `constant + scale · coefficient` lane by lane (the scalar oracle).
    fn gather_by_lane<const N: usize>(
        scene: &Scene,
        lanes: &[LaneSpectrum; LANES],
    ) -> [[f32; LANES]; N] {
        let mut out = [[0.0f32; LANES]; N];
        for (lane, spectrum) in lanes.iter().enumerate() {
            let mut row = [0.0f32; N];
            if let Some(reference) = &spectrum.of {
                with_reference_fourier(scene, reference, |coeffs| {
                    for (r, &c) in row.iter_mut().zip(coeffs) {
                        *r = spectrum.scale * c;
                    }
                });
            }
            row[0] += spectrum.constant;
            for (j, value) in row.into_iter().enumerate() {
                out[j][lane] = value;
            }
        }
        out
    }

    fn check<const N: usize>(scene: &Scene, lanes: &[LaneSpectrum; LANES]) {
        let packed = gather_fourier::<N>(scene, lanes);
        let expected = gather_by_lane::<N>(scene, lanes);
        for (j, row) in expected.iter().enumerate() {
            assert_eq!(
                packed.coeffs[j].to_array().map(f32::to_bits),
                row.map(f32::to_bits),
                "N = {N}, coefficient {j}"
            );
        }
    }

    /// Lanes of every kind over the scene spectra `0 .. spectra`: a
    /// spectrum, its complement, a scaled and offset one, and `last(lane)`
    /// in every fourth lane.
    fn mixed_lanes(spectra: u32, last: impl Fn(usize) -> LaneSpectrum) -> [LaneSpectrum; LANES] {
        core::array::from_fn(|lane| match lane % 4 {
            0 => LaneSpectrum::scene(lane as u32 % spectra),
            1 => LaneSpectrum::complement(SpectralRef::Scene((lane as u32 + 1) % spectra)),
            2 => LaneSpectrum {
                constant: 0.25 * lane as f32,
                scale: -1.5 + lane as f32,
                of: Some(SpectralRef::Scene((lane as u32 + 2) % spectra)),
            },
            _ => last(lane),
        })
    }

    /// A lane with only a constant part.
    fn constant_lane() -> LaneSpectrum {
        LaneSpectrum {
            constant: 0.7,
            ..LaneSpectrum::ZERO
        }
    }

    #[test]
    fn gather_matches_the_lane_by_lane_oracle_bit_for_bit() {
        let Ok(scene) = crate::scene::builtin::cornell_box(SpectralRange::VISIBLE) else {
            panic!("Cornell box");
        };
        let spectra = scene.spectra.len() as u32;
        assert!(spectra >= 3);
        // A constant lane and a dangling reference (zeros).
        let lanes = mixed_lanes(spectra, |lane| {
            if lane == 3 {
                constant_lane()
            } else {
                LaneSpectrum::scene(spectra + 5)
            }
        });
        assert!(gather_from_registers::<12>(&scene, &lanes).is_none());
        check::<4>(&scene, &lanes);
        check::<8>(&scene, &lanes);
        check::<12>(&scene, &lanes);
        check::<16>(&scene, &lanes);
        check::<32>(&scene, &lanes);
        // Only spectra held in registers (and lanes without a spectral
        // part): the register path, against the same oracle.
        let held = spectra.min(LANES as u32);
        let lanes = mixed_lanes(held, |_| constant_lane());
        assert!(gather_from_registers::<12>(&scene, &lanes).is_some());
        check::<4>(&scene, &lanes);
        check::<8>(&scene, &lanes);
        check::<12>(&scene, &lanes);
        check::<16>(&scene, &lanes);
        check::<32>(&scene, &lanes);
    }

    /// The sampled gather equals `constant + scale · value(λ)` lane by lane
    /// and wavelength by wavelength through [`reference_value`] (zero past
    /// the hero where the secondaries are terminated), bit for bit: for
    /// scene spectra on the transport's grid, a constant lane and a
    /// dangling reference, and for a transport over another range, whose
    /// spectra are off its grid (the fallback path).
    #[test]
    fn sampled_gather_matches_the_lane_by_lane_oracle_bit_for_bit() {
        let Ok(scene) = crate::scene::builtin::cornell_box(SpectralRange::VISIBLE) else {
            panic!("Cornell box");
        };
        let spectra = scene.spectra.len() as u32;
        let Ok(narrow) = SpectralRange::new(380.0, 780.0) else {
            panic!("range");
        };
        let mut rng = Rng::new(11, 12);
        for (round, range) in [SpectralRange::VISIBLE, narrow]
            .iter()
            .cycle()
            .take(60)
            .enumerate()
        {
            let transport = SampledTransport::<4>::new(*range, WavelengthStrategy::Hero);
            let seeds: [Rng; LANES] = core::array::from_fn(|_| Rng::new(rng.next_u32(), 7));
            let mut wavelengths = transport.sample_wavelengths(|lane| seeds[lane]);
            for lane in 0..LANES {
                if (lane + round) % 3 == 0 {
                    transport.terminate_secondary(&mut wavelengths, lane);
                }
            }
            let lanes = mixed_lanes(spectra, |lane| {
                if lane == 3 {
                    constant_lane()
                } else {
                    LaneSpectrum::scene(spectra + 5)
                }
            });
            let gathered = transport.gather(&scene, &wavelengths, &lanes);
            for (lane, spectrum) in lanes.iter().enumerate() {
                let w = wavelengths.lane(lane);
                for (i, &l) in w.lambda_nm().iter().enumerate() {
                    let expected = if i > 0 && w.secondary_terminated() {
                        0.0
                    } else {
                        let x = spectrum
                            .of
                            .as_ref()
                            .map_or(0.0, |r| reference_value(&scene, r, l));
                        spectrum.constant + spectrum.scale * x
                    };
                    assert_eq!(
                        gathered[i].to_array()[lane].to_bits(),
                        expected.to_bits(),
                        "round {round}, lane {lane}, wavelength {i}"
                    );
                }
            }
        }
    }

    /// Gathering scene spectra by id equals gathering their lane spectra
    /// (zero outside the lanes) and the lane-by-lane oracle, bit for bit: from the registers where every
    /// id is held, through the general gather where one is not (the
    /// Cornell box has fewer spectra than registers, so unknown ids stand
    /// in for unheld ones).
    #[test]
    fn gather_by_id_equals_the_general_gather() {
        let Ok(scene) = crate::scene::builtin::cornell_box(SpectralRange::VISIBLE) else {
            panic!("Cornell box");
        };
        let Ok(transport) =
            FourierTransport::<12>::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Series)
        else {
            panic!("transport");
        };
        let spectra = scene.spectra.len() as u32;
        let mut rng = Rng::new(5, 6);
        for round in 0..500 {
            let lanes = LaneMask((rng.next_u32() & 0xff) as u8);
            let ids: [SpectrumId; LANES] = core::array::from_fn(|_| {
                // Every fifth round has unknown ids too.
                let range = if round % 5 == 0 { spectra + 3 } else { spectra };
                rng.next_u32() % range
            });
            let by_id = transport.gather_ids(&scene, &(), &ids, lanes);
            let spectra: [LaneSpectrum; LANES] = core::array::from_fn(|lane| {
                if lanes.contains(lane) {
                    LaneSpectrum::scene(ids[lane])
                } else {
                    LaneSpectrum::ZERO
                }
            });
            let general = transport.gather(&scene, &(), &spectra);
            let oracle = gather_by_lane::<12>(&scene, &spectra);
            for ((a, b), row) in by_id.coeffs.iter().zip(&general.coeffs).zip(&oracle) {
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits)
                );
                assert_eq!(a.to_array().map(f32::to_bits), row.map(f32::to_bits));
            }
        }
    }

    /// The packet-wide finite check equals the per-lane one, for both
    /// buffers, with NaN and infinities in random places and huge finite
    /// coefficients (whose XYZ may overflow).
    #[test]
    fn finite_lanes_equal_the_per_lane_check() {
        let mut rng = Rng::new(13, 14);
        for buffer in [Buffer::Spectral, Buffer::Xyz] {
            let Ok(transport) =
                FourierTransport::<12>::new(SpectralRange::VISIBLE, buffer, XyzRoute::Series)
            else {
                panic!("transport");
            };
            for _ in 0..300 {
                let mut coeffs: [[f32; LANES]; 12] =
                    core::array::from_fn(|_| core::array::from_fn(|_| rng.next_f32() - 0.5));
                for _ in 0..rng.next_u32() % 4 {
                    let (j, lane) = (
                        (rng.next_u32() % 12) as usize,
                        (rng.next_u32() % 8) as usize,
                    );
                    coeffs[j][lane] = match rng.next_u32() % 4 {
                        0 => f32::NAN,
                        1 => f32::INFINITY,
                        2 => f32::NEG_INFINITY,
                        _ => 3e38,
                    };
                }
                let radiance = FourierSpectrum::<f32x8, 12>::from_coeffs(coeffs.map(f32x8::new));
                let samples = transport.samples(&radiance, &());
                let per_lane = (0..LANES)
                    .filter(|&lane| FourierTransport::<12>::sample_is_finite(&samples[lane]))
                    .fold(LaneMask::NONE, LaneMask::with);
                assert_eq!(transport.finite_lanes(&radiance, &samples), per_lane);
            }
        }
    }

    /// The spectral-buffer samples hold each lane's coefficients, for `N`
    /// below, at and above one chunk of 8.
    fn check_samples<const N: usize>() {
        let Ok(transport) =
            FourierTransport::<N>::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Series)
        else {
            panic!("transport");
        };
        let radiance = FourierSpectrum::<f32x8, N>::from_coeffs(core::array::from_fn(|j| {
            f32x8::new(core::array::from_fn(|lane| (100 * j + lane) as f32 - 0.5))
        }));
        let samples = transport.samples(&radiance, &());
        for (lane, sample) in samples.iter().enumerate() {
            for (j, &c) in sample.coeffs.iter().enumerate() {
                assert_eq!(
                    c,
                    radiance.coeffs[j].to_array()[lane],
                    "N = {N}, lane {lane}, coefficient {j}"
                );
            }
            assert!(FourierTransport::<N>::sample_is_finite(sample));
        }
        let mut broken = radiance;
        broken.coeffs[N - 1] = f32x8::new([0.0, f32::NAN, 0.0, f32::INFINITY, 0.0, 0.0, 0.0, 0.0]);
        let samples = transport.samples(&broken, &());
        let finite = samples.map(|s| FourierTransport::<N>::sample_is_finite(&s));
        assert_eq!(finite, [true, false, true, false, true, true, true, true]);
    }

    /// The check finds a NaN or an infinity at every position of every
    /// length.
    #[test]
    fn all_finite_finds_every_non_finite_value() {
        for length in 0..=20 {
            let values: Vec<f32> = (0..length).map(|i| i as f32 - 3.5).collect();
            assert!(all_finite(&values), "{length}");
            for position in 0..length {
                for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                    let mut broken = values.clone();
                    broken[position] = bad;
                    assert!(!all_finite(&broken), "{length} {position} {bad}");
                }
            }
        }
    }

    #[test]
    fn fourier_samples_match_the_lanes() {
        check_samples::<4>();
        check_samples::<8>();
        check_samples::<12>();
        check_samples::<16>();
        check_samples::<32>();
    }
}
