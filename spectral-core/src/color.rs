//! Colour types: CIE XYZ, CIELAB, linear sRGB and the sRGB encoding.
//!
//! * XYZ → CIELAB (CIE 15:2018): `f(t) = t^{1/3}` if `t > (6/29)^3`, else
//!   `t/(3 (6/29)^2) + 4/29`; `L* = 116 f(Y/Yn) − 16`,
//!   `a* = 500 (f(X/Xn) − f(Y/Yn))`, `b* = 200 (f(Y/Yn) − f(Z/Zn))`. For
//!   spectral work the white comes from the same CMF table and illuminant
//!   ([`crate::xyz::white_point`]).
//! * XYZ ↔ linear sRGB (IEC 61966-2-1): the matrices below, derived from the
//!   sRGB primaries and the D65 white chromaticity; the test
//!   `matrix_is_derived_from_primaries` re-derives them.
//! * sRGB encoding: `12.92 v` for `v ≤ 0.0031308`, else `1.055 v^{1/2.4} − 0.055`.

/// Chromaticities `(x, y)` of the sRGB red, green and blue primaries.
pub const SRGB_PRIMARIES_XY: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];
/// Chromaticity `(x, y)` of the sRGB (D65) white.
pub const SRGB_WHITE_XY: [f64; 2] = [0.3127, 0.3290];

/// XYZ → linear sRGB (rows R, G, B).
pub const XYZ_TO_LINEAR_SRGB: [[f64; 3]; 3] = [
    [3.240_969_9, -1.537_383_2, -0.498_610_8],
    [-0.969_243_6, 1.875_967_5, 0.041_555_1],
    [0.055_630_1, -0.203_977_0, 1.056_971_5],
];

/// Linear sRGB → XYZ (rows X, Y, Z); the inverse of [`XYZ_TO_LINEAR_SRGB`].
pub const LINEAR_SRGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.412_390_8, 0.357_584_3, 0.180_480_8],
    [0.212_639_0, 0.715_168_7, 0.072_192_3],
    [0.019_330_8, 0.119_194_8, 0.950_532_2],
];

fn mat3(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    core::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// CIE 1931 XYZ tristimulus values, `f64` by default.
///
/// `T` is the number type: `Xyz` (`f64`) for one colour, and the
/// [`Lane`](crate::Lane) type of the spectra for the lane-wise conversions
/// ([`XyzKernel::apply`](crate::xyz::XyzKernel::apply) and the
/// [`XyzConverter`](crate::xyz::XyzConverter) routes), e.g. `Xyz<f32x8>`
/// for eight ray lanes. Colour science (chromaticity, CIELAB, sRGB) is
/// defined on `Xyz<f64>`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Xyz<T = f64> {
    /// X.
    pub x: T,
    /// Y (luminance).
    pub y: T,
    /// Z.
    pub z: T,
}

impl<T: Copy> Xyz<T> {
    /// From components.
    pub const fn new(x: T, y: T, z: T) -> Self {
        Self { x, y, z }
    }

    /// From an array `[X, Y, Z]`.
    pub const fn from_array(v: [T; 3]) -> Self {
        Self::new(v[0], v[1], v[2])
    }

    /// As an array `[X, Y, Z]`.
    pub const fn to_array(self) -> [T; 3] {
        [self.x, self.y, self.z]
    }

    /// `f` applied to each component (e.g. one lane of an `Xyz<f32x8>`).
    pub fn map<U: Copy>(self, f: impl Fn(T) -> U) -> Xyz<U> {
        Xyz::new(f(self.x), f(self.y), f(self.z))
    }
}

impl Xyz {
    /// From chromaticity `(x, y)` and luminance `Y`.
    pub fn from_chromaticity(x: f64, y: f64, luminance: f64) -> Self {
        Self::new(x * luminance / y, luminance, (1.0 - x - y) * luminance / y)
    }

    /// Chromaticity `(x, y)`; `(0, 0)` for black.
    pub fn chromaticity(self) -> [f64; 2] {
        let sum = self.x + self.y + self.z;
        if sum == 0.0 {
            [0.0, 0.0]
        } else {
            [self.x / sum, self.y / sum]
        }
    }

    /// Every component times `factor`.
    pub fn scale(self, factor: f64) -> Self {
        Self::new(self.x * factor, self.y * factor, self.z * factor)
    }

    /// CIELAB relative to `white` (module docs).
    pub fn to_lab(self, white: Xyz) -> Lab {
        let fx = lab_f(self.x / white.x);
        let fy = lab_f(self.y / white.y);
        let fz = lab_f(self.z / white.z);
        Lab {
            l: 116.0 * fy - 16.0,
            a: 500.0 * (fx - fy),
            b: 200.0 * (fy - fz),
        }
    }

    /// Linear sRGB (may be negative or above 1 out of gamut).
    pub fn to_linear_srgb(self) -> LinearSrgb {
        let [r, g, b] = mat3(&XYZ_TO_LINEAR_SRGB, self.to_array());
        LinearSrgb { r, g, b }
    }
}

const LAB_DELTA: f64 = 6.0 / 29.0;

fn lab_f(t: f64) -> f64 {
    if t > LAB_DELTA * LAB_DELTA * LAB_DELTA {
        libm::cbrt(t)
    } else {
        t / (3.0 * LAB_DELTA * LAB_DELTA) + 4.0 / 29.0
    }
}

fn lab_f_inverse(f: f64) -> f64 {
    if f > LAB_DELTA {
        f * f * f
    } else {
        3.0 * LAB_DELTA * LAB_DELTA * (f - 4.0 / 29.0)
    }
}

/// CIELAB coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Lab {
    /// Lightness L*.
    pub l: f64,
    /// Green–red a*.
    pub a: f64,
    /// Blue–yellow b*.
    pub b: f64,
}

impl Lab {
    /// From components.
    pub const fn new(l: f64, a: f64, b: f64) -> Self {
        Self { l, a, b }
    }

    /// Back to XYZ relative to `white`.
    pub fn to_xyz(self, white: Xyz) -> Xyz {
        let fy = (self.l + 16.0) / 116.0;
        let fx = fy + self.a / 500.0;
        let fz = fy - self.b / 200.0;
        Xyz::new(
            white.x * lab_f_inverse(fx),
            white.y * lab_f_inverse(fy),
            white.z * lab_f_inverse(fz),
        )
    }
}

/// Linear-light sRGB.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinearSrgb {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
}

impl LinearSrgb {
    /// From components.
    pub const fn new(r: f64, g: f64, b: f64) -> Self {
        Self { r, g, b }
    }

    /// To XYZ.
    pub fn to_xyz(self) -> Xyz {
        Xyz::from_array(mat3(&LINEAR_SRGB_TO_XYZ, [self.r, self.g, self.b]))
    }

    /// Encoded sRGB in [0, 1] (clamped, NaN → 0).
    pub fn encode(self) -> [f64; 3] {
        [self.r, self.g, self.b].map(|v| srgb_encode(clamp_unit(v)))
    }

    /// Encoded 8-bit sRGB (clamped, rounded).
    pub fn to_srgb8(self) -> [u8; 3] {
        self.encode().map(|v| libm::round(v * 255.0) as u8)
    }
}

/// Clamps to [0, 1]; NaN maps to 0.
pub fn clamp_unit(v: f64) -> f64 {
    if v > 0.0 { v.min(1.0) } else { 0.0 }
}

/// The sRGB transfer function (linear → encoded), for `v` in [0, 1].
pub fn srgb_encode(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * libm::pow(v, 1.0 / 2.4) - 0.055
    }
}

/// The inverse sRGB transfer function (encoded → linear).
pub fn srgb_decode(v: f64) -> f64 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        libm::pow((v + 0.055) / 1.055, 2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inverse of a 3×3 matrix by cofactors.
    fn inverse(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let c = |r: usize, k: usize| {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
        };
        let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
        core::array::from_fn(|r| core::array::from_fn(|k| c(k, r) / det))
    }

    #[test]
    fn matrix_is_derived_from_primaries() {
        // Columns: XYZ of each primary with Y = 1, scaled so R+G+B = white.
        let primary = |i: usize| {
            Xyz::from_chromaticity(SRGB_PRIMARIES_XY[i][0], SRGB_PRIMARIES_XY[i][1], 1.0)
        };
        let p = [primary(0), primary(1), primary(2)];
        let unscaled = [
            [p[0].x, p[1].x, p[2].x],
            [p[0].y, p[1].y, p[2].y],
            [p[0].z, p[1].z, p[2].z],
        ];
        let white = Xyz::from_chromaticity(SRGB_WHITE_XY[0], SRGB_WHITE_XY[1], 1.0);
        let s = mat3(&inverse(&unscaled), white.to_array());
        let to_xyz: [[f64; 3]; 3] =
            core::array::from_fn(|r| core::array::from_fn(|k| unscaled[r][k] * s[k]));
        let to_rgb = inverse(&to_xyz);
        for r in 0..3 {
            for k in 0..3 {
                assert!(
                    (to_xyz[r][k] - LINEAR_SRGB_TO_XYZ[r][k]).abs() < 1e-7,
                    "{r}{k}"
                );
                assert!(
                    (to_rgb[r][k] - XYZ_TO_LINEAR_SRGB[r][k]).abs() < 1e-7,
                    "{r}{k}"
                );
            }
        }
    }

    #[test]
    fn white_maps_to_unit_rgb_and_lab_round_trips() {
        let white = LinearSrgb::new(1.0, 1.0, 1.0).to_xyz();
        let [x, y] = white.chromaticity();
        assert!((x - SRGB_WHITE_XY[0]).abs() < 1e-6 && (y - SRGB_WHITE_XY[1]).abs() < 1e-6);
        let lab = white.to_lab(white);
        assert!((lab.l - 100.0).abs() < 1e-12 && lab.a.abs() < 1e-12 && lab.b.abs() < 1e-12);
        for xyz in [
            Xyz::new(0.2, 0.3, 0.4),
            Xyz::new(0.001, 0.002, 0.0005),
            Xyz::new(0.9, 0.5, 0.1),
        ] {
            let back = xyz.to_lab(white).to_xyz(white);
            assert!((back.x - xyz.x).abs() < 1e-12);
            assert!((back.y - xyz.y).abs() < 1e-12);
            assert!((back.z - xyz.z).abs() < 1e-12);
        }
    }

    #[test]
    fn srgb_transfer_round_trips_and_is_continuous() {
        for i in 0..=100 {
            let v = i as f64 / 100.0;
            assert!((srgb_decode(srgb_encode(v)) - v).abs() < 1e-12);
        }
        // The standard's two pieces meet with a jump of 2.85e-8 at the knee.
        let knee = 0.003_130_8;
        let jump = (srgb_encode(knee) - srgb_encode(knee + 1e-12)).abs();
        assert!(jump < 3e-8, "{jump}");
        assert_eq!(LinearSrgb::new(2.0, -1.0, f64::NAN).to_srgb8(), [255, 0, 0]);
        assert_eq!(LinearSrgb::new(0.5, 0.5, 0.5).to_srgb8(), [188, 188, 188]);
    }
}
