//! Inference of the small sine-activated MLP that outputs `N` Fourier
//! coefficients at once (paper §4, figure 2): inputs (e.g. `cos θ`, a film
//! thickness) → two hidden layers of `H` neurons with `sin` activation →
//! `OUT` linear outputs, the coefficients `c_0 … c_{OUT−1}` of the material's
//! spectrum for those inputs.
//!
//! `h1 = sin(W1 x' + b1)`, `h2 = sin(W2 h1 + b2)`, `c = W3 h2 + b3`, with the
//! inputs normalised as `x' = (x − offset) · scale`. Frequencies (SIREN's
//! `ω₀`) are folded into the weights by the trainer.
//!
//! ## Byte format (little-endian, version 1)
//!
//! | bytes | field |
//! | --- | --- |
//! | 4 | magic `FSNN` |
//! | 2 | version `u16` = 1 |
//! | 1 | activation `u8`: 1 = sine |
//! | 1 | hidden layers `u8` = 2 |
//! | 2, 2, 2 | inputs, hidden width, outputs (`u16`) |
//! | 2 | reserved `u16` = 0 |
//! | 4, 4 | spectral range `min_nm`, `max_nm` (`f32`) |
//! | 8 · inputs | per input `offset`, `scale` (`f32`) |
//! | 4 · (H·IN + H + H·H + H + OUT·H + OUT) | `W1` (row-major, H rows), `b1`, `W2`, `b2`, `W3`, `b3` (`f32`) |
//!
//! [`SineMlp::from_bytes`] checks every field, the exact length and that
//! every number is finite and at most [`MAX_MAGNITUDE`] in magnitude (so
//! `f32` evaluation stays finite); bad bytes give `Err`, never a panic.

use crate::SpectralError;
use crate::fourier::FourierSpectrum;
use crate::lane::Lane;
use crate::range::SpectralRange;

/// File magic.
pub const MAGIC: [u8; 4] = *b"FSNN";
/// Supported version.
pub const VERSION: u16 = 1;
/// Activation code of `sin`.
pub const ACTIVATION_SINE: u8 = 1;
/// Header bytes before the input normalisation.
pub const HEADER_BYTES: usize = 24;
/// Largest magnitude of any stored number: keeps `f32` evaluation finite for
/// inputs of magnitude up to 1e6 (`|W x'|` stays below 1e30).
pub const MAX_MAGNITUDE: f32 = 1e6;

/// A two-hidden-layer sine MLP with `IN` inputs, `H` hidden neurons per
/// layer and `OUT` outputs, weights in fixed arrays (no allocation).
#[derive(Debug, Clone, PartialEq)]
pub struct SineMlp<const IN: usize, const H: usize, const OUT: usize> {
    /// Spectral range of the output coefficients.
    pub range: SpectralRange,
    /// Per input `(offset, scale)`.
    pub normalisation: [(f32, f32); IN],
    /// First layer weights, `H × IN`.
    pub w1: [[f32; IN]; H],
    /// First layer biases.
    pub b1: [f32; H],
    /// Second layer weights, `H × H`.
    pub w2: [[f32; H]; H],
    /// Second layer biases.
    pub b2: [f32; H],
    /// Output weights, `OUT × H`.
    pub w3: [[f32; H]; OUT],
    /// Output biases.
    pub b3: [f32; OUT],
}

/// Reads little-endian values from a byte slice without panicking.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take<const K: usize>(&mut self) -> Result<[u8; K], SpectralError> {
        let slice = self
            .bytes
            .get(self.at..self.at + K)
            .ok_or(SpectralError::InvalidParameter("network file is truncated"))?;
        self.at += K;
        let mut out = [0u8; K];
        out.copy_from_slice(slice);
        Ok(out)
    }

    fn u8(&mut self) -> Result<u8, SpectralError> {
        Ok(self.take::<1>()?[0])
    }

    fn u16(&mut self) -> Result<u16, SpectralError> {
        Ok(u16::from_le_bytes(self.take()?))
    }

    fn f32(&mut self) -> Result<f32, SpectralError> {
        let v = f32::from_le_bytes(self.take()?);
        if v.is_finite() && v.abs() <= MAX_MAGNITUDE {
            Ok(v)
        } else {
            Err(SpectralError::InvalidParameter(
                "network file holds a NaN, an infinity or a number above 1e6 in magnitude",
            ))
        }
    }

    fn array<const K: usize>(&mut self) -> Result<[f32; K], SpectralError> {
        let mut out = [0.0; K];
        for v in &mut out {
            *v = self.f32()?;
        }
        Ok(out)
    }
}

impl<const IN: usize, const H: usize, const OUT: usize> SineMlp<IN, H, OUT> {
    /// Bytes of a file of this shape.
    pub const fn byte_len() -> usize {
        HEADER_BYTES + 8 * IN + 4 * (H * IN + H + H * H + H + OUT * H + OUT)
    }

    /// Bytes of the weights alone.
    pub const fn weight_bytes() -> usize {
        4 * (H * IN + H + H * H + H + OUT * H + OUT)
    }

    /// Parses and validates a network file (module docs).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, SpectralError> {
        let mut r = Reader { bytes, at: 0 };
        if r.take::<4>()? != MAGIC {
            return Err(SpectralError::InvalidParameter(
                "not a network file (magic FSNN missing)",
            ));
        }
        if r.u16()? != VERSION {
            return Err(SpectralError::InvalidParameter(
                "unsupported network file version",
            ));
        }
        if r.u8()? != ACTIVATION_SINE {
            return Err(SpectralError::InvalidParameter(
                "unsupported activation (only sine)",
            ));
        }
        if r.u8()? != 2 {
            return Err(SpectralError::InvalidParameter(
                "unsupported number of hidden layers (only 2)",
            ));
        }
        let (inputs, hidden, outputs) = (r.u16()?, r.u16()?, r.u16()?);
        if (
            usize::from(inputs),
            usize::from(hidden),
            usize::from(outputs),
        ) != (IN, H, OUT)
        {
            return Err(SpectralError::InvalidParameter(
                "network shape differs from the expected one",
            ));
        }
        if r.u16()? != 0 {
            return Err(SpectralError::InvalidParameter(
                "reserved header field is not zero",
            ));
        }
        if bytes.len() != Self::byte_len() {
            return Err(SpectralError::InvalidParameter(
                "network file length does not match its shape",
            ));
        }
        let range = SpectralRange::new(f64::from(r.f32()?), f64::from(r.f32()?))?;
        let mut normalisation = [(0.0, 1.0); IN];
        for n in &mut normalisation {
            *n = (r.f32()?, r.f32()?);
        }
        let mut w1 = [[0.0; IN]; H];
        for row in &mut w1 {
            *row = r.array()?;
        }
        let b1 = r.array()?;
        let mut w2 = [[0.0; H]; H];
        for row in &mut w2 {
            *row = r.array()?;
        }
        let b2 = r.array()?;
        let mut w3 = [[0.0; H]; OUT];
        for row in &mut w3 {
            *row = r.array()?;
        }
        let b3 = r.array()?;
        Ok(Self {
            range,
            normalisation,
            w1,
            b1,
            w2,
            b2,
            w3,
            b3,
        })
    }

    /// Writes the network in the byte format into `out` (exactly
    /// [`byte_len`](Self::byte_len) bytes); `Err` if `out` is too short.
    pub fn write_bytes(&self, out: &mut [u8]) -> Result<usize, SpectralError> {
        let len = Self::byte_len();
        let out = out
            .get_mut(..len)
            .ok_or(SpectralError::InvalidParameter("output buffer too short"))?;
        let mut at = 0;
        let mut put = |bytes: &[u8]| {
            out[at..at + bytes.len()].copy_from_slice(bytes);
            at += bytes.len();
        };
        put(&MAGIC);
        put(&VERSION.to_le_bytes());
        put(&[ACTIVATION_SINE, 2]);
        for dim in [IN, H, OUT, 0] {
            put(&(dim as u16).to_le_bytes());
        }
        put(&(self.range.min_nm() as f32).to_le_bytes());
        put(&(self.range.max_nm() as f32).to_le_bytes());
        for (offset, scale) in self.normalisation {
            put(&offset.to_le_bytes());
            put(&scale.to_le_bytes());
        }
        let rows = self.w1.iter().flatten().chain(&self.b1);
        let rows = rows.chain(self.w2.iter().flatten()).chain(&self.b2);
        for v in rows.chain(self.w3.iter().flatten()).chain(&self.b3) {
            put(&v.to_le_bytes());
        }
        Ok(len)
    }

    /// The coefficients for one input (any lane type: `f32` or 8 lanes).
    pub fn eval<L: Lane>(&self, x: [L; IN]) -> FourierSpectrum<L, OUT> {
        let x: [L; IN] = core::array::from_fn(|i| {
            let (offset, scale) = self.normalisation[i];
            (x[i] - L::splat(f64::from(offset))) * L::splat(f64::from(scale))
        });
        let layer = |w: &[f32], b: f32, input: &[L]| {
            let mut acc = L::splat(f64::from(b));
            for (&wi, &xi) in w.iter().zip(input) {
                acc = xi.mul_add(L::splat(f64::from(wi)), acc);
            }
            acc
        };
        let h1: [L; H] = core::array::from_fn(|k| layer(&self.w1[k], self.b1[k], &x).sin());
        let h2: [L; H] = core::array::from_fn(|k| layer(&self.w2[k], self.b2[k], &h1).sin());
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
            layer(&self.w3[j], self.b3[j], &h2)
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn network() -> SineMlp<2, 3, 4> {
        let f = |i: usize| (i as f32 * 0.37).sin() * 0.8;
        SineMlp {
            range: SpectralRange::VISIBLE,
            normalisation: [(0.5, 2.0), (450.0, 0.004)],
            w1: core::array::from_fn(|r| core::array::from_fn(|c| f(r * 2 + c))),
            b1: core::array::from_fn(|k| f(10 + k)),
            w2: core::array::from_fn(|r| core::array::from_fn(|c| f(20 + r * 3 + c))),
            b2: core::array::from_fn(|k| f(40 + k)),
            w3: core::array::from_fn(|r| core::array::from_fn(|c| f(50 + r * 3 + c))),
            b3: core::array::from_fn(|k| f(70 + k)),
        }
    }

    #[test]
    fn bytes_round_trip_and_corruption_is_detected() {
        let net = network();
        let mut bytes = [0u8; SineMlp::<2, 3, 4>::byte_len()];
        assert_eq!(net.write_bytes(&mut bytes), Ok(bytes.len()));
        assert_eq!(SineMlp::<2, 3, 4>::from_bytes(&bytes), Ok(net.clone()));
        // Wrong shape, truncation, trailing bytes, magic, version, NaN.
        assert!(SineMlp::<1, 3, 4>::from_bytes(&bytes).is_err());
        assert!(SineMlp::<2, 3, 4>::from_bytes(&bytes[..bytes.len() - 1]).is_err());
        let mut longer = [0u8; SineMlp::<2, 3, 4>::byte_len() + 1];
        longer[..bytes.len()].copy_from_slice(&bytes);
        assert!(SineMlp::<2, 3, 4>::from_bytes(&longer).is_err());
        for (index, value) in [(0usize, b'X'), (4, 2), (6, 3), (7, 1)] {
            let mut bad = bytes;
            bad[index] = value;
            assert!(
                SineMlp::<2, 3, 4>::from_bytes(&bad).is_err(),
                "byte {index}"
            );
        }
        let mut nan = bytes;
        nan[HEADER_BYTES + 20..HEADER_BYTES + 24].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(SineMlp::<2, 3, 4>::from_bytes(&nan).is_err());
        let mut large = bytes;
        let above = MAX_MAGNITUDE * 1.5;
        large[HEADER_BYTES + 20..HEADER_BYTES + 24].copy_from_slice(&above.to_le_bytes());
        assert!(SineMlp::<2, 3, 4>::from_bytes(&large).is_err());
        assert!(SineMlp::<2, 3, 4>::from_bytes(&[]).is_err());
    }

    #[test]
    fn evaluation_matches_a_direct_formula() {
        let net = network();
        let x = [0.3f64, 600.0];
        let xn = [(x[0] - 0.5) * 2.0, (x[1] - 450.0) * 0.004];
        let h1: [f64; 3] = core::array::from_fn(|k| {
            (f64::from(net.b1[k]) + (0..2).map(|i| f64::from(net.w1[k][i]) * xn[i]).sum::<f64>())
                .sin()
        });
        let h2: [f64; 3] = core::array::from_fn(|k| {
            (f64::from(net.b2[k]) + (0..3).map(|i| f64::from(net.w2[k][i]) * h1[i]).sum::<f64>())
                .sin()
        });
        let out = net.eval::<f64>(x);
        for j in 0..4 {
            let expected =
                f64::from(net.b3[j]) + (0..3).map(|i| f64::from(net.w3[j][i]) * h2[i]).sum::<f64>();
            assert!((out.coeffs[j] - expected).abs() < 1e-6, "{j}");
        }
    }
}
