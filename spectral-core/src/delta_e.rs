//! Colour differences: CIE76 `ΔE*ab` and CIEDE2000.
//!
//! CIE76 is the Euclidean distance in CIELAB. CIEDE2000 follows CIE 142-2001
//! with `k_L = k_C = k_H = 1`, implemented after G. Sharma, W. Wu,
//! E. N. Dalal, "The CIEDE2000 color-difference formula: implementation
//! notes, supplementary test data, and mathematical observations", Color
//! Res. Appl. 30(1), 2005, including their conventions for the hue mean and
//! difference when a chroma is zero. Their 34 test pairs are checked in the
//! workspace integration tests (`tests/tests/reference_data.rs`).

use crate::color::Lab;

/// CIE76 colour difference `|Lab1 − Lab2|`.
pub fn delta_e76(lab1: Lab, lab2: Lab) -> f64 {
    let (dl, da, db) = (lab1.l - lab2.l, lab1.a - lab2.a, lab1.b - lab2.b);
    libm::sqrt(dl * dl + da * da + db * db)
}

/// `25^7`, the chroma constant of CIEDE2000.
const TWENTY_FIVE_POW_7: f64 = 6_103_515_625.0;

fn degrees(radians: f64) -> f64 {
    radians.to_degrees()
}

fn cos_deg(deg: f64) -> f64 {
    libm::cos(deg.to_radians())
}

fn sin_deg(deg: f64) -> f64 {
    libm::sin(deg.to_radians())
}

/// Hue angle in degrees in `[0, 360)`, `0` for a neutral colour.
fn hue_deg(a: f64, b: f64) -> f64 {
    if a == 0.0 && b == 0.0 {
        return 0.0;
    }
    let h = degrees(libm::atan2(b, a));
    if h < 0.0 { h + 360.0 } else { h }
}

/// CIEDE2000 colour difference (`k_L = k_C = k_H = 1`).
pub fn delta_e2000(lab1: Lab, lab2: Lab) -> f64 {
    let c1 = libm::hypot(lab1.a, lab1.b);
    let c2 = libm::hypot(lab2.a, lab2.b);
    let c_mean_7 = libm::pow(0.5 * (c1 + c2), 7.0);
    let g = 0.5 * (1.0 - libm::sqrt(c_mean_7 / (c_mean_7 + TWENTY_FIVE_POW_7)));
    let a1 = (1.0 + g) * lab1.a;
    let a2 = (1.0 + g) * lab2.a;
    let c1p = libm::hypot(a1, lab1.b);
    let c2p = libm::hypot(a2, lab2.b);
    let h1p = hue_deg(a1, lab1.b);
    let h2p = hue_deg(a2, lab2.b);
    let chroma_product = c1p * c2p;

    let dl = lab2.l - lab1.l;
    let dc = c2p - c1p;
    let dh_deg = if chroma_product == 0.0 {
        0.0
    } else {
        let d = h2p - h1p;
        if d > 180.0 {
            d - 360.0
        } else if d < -180.0 {
            d + 360.0
        } else {
            d
        }
    };
    let dh_big = 2.0 * libm::sqrt(chroma_product) * sin_deg(0.5 * dh_deg);

    let l_mean = 0.5 * (lab1.l + lab2.l);
    let c_mean = 0.5 * (c1p + c2p);
    let h_mean = if chroma_product == 0.0 {
        h1p + h2p
    } else if (h1p - h2p).abs() <= 180.0 {
        0.5 * (h1p + h2p)
    } else if h1p + h2p < 360.0 {
        0.5 * (h1p + h2p + 360.0)
    } else {
        0.5 * (h1p + h2p - 360.0)
    };

    let t = 1.0 - 0.17 * cos_deg(h_mean - 30.0)
        + 0.24 * cos_deg(2.0 * h_mean)
        + 0.32 * cos_deg(3.0 * h_mean + 6.0)
        - 0.20 * cos_deg(4.0 * h_mean - 63.0);
    let d_theta = 30.0 * libm::exp(-libm::pow((h_mean - 275.0) / 25.0, 2.0));
    let c_mean_p7 = libm::pow(c_mean, 7.0);
    let r_c = 2.0 * libm::sqrt(c_mean_p7 / (c_mean_p7 + TWENTY_FIVE_POW_7));
    let l50 = (l_mean - 50.0) * (l_mean - 50.0);
    let s_l = 1.0 + 0.015 * l50 / libm::sqrt(20.0 + l50);
    let s_c = 1.0 + 0.045 * c_mean;
    let s_h = 1.0 + 0.015 * c_mean * t;
    let r_t = -sin_deg(2.0 * d_theta) * r_c;

    let (tl, tc, th) = (dl / s_l, dc / s_c, dh_big / s_h);
    libm::sqrt((tl * tl + tc * tc + th * th + r_t * tc * th).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_colours_have_zero_difference() {
        let lab = Lab::new(50.0, 10.0, -20.0);
        assert_eq!(delta_e76(lab, lab), 0.0);
        assert_eq!(delta_e2000(lab, lab), 0.0);
        let grey = Lab::new(50.0, 0.0, 0.0);
        assert_eq!(delta_e2000(grey, grey), 0.0);
    }

    #[test]
    fn symmetric_and_lightness_only() {
        let a = Lab::new(50.0, 2.6772, -79.7751);
        let b = Lab::new(50.0, 0.0, -82.7485);
        assert!((delta_e2000(a, b) - delta_e2000(b, a)).abs() < 1e-12);
        assert!((delta_e2000(a, b) - 2.0425).abs() < 1e-4);
        assert!(
            (delta_e76(Lab::new(10.0, 0.0, 0.0), Lab::new(13.0, 4.0, 0.0)) - 5.0).abs() < 1e-15
        );
    }
}
