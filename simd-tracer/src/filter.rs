//! Pixel reconstruction filters, applied by filter importance sampling.
//!
//! * Box: the sample offset is uniform in the pixel.
//! * Gaussian: Mitsuba 3's default, standard deviation 0.5 px truncated at a
//!   radius of 2 px, `f(x) = max(0, exp(−x²/(2σ²)) − exp(−r²/(2σ²)))`,
//!   separable in x and y.
//!
//! Instead of splatting every sample into all pixels under the filter
//! footprint (Mitsuba), each sample's offset is drawn from the filter itself
//! (pbrt-v4's `FilterSampler`): the sample lands in one pixel with weight
//! `f/p`, which is constant here because the offset is drawn from `f` exactly
//! (inverse CDF of the tabulated 1-D filter with linear interpolation, whose
//! density is the piecewise-linear `f` itself). The converged image equals
//! the splatted one; a pixel's samples never touch other pixels, so tiles
//! render independently and deterministically.
//!
//! Offsets for a whole packet come from [`Filter::sample_offset_x8`], which
//! looks up each lane's segment and then runs the same IEEE operations as
//! the scalar sampler on `f32x8` (no fused multiply-add), so every lane
//! equals [`Filter::sample_offset`] bit for bit (tested).

use wide::f32x8;

/// Standard deviation of the Gaussian filter, px.
pub const GAUSSIAN_SIGMA_PX: f32 = 0.5;
/// Radius of the Gaussian filter, px.
pub const GAUSSIAN_RADIUS_PX: f32 = 2.0;
const TABLE_SIZE: usize = 256;
/// Entries of the inverse-CDF lookup that makes sampling `O(1)`.
const INVERSE_SIZE: usize = 4096;

/// A reconstruction filter.
#[derive(Debug, Clone, PartialEq)]
pub enum Filter {
    /// Box of one pixel.
    Box,
    /// Truncated Gaussian (σ = 0.5 px, r = 2 px), sampled by its inverse CDF.
    Gaussian(GaussianSampler),
}

impl Filter {
    /// Mitsuba's default Gaussian.
    pub fn gaussian() -> Self {
        Self::Gaussian(GaussianSampler::new(GAUSSIAN_SIGMA_PX, GAUSSIAN_RADIUS_PX))
    }

    /// An offset from the pixel centre, px, for uniform `(u, v)`.
    pub fn sample_offset(&self, u: f32, v: f32) -> (f32, f32) {
        match self {
            Self::Box => (u - 0.5, v - 0.5),
            Self::Gaussian(g) => (g.sample(u), g.sample(v)),
        }
    }

    /// [`Filter::sample_offset`] for 8 lanes at once.
    pub fn sample_offset_x8(&self, u: f32x8, v: f32x8) -> (f32x8, f32x8) {
        match self {
            Self::Box => {
                let half = f32x8::splat(0.5);
                (u - half, v - half)
            }
            Self::Gaussian(g) => (g.sample_x8(u), g.sample_x8(v)),
        }
    }
}

/// Inverse-CDF sampler of the 1-D truncated Gaussian on `[−r, r]`.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianSampler {
    radius: f32,
    /// CDF of the piecewise-linear filter at `TABLE_SIZE + 1` evenly spaced
    /// points of `[−r, r]` (0 … 1).
    cdf: Vec<f32>,
    /// Per segment `[c0, c1, f0, f1]`: the CDF and the filter value at its
    /// two ends, side by side so a lane reads its segment in one load
    /// (fixed sizes: the lookups need no bounds checks).
    segments: Box<[[f32; 4]; TABLE_SIZE]>,
    /// `inverse[k]`: the segment containing the CDF value `k/INVERSE_SIZE`,
    /// so sampling starts its search there (at most a step or two).
    inverse: Box<[u16; INVERSE_SIZE + 1]>,
}

impl GaussianSampler {
    /// The sampler of `max(0, exp(−x²/2σ²) − exp(−r²/2σ²))` on `[−r, r]`.
    pub fn new(sigma: f32, radius: f32) -> Self {
        let bias = (-radius * radius / (2.0 * sigma * sigma)).exp();
        let step = 2.0 * radius / TABLE_SIZE as f32;
        let values: Vec<f32> = (0..=TABLE_SIZE)
            .map(|i| {
                let x = -radius + i as f32 * step;
                ((-x * x / (2.0 * sigma * sigma)).exp() - bias).max(0.0)
            })
            .collect();
        let mut cdf = Vec::with_capacity(TABLE_SIZE + 1);
        let mut total = 0.0f64;
        cdf.push(0.0f64);
        for pair in values.windows(2) {
            total += 0.5 * f64::from(pair[0] + pair[1]) * f64::from(step);
            cdf.push(total);
        }
        let cdf: Vec<f32> = cdf.into_iter().map(|c| (c / total) as f32).collect();
        let inverse = Box::new(core::array::from_fn(|k| {
            let u = k as f32 / INVERSE_SIZE as f32;
            (cdf.partition_point(|&c| c <= u).clamp(1, TABLE_SIZE) - 1) as u16
        }));
        let segments = Box::new(core::array::from_fn(|i| {
            [cdf[i], cdf[i + 1], values[i], values[i + 1]]
        }));
        Self {
            radius,
            cdf,
            segments,
            inverse,
        }
    }

    /// The segment whose CDF interval contains `u`.
    fn segment(&self, u: f32) -> usize {
        self.segment_from(((u * INVERSE_SIZE as f32) as usize).min(INVERSE_SIZE), u)
    }

    /// [`GaussianSampler::segment`] with the inverse-table cell `k` of `u`
    /// given.
    #[inline(always)]
    fn segment_from(&self, k: usize, u: f32) -> usize {
        let mut segment = usize::from(self.inverse[k.min(INVERSE_SIZE)]).min(TABLE_SIZE - 1);
        while segment + 1 < TABLE_SIZE && self.segments[segment][1] <= u {
            segment += 1;
        }
        segment
    }

    /// [`GaussianSampler::sample`] for 8 lanes: the segments are looked up
    /// per lane, the quadratic is solved 8-wide with the scalar operations
    /// in the scalar order.
    pub fn sample_x8(&self, u: f32x8) -> f32x8 {
        let lanes = u.to_array();
        // The inverse-table cells 8-wide: `u` clamped to [0, 1] (NaN to 0)
        // gives the scalar conversion's saturated index.
        let size = f32x8::splat(INVERSE_SIZE as f32);
        let cells = (u.fast_max(f32x8::ZERO).fast_min(f32x8::ONE) * size)
            .trunc_int()
            .to_array();
        let mut segment = [0.0f32; 8];
        let rows: [[f32; 4]; 8] = core::array::from_fn(|lane| {
            let k = self.segment_from(cells[lane] as usize, lanes[lane]);
            segment[lane] = k as f32;
            self.segments[k.min(TABLE_SIZE - 1)]
        });
        let column = |i: usize| f32x8::new(core::array::from_fn(|lane| rows[lane][i]));
        let (c0, c1, f0, f1) = (column(0), column(1), column(2), column(3));
        let (zero, one, half) = (f32x8::ZERO, f32x8::ONE, f32x8::splat(0.5));
        let step = f32x8::splat(2.0 * self.radius / TABLE_SIZE as f32);
        let mass = c1 - c0;
        let target = mass
            .simd_gt(zero)
            .select(((u - c0) / mass).fast_max(zero).fast_min(one), half);
        let flat = (f1 - f0)
            .abs()
            .simd_lt(f32x8::splat(1e-6) * (f0 + f1).fast_max(f32x8::splat(1e-30)));
        let a = half * (f1 - f0);
        let b = f0;
        let c = -target * half * (f0 + f1);
        let denominator = b + (b * b - f32x8::splat(4.0) * a * c).fast_max(zero).sqrt();
        let curved = denominator.simd_gt(zero).select(
            (f32x8::splat(2.0) * -c / denominator)
                .fast_max(zero)
                .fast_min(one),
            zero,
        );
        let t = flat.select(target, curved);
        f32x8::splat(-self.radius) + (f32x8::new(segment) + t) * step
    }

    /// Offset for uniform `u ∈ [0, 1)`: inverts the CDF of the piecewise
    /// linear density exactly (a quadratic on each segment).
    pub fn sample(&self, u: f32) -> f32 {
        let segment = self.segment(u);
        let step = 2.0 * self.radius / TABLE_SIZE as f32;
        let [c0, c1, f0, f1] = self.segments[segment.min(TABLE_SIZE - 1)];
        let mass = c1 - c0;
        let target = if mass > 0.0 {
            ((u - c0) / mass).clamp(0.0, 1.0)
        } else {
            0.5
        };
        // Within the segment the density is f0 + (f1 − f0) t, t ∈ [0, 1];
        // solve ∫0^t = target ∫0^1 for t.
        let t = if (f1 - f0).abs() < 1e-6 * (f0 + f1).max(1e-30) {
            target
        } else {
            let a = 0.5 * (f1 - f0);
            let b = f0;
            let c = -target * 0.5 * (f0 + f1);
            let denominator = b + (b * b - 4.0 * a * c).max(0.0).sqrt();
            if denominator > 0.0 {
                (2.0 * -c / denominator).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        -self.radius + (segment as f32 + t) * step
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
        // The O(1) segment lookup equals a binary search.
        for i in 0..10_000 {
            let u = i as f32 / 10_000.0;
            let binary = g.cdf.partition_point(|&c| c <= u).clamp(1, TABLE_SIZE) - 1;
            assert_eq!(g.segment(u), binary, "{u}");
        }
    }

    #[test]
    fn packet_offsets_equal_scalar_offsets_bit_for_bit() {
        let mut rng = crate::rng::Rng::new(7, 11);
        let edges = [0.0, 0.5, 1.0 - f32::EPSILON, 1e-9, 0.25, 0.75, 0.999, 1e-3];
        for filter in [Filter::gaussian(), Filter::Box] {
            for round in 0..2000 {
                let (u, v): ([f32; 8], [f32; 8]) = if round == 0 {
                    (
                        edges,
                        edges.map(|e| 1.0 - f32::EPSILON - e).map(|e| e.max(0.0)),
                    )
                } else {
                    (
                        core::array::from_fn(|_| rng.next_f32()),
                        core::array::from_fn(|_| rng.next_f32()),
                    )
                };
                let (x, y) = filter.sample_offset_x8(f32x8::new(u), f32x8::new(v));
                for lane in 0..8 {
                    let (sx, sy) = filter.sample_offset(u[lane], v[lane]);
                    assert_eq!(x.to_array()[lane].to_bits(), sx.to_bits(), "{}", u[lane]);
                    assert_eq!(y.to_array()[lane].to_bits(), sy.to_bits(), "{}", v[lane]);
                }
            }
        }
    }

    #[test]
    fn box_is_uniform_in_the_pixel() {
        assert_eq!(Filter::Box.sample_offset(0.0, 0.999), (-0.5, 0.499));
    }
}
