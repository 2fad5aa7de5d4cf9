//! `fspec train`: fits the paper's small sine MLP (figure 2) to a thin
//! film's Fresnel reflectance, on the CPU, seeded and reproducible.
//!
//! * Target: the exact Airy reflectance `R(cos θ, λ)` of a film (index
//!   `--film-ior`, `--thickness-nm`, on a `--substrate-ior` substrate, in
//!   air), projected to `N` Fourier coefficients on a 1 nm grid
//!   (`spectral_core::table`'s projection). With `--param
//!   thickness:LO..HI` the thickness becomes a second input.
//! * Network: inputs → `H` sine neurons → `H` sine neurons → `N` linear
//!   outputs; SIREN initialisation (Sitzmann et al. 2020) with
//!   `ω₀ = 4` folded into the first layer.
//! * Loss: `L = mean_batch [ (1/K) ‖B (c − c*)‖² + β (1/N) ‖c − c*‖² ]`, the
//!   squared error of the reconstructed spectrum at `K = 48` wavelengths
//!   (`B` the series basis) plus a coefficient term (`β = 0.1`) that keeps
//!   high-order coefficients from drifting where the basis is blind.
//! * Optimiser: Adam (lr 2·10⁻³ decaying to 10⁻⁴, β₁ 0.9, β₂ 0.999), batches
//!   of 128 fresh random inputs per step from a pool of precomputed exact
//!   targets; hand-written backpropagation, guarded by a finite-difference
//!   gradient test.
//!
//! The result is written in `spectral_core::neural`'s byte format.

use crate::error::CliError;
use crate::image_out::write_atomically;
use spectral_core::SpectralRange;
use spectral_core::complex::Complex;
use spectral_core::optics::{Layer, multilayer};
use spectral_core::table::FourierTable;
use std::io::Write;
use std::path::PathBuf;

/// Wavelengths of the reconstruction loss.
const LOSS_WAVELENGTHS: usize = 48;
/// Weight of the coefficient term.
const COEFFICIENT_WEIGHT: f64 = 0.1;
/// First-layer frequency.
const OMEGA_0: f64 = 4.0;

/// Arguments of `fspec train thin-film`.
#[derive(Debug, Clone, clap::Args)]
pub struct TrainArgs {
    /// What to fit (only `thin-film`).
    #[arg(value_parser = ["thin-film"])]
    pub material: String,
    /// Film thickness, nm (ignored with --param thickness:…).
    #[arg(long, default_value_t = 400.0)]
    pub thickness_nm: f64,
    /// Film index of refraction.
    #[arg(long, default_value_t = 2.0)]
    pub film_ior: f64,
    /// Substrate index of refraction.
    #[arg(long, default_value_t = 1.5)]
    pub substrate_ior: f64,
    /// Fourier coefficients N the network outputs (1–32).
    #[arg(long, default_value_t = 10)]
    pub coeffs: usize,
    /// Neurons per hidden layer (1–64).
    #[arg(long, default_value_t = 10)]
    pub hidden: usize,
    /// A second input, `thickness:LO..HI` (nm): a parametric film.
    #[arg(long)]
    pub param: Option<String>,
    /// Optimisation steps.
    #[arg(long, default_value_t = 20_000)]
    pub steps: usize,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output file.
    #[arg(long, default_value = "film.nn")]
    pub out: PathBuf,
    /// Also write the evidence of the paper's figure 3 into this folder:
    /// `tables.png` (explicit, Fourier-table and network reflectance tables
    /// side by side, then 10 × the network's error) and `evidence.md`
    /// (max/RMS error, ΔE2000 under D65, memory).
    #[arg(long)]
    pub evidence: Option<PathBuf>,
}

/// The film of a training run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilmSpec {
    /// Film index.
    pub film_ior: f64,
    /// Substrate index.
    pub substrate_ior: f64,
    /// Thickness range, nm (equal ends: fixed thickness).
    pub thickness_nm: (f64, f64),
}

impl FilmSpec {
    /// Unpolarised reflectance from air at `cos θ`, `λ`, thickness `t`.
    pub fn reflectance(&self, cos_theta: f64, lambda_nm: f64, thickness_nm: f64) -> f64 {
        let layer = Layer {
            index: Complex::real(self.film_ior),
            thickness_nm,
        };
        multilayer(
            lambda_nm,
            1.0,
            &[layer],
            Complex::real(self.substrate_ior),
            cos_theta,
        )
        .reflectance()
    }

    /// Whether the thickness is an input.
    pub fn parametric(&self) -> bool {
        self.thickness_nm.0 != self.thickness_nm.1
    }
}

/// A dense MLP `in → h → h → out` with sine hidden activations, in f64.
#[derive(Debug, Clone, PartialEq)]
pub struct Mlp {
    /// Inputs.
    pub inputs: usize,
    /// Hidden width.
    pub hidden: usize,
    /// Outputs.
    pub outputs: usize,
    /// All parameters: W1, b1, W2, b2, W3, b3 (row-major weights).
    pub params: Vec<f64>,
    /// Input `(offset, scale)`.
    pub normalisation: Vec<(f64, f64)>,
}

/// xorshift64* — the trainer's seeded generator.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Intermediate values of a forward pass (for backpropagation).
struct Forward {
    x: Vec<f64>,
    z1: Vec<f64>,
    h1: Vec<f64>,
    z2: Vec<f64>,
    h2: Vec<f64>,
    out: Vec<f64>,
}

impl Mlp {
    /// SIREN-initialised network.
    pub fn new(
        inputs: usize,
        hidden: usize,
        outputs: usize,
        normalisation: Vec<(f64, f64)>,
        rng: &mut Rng,
    ) -> Self {
        let mut params = Vec::with_capacity(Self::count(inputs, hidden, outputs));
        let mut uniform = |n: usize, bound: f64, params: &mut Vec<f64>| {
            for _ in 0..n {
                params.push((2.0 * rng.unit() - 1.0) * bound);
            }
        };
        uniform(hidden * inputs, OMEGA_0 / inputs as f64, &mut params);
        uniform(hidden, 1.0 / (inputs as f64).sqrt(), &mut params);
        let hidden_bound = (6.0 / hidden as f64).sqrt();
        uniform(hidden * hidden, hidden_bound, &mut params);
        uniform(hidden, 1.0 / (hidden as f64).sqrt(), &mut params);
        uniform(outputs * hidden, hidden_bound * 0.1, &mut params);
        params.extend(std::iter::repeat_n(0.0, outputs));
        Self {
            inputs,
            hidden,
            outputs,
            params,
            normalisation,
        }
    }

    /// Number of parameters of a shape.
    pub fn count(inputs: usize, hidden: usize, outputs: usize) -> usize {
        hidden * inputs + hidden + hidden * hidden + hidden + outputs * hidden + outputs
    }

    /// Offsets of W1, b1, W2, b2, W3, b3 in `params`.
    fn offsets(&self) -> [usize; 6] {
        let (i, h, o) = (self.inputs, self.hidden, self.outputs);
        let w1 = 0;
        let b1 = w1 + h * i;
        let w2 = b1 + h;
        let b2 = w2 + h * h;
        let w3 = b2 + h;
        let b3 = w3 + o * h;
        [w1, b1, w2, b2, w3, b3]
    }

    fn forward(&self, input: &[f64]) -> Forward {
        let [w1, b1, w2, b2, w3, b3] = self.offsets();
        let (i, h, o) = (self.inputs, self.hidden, self.outputs);
        let p = &self.params;
        let x: Vec<f64> = input
            .iter()
            .zip(&self.normalisation)
            .map(|(v, (offset, scale))| (v - offset) * scale)
            .collect();
        let z1: Vec<f64> = (0..h)
            .map(|k| p[b1 + k] + (0..i).map(|c| p[w1 + k * i + c] * x[c]).sum::<f64>())
            .collect();
        let h1: Vec<f64> = z1.iter().map(|z| z.sin()).collect();
        let z2: Vec<f64> = (0..h)
            .map(|k| p[b2 + k] + (0..h).map(|c| p[w2 + k * h + c] * h1[c]).sum::<f64>())
            .collect();
        let h2: Vec<f64> = z2.iter().map(|z| z.sin()).collect();
        let out = (0..o)
            .map(|k| p[b3 + k] + (0..h).map(|c| p[w3 + k * h + c] * h2[c]).sum::<f64>())
            .collect();
        Forward {
            x,
            z1,
            h1,
            z2,
            h2,
            out,
        }
    }

    /// The outputs for one input.
    pub fn eval(&self, input: &[f64]) -> Vec<f64> {
        self.forward(input).out
    }

    /// Adds `∂L/∂params` for one input with output gradient `d_out` to `grad`.
    fn backward(&self, f: &Forward, d_out: &[f64], grad: &mut [f64]) {
        let [w1, b1, w2, b2, w3, b3] = self.offsets();
        let (i, h, o) = (self.inputs, self.hidden, self.outputs);
        let p = &self.params;
        let mut d_h2 = vec![0.0; h];
        for k in 0..o {
            grad[b3 + k] += d_out[k];
            for c in 0..h {
                grad[w3 + k * h + c] += d_out[k] * f.h2[c];
                d_h2[c] += d_out[k] * p[w3 + k * h + c];
            }
        }
        let d_z2: Vec<f64> = (0..h).map(|k| d_h2[k] * f.z2[k].cos()).collect();
        let mut d_h1 = vec![0.0; h];
        for k in 0..h {
            grad[b2 + k] += d_z2[k];
            for c in 0..h {
                grad[w2 + k * h + c] += d_z2[k] * f.h1[c];
                d_h1[c] += d_z2[k] * p[w2 + k * h + c];
            }
        }
        for k in 0..h {
            let d_z1 = d_h1[k] * f.z1[k].cos();
            grad[b1 + k] += d_z1;
            for c in 0..i {
                grad[w1 + k * i + c] += d_z1 * f.x[c];
            }
        }
    }

    /// The network in `spectral_core::neural`'s byte format.
    pub fn to_bytes(&self, range: &SpectralRange) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(&spectral_core::neural::MAGIC);
        out.extend_from_slice(&spectral_core::neural::VERSION.to_le_bytes());
        out.extend_from_slice(&[spectral_core::neural::ACTIVATION_SINE, 2]);
        for dim in [self.inputs, self.hidden, self.outputs, 0] {
            out.extend_from_slice(&(dim as u16).to_le_bytes());
        }
        out.extend_from_slice(&(range.min_nm() as f32).to_le_bytes());
        out.extend_from_slice(&(range.max_nm() as f32).to_le_bytes());
        for (offset, scale) in &self.normalisation {
            out.extend_from_slice(&(*offset as f32).to_le_bytes());
            out.extend_from_slice(&(*scale as f32).to_le_bytes());
        }
        for p in &self.params {
            out.extend_from_slice(&(*p as f32).to_le_bytes());
        }
        out
    }
}

/// The loss: reconstruction through the basis `B` (K × N, row-major) plus
/// the coefficient term; returns the loss and fills `d_out = ∂L/∂c`.
fn loss(basis: &[f64], n: usize, c: &[f64], target: &[f64], d_out: &mut [f64]) -> f64 {
    let k = basis.len() / n;
    let diff: Vec<f64> = c.iter().zip(target).map(|(a, b)| a - b).collect();
    let mut value = 0.0;
    d_out.iter_mut().for_each(|d| *d = 0.0);
    for row in basis.chunks_exact(n) {
        let e: f64 = row.iter().zip(&diff).map(|(b, d)| b * d).sum();
        value += e * e / k as f64;
        for (dj, b) in d_out.iter_mut().zip(row) {
            *dj += 2.0 * e * b / k as f64;
        }
    }
    for (dj, d) in d_out.iter_mut().zip(&diff) {
        value += COEFFICIENT_WEIGHT * d * d / n as f64;
        *dj += 2.0 * COEFFICIENT_WEIGHT * d / n as f64;
    }
    value
}

/// Exact targets: the film's coefficients at `(cos θ, thickness)`.
fn target<const N: usize>(
    film: &FilmSpec,
    range: &SpectralRange,
    cos: f64,
    thickness: f64,
) -> Result<Vec<f64>, CliError> {
    // A two-row table is exactly the projection of the 1 nm polyline.
    let table =
        FourierTable::<N, 2>::build(range, 0.0, 1.0, |_, l| film.reflectance(cos, l, thickness))
            .map_err(|e| CliError::input(format!("film: {e}")))?;
    Ok(table.row(0).coeffs.iter().map(|&v| f64::from(v)).collect())
}

/// A training run's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Trained {
    /// The network.
    pub network: Mlp,
    /// `(step, loss)` every 1000 steps.
    pub curve: Vec<(usize, f64)>,
}

/// Trains on `film` (N coefficients, H hidden neurons).
pub fn train<const N: usize>(
    film: &FilmSpec,
    hidden: usize,
    steps: usize,
    seed: u64,
    report: &mut dyn FnMut(usize, f64),
) -> Result<Trained, CliError> {
    let range = SpectralRange::VISIBLE;
    let mut rng = Rng::new(seed);
    let parametric = film.parametric();
    let (lo, hi) = film.thickness_nm;
    // Pool of exact samples (inputs uniform in cos θ and thickness).
    let pool_size = 4096;
    let mut pool = Vec::with_capacity(pool_size);
    for _ in 0..pool_size {
        let cos = rng.unit();
        let thickness = lo + (hi - lo) * rng.unit();
        let input = if parametric {
            vec![cos, thickness]
        } else {
            vec![cos]
        };
        pool.push((input, target::<N>(film, &range, cos, thickness)?));
    }
    let mut normalisation = vec![(0.5, 2.0)];
    if parametric {
        normalisation.push((0.5 * (lo + hi), 2.0 / (hi - lo)));
    }
    let mut net = Mlp::new(
        if parametric { 2 } else { 1 },
        hidden,
        N,
        normalisation,
        &mut rng,
    );
    // Loss basis: the series at K wavelengths.
    let basis: Vec<f64> = (0..LOSS_WAVELENGTHS)
        .flat_map(|k| {
            let lambda =
                range.min_nm() + range.width_nm() * (k as f64 + 0.5) / LOSS_WAVELENGTHS as f64;
            let phi = range.phase(lambda);
            (0..N).map(move |j| {
                if j == 0 {
                    1.0
                } else {
                    2.0 * (j as f64 * phi).cos()
                }
            })
        })
        .collect();
    let count = net.params.len();
    let (mut m, mut v) = (vec![0.0; count], vec![0.0; count]);
    let (beta1, beta2, eps) = (0.9f64, 0.999f64, 1e-8);
    let batch = 128;
    let mut grad = vec![0.0; count];
    let mut d_out = vec![0.0; N];
    let mut curve = Vec::new();
    let mut running = 0.0;
    for step in 1..=steps {
        grad.iter_mut().for_each(|g| *g = 0.0);
        let mut batch_loss = 0.0;
        for _ in 0..batch {
            let index = ((rng.unit() * pool_size as f64) as usize).min(pool_size - 1);
            let (input, tgt) = &pool[index];
            let f = net.forward(input);
            batch_loss += loss(&basis, N, &f.out, tgt, &mut d_out);
            net.backward(&f, &d_out, &mut grad);
        }
        batch_loss /= batch as f64;
        let progress = step as f64 / steps as f64;
        let lr = 2e-3 * (1.0 - progress) + 1e-4 * progress;
        for j in 0..count {
            let g = grad[j] / batch as f64;
            m[j] = beta1 * m[j] + (1.0 - beta1) * g;
            v[j] = beta2 * v[j] + (1.0 - beta2) * g * g;
            let m_hat = m[j] / (1.0 - beta1.powi(step as i32));
            let v_hat = v[j] / (1.0 - beta2.powi(step as i32));
            net.params[j] -= lr * m_hat / (v_hat.sqrt() + eps);
        }
        running += batch_loss;
        if step % 1000 == 0 || step == steps {
            let mean = running / (((step - 1) % 1000) + 1) as f64;
            curve.push((step, mean));
            report(step, mean);
            running = 0.0;
        }
        if !net.params.iter().all(|p| p.is_finite()) {
            return Err(CliError::input("training diverged (non-finite weights)"));
        }
    }
    Ok(Trained {
        network: net,
        curve,
    })
}

/// Parses `thickness:LO..HI`.
pub fn parse_param(text: &str) -> Result<(f64, f64), CliError> {
    let bad = || {
        CliError::input(format!(
            "--param {text}: expected thickness:LO..HI in nm, e.g. thickness:100..800"
        ))
    };
    let range = text.strip_prefix("thickness:").ok_or_else(bad)?;
    let (lo, hi) = range.split_once("..").ok_or_else(bad)?;
    let (lo, hi): (f64, f64) = (
        lo.trim().parse().map_err(|_| bad())?,
        hi.trim().parse().map_err(|_| bad())?,
    );
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi && hi <= 1e5) {
        return Err(bad());
    }
    Ok((lo, hi))
}

/// Runs `fspec train`, printing the training curve to `out`.
pub fn run(args: &TrainArgs, out: &mut dyn Write) -> Result<Trained, CliError> {
    let thickness = match &args.param {
        Some(p) => parse_param(p)?,
        None => (args.thickness_nm, args.thickness_nm),
    };
    let valid_ior = |v: f64| v.is_finite() && (1.0..=10.0).contains(&v);
    if !valid_ior(args.film_ior) || !valid_ior(args.substrate_ior) {
        return Err(CliError::input(
            "--film-ior and --substrate-ior must be between 1 and 10",
        ));
    }
    if !(thickness.0.is_finite() && thickness.0 >= 0.0 && thickness.1 <= 1e5) {
        return Err(CliError::input(
            "--thickness-nm must be between 0 and 100000",
        ));
    }
    if !(1..=64).contains(&args.hidden) || args.steps == 0 {
        return Err(CliError::input(
            "--hidden must be 1 to 64 and --steps at least 1",
        ));
    }
    // Fail before training, not after it.
    let parent = match args.out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if !parent.is_dir() {
        return Err(CliError::input(format!(
            "cannot write {}: directory {} does not exist",
            args.out.display(),
            parent.display()
        )));
    }
    let film = FilmSpec {
        film_ior: args.film_ior,
        substrate_ior: args.substrate_ior,
        thickness_nm: thickness,
    };
    let mut report = |step: usize, loss: f64| {
        let _ = writeln!(out, "step {step:>6}  loss {loss:.3e}");
    };
    let trained = crate::coeffs::dispatch_coeffs!(args.coeffs, |N| train::<N>(
        &film,
        args.hidden,
        args.steps,
        args.seed,
        &mut report
    ))?;
    let bytes = trained.network.to_bytes(&SpectralRange::VISIBLE);
    write_atomically(&args.out, |file| {
        file.write_all(&bytes).map_err(|e| e.to_string())
    })?;
    if let Some(dir) = &args.evidence {
        let evidence = crate::neural_report::evidence(&film, &bytes)?;
        let table = crate::neural_report::markdown(&evidence);
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::input(format!("cannot create {}: {e}", dir.display())))?;
        crate::neural_report::write_picture(&dir.join("tables.png"), &evidence)?;
        let text = format!(
            "# Neural thin film: evidence\n\n`fspec train thin-film --film-ior {} --substrate-ior {} --thickness-nm {}{} --coeffs {} --hidden {} --steps {} --seed {}`\n\n{table}\n![explicit | Fourier table | network | 10 × network error](tables.png)\n",
            args.film_ior,
            args.substrate_ior,
            args.thickness_nm,
            args.param
                .as_ref()
                .map_or(String::new(), |p| format!(" --param {p}")),
            args.coeffs,
            args.hidden,
            args.steps,
            args.seed
        );
        write_atomically(&dir.join("evidence.md"), |file| {
            file.write_all(text.as_bytes()).map_err(|e| e.to_string())
        })?;
        let _ = write!(out, "{table}");
    }
    Ok(trained)
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectral_core::fourier::FourierSpectrum;

    #[test]
    fn backpropagation_matches_finite_differences() {
        let mut rng = Rng::new(3);
        let mut net = Mlp::new(2, 4, 3, vec![(0.5, 2.0), (400.0, 0.01)], &mut rng);
        // Non-zero output biases so every path matters.
        let count = net.params.len();
        for j in count - 3..count {
            net.params[j] = 0.1 * j as f64;
        }
        let basis: Vec<f64> = (0..15).map(|i| ((i * 7) % 5) as f64 * 0.3 - 0.5).collect();
        let input = [0.3, 650.0];
        let target = [0.2, -0.1, 0.05];
        let mut d_out = vec![0.0; 3];
        let f = net.forward(&input);
        loss(&basis, 3, &f.out, &target, &mut d_out);
        let mut grad = vec![0.0; count];
        net.backward(&f, &d_out, &mut grad);
        let mut scratch = vec![0.0; 3];
        for (j, &analytic) in grad.iter().enumerate() {
            let h = 1e-6;
            let mut plus = net.clone();
            plus.params[j] += h;
            let mut minus = net.clone();
            minus.params[j] -= h;
            let lp = loss(&basis, 3, &plus.eval(&input), &target, &mut scratch);
            let lm = loss(&basis, 3, &minus.eval(&input), &target, &mut scratch);
            let numeric = (lp - lm) / (2.0 * h);
            assert!(
                (numeric - analytic).abs() < 1e-6 * (1.0 + numeric.abs()),
                "param {j}: {numeric} vs {analytic}"
            );
        }
    }

    #[test]
    fn bytes_load_into_the_core_network_with_the_same_outputs() {
        let mut rng = Rng::new(9);
        let net = Mlp::new(1, 10, 10, vec![(0.5, 2.0)], &mut rng);
        let bytes = net.to_bytes(&SpectralRange::VISIBLE);
        let core = spectral_core::neural::SineMlp::<1, 10, 10>::from_bytes(&bytes).unwrap();
        for x in [0.0, 0.3, 1.0] {
            let a = net.eval(&[x]);
            let b: FourierSpectrum<f64, 10> = core.eval([x]);
            for (j, (a_j, b_j)) in a.iter().zip(b.coeffs.iter()).enumerate() {
                assert!((a_j - b_j).abs() < 1e-5, "{x} {j}");
            }
        }
    }

    #[test]
    fn parameter_syntax() {
        assert_eq!(parse_param("thickness:100..800").unwrap(), (100.0, 800.0));
        for bad in [
            "thickness:800..100",
            "width:1..2",
            "thickness:1",
            "thickness:a..b",
            "thickness:-1..5",
        ] {
            assert!(parse_param(bad).is_err(), "{bad}");
        }
    }
}
