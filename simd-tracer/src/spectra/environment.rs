//! Equirectangular HDR environment maps as spectra: each texel's linear
//! sRGB radiance becomes an **RGB illuminant**, the upsampled colour times
//! D65, as in Mitsuba's and pbrt-v4's spectral modes:
//!
//! `L(λ) = k · 2m · S(poly_rgb/2m(λ)) · D65(λ) / Y_D65`, `m = max(r, g, b)`,
//!
//! with `S(poly)` the Jakob–Hanika sigmoid of the reflectance `rgb / 2m`
//! ([`spectral_core::upsample`]) and `k` the map's scale. White `(1, 1, 1)`
//! is D65 at luminance 1.
//!
//! Each texel is projected once, at load, to [`ENVIRONMENT_COEFFS`] Fourier
//! coefficients for the Fourier transport, by 2-point Gauss–Legendre on
//! the 5 nm panels of the D65 table (D65 is linear within each panel, the
//! sigmoid smooth; the tests compare with the fine projection of
//! [`spectral_core::upsample::RgbIlluminant`]); sampled transports evaluate
//! `2m · S(·) · D65` exactly at their wavelengths. Memory per texel:
//! `4 · ENVIRONMENT_COEFFS + 16` bytes.
//!
//! **Spectral maps** ([`EnvironmentMap::spectral`]): texels given as `n`
//! Fourier coefficients of their radiance (a spectral OpenEXR projected
//! once at load, or a coefficient file), times the scale `k`, with each
//! texel's luminance for the sampling weights. Both transports read the
//! coefficients: the Fourier transport the bilinear coefficients, the
//! sampled ones their series at each wavelength (negative lobes clamped
//! to 0). Why not keep the image's bins for the sampled transports: the
//! coefficients take `4n` bytes per texel against `4B` for `B` bins (16
//! against 31 for a 400–700 nm image at 10 nm), one copy serves every
//! transport, and the transports then render the same spectrum, so their
//! comparison measures the transport and not the representation; the
//! price is the truncation error, which `fspec texture` reports per texel.
//! Coefficients interpolate linearly, so the bilinear lookup is the
//! projection of the bilinearly interpolated spectrum.
//!
//! **Mapping** (Mitsuba's `envmap`, local frame `+y` up): the direction
//! `d = (sin φ sin θ, cos θ, −cos φ sin θ)` with `φ = 2π u`, `θ = π v`;
//! inversely `u = atan2(d.x, −d.z) / 2π` (wrapped into [0, 1)),
//! `v = acos(d.y) / π`. The map's `to_world` is a rotation. Texel
//! positions and interpolation follow Mitsuba 3.9's `envmap`: columns are
//! texel-centred, `u_i = (i + ½)/W`, wrapping; rows are corner-aligned,
//! `v_j = j/(H − 1)` (row 0 straight up, the last row straight down).
//! Between the four nearest texels the *shape* `S` (the sigmoid spectrum)
//! and the *intensity* `k · 2m` are interpolated bilinearly each and then
//! multiplied, as Mitsuba's spectral variants do (the upsampling is
//! nonlinear, so this is not the interpolation of the texels' spectra);
//! the stored coefficients are those of `S · D65 / Y_D65` alone.
//!
//! **Sampling weights** ([`EnvironmentMap::sampling_weights`]): the exact
//! mean of the bilinear interpolant of the luminance over each texel,
//! `(1 6 1)/8 ⊗ (1 6 1)/8` (so no texel where the interpolated radiance is
//! positive has weight 0), times `sin θ` at the row centre (the solid
//! angle of the row). The direction pdf is `pdf(u, v) / (2π² sin θ)`.

use crate::spectra::{MAX_COEFFS, SceneSpectrum, SpectrumSource};
use glam::{Mat3, Vec3};
use rayon::prelude::*;
use spectral_core::cmf;
use spectral_core::upsample::{SigmoidPolynomial, srgb_reflectance};
use spectral_core::{FourierSpectrum, SpectralError, SpectralRange, Spectrum};
use std::f32::consts::{PI, TAU};
use wide::f32x8;

/// Fourier coefficients stored per texel.
pub const ENVIRONMENT_COEFFS: usize = 16;

/// How far `Mᵀ M` may be from the identity for `M` to count as a rotation
/// (rotations composed in `f32`, or given as a rounded matrix).
pub const ROTATION_TOLERANCE: f32 = 1e-4;

/// Largest map accepted, texels (2²⁶, as textures).
pub const MAX_ENVIRONMENT_TEXELS: usize = 1 << 26;

/// Width of the panels of the per-texel projection, nm: the D65 table's
/// spacing (CIE 15:2004 tabulates D65 every 5 nm).
const PANEL_NM: f64 = 5.0;

/// 2-point Gauss–Legendre nodes on [−1, 1] (weights 1): `±1/√3`.
const GAUSS_LEGENDRE_2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];

/// Linear-sRGB luminance weights (the `Y` row of the sRGB → XYZ matrix,
/// IEC 61966-2-1).
const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Nodes of the per-texel projection taken at once: the `f32` lanes of
/// one AVX2 register.
const NODE_LANES: usize = 8;

/// A sigmoid argument beyond this magnitude is saturated: `S = 0` or `1`
/// (`1 − S < 1/(8x²)`, far below the `f32` resolution of 1), and `x²`
/// stays finite in `f32` (`(2⁶⁰)² = 2¹²⁰ < f32::MAX`).
const SIGMOID_SATURATED: f32 = (1u64 << 60) as f32;

/// Rows of the per-texel projection: `(λ, Σ-weight · D(λ) · cos(jφ) / W)`,
/// in chunks of [`NODE_LANES`] nodes (the last padded with nodes of
/// weight 0). Each texel evaluates its sigmoid polynomial at every node,
/// eight nodes at a time, in `f32` ([`Projection::coefficients`]; its
/// scalar oracle, the same sum in `f64`, is tested within the rounding
/// bound of `f32`).
///
/// Why `f32`: the shape the sampled transports evaluate is the texel's
/// sigmoid polynomial stored in `f32`, so the Fourier transport projects
/// that same polynomial; the rounding of the `f32` sums (about 10⁻⁶ of
/// the coefficients' size) is far below the 2-point rule's error against
/// the fine projection (10⁻³, tested). Eight lanes instead of the four of
/// `f64` halve the load's largest cost on environment-lit scenes
/// (`docs/performance.md`).
struct Projection {
    /// `t = (λ − 360)/470`, clamped to `[0, 1]`, of each node: the
    /// sigmoid polynomial's variable.
    t: Vec<f32x8>,
    /// `weights[chunk][j]`: coefficient `j`'s weights of the chunk's nodes.
    weights: Vec<[f32x8; ENVIRONMENT_COEFFS]>,
}

impl Projection {
    fn new(range: &SpectralRange, illuminant: &SceneSpectrum) -> Self {
        let panels = (range.width_nm() / PANEL_NM).ceil().max(1.0) as usize;
        let panel_nm = range.width_nm() / panels as f64;
        let mut nodes: Vec<(f64, [f64; ENVIRONMENT_COEFFS])> = Vec::with_capacity(2 * panels);
        for panel in 0..panels {
            let centre_nm = range.min_nm() + (panel as f64 + 0.5) * panel_nm;
            for node in GAUSS_LEGENDRE_2 {
                let l = centre_nm + 0.5 * panel_nm * node;
                let base =
                    0.5 * panel_nm * f64::from(illuminant.value(l as f32)) / range.width_nm();
                let phase = range.phase(l);
                nodes.push((l, core::array::from_fn(|j| base * (j as f64 * phase).cos())));
            }
        }
        let sigmoid_t =
            |l: f64| ((l - cmf::FIRST_NM) / (cmf::LAST_NM - cmf::FIRST_NM)).clamp(0.0, 1.0);
        let chunks = nodes.chunks(NODE_LANES);
        let t = chunks
            .clone()
            .map(|chunk| {
                f32x8::new(core::array::from_fn(|i| {
                    chunk.get(i).map_or(0.0, |n| sigmoid_t(n.0) as f32)
                }))
            })
            .collect();
        let weights = chunks
            .map(|chunk| {
                core::array::from_fn(|j| {
                    f32x8::new(core::array::from_fn(|i| {
                        chunk.get(i).map_or(0.0, |n| n.1[j] as f32)
                    }))
                })
            })
            .collect();
        Self { t, weights }
    }

    /// The projection of `S(c0 t² + c1 t + c2)` for the `f32` sigmoid
    /// coefficients `shape` (`c0`, `c1` finite; `c2` may be infinite, the
    /// grey extremes): the sigmoid at eight nodes at a time,
    /// `S(x) = ½ + ½ x/√(1 + x²)`, saturated beyond [`SIGMOID_SATURATED`].
    fn coefficients(&self, shape: [f32; 3]) -> [f32; ENVIRONMENT_COEFFS] {
        let [c0, c1, c2] = shape.map(f32x8::splat);
        let (half, one) = (f32x8::splat(0.5), f32x8::ONE);
        let saturated = f32x8::splat(SIGMOID_SATURATED);
        let mut sums = [f32x8::ZERO; ENVIRONMENT_COEFFS];
        for (&t, row) in self.t.iter().zip(&self.weights) {
            let x = c0.mul_add(t, c1).mul_add(t, c2);
            let smooth = half.mul_add(x / x.mul_add(x, one).sqrt(), half);
            let step = x.simd_gt(f32x8::ZERO).select(one, f32x8::ZERO);
            let s = x.abs().simd_gt(saturated).select(step, smooth);
            for (sum, &w) in sums.iter_mut().zip(row) {
                *sum = s.mul_add(w, *sum);
            }
        }
        sums.map(f32x8::reduce_add)
    }
}

/// An environment map (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    texels: Texels,
    /// Luminance `k · Y` per texel (the sampling weights' source).
    luminance: Vec<f32>,
    to_world: Mat3,
    to_local: Mat3,
}

/// What each texel holds.
#[derive(Debug, Clone, PartialEq)]
enum Texels {
    /// RGB illuminants (module docs).
    Rgb {
        /// Sigmoid coefficients of `rgb / 2m` per texel.
        sigmoid: Vec<[f32; 3]>,
        /// `k · 2m` per texel.
        intensity: Vec<f32>,
        /// [`ENVIRONMENT_COEFFS`] coefficients of each texel's shape
        /// `S · D65 / Y_D65`.
        fourier: Vec<f32>,
        /// D65 at luminance 1 (boxed: a dense table, large beside the
        /// other variant).
        illuminant: Box<SceneSpectrum>,
    },
    /// Spectral radiance (module docs, "Spectral maps"): `n` coefficients
    /// per texel, the scale `k` included.
    Spectral {
        /// Coefficients per texel.
        n: usize,
        /// Texel-major coefficients.
        fourier: Vec<f32>,
        /// The range the coefficients are over.
        range: SpectralRange,
    },
}

/// What goes into a spectral [`EnvironmentMap`] (module docs, "Spectral
/// maps").
#[derive(Debug, Clone, Copy)]
pub struct SpectralEnvironmentImage<'a> {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Coefficients per texel, 1 … [`MAX_COEFFS`].
    pub n: usize,
    /// Texel-major Fourier coefficients of each texel's radiance over the
    /// map's range, row-major from the top-left, finite.
    pub coeffs: &'a [f32],
    /// Each texel's luminance `Y` (`∫ L ȳ dλ / ∫ ȳ dλ`), finite and ≥ 0.
    pub luminance: &'a [f32],
    /// Multiplier `k`.
    pub scale: f32,
    /// Local to world: a rotation.
    pub to_world: Mat3,
}

/// What goes into an [`EnvironmentMap`].
#[derive(Debug, Clone, Copy)]
pub struct EnvironmentImage<'a> {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Linear sRGB radiance, row-major from the top-left, finite and ≥ 0.
    pub rgb: &'a [[f32; 3]],
    /// Multiplier `k`.
    pub scale: f32,
    /// Local to world: a rotation.
    pub to_world: Mat3,
}

/// The checks every map shares: a size of 1 to
/// [`MAX_ENVIRONMENT_TEXELS`] texels, a finite scale `>= 0`, a rotation;
/// the texel count.
fn check_map(width: u32, height: u32, scale: f32, to_world: Mat3) -> Result<usize, SpectralError> {
    let texels = width as usize * height as usize;
    if width == 0 || height == 0 || texels > MAX_ENVIRONMENT_TEXELS {
        return Err(SpectralError::InvalidParameter(
            "environment map size (1 to 2^26 texels)",
        ));
    }
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(SpectralError::InvalidParameter(
            "environment scale (finite, >= 0)",
        ));
    }
    if !EnvironmentMap::is_rotation(to_world) {
        return Err(SpectralError::InvalidParameter(
            "environment transform (a rotation)",
        ));
    }
    Ok(texels)
}

impl EnvironmentMap {
    /// The map of `image` over `range`.
    pub fn new(image: &EnvironmentImage<'_>, range: SpectralRange) -> Result<Self, SpectralError> {
        let EnvironmentImage {
            width,
            height,
            rgb,
            scale,
            to_world,
        } = *image;
        let texels = check_map(width, height, scale, to_world)?;
        if rgb.len() != texels {
            return Err(SpectralError::LengthMismatch {
                wavelengths: texels,
                values: rgb.len(),
            });
        }
        if let Some(index) = rgb
            .iter()
            .flatten()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            return Err(SpectralError::NonFiniteValue { index });
        }
        let illuminant = SceneSpectrum::new(SpectrumSource::RgbIlluminant([1.0; 3]), range)?;
        let projection = Projection::new(&range, &illuminant);
        // Each texel's records are written in place, in parallel: no
        // per-texel tuples collected and copied again.
        let mut sigmoid = vec![[0.0f32; 3]; texels];
        let mut intensity = vec![0.0f32; texels];
        let mut fourier = vec![0.0f32; texels * ENVIRONMENT_COEFFS];
        fourier
            .par_chunks_mut(ENVIRONMENT_COEFFS)
            .zip(sigmoid.par_iter_mut())
            .zip(intensity.par_iter_mut())
            .zip(rgb.par_iter())
            .try_for_each(|(((coefficients, shape_out), k), texel)| {
                let largest = texel[0].max(texel[1]).max(texel[2]);
                if largest == 0.0 || scale == 0.0 {
                    // Black: Mitsuba's zero reflectance (S ≡ 0) at zero intensity.
                    *shape_out = SigmoidPolynomial::grey(0.0).coeffs.map(|c| c as f32);
                    return Ok(());
                }
                let twice_largest = 2.0 * f64::from(largest);
                let shape = srgb_reflectance(texel.map(|v| f64::from(v) / twice_largest))?
                    .coeffs
                    .map(|c| c as f32);
                // The table's polynomials are finite; only a grey's `c2` is
                // infinite (0 or 1 exactly).
                if !(shape[0].is_finite() && shape[1].is_finite()) {
                    return Err(SpectralError::InvalidParameter(
                        "environment texel colour (no finite sigmoid polynomial)",
                    ));
                }
                *shape_out = shape;
                *k = (twice_largest * f64::from(scale)) as f32;
                coefficients.copy_from_slice(&projection.coefficients(shape));
                Ok(())
            })?;
        if let Some(index) = fourier.iter().position(|c| !c.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self {
            width,
            height,
            texels: Texels::Rgb {
                sigmoid,
                intensity,
                fourier,
                illuminant: Box::new(illuminant),
            },
            luminance: rgb
                .iter()
                .map(|c| scale * (LUMINANCE[0] * c[0] + LUMINANCE[1] * c[1] + LUMINANCE[2] * c[2]))
                .collect(),
            to_world,
            to_local: to_world.transpose(),
        })
    }

    /// The spectral map of `image` over `range` (module docs, "Spectral
    /// maps"): the coefficients and luminances times the scale.
    pub fn spectral(
        image: &SpectralEnvironmentImage<'_>,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        let SpectralEnvironmentImage {
            width,
            height,
            n,
            coeffs,
            luminance,
            scale,
            to_world,
        } = *image;
        let texels = check_map(width, height, scale, to_world)?;
        if n == 0 || n > MAX_COEFFS {
            return Err(SpectralError::InvalidParameter(
                "environment coefficients (1 to 32)",
            ));
        }
        if coeffs.len() != texels * n || luminance.len() != texels {
            return Err(SpectralError::LengthMismatch {
                wavelengths: texels * n,
                values: coeffs.len(),
            });
        }
        let fourier: Vec<f32> = coeffs.iter().map(|c| c * scale).collect();
        if let Some(index) = fourier.iter().position(|c| !c.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        let luminance: Vec<f32> = luminance.iter().map(|y| y * scale).collect();
        if let Some(index) = luminance.iter().position(|y| !(y.is_finite() && *y >= 0.0)) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self {
            width,
            height,
            texels: Texels::Spectral { n, fourier, range },
            luminance,
            to_world,
            to_local: to_world.transpose(),
        })
    }

    /// Whether `m` is a rotation (or a rotation with a mirror) a map may
    /// take: finite, `Mᵀ M` within [`ROTATION_TOLERANCE`] of the identity.
    pub fn is_rotation(m: Mat3) -> bool {
        m.is_finite()
            && (m.transpose() * m - Mat3::IDENTITY)
                .to_cols_array()
                .iter()
                .all(|e| e.abs() < ROTATION_TOLERANCE)
    }

    /// Width and height, texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        let texels = match &self.texels {
            Texels::Rgb {
                sigmoid,
                intensity,
                fourier,
                illuminant,
            } => {
                sigmoid.capacity() * 12
                    + intensity.capacity() * 4
                    + fourier.capacity() * 4
                    + illuminant.memory_bytes()
            }
            Texels::Spectral { fourier, .. } => fourier.capacity() * 4,
        };
        texels + self.luminance.capacity() * 4
    }

    /// Coefficients per texel: [`ENVIRONMENT_COEFFS`] for RGB maps, the
    /// image's `n` for spectral ones.
    pub fn coefficients_per_texel(&self) -> usize {
        match &self.texels {
            Texels::Rgb { .. } => ENVIRONMENT_COEFFS,
            Texels::Spectral { n, .. } => *n,
        }
    }

    /// The map coordinates `(u, v)` of the world direction `direction`
    /// (any length; `(0, 0)` for a zero or non-finite one) and `sin θ`,
    /// taken from the direction's horizontal length (near the poles
    /// `sin(acos(y))` loses every digit).
    pub fn uv_and_sin_theta(&self, direction: Vec3) -> ([f32; 2], f32) {
        let Some(d) = (self.to_local * direction).try_normalize() else {
            return ([0.0, 0.0], 0.0);
        };
        let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
        let u = (d.x.atan2(-d.z) / TAU).rem_euclid(1.0);
        // `rem_euclid` of a tiny negative number rounds to 1.
        let u = if u >= 1.0 { 0.0 } else { u };
        // `v` stays below 1 (the largest `f32` below it), inside the last
        // row, as `u` stays below 1.
        let v = (d.y.clamp(-1.0, 1.0).acos() / PI).min(1.0 - f32::EPSILON / 2.0);
        ([u, v], sin_theta)
    }

    /// The unit world direction of map coordinates `(u, v)` and `sin θ`.
    pub fn direction_of(&self, [u, v]: [f32; 2]) -> (Vec3, f32) {
        let (phi, theta) = (TAU * u, PI * v);
        let (sin_theta, cos_theta) = theta.sin_cos();
        let (sin_phi, cos_phi) = phi.sin_cos();
        let local = Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta);
        (self.to_world * local, sin_theta)
    }

    /// The four texels and weights around `(u, v)` (wrapping in `u`,
    /// clamped in `v`).
    fn footprint(&self, [u, v]: [f32; 2]) -> [(usize, f32); 4] {
        let (w, h) = (self.width as i64, self.height as i64);
        let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
        let x = finite(u) * w as f32 - 0.5;
        let y = finite(v).clamp(0.0, 1.0) * (h - 1) as f32;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let column = |c: f32| (c as i64).rem_euclid(w) as usize;
        let row = |r: f32| (r as i64).clamp(0, h - 1) as usize;
        let (c0, c1, r0, r1) = (column(x0), column(x0 + 1.0), row(y0), row(y0 + 1.0));
        let w = w as usize;
        [
            (r0 * w + c0, (1.0 - fx) * (1.0 - fy)),
            (r0 * w + c1, fx * (1.0 - fy)),
            (r1 * w + c0, (1.0 - fx) * fy),
            (r1 * w + c1, fx * fy),
        ]
    }

    /// The bilinear intensity `Σ w k` of an RGB map's `footprint`.
    fn intensity_at(intensity: &[f32], footprint: &[(usize, f32); 4]) -> f32 {
        footprint
            .iter()
            .map(|&(texel, weight)| weight * intensity.get(texel).copied().unwrap_or(0.0))
            .sum()
    }

    /// The bilinear combination of `n` coefficients per texel over
    /// `footprint` (zero past `n`).
    fn bilinear<const M: usize>(
        fourier: &[f32],
        n: usize,
        footprint: &[(usize, f32); 4],
    ) -> [f32; M] {
        let mut out = [0.0f32; M];
        for &(texel, weight) in footprint {
            let start = texel * n;
            if let Some(c) = fourier.get(start..start + n) {
                for (o, &value) in out.iter_mut().zip(c) {
                    *o += weight * value;
                }
            }
        }
        out
    }

    /// Fourier coefficients at `(u, v)` (module docs: for RGB maps the
    /// bilinear shape's coefficients times the bilinear intensity, for
    /// spectral maps the bilinear coefficients; zero past those stored).
    pub fn fourier_at<const M: usize>(&self, uv: [f32; 2]) -> [f32; M] {
        let footprint = self.footprint(uv);
        match &self.texels {
            Texels::Rgb {
                intensity, fourier, ..
            } => {
                let k = Self::intensity_at(intensity, &footprint);
                Self::bilinear::<M>(fourier, ENVIRONMENT_COEFFS, &footprint).map(|c| c * k)
            }
            Texels::Spectral { n, fourier, .. } => Self::bilinear::<M>(fourier, *n, &footprint),
        }
    }

    /// The radiance at `(u, v)` and `lambda_nm` (module docs: for RGB maps
    /// the bilinear shape at `λ` times the bilinear intensity times D65,
    /// for spectral maps the series of the bilinear coefficients at `λ`,
    /// negative values clamped to 0).
    pub fn value_at(&self, uv: [f32; 2], lambda_nm: f32) -> f32 {
        let lambda = f64::from(lambda_nm);
        let footprint = self.footprint(uv);
        match &self.texels {
            Texels::Rgb {
                sigmoid,
                intensity,
                illuminant,
                ..
            } => {
                let shapes: f32 = footprint
                    .iter()
                    .map(|&(texel, weight)| {
                        let Some(c) = sigmoid.get(texel) else {
                            return 0.0;
                        };
                        let shape = SigmoidPolynomial {
                            coeffs: c.map(f64::from),
                        };
                        weight * shape.value(lambda) as f32
                    })
                    .sum();
                shapes * Self::intensity_at(intensity, &footprint) * illuminant.value(lambda_nm)
            }
            Texels::Spectral { n, fourier, range } => {
                let c = Self::bilinear::<MAX_COEFFS>(fourier, *n, &footprint);
                let series: FourierSpectrum<f64, MAX_COEFFS> =
                    FourierSpectrum::from_coeffs(c.map(f64::from));
                (series.eval_cos(range.cos_phase(lambda)) as f32).max(0.0)
            }
        }
    }

    /// Per-texel weights for importance sampling (module docs), row-major.
    pub fn sampling_weights(&self) -> Vec<f32> {
        let (w, h) = (self.width as usize, self.height as usize);
        let at = |c: usize, r: usize| self.luminance.get(r * w + c).copied().unwrap_or(0.0);
        // (1 6 1)/8 across each row (wrapping), then down the columns (clamped).
        let mut across = vec![0.0f32; w * h];
        for r in 0..h {
            for c in 0..w {
                let (left, right) = ((c + w - 1) % w, (c + 1) % w);
                across[r * w + c] = (at(left, r) + 6.0 * at(c, r) + at(right, r)) / 8.0;
            }
        }
        let mut weights = vec![0.0f32; w * h];
        for r in 0..h {
            let (up, down) = (r.saturating_sub(1), (r + 1).min(h - 1));
            let sin_theta = (PI * (r as f32 + 0.5) / h as f32).sin();
            for c in 0..w {
                let filtered =
                    (across[up * w + c] + 6.0 * across[r * w + c] + across[down * w + c]) / 8.0;
                weights[r * w + c] = filtered * sin_theta;
            }
        }
        weights
    }

    /// Texel `texel`'s mean radiance over the range, `c₀` (times `k` for
    /// RGB maps).
    fn mean_of_texel(&self, texel: usize) -> f32 {
        match &self.texels {
            Texels::Rgb {
                intensity, fourier, ..
            } => {
                let c0 = fourier.get(texel * ENVIRONMENT_COEFFS).copied();
                c0.unwrap_or(0.0) * intensity.get(texel).copied().unwrap_or(0.0)
            }
            Texels::Spectral { n, fourier, .. } => fourier.get(texel * n).copied().unwrap_or(0.0),
        }
    }

    /// The mean spectral radiance over the sphere and the spectral range
    /// (`∫ c₀ dω / 4π`, `c₀` each texel's mean over the range), for the
    /// light's share of next-event estimation.
    pub fn mean_radiance(&self) -> f64 {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut sum = 0.0f64;
        for r in 0..h {
            let sin_theta = f64::from((PI * (r as f32 + 0.5) / h as f32).sin());
            let row: f64 = (0..w)
                .map(|c| f64::from(self.mean_of_texel(r * w + c)))
                .sum();
            sum += row * sin_theta;
        }
        // Σ c₀ sinθ Δθ Δφ / 4π with Δθ Δφ = 2π² / (W H).
        let pi = std::f64::consts::PI;
        sum * 2.0 * pi * pi / (w as f64 * h as f64) / (4.0 * pi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectral_core::upsample::RgbIlluminant;

    fn map(width: u32, height: u32, rgb: &[[f32; 3]]) -> EnvironmentMap {
        let image = EnvironmentImage {
            width,
            height,
            rgb,
            scale: 1.0,
            to_world: Mat3::IDENTITY,
        };
        match EnvironmentMap::new(&image, SpectralRange::VISIBLE) {
            Ok(map) => map,
            Err(e) => panic!("{e}"),
        }
    }

    /// The eight-node `f32` projection against its scalar oracle, the same
    /// sum in `f64` (the polynomial at the node's `t`, the sigmoid, the
    /// node's weights), within the rounding bound of `f32`: per node
    /// `|ΔS| ≤ 4u + 2u·(|c0|t² + |c1|t + |c2|)` (two roundings of the
    /// polynomial, whose slope through `S` is at most ½; four in the
    /// sigmoid), and `γ_k Σ |S w|` for the `k` rounded adds of each sum
    /// (`u = 2⁻²⁴`, `γ_k = ku/(1 − ku)`, Higham's summation bound). For
    /// ordinary, steep, saturated (`S` is 0 or 1: `x²` would overflow
    /// `f32`) and the grey extremes' infinite polynomials. Negative
    /// control: the oracle of a neighbouring polynomial, `c2` moved by
    /// 10⁻³ of the coefficients' size, is outside the bound.
    #[test]
    fn the_projection_is_its_scalar_oracle() -> Result<(), SpectralError> {
        let range = SpectralRange::VISIBLE;
        let illuminant = SceneSpectrum::new(SpectrumSource::RgbIlluminant([1.0; 3]), range)?;
        let projection = Projection::new(&range, &illuminant);
        let u = f64::from(f32::EPSILON) / 2.0;
        let gamma = |k: f64| k * u / (1.0 - k * u);
        // One rounding per chunk in each lane's sum, three in the lanes' sum.
        let adds = projection.t.len() as f64 + 3.0;
        let shapes: [[f32; 3]; 8] = [
            [0.0, 0.0, 0.3],
            [-12.5, 9.0, -1.0],
            [310.0, -280.0, 55.0],
            [3.0e4, -3.1e4, 7.5e3],
            [1e30, -1e30, 0.0],
            [0.0, 0.0, 1e30],
            [0.0, 0.0, f32::INFINITY],
            [0.0, 0.0, f32::NEG_INFINITY],
        ];
        let oracle = |shape: [f32; 3]| {
            let [c0, c1, c2] = shape.map(f64::from);
            let mut sums = [0.0f64; ENVIRONMENT_COEFFS];
            let mut bounds = [0.0f64; ENVIRONMENT_COEFFS];
            for (t, row) in projection.t.iter().zip(&projection.weights) {
                for (lane, &t) in t.to_array().iter().enumerate() {
                    let t = f64::from(t);
                    let x = (c0 * t + c1) * t + c2;
                    let s = if x.abs() > 1e100 {
                        if x > 0.0 { 1.0 } else { 0.0 }
                    } else {
                        0.5 + 0.5 * x / (1.0 + x * x).sqrt()
                    };
                    let size = c0.abs() * t * t + c1.abs() * t + c2.abs();
                    let node_error = if size.is_finite() {
                        4.0 * u + 2.0 * u * size
                    } else {
                        0.0 // S is the exact step at an infinite argument
                    };
                    for j in 0..ENVIRONMENT_COEFFS {
                        let w = f64::from(row[j].to_array()[lane]);
                        sums[j] += s * w;
                        bounds[j] += node_error * w.abs() + gamma(adds) * (s * w).abs();
                    }
                }
            }
            (sums, bounds)
        };
        for shape in shapes {
            let (want, bound) = oracle(shape);
            let got = projection.coefficients(shape);
            for j in 0..ENVIRONMENT_COEFFS {
                let error = (f64::from(got[j]) - want[j]).abs();
                assert!(
                    error <= bound[j],
                    "{shape:?} coefficient {j}: {} against {} (bound {})",
                    got[j],
                    want[j],
                    bound[j]
                );
            }
            // Negative control: a neighbouring polynomial's sums lie outside
            // (where the sigmoid is not saturated throughout).
            let [c0, c1, c2] = shape;
            let size = 1.0 + c0.abs() + c1.abs() + c2.abs();
            if size < 1e6 {
                let (other, _) = oracle([c0, c1, c2 + 1e-3 * size]);
                assert!(
                    (0..ENVIRONMENT_COEFFS)
                        .any(|j| (f64::from(got[j]) - other[j]).abs() > bound[j]),
                    "{shape:?}: the bound does not tell c2 from its neighbour"
                );
            }
        }
        Ok(())
    }

    #[test]
    fn texels_are_rgb_illuminants() {
        let colours = [
            [0.9, 0.2, 0.05],
            [0.01, 0.3, 2.5],
            [1.0, 1.0, 1.0],
            [0.0; 3],
        ];
        let env = map(4, 1, &colours);
        let range = SpectralRange::VISIBLE;
        for (i, rgb) in colours.iter().enumerate() {
            let uv = [(i as f32 + 0.5) / 4.0, 0.5];
            let exact = match RgbIlluminant::new(rgb.map(f64::from)) {
                Ok(s) => s,
                Err(e) => panic!("{e}"),
            };
            let c: [f32; ENVIRONMENT_COEFFS] = env.fourier_at(uv);
            let reference = exact.project::<ENVIRONMENT_COEFFS>(&range);
            let size = reference.coeffs[0].abs().max(1e-6);
            for (j, (&got, &want)) in c.iter().zip(&reference.coeffs).enumerate() {
                let error = (f64::from(got) - want).abs();
                assert!(error < 2e-3 * size, "{rgb:?} c{j}: {got} vs {want}");
            }
            for l in [380.0f32, 455.0, 532.5, 610.0, 700.0, 825.0] {
                let (got, want) = (env.value_at(uv, l), exact.value(f64::from(l)) as f32);
                assert!(
                    (got - want).abs() <= 2e-3 * want.max(1e-3),
                    "{rgb:?} {l}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn directions_and_coordinates_invert_each_other() {
        let rotation = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        let image = EnvironmentImage {
            width: 8,
            height: 4,
            rgb: &[[1.0; 3]; 32],
            scale: 1.0,
            to_world: rotation,
        };
        let Ok(env) = EnvironmentMap::new(&image, SpectralRange::VISIBLE) else {
            panic!("map");
        };
        for i in 0..50 {
            let uv = [
                (i as f32 * 0.137).fract(),
                0.02 + 0.96 * (i as f32 * 0.291).fract(),
            ];
            let (d, sin_theta) = env.direction_of(uv);
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!((sin_theta - (PI * uv[1]).sin()).abs() < 1e-6);
            let back = env.uv_and_sin_theta(d).0;
            let du = (back[0] - uv[0]).abs();
            assert!(
                du.min(1.0 - du) < 1e-4 && (back[1] - uv[1]).abs() < 1e-4,
                "{uv:?} {back:?}"
            );
        }
        // Mitsuba's frame: v = 0 is up (+y), u = 0 looks along −z, u = ¼ along +x.
        let flat = map(8, 4, &[[1.0; 3]; 32]);
        assert!((flat.direction_of([0.3, 0.0]).0 - Vec3::Y).length() < 1e-6);
        assert!((flat.direction_of([0.0, 0.5]).0 - -Vec3::Z).length() < 1e-6);
        assert!((flat.direction_of([0.25, 0.5]).0 - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn sampling_weights_cover_the_bilinear_support() {
        // One bright texel: its neighbours, where the interpolated radiance
        // is positive, have positive weight; the rest zero.
        let mut rgb = vec![[0.0f32; 3]; 8 * 4];
        rgb[8 + 3] = [1.0; 3];
        let env = map(8, 4, &rgb);
        let weights = env.sampling_weights();
        for r in 0..4usize {
            for c in 0..8usize {
                let near = r.abs_diff(1) <= 1 && c.abs_diff(3) <= 1;
                assert_eq!(weights[r * 8 + c] > 0.0, near, "texel {c}, {r}");
                let lit =
                    env.value_at([(c as f32 + 0.5) / 8.0, (r as f32 + 0.5) / 4.0], 550.0) > 0.0;
                assert!(!lit || near);
            }
        }
        // A uniform white map's mean radiance is the mean of D65 at Y = 1.
        let uniform = map(16, 8, &[[1.0; 3]; 128]);
        let Texels::Rgb { illuminant, .. } = &uniform.texels else {
            panic!("not an RGB map");
        };
        let d65 = illuminant.mean();
        assert!(
            (uniform.mean_radiance() / d65 - 1.0).abs() < 0.01,
            "{} vs {d65}",
            uniform.mean_radiance()
        );
    }

    #[test]
    fn spectral_maps_hold_their_coefficients_times_the_scale() {
        let range = SpectralRange::VISIBLE;
        const COEFFS: [f32; 6] = [0.5, 0.1, -0.05, 0.2, 0.0, 0.01];
        let image = |n: usize, coeffs: &'static [f32], luminance: &'static [f32], scale: f32| {
            SpectralEnvironmentImage {
                width: 2,
                height: 1,
                n,
                coeffs,
                luminance,
                scale,
                to_world: Mat3::IDENTITY,
            }
        };
        let Ok(map) = EnvironmentMap::spectral(&image(3, &COEFFS, &[1.0, 0.5], 2.0), range) else {
            panic!("a valid spectral map was refused");
        };
        assert_eq!(map.coefficients_per_texel(), 3);
        // Texel 0's centre: u = 1/4; every row is the same texel (H = 1).
        let c: [f32; 4] = map.fourier_at([0.25, 0.5]);
        assert_eq!(c, [1.0, 0.2, -0.1, 0.0]);
        let series = FourierSpectrum::<f64, 3>::from_coeffs([1.0, 0.2, -0.1]);
        let want = series.eval_cos(range.cos_phase(500.0)) as f32;
        assert!((map.value_at([0.25, 0.5], 500.0) - want).abs() < 1e-6);
        // Mean radiance over the sphere: the texels' mean c₀ when every row
        // is the same (the rows' sin θ weights integrate to 2 within the
        // midpoint rule's (π/H)²/24 relative error).
        let rows = 64;
        let tall_coeffs: Vec<f32> = (0..rows).flat_map(|_| COEFFS).collect();
        let tall_luminance = vec![1.0f32; 2 * rows];
        let tall = EnvironmentMap::spectral(
            &SpectralEnvironmentImage {
                height: rows as u32,
                coeffs: &tall_coeffs,
                luminance: &tall_luminance,
                ..image(3, &COEFFS, &[1.0, 0.5], 2.0)
            },
            range,
        );
        let mean = tall.map(|m| m.mean_radiance()).unwrap_or(f64::NAN);
        assert!((mean - 0.7).abs() < 1e-3, "{mean}");
        assert_eq!(map.memory_bytes(), 4 * 6 + 4 * 2);
        for bad in [
            image(0, &[], &[1.0, 1.0], 1.0),
            image(33, &[0.0; 66], &[1.0, 1.0], 1.0),
            image(3, &[0.0; 5], &[1.0, 1.0], 1.0),
            image(3, &COEFFS, &[1.0], 1.0),
            image(3, &[f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0], &[1.0, 1.0], 1.0),
            image(3, &COEFFS, &[-1.0, 1.0], 1.0),
            image(3, &COEFFS, &[1.0, 1.0], f32::INFINITY),
        ] {
            assert!(EnvironmentMap::spectral(&bad, range).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn bad_maps_are_refused() {
        let image = |rgb: &'static [[f32; 3]], to_world: Mat3, scale: f32| EnvironmentImage {
            width: 2,
            height: 1,
            rgb,
            scale,
            to_world,
        };
        let range = SpectralRange::VISIBLE;
        let ok: &'static [[f32; 3]] = &[[1.0; 3], [0.5; 3]];
        assert!(EnvironmentMap::new(&image(ok, Mat3::IDENTITY, 1.0), range).is_ok());
        assert!(EnvironmentMap::new(&image(&[[1.0; 3]], Mat3::IDENTITY, 1.0), range).is_err());
        assert!(
            EnvironmentMap::new(
                &image(&[[f32::NAN; 3], [0.0; 3]], Mat3::IDENTITY, 1.0),
                range
            )
            .is_err()
        );
        assert!(
            EnvironmentMap::new(&image(&[[-1.0; 3], [0.0; 3]], Mat3::IDENTITY, 1.0), range)
                .is_err()
        );
        assert!(
            EnvironmentMap::new(
                &image(ok, Mat3::from_diagonal(Vec3::splat(2.0)), 1.0),
                range
            )
            .is_err()
        );
        assert!(EnvironmentMap::new(&image(ok, Mat3::IDENTITY, f32::INFINITY), range).is_err());
    }
}
