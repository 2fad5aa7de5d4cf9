//! The RGB → spectrum coefficient table of Jakob & Hanika, "A Low-Dimensional
//! Function Space for Efficient Spectral Upsampling", CGF 38(2), 2019
//! (MATH.md §6), fitted with the project's own data.
//!
//! A reflectance is `r(λ) = S(c0 t² + c1 t + c2)` with `t = (λ − 360)/470`
//! and `S(x) = ½ + x/(2 sqrt(1 + x²))`. For every grid point of the table the
//! three coefficients are found by Newton's method on the CIELAB residual
//! between the target sRGB colour and the colour of `r` under D65 (CIE 1931
//! 2°, 1 nm trapezoid quadrature over 360–830 nm, the embedded tables of
//! `data/`). Grid: the largest channel `l ∈ {R, G, B}`, its value
//! `z = smoothstep(smoothstep(k/(res−1)))`, and the two ratios
//! `x, y ∈ [0, 1]` of the other channels to it. Along `z` the solution is
//! continued from `k = res/5` upwards and downwards, each step warm-started
//! from the previous one, as in the paper.
//!
//! Output: `res` and `3 · res · res · res · 3` little-endian `f32`
//! coefficients (normalised-`t` form), index `(((l·res + k)·res + j)·res + i)·3`.

use crate::{data_dir, read_table};

/// Table resolution per axis.
pub const RESOLUTION: usize = 32;

/// `smoothstep(smoothstep(u))`: the `z` spacing of the table.
pub fn z_of(k: usize, resolution: usize) -> f64 {
    let smoothstep = |x: f64| x * x * (3.0 - 2.0 * x);
    smoothstep(smoothstep(k as f64 / (resolution - 1) as f64))
}

/// Quadrature tables: per 1 nm sample, `t`, and the weight × CMF × D65 in
/// XYZ, normalised so that the white (r = 1) has Y = 1.
struct Quadrature {
    t: Vec<f64>,
    weights: Vec<[f64; 3]>,
    white: [f64; 3],
}

fn linear(nm: &[f64], values: &[f64], lambda: f64) -> f64 {
    let upper = nm.partition_point(|&l| l <= lambda);
    if upper == 0 {
        return values[0];
    }
    if upper == nm.len() {
        return values[nm.len() - 1];
    }
    let t = (lambda - nm[upper - 1]) / (nm[upper] - nm[upper - 1]);
    values[upper - 1] + t * (values[upper] - values[upper - 1])
}

fn quadrature() -> Result<Quadrature, String> {
    let dir = data_dir();
    let cmf = read_table(&dir.join("cie1931_2deg_cmf.csv"))?;
    let d65 = read_table(&dir.join("illuminant_d65.csv"))?;
    let (d65_nm, d65_power) = (d65.column(0), d65.column(1));
    let nm = cmf.column(0);
    let last = nm.len() - 1;
    let mut weights = Vec::with_capacity(nm.len());
    let mut white = [0.0; 3];
    for (i, row) in cmf.rows.iter().enumerate() {
        let trapezoid = if i == 0 || i == last { 0.5 } else { 1.0 };
        let power = linear(&d65_nm, &d65_power, row[0]) * trapezoid;
        let w = [row[1] * power, row[2] * power, row[3] * power];
        for r in 0..3 {
            white[r] += w[r];
        }
        weights.push(w);
    }
    let y_white = white[1];
    for w in &mut weights {
        for v in w.iter_mut() {
            *v /= y_white;
        }
    }
    let white = white.map(|v| v / y_white);
    let t = nm
        .iter()
        .map(|l| (l - nm[0]) / (nm[last] - nm[0]))
        .collect();
    Ok(Quadrature { t, weights, white })
}

fn lab_f(t: f64) -> f64 {
    let delta: f64 = 6.0 / 29.0;
    if t > delta * delta * delta {
        t.cbrt()
    } else {
        t / (3.0 * delta * delta) + 4.0 / 29.0
    }
}

fn lab_f_derivative(t: f64) -> f64 {
    let delta: f64 = 6.0 / 29.0;
    if t > delta * delta * delta {
        1.0 / (3.0 * t.cbrt() * t.cbrt())
    } else {
        1.0 / (3.0 * delta * delta)
    }
}

fn lab(xyz: [f64; 3], white: [f64; 3]) -> [f64; 3] {
    let f = [0, 1, 2].map(|r| lab_f(xyz[r] / white[r]));
    [
        116.0 * f[1] - 16.0,
        500.0 * (f[0] - f[1]),
        200.0 * (f[1] - f[2]),
    ]
}

/// XYZ of `S(poly)` and its Jacobian with respect to the coefficients.
fn xyz_and_jacobian(c: [f64; 3], q: &Quadrature) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut xyz = [0.0; 3];
    let mut jac = [[0.0; 3]; 3];
    for (&t, w) in q.t.iter().zip(&q.weights) {
        let x = (c[0] * t + c[1]) * t + c[2];
        let root = (1.0 + x * x).sqrt();
        let s = 0.5 + 0.5 * x / root;
        let ds = 0.5 / (root * root * root);
        let basis = [t * t, t, 1.0];
        for r in 0..3 {
            xyz[r] += w[r] * s;
            for k in 0..3 {
                jac[r][k] += w[r] * ds * basis[k];
            }
        }
    }
    (xyz, jac)
}

fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    if d.abs() < 1e-300 || !d.is_finite() {
        return None;
    }
    Some([0, 1, 2].map(|k| {
        let mut m = a;
        for r in 0..3 {
            m[r][k] = b[r];
        }
        det(m) / d
    }))
}

/// Newton iterations on the CIELAB residual of `rgb` from `start`.
fn fit(
    rgb: [f64; 3],
    start: [f64; 3],
    q: &Quadrature,
    xyz_of_rgb: &dyn Fn([f64; 3]) -> [f64; 3],
) -> [f64; 3] {
    let target = lab(xyz_of_rgb(rgb), q.white);
    let mut c = start;
    for _ in 0..30 {
        let (xyz, jac_xyz) = xyz_and_jacobian(c, q);
        let current = lab(xyz, q.white);
        let residual = [0, 1, 2].map(|r| current[r] - target[r]);
        if residual.iter().map(|v| v * v).sum::<f64>() < 1e-12 {
            break;
        }
        // d Lab / d XYZ.
        let df = [0, 1, 2].map(|r| lab_f_derivative(xyz[r] / q.white[r]) / q.white[r]);
        let d_lab_d_xyz = [
            [0.0, 116.0 * df[1], 0.0],
            [500.0 * df[0], -500.0 * df[1], 0.0],
            [0.0, 200.0 * df[1], -200.0 * df[2]],
        ];
        let mut jac = [[0.0; 3]; 3];
        for r in 0..3 {
            for k in 0..3 {
                jac[r][k] = (0..3).map(|m| d_lab_d_xyz[r][m] * jac_xyz[m][k]).sum();
            }
        }
        let Some(step) = solve3(jac, residual) else {
            break;
        };
        // Damped step: keep the polynomial in a sane range.
        let length = step.iter().map(|v| v * v).sum::<f64>().sqrt();
        let damping = if length > 50.0 { 50.0 / length } else { 1.0 };
        for k in 0..3 {
            c[k] -= damping * step[k];
        }
    }
    c
}

/// Fits the whole table for the sRGB gamut with `resolution` points per axis,
/// using `threads` worker threads. `xyz_of_rgb` is the sRGB → XYZ map
/// (linear sRGB, D65 white with Y = 1).
pub fn fit_table(
    resolution: usize,
    threads: usize,
    xyz_of_rgb: &(dyn Fn([f64; 3]) -> [f64; 3] + Sync),
) -> Result<Vec<f32>, String> {
    let q = quadrature()?;
    let mut data = vec![0.0f32; 3 * resolution * resolution * resolution * 3];
    let rows: Vec<(usize, usize)> = (0..3)
        .flat_map(|l| (0..resolution).map(move |j| (l, j)))
        .collect();
    let chunk = rows.len().div_ceil(threads.max(1));
    let results: Vec<Vec<(usize, [f32; 3])>> = std::thread::scope(|scope| {
        let handles: Vec<_> = rows
            .chunks(chunk)
            .map(|part| {
                let q = &q;
                scope.spawn(move || {
                    let mut out = Vec::new();
                    for &(l, j) in part {
                        let y = j as f64 / (resolution - 1) as f64;
                        for i in 0..resolution {
                            let x = i as f64 / (resolution - 1) as f64;
                            let start = resolution / 5;
                            let upward = start..resolution;
                            let downward = (0..start).rev();
                            for ks in [upward.collect::<Vec<_>>(), downward.collect::<Vec<_>>()] {
                                let mut c = [0.0; 3];
                                for k in ks {
                                    let z = z_of(k, resolution);
                                    let mut rgb = [0.0; 3];
                                    rgb[l] = z;
                                    rgb[(l + 1) % 3] = x * z;
                                    rgb[(l + 2) % 3] = y * z;
                                    c = fit(rgb, c, q, xyz_of_rgb);
                                    let index =
                                        ((l * resolution + k) * resolution + j) * resolution + i;
                                    out.push((index, c.map(|v| v as f32)));
                                }
                            }
                        }
                    }
                    out
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let mut written = 0;
    for (index, c) in results.into_iter().flatten() {
        data[3 * index..3 * index + 3].copy_from_slice(&c);
        written += 1;
    }
    if written != 3 * resolution * resolution * resolution {
        return Err(format!(
            "sigmoid fit: {written} grid points fitted, a worker failed"
        ));
    }
    Ok(data)
}

/// The table as little-endian bytes.
pub fn to_bytes(data: &[f32]) -> Vec<u8> {
    data.iter().flat_map(|v| v.to_le_bytes()).collect()
}
