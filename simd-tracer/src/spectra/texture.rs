//! Textures: spectral (RGB upsampled or Fourier coefficients per texel),
//! scalar, and the procedural checkerboard of two spectra; every lookup
//! goes through a UV transform, a wrap mode and a filter
//! ([`TextureSampling`]).
//!
//! * RGB textures are upsampled once at load (Jakob–Hanika sigmoid per
//!   texel, cached per distinct colour) and projected to
//!   [`TEXTURE_COEFFS`] Fourier coefficients; sampled transports evaluate
//!   the texel's sigmoid exactly at each wavelength.
//! * Fourier textures hold `N` coefficients per texel (EXR channels
//!   `F0 … F{N−1}`); sampled transports evaluate the series (negative lobes
//!   clamped to 0).
//! * Scalar textures (e.g. a film thickness in [0, 1] of its range).
//! * Vector textures: three values per texel as stored, interpolated
//!   channel by channel (the tangent-space normals of a normal map,
//!   `shading/material/normal_map.rs`); no spectral lookup reads them.
//! * Checkerboards hold two prepared [`SceneSpectrum`]s (below).
//!
//! # UV transform
//!
//! A lookup at `(u, v)` first maps the coordinates by the affine 2 × 3
//! matrix `M` of the texture's [`UvTransform`], `(u', v') = M · (u, v, 1)`
//! (the top two rows of the plain affine 3 × 3 matrix that Mitsuba 3's
//! `to_uv` holds). Built from a scale `S = diag(s_u, s_v)`, a rotation by
//! `θ` (counter-clockwise: from +u towards +v) and an offset `o` it is
//!
//! ```text
//! uv' = R(θ) · (S · uv) + o,   M = [ s_u cos θ   −s_v sin θ   o_u ]
//!                                  [ s_u sin θ    s_v cos θ   o_v ]
//! ```
//!
//! scale first, then rotation, then offset: Mitsuba's `to_uv` written as
//! `<scale/>`, `<rotate/>`, `<translate/>` in that order (`T · R · S`).
//! A scale of 4 repeats an image 4 times across a quad. The identity (the
//! default) is skipped, so that untransformed lookups are bit for bit
//! those without a transform. Why the options belong to the texture: the
//! BSDFs and transports pass the hit's `(u, v)` on untouched
//! (`SpectralRef::Texture`) and only call [`Texture::fourier_at`],
//! [`Texture::value_at`] and [`Texture::scalar_at`], so a new option or
//! kind of texture changes nothing there.
//!
//! # Image lookups
//!
//! Texel `(i, j)` of a `W × H` image (column `i` from the left, row `j`
//! from the top: OBJ's `v` points up, rows go down) is centred at
//! `u' = (i + ½)/W`, `v' = 1 − (j + ½)/H`. In texel units
//! `x = u' W − ½`, `y = (1 − v') H − ½`:
//!
//! * **bilinear** (the default): the four texels around `(x, y)`,
//!   weighted `(1 − f_x)(1 − f_y)`, `f_x (1 − f_y)`, `(1 − f_x) f_y`,
//!   `f_x f_y` with `f_x = x − ⌊x⌋`, `f_y = y − ⌊y⌋`;
//! * **nearest**: the texel whose cell holds the point, column
//!   `⌊u' W⌋` and row `⌊(1 − v') H⌋`; a point exactly on an edge between
//!   texels takes the one on the side of larger `u` and, rows counting
//!   down, the one below (smaller `v`).
//!
//! A texel index outside the image is mapped into it by the wrap mode:
//!
//! * **repeat** (the default): `i mod W`, the image tiling the plane;
//! * **mirror**: the image reflected at every integer `u'` and `v'`, so that
//!   `[1, 2]` shows it mirrored and the period is 2: index `k = i mod 2W`
//!   if `k < W`, else `2W − 1 − k`. Reflecting the coordinate
//!   (`u' ↦ 2 − u'` on `[1, 2]`) and then clamping gives the same lookups;
//! * **clamp**: `i` clamped to `0 … W − 1`, the edge texels extending
//!   outwards (the same as clamping `u'` to `[0, 1]` first).
//!
//! Coordinates are first reduced to one period (`u' − ⌊u'⌋` for repeat,
//! modulo 2 for mirror, clamped to `[0, 1]` for clamp), which keeps their
//! precision far from the origin; non-finite coordinates read as 0.
//! Coefficients interpolate linearly, which commutes with the projection:
//! the bilinear lookup of a coefficient texture equals the projection of
//! the bilinearly interpolated spectrum. Scalar textures use the same
//! footprint as spectral ones.
//!
//! # Checkerboard
//!
//! The procedural texture of Mitsuba 3's `checkerboard`
//! (`src/textures/checkerboard.cpp`, its spectral `eval`): with
//! `f(x) = x − ⌊x⌋` of the transformed coordinates, the first spectrum
//! where `f(u') > ½` and `f(v') > ½` agree — the squares `[0, ½]²` and
//! `(½, 1)²` of every unit cell — and the second elsewhere; a coordinate
//! with `f = ½` exactly belongs to the lower half. (Mitsuba's monochrome
//! `eval_1` assigns the colours the other way round; the spectral `eval`
//! is what colours a surface.) One unit of `u'` holds two squares, so a UV
//! scale of 4 makes 8 × 8 squares on a quad. As in Mitsuba it is evaluated
//! without filtering, at the hit point (the pixel samples antialias its
//! edges); wrap mode and filter do not apply to it. Why procedural: the
//! edges stay sharp at any scale and each square is its spectrum exactly
//! (its Fourier coefficients for [`Texture::fourier_at`], its dense table
//! for [`Texture::value_at`]), so the transports read it like any other
//! texture.
//!
//! Memory per texel: `4 · TEXTURE_COEFFS` bytes of coefficients (+12 bytes
//! of sigmoid for RGB textures) against `4 · 32` for a 32-wavelength
//! spectral texture and `4 · 471` for a 1 nm one.

use crate::spectra::{MAX_COEFFS, SceneSpectrum};
use spectral_core::upsample::{SigmoidPolynomial, srgb_reflectance};
use spectral_core::{FourierBasis, FourierSpectrum, SpectralError, SpectralRange, Spectrum};
use std::collections::HashMap;

/// Coefficients stored per texel of RGB textures.
pub const TEXTURE_COEFFS: usize = 16;
/// Largest texture accepted, texels.
pub const MAX_TEXELS: usize = 1 << 26;

/// Period of the mirror wrap mode in texture coordinates: the image and
/// its reflection.
const MIRROR_PERIOD: f32 = 2.0;
/// Where a checkerboard's unit cell changes squares, in fractions of the
/// cell.
const CHECKER_HALF: f32 = 0.5;
/// Offset of a texel's centre from its corner, texels.
const TEXEL_CENTRE: f32 = 0.5;

/// How texel indices outside the image are mapped into it (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum WrapMode {
    /// `i mod W`: the image tiles the plane.
    #[default]
    Repeat,
    /// The image reflected at every integer coordinate (period 2).
    Mirror,
    /// The index clamped to the image: the edge texels extend outwards.
    Clamp,
}

impl WrapMode {
    /// `x` reduced to one period of the mode (0 if not finite).
    fn reduce(self, x: f32) -> f32 {
        if !x.is_finite() {
            return 0.0;
        }
        match self {
            Self::Repeat => x - x.floor(),
            Self::Mirror => x - MIRROR_PERIOD * (x / MIRROR_PERIOD).floor(),
            Self::Clamp => x.clamp(0.0, 1.0),
        }
    }

    /// The texel of the integer-valued index `i` in `0 .. n` (`n >= 1`).
    fn index(self, i: f32, n: usize) -> usize {
        // Saturating: the reduced coordinates keep `i` within a few periods.
        let (i, n) = (i as i64, n as i64);
        let index = match self {
            Self::Repeat => i.rem_euclid(n),
            Self::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k < n { k } else { 2 * n - 1 - k }
            }
            Self::Clamp => i.clamp(0, n - 1),
        };
        index as usize
    }
}

/// How the texels around a lookup are combined (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum FilterMode {
    /// The four nearest texel centres, weighted bilinearly.
    #[default]
    Bilinear,
    /// The texel whose cell holds the point.
    Nearest,
}

/// An affine map of texture coordinates, `(u', v') = M · (u, v, 1)`
/// (module docs: order and Mitsuba's `to_uv`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvTransform {
    matrix: [[f32; 3]; 2],
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl UvTransform {
    /// The identity: coordinates unchanged.
    pub const IDENTITY: Self = Self {
        matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    };

    /// `uv' = R(rotation_deg) · (diag(scale) · uv) + offset`: scale, then
    /// rotation counter-clockwise (from +u towards +v), then offset.
    /// Entries are computed in f64 and rounded once; an entry that is not
    /// finite in f32 is an error.
    pub fn new(
        scale: [f64; 2],
        offset: [f64; 2],
        rotation_deg: f64,
    ) -> Result<Self, SpectralError> {
        let (sin, cos) = rotation_deg.to_radians().sin_cos();
        let [su, sv] = scale;
        let [ou, ov] = offset;
        Self::from_matrix(
            [[su * cos, -sv * sin, ou], [su * sin, sv * cos, ov]].map(|row| row.map(|m| m as f32)),
        )
    }

    /// The transform of the affine matrix `matrix` (the top two rows of a
    /// 3 × 3 affine matrix such as Mitsuba's `to_uv`); non-finite entries
    /// are an error.
    pub fn from_matrix(matrix: [[f32; 3]; 2]) -> Result<Self, SpectralError> {
        if matrix.iter().flatten().any(|m| !m.is_finite()) {
            return Err(SpectralError::InvalidParameter(
                "UV transform (finite scale, offset and rotation)",
            ));
        }
        Ok(Self { matrix })
    }

    /// The matrix `M`, rows `[a, b, c]` of `u' = a u + b v + c` and of `v'`.
    pub fn matrix(&self) -> [[f32; 3]; 2] {
        self.matrix
    }

    /// `(u', v') = M · (u, v, 1)`; the identity returns `(u, v)` unchanged.
    #[inline]
    pub fn apply(&self, u: f32, v: f32) -> (f32, f32) {
        if *self == Self::IDENTITY {
            return (u, v);
        }
        let [[a, b, c], [d, e, f]] = self.matrix;
        (a * u + b * v + c, d * u + e * v + f)
    }
}

/// How a texture is looked up: UV transform, wrap mode, filter (module
/// docs). The default (identity, repeat, bilinear) is the lookup of a
/// texture built without options.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TextureSampling {
    /// Texel indices outside the image.
    pub wrap: WrapMode,
    /// Combination of the texels around the point.
    pub filter: FilterMode,
    /// Applied to `(u, v)` before everything else.
    pub uv: UvTransform,
}

/// What a texture holds.
#[derive(Debug, Clone, PartialEq)]
pub enum TextureData {
    /// Upsampled sRGB reflectance.
    Rgb {
        /// Sigmoid coefficients per texel.
        sigmoid: Vec<[f32; 3]>,
        /// `TEXTURE_COEFFS` Fourier coefficients per texel.
        fourier: Vec<f32>,
    },
    /// `n` Fourier coefficients per texel.
    Fourier {
        /// Coefficients per texel.
        n: usize,
        /// Texel-major coefficients.
        coeffs: Vec<f32>,
    },
    /// One value per texel.
    Scalar(Vec<f32>),
    /// Three values per texel, as stored (a normal map's `(r, g, b)`).
    Vector(Vec<[f32; 3]>),
    /// Mitsuba 3's checkerboard of two spectra (module docs).
    Checkerboard {
        /// Where the halves of `u'` and `v'` agree (Mitsuba's `color0`).
        color0: Box<SceneSpectrum>,
        /// Elsewhere (Mitsuba's `color1`).
        color1: Box<SceneSpectrum>,
    },
}

/// A texture.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Texels per row (1 for a checkerboard, which has no texels).
    width: u32,
    /// Rows (1 for a checkerboard).
    height: u32,
    data: TextureData,
    range: SpectralRange,
    sampling: TextureSampling,
}

/// The texels of one image lookup with their weights: four for bilinear
/// filtering, one for nearest.
struct Footprint {
    taps: [(usize, f32); 4],
    count: usize,
}

impl Footprint {
    /// The texels and weights in use.
    fn taps(&self) -> &[(usize, f32)] {
        self.taps.get(..self.count).unwrap_or(&self.taps)
    }
}

fn check_size(
    width: u32,
    height: u32,
    len: usize,
    per_texel: usize,
) -> Result<usize, SpectralError> {
    let texels = width as usize * height as usize;
    if width == 0 || height == 0 || texels > MAX_TEXELS {
        return Err(SpectralError::InvalidParameter(
            "texture size (1 to 2^26 texels)",
        ));
    }
    if len != texels * per_texel {
        return Err(SpectralError::LengthMismatch {
            wavelengths: texels * per_texel,
            values: len,
        });
    }
    Ok(texels)
}

impl Texture {
    /// A texture of `data` with the default sampling.
    fn with_data(width: u32, height: u32, data: TextureData, range: SpectralRange) -> Self {
        Self {
            width,
            height,
            data,
            range,
            sampling: TextureSampling::default(),
        }
    }

    /// An sRGB reflectance texture (`rgb` row-major from the top-left).
    pub fn rgb(
        width: u32,
        height: u32,
        rgb: &[[f32; 3]],
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        check_size(width, height, rgb.len(), 1)?;
        let mut cache: HashMap<[u32; 3], ([f32; 3], [f32; TEXTURE_COEFFS])> = HashMap::new();
        let mut sigmoid = Vec::with_capacity(rgb.len());
        let mut fourier = Vec::with_capacity(rgb.len() * TEXTURE_COEFFS);
        for (index, texel) in rgb.iter().enumerate() {
            if let Some(position) = texel.iter().position(|v| !v.is_finite()) {
                return Err(SpectralError::NonFiniteValue {
                    index: 3 * index + position,
                });
            }
            let key = texel.map(f32::to_bits);
            let entry = match cache.get(&key) {
                Some(entry) => *entry,
                None => {
                    let poly = srgb_reflectance(texel.map(f64::from))?;
                    let c: FourierSpectrum<f64, TEXTURE_COEFFS> = poly.project(&range);
                    let entry = (poly.coeffs.map(|v| v as f32), c.coeffs.map(|v| v as f32));
                    cache.insert(key, entry);
                    entry
                }
            };
            sigmoid.push(entry.0);
            fourier.extend_from_slice(&entry.1);
        }
        Ok(Self::with_data(
            width,
            height,
            TextureData::Rgb { sigmoid, fourier },
            range,
        ))
    }

    /// A texture of `n` Fourier coefficients per texel over `range`.
    pub fn fourier(
        width: u32,
        height: u32,
        n: usize,
        coeffs: Vec<f32>,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        if n == 0 || n > MAX_COEFFS {
            return Err(SpectralError::InvalidParameter(
                "texture coefficients (1 to 32)",
            ));
        }
        check_size(width, height, coeffs.len(), n)?;
        if let Some(index) = coeffs.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self::with_data(
            width,
            height,
            TextureData::Fourier { n, coeffs },
            range,
        ))
    }

    /// A scalar texture.
    pub fn scalar(
        width: u32,
        height: u32,
        values: Vec<f32>,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        check_size(width, height, values.len(), 1)?;
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self::with_data(
            width,
            height,
            TextureData::Scalar(values),
            range,
        ))
    }

    /// A texture of three values per texel, as stored (`texels` row-major
    /// from the top-left; all finite).
    pub fn vector(
        width: u32,
        height: u32,
        texels: Vec<[f32; 3]>,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        check_size(width, height, texels.len(), 1)?;
        if let Some(index) = texels.iter().position(|t| !t.iter().all(|v| v.is_finite())) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self::with_data(
            width,
            height,
            TextureData::Vector(texels),
            range,
        ))
    }

    /// Mitsuba 3's checkerboard (module docs): `color0` on the squares
    /// `[0, ½]²` and `(½, 1)²` of every unit cell of the transformed
    /// coordinates, `color1` on the others. Both spectra must have been
    /// prepared over `range`.
    pub fn checkerboard(
        color0: &SceneSpectrum,
        color1: &SceneSpectrum,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        if *color0.range() != range || *color1.range() != range {
            return Err(SpectralError::InvalidParameter(
                "checkerboard spectra (prepared over the texture's range)",
            ));
        }
        Ok(Self::with_data(
            1,
            1,
            TextureData::Checkerboard {
                color0: Box::new(color0.clone()),
                color1: Box::new(color1.clone()),
            },
            range,
        ))
    }

    /// This reflectance texture with `f` applied to its value at every
    /// wavelength of every texel (a nonlinear plastic's `ρ/(1 − ρ F)`), with
    /// the same sampling: a texture of [`TEXTURE_COEFFS`] Fourier
    /// coefficients per texel, each the projection of `f` of the texel's
    /// spectrum (a checkerboard stays a checkerboard of its two spectra
    /// mapped, tabulated every `step_nm`). Lookups then blend mapped
    /// texels, where a renderer mapping after the lookup (Mitsuba) maps
    /// the blend: the two agree at texel centres and with nearest
    /// filtering, and differ between texels of unequal colours by the
    /// curvature of `f`. Scalar and vector textures are no reflectances.
    pub fn mapped_reflectance(
        &self,
        step_nm: f64,
        f: impl Fn(f64) -> f64,
    ) -> Result<Self, SpectralError> {
        let basis = FourierBasis::<TEXTURE_COEFFS>::new(self.range);
        let project = |value: &dyn Fn(f64) -> f64| {
            basis
                .project_function(|lambda_nm| f(value(lambda_nm)))
                .coeffs
                .map(|c| c as f32)
        };
        let data = match &self.data {
            TextureData::Rgb { sigmoid, .. } => {
                let mut cache: HashMap<[u32; 3], [f32; TEXTURE_COEFFS]> = HashMap::new();
                let mut coeffs = Vec::with_capacity(sigmoid.len() * TEXTURE_COEFFS);
                for texel in sigmoid {
                    let mapped = *cache.entry(texel.map(f32::to_bits)).or_insert_with(|| {
                        let poly = SigmoidPolynomial {
                            coeffs: texel.map(f64::from),
                        };
                        project(&|lambda_nm| poly.value(lambda_nm))
                    });
                    coeffs.extend_from_slice(&mapped);
                }
                TextureData::Fourier {
                    n: TEXTURE_COEFFS,
                    coeffs,
                }
            }
            TextureData::Fourier { n, coeffs } => {
                let mut mapped = Vec::with_capacity(coeffs.len() / n * TEXTURE_COEFFS);
                for texel in coeffs.chunks_exact(*n) {
                    let series: FourierSpectrum<f64, MAX_COEFFS> =
                        FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                            texel.get(j).map_or(0.0, |&c| f64::from(c))
                        }));
                    mapped.extend_from_slice(&project(&|lambda_nm| {
                        series.eval_cos(self.range.cos_phase(lambda_nm)).max(0.0)
                    }));
                }
                TextureData::Fourier {
                    n: TEXTURE_COEFFS,
                    coeffs: mapped,
                }
            }
            TextureData::Checkerboard { color0, color1 } => {
                let map = |spectrum: &SceneSpectrum| {
                    SceneSpectrum::new(spectrum.tabulate_with(step_nm, &f), self.range)
                };
                TextureData::Checkerboard {
                    color0: Box::new(map(color0)?),
                    color1: Box::new(map(color1)?),
                }
            }
            TextureData::Scalar(_) | TextureData::Vector(_) => {
                return Err(SpectralError::InvalidParameter(
                    "a reflectance texture (not a scalar or vector one)",
                ));
            }
        };
        if let TextureData::Fourier { coeffs, .. } = &data
            && let Some(index) = coeffs.iter().position(|v| !v.is_finite())
        {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self::with_data(self.width, self.height, data, self.range).with_sampling(self.sampling))
    }

    /// The texture looked up with `sampling` instead of the default.
    pub fn with_sampling(mut self, sampling: TextureSampling) -> Self {
        self.sampling = sampling;
        self
    }

    /// How the texture is looked up.
    pub fn sampling(&self) -> TextureSampling {
        self.sampling
    }

    /// The data.
    pub fn data(&self) -> &TextureData {
        &self.data
    }

    /// Bytes of texel data (of the two spectra for a checkerboard).
    pub fn memory_bytes(&self) -> usize {
        match &self.data {
            TextureData::Rgb { sigmoid, fourier } => 12 * sigmoid.len() + 4 * fourier.len(),
            TextureData::Fourier { coeffs, .. } => 4 * coeffs.len(),
            TextureData::Scalar(values) => 4 * values.len(),
            TextureData::Vector(texels) => 12 * texels.len(),
            TextureData::Checkerboard { color0, color1 } => {
                color0.memory_bytes() + color1.memory_bytes()
            }
        }
    }

    /// The texels and weights of an image lookup at `(u, v)` (module docs).
    fn footprint(&self, u: f32, v: f32) -> Footprint {
        let TextureSampling { wrap, filter, uv } = self.sampling;
        let (u, v) = uv.apply(u, v);
        let (u, v) = (wrap.reduce(u), wrap.reduce(v));
        let (w, h) = (self.width as usize, self.height as usize);
        match filter {
            FilterMode::Bilinear => {
                let x = u * w as f32 - TEXEL_CENTRE;
                let y = (1.0 - v) * h as f32 - TEXEL_CENTRE;
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (c0, c1) = (wrap.index(x0, w), wrap.index(x0 + 1.0, w));
                let (r0, r1) = (wrap.index(y0, h), wrap.index(y0 + 1.0, h));
                Footprint {
                    taps: [
                        (r0 * w + c0, (1.0 - fx) * (1.0 - fy)),
                        (r0 * w + c1, fx * (1.0 - fy)),
                        (r1 * w + c0, (1.0 - fx) * fy),
                        (r1 * w + c1, fx * fy),
                    ],
                    count: 4,
                }
            }
            FilterMode::Nearest => {
                let column = wrap.index((u * w as f32).floor(), w);
                let row = wrap.index(((1.0 - v) * h as f32).floor(), h);
                Footprint {
                    taps: [(row * w + column, 1.0); 4],
                    count: 1,
                }
            }
        }
    }

    /// The square of a checkerboard at `(u, v)`: `color0` where the
    /// halves of the transformed coordinates' unit cell agree (module docs).
    fn square<'a>(
        &self,
        color0: &'a SceneSpectrum,
        color1: &'a SceneSpectrum,
        u: f32,
        v: f32,
    ) -> &'a SceneSpectrum {
        let (u, v) = self.sampling.uv.apply(u, v);
        let upper = |x: f32| x - x.floor() > CHECKER_HALF;
        if upper(u) == upper(v) { color0 } else { color1 }
    }

    /// Fourier coefficients at `(u, v)`, filtered (zero beyond the stored
    /// ones; a checkerboard's square has all [`MAX_COEFFS`]).
    pub fn fourier_at(&self, u: f32, v: f32) -> [f32; MAX_COEFFS] {
        let mut out = [0.0f32; MAX_COEFFS];
        let (n, data): (usize, &[f32]) = match &self.data {
            TextureData::Rgb { fourier, .. } => (TEXTURE_COEFFS, fourier),
            TextureData::Fourier { n, coeffs } => (*n, coeffs),
            TextureData::Scalar(_) | TextureData::Vector(_) => {
                out[0] = self.scalar_at(u, v);
                return out;
            }
            TextureData::Checkerboard { color0, color1 } => {
                return *self.square(color0, color1, u, v).coefficients_f32();
            }
        };
        for &(texel, weight) in self.footprint(u, v).taps() {
            if let Some(c) = data.get(texel * n..texel * n + n) {
                for (o, &value) in out.iter_mut().zip(c) {
                    *o += weight * value;
                }
            }
        }
        out
    }

    /// The spectral value at `(u, v)` and `lambda_nm` (sampled transports).
    pub fn value_at(&self, u: f32, v: f32, lambda_nm: f32) -> f32 {
        match &self.data {
            TextureData::Rgb { sigmoid, .. } => self
                .footprint(u, v)
                .taps()
                .iter()
                .map(|&(texel, weight)| {
                    let c = sigmoid.get(texel).copied().unwrap_or([0.0; 3]);
                    let poly = SigmoidPolynomial {
                        coeffs: c.map(f64::from),
                    };
                    weight * poly.value(f64::from(lambda_nm)) as f32
                })
                .sum(),
            TextureData::Fourier { n, .. } => {
                let c = self.fourier_at(u, v);
                let x = self.range.cos_phase(f64::from(lambda_nm));
                let series: FourierSpectrum<f64, MAX_COEFFS> =
                    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                        if j < *n { f64::from(c[j]) } else { 0.0 }
                    }));
                (series.eval_cos(x) as f32).max(0.0)
            }
            TextureData::Scalar(_) | TextureData::Vector(_) => self.scalar_at(u, v),
            TextureData::Checkerboard { color0, color1 } => {
                self.square(color0, color1, u, v).value(lambda_nm)
            }
        }
    }

    /// The scalar value at `(u, v)` (the mean `c_0` of spectral textures,
    /// the mean of a vector texture's three values).
    pub fn scalar_at(&self, u: f32, v: f32) -> f32 {
        match &self.data {
            TextureData::Scalar(values) => self
                .footprint(u, v)
                .taps()
                .iter()
                .map(|&(texel, weight)| weight * values.get(texel).copied().unwrap_or(0.0))
                .sum(),
            TextureData::Vector(_) => {
                let [a, b, c] = self.vector_at(u, v).unwrap_or_default();
                (a + b + c) / 3.0
            }
            _ => self.fourier_at(u, v)[0],
        }
    }

    /// The gradient `[∂f/∂u, ∂f/∂v]` of a scalar texture's bilinear lookup
    /// at `(u, v)` (a bump map's slopes): with `f_00 … f_11` the four texels
    /// of the footprint (module docs) and `f_x, f_y` its fractions,
    /// `∂f/∂x = (1 − f_y)(f_10 − f_00) + f_y (f_11 − f_01)`,
    /// `∂f/∂y = (1 − f_x)(f_01 − f_00) + f_x (f_11 − f_10)`, then
    /// `∂f/∂u' = W ∂f/∂x`, `∂f/∂v' = −H ∂f/∂y` (rows go down) and through
    /// the UV transform `∂f/∂u = M_00 ∂f/∂u' + M_10 ∂f/∂v'`,
    /// `∂f/∂v = M_01 ∂f/∂u' + M_11 ∂f/∂v'` (Mitsuba 3.9.1's
    /// `BitmapTexture::eval_1_grad`). Zero for nearest lookups (piecewise
    /// constant) and for textures other than scalar ones.
    pub fn scalar_gradient_at(&self, u: f32, v: f32) -> [f32; 2] {
        let TextureData::Scalar(values) = &self.data else {
            return [0.0; 2];
        };
        let TextureSampling { wrap, filter, uv } = self.sampling;
        if filter == FilterMode::Nearest {
            return [0.0; 2];
        }
        let (u1, v1) = uv.apply(u, v);
        let (u1, v1) = (wrap.reduce(u1), wrap.reduce(v1));
        let (w, h) = (self.width as usize, self.height as usize);
        let x = u1 * w as f32 - TEXEL_CENTRE;
        let y = (1.0 - v1) * h as f32 - TEXEL_CENTRE;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (c0, c1) = (wrap.index(x0, w), wrap.index(x0 + 1.0, w));
        let (r0, r1) = (wrap.index(y0, h), wrap.index(y0 + 1.0, h));
        let at = |row: usize, column: usize| values.get(row * w + column).copied().unwrap_or(0.0);
        let (f00, f10, f01, f11) = (at(r0, c0), at(r0, c1), at(r1, c0), at(r1, c1));
        let df_dx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let df_dy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        let (df_du1, df_dv1) = (w as f32 * df_dx, -(h as f32) * df_dy);
        let [[m00, m01, _], [m10, m11, _]] = uv.matrix();
        [m00 * df_du1 + m10 * df_dv1, m01 * df_du1 + m11 * df_dv1]
    }

    /// The three values of a vector texture at `(u, v)`, each channel
    /// filtered as a scalar texture's value (`None` for other textures).
    pub fn vector_at(&self, u: f32, v: f32) -> Option<[f32; 3]> {
        let TextureData::Vector(texels) = &self.data else {
            return None;
        };
        let mut out = [0.0f32; 3];
        for &(texel, weight) in self.footprint(u, v).taps() {
            let values = texels.get(texel).copied().unwrap_or_default();
            for (o, value) in out.iter_mut().zip(values) {
                *o += weight * value;
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::SpectrumSource;
    use spectral_core::registry::Builtin;

    #[test]
    fn lookups_at_texel_centres_equal_the_texels() {
        let range = SpectralRange::VISIBLE;
        let rgb = vec![
            [0.8, 0.1, 0.1],
            [0.1, 0.8, 0.1],
            [0.1, 0.1, 0.8],
            [0.5, 0.5, 0.5],
        ];
        let t = Texture::rgb(2, 2, &rgb, range).unwrap();
        // Texel (1, 0) (top right) is centred at u = 0.75, v = 0.75.
        let direct = srgb_reflectance([0.1, 0.8, 0.1]).unwrap();
        let c: FourierSpectrum<f64, TEXTURE_COEFFS> = direct.project(&range);
        let looked_up = t.fourier_at(0.75, 0.75);
        for (j, (&got, want)) in looked_up.iter().zip(c.coeffs).enumerate() {
            assert!((f64::from(got) - want).abs() < 1e-6, "j = {j}");
        }
        for l in [400.0f32, 550.0, 700.0] {
            assert!(
                (f64::from(t.value_at(0.75, 0.75, l)) - direct.value(f64::from(l))).abs() < 1e-6
            );
        }
        // Half way between two texels: the mean.
        let mid = t.scalar_at(0.5, 0.75);
        let expected = 0.5 * (t.fourier_at(0.25, 0.75)[0] + t.fourier_at(0.75, 0.75)[0]);
        assert!((mid - expected).abs() < 1e-6);
        // Wrapping.
        assert_eq!(t.fourier_at(1.75, -0.25), t.fourier_at(0.75, 0.75));
        assert_eq!(t.memory_bytes(), 4 * (12 + 4 * TEXTURE_COEFFS));
    }

    #[test]
    fn invalid_textures_are_errors() {
        let range = SpectralRange::VISIBLE;
        assert!(Texture::rgb(0, 1, &[], range).is_err());
        assert!(Texture::rgb(2, 1, &[[0.0; 3]], range).is_err());
        assert!(Texture::rgb(1, 1, &[[f32::NAN, 0.0, 0.0]], range).is_err());
        assert!(Texture::fourier(1, 1, 0, vec![], range).is_err());
        assert!(Texture::fourier(1, 1, 2, vec![1.0, f32::INFINITY], range).is_err());
        assert!(Texture::scalar(1, 1, vec![f32::NAN], range).is_err());
        let s = Texture::scalar(2, 1, vec![0.0, 1.0], range).unwrap();
        assert!((s.scalar_at(0.5, 0.5) - 0.5).abs() < 1e-6);
        assert!(UvTransform::new([1e300, 1.0], [0.0, 0.0], 0.0).is_err());
        assert!(UvTransform::new([1.0, 1.0], [f64::NAN, 0.0], 0.0).is_err());
        assert!(UvTransform::new([1.0, 1.0], [0.0, 0.0], f64::INFINITY).is_err());
        assert!(UvTransform::from_matrix([[1.0, 0.0, f32::NAN], [0.0, 1.0, 0.0]]).is_err());
    }

    /// The lookup before sampling options existed: repeat, bilinear.
    fn plain_footprint(w: usize, h: usize, u: f32, v: f32) -> [(usize, f32); 4] {
        let wrap = |x: f32| if x.is_finite() { x - x.floor() } else { 0.0 };
        let x = wrap(u) * w as f32 - 0.5;
        let y = (1.0 - wrap(v)) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let column = |c: f32| (c as i64).rem_euclid(w as i64) as usize;
        let row = |r: f32| (r as i64).rem_euclid(h as i64) as usize;
        let (c0, c1, r0, r1) = (column(x0), column(x0 + 1.0), row(y0), row(y0 + 1.0));
        [
            (r0 * w + c0, (1.0 - fx) * (1.0 - fy)),
            (r0 * w + c1, fx * (1.0 - fy)),
            (r1 * w + c0, (1.0 - fx) * fy),
            (r1 * w + c1, fx * fy),
        ]
    }

    #[test]
    fn default_sampling_gives_the_bits_of_the_plain_lookup() {
        let range = SpectralRange::VISIBLE;
        let (w, h) = (5usize, 3usize);
        let values: Vec<f32> = (0..w * h).map(|i| 0.1 + 0.37 * i as f32).collect();
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [0.05 * i as f32, 0.9 - 0.04 * i as f32, 0.5])
            .collect();
        let scalar = Texture::scalar(w as u32, h as u32, values.clone(), range).unwrap();
        let colour = Texture::rgb(w as u32, h as u32, &rgb, range).unwrap();
        let TextureData::Rgb { sigmoid, fourier } = colour.data() else {
            panic!("not an RGB texture");
        };
        let explicit = scalar.clone().with_sampling(TextureSampling {
            wrap: WrapMode::Repeat,
            filter: FilterMode::Bilinear,
            uv: UvTransform::IDENTITY,
        });
        let coordinates = [
            0.0,
            0.1,
            0.2,
            0.5,
            0.999_999,
            1.0,
            1.7,
            -0.0,
            -1e-9,
            -0.3,
            -2.5,
            123.456,
            1e7,
            -1e30,
            f32::NAN,
            f32::INFINITY,
        ];
        for &u in &coordinates {
            for &v in &coordinates {
                let taps = plain_footprint(w, h, u, v);
                let want: f32 = taps.iter().map(|&(t, weight)| weight * values[t]).sum();
                assert_eq!(
                    scalar.scalar_at(u, v).to_bits(),
                    want.to_bits(),
                    "({u}, {v})"
                );
                assert_eq!(explicit.scalar_at(u, v).to_bits(), want.to_bits());
                let mut coeffs = [0.0f32; MAX_COEFFS];
                for &(t, weight) in &taps {
                    let texel = &fourier[t * TEXTURE_COEFFS..(t + 1) * TEXTURE_COEFFS];
                    for (o, &c) in coeffs.iter_mut().zip(texel) {
                        *o += weight * c;
                    }
                }
                let got = colour.fourier_at(u, v);
                assert_eq!(
                    got.map(f32::to_bits),
                    coeffs.map(f32::to_bits),
                    "({u}, {v})"
                );
                let lambda = 555.5;
                let value: f32 = taps
                    .iter()
                    .map(|&(t, weight)| {
                        let poly = SigmoidPolynomial {
                            coeffs: sigmoid[t].map(f64::from),
                        };
                        weight * poly.value(f64::from(lambda)) as f32
                    })
                    .sum();
                assert_eq!(colour.value_at(u, v, lambda).to_bits(), value.to_bits());
            }
        }
    }

    /// A 4 × 2 scalar texture of powers of two, rows from the top:
    /// `1 2 4 8` (centred at v = 0.75) and `16 32 64 128` (v = 0.25);
    /// columns centred at u = 0.125, 0.375, 0.625, 0.875.
    fn powers(wrap: WrapMode, filter: FilterMode) -> Texture {
        let values = vec![1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0];
        Texture::scalar(4, 2, values, SpectralRange::VISIBLE)
            .unwrap()
            .with_sampling(TextureSampling {
                wrap,
                filter,
                uv: UvTransform::IDENTITY,
            })
    }

    /// Checks `(u, v, repeat, mirror, clamp)` rows against [`powers`].
    fn check_wrap_modes(filter: FilterMode, rows: &[(f32, f32, f32, f32, f32)]) {
        let modes = [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp];
        for &(u, v, repeat, mirror, clamp) in rows {
            for (mode, want) in modes.into_iter().zip([repeat, mirror, clamp]) {
                let got = powers(mode, filter).scalar_at(u, v);
                assert!(
                    (got - want).abs() <= 1e-5 * want,
                    "{filter:?} {mode:?} at ({u}, {v}): {got}, expected {want}"
                );
            }
        }
    }

    #[test]
    fn bilinear_lookups_in_each_wrap_mode_mix_the_expected_texels() {
        check_wrap_modes(
            FilterMode::Bilinear,
            &[
                // Texel centres; half way between columns; between all four.
                (0.125, 0.75, 1.0, 1.0, 1.0),
                (0.25, 0.75, 1.5, 1.5, 1.5),
                (0.25, 0.5, 12.75, 12.75, 12.75),
                // u = 0: half the first and half the last (repeat), the
                // edge texel (mirror reflects texel 0, clamp extends it).
                (0.0, 0.75, 4.5, 1.0, 1.0),
                (1.0, 0.75, 4.5, 8.0, 8.0),
                (f32::NAN, 0.75, 4.5, 1.0, 1.0),
                // Outside [0, 1]: repeat tiles, mirror reflects, clamp
                // extends (−0.375 ↦ 0.625 | 0.375 | 0).
                (-0.375, 0.75, 4.0, 2.0, 1.0),
                // 1.3 ↦ 0.3 | 0.7 | 1: 0.3·1 + 0.7·2 and 0.7·4 + 0.3·8.
                (1.3, 0.75, 1.7, 5.2, 8.0),
                (1.875, 0.75, 8.0, 1.0, 8.0),
                (2.625, 0.25, 64.0, 64.0, 128.0),
                (-3.875, 0.75, 1.0, 1.0, 1.0),
                // v: half way between the rows, the top and bottom edges,
                // below the image.
                (0.125, 0.5, 8.5, 8.5, 8.5),
                (0.125, 1.0, 8.5, 1.0, 1.0),
                (0.125, 0.0, 8.5, 16.0, 16.0),
                (0.125, -0.25, 1.0, 16.0, 16.0),
            ],
        );
    }

    #[test]
    fn nearest_lookups_in_each_wrap_mode_take_the_expected_texel() {
        check_wrap_modes(
            FilterMode::Nearest,
            &[
                (0.2, 0.6, 1.0, 1.0, 1.0),
                // On the edge between columns 0 and 1: the larger u.
                (0.25, 0.75, 2.0, 2.0, 2.0),
                // On the edge between the rows: the row below.
                (0.125, 0.5, 16.0, 16.0, 16.0),
                (1.0, 0.75, 1.0, 8.0, 8.0),
                (-0.1, 0.75, 8.0, 1.0, 1.0),
                (1.9, 0.75, 8.0, 1.0, 8.0),
                (0.125, 0.0, 1.0, 16.0, 16.0),
                (0.125, 1.0, 1.0, 1.0, 1.0),
                (0.875, -0.3, 8.0, 128.0, 128.0),
            ],
        );
    }

    /// A scalar texture's gradient against central differences of its own
    /// bilinear lookups, inside texel cells (where the lookup is smooth),
    /// through a UV transform and with both wraps that keep the image's
    /// orientation; zero for nearest lookups. Negative control: the
    /// gradient of the transposed image differs.
    #[test]
    fn scalar_gradients_are_the_slopes_of_the_bilinear_lookup() {
        let range = SpectralRange::VISIBLE;
        let values = vec![0.1, 0.7, 0.3, 0.9, 0.2, 0.5, 0.8, 0.0, 0.6];
        let transposed: Vec<f32> = (0..9).map(|k| values[(k % 3) * 3 + k / 3]).collect();
        let sampling = |wrap| TextureSampling {
            wrap,
            filter: FilterMode::Bilinear,
            uv: UvTransform::new([2.0, 0.5], [0.1, 0.3], 25.0).unwrap(),
        };
        let step = 1e-3f32;
        for wrap in [WrapMode::Repeat, WrapMode::Mirror] {
            let t = Texture::scalar(3, 3, values.clone(), range)
                .unwrap()
                .with_sampling(sampling(wrap));
            let other = Texture::scalar(3, 3, transposed.clone(), range)
                .unwrap()
                .with_sampling(sampling(wrap));
            let (mut compared, mut apart) = (0, 0.0f32);
            for (u, v) in [(0.13, 0.41), (0.52, 0.77), (0.31, 0.08), (0.9, 0.6)] {
                let [gu, gv] = t.scalar_gradient_at(u, v);
                let du = (t.scalar_at(u + step, v) - t.scalar_at(u - step, v)) / (2.0 * step);
                let dv = (t.scalar_at(u, v + step) - t.scalar_at(u, v - step)) / (2.0 * step);
                // A texel edge between the two lookups breaks the slope.
                if (gu - du).abs() > 0.02 * gu.abs().max(1.0) {
                    continue;
                }
                assert!(
                    (gv - dv).abs() < 0.02 * gv.abs().max(1.0),
                    "{gv} against {dv}"
                );
                compared += 1;
                let [ou, ov] = other.scalar_gradient_at(u, v);
                apart += (ou - gu).abs() + (ov - gv).abs();
            }
            assert!(compared >= 3, "{wrap:?}: {compared}");
            assert!(
                apart > 0.5,
                "{wrap:?}: the transposed image's slopes {apart} apart"
            );
        }
        let nearest =
            Texture::scalar(3, 3, values, range)
                .unwrap()
                .with_sampling(TextureSampling {
                    filter: FilterMode::Nearest,
                    ..TextureSampling::default()
                });
        assert_eq!(nearest.scalar_gradient_at(0.4, 0.4), [0.0; 2]);
    }

    /// Each channel of a vector texture is looked up as a scalar texture of
    /// that channel alone (the same footprint and weights), and only vector
    /// textures answer [`Texture::vector_at`].
    #[test]
    fn vector_textures_filter_each_channel_as_a_scalar_texture() {
        let range = SpectralRange::VISIBLE;
        let texels = vec![
            [0.5, 0.5, 1.0],
            [1.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
            [0.25, 0.75, 0.9],
        ];
        let vector = Texture::vector(2, 2, texels.clone(), range).unwrap();
        let channel =
            |k: usize| Texture::scalar(2, 2, texels.iter().map(|t| t[k]).collect(), range).unwrap();
        for (u, v) in [(0.25, 0.75), (0.4, 0.6), (0.9, 0.1), (-0.3, 1.7)] {
            let got = vector.vector_at(u, v).unwrap();
            for (k, value) in got.into_iter().enumerate() {
                assert_eq!(value.to_bits(), channel(k).scalar_at(u, v).to_bits());
            }
        }
        assert_eq!(vector.vector_at(0.25, 0.75), Some([0.5, 0.5, 1.0]));
        assert_eq!(channel(0).vector_at(0.25, 0.75), None);
        assert_eq!(vector.memory_bytes(), 48);
        // Negative control: a non-finite texel is refused.
        let mut bad = texels;
        bad[2][1] = f32::NAN;
        assert!(Texture::vector(2, 2, bad, range).is_err());
    }

    #[test]
    fn spectral_lookups_honour_the_sampling() {
        let range = SpectralRange::VISIBLE;
        let rgb = [[0.8, 0.1, 0.1], [0.1, 0.1, 0.8]];
        let texture = Texture::rgb(2, 1, &rgb, range).unwrap();
        let sampled = |wrap, filter| {
            texture.clone().with_sampling(TextureSampling {
                wrap,
                filter,
                uv: UvTransform::IDENTITY,
            })
        };
        let left = texture.fourier_at(0.25, 0.5);
        let right = texture.fourier_at(0.75, 0.5);
        // Nearest: one texel; mirror at u = 1.1 reflects to 0.9 (right),
        // clamp at u = −1 extends the left edge.
        let nearest = sampled(WrapMode::Repeat, FilterMode::Nearest);
        assert_eq!(nearest.fourier_at(0.49, 0.5), left);
        assert_eq!(nearest.fourier_at(0.5, 0.5), right);
        let mirror = sampled(WrapMode::Mirror, FilterMode::Nearest);
        assert_eq!(mirror.fourier_at(1.1, 0.5), right);
        assert_eq!(mirror.fourier_at(1.6, 0.5), left);
        let clamp = sampled(WrapMode::Clamp, FilterMode::Bilinear);
        assert_eq!(clamp.fourier_at(-1.0, 0.5), left);
        for l in [420.0, 610.0] {
            assert_eq!(
                clamp.value_at(-1.0, 0.5, l).to_bits(),
                texture.value_at(0.25, 0.5, l).to_bits()
            );
            assert_eq!(
                mirror.value_at(1.1, 0.5, l).to_bits(),
                texture.value_at(0.75, 0.5, l).to_bits()
            );
        }
        assert_eq!(mirror.sampling().wrap, WrapMode::Mirror);
    }

    #[test]
    fn the_uv_transform_scales_then_rotates_then_offsets() {
        // S = diag(2, 4), θ = 30°, o = (0.5, 0): S·(0.25, 0.125) = (0.5, 0.5),
        // rotated (0.5 (cos θ − sin θ), 0.5 (sin θ + cos θ)) =
        // (0.1830127, 0.6830127), offset (0.6830127, 0.6830127).
        let t = UvTransform::new([2.0, 4.0], [0.5, 0.0], 30.0).unwrap();
        let (u, v) = t.apply(0.25, 0.125);
        assert!((u - 0.683_012_7).abs() < 1e-6, "{u}");
        assert!((v - 0.683_012_7).abs() < 1e-6, "{v}");
        let want = [[1.732_050_8, -2.0, 0.5], [1.0, 3.464_101_6, 0.0]];
        for (row, want_row) in t.matrix().iter().zip(want) {
            for (&m, w) in row.iter().zip(want_row) {
                assert!((m - w).abs() < 1e-6, "{:?}", t.matrix());
            }
        }
        assert_eq!(UvTransform::from_matrix(t.matrix()).unwrap(), t);
        assert_eq!(UvTransform::default(), UvTransform::IDENTITY);
        assert_eq!(
            UvTransform::new([1.0, 1.0], [0.0, 0.0], 0.0).unwrap(),
            UvTransform::IDENTITY
        );
    }

    #[test]
    fn the_uv_transform_applies_before_the_lookup() {
        let with_uv = |uv| {
            powers(WrapMode::Repeat, FilterMode::Bilinear).with_sampling(TextureSampling {
                uv,
                ..TextureSampling::default()
            })
        };
        // Scale 2: u = 0.0625 reads 0.125 (texel 1).
        let scaled = with_uv(UvTransform::new([2.0, 1.0], [0.0, 0.0], 0.0).unwrap());
        assert!((scaled.scalar_at(0.0625, 0.75) - 1.0).abs() < 1e-6);
        // Offset 0.25: u = 0.125 reads 0.375 (texel 2).
        let offset = with_uv(UvTransform::new([1.0, 1.0], [0.25, 0.0], 0.0).unwrap());
        assert!((offset.scalar_at(0.125, 0.75) - 2.0).abs() < 1e-6);
        // A quarter turn: (u, v) ↦ (−v, u); (0.75, 0.375) reads
        // (−0.375, 0.75) ↦ 0.625 (texel 4).
        let turned = with_uv(UvTransform::new([1.0, 1.0], [0.0, 0.0], 90.0).unwrap());
        assert!((turned.scalar_at(0.75, 0.375) - 4.0).abs() < 1e-5);
    }

    fn spectrum(source: SpectrumSource) -> SceneSpectrum {
        SceneSpectrum::new(source, SpectralRange::VISIBLE).unwrap()
    }

    #[test]
    fn checkerboard_squares_are_the_two_spectra() {
        let range = SpectralRange::VISIBLE;
        let a = spectrum(SpectrumSource::Builtin(
            Builtin::lookup("colorchecker-2").unwrap(),
        ));
        let b = spectrum(SpectrumSource::RgbReflectance([0.1, 0.1, 0.1]));
        assert_ne!(a.coefficients_f32(), b.coefficients_f32());
        let board = Texture::checkerboard(&a, &b, range).unwrap();
        let is = |t: &Texture, u: f32, v: f32, want: &SceneSpectrum| {
            assert_eq!(&t.fourier_at(u, v), want.coefficients_f32(), "({u}, {v})");
            assert_eq!(t.scalar_at(u, v), want.coefficients_f32()[0]);
            for l in [380.0, 455.5, 610.0, 700.0] {
                assert_eq!(t.value_at(u, v, l).to_bits(), want.value(l).to_bits());
            }
        };
        // The four quadrants of the unit cell: `a` where both halves agree.
        is(&board, 0.25, 0.25, &a);
        is(&board, 0.75, 0.25, &b);
        is(&board, 0.25, 0.75, &b);
        is(&board, 0.75, 0.75, &a);
        // f = ½ belongs to the lower half, integers start a cell.
        is(&board, 0.5, 0.25, &a);
        is(&board, 0.5, 0.5, &a);
        is(&board, 0.5, 0.75, &b);
        is(&board, 0.0, 0.75, &b);
        is(&board, 1.0, 1.0, &a);
        // Periodic, also for negative coordinates (frac(−0.25) = 0.75).
        is(&board, -0.25, 0.25, &b);
        is(&board, -0.25, -0.25, &a);
        is(&board, 7.75, -3.25, &a);
        is(&board, 7.75, -3.75, &b);
        // The UV transform applies; wrap and filter do not.
        let scaled = board.clone().with_sampling(TextureSampling {
            wrap: WrapMode::Mirror,
            filter: FilterMode::Nearest,
            uv: UvTransform::new([2.0, 2.0], [0.0, 0.0], 0.0).unwrap(),
        });
        is(&scaled, 0.125, 0.125, &a);
        is(&scaled, 0.375, 0.125, &b);
        is(&scaled, 0.3, 0.3, &a);
        is(&scaled, -0.125, 0.125, &b);
        assert_eq!(board.memory_bytes(), a.memory_bytes() + b.memory_bytes());
    }

    /// A mapped texture holds `f` of each texel's spectrum: at texel
    /// centres (nearest filtering) the mapped value at a wavelength is `f`
    /// of the original's within the truncation of [`TEXTURE_COEFFS`]
    /// coefficients: the bound is `f`'s largest slope on these values
    /// (`1/(1 − 0.6)² = 6.25` at ρ = 1) times the truncation error of the
    /// original's own coefficients on these texels, measured here, plus a
    /// float margin. The sampling is kept, a checkerboard's squares are
    /// mapped, a scalar texture is refused. Negative control: the original
    /// values, which `f` (a nonlinear plastic's) moves much further.
    #[test]
    fn mapped_textures_hold_f_of_every_texel() {
        let range = SpectralRange::VISIBLE;
        let fdr = 0.6;
        let f = |rho: f64| rho / (1.0 - fdr * rho);
        let largest_slope = 1.0 / ((1.0 - fdr) * (1.0 - fdr));
        let texels = [
            [0.1, 0.8, 0.1],
            [0.7, 0.2, 0.5],
            [0.9, 0.9, 0.9],
            [0.05, 0.1, 0.6],
        ];
        let sampling = TextureSampling {
            filter: FilterMode::Nearest,
            ..TextureSampling::default()
        };
        let rgb = Texture::rgb(2, 2, &texels, range)
            .unwrap()
            .with_sampling(sampling);
        let centres = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];
        let wavelengths_nm = [420.0, 480.0, 550.0, 610.0, 680.0];
        let points: Vec<(f32, f32, f32)> = centres
            .iter()
            .flat_map(|&(u, v)| wavelengths_nm.map(|l| (u, v, l)))
            .collect();
        let series_at = |t: &Texture, u: f32, v: f32, lambda_nm: f32| {
            let series: FourierSpectrum<f64, MAX_COEFFS> =
                FourierSpectrum::from_coeffs(t.fourier_at(u, v).map(f64::from));
            series.eval_cos(range.cos_phase(f64::from(lambda_nm)))
        };
        let truncation = points
            .iter()
            .map(|&(u, v, l)| (series_at(&rgb, u, v, l) - f64::from(rgb.value_at(u, v, l))).abs())
            .fold(0.0f64, f64::max);
        let tolerance = largest_slope * truncation + 1e-3;
        let mapped = rgb.mapped_reflectance(1.0, f).unwrap();
        assert_eq!(mapped.sampling(), sampling);
        let mut largest_error = 0.0f64;
        let mut largest_change = 0.0f64;
        for &(u, v, lambda_nm) in &points {
            let original = f64::from(rgb.value_at(u, v, lambda_nm));
            let got = f64::from(mapped.value_at(u, v, lambda_nm));
            largest_error = largest_error.max((got - f(original)).abs());
            largest_change = largest_change.max((got - original).abs());
        }
        println!(
            "truncation {truncation:.4}: mapped off by {largest_error:.4} (bound {tolerance:.4}), the original by {largest_change:.4}"
        );
        assert!(largest_error < tolerance, "{largest_error}");
        assert!(largest_change > 3.0 * tolerance, "{largest_change}");
        // Mapped again (halved): a Fourier texture maps from its own
        // coefficients.
        let halved = mapped.mapped_reflectance(1.0, |rho| 0.5 * rho).unwrap();
        for &(u, v, lambda_nm) in &points {
            let once = f64::from(mapped.value_at(u, v, lambda_nm));
            let again = f64::from(halved.value_at(u, v, lambda_nm));
            assert!((again - 0.5 * once).abs() < 1e-3, "{again} against {once}");
        }
        let a = spectrum(SpectrumSource::RgbReflectance([0.6, 0.3, 0.1]));
        let b = spectrum(SpectrumSource::RgbReflectance([0.1, 0.1, 0.1]));
        let board = Texture::checkerboard(&a, &b, range)
            .unwrap()
            .mapped_reflectance(1.0, f)
            .unwrap();
        for (u, original) in [(0.25, &a), (0.75, &b)] {
            let got = f64::from(board.value_at(u, 0.25, 550.0));
            let want = f(f64::from(original.value(550.0)));
            assert!((got - want).abs() < 1e-4, "{got} against {want}");
        }
        let scalar = Texture::scalar(1, 1, vec![0.5], range).unwrap();
        assert!(scalar.mapped_reflectance(1.0, f).is_err());
    }

    #[test]
    fn checkerboard_spectra_must_share_the_range() {
        let range = SpectralRange::VISIBLE;
        let a = spectrum(SpectrumSource::Constant(0.5));
        let other = SpectralRange::new(400.0, 700.0).unwrap();
        let b = SceneSpectrum::new(SpectrumSource::Constant(0.2), other).unwrap();
        assert!(Texture::checkerboard(&a, &b, range).is_err());
        assert!(Texture::checkerboard(&b, &a, range).is_err());
        assert!(Texture::checkerboard(&a, &b, other).is_err());
        assert!(Texture::checkerboard(&a, &a, range).is_ok());
    }
}
