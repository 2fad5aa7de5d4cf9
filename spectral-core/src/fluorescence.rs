//! Fluorescence: a layer of fluorophore that absorbs light at one
//! wavelength and re-emits part of it at longer ones, its reradiation
//! kernel, and that kernel as an `N × N` operator on Fourier coefficients.
//!
//! **Model.** Incident light of wavelength `λi` is absorbed with the
//! absorptance `a(λi) = a_peak · A(λi)` (`A` the absorption band, 1 at its
//! peak); the base under the layer reflects what is not absorbed (the
//! renderer's elastic reflectance is `ρ(λ) (1 − a(λ))`). A fraction `Φ`
//! of the absorbed photons (the quantum yield) is re-emitted with the
//! emission band's shape (Kasha's rule: the shape does not depend on
//! `λi`). Radiance counts energy, and a photon of `λi` re-emitted at `λo`
//! carries `λi/λo` of its energy, so the reradiation kernel per nm of `λo` is
//!
//! `M(λo, λi) = Φ · x(λi) · ê(λo) · λi/λo`,
//!
//! with `x(λi) = a(λi)` below the split wavelength `λ00` and 0 above it,
//! and `ê(λo)` the emission band above `λ00`, normalised to unit integral
//! over `[λ00, λ1]`. `λ00` is where the peak-normalised absorption and
//! emission bands cross: the usual estimate of the 0–0 transition
//! (Lakowicz, *Principles of Fluorescence Spectroscopy*, 3rd ed., §1.3).
//! Light absorbed above `λ00` is lost (the small anti-Stokes emission of
//! the overlap region is not modelled), emission below `λ00` is folded
//! into the band above it. **Why this form:** every `λi < λ00 ≤ λo`, so
//! energy only moves to longer wavelengths (Stokes), and
//! `∫ M(λo, λi) dλo = Φ x(λi) ∫ ê(λo) λi/λo dλo ≤ Φ a(λi)`: re-emitted
//! energy never exceeds the absorbed energy times the quantum yield. And
//! `M` is separable, `M(λo, λi) = u(λo) v(λi)` with `u = ê λ00/λo` (the
//! emitted side) and `v = Φ x λi/λ00` (the excited side), which a path
//! tracer can carry as one spectrum on each side of the event.
//!
//! **Operator.** Light `L_i = c_0 + 2 Σ c_j cos(jφ)` leaves as `L_o(λo) =
//! ∫ M(λo, λi) L_i(λi) dλi`, whose coefficients are `o_k = Σ_j R_kj c_j`,
//!
//! `R_kj = (1/W) ∫∫ cos(kφ(λo)) M(λo, λi) b_j(λi) dλi dλo`, `b_0 = 1`,
//! `b_j = 2 cos(jφ)`, `W = λ1 − λ0`
//!
//! ([`reradiation_operator`], midpoint quadrature on a grid; any kernel,
//! separable or not). For the separable kernel `R = ũ ṽᵀ` with `ũ` the
//! coefficients of `u` and `ṽ_j = ∫ v b_j dλ` (tested).
//!
//! **Range.** Only light inside the spectral range is transported: with the
//! default 360–830 nm an optical brightener is excited by its absorption
//! band above 360 nm only (a UV lamp's output below 360 nm does not exist
//! in the render). The built-in brightener absorbs at 375 nm, inside it.
//!
//! Data: [`BRIGHTENER`] and [`FLUORESCEIN`], analytic fits to published
//! peaks (sources in `data/README.md`, parameters in
//! `data/fluorophores.csv`).

use crate::{SpectralError, SpectralRange};

/// One absorption or emission band: an asymmetric Gaussian in wavelength,
/// 1 at `peak_nm`, falling to ½ at `peak_nm − blue_hwhm_nm` and
/// `peak_nm + red_hwhm_nm`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// Wavelength of the maximum, nm.
    pub peak_nm: f64,
    /// Half width at half maximum on the short-wavelength side, nm.
    pub blue_hwhm_nm: f64,
    /// Half width at half maximum on the long-wavelength side, nm.
    pub red_hwhm_nm: f64,
}

impl Band {
    /// Checks that every field is finite and positive.
    pub fn validate(&self) -> Result<(), SpectralError> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !ok(self.peak_nm) {
            return Err(SpectralError::InvalidParameter("peak_nm"));
        }
        if !ok(self.blue_hwhm_nm) || !ok(self.red_hwhm_nm) {
            return Err(SpectralError::InvalidParameter("hwhm_nm"));
        }
        Ok(())
    }

    /// `exp(−ln 2 · ((λ − peak)/hwhm)²)` with the half width of the side.
    pub fn value(&self, lambda_nm: f64) -> f64 {
        let hwhm = if lambda_nm < self.peak_nm {
            self.blue_hwhm_nm
        } else {
            self.red_hwhm_nm
        };
        let t = (lambda_nm - self.peak_nm) / hwhm;
        libm::exp(-core::f64::consts::LN_2 * t * t)
    }
}

/// A fluorophore: absorption and emission bands and the quantum yield
/// (photons out per photon absorbed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fluorophore {
    /// Absorption (excitation) band.
    pub absorption: Band,
    /// Emission band.
    pub emission: Band,
    /// Quantum yield `Φ` in [0, 1].
    pub quantum_yield: f64,
}

/// An optical brightener (fluorescent whitening agent of the benzoxazole /
/// stilbene family, BASF's Tinopal data): absorption peak 375 nm,
/// fluorescence peak 437 nm, quantum yield 0.81 (in DMF). Half widths chosen
/// so that the half-maximum points lie in the bands Siegrist et al.
/// (Ullmann's, "Optical brighteners") give: absorption 340–400 nm,
/// emission 420–470 nm (sources in `data/README.md`).
pub const BRIGHTENER: Fluorophore = Fluorophore {
    absorption: Band {
        peak_nm: 375.0,
        blue_hwhm_nm: 28.0,
        red_hwhm_nm: 20.0,
    },
    emission: Band {
        peak_nm: 437.0,
        blue_hwhm_nm: 18.0,
        red_hwhm_nm: 32.0,
    },
    quantum_yield: 0.81,
};

/// Fluorescein dianion (basic solution): absorption peak 490 nm, quantum
/// yield 0.93 (Sjöback, Nygren, Kubista 1995), emission peak 514 nm; half
/// widths fitted to the published band shapes (sources in
/// `data/README.md`).
pub const FLUORESCEIN: Fluorophore = Fluorophore {
    absorption: Band {
        peak_nm: 490.0,
        blue_hwhm_nm: 30.0,
        red_hwhm_nm: 14.0,
    },
    emission: Band {
        peak_nm: 514.0,
        blue_hwhm_nm: 12.0,
        red_hwhm_nm: 28.0,
    },
    quantum_yield: 0.93,
};

/// Bisection steps for the band crossing: 2⁻⁶⁰ of the peak distance.
const SPLIT_BISECTION_STEPS: usize = 60;

impl Fluorophore {
    /// Checks the bands, `0 ≤ Φ ≤ 1` and that emission peaks above
    /// absorption.
    pub fn validate(&self) -> Result<(), SpectralError> {
        self.absorption.validate()?;
        self.emission.validate()?;
        if !(0.0..=1.0).contains(&self.quantum_yield) {
            return Err(SpectralError::InvalidParameter("quantum_yield"));
        }
        if self.emission.peak_nm <= self.absorption.peak_nm {
            return Err(SpectralError::InvalidParameter(
                "emission peak must lie above the absorption peak",
            ));
        }
        Ok(())
    }

    /// `λ00`: where the peak-normalised bands cross between their peaks
    /// (module docs), by bisection.
    pub fn split_nm(&self) -> f64 {
        let (mut lo, mut hi) = (self.absorption.peak_nm, self.emission.peak_nm);
        for _ in 0..SPLIT_BISECTION_STEPS {
            let mid = 0.5 * (lo + hi);
            if self.absorption.value(mid) > self.emission.value(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// Grid step of the emission band's normalisation, nm.
const NORMALISATION_STEP_NM: f64 = 0.05;

/// A fluorophore layer over a spectral range: its absorptance scale and
/// the prepared split and normalisation (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluorescentLayer {
    fluorophore: Fluorophore,
    peak_absorptance: f64,
    range: SpectralRange,
    split_nm: f64,
    /// `∫_{λ00}^{λ1} e(λ) dλ`, nm.
    emission_integral_nm: f64,
}

impl FluorescentLayer {
    /// A layer absorbing `peak_absorptance` ∈ (0, 1] at the absorption
    /// peak. Errors: an invalid fluorophore or range, an absorptance out of
    /// range, or a split wavelength outside the range (no emission inside it).
    pub fn new(
        fluorophore: Fluorophore,
        peak_absorptance: f64,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        fluorophore.validate()?;
        range.validate()?;
        if !(peak_absorptance > 0.0 && peak_absorptance <= 1.0) {
            return Err(SpectralError::InvalidParameter("peak_absorptance"));
        }
        let split_nm = fluorophore.split_nm();
        if !(split_nm > range.min_nm() && split_nm < range.max_nm()) {
            return Err(SpectralError::InvalidParameter(
                "the bands cross outside the spectral range",
            ));
        }
        let steps = libm::ceil((range.max_nm() - split_nm) / NORMALISATION_STEP_NM).max(1.0);
        let h = (range.max_nm() - split_nm) / steps;
        let emission_integral_nm = (0..steps as usize)
            .map(|i| fluorophore.emission.value(split_nm + (i as f64 + 0.5) * h) * h)
            .sum();
        Ok(Self {
            fluorophore,
            peak_absorptance,
            range,
            split_nm,
            emission_integral_nm,
        })
    }

    /// The fluorophore.
    pub fn fluorophore(&self) -> &Fluorophore {
        &self.fluorophore
    }

    /// The range the layer was prepared over.
    pub fn range(&self) -> &SpectralRange {
        &self.range
    }

    /// `λ00`, nm.
    pub fn split_nm(&self) -> f64 {
        self.split_nm
    }

    /// Fraction of incident light absorbed, `a(λ) ∈ [0, 1]`.
    pub fn absorptance(&self, lambda_nm: f64) -> f64 {
        self.peak_absorptance * self.fluorophore.absorption.value(lambda_nm)
    }

    /// `x(λi)`: the absorptance below `λ00` (light that can be re-emitted).
    pub fn excitation(&self, lambda_nm: f64) -> f64 {
        if lambda_nm < self.split_nm {
            self.absorptance(lambda_nm)
        } else {
            0.0
        }
    }

    /// `ê(λo)`: the emission band on `[λ00, λ1]`, unit integral, per nm.
    pub fn emission_pdf_per_nm(&self, lambda_nm: f64) -> f64 {
        if lambda_nm >= self.split_nm && lambda_nm <= self.range.max_nm() {
            self.fluorophore.emission.value(lambda_nm) / self.emission_integral_nm
        } else {
            0.0
        }
    }

    /// `u(λo) = ê(λo) λ00/λo`, per nm: the emitted side of the kernel.
    pub fn emitted_side_per_nm(&self, lambda_o_nm: f64) -> f64 {
        self.emission_pdf_per_nm(lambda_o_nm) * self.split_nm / lambda_o_nm
    }

    /// `v(λi) = Φ x(λi) λi/λ00`: the excited side of the kernel.
    pub fn excited_side(&self, lambda_i_nm: f64) -> f64 {
        self.fluorophore.quantum_yield * self.excitation(lambda_i_nm) * lambda_i_nm / self.split_nm
    }

    /// `M(λo, λi) = u(λo) v(λi)`, per nm of `λo`.
    pub fn reradiation_per_nm(&self, lambda_o_nm: f64, lambda_i_nm: f64) -> f64 {
        self.emitted_side_per_nm(lambda_o_nm) * self.excited_side(lambda_i_nm)
    }
}

/// The operator `R` of a reradiation kernel `kernel(λo, λi)` (per nm of
/// `λo`) on the coefficients of a range (module docs), by the midpoint rule
/// on cells of at most `step_nm`: `o = R c` for incident coefficients `c`.
/// `O(G² N + G N²)` for `G` cells. Errors: an invalid range, or a step that
/// is not finite and positive.
pub fn reradiation_operator<const N: usize>(
    range: &SpectralRange,
    step_nm: f64,
    kernel: impl Fn(f64, f64) -> f64,
) -> Result<[[f64; N]; N], SpectralError> {
    range.validate()?;
    if !(step_nm.is_finite() && step_nm > 0.0) {
        return Err(SpectralError::InvalidParameter("step_nm"));
    }
    let cells = libm::ceil(range.width_nm() / step_nm).max(1.0) as usize;
    let h = range.width_nm() / cells as f64;
    let at = |cell: usize| range.min_nm() + (cell as f64 + 0.5) * h;
    let mut operator = [[0.0; N]; N];
    for o in 0..cells {
        let lambda_o = at(o);
        // t_j(λo) = ∫ M(λo, λi) b_j(λi) dλi
        let mut t = [0.0; N];
        for i in 0..cells {
            let lambda_i = at(i);
            let m = kernel(lambda_o, lambda_i) * h;
            if m == 0.0 {
                continue;
            }
            let x = range.cos_phase(lambda_i);
            let (mut prev, mut cos_j) = (1.0, x);
            t[0] += m;
            for tj in t.iter_mut().skip(1) {
                *tj += 2.0 * m * cos_j;
                let next = 2.0 * x * cos_j - prev;
                prev = cos_j;
                cos_j = next;
            }
        }
        let x = range.cos_phase(lambda_o);
        let (mut cos_prev, mut cos_k) = (1.0, 1.0);
        for (k, row) in operator.iter_mut().enumerate() {
            let weight = cos_k * h / range.width_nm();
            for (r, &tj) in row.iter_mut().zip(&t) {
                *r += weight * tj;
            }
            let next = if k == 0 {
                x
            } else {
                2.0 * x * cos_k - cos_prev
            };
            cos_prev = cos_k;
            cos_k = next;
        }
    }
    Ok(operator)
}

/// `o = R c`: the operator applied to incident coefficients.
pub fn apply_operator<const N: usize>(operator: &[[f64; N]; N], incident: &[f64; N]) -> [f64; N] {
    core::array::from_fn(|k| operator[k].iter().zip(incident).map(|(r, c)| r * c).sum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::{project_function, project_function_panels};

    fn layers() -> [FluorescentLayer; 2] {
        [BRIGHTENER, FLUORESCEIN].map(|f| {
            let Ok(layer) = FluorescentLayer::new(f, 0.9, SpectralRange::VISIBLE) else {
                panic!("layer");
            };
            layer
        })
    }

    /// Re-emitted energy ≤ absorbed energy × Φ, wavelength by wavelength,
    /// on a 0.1 nm grid; and the emission pdf integrates to 1.
    #[test]
    fn reemitted_energy_is_at_most_the_absorbed_energy_times_the_quantum_yield() {
        for layer in layers() {
            let h = 0.1;
            let grid = |lo: f64, hi: f64| {
                let n = ((hi - lo) / h) as usize;
                (0..n).map(move |i| lo + (i as f64 + 0.5) * h)
            };
            let total: f64 = grid(360.0, 830.0)
                .map(|l| layer.emission_pdf_per_nm(l) * h)
                .sum();
            assert!((total - 1.0).abs() < 1e-3, "{total}");
            for lambda_i in grid(360.0, 830.0).step_by(7) {
                let out: f64 = grid(360.0, 830.0)
                    .map(|lo| layer.reradiation_per_nm(lo, lambda_i) * h)
                    .sum();
                let bound = layer.fluorophore().quantum_yield * layer.absorptance(lambda_i);
                assert!(
                    out <= bound * (1.0 + 1e-3) + 1e-12,
                    "{lambda_i}: {out} > {bound}"
                );
                // The energy ratio λi/λo < 1 makes the inequality strict
                // wherever light is re-emitted.
                if out > 0.0 {
                    assert!(out < bound);
                }
            }
        }
    }

    /// `M(λo, λi) = 0` whenever `λo < λi` (dense check), and the operator
    /// maps light that lies wholly above `λ00` to zero.
    #[test]
    fn energy_never_moves_to_shorter_wavelengths() {
        for layer in layers() {
            for i in 0..470 {
                for o in 0..470 {
                    let (lambda_i, lambda_o) = (360.5 + i as f64, 360.5 + o as f64);
                    if lambda_o < lambda_i {
                        assert_eq!(layer.reradiation_per_nm(lambda_o, lambda_i), 0.0);
                    }
                }
            }
            let range = SpectralRange::VISIBLE;
            let Ok(op) =
                reradiation_operator::<16>(&range, 0.5, |o, i| layer.reradiation_per_nm(o, i))
            else {
                panic!("operator");
            };
            // Red light, zero below 600 nm (well above both splits): its
            // truncated series rings below λ00, and only that ringing can
            // be re-emitted: |∫ L_o| ≤ ∫ u · ∫ v |series| (quadrature).
            let red = project_function::<16>(&range, |l| if l > 600.0 { 1.0 } else { 0.0 });
            let series = |c: &[f64; 16], l: f64| {
                let x = range.phase(l);
                c[0] + 2.0 * (1..16).map(|j| c[j] * libm::cos(j as f64 * x)).sum::<f64>()
            };
            let h = 0.05;
            let cells = (range.width_nm() / h) as usize;
            let at = |i: usize| range.min_nm() + (i as f64 + 0.5) * h;
            let u_integral: f64 = (0..cells)
                .map(|i| layer.emitted_side_per_nm(at(i)) * h)
                .sum();
            let ringing: f64 = (0..cells)
                .map(|i| layer.excited_side(at(i)) * series(&red.coeffs, at(i)).abs() * h)
                .sum();
            let red_out = apply_operator(&op, &red.coeffs)[0] * range.width_nm();
            assert!(
                red_out.abs() <= 1.01 * u_integral * ringing,
                "{red_out} vs {}",
                u_integral * ringing
            );
            // UV-blue light of the same power is re-emitted, a hundred
            // times more than the red light's ringing.
            let blue =
                project_function::<16>(&range, |l| if l < 360.0 + 230.0 { 1.0 } else { 0.0 });
            let blue_out = apply_operator(&op, &blue.coeffs)[0] * range.width_nm();
            assert!(blue_out > 100.0 * red_out.abs(), "{blue_out} vs {red_out}");
        }
    }

    /// The operator of the separable kernel is the outer product `ũ ṽᵀ`
    /// (module docs), and the operator applied to a box of light equals
    /// the projection of `∫ M(λo, λi) L(λi) dλi` done by quadrature
    /// independently (Gauss–Legendre in `λo`, a fine midpoint rule in `λi`).
    #[test]
    fn operator_matches_its_factors_and_quadrature() {
        const N: usize = 12;
        let range = SpectralRange::VISIBLE;
        for layer in layers() {
            // The kernel jumps at λ00, where the midpoint rule errs by
            // O(step): 0.125 nm keeps that below the tolerance.
            let Ok(op) =
                reradiation_operator::<N>(&range, 0.125, |o, i| layer.reradiation_per_nm(o, i))
            else {
                panic!("operator");
            };
            // The factors are discontinuous at λ00: fine panels (0.05 nm).
            let panels = 9400;
            let u = project_function_panels::<N>(&range, panels, |l| layer.emitted_side_per_nm(l));
            let v = project_function_panels::<N>(&range, panels, |l| layer.excited_side(l));
            let w = range.width_nm();
            for (k, (row, uk)) in op.iter().zip(&u.coeffs).enumerate() {
                for (j, (&entry, &vc)) in row.iter().zip(&v.coeffs).enumerate() {
                    let vj = if j == 0 { w * vc } else { 2.0 * w * vc };
                    let expected = uk * vj;
                    let scale = u.coeffs[0] * w * v.coeffs[0];
                    assert!(
                        (entry - expected).abs() < 2e-3 * scale,
                        "{k},{j}: {entry} vs {expected}"
                    );
                }
            }
            // A box of light 360–440 nm (coefficients by projection).
            let light = |l: f64| if l < 440.0 { 1.0 } else { 0.0 };
            let c = project_function::<N>(&range, light);
            // Radiance out by quadrature of the kernel against the
            // truncated incident series.
            let series = |l: f64| {
                let x = range.phase(l);
                c.coeffs[0]
                    + 2.0
                        * (1..N)
                            .map(|j| c.coeffs[j] * libm::cos(j as f64 * x))
                            .sum::<f64>()
            };
            let fine = 0.05;
            let cells = (w / fine) as usize;
            let out = project_function::<N>(&range, |lo| {
                (0..cells)
                    .map(|i| {
                        let li = 360.0 + (i as f64 + 0.5) * fine;
                        layer.reradiation_per_nm(lo, li) * series(li) * fine
                    })
                    .sum()
            });
            let applied = apply_operator(&op, &c.coeffs);
            for (k, (a, o)) in applied.iter().zip(&out.coeffs).enumerate() {
                assert!(
                    (a - o).abs() < 2e-3 * out.coeffs[0].abs(),
                    "{k}: {a} vs {o}"
                );
            }
        }
    }

    #[test]
    fn invalid_layers_are_rejected() {
        let range = SpectralRange::VISIBLE;
        let mut f = FLUORESCEIN;
        f.quantum_yield = 1.5;
        assert!(FluorescentLayer::new(f, 0.5, range).is_err());
        let mut f = FLUORESCEIN;
        f.emission.peak_nm = 400.0;
        assert!(FluorescentLayer::new(f, 0.5, range).is_err());
        let mut f = FLUORESCEIN;
        f.absorption.red_hwhm_nm = f64::NAN;
        assert!(FluorescentLayer::new(f, 0.5, range).is_err());
        for a in [0.0, -0.1, 1.1, f64::NAN] {
            assert!(FluorescentLayer::new(FLUORESCEIN, a, range).is_err());
        }
        assert!(reradiation_operator::<4>(&range, 0.0, |_, _| 0.0).is_err());
        // Bands that cross below 360 nm.
        let mut f = BRIGHTENER;
        f.absorption.peak_nm = 300.0;
        f.emission.peak_nm = 340.0;
        assert!(FluorescentLayer::new(f, 0.5, range).is_err());
    }

    /// The constants are the parameters of `data/fluorophores.csv`.
    #[test]
    fn constants_match_the_data_file() {
        let text = include_str!("../../data/fluorophores.csv");
        let rows: std::vec::Vec<&str> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("name"))
            .collect();
        assert_eq!(rows.len(), 2);
        for row in rows {
            let fields: std::vec::Vec<&str> = row.split(',').collect();
            let Ok(numbers) = fields[1..]
                .iter()
                .map(|f| f.trim().parse::<f64>())
                .collect::<Result<std::vec::Vec<f64>, _>>()
            else {
                panic!("{row}");
            };
            let f = match fields[0] {
                "brightener" => BRIGHTENER,
                "fluorescein" => FLUORESCEIN,
                other => panic!("{other}"),
            };
            let expected = [
                f.absorption.peak_nm,
                f.absorption.blue_hwhm_nm,
                f.absorption.red_hwhm_nm,
                f.emission.peak_nm,
                f.emission.blue_hwhm_nm,
                f.emission.red_hwhm_nm,
                f.quantum_yield,
            ];
            assert_eq!(numbers, expected, "{row}");
        }
    }

    /// The split lies between the peaks where the bands are equal.
    #[test]
    fn split_is_the_band_crossing() {
        for f in [BRIGHTENER, FLUORESCEIN] {
            let s = f.split_nm();
            assert!(s > f.absorption.peak_nm && s < f.emission.peak_nm);
            assert!((f.absorption.value(s) - f.emission.value(s)).abs() < 1e-12);
        }
    }
}
