//! Pixel reconstruction filters, applied by filter importance sampling,
//! with Mitsuba 3.9.1's filters (src/rfilters/box.cpp, tent.cpp,
//! gaussian.cpp, mitchell.cpp, catmullrom.cpp, lanczos.cpp) and their
//! parameters:
//!
//! * Box: the sample offset is uniform in the pixel, `[−0.5, 0.5)²`.
//!   Mitsuba's box has a fixed radius of 0.5 px and no parameter (a
//!   `radius` given to it is refused as an unreferenced property).
//! * Tent (`radius`, default 1 px): `f(x) = max(0, 1 − |x|/r)`, separable.
//!   Sampled by its exact inverse CDF: `F(x) = (1 + x/r)²/2` for `x ≤ 0`,
//!   so `x = r (√(2u) − 1)` for `u < 1/2` and `x = r (1 − √(2(1 − u)))`
//!   above (the two halves mirrored, each through one square root).
//! * Gaussian (`stddev` σ, default 0.5 px): truncated at Mitsuba's radius
//!   `r = 4σ`, `f(x) = max(0, exp(−x²/(2σ²)) − exp(−r²/(2σ²)))`, separable
//!   in x and y. (Mitsuba evaluates a Remez polynomial fit of the same
//!   shifted exponential; the exponential is its target.)
//! * Cubic (Mitchell and Netravali 1988; Mitsuba's `mitchell`, `B` and `C`
//!   default 1/3, and `catmullrom`, `B = 0`, `C = 1/2`), radius 2 px:
//!   `f(x) = ((12 − 9B − 6C)|x|³ + (−18 + 12B + 6C)|x|² + (6 − 2B))/6`
//!   for `|x| < 1`, `((−B − 6C)|x|³ + (6B + 30C)|x|² + (−12B − 48C)|x| +
//!   8B + 24C)/6` for `1 ≤ |x| < 2`, 0 beyond; `B, C ∈ [0, 1]`.
//! * Lanczos (`lobes` `a`, default 3; radius `a` px):
//!   `f(x) = sin(πx) sin(πx/a) / (πx · πx/a)` for `|x| ≤ a`, 1 at 0.
//!
//! The cubic (but for `C = 0`) and the Lanczos filters have negative
//! lobes ([`Filter::has_negative_lobes`]): a density cannot be drawn from
//! them, so they are applied by splatting only (the render refuses them
//! with the sampling film), and a pixel's weight sum may then be negative
//! (Mitsuba divides by it all the same).
//!
//! Instead of splatting every sample into all pixels under the filter
//! footprint (Mitsuba), each sample's offset is drawn from the filter itself
//! (pbrt-v4's `FilterSampler`): the sample lands in one pixel with weight
//! `f/p`, which is constant here because the offset is drawn from `f` itself.
//! The 1-D Gaussian is sampled through its inverse CDF, tabulated at the
//! 1 025 CDF values `k/1024` (solved in `f64`) and interpolated linearly:
//! each of the 1 024 cells of equal mass spreads its mass evenly between
//! two knots. That piecewise-constant density is the filter the renderer
//! applies: at σ = 0.5 px its CDF is within 2e-5 of the Gaussian's for
//! `|x| < 1.17` px, within 1e-4 in the tails and within 4e-4 in the two
//! outermost cells (`|x| > 1.7` px, where the filter rises from 0 and stays
//! below 0.2 % of its peak), tested against the Gaussian's numerical
//! integral (the errors scale with σ in px, so relative to the filter's
//! width they are the same for every σ): far below anything a
//! reconstruction filter's shape shows in an image. A sample
//! costs one table lookup, a multiply and an add (an exact inversion of a
//! piecewise-linear table, a quadratic per sample behind a data-dependent
//! search, cost 3 % of a Cornell-box render). The converged image equals the splatted one; a
//! pixel's samples never touch other pixels, so tiles render independently
//! and deterministically.
//!
//! **Splatting** ([`crate::film::FilmMode::Splat`], Mitsuba's way) needs
//! the filters' values instead: [`Filter::weight`] evaluates Mitsuba's
//! 1-D definitions above (the box is 1 on `[−0.5, 0.5)`, as Mitsuba's
//! `x >= -.5 && x < .5`, so a box splat touches its own pixel only), and a
//! sample at offset `(dx, dy)` from pixel `p`'s centre weighs
//! `w = f(dx) f(dy)` there (separable, the product in `f32` as Mitsuba's).
//! A sample lies at most half a pixel from its own pixel's centre, so the
//! pixels it can reach are those within [`Filter::splat_margin_px`]
//! `M = ⌈r + 1/2⌉ − 1` columns and rows of its own (the centres within `r`
//! of an offset in `[−1/2, 1/2)`).
//!
//! Offsets for a whole packet come from [`Filter::sample_offset_x8`], which
//! runs the scalar sampler's IEEE operations on `f32x8` (no fused
//! multiply-add; the square root is correctly rounded in both), finding
//! the Gaussian's cells 8-wide and looking each lane's cell up, so every
//! lane equals [`Filter::sample_offset`] bit for bit (tested for every
//! filter).

use crate::simd::exp_nonpositive_x8;
use wide::f32x8;

/// Standard deviation of the default Gaussian filter, px (Mitsuba's
/// `stddev` default).
pub const GAUSSIAN_SIGMA_PX: f32 = 0.5;
/// Radius of a Gaussian filter in standard deviations (Mitsuba cuts the
/// Gaussian off at 4σ).
pub const GAUSSIAN_RADIUS_STDDEVS: f32 = 4.0;
/// Radius of the default Gaussian filter, px.
pub const GAUSSIAN_RADIUS_PX: f32 = GAUSSIAN_RADIUS_STDDEVS * GAUSSIAN_SIGMA_PX;
/// Radius of the default tent filter, px (Mitsuba's `radius` default).
pub const TENT_RADIUS_PX: f32 = 1.0;
/// The largest filter radius accepted, px: a wider filter would blur over
/// more than a hundred pixels, which no scene asks for, and keeps the
/// offsets far inside `f32`'s exact range of pixel coordinates.
pub const MAX_FILTER_RADIUS_PX: f32 = 64.0;
/// The widest splat margin, px: [`Filter::splat_margin_px`] of a filter of
/// radius [`MAX_FILTER_RADIUS_PX`], `⌈64 + 1/2⌉ − 1` (tested).
pub const MAX_SPLAT_MARGIN_PX: u32 = 64;
/// The largest weight (in magnitude) one pass may splat into a pixel:
/// every 1-D filter value is at most 1 in magnitude (box 1, tent
/// `1 − |x|/r`, Gaussian `1 − e^(−r²/2σ²)`, cubic `1 − B/3` at 0 and less
/// elsewhere for `B, C ∈ [0, 1]`, Lanczos `|sinc · sinc| ≤ 1`), so
/// `|f(dx) f(dy)| ≤ 1`, and a pass puts one sample in each of the at most
/// `(2M + 1)²` pixels that reach it, `M` at most [`MAX_SPLAT_MARGIN_PX`].
/// The bound the film states' weight sums are checked against.
pub const MAX_SPLAT_WEIGHT_PER_PASS: f64 =
    ((2 * MAX_SPLAT_MARGIN_PX + 1) * (2 * MAX_SPLAT_MARGIN_PX + 1)) as f64;
/// Radius of the cubic filters, px (Mitsuba's `m_radius = 2`).
pub const CUBIC_RADIUS_PX: f32 = 2.0;
/// Mitchell and Netravali's recommended `B` and `C` (Mitsuba's
/// `mitchell` defaults).
pub const MITCHELL_B_C: [f32; 2] = [1.0 / 3.0, 1.0 / 3.0];
/// The Catmull–Rom spline as a cubic filter (Mitsuba's `catmullrom`).
pub const CATMULL_ROM_B_C: [f32; 2] = [0.0, 0.5];
/// Mitsuba's default number of Lanczos lobes.
pub const LANCZOS_LOBES: u32 = 3;
/// Below this `|x|` the Lanczos filter is 1 (Mitsuba's `dr::Epsilon`,
/// `2⁻²⁴`: the quotient's `0/0` avoided).
const LANCZOS_ORIGIN_PX: f32 = 1.0 / 16_777_216.0;
/// Cells of the tabulated inverse CDF: the Gaussian's offsets at the CDF
/// values `k / INVERSE_CELLS`, interpolated linearly in between.
const INVERSE_CELLS: usize = 1024;
/// Segments of the `f64` trapezoid CDF the knots are solved on.
const BUILD_SEGMENTS: usize = 4096;

/// A reconstruction filter.
#[derive(Debug, Clone, PartialEq)]
pub enum Filter {
    /// Box of one pixel (Mitsuba's `box`).
    Box,
    /// Tent `max(0, 1 − |x|/r)` of radius `radius_px` (Mitsuba's `tent`),
    /// sampled by its exact inverse CDF. Build it with [`Filter::tent`],
    /// which checks the radius; [`Filter::validate`] checks a literal one.
    Tent {
        /// Radius `r`, px (in `(0, MAX_FILTER_RADIUS_PX]`).
        radius_px: f32,
    },
    /// Truncated Gaussian (σ, r = 4σ), sampled by its inverse CDF.
    Gaussian(GaussianSampler),
    /// Mitchell–Netravali cubic of parameters `B`, `C` (module docs),
    /// radius [`CUBIC_RADIUS_PX`]; splatted only. Build it with
    /// [`Filter::cubic`], which checks `B` and `C`.
    Cubic {
        /// `B`, in `[0, 1]`.
        b: f32,
        /// `C`, in `[0, 1]`.
        c: f32,
    },
    /// Lanczos windowed sinc of `lobes` lobes (module docs), radius
    /// `lobes` px; splatted only. Build it with [`Filter::lanczos`].
    Lanczos {
        /// Lobes, 1 to [`MAX_FILTER_RADIUS_PX`].
        lobes: u32,
    },
}

/// A filter parameter out of range.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilterError(String);

impl core::fmt::Display for FilterError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for FilterError {}

/// `value` if it is a radius the filters accept: finite, positive, at most
/// [`MAX_FILTER_RADIUS_PX`].
fn checked_radius(what: &str, value: f32) -> Result<f32, FilterError> {
    if value.is_finite() && value > 0.0 && value <= MAX_FILTER_RADIUS_PX {
        Ok(value)
    } else {
        Err(FilterError(format!(
            "filter {what} {value} px: must be positive and at most {MAX_FILTER_RADIUS_PX} px"
        )))
    }
}

impl Filter {
    /// Mitsuba's default Gaussian (σ = 0.5 px, r = 2 px).
    pub fn gaussian() -> Self {
        Self::Gaussian(GaussianSampler::new(GAUSSIAN_SIGMA_PX, GAUSSIAN_RADIUS_PX))
    }

    /// Mitsuba's Gaussian of standard deviation `stddev_px`, cut off at
    /// `4 stddev_px`; the radius must be at most [`MAX_FILTER_RADIUS_PX`].
    pub fn gaussian_with_stddev(stddev_px: f32) -> Result<Self, FilterError> {
        let radius = checked_radius("radius (4 × stddev)", GAUSSIAN_RADIUS_STDDEVS * stddev_px)?;
        Ok(Self::Gaussian(GaussianSampler::new(stddev_px, radius)))
    }

    /// Mitsuba's tent of radius `radius_px` (its default: [`TENT_RADIUS_PX`]).
    pub fn tent(radius_px: f32) -> Result<Self, FilterError> {
        Ok(Self::Tent {
            radius_px: checked_radius("radius", radius_px)?,
        })
    }

    /// Mitsuba's cubic filter of parameters `b` and `c`, each in
    /// `[0, 1]` (Mitchell and Netravali's square of parameters, where every
    /// value is at most 1 in magnitude; [`MITCHELL_B_C`],
    /// [`CATMULL_ROM_B_C`]).
    pub fn cubic(b: f32, c: f32) -> Result<Self, FilterError> {
        for (name, value) in [("B", b), ("C", c)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(FilterError(format!(
                    "cubic filter {name} {value}: must be in [0, 1]"
                )));
            }
        }
        Ok(Self::Cubic { b, c })
    }

    /// Mitsuba's Lanczos filter of `lobes` lobes (1 to
    /// [`MAX_FILTER_RADIUS_PX`]).
    pub fn lanczos(lobes: u32) -> Result<Self, FilterError> {
        checked_radius("lobes", lobes as f32)?;
        if lobes == 0 {
            return Err(FilterError("Lanczos filter of 0 lobes".into()));
        }
        Ok(Self::Lanczos { lobes })
    }

    /// Whether the filter's parameters are in range (a filter written as a
    /// literal may not be).
    pub fn validate(&self) -> Result<(), FilterError> {
        match self {
            Self::Tent { radius_px } => checked_radius("radius", *radius_px).map(|_| ()),
            Self::Cubic { b, c } => Self::cubic(*b, *c).map(|_| ()),
            Self::Lanczos { lobes } => Self::lanczos(*lobes).map(|_| ()),
            Self::Box | Self::Gaussian(_) => Ok(()),
        }
    }

    /// Whether the filter takes negative values somewhere: then it is
    /// splatted only (module docs).
    pub fn has_negative_lobes(&self) -> bool {
        match self {
            Self::Cubic { c, .. } => *c > 0.0,
            Self::Lanczos { .. } => true,
            Self::Box | Self::Tent { .. } | Self::Gaussian(_) => false,
        }
    }

    /// The filter's radius, px: offsets lie in `[−r, r]²`.
    pub fn radius_px(&self) -> f32 {
        match self {
            Self::Box => 0.5,
            Self::Tent { radius_px } => *radius_px,
            Self::Gaussian(g) => g.radius_px,
            Self::Cubic { .. } => CUBIC_RADIUS_PX,
            Self::Lanczos { lobes } => *lobes as f32,
        }
    }

    /// Columns (and rows) on either side of its own pixel that a splatted
    /// sample can reach: `M = ⌈r + 1/2⌉ − 1` (module docs).
    pub fn splat_margin_px(&self) -> u32 {
        // r ≤ MAX_FILTER_RADIUS_PX: the value is a small whole number.
        ((self.radius_px() + 0.5).ceil() - 1.0).max(0.0) as u32
    }

    /// The filter's 1-D value at `x` px from a pixel centre, Mitsuba's
    /// definitions (module docs): box `[−0.5 ≤ x < 0.5]`, tent
    /// `max(0, 1 − |x|/r)`, Gaussian `max(0, e^(−x²/2σ²) − e^(−r²/2σ²))`.
    pub fn weight(&self, x: f32) -> f32 {
        match self {
            Self::Box => {
                if (-0.5..0.5).contains(&x) {
                    1.0
                } else {
                    0.0
                }
            }
            Self::Tent { radius_px } => (1.0 - x.abs() / radius_px).max(0.0),
            Self::Gaussian(g) => g.weight(x),
            Self::Cubic { b, c } => cubic_weight(x, *b, *c),
            Self::Lanczos { lobes } => lanczos_weight(x, *lobes as f32),
        }
    }

    /// [`Filter::weight`] for 8 lanes at once (the splat's weights of one
    /// row or column). The Gaussian's `e^x` is the 8-wide exponential of
    /// non-positive arguments ([`exp_nonpositive_x8`], within 2 ulp),
    /// within 2 × 10⁻⁷ of the scalar `expf` (tested lane by lane against
    /// [`Filter::weight`], the oracle). NaN lanes give 0, as the scalar
    /// box and Gaussian do.
    pub fn weight_x8(&self, x: f32x8) -> f32x8 {
        match self {
            Self::Box => {
                let inside = x.simd_ge(f32x8::splat(-0.5)) & x.simd_lt(f32x8::splat(0.5));
                inside.select(f32x8::ONE, f32x8::ZERO)
            }
            Self::Tent { radius_px } => {
                let value = (f32x8::ONE - x.abs() / f32x8::splat(*radius_px)).max(f32x8::ZERO);
                // `max` keeps the NaN of a NaN lane; the scalar's `f32::max`
                // gives 0 there.
                value.is_nan().select(f32x8::ZERO, value)
            }
            Self::Gaussian(g) => g.weight_x8(x),
            Self::Cubic { b, c } => cubic_weight_x8(x, *b, *c),
            // Lane by lane: `sin` has no 8-wide form here, and the filter
            // is rare (its splat's weights are one row and one column a
            // sample).
            Self::Lanczos { lobes } => {
                let lanes = x.to_array().map(|x| lanczos_weight(x, *lobes as f32));
                f32x8::new(lanes)
            }
        }
    }

    /// An offset from the pixel centre, px, for uniform `(u, v)`. Filters
    /// with negative lobes have no density to draw from: they give the
    /// box's offsets, which the splat film uses for every filter (the
    /// render refuses them with the sampling film).
    pub fn sample_offset(&self, u: f32, v: f32) -> (f32, f32) {
        match self {
            Self::Box | Self::Cubic { .. } | Self::Lanczos { .. } => (u - 0.5, v - 0.5),
            Self::Tent { radius_px } => (tent_sample(u, *radius_px), tent_sample(v, *radius_px)),
            Self::Gaussian(g) => (g.sample(u), g.sample(v)),
        }
    }

    /// [`Filter::sample_offset`] for 8 lanes at once.
    pub fn sample_offset_x8(&self, u: f32x8, v: f32x8) -> (f32x8, f32x8) {
        match self {
            Self::Box | Self::Cubic { .. } | Self::Lanczos { .. } => {
                let half = f32x8::splat(0.5);
                (u - half, v - half)
            }
            Self::Tent { radius_px } => {
                let r = f32x8::splat(*radius_px);
                (tent_sample_x8(u, r), tent_sample_x8(v, r))
            }
            Self::Gaussian(g) => (g.sample_x8(u), g.sample_x8(v)),
        }
    }
}

/// The cubic filter's coefficients `[a3, a2, a0]` (`|x| < 1`) and
/// `[b3, b2, b1, b0]` (`1 ≤ |x| < 2`), each over 6 (module docs).
fn cubic_coefficients(b: f32, c: f32) -> ([f32; 3], [f32; 4]) {
    let sixth = 1.0 / 6.0;
    (
        [
            (12.0 - 9.0 * b - 6.0 * c) * sixth,
            (-18.0 + 12.0 * b + 6.0 * c) * sixth,
            (6.0 - 2.0 * b) * sixth,
        ],
        [
            (-b - 6.0 * c) * sixth,
            (6.0 * b + 30.0 * c) * sixth,
            (-12.0 * b - 48.0 * c) * sixth,
            (8.0 * b + 24.0 * c) * sixth,
        ],
    )
}

/// The cubic filter at `x` (module docs); NaN gives 0.
fn cubic_weight(x: f32, b: f32, c: f32) -> f32 {
    let ([a3, a2, a0], [b3, b2, b1, b0]) = cubic_coefficients(b, c);
    let x = x.abs();
    if x < 1.0 {
        (a3 * x + a2) * x * x + a0
    } else if x < CUBIC_RADIUS_PX {
        ((b3 * x + b2) * x + b1) * x + b0
    } else {
        0.0
    }
}

/// [`cubic_weight`] for 8 lanes, with the same operations (NaN lanes fail
/// both comparisons and give 0).
fn cubic_weight_x8(x: f32x8, b: f32, c: f32) -> f32x8 {
    let ([a3, a2, a0], [b3, b2, b1, b0]) = cubic_coefficients(b, c);
    let splat = f32x8::splat;
    let x = x.abs();
    let inner = (splat(a3) * x + splat(a2)) * x * x + splat(a0);
    let outer = ((splat(b3) * x + splat(b2)) * x + splat(b1)) * x + splat(b0);
    let value = x.simd_lt(f32x8::ONE).select(inner, outer);
    x.simd_lt(splat(CUBIC_RADIUS_PX)).select(value, f32x8::ZERO)
}

/// The Lanczos filter of `lobes` lobes at `x` (module docs); NaN gives 0.
fn lanczos_weight(x: f32, lobes: f32) -> f32 {
    let x = x.abs();
    if x < LANCZOS_ORIGIN_PX {
        1.0
    } else if x <= lobes {
        let x1 = core::f32::consts::PI * x;
        let x2 = x1 / lobes;
        (x1.sin() * x2.sin()) / (x1 * x2)
    } else {
        0.0
    }
}

/// `u` clamped to `[0, 1]`, NaN to 0: `u > 0 ? min(u, 1) : 0`, the
/// packet's `max` then `min`.
#[inline(always)]
fn clamp_unit(u: f32) -> f32 {
    if u > 0.0 { u.min(1.0) } else { 0.0 }
}

/// [`clamp_unit`] for 8 lanes (`max` before `min` maps NaN to 0).
#[inline(always)]
fn clamp_unit_x8(u: f32x8) -> f32x8 {
    u.fast_max(f32x8::ZERO).fast_min(f32x8::ONE)
}

/// The tent's inverse CDF at `u` (module docs): `r (√(2u) − 1)` below
/// `u = 1/2`, `r (1 − √(2(1 − u)))` from there on.
#[inline(always)]
fn tent_sample(u: f32, radius_px: f32) -> f32 {
    let u = clamp_unit(u);
    let unit = if u < 0.5 {
        (2.0 * u).sqrt() - 1.0
    } else {
        1.0 - (2.0 * (1.0 - u)).sqrt()
    };
    unit * radius_px
}

/// [`tent_sample`] for 8 lanes, with the same operations.
#[inline(always)]
fn tent_sample_x8(u: f32x8, radius_px: f32x8) -> f32x8 {
    let (one, two) = (f32x8::ONE, f32x8::splat(2.0));
    let u = clamp_unit_x8(u);
    let lower = (two * u).sqrt() - one;
    let upper = one - (two * (one - u)).sqrt();
    u.simd_lt(f32x8::splat(0.5)).select(lower, upper) * radius_px
}

/// Inverse-CDF sampler of the 1-D truncated Gaussian on `[−r, r]`.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianSampler {
    /// Per cell `k` of `u ∈ [k/K, (k + 1)/K)` (`K` = [`INVERSE_CELLS`]):
    /// the offset `x_k` at its start and the step `x_{k+1} − x_k` to the
    /// next knot (fixed size: the lookups need no bounds checks).
    cells: Box<[[f32; 2]; INVERSE_CELLS]>,
    /// The truncation radius, px.
    radius_px: f32,
    /// `−1/(2σ²)`, px⁻², the exponent's factor in [`GaussianSampler::weight`].
    exponent_per_px2: f32,
    /// `e^(−r²/2σ²)`, the value subtracted so the filter reaches 0 at `r`.
    bias: f32,
}

impl GaussianSampler {
    /// The sampler of `max(0, exp(−x²/2σ²) − exp(−r²/2σ²))` on `[−r, r]`:
    /// the knots `x_k = F⁻¹(k/K)` of the filter's CDF `F`, solved in `f64`
    /// on its trapezoid integral over `BUILD_SEGMENTS` segments (exactly,
    /// a quadratic per segment), then rounded to `f32`.
    pub fn new(sigma: f32, radius_px: f32) -> Self {
        let (sigma, radius) = (f64::from(sigma), f64::from(radius_px));
        let two_variance = 2.0 * sigma * sigma;
        let bias = (-radius * radius / two_variance).exp();
        let step = 2.0 * radius / BUILD_SEGMENTS as f64;
        let values: Vec<f64> = (0..=BUILD_SEGMENTS)
            .map(|i| {
                let x = -radius + i as f64 * step;
                ((-x * x / two_variance).exp() - bias).max(0.0)
            })
            .collect();
        let mut cdf = Vec::with_capacity(BUILD_SEGMENTS + 1);
        let mut total = 0.0f64;
        cdf.push(total);
        for pair in values.windows(2) {
            total += 0.5 * (pair[0] + pair[1]) * step;
            cdf.push(total);
        }
        // F⁻¹(u): the segment holding the mass u · total, then the distance
        // s into it where ∫0^s (f0 + (f1 − f0) τ/step) dτ reaches the rest,
        // s = 2 rest / (f0 + √(f0² + 2 (f1 − f0) rest / step)) (the stable
        // root, also for f0 = 0).
        let knot = |u: f64| {
            let target = u * total;
            let i = cdf
                .partition_point(|&c| c <= target)
                .clamp(1, BUILD_SEGMENTS)
                - 1;
            let (f0, f1) = (values[i], values[i + 1]);
            let rest = (target - cdf[i]).max(0.0);
            let denominator = f0 + (f0 * f0 + 2.0 * (f1 - f0) * rest / step).max(0.0).sqrt();
            let s = if denominator > 0.0 {
                (2.0 * rest / denominator).clamp(0.0, step)
            } else {
                0.0
            };
            (-radius + i as f64 * step + s).clamp(-radius, radius) as f32
        };
        let knots: Vec<f32> = (0..=INVERSE_CELLS)
            .map(|k| match k {
                0 => -radius as f32,
                INVERSE_CELLS => radius as f32,
                _ => knot(k as f64 / INVERSE_CELLS as f64),
            })
            .collect();
        Self {
            cells: Box::new(core::array::from_fn(|k| {
                [knots[k], knots[k + 1] - knots[k]]
            })),
            radius_px,
            exponent_per_px2: (-1.0 / two_variance) as f32,
            bias: bias as f32,
        }
    }

    /// The filter's value at `x` px, `max(0, e^(−x²/2σ²) − e^(−r²/2σ²))`
    /// in `f32` (Mitsuba's truncated Gaussian; 0 beyond `r`).
    pub fn weight(&self, x: f32) -> f32 {
        if x.abs() >= self.radius_px {
            return 0.0;
        }
        ((x * x * self.exponent_per_px2).exp() - self.bias).max(0.0)
    }

    /// [`GaussianSampler::weight`] for 8 lanes (NaN and `|x| ≥ r` give 0).
    pub fn weight_x8(&self, x: f32x8) -> f32x8 {
        let inside = x.abs().simd_lt(f32x8::splat(self.radius_px));
        // `x² · exponent ≤ 0`, and lanes outside the support (where it may
        // pass the exponential's domain) are masked below.
        let value = (exp_nonpositive_x8(x * x * f32x8::splat(self.exponent_per_px2))
            - f32x8::splat(self.bias))
        .max(f32x8::ZERO);
        inside.select(value, f32x8::ZERO)
    }

    /// The cell of `u` (clamped to `[0, 1]`, NaN to 0) and the position in
    /// it, `u K − k ∈ [0, 1]`.
    #[inline(always)]
    fn cell(u: f32) -> (usize, f32) {
        let scaled = clamp_unit(u) * INVERSE_CELLS as f32;
        let k = (scaled as usize).min(INVERSE_CELLS - 1);
        (k, scaled - k as f32)
    }

    /// [`GaussianSampler::sample`] for 8 lanes: the cells 8-wide, one
    /// lookup per lane, the interpolation 8-wide with the scalar
    /// operations.
    pub fn sample_x8(&self, u: f32x8) -> f32x8 {
        let scaled = clamp_unit_x8(u) * f32x8::splat(INVERSE_CELLS as f32);
        let last = wide::i32x8::splat((INVERSE_CELLS - 1) as i32);
        let k = scaled.trunc_int().min(last);
        let position = scaled - k.round_float();
        let k = k.to_array();
        let cell = |lane: usize| self.cells[(k[lane] as usize).min(INVERSE_CELLS - 1)];
        let start = f32x8::new(core::array::from_fn(|lane| cell(lane)[0]));
        let width = f32x8::new(core::array::from_fn(|lane| cell(lane)[1]));
        start + width * position
    }

    /// Offset for uniform `u ∈ [0, 1)`: `x_k + (x_{k+1} − x_k)(uK − k)`,
    /// the inverse CDF interpolated linearly between its knots, so each
    /// cell's `1/K` of the mass is spread evenly over `[x_k, x_{k+1}]`.
    pub fn sample(&self, u: f32) -> f32 {
        let (k, position) = Self::cell(u);
        let [start, width] = self.cells[k.min(INVERSE_CELLS - 1)];
        start + width * position
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_offsets_have_the_filter_distribution() {
        let g = GaussianSampler::new(GAUSSIAN_SIGMA_PX, GAUSSIAN_RADIUS_PX);
        let n = 200_000;
        let samples: Vec<f32> = (0..n)
            .map(|i| g.sample((i as f32 + 0.5) / n as f32))
            .collect();
        assert!(samples.iter().all(|x| x.abs() <= GAUSSIAN_RADIUS_PX));
        let mean: f64 = samples.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
        let var: f64 = samples.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 1e-4, "{mean}");
        // The truncation at 4σ removes almost nothing; the bias term lowers the variance slightly.
        assert!((var.sqrt() - 0.5).abs() < 0.01, "{}", var.sqrt());
        assert!((g.sample(0.5)).abs() < 1e-4);
        // The ends, where the filter value is exactly 0, stay finite.
        assert_eq!(g.sample(0.0), -GAUSSIAN_RADIUS_PX);
        assert!(g.sample(1.0 - f32::EPSILON).is_finite());
        assert!(g.sample(0.0) <= g.sample(0.1) && g.sample(0.1) <= g.sample(0.9));
        assert_eq!(g.sample(1.0), GAUSSIAN_RADIUS_PX);
        assert_eq!(g.sample(f32::NAN), -GAUSSIAN_RADIUS_PX);
    }

    /// The CDF of the filter `f` on `[−radius, radius]` from its own
    /// numerical integral (Simpson's rule over 20 000 intervals, a node at
    /// 0 where the tent has its kink), linear between the stored points
    /// (spacing 2e-4 of the radius).
    fn numerical_cdf(f: impl Fn(f64) -> f64, radius: f64) -> impl Fn(f64) -> f64 {
        let intervals = 20_000;
        let h = 2.0 * radius / f64::from(intervals);
        let mut cumulative = vec![0.0f64];
        for i in (0..intervals).step_by(2) {
            let x0 = -radius + f64::from(i) * h;
            let area = h / 3.0 * (f(x0) + 4.0 * f(x0 + h) + f(x0 + 2.0 * h));
            cumulative.push(cumulative.last().copied().unwrap_or(0.0) + area);
        }
        let total = cumulative.last().copied().unwrap_or(1.0);
        move |x: f64| {
            let position = (x + radius) / (2.0 * h);
            let i = (position.floor().max(0.0) as usize).min(cumulative.len() - 2);
            let t = (position - i as f64).clamp(0.0, 1.0);
            (cumulative[i] + t * (cumulative[i + 1] - cumulative[i])) / total
        }
    }

    /// The largest `|F(sample(u)) − u|` over a dense grid of `u`: 0 for an
    /// exact inverse of `F`. Split as the Gaussian's table is: the core (10
    /// cells of the table in from either end), the next 9 cells, the two
    /// outermost cells.
    fn cdf_errors(sample: impl Fn(f32) -> f32, cdf: impl Fn(f64) -> f64) -> [f64; 3] {
        let n = 100_000;
        let mut worst = [0.0f64; 3];
        let cell = 1.0 / INVERSE_CELLS as f64;
        for i in 0..n {
            let u = (f64::from(i) + 0.5) / f64::from(n);
            let error = (cdf(f64::from(sample(u as f32))) - u).abs();
            let from_end = u.min(1.0 - u) / cell;
            let part = if from_end >= 10.0 {
                0
            } else if from_end >= 1.0 {
                1
            } else {
                2
            };
            worst[part] = worst[part].max(error);
        }
        worst
    }

    /// The truncated Gaussian of standard deviation `sigma` (r = 4σ).
    fn gaussian(sigma: f64) -> impl Fn(f64) -> f64 {
        let radius = f64::from(GAUSSIAN_RADIUS_STDDEVS) * sigma;
        let bias = (-radius * radius / (2.0 * sigma * sigma)).exp();
        move |x: f64| ((-x * x / (2.0 * sigma * sigma)).exp() - bias).max(0.0)
    }

    /// The tent of radius `radius`.
    fn tent(radius: f64) -> impl Fn(f64) -> f64 {
        move |x: f64| (1.0 - x.abs() / radius).max(0.0)
    }

    /// The sampled offsets' CDF against the truncated Gaussian's, for the
    /// default σ and two others (Mitsuba's `stddev`), on a dense grid of `u`
    /// (the inverse of the sampler's CDF at those points); a sampler checked
    /// against the CDF of a 10 % wider Gaussian fails.
    #[test]
    fn gaussian_offsets_follow_the_filter_cdf() -> Result<(), FilterError> {
        for sigma in [GAUSSIAN_SIGMA_PX, 0.3, 1.25] {
            let filter = Filter::gaussian_with_stddev(sigma)?;
            let Filter::Gaussian(g) = &filter else {
                panic!("a Gaussian filter");
            };
            let radius = f64::from(GAUSSIAN_RADIUS_STDDEVS * sigma);
            assert_eq!(filter.radius_px(), GAUSSIAN_RADIUS_STDDEVS * sigma);
            let worst = cdf_errors(
                |u| g.sample(u),
                numerical_cdf(gaussian(f64::from(sigma)), radius),
            );
            assert!(
                worst[0] < 2e-5,
                "σ {sigma}: CDF error in the core {}",
                worst[0]
            );
            assert!(
                worst[1] < 1e-4,
                "σ {sigma}: CDF error in the tails {}",
                worst[1]
            );
            // The outermost cells (|x| > 1.7 σ/0.5, below 0.2 % of the
            // peak) hold their 1/1024 of the mass, spread evenly where the
            // filter rises from 0: within half a cell's mass.
            let cell = 1.0 / INVERSE_CELLS as f64;
            assert!(worst[2] < 0.5 * cell, "σ {sigma}: end cells {}", worst[2]);
            // Negative control: the CDF of σ × 1.1 (on its own wider range).
            let wider = 1.1 * f64::from(sigma);
            let wrong = cdf_errors(
                |u| g.sample(u),
                numerical_cdf(gaussian(wider), f64::from(GAUSSIAN_RADIUS_STDDEVS) * wider),
            );
            assert!(
                wrong[0] > 1e-2,
                "σ {sigma}: a wrong σ passes ({})",
                wrong[0]
            );
        }
        // The default is the σ = 0.5 filter, bit for bit.
        assert_eq!(
            Filter::gaussian(),
            Filter::gaussian_with_stddev(GAUSSIAN_SIGMA_PX)?
        );
        Ok(())
    }

    /// The tent's inverse CDF is exact: the sampled offsets' CDF equals the
    /// tent's numerical integral to rounding everywhere, for the default
    /// radius and two others; against the CDF of a 10 % wider tent it fails.
    #[test]
    fn tent_offsets_follow_the_filter_cdf() -> Result<(), FilterError> {
        for radius in [TENT_RADIUS_PX, 0.5, 2.5] {
            let filter = Filter::tent(radius)?;
            assert_eq!(filter.radius_px(), radius);
            let sample = |u: f32| filter.sample_offset(u, u).0;
            let r = f64::from(radius);
            let worst = cdf_errors(sample, numerical_cdf(tent(r), r));
            assert!(
                worst.iter().all(|&e| e < 2e-6),
                "radius {radius}: CDF errors {worst:?}"
            );
            let wrong = cdf_errors(sample, numerical_cdf(tent(1.1 * r), 1.1 * r));
            assert!(wrong[0] > 1e-2, "radius {radius}: a wrong radius passes");
            // The ends and the middle, and offsets within the radius.
            assert_eq!(sample(0.0), -radius);
            assert_eq!(sample(0.5), 0.0);
            assert_eq!(sample(1.0), radius);
            assert_eq!(sample(f32::NAN), -radius);
            assert!((0..1000).all(|i| sample(i as f32 / 1000.0).abs() <= radius));
        }
        Ok(())
    }

    /// The box's offsets are uniform on `[−0.5, 0.5)`: the CDF `x + 1/2`
    /// exactly; checked against a tent of the same support it fails.
    #[test]
    fn box_offsets_follow_the_filter_cdf() {
        let sample = |u: f32| Filter::Box.sample_offset(u, u).0;
        let worst = cdf_errors(sample, |x| (x + 0.5).clamp(0.0, 1.0));
        assert!(worst.iter().all(|&e| e < 1e-6), "{worst:?}");
        let wrong = cdf_errors(sample, numerical_cdf(tent(0.5), 0.5));
        assert!(wrong[0] > 1e-2);
        assert_eq!(Filter::Box.radius_px(), 0.5);
    }

    /// Radii out of range are refused, by the constructors and by
    /// `validate` for a literal tent.
    #[test]
    fn filter_parameters_are_checked() {
        for bad in [
            0.0,
            -1.0,
            f32::NAN,
            f32::INFINITY,
            2.0 * MAX_FILTER_RADIUS_PX,
        ] {
            assert!(Filter::tent(bad).is_err(), "tent {bad}");
            assert!(Filter::gaussian_with_stddev(bad).is_err(), "gaussian {bad}");
            assert!(Filter::Tent { radius_px: bad }.validate().is_err());
        }
        assert!(Filter::gaussian_with_stddev(MAX_FILTER_RADIUS_PX).is_err());
        assert!(Filter::Tent { radius_px: 1.5 }.validate().is_ok());
        assert!(Filter::Box.validate().is_ok() && Filter::gaussian().validate().is_ok());
    }

    #[test]
    fn packet_offsets_equal_scalar_offsets_bit_for_bit() -> Result<(), FilterError> {
        let mut rng = crate::sampling::rng::Rng::new(7, 11);
        let edges = [0.0, 0.5, 1.0 - f32::EPSILON, 1e-9, 0.25, 0.75, 0.999, 1e-3];
        let specials = [
            f32::NAN,
            -0.25,
            1.5,
            0.5 - f32::EPSILON / 4.0,
            0.0,
            1.0,
            2e-38,
            0.5,
        ];
        let filters = [
            Filter::gaussian(),
            Filter::gaussian_with_stddev(0.3)?,
            Filter::Box,
            Filter::tent(TENT_RADIUS_PX)?,
            Filter::tent(1.7)?,
        ];
        for filter in filters {
            for round in 0..2000 {
                let (u, v): ([f32; 8], [f32; 8]) = match round {
                    0 => (
                        edges,
                        edges.map(|e| 1.0 - f32::EPSILON - e).map(|e| e.max(0.0)),
                    ),
                    // Outside [0, 1) and NaN: the box passes them through,
                    // the others clamp; scalar and packet alike.
                    1 => (specials, edges),
                    _ => (
                        core::array::from_fn(|_| rng.next_f32()),
                        core::array::from_fn(|_| rng.next_f32()),
                    ),
                };
                let (x, y) = filter.sample_offset_x8(f32x8::new(u), f32x8::new(v));
                for lane in 0..8 {
                    let (sx, sy) = filter.sample_offset(u[lane], v[lane]);
                    assert_eq!(
                        x.to_array()[lane].to_bits(),
                        sx.to_bits(),
                        "{filter:?} {}",
                        u[lane]
                    );
                    assert_eq!(
                        y.to_array()[lane].to_bits(),
                        sy.to_bits(),
                        "{filter:?} {}",
                        v[lane]
                    );
                }
            }
        }
        Ok(())
    }

    /// The 8-wide weights equal the scalar oracle lane by lane (the box
    /// and the tent bit for bit, the Gaussian within 2 × 10⁻⁷ of its peak
    /// 1), inside, at and beyond the radius, and give 0 for NaN.
    #[test]
    fn weight_x8_matches_the_scalar_weights() -> Result<(), FilterError> {
        for filter in [
            Filter::Box,
            Filter::gaussian(),
            Filter::tent(TENT_RADIUS_PX)?,
            Filter::tent(2.5)?,
        ] {
            let r = filter.radius_px();
            for start in -400..=400 {
                let x: [f32; 8] =
                    core::array::from_fn(|lane| (start * 8 + lane as i32) as f32 * r / 2400.0);
                let wide = filter.weight_x8(f32x8::new(x)).to_array();
                for lane in 0..8 {
                    let scalar = filter.weight(x[lane]);
                    let tolerance = match filter {
                        Filter::Gaussian(_) => 2e-7,
                        _ => 0.0,
                    };
                    assert!(
                        (wide[lane] - scalar).abs() <= tolerance,
                        "{filter:?} at {}: {} vs {scalar}",
                        x[lane],
                        wide[lane]
                    );
                }
            }
            let edges = f32x8::new([r, -r, f32::NAN, 2.0 * r, -2.0 * r, 0.0, r * 0.999, -0.5]);
            let wide = filter.weight_x8(edges).to_array();
            for (lane, &x) in edges.to_array().iter().enumerate() {
                let scalar = if x.is_nan() { 0.0 } else { filter.weight(x) };
                assert!((wide[lane] - scalar).abs() <= 2e-7, "{filter:?} at {x}");
            }
        }
        Ok(())
    }

    /// The splat weights are Mitsuba's filter values: the box 1 on
    /// `[−0.5, 0.5)`, the tent and the truncated Gaussian against their
    /// `f64` forms, 0 at and beyond the radius; the margins reach every
    /// centre within the radius of an offset in `[−0.5, 0.5)` and no more.
    #[test]
    fn splat_weights_and_margins_follow_the_filters() -> Result<(), FilterError> {
        assert_eq!(Filter::Box.weight(-0.5), 1.0);
        assert_eq!(Filter::Box.weight(0.5), 0.0);
        assert_eq!(Filter::Box.weight(0.499), 1.0);
        assert_eq!(Filter::Box.splat_margin_px(), 0);
        let sigma = f64::from(GAUSSIAN_SIGMA_PX);
        for filter in [
            Filter::gaussian(),
            Filter::tent(TENT_RADIUS_PX)?,
            Filter::tent(2.5)?,
        ] {
            let r = filter.radius_px();
            let exact: Box<dyn Fn(f64) -> f64> = match filter {
                Filter::Gaussian(_) => Box::new(gaussian(sigma)),
                _ => Box::new(tent(f64::from(r))),
            };
            for i in -400..=400 {
                let x = i as f32 * r / 300.0;
                let error = (f64::from(filter.weight(x)) - exact(f64::from(x))).abs();
                assert!(error < 1e-6, "{filter:?} at {x}: {error}");
            }
            assert_eq!(filter.weight(r), 0.0);
            assert_eq!(filter.weight(-r), 0.0);
            // Every pixel centre k with |o − k| < r for some o ∈ [−0.5, 0.5)
            // lies within the margin, and the margin holds no other.
            let margin = filter.splat_margin_px() as i32;
            let reached = |k: i32| (k as f32).abs() - 0.5 < r;
            assert!(reached(margin) && !reached(margin + 1), "{filter:?}");
        }
        assert_eq!(Filter::gaussian().splat_margin_px(), 2);
        assert_eq!(
            Filter::tent(MAX_FILTER_RADIUS_PX)?.splat_margin_px(),
            MAX_SPLAT_MARGIN_PX
        );
        Ok(())
    }

    /// Mitsuba 3.9.1's cubic and Lanczos filters in `f64`, written from its
    /// plugins (src/rfilters/mitchell.cpp, lanczos.cpp) as they read: the
    /// oracle of [`Filter::weight`].
    fn mitsuba_cubic(x: f64, b: f64, c: f64) -> f64 {
        let x = x.abs();
        let (x2, x3) = (x * x, x * x * x);
        let value = if x < 1.0 {
            (12.0 - 9.0 * b - 6.0 * c) * x3 + (-18.0 + 12.0 * b + 6.0 * c) * x2 + (6.0 - 2.0 * b)
        } else {
            (-b - 6.0 * c) * x3
                + (6.0 * b + 30.0 * c) * x2
                + (-12.0 * b - 48.0 * c) * x
                + (8.0 * b + 24.0 * c)
        };
        if x < 2.0 { value / 6.0 } else { 0.0 }
    }

    fn mitsuba_lanczos(x: f64, lobes: f64) -> f64 {
        let x = x.abs();
        let x1 = std::f64::consts::PI * x;
        let x2 = x1 / lobes;
        if x < f64::from(LANCZOS_ORIGIN_PX) {
            1.0
        } else if x > lobes {
            0.0
        } else {
            x1.sin() * x2.sin() / (x1 * x2)
        }
    }

    /// The cubic and Lanczos filters: their values against Mitsuba's forms
    /// in `f64` (within 2·10⁻⁶), the 8-wide weights equal to the scalar
    /// ones bit for bit (NaN lanes 0), a Mitchell filter's integral 1 and
    /// the Lanczos filter's zeros at the whole pixels; both have negative
    /// lobes (but the cubic with `C = 0`), and their parameters are checked.
    /// A wrong `B` is far from Mitsuba's values (the negative control).
    #[test]
    fn cubic_and_lanczos_filters_follow_mitsuba() -> Result<(), FilterError> {
        let [mb, mc] = MITCHELL_B_C;
        let [cb, cc] = CATMULL_ROM_B_C;
        let filters = [
            (Filter::cubic(mb, mc)?, 2.0),
            (Filter::cubic(cb, cc)?, 2.0),
            (Filter::cubic(0.8, 0.1)?, 2.0),
            (Filter::lanczos(LANCZOS_LOBES)?, 3.0),
            (Filter::lanczos(2)?, 2.0),
        ];
        for (filter, radius) in &filters {
            assert_eq!(filter.radius_px(), *radius);
            assert!(filter.has_negative_lobes(), "{filter:?}");
            let exact = |x: f64| match filter {
                Filter::Cubic { b, c } => mitsuba_cubic(x, f64::from(*b), f64::from(*c)),
                Filter::Lanczos { lobes } => mitsuba_lanczos(x, f64::from(*lobes)),
                _ => f64::NAN,
            };
            for i in -500..=500 {
                let x = i as f32 * radius / 400.0;
                let error = (f64::from(filter.weight(x)) - exact(f64::from(x))).abs();
                assert!(error < 2e-6, "{filter:?} at {x}: {error}");
            }
            for start in -100..=100 {
                let x: [f32; 8] =
                    core::array::from_fn(|lane| (start * 8 + lane as i32) as f32 * radius / 700.0);
                let wide = filter.weight_x8(f32x8::new(x)).to_array();
                for lane in 0..8 {
                    assert_eq!(wide[lane].to_bits(), filter.weight(x[lane]).to_bits());
                }
            }
            let nan = filter.weight_x8(f32x8::splat(f32::NAN)).to_array();
            assert!(nan.iter().all(|&w| w == 0.0) && filter.weight(f32::NAN) == 0.0);
            // Every value at most 1 in magnitude (MAX_SPLAT_WEIGHT_PER_PASS).
            assert!((-4000..=4000).all(|i| filter.weight(i as f32 / 1000.0).abs() <= 1.0));
        }
        // Mitchell–Netravali filters integrate to 1 for every B and C.
        for (b, c) in [(mb, mc), (cb, cc), (0.8, 0.1), (0.0, 0.0)] {
            let steps = 40_000;
            let h = 4.0 / f64::from(steps);
            let integral: f64 = (0..steps)
                .map(|i| {
                    mitsuba_cubic(-2.0 + (f64::from(i) + 0.5) * h, f64::from(b), f64::from(c)) * h
                })
                .sum();
            assert!((integral - 1.0).abs() < 1e-6, "B {b} C {c}: {integral}");
        }
        // Lanczos is 1 at 0 and 0 at every other whole pixel.
        let lanczos = Filter::lanczos(LANCZOS_LOBES)?;
        assert_eq!(lanczos.weight(0.0), 1.0);
        for k in 1..=3 {
            assert!(lanczos.weight(k as f32).abs() < 1e-6, "{k}");
        }
        assert!(!Filter::cubic(1.0, 0.0)?.has_negative_lobes());
        for (b, c) in [(-0.1, 0.3), (0.3, 1.5), (f32::NAN, 0.3)] {
            assert!(Filter::cubic(b, c).is_err(), "B {b} C {c}");
            assert!(Filter::Cubic { b, c }.validate().is_err());
        }
        assert!(Filter::lanczos(0).is_err() && Filter::lanczos(65).is_err());
        assert!(Filter::Lanczos { lobes: 0 }.validate().is_err());
        // Negative control: B 0.5 instead of 1/3.
        let wrong = Filter::cubic(0.5, mc)?;
        let off = (0..=200)
            .map(|i| {
                let x = f64::from(i) / 100.0;
                (f64::from(wrong.weight(x as f32)) - mitsuba_cubic(x, f64::from(mb), f64::from(mc)))
                    .abs()
            })
            .fold(0.0, f64::max);
        assert!(off > 1e-2, "{off}");
        Ok(())
    }

    #[test]
    fn box_is_uniform_in_the_pixel() {
        assert_eq!(Filter::Box.sample_offset(0.0, 0.999), (-0.5, 0.499));
    }
}
