//! `fspec experiment conversions`: the paper's table (section
//! «Эксперименты», part 1) and its figures 7 and 10 on the `lamps` and
//! `laser` scenes.
//!
//! Columns: Fourier N = 12 converted to XYZ by the series, lookup-table,
//! zeroth-coefficient and MESE routes (each with a spectral buffer — the
//! per-pixel mean coefficients converted once — and with an RGB buffer —
//! every sample converted), Spec32 (32 stratified wavelengths per path) and
//! Spec4 hero (4 hero wavelengths, what pbrt-v4 and Mitsuba 3 use). Rows:
//! mean ΔE2000, mean ΔE76, mean chromatic error, PSNR (metrics in
//! [`super::image`]) against the converged reference, and the render times.
//! A sampled transport has no spectral buffer (its samples reach the film
//! as XYZ), so its spectral-buffer time is "—", as in the paper.
//!
//! All compared renders use the same seed, so they trace the same paths
//! (common random numbers: the path and wavelength streams are separate);
//! the reference halves use other seeds. The curves of mean ΔE2000 and PSNR
//! against samples per pixel (1, 2, 4, … up to the table's spp) are drawn
//! for Fourier N = 12 (zeroth, spectral buffer), Spec4 hero and Spec32.
//! Times are wall-clock seconds of the whole render on all cores.

use super::image::{
    self, Comparison, DisplayImage, Method, Reference, TEST_SEED, compare, render_method,
};
use super::plot::{LinePlot, Scale, Series};
use super::report::{Claim, Section, Table, Verdict, fixed, write_text};
use super::{Config, progress};
use crate::error::CliError;
use crate::image_out::{Exposure, Tone, XyzImage, write_png};
use simd_tracer::film::Buffer;
use simd_tracer::render::RenderResult;
use spectral_core::FourierBasis;
use spectral_core::FourierSpectrum;
use spectral_core::color::Xyz;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::{XyzConverter, XyzRoute};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The scenes of the experiment.
pub const SCENES: [&str; 2] = ["lamps", "laser"];
/// Coefficients of the Fourier columns.
pub const COEFFS: usize = 12;
/// The four conversion routes, in the paper's column order.
const ROUTES: [XyzRoute; 4] = [
    XyzRoute::Series,
    XyzRoute::Lut,
    XyzRoute::Zeroth,
    XyzRoute::Mese,
];
/// Interleaved repeats of the timing renders (the minimum is kept: the
/// machine is shared, and the minimum is the least disturbed run).
pub const TIMING_REPEATS: usize = 3;
// The table's row labels say "min of 3"; keep them in step.
const _: () = assert!(TIMING_REPEATS == 3, "update the timing row labels");
/// Largest side of the timing renders, pixels.
pub const TIMING_SIZE: u32 = 256;
/// The timing renders take the table's spp divided by this.
pub const TIMING_SPP_DIVISOR: u32 = 4;
/// A time difference below this fraction counts as a tie.
const TIME_TIE_FRACTION: f64 = 0.03;
/// "Much more time": MESE at least this many times the zeroth route.
const MUCH_SLOWER_FACTOR: f64 = 1.5;
/// "Gains little": a ΔE2000 improvement below this fraction of the value.
const LITTLE_GAIN_FRACTION: f64 = 0.05;
/// "Most colour noise removed": chromatic error at most this fraction of
/// the sampled method's.
const MOST_REMOVED_FRACTION: f64 = 0.5;

fn spec32() -> Method {
    Method::Sampled {
        wavelengths: 32,
        strategy: WavelengthStrategy::Stratified,
    }
}

/// One column of the table.
#[derive(Debug, Clone)]
struct Column {
    name: String,
    spectral: Option<Measured>,
    rgb: Measured,
    convert_ms: Option<f64>,
    /// Minimum over the timing repeats: spectral buffer (Fourier) and RGB.
    timed_spectral: Option<f64>,
    timed_rgb: f64,
}

/// One render compared with the reference.
#[derive(Debug, Clone, Copy)]
struct Measured {
    cmp: Comparison,
    seconds: f64,
}

/// The measurements of one scene.
#[derive(Debug, Clone)]
pub struct SceneResult {
    /// Scene name.
    pub scene: String,
    columns: Vec<Column>,
    reference: Reference,
    /// `(method label, spp, comparison)` of the curves.
    curves: Vec<(String, u32, Comparison)>,
}

impl SceneResult {
    fn column(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|c| c.name == name)
    }
}

fn measure(
    result: &RenderResult,
    reference: &Reference,
) -> Result<(Measured, DisplayImage), CliError> {
    let display = DisplayImage::new(&result.xyz);
    Ok((
        Measured {
            cmp: compare(&display, &reference.display)?,
            seconds: result.elapsed.as_secs_f64(),
        },
        display,
    ))
}

/// Milliseconds to convert every pixel's mean coefficients by `route` on
/// one thread (the conversion step of the spectral buffer alone).
fn conversion_ms(result: &RenderResult, route: XyzRoute) -> Result<Option<f64>, CliError> {
    let Some((n, coeffs)) = &result.coefficients else {
        return Ok(None);
    };
    if *n != COEFFS {
        return Ok(None);
    }
    let converter = Box::new(
        XyzConverter::<COEFFS>::new(&FourierBasis::VISIBLE)
            .map_err(|e| CliError::input(format!("spectral range: {e}")))?,
    );
    let start = Instant::now();
    let mut checksum = 0.0;
    for pixel in coeffs.chunks_exact(COEFFS) {
        let c = FourierSpectrum::<f64, COEFFS>::from_coeffs(core::array::from_fn(|j| {
            f64::from(pixel[j])
        }));
        checksum += converter.convert(route, &c).y;
    }
    let ms = start.elapsed().as_secs_f64() * 1e3;
    // The checksum keeps the loop from being optimised away.
    Ok(Some(if checksum.is_nan() { f64::NAN } else { ms }))
}

fn save_png(dir: &Path, name: &str, size: u32, xyz: &[Xyz]) -> Result<(), CliError> {
    let image = XyzImage {
        width: size,
        height: size,
        xyz,
    };
    write_png(&dir.join(name), &image, Exposure::default(), Tone::Clamp)
}

/// The crop of the comparison strip: left, top and side as fractions of
/// the image side (the objects on the floor), and the gap between crops.
const CROP_LEFT: f64 = 0.15;
const CROP_TOP: f64 = 0.5;
const CROP_SIDE: f64 = 0.35;
const CROP_GAP_PX: u32 = 4;

/// Writes full-resolution crops of `images` side by side (black gaps).
fn save_strip(dir: &Path, name: &str, size: u32, images: &[&[Xyz]]) -> Result<(), CliError> {
    let side = ((f64::from(size) * CROP_SIDE) as u32).max(1);
    let left = (f64::from(size) * CROP_LEFT) as u32;
    let top = (f64::from(size) * CROP_TOP) as u32;
    let count = images.len() as u32;
    let width = count * side + count.saturating_sub(1) * CROP_GAP_PX;
    let mut strip = vec![Xyz::default(); (width * side) as usize];
    for (k, image) in images.iter().enumerate() {
        let x0 = k as u32 * (side + CROP_GAP_PX);
        for y in 0..side {
            for x in 0..side {
                let (sx, sy) = ((left + x).min(size - 1), (top + y).min(size - 1));
                if let Some(&v) = image.get((sy * size + sx) as usize) {
                    strip[(y * width + x0 + x) as usize] = v;
                }
            }
        }
    }
    let image = XyzImage {
        width,
        height: side,
        xyz: &strip,
    };
    write_png(&dir.join(name), &image, Exposure::default(), Tone::Clamp)
}

/// `(size, spp)` of the timing renders.
pub fn timing_size(config: &Config) -> (u32, u32) {
    (
        config.size.min(TIMING_SIZE),
        (config.spp / TIMING_SPP_DIVISOR).max(1),
    )
}

/// Minimum render seconds of each method over [`TIMING_REPEATS`]
/// interleaved rounds at [`timing_size`].
fn timing(
    name: &str,
    scene: &simd_tracer::scene::Scene,
    methods: &[Method],
    config: &Config,
) -> Result<Vec<f64>, CliError> {
    let (size, spp) = timing_size(config);
    let settings = image::settings(size, spp, TEST_SEED, config.threads);
    let mut best = vec![f64::INFINITY; methods.len()];
    for round in 0..TIMING_REPEATS {
        progress(&format!(
            "{name}: timing round {}/{TIMING_REPEATS} ({size}×{size}, {spp} spp)",
            round + 1
        ));
        for (b, &method) in best.iter_mut().zip(methods) {
            let result = render_method(scene, method, &settings)?;
            *b = b.min(result.elapsed.as_secs_f64());
        }
    }
    Ok(best)
}

/// The spp values of the curves: powers of two below `spp`, then `spp`.
pub fn curve_spp(spp: u32) -> Vec<u32> {
    let mut list: Vec<u32> = (0..31)
        .map(|k| 1u32 << k)
        .take_while(|&s| s < spp)
        .collect();
    list.push(spp);
    list
}

fn run_scene(name: &str, config: &Config, dir: &Path) -> Result<SceneResult, CliError> {
    let scene = image::load_scene(name)?;
    let reference = image::reference(
        name,
        &scene,
        config.size,
        config.reference_spp,
        config.threads,
        &config.cache_dir(dir),
    )?;
    save_png(
        dir,
        &format!("{name}-reference.png"),
        config.size,
        &reference.xyz,
    )?;
    let settings = image::settings(config.size, config.spp, TEST_SEED, config.threads);
    let mut columns = Vec::new();
    let mut curve_images = Vec::new();
    // Reference, Fourier, Spec32, Spec4 hero: the comparison strip.
    let mut strip = vec![reference.xyz.clone()];
    for route in ROUTES {
        let mut spectral = None;
        let mut rgb = None;
        let mut convert_ms = None;
        for buffer in [Buffer::Spectral, Buffer::Xyz] {
            let method = Method::Fourier {
                coeffs: COEFFS,
                route,
                buffer,
            };
            progress(&format!("{name}: {}", method.label()));
            let result = render_method(&scene, method, &settings)?;
            let (measured, _) = measure(&result, &reference)?;
            if buffer == Buffer::Spectral {
                convert_ms = conversion_ms(&result, route)?;
                spectral = Some(measured);
                if route == XyzRoute::Zeroth {
                    save_png(
                        dir,
                        &format!("{name}-fourier{COEFFS}-{}spp.png", config.spp),
                        config.size,
                        &result.xyz,
                    )?;
                    strip.push(result.xyz.clone());
                    curve_images.push((Method::fourier(COEFFS), measured.cmp));
                }
            } else {
                rgb = Some(measured);
            }
        }
        if let Some(rgb) = rgb {
            columns.push(Column {
                name: image::route_name(route).to_string(),
                spectral,
                rgb,
                convert_ms,
                timed_spectral: None,
                timed_rgb: f64::NAN,
            });
        }
    }
    for (method, file) in [(spec32(), "spec32"), (Method::spec4_hero(), "spec4-hero")] {
        progress(&format!("{name}: {}", method.label()));
        let result = render_method(&scene, method, &settings)?;
        let (measured, _) = measure(&result, &reference)?;
        save_png(
            dir,
            &format!("{name}-{file}-{}spp.png", config.spp),
            config.size,
            &result.xyz,
        )?;
        curve_images.push((method, measured.cmp));
        strip.push(result.xyz);
        columns.push(Column {
            name: method.label(),
            spectral: None,
            rgb: measured,
            convert_ms: None,
            timed_spectral: None,
            timed_rgb: f64::NAN,
        });
    }
    let views: Vec<&[Xyz]> = strip.iter().map(Vec::as_slice).collect();
    save_strip(
        dir,
        &format!("conversions-{name}-crops.png"),
        config.size,
        &views,
    )?;
    drop(strip);
    // Interleaved, repeated timing renders (the column order: each route
    // with both buffers, then the sampled transports).
    let mut timed_methods = Vec::new();
    for route in ROUTES {
        for buffer in [Buffer::Spectral, Buffer::Xyz] {
            timed_methods.push(Method::Fourier {
                coeffs: COEFFS,
                route,
                buffer,
            });
        }
    }
    timed_methods.extend([spec32(), Method::spec4_hero()]);
    let times = timing(name, &scene, &timed_methods, config)?;
    let mut next = times.iter().copied();
    for column in columns.iter_mut() {
        if column.spectral.is_some() {
            column.timed_spectral = next.next();
        }
        column.timed_rgb = next.next().unwrap_or(f64::NAN);
    }
    let mut curves = Vec::new();
    for method in [Method::fourier(COEFFS), Method::spec4_hero(), spec32()] {
        for spp in curve_spp(config.spp) {
            let cmp = if spp == config.spp {
                curve_images
                    .iter()
                    .find(|(m, _)| *m == method)
                    .map(|(_, c)| *c)
            } else {
                None
            };
            let cmp = match cmp {
                Some(c) => c,
                None => {
                    progress(&format!("{name}: curve {} at {spp} spp", method.label()));
                    let s = image::settings(config.size, spp, TEST_SEED, config.threads);
                    let result = render_method(&scene, method, &s)?;
                    measure(&result, &reference)?.0.cmp
                }
            };
            curves.push((method.label(), spp, cmp));
        }
    }
    Ok(SceneResult {
        scene: name.to_string(),
        columns,
        reference,
        curves,
    })
}

fn scene_table(result: &SceneResult) -> Table {
    let mut headers = vec!["".to_string()];
    headers.extend(result.columns.iter().map(|c| c.name.clone()));
    let mut table = Table::new(&headers);
    let dash = || "—".to_string();
    type Cell = fn(&Column) -> Option<f64>;
    let rows: [(&str, Cell, usize); 11] = [
        (
            "mean ΔE2000 (spectral buffer; sampled: per sample)",
            |c| Some(c.spectral.unwrap_or(c.rgb).cmp.delta_e2000),
            3,
        ),
        (
            "mean ΔE76 (spectral buffer; sampled: per sample)",
            |c| Some(c.spectral.unwrap_or(c.rgb).cmp.delta_e76),
            3,
        ),
        (
            "mean chromatic error √(Δa*²+Δb*²)",
            |c| Some(c.spectral.unwrap_or(c.rgb).cmp.chroma),
            3,
        ),
        (
            "PSNR, dB",
            |c| Some(c.spectral.unwrap_or(c.rgb).cmp.psnr_db),
            2,
        ),
        (
            "mean ΔE2000, RGB buffer",
            |c| Some(c.rgb.cmp.delta_e2000),
            3,
        ),
        ("PSNR, RGB buffer, dB", |c| Some(c.rgb.cmp.psnr_db), 2),
        (
            "render time, spectral buffer, s",
            |c| c.spectral.map(|m| m.seconds),
            2,
        ),
        ("render time, RGB buffer, s", |c| Some(c.rgb.seconds), 2),
        (
            "timing render, spectral buffer, min of 3, s",
            |c| c.timed_spectral,
            3,
        ),
        (
            "timing render, RGB buffer, min of 3, s",
            |c| Some(c.timed_rgb),
            3,
        ),
        (
            "spectral-buffer conversion alone (1 thread), ms",
            |c| c.convert_ms,
            3,
        ),
    ];
    for (label, cell, decimals) in rows {
        let mut row = vec![label.to_string()];
        row.extend(
            result
                .columns
                .iter()
                .map(|c| cell(c).map_or_else(dash, |v| fixed(v, decimals))),
        );
        table.push(row);
    }
    table
}

fn curve_table(results: &[SceneResult]) -> Table {
    let mut table = Table::new(&[
        "scene",
        "method",
        "spp",
        "mean_delta_e2000",
        "mean_delta_e76",
        "mean_chroma_error",
        "psnr_db",
    ]);
    for r in results {
        for (label, spp, c) in &r.curves {
            table.push(vec![
                r.scene.clone(),
                label.clone(),
                spp.to_string(),
                fixed(c.delta_e2000, 4),
                fixed(c.delta_e76, 4),
                fixed(c.chroma, 4),
                fixed(c.psnr_db, 3),
            ]);
        }
    }
    table
}

fn curve_plots(result: &SceneResult, dir: &Path) -> Result<Vec<String>, CliError> {
    let labels: Vec<String> = [Method::fourier(COEFFS), Method::spec4_hero(), spec32()]
        .iter()
        .map(Method::label)
        .collect();
    let series = |metric: fn(&Comparison) -> f64| -> Vec<Series> {
        labels
            .iter()
            .map(|label| Series {
                name: label.clone(),
                points: result
                    .curves
                    .iter()
                    .filter(|(l, _, _)| l == label)
                    .map(|(_, spp, c)| (f64::from(*spp), metric(c)))
                    .collect(),
            })
            .collect()
    };
    let scene = &result.scene;
    let mut files = Vec::new();
    let delta_e = series(|c| c.delta_e2000);
    let title = format!("{scene}: mean ΔE2000 vs samples per pixel");
    let name = format!("conversions-{scene}-delta-e.png");
    LinePlot {
        title: &title,
        x_label: "samples per pixel",
        y_label: "mean ΔE2000",
        x_scale: Scale::Log2,
        y_scale: Scale::Log10,
        series: &delta_e,
    }
    .write_png(&dir.join(&name))?;
    files.push(name);
    let psnr = series(|c| c.psnr_db);
    let title = format!("{scene}: PSNR vs samples per pixel");
    let name = format!("conversions-{scene}-psnr.png");
    LinePlot {
        title: &title,
        x_label: "samples per pixel",
        y_label: "PSNR, dB",
        x_scale: Scale::Log2,
        y_scale: Scale::Linear,
        series: &psnr,
    }
    .write_png(&dir.join(&name))?;
    files.push(name);
    Ok(files)
}

fn claims(results: &[SceneResult], timing: (u32, u32)) -> Vec<Claim> {
    let mut claims = Vec::new();
    // 1. The zeroth-coefficient route is the fastest in both buffers.
    let mut wins = 0usize;
    let mut total = 0usize;
    let mut measured = Vec::new();
    for r in results {
        let routes: Vec<&Column> = ROUTES
            .iter()
            .filter_map(|&route| r.column(image::route_name(route)))
            .collect();
        let zeroth = r.column(image::route_name(XyzRoute::Zeroth));
        for (buffer, time) in [
            (
                "spectral",
                (|c: &Column| c.timed_spectral.unwrap_or(f64::NAN)) as fn(&Column) -> f64,
            ),
            ("RGB", |c: &Column| c.timed_rgb),
        ] {
            let Some(z) = zeroth else { continue };
            let others = routes
                .iter()
                .filter(|c| c.name != z.name)
                .map(|c| time(c))
                .fold(f64::INFINITY, f64::min);
            total += 1;
            if time(z) <= others * (1.0 + TIME_TIE_FRACTION) {
                wins += 1;
            }
            let times: Vec<String> = routes
                .iter()
                .map(|c| format!("{} {:.3}", c.name, time(c)))
                .collect();
            measured.push(format!("{} {buffer}: {} s", r.scene, times.join(", ")));
        }
    }
    let spectral_note = results
        .iter()
        .filter_map(|r| {
            let ms: Vec<String> = ROUTES
                .iter()
                .filter_map(|&route| {
                    r.column(image::route_name(route))
                        .and_then(|c| c.convert_ms)
                        .map(|v| format!("{} {v:.1}", image::route_name(route)))
                })
                .collect();
            (!ms.is_empty()).then(|| format!("{}: {} ms", r.scene, ms.join(", ")))
        })
        .collect::<Vec<_>>()
        .join("; ");
    claims.push(Claim {
        claim: "The zeroth-coefficient route is the fastest conversion in both buffers".into(),
        measured: format!(
            "Timing renders ({}×{} pixels, {} spp, minimum of {TIMING_REPEATS} interleaved runs; ties within {:.0} % count as fastest): {}. The spectral-buffer conversion step alone (1 thread): {spectral_note}.",
            timing.0,
            timing.0,
            timing.1,
            TIME_TIE_FRACTION * 100.0,
            measured.join("; ")
        ),
        verdict: if wins == total && total > 0 {
            Verdict::Holds
        } else if wins > 0 {
            Verdict::Partially
        } else {
            Verdict::DoesNotHold
        },
    });
    // 2. Fourier methods reach lower ΔE than Spec32 on the lamps scene.
    if let Some(lamps) = results.iter().find(|r| r.scene == "lamps") {
        let spec = lamps
            .column(&spec32().label())
            .map(|c| c.rgb.cmp.delta_e2000);
        let fourier: Vec<(String, f64)> = ROUTES
            .iter()
            .filter_map(|&route| {
                lamps
                    .column(image::route_name(route))
                    .and_then(|c| c.spectral)
                    .map(|m| (image::route_name(route).to_string(), m.cmp.delta_e2000))
            })
            .collect();
        if let Some(spec) = spec {
            let lower = fourier.iter().filter(|(_, d)| *d < spec).count();
            let list: Vec<String> = fourier.iter().map(|(n, d)| format!("{n} {d:.3}")).collect();
            claims.push(Claim {
                claim: "On the lamps scene the Fourier methods reach a lower ΔE than Spec32".into(),
                measured: format!(
                    "mean ΔE2000: Fourier N={COEFFS} {} vs Spec32 {spec:.3} (reference's own noise ≈ {:.3}).",
                    list.join(", "),
                    lamps.reference.halves.delta_e2000 / 2.0
                ),
                verdict: if lower == fourier.len() && lower > 0 {
                    Verdict::Holds
                } else if lower > 0 {
                    Verdict::Partially
                } else {
                    Verdict::DoesNotHold
                },
            });
        }
    }
    // 3. On the laser scene the Fourier method removes most colour noise.
    if let Some(laser) = results.iter().find(|r| r.scene == "laser") {
        let chroma = |name: &str| {
            laser
                .column(name)
                .map(|c| c.spectral.unwrap_or(c.rgb).cmp.chroma)
        };
        let fourier = chroma(image::route_name(XyzRoute::Zeroth));
        let s32 = chroma(&spec32().label());
        let s4 = chroma(&Method::spec4_hero().label());
        if let (Some(f), Some(s32), Some(s4)) = (fourier, s32, s4) {
            let floor = laser.reference.halves.chroma / 2.0;
            // The reference's own noise adds in quadrature to each error.
            let own = |e: f64| (e * e - floor * floor).max(0.0).sqrt();
            let (cf, c32, c4) = (own(f), own(s32), own(s4));
            claims.push(Claim {
                claim: "On the laser scene the Fourier method removes most colour noise".into(),
                measured: format!(
                    "mean chromatic error √(Δa*²+Δb*²) against the reference: Fourier N={COEFFS} {f:.3}, Spec32 {s32:.3}, Spec4 hero {s4:.3}; the reference's own chromatic noise ≈ {floor:.3}; with it removed in quadrature: Fourier {cf:.3}, Spec32 {c32:.3} ({:.0} % removed), Spec4 hero {c4:.3} ({:.0} % removed).",
                    100.0 * (1.0 - cf / c32),
                    100.0 * (1.0 - cf / c4)
                ),
                verdict: if cf <= MOST_REMOVED_FRACTION * c32 && cf <= MOST_REMOVED_FRACTION * c4 {
                    Verdict::Holds
                } else if cf <= MOST_REMOVED_FRACTION * c4 || cf < c32 {
                    Verdict::Partially
                } else {
                    Verdict::DoesNotHold
                },
            });
        }
    }
    // 4. MESE costs much more time and gains little.
    let mut parts = Vec::new();
    let mut slow = 0usize;
    let mut little = 0usize;
    for r in results {
        let (Some(m), Some(z)) = (
            r.column(image::route_name(XyzRoute::Mese)),
            r.column(image::route_name(XyzRoute::Zeroth)),
        ) else {
            continue;
        };
        let ratio_rgb = m.timed_rgb / z.timed_rgb;
        let ratio_spectral = match (m.timed_spectral, z.timed_spectral) {
            (Some(a), Some(b)) => a / b,
            _ => f64::NAN,
        };
        let de = |c: &Column| c.spectral.unwrap_or(c.rgb).cmp.delta_e2000;
        let gain = de(z) - de(m);
        let gain_rgb = z.rgb.cmp.delta_e2000 - m.rgb.cmp.delta_e2000;
        if ratio_rgb >= MUCH_SLOWER_FACTOR {
            slow += 1;
        }
        if gain < LITTLE_GAIN_FRACTION * de(z) && gain_rgb < LITTLE_GAIN_FRACTION * de(z) {
            little += 1;
        }
        parts.push(format!(
            "{}: time MESE/zeroth {ratio_spectral:.2}× (spectral buffer), {ratio_rgb:.2}× (RGB buffer); ΔE2000 gain {gain:+.3} (spectral), {gain_rgb:+.3} (RGB) on {:.3}",
            r.scene,
            de(z)
        ));
    }
    let n = parts.len();
    claims.push(Claim {
        claim: "MESE costs much more time and gains little".into(),
        measured: format!(
            "{} (\"much more\": ≥ {MUCH_SLOWER_FACTOR}× in the RGB buffer; \"little\": gain < {:.0} % of ΔE).",
            parts.join("; "),
            LITTLE_GAIN_FRACTION * 100.0
        ),
        verdict: if n > 0 && slow == n && little == n {
            Verdict::Holds
        } else if slow > 0 || little > 0 {
            Verdict::Partially
        } else {
            Verdict::DoesNotHold
        },
    });
    claims
}

/// Runs the experiment, writing into `dir`.
pub fn run(config: &Config, dir: &Path) -> Result<Section, CliError> {
    let mut results = Vec::new();
    for name in SCENES {
        results.push(run_scene(name, config, dir)?);
    }
    let (chunks, chunk_spp) = image::reference_chunks(config.reference_spp);
    let mut md = String::new();
    let mut files = Vec::new();
    let _ = writeln!(
        md,
        "## Conversions (the paper's table, figures 7 and 10)\n\n{}×{} pixels, {} spp, Fourier N = {COEFFS}, max depth 8, Gaussian filter, seed {TEST_SEED} for every compared render (the same paths for all methods). Reference: {} at {} spp ({} chunks of {} spp, seeds from {}). Metrics on the displayed image (linear sRGB clamped to [0, 1]; Lab relative to the D65 display white; PSNR on the sRGB-encoded values). Times: wall clock on all cores; the \"render time\" rows are the single table renders, the \"timing render\" rows the minimum of {TIMING_REPEATS} interleaved renders at {}×{} pixels and {} spp (less disturbed by other load; the claims use these).\n",
        config.size,
        config.size,
        config.spp,
        Method::reference().label(),
        chunks * chunk_spp,
        chunks,
        chunk_spp,
        image::REFERENCE_SEED,
        timing_size(config).0,
        timing_size(config).0,
        timing_size(config).1,
    );
    for r in &results {
        let table = scene_table(r);
        let csv = format!("conversions-{}.csv", r.scene);
        files.push(write_text(dir, &csv, &table.to_csv())?);
        let _ = writeln!(
            md,
            "### Scene `{}`\n\nReference noise: mean ΔE2000 between its two halves {:.3} (ΔE76 {:.3}, chromatic {:.3}, PSNR {:.2} dB), so the full reference's own noise is about half of that: ΔE2000 ≈ {:.3}. Reference render time {:.1} s (0 = cached).\n\n{}\n[{csv}]({csv}) · ![{} ΔE]({}) ![{} PSNR]({})\n\nCrops at full resolution, left to right: reference, Fourier N = {COEFFS}, Spec32, Spec4 hero ({} spp): ![{} crops](conversions-{}-crops.png)\n",
            r.scene,
            r.reference.halves.delta_e2000,
            r.reference.halves.delta_e76,
            r.reference.halves.chroma,
            r.reference.halves.psnr_db,
            r.reference.halves.delta_e2000 / 2.0,
            r.reference.seconds,
            table.to_markdown(),
            r.scene,
            format_args!("conversions-{}-delta-e.png", r.scene),
            r.scene,
            format_args!("conversions-{}-psnr.png", r.scene),
            config.spp,
            r.scene,
            r.scene,
        );
        for name in curve_plots(r, dir)? {
            files.push(dir.join(name));
        }
        files.push(dir.join(format!("conversions-{}-crops.png", r.scene)));
    }
    let curves = curve_table(&results);
    files.push(write_text(dir, "conversions-curves.csv", &curves.to_csv())?);
    let _ = writeln!(
        md,
        "Curves (all scenes): [conversions-curves.csv](conversions-curves.csv)\n\n{}",
        curves.to_markdown()
    );
    let claims = claims(&results, timing_size(config));
    let _ = writeln!(
        md,
        "### Claims\n\n{}",
        super::report::claims_markdown(&claims)
    );
    files.push(write_text(dir, "conversions.md", &md)?);
    Ok(Section {
        markdown: md,
        claims,
        files,
    })
}
