//! The light paths' share of the film (`integrator::light_paths`): their
//! hits, weighted by the pixel filter, summed per pixel of the window, and
//! added to the film's pixels when the image is resolved or saved.
//!
//! **Weights.** A light path's hit at film point `x` carries `C(x)`, XYZ per
//! px² and pass. The camera samples estimate, per pass,
//!
//! * with the sampled filter ([`FilmMode::Sample`]), `∫ f̂(x − c) L(x) dx`
//!   with one sample, weight 1, per pixel and pass: `f̂ = f / ∫f` is the
//!   density the offsets are drawn from, over the whole plane (a sample may
//!   land past the film's edge). The light paths add `f̂(x − c) C(x)`;
//! * splatting ([`FilmMode::Splat`]), the ratio of `∫_film f(x − c) L(x) dx`
//!   to `∫_film f(x − c) dx` per pass (one sample, uniform in each pixel of
//!   the film, adds `f L` and `f`). The light paths add `f(x − c) C(x)` to
//!   the numerator for `x` on the film, and nothing to the weights.
//!
//! Either way a pixel's sums gain, per pass, the expected share of the
//! light paths' light in the same units as its camera samples, so the
//! resolved pixel is the sum of both estimates. `∫f` is the 1-D integral
//! of the filter, by the midpoint rule (the sampled Gaussian's tabulated
//! density is within `4·10⁻⁴` of `f/∫f`, `film::filter`).
//!
//! **Order.** Hits are added in the order of their passes and, within a
//! pass, of their paths (the renderer collects each pass's chunks of paths
//! in order), into sums of their own: the film's camera sums never see
//! them until the end, so the bits depend on neither the thread count nor
//! the batch sizes. A crop traces every light path and keeps the hits
//! that reach its window, which are the full render's.

use super::PixelWindow;
use crate::film::FilmMode;
use crate::film::filter::Filter;
use crate::integrator::light_paths::FilmHit;

/// Midpoints of the filter's 1-D integral ([`LightFilm`]'s `∫f`).
const FILTER_INTEGRAL_POINTS: usize = 4096;

/// The light paths' XYZ sums over a window (module docs).
#[derive(Debug, Clone)]
pub(super) struct LightFilm {
    window: PixelWindow,
    film_size: (u32, u32),
    filter: Filter,
    /// Whether hits are splatted (else weighted by the sampled density).
    splat: bool,
    /// `1/∫f` with the sampled filter, 1 splatting.
    normaliser: f32,
    sums: Vec<[f64; 3]>,
}

impl LightFilm {
    /// Empty sums over `window` of a `width × height` film.
    pub(super) fn new(
        window: PixelWindow,
        (width, height): (u32, u32),
        filter: Filter,
        mode: FilmMode,
    ) -> Self {
        let splat = mode == FilmMode::Splat;
        let normaliser = if splat {
            1.0
        } else {
            let radius = f64::from(filter.radius_px());
            let step = 2.0 * radius / FILTER_INTEGRAL_POINTS as f64;
            let integral: f64 = (0..FILTER_INTEGRAL_POINTS)
                .map(|k| f64::from(filter.weight((-radius + (k as f64 + 0.5) * step) as f32)))
                .sum::<f64>()
                * step;
            (1.0 / integral) as f32
        };
        Self {
            window,
            film_size: (width, height),
            filter,
            splat,
            normaliser,
            sums: vec![[0.0; 3]; window.pixel_count() as usize],
        }
    }

    /// The filter's normalised weights `(pixel, weight)` along one axis of
    /// `size` pixels for a hit at `at`.
    fn weights(&self, at: f32, size: u32) -> impl Iterator<Item = (u32, f32)> + '_ {
        let radius = self.filter.radius_px();
        let first = (at - radius - 0.5).floor().max(0.0) as u32;
        let last = ((at + radius - 0.5).ceil().max(0.0) as u32).min(size.saturating_sub(1));
        (first..=last).filter_map(move |pixel| {
            let weight = self.filter.weight(at - (pixel as f32 + 0.5)) * self.normaliser;
            (weight != 0.0).then_some((pixel, weight))
        })
    }

    /// Adds a light path's hit.
    pub(super) fn add(&mut self, hit: &FilmHit) {
        let (width, height) = self.film_size;
        let on_film = (0.0..width as f32).contains(&hit.x) && (0.0..height as f32).contains(&hit.y);
        if !(hit.x.is_finite() && hit.y.is_finite()) || (self.splat && !on_film) {
            return;
        }
        let window = self.window;
        let rows: Vec<(u32, f32)> = self.weights(hit.y, height).collect();
        let columns: Vec<(u32, f32)> = self.weights(hit.x, width).collect();
        for &(y, wy) in &rows {
            for &(x, wx) in &columns {
                if !window.contains(x, y) {
                    continue;
                }
                let index = ((y - window.y) * window.width + x - window.x) as usize;
                let weight = f64::from(wx * wy);
                if let Some(sum) = self.sums.get_mut(index) {
                    for (acc, &v) in sum.iter_mut().zip(&hit.xyz) {
                        *acc += weight * f64::from(v);
                    }
                }
            }
        }
    }

    /// The sums of film pixel `(x, y)` of the window.
    pub(super) fn at(&self, x: u32, y: u32) -> &[f64; 3] {
        let window = self.window;
        let index = ((y - window.y) * window.width + x - window.x) as usize;
        self.sums.get(index).unwrap_or(&[0.0; 3])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Under the sampled filter a hit's weights, averaged over where in a
    /// pixel it lands, sum to 1 (each weight is the density of the camera
    /// samples' offsets; a hit's own sum is a sampled sum of the filter,
    /// 0.9 % off the integral for the narrow Gaussian), and less near the
    /// film's edge (but for the box); splatting a pixel's weight is the filter's `f(dx) f(dy)`
    /// and a hit off the film adds nothing. The box puts a hit in its own pixel.
    #[test]
    fn weights_are_the_density_or_the_filter() {
        let window = PixelWindow::full(8, 6);
        let hit = |x, y| FilmHit {
            x,
            y,
            xyz: [1.0, 2.0, 3.0],
        };
        let total = |film: &LightFilm| film.sums.iter().map(|s| s[1]).sum::<f64>() / 2.0;
        const STEPS: usize = 16;
        for filter in [Filter::Box, Filter::gaussian(), Filter::tent(1.0).unwrap()] {
            for (x0, y0, inside) in [(3.0, 2.0, true), (0.0, 0.0, false), (7.0, 5.0, false)] {
                let mut film = LightFilm::new(window, (8, 6), filter.clone(), FilmMode::Sample);
                for i in 0..STEPS * STEPS {
                    let (dx, dy) = ((i % STEPS) as f32 + 0.5, (i / STEPS) as f32 + 0.5);
                    film.add(&hit(x0 + dx / STEPS as f32, y0 + dy / STEPS as f32));
                }
                let mean = total(&film) / (STEPS * STEPS) as f64;
                // The box never reaches past a hit's own pixel.
                if inside || matches!(filter, Filter::Box) {
                    assert!((mean - 1.0).abs() < 2e-3, "{filter:?} {x0} {y0}: {mean}");
                } else {
                    assert!(mean < 1.0 - 1e-2, "{filter:?} {x0} {y0}: {mean}");
                }
            }
        }
        let mut film = LightFilm::new(window, (8, 6), Filter::Box, FilmMode::Sample);
        film.add(&hit(3.3, 2.7));
        assert_eq!(film.at(3, 2), &[1.0, 2.0, 3.0]);
        let mut film = LightFilm::new(window, (8, 6), Filter::gaussian(), FilmMode::Splat);
        film.add(&hit(-0.1, 2.0));
        assert_eq!(total(&film), 0.0);
        film.add(&hit(4.2, 3.0));
        let gaussian = Filter::gaussian();
        let weight = f64::from(gaussian.weight(4.2 - 4.5) * gaussian.weight(3.0 - 3.5));
        assert!(
            (film.at(4, 3)[0] - weight).abs() < 1e-6,
            "{:?} vs {weight}",
            film.at(4, 3)
        );
    }
}
