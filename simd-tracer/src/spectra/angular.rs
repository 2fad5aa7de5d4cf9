//! Spectra that depend on an angle: Fresnel reflectances of conductors and
//! dielectrics and thin-film stacks, in both representations.
//!
//! Each [`AngularSpectrum`] keeps
//! * the exact function `F(cos θ, λ)` (computed from the original data at
//!   every wavelength: sampled transports evaluate it exactly), and
//! * a `FourierTable<32, 180>` of the core (paper §4, MATH.md §5): 180 rows
//!   over `cos θ ∈ [0, 1]`, each the exact projection of the function sampled
//!   at 1 nm; Fourier transports interpolate the rows and keep the first `N`
//!   coefficients. Memory: 32 · 180 · 4 B = 23 KB per table.
//!
//! A film whose thickness comes from a texture carries one such table per
//! thickness on an even grid ([`FILM_THICKNESS_ROWS`]) and interpolates
//! bilinearly in (cos θ, thickness); the sampled transports evaluate the
//! stack at the texel's exact thickness.

use crate::spectra::{MAX_COEFFS, SceneSpectrum};
use spectral_core::FourierBasis;
use spectral_core::complex::Complex;
use spectral_core::neural::SineMlp;
use spectral_core::optics::{Layer, fresnel_conductor, fresnel_dielectric, multilayer};
use spectral_core::table::{FilmQuantity, FilmSide, FourierTable};
use spectral_core::{SpectralError, SpectralRange};

/// Rows of every angular table (cos θ from 0 to 1).
pub const ANGLE_ROWS: usize = 180;
/// Thickness rows of a textured-thickness film table.
pub const FILM_THICKNESS_ROWS: usize = 32;
/// Wavelength at which dispersive media set directions in Fourier mode, nm.
pub const REFERENCE_WAVELENGTH_NM: f64 = 550.0;

/// A (possibly dispersive) real index of refraction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ior {
    /// The same at every wavelength.
    Constant(f64),
    /// Cauchy: `n(λ) = a + b/λ²`, `λ` in µm.
    Cauchy {
        /// `a`.
        a: f64,
        /// `b`, µm².
        b: f64,
    },
    /// Sellmeier: `n² = 1 + Σ B_i λ²/(λ² − C_i)`, `λ` in µm, `C_i` in µm².
    Sellmeier {
        /// `B_1 … B_3`.
        b: [f64; 3],
        /// `C_1 … C_3`, µm².
        c: [f64; 3],
    },
}

impl Ior {
    /// Schott N-BK7 (Sellmeier coefficients from the Schott data sheet).
    pub const BK7: Self = Self::Sellmeier {
        b: [1.039_612_12, 0.231_792_344, 1.010_469_45],
        c: [0.006_000_698_67, 0.020_017_914_4, 103.560_653],
    };

    /// `n(λ)`.
    pub fn at(&self, lambda_nm: f64) -> f64 {
        let l_um = lambda_nm * 1e-3;
        match *self {
            Self::Constant(n) => n,
            Self::Cauchy { a, b } => a + b / (l_um * l_um),
            Self::Sellmeier { b, c } => {
                let l2 = l_um * l_um;
                let sum: f64 = (0..3).map(|i| b[i] * l2 / (l2 - c[i])).sum();
                (1.0 + sum).sqrt()
            }
        }
    }

    /// Whether `n` varies with wavelength.
    pub fn is_dispersive(&self) -> bool {
        !matches!(self, Self::Constant(_))
    }

    /// Checks that `n(λ)` is finite and ≥ 1 over `range`.
    pub fn validate(&self, range: &SpectralRange) -> Result<(), SpectralError> {
        let steps = 94;
        for i in 0..=steps {
            let l = range.min_nm() + range.width_nm() * i as f64 / steps as f64;
            let n = self.at(l);
            if !(n.is_finite() && n >= 1.0) {
                return Err(SpectralError::InvalidParameter(
                    "index of refraction (must be finite and >= 1)",
                ));
            }
        }
        Ok(())
    }
}

/// A homogeneous film layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilmLayer {
    /// Real index (dispersion allowed).
    pub ior: Ior,
    /// Extinction coefficient `k` (constant).
    pub k: f64,
    /// Thickness, nm.
    pub thickness_nm: f64,
}

macro_rules! networks {
    ($($variant:ident: $inputs:literal, $hidden:literal, $outputs:literal;)*) => {
        /// A trained sine MLP of one of the supported shapes (inputs
        /// `cos θ` [and a film thickness in nm], hidden width, outputs).
        #[derive(Debug, Clone, PartialEq)]
        pub enum Network {
            $(
                #[doc = concat!(stringify!($inputs), " input(s), ", stringify!($hidden), " hidden, ", stringify!($outputs), " coefficients")]
                $variant(Box<SineMlp<$inputs, $hidden, $outputs>>),
            )*
        }

        impl Network {
            /// Parses a network file of any supported shape.
            pub fn from_bytes(bytes: &[u8]) -> Result<Self, SpectralError> {
                $(
                    if let Ok(net) = SineMlp::<$inputs, $hidden, $outputs>::from_bytes(bytes) {
                        return Ok(Self::$variant(Box::new(net)));
                    }
                )*
                // Report the specific problem for the most common shape.
                SineMlp::<1, 10, 10>::from_bytes(bytes).map(|net| Self::In1H10N10(Box::new(net))).map_err(|e| match e {
                    SpectralError::InvalidParameter("network shape differs from the expected one") => SpectralError::InvalidParameter(
                        "network shape not supported (inputs 1-2, hidden 10 or 16, outputs 10, 12 or 16)",
                    ),
                    other => other,
                })
            }

            /// Number of inputs.
            pub fn inputs(&self) -> usize {
                match self {
                    $(Self::$variant(_) => $inputs,)*
                }
            }

            /// Number of output coefficients.
            pub fn outputs(&self) -> usize {
                match self {
                    $(Self::$variant(_) => $outputs,)*
                }
            }

            /// The spectral range of the outputs.
            pub fn range(&self) -> SpectralRange {
                match self {
                    $(Self::$variant(net) => net.range,)*
                }
            }

            /// The coefficients at `cos θ` and thickness (nm; ignored by
            /// one-input networks).
            pub fn eval(&self, cos_theta: f32, thickness_nm: f32) -> [f32; MAX_COEFFS] {
                let mut out = [0.0f32; MAX_COEFFS];
                match self {
                    $(Self::$variant(net) => {
                        let input: [f32; $inputs] = core::array::from_fn(|i| if i == 0 { cos_theta } else { thickness_nm });
                        let c = net.eval::<f32>(input);
                        out[..$outputs].copy_from_slice(&c.coeffs);
                    })*
                }
                out
            }

            /// The interval input `index` was trained on, read from its
            /// normalisation `x' = (x − offset)·scale` (which maps it to
            /// [−1, 1]); `None` for a missing input or a zero scale.
            pub fn trained_input_range(&self, index: usize) -> Option<(f32, f32)> {
                let (offset, scale) = match self {
                    $(Self::$variant(net) => *net.normalisation.get(index)?,)*
                };
                (scale != 0.0).then(|| {
                    let half = (1.0 / scale).abs();
                    (offset - half, offset + half)
                })
            }

            /// Bytes of weights.
            pub fn weight_bytes(&self) -> usize {
                match self {
                    $(Self::$variant(_) => SineMlp::<$inputs, $hidden, $outputs>::weight_bytes(),)*
                }
            }
        }
    };
}

networks! {
    In1H10N10: 1, 10, 10;
    In1H10N12: 1, 10, 12;
    In1H10N16: 1, 10, 16;
    In1H16N10: 1, 16, 10;
    In1H16N12: 1, 16, 12;
    In1H16N16: 1, 16, 16;
    In2H10N10: 2, 10, 10;
    In2H10N12: 2, 10, 12;
    In2H10N16: 2, 10, 16;
    In2H16N10: 2, 16, 10;
    In2H16N12: 2, 16, 12;
    In2H16N16: 2, 16, 16;
}

/// The exact angular function.
#[derive(Debug, Clone, PartialEq)]
pub enum AngularFunction {
    /// Conductor Fresnel reflectance from `n(λ)`, `k(λ)` scene spectra seen
    /// from a medium of index `outside`, times an optional tint `s(λ)`:
    /// `s(λ) F(cos θ, λ)` (Mitsuba's `specular_reflectance` of its
    /// conductors, src/bsdfs/conductor.cpp: a factor on the Fresnel term;
    /// with `n = 0`, `k = 1`, where `F = 1`, the tint alone).
    Conductor {
        /// Real part.
        n: Box<SceneSpectrum>,
        /// Imaginary part.
        k: Box<SceneSpectrum>,
        /// Outside index.
        outside: f64,
        /// The factor `s(λ)` (`None`: 1).
        tint: Option<Box<SceneSpectrum>>,
    },
    /// Dielectric Fresnel reflectance, lit from outside or from inside.
    Dielectric {
        /// `n_inside / n_outside`.
        ior: Ior,
        /// Lit from the denser side.
        from_inside: bool,
    },
    /// Thin-film stack on a substrate (first layer nearest the incident medium).
    Film {
        /// Layers.
        layers: Vec<FilmLayer>,
        /// Substrate index `n + ik` (real part may be dispersive).
        substrate: Ior,
        /// Substrate extinction.
        substrate_k: f64,
        /// Incident medium index.
        incident: f64,
        /// Reflectance or transmittance.
        quantity: FilmQuantity,
        /// Lit from the front or from the substrate.
        side: FilmSide,
        /// Thickness range of layer 0 when it comes from a texture.
        thickness_range_nm: Option<(f64, f64)>,
    },
    /// A trained network that outputs the coefficients (paper §4); the
    /// network *is* the representation: sampled transports evaluate its
    /// series at each wavelength.
    Neural {
        /// The network.
        network: Network,
        /// Thickness range (nm) a [0, 1] texture value maps into, for
        /// two-input (parametric film) networks.
        thickness_range_nm: (f64, f64),
    },
}

impl AngularFunction {
    /// `F(cos θ, λ)`; `thickness_nm` overrides layer 0 of a film (textures).
    pub fn eval(&self, cos_theta: f64, lambda_nm: f64, thickness_nm: Option<f64>) -> f64 {
        match self {
            Self::Conductor {
                n,
                k,
                outside,
                tint,
            } => {
                let index = Complex::new(
                    f64::from(n.value(lambda_nm as f32)),
                    f64::from(k.value(lambda_nm as f32)),
                );
                let scale = tint
                    .as_ref()
                    .map_or(1.0, |t| f64::from(t.value(lambda_nm as f32)));
                scale * fresnel_conductor(cos_theta, index.scale(1.0 / outside))
            }
            Self::Dielectric { ior, from_inside } => {
                let sign = if *from_inside { -1.0 } else { 1.0 };
                fresnel_dielectric(sign * cos_theta, ior.at(lambda_nm))
            }
            Self::Film {
                layers,
                substrate,
                substrate_k,
                incident,
                quantity,
                side,
                ..
            } => {
                let mut stack = [Layer {
                    index: Complex::ONE,
                    thickness_nm: 0.0,
                }; spectral_core::table::MAX_LAYERS];
                let count = layers.len().min(stack.len());
                for (slot, layer) in stack.iter_mut().zip(layers) {
                    *slot = Layer {
                        index: Complex::new(layer.ior.at(lambda_nm), layer.k),
                        thickness_nm: layer.thickness_nm,
                    };
                }
                if let (Some(t), Some(first)) = (thickness_nm, stack.first_mut()) {
                    first.thickness_nm = t;
                }
                let substrate = Complex::new(substrate.at(lambda_nm), *substrate_k);
                let stack = &mut stack[..count];
                let response = match side {
                    FilmSide::Front => {
                        multilayer(lambda_nm, *incident, stack, substrate, cos_theta)
                    }
                    FilmSide::Back => {
                        stack.reverse();
                        multilayer(
                            lambda_nm,
                            substrate.re,
                            stack,
                            Complex::real(*incident),
                            cos_theta,
                        )
                    }
                };
                match quantity {
                    FilmQuantity::Reflectance => response.reflectance(),
                    FilmQuantity::Transmittance => response.transmittance(),
                }
            }
            Self::Neural {
                network,
                thickness_range_nm,
            } => {
                let range = network.range();
                let t = thickness_nm.unwrap_or(thickness_range_nm.0);
                let c = network.eval(cos_theta as f32, t as f32);
                let series: spectral_core::FourierSpectrum<f64, MAX_COEFFS> =
                    spectral_core::FourierSpectrum::from_coeffs(c.map(f64::from));
                series.eval(&FourierBasis::new(range), lambda_nm).max(0.0)
            }
        }
    }
}

/// An angular spectrum with its Fourier table(s).
#[derive(Debug, Clone)]
pub struct AngularSpectrum {
    function: AngularFunction,
    /// One table, or one per thickness row for textured films.
    tables: Vec<FourierTable<MAX_COEFFS, ANGLE_ROWS>>,
}

impl AngularSpectrum {
    /// Builds the table(s) of `function` over `range`.
    pub fn new(function: AngularFunction, range: &SpectralRange) -> Result<Self, SpectralError> {
        if let AngularFunction::Film {
            layers,
            thickness_range_nm,
            substrate,
            ..
        } = &function
        {
            if layers.is_empty() || layers.len() > spectral_core::table::MAX_LAYERS {
                return Err(SpectralError::InvalidParameter("film layers (1 to 16)"));
            }
            substrate.validate(range)?;
            for layer in layers {
                layer.ior.validate(range)?;
                if !(layer.k.is_finite()
                    && layer.k >= 0.0
                    && layer.thickness_nm.is_finite()
                    && layer.thickness_nm >= 0.0)
                {
                    return Err(SpectralError::InvalidParameter(
                        "film layer k and thickness (finite, >= 0)",
                    ));
                }
            }
            if let Some((lo, hi)) = thickness_range_nm {
                if !(lo.is_finite() && hi.is_finite() && *lo >= 0.0 && lo < hi) {
                    return Err(SpectralError::InvalidParameter("film thickness range"));
                }
            }
        }
        if let AngularFunction::Dielectric { ior, .. } = &function {
            ior.validate(range)?;
        }
        if let AngularFunction::Neural {
            network,
            thickness_range_nm: (lo, hi),
        } = &function
        {
            if network.range() != *range {
                return Err(SpectralError::InvalidParameter(
                    "the network's spectral range differs from the scene's",
                ));
            }
            if !(lo.is_finite() && hi.is_finite() && *lo >= 0.0 && lo <= hi) {
                return Err(SpectralError::InvalidParameter("network thickness range"));
            }
            return Ok(Self {
                function,
                tables: Vec::new(),
            });
        }
        let thicknesses: Vec<Option<f64>> = match &function {
            AngularFunction::Film {
                thickness_range_nm: Some((lo, hi)),
                ..
            } => (0..FILM_THICKNESS_ROWS)
                .map(|i| Some(lo + (hi - lo) * i as f64 / (FILM_THICKNESS_ROWS - 1) as f64))
                .collect(),
            _ => vec![None],
        };
        let tables = thicknesses
            .into_iter()
            .map(|t| FourierTable::build(range, 0.0, 1.0, |cos, l| function.eval(cos, l, t)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { function, tables })
    }

    /// The exact function.
    pub fn function(&self) -> &AngularFunction {
        &self.function
    }

    /// `F(cos θ, λ)` exactly (`thickness01` ∈ [0, 1] selects the thickness of
    /// a textured film within its range).
    pub fn eval(&self, cos_theta: f32, lambda_nm: f32, thickness01: f32) -> f32 {
        let thickness = match &self.function {
            AngularFunction::Film {
                thickness_range_nm: Some((lo, hi)),
                ..
            }
            | AngularFunction::Neural {
                thickness_range_nm: (lo, hi),
                ..
            } => Some(lo + (hi - lo) * f64::from(thickness01.clamp(0.0, 1.0))),
            _ => None,
        };
        self.function
            .eval(f64::from(cos_theta), f64::from(lambda_nm), thickness) as f32
    }

    /// The Fourier coefficients at `cos θ` (and thickness), all 32.
    pub fn fourier(&self, cos_theta: f32, thickness01: f32) -> [f32; MAX_COEFFS] {
        if let AngularFunction::Neural {
            network,
            thickness_range_nm: (lo, hi),
        } = &self.function
        {
            let t = lo + (hi - lo) * f64::from(thickness01.clamp(0.0, 1.0));
            return network.eval(cos_theta, t as f32);
        }
        let cos = f64::from(cos_theta);
        if self.tables.len() <= 1 {
            return self
                .tables
                .first()
                .map_or([0.0; MAX_COEFFS], |t| t.lookup(cos).coeffs);
        }
        let x = f64::from(thickness01.clamp(0.0, 1.0)) * (self.tables.len() - 1) as f64;
        let i = (x as usize).min(self.tables.len() - 2);
        let t = (x - i as f64) as f32;
        let (a, b) = (
            self.tables[i].lookup(cos).coeffs,
            self.tables[i + 1].lookup(cos).coeffs,
        );
        core::array::from_fn(|j| a[j] + t * (b[j] - a[j]))
    }

    /// The mean over wavelengths (`c_0`) at `cos θ`: the reflect/refract
    /// probability of dielectric-like interfaces.
    pub fn mean(&self, cos_theta: f32, thickness01: f32) -> f32 {
        self.fourier(cos_theta, thickness01)[0]
    }

    /// Bytes of Fourier tables, or of network weights.
    pub fn table_bytes(&self) -> usize {
        match &self.function {
            AngularFunction::Neural { network, .. } => network.weight_bytes(),
            _ => self.tables.len() * FourierTable::<MAX_COEFFS, ANGLE_ROWS>::memory_bytes(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::SpectrumSource;
    use spectral_core::registry::Builtin;

    #[test]
    fn bk7_index() {
        // Schott data sheet: n_d (587.56 nm) = 1.5168.
        assert!((Ior::BK7.at(587.56) - 1.5168).abs() < 1e-4);
        assert!(Ior::BK7.at(400.0) > Ior::BK7.at(700.0));
        assert!(
            Ior::Constant(0.5)
                .validate(&SpectralRange::VISIBLE)
                .is_err()
        );
        let cauchy = Ior::Cauchy { a: 1.5, b: 0.004 };
        assert!((cauchy.at(500.0) - 1.516).abs() < 1e-12);
    }

    /// A tint multiplies the conductor's Fresnel term at every angle and
    /// wavelength, exactly and in the Fourier table; without the tint the
    /// values differ (the negative control).
    #[test]
    fn a_tint_multiplies_the_fresnel_term() -> Result<(), SpectralError> {
        let range = SpectralRange::VISIBLE;
        let spectrum = |name: &str| -> Result<Box<SceneSpectrum>, SpectralError> {
            let builtin =
                Builtin::lookup(name).map_err(|_| SpectralError::InvalidParameter("builtin"))?;
            Ok(Box::new(SceneSpectrum::new(
                SpectrumSource::Builtin(builtin),
                range,
            )?))
        };
        let ramp = SceneSpectrum::new(
            SpectrumSource::Tabulated {
                lambda_nm: vec![360.0, 830.0],
                values: vec![0.2, 0.9],
            },
            range,
        )?;
        let conductor =
            |tint: Option<Box<SceneSpectrum>>| -> Result<AngularSpectrum, SpectralError> {
                AngularSpectrum::new(
                    AngularFunction::Conductor {
                        n: spectrum("copper-n")?,
                        k: spectrum("copper-k")?,
                        outside: 1.0,
                        tint,
                    },
                    &range,
                )
            };
        let (plain, tinted) = (conductor(None)?, conductor(Some(Box::new(ramp.clone())))?);
        for cos in [1.0f32, 0.6, 0.2] {
            for lambda in [420.0f32, 550.0, 680.0] {
                let expected = ramp.value(lambda) * plain.eval(cos, lambda, 0.0);
                let got = tinted.eval(cos, lambda, 0.0);
                assert!((got - expected).abs() < 1e-6, "{got} vs {expected}");
                assert!((plain.eval(cos, lambda, 0.0) - got).abs() > 1e-3);
            }
            // The table is the projection of the product.
            let series = |table: &AngularSpectrum| {
                let c = table.fourier(cos, 0.0);
                spectral_core::FourierSpectrum::<f32, 16>::from_coeffs(core::array::from_fn(|j| {
                    c[j]
                }))
            };
            let at = series(&tinted).eval(&FourierBasis::new(range), 550.0);
            let exact = tinted.eval(cos, 550.0, 0.0);
            assert!((at - exact).abs() < 0.02, "{at} vs {exact}");
        }
        Ok(())
    }

    #[test]
    fn gold_table_matches_exact_fresnel_at_normal_incidence() {
        let range = SpectralRange::VISIBLE;
        let n = SceneSpectrum::new(
            SpectrumSource::Builtin(Builtin::lookup("gold-n").unwrap()),
            range,
        )
        .unwrap();
        let k = SceneSpectrum::new(
            SpectrumSource::Builtin(Builtin::lookup("gold-k").unwrap()),
            range,
        )
        .unwrap();
        let (n551, k551) = (f64::from(n.value(551.0)), f64::from(k.value(551.0)));
        let gold = AngularSpectrum::new(
            AngularFunction::Conductor {
                n: Box::new(n),
                k: Box::new(k),
                outside: 1.0,
                tint: None,
            },
            &range,
        )
        .unwrap();
        // Normal incidence: R = ((n−1)² + k²)/((n+1)² + k²) with Johnson &
        // Christy's n, k interpolated at 551 nm.
        let closed_form =
            ((n551 - 1.0).powi(2) + k551 * k551) / ((n551 + 1.0).powi(2) + k551 * k551);
        let exact = gold.eval(1.0, 551.0, 0.0);
        assert!(
            (f64::from(exact) - closed_form).abs() < 1e-6,
            "{exact} vs {closed_form}"
        );
        let coeffs = gold.fourier(1.0, 0.0);
        let series: spectral_core::FourierSpectrum<f32, 16> =
            spectral_core::FourierSpectrum::from_coeffs(core::array::from_fn(|j| coeffs[j]));
        let at = series.eval(&FourierBasis::new(range), 551.0);
        assert!((at - exact).abs() < 0.02, "{at} vs {exact}");
        assert!(gold.table_bytes() == 32 * 180 * 4);
    }
}
