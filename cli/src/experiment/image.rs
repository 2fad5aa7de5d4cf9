//! Rendering the built-in scenes by each method, comparing images, and the
//! cached converged reference.
//!
//! **Image metrics.** Images are compared as the PNG shows them: XYZ → linear
//! sRGB (exposure 0) → each channel clamped to [0, 1]. ΔE: the clamped
//! colour back to XYZ, CIELAB relative to the sRGB display white (D65,
//! `Y = 1`, i.e. linear sRGB (1, 1, 1)), then CIEDE2000 and CIE76 per pixel,
//! averaged over all pixels. PSNR: `10 log₁₀(1/MSE)` over the three
//! sRGB-encoded (gamma) channels of the clamped image, in dB (capped at
//! [`PSNR_CAP_DB`] for identical images).
//!
//! **Chromatic error** (colour noise): `√(Δa*² + Δb*²)` per pixel, the
//! CIELAB difference without its lightness part, averaged.
//!
//! **Reference.** An unbiased sampled render (32 stratified wavelengths per
//! path) at high spp, made of an even number of independent chunks of at
//! most [`REFERENCE_CHUNK_SPP`] spp (seeds from [`REFERENCE_SEED`]); the
//! reference is their mean, and the mean ΔE between the mean of the even
//! and the mean of the odd chunks (two independent halves) measures its own
//! noise: each half has √2 times the noise of the full reference, their
//! difference 2 times, so the reference's own noise is about half the
//! half-vs-half ΔE. Chunks are cached in `OUT/cache/` (raw little-endian
//! `f32` XYZ after a text header) and reused when the scene, size, spp and
//! seed match, so a larger `--reference-spp` only renders the new chunks;
//! delete the folder after changing the renderer.

use crate::error::CliError;
use simd_tracer::film::filter::Filter;
use simd_tracer::film::{Buffer, FilmMode};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::sampling::sampler::SamplerKind;
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::color::{Lab, LinearSrgb, Xyz, clamp_unit};
use spectral_core::delta_e::{delta_e76, delta_e2000};
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use std::path::{Path, PathBuf};

/// Seed of the first reference chunk (chunk `i` has `REFERENCE_SEED + i`).
pub const REFERENCE_SEED: u64 = 1001;
/// Most samples per pixel of one reference chunk.
pub const REFERENCE_CHUNK_SPP: u32 = 128;
/// Seed of every compared render (all methods share the path random
/// numbers: common random numbers, the differences are spectral only).
pub const TEST_SEED: u64 = 1;
/// PSNR reported for identical images, dB.
pub const PSNR_CAP_DB: f64 = 200.0;
/// Longest path (segments) and Russian-roulette depth: `fspec render`'s
/// defaults.
const MAX_DEPTH: u32 = 8;
const RR_DEPTH: u32 = 5;
/// Header line of a cached reference half.
const CACHE_MAGIC: &str = "fspec-reference-xyz-f32-v1";

/// A way to render: what a path carries and how colour is formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// `coeffs` Fourier coefficients, converted by `route` in `buffer`.
    Fourier {
        /// N.
        coeffs: usize,
        /// Conversion route.
        route: XyzRoute,
        /// Spectral (per pixel) or XYZ (per sample) buffer.
        buffer: Buffer,
    },
    /// `wavelengths` sampled wavelengths per path.
    Sampled {
        /// C.
        wavelengths: usize,
        /// How they are chosen.
        strategy: WavelengthStrategy,
    },
}

impl Method {
    /// Fourier N with the zeroth-coefficient route and a spectral buffer.
    pub fn fourier(coeffs: usize) -> Self {
        Self::Fourier {
            coeffs,
            route: XyzRoute::Zeroth,
            buffer: Buffer::Spectral,
        }
    }

    /// The reference transport: 32 stratified wavelengths.
    pub fn reference() -> Self {
        Self::Sampled {
            wavelengths: 32,
            strategy: WavelengthStrategy::Stratified,
        }
    }

    /// Spec4 hero: 4 hero wavelengths (pbrt-v4 / Mitsuba 3 style).
    pub fn spec4_hero() -> Self {
        Self::Sampled {
            wavelengths: 4,
            strategy: WavelengthStrategy::Hero,
        }
    }

    /// A short label, e.g. `Fourier N=12 zeroth, spectral buffer`.
    pub fn label(&self) -> String {
        match *self {
            Self::Fourier {
                coeffs,
                route,
                buffer,
            } => format!(
                "Fourier N={coeffs} {}, {} buffer",
                route_name(route),
                match buffer {
                    Buffer::Spectral => "spectral",
                    Buffer::Xyz => "RGB",
                }
            ),
            Self::Sampled {
                wavelengths,
                strategy,
            } => format!("Spec{wavelengths} {}", strategy_name(strategy)),
        }
    }
}

/// The name of a conversion route.
pub fn route_name(route: XyzRoute) -> &'static str {
    match route {
        XyzRoute::Series => "series",
        XyzRoute::Lut => "lookup table",
        XyzRoute::Zeroth => "zeroth coefficient",
        XyzRoute::Mese => "MESE",
    }
}

/// The name of a wavelength strategy.
pub fn strategy_name(strategy: WavelengthStrategy) -> &'static str {
    match strategy {
        WavelengthStrategy::Uniform => "uniform",
        WavelengthStrategy::Stratified => "stratified",
        WavelengthStrategy::Hero => "hero",
        WavelengthStrategy::Visible => "visible",
        WavelengthStrategy::VisibleHero => "visible hero",
    }
}

/// Builds built-in scene `name` over 360–830 nm.
pub fn load_scene(name: &str) -> Result<Scene, CliError> {
    builtin_scene(name, SpectralRange::VISIBLE, &SceneOptions::default())
        .map_err(|e| CliError::input(e.to_string()))?
        .build()
        .map_err(|e| CliError::input(format!("{name}: {e}")))
}

/// Render settings: `size × size` pixels, `spp`, `seed`, Gaussian filter,
/// `fspec render`'s depth and roulette.
pub fn settings(size: u32, spp: u32, seed: u64, threads: Option<usize>) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        spp,
        integrator: IntegratorSettings {
            max_depth: MAX_DEPTH,
            rr_depth: RR_DEPTH,
            hide_emitters: false,
        },
        seed,
        filter: Filter::gaussian(),
        threads,
        time_limit: None,
        window: None,
        film: FilmMode::Sample,
        // The experiments' recorded figures were measured with it.
        sampler: SamplerKind::Independent,
    }
}

fn run<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    render(transport, scene, settings, &mut |_| true).map_err(|e| CliError::input(e.to_string()))
}

fn fourier<const N: usize>(
    scene: &Scene,
    route: XyzRoute,
    buffer: Buffer,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    let transport = FourierTransport::<N>::new(scene.range(), buffer, route)
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    run(&transport, scene, settings)
}

fn sampled<const C: usize>(
    scene: &Scene,
    strategy: WavelengthStrategy,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    run(
        &SampledTransport::<C>::new(scene.range(), strategy),
        scene,
        settings,
    )
}

/// Renders `scene` by `method` (N ∈ {4, 8, 12, 16, 24, 32}, C ∈ {4, 8, 32}).
pub fn render_method(
    scene: &Scene,
    method: Method,
    settings: &RenderSettings,
) -> Result<RenderResult, CliError> {
    match method {
        Method::Fourier {
            coeffs,
            route,
            buffer,
        } => match coeffs {
            4 => fourier::<4>(scene, route, buffer, settings),
            8 => fourier::<8>(scene, route, buffer, settings),
            12 => fourier::<12>(scene, route, buffer, settings),
            16 => fourier::<16>(scene, route, buffer, settings),
            24 => fourier::<24>(scene, route, buffer, settings),
            32 => fourier::<32>(scene, route, buffer, settings),
            n => Err(CliError::input(format!(
                "experiment: N = {n} coefficients is not compiled in (4, 8, 12, 16, 24, 32)"
            ))),
        },
        Method::Sampled {
            wavelengths,
            strategy,
        } => match wavelengths {
            4 => sampled::<4>(scene, strategy, settings),
            8 => sampled::<8>(scene, strategy, settings),
            32 => sampled::<32>(scene, strategy, settings),
            c => Err(CliError::input(format!(
                "experiment: C = {c} wavelengths is not compiled in (4, 8, 32)"
            ))),
        },
    }
}

/// The clamped display colour of `xyz` (module docs).
fn display_rgb(xyz: Xyz) -> LinearSrgb {
    let rgb = xyz.to_linear_srgb();
    LinearSrgb::new(clamp_unit(rgb.r), clamp_unit(rgb.g), clamp_unit(rgb.b))
}

/// An image as displayed: CIELAB and sRGB-encoded values per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct DisplayImage {
    /// CIELAB relative to the display white.
    pub lab: Vec<Lab>,
    /// sRGB-encoded channels in [0, 1].
    pub encoded: Vec<[f64; 3]>,
}

impl DisplayImage {
    /// The display form of an XYZ image.
    pub fn new(xyz: &[Xyz]) -> Self {
        let white = LinearSrgb::new(1.0, 1.0, 1.0).to_xyz();
        let (lab, encoded) = xyz
            .iter()
            .map(|&v| {
                let rgb = display_rgb(v);
                (rgb.to_xyz().to_lab(white), rgb.encode())
            })
            .unzip();
        Self { lab, encoded }
    }
}

/// Mean differences between a test image and a reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    /// Mean CIEDE2000.
    pub delta_e2000: f64,
    /// Mean CIE76.
    pub delta_e76: f64,
    /// Mean chromatic difference `√(Δa*² + Δb*²)`.
    pub chroma: f64,
    /// PSNR of the sRGB-encoded channels, dB.
    pub psnr_db: f64,
}

/// Compares two display images of the same size (module docs).
pub fn compare(test: &DisplayImage, reference: &DisplayImage) -> Result<Comparison, CliError> {
    let pixels = test.lab.len();
    if pixels == 0 || pixels != reference.lab.len() {
        return Err(CliError::input(format!(
            "experiment: cannot compare images of {pixels} and {} pixels",
            reference.lab.len()
        )));
    }
    let (mut de2000, mut de76, mut chroma, mut squared) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..pixels {
        let (a, b) = (test.lab[i], reference.lab[i]);
        de2000 += delta_e2000(a, b);
        de76 += delta_e76(a, b);
        chroma += (a.a - b.a).hypot(a.b - b.b);
        squared += test.encoded[i]
            .iter()
            .zip(&reference.encoded[i])
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>();
    }
    let n = pixels as f64;
    let mse = squared / (3.0 * n);
    let psnr_db = if mse > 0.0 {
        (-10.0 * mse.log10()).min(PSNR_CAP_DB)
    } else {
        PSNR_CAP_DB
    };
    Ok(Comparison {
        delta_e2000: de2000 / n,
        delta_e76: de76 / n,
        chroma: chroma / n,
        psnr_db,
    })
}

/// Means of `block × block` pixel blocks of a `size × size` XYZ image (the
/// last partial row/column of blocks is dropped; a block larger than the
/// image shrinks to the whole image).
pub fn block_means(xyz: &[Xyz], size: u32, block: u32) -> Vec<Xyz> {
    let (size, block) = (size as usize, block.clamp(1, size.max(1)) as usize);
    let blocks = size / block;
    let mut out = Vec::with_capacity(blocks * blocks);
    for by in 0..blocks {
        for bx in 0..blocks {
            let mut sum = [0.0; 3];
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    if let Some(v) = xyz.get(y * size + x) {
                        for (s, c) in sum.iter_mut().zip(v.to_array()) {
                            *s += c;
                        }
                    }
                }
            }
            out.push(Xyz::from_array(sum.map(|s| s / (block * block) as f64)));
        }
    }
    out
}

/// The converged reference of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Mean of all chunks, XYZ per pixel.
    pub xyz: Vec<Xyz>,
    /// Its display form.
    pub display: DisplayImage,
    /// Half A vs half B.
    pub halves: Comparison,
    /// Half A vs half B on block means of [`crate::experiment::BIAS_BLOCK_PX`].
    pub halves_blocks: Comparison,
    /// Samples per pixel of the whole reference (chunks × chunk spp).
    pub spp: u32,
    /// Render seconds of the chunks rendered now (0 when all were cached).
    pub seconds: f64,
}

fn cache_path(dir: &Path, scene: &str, size: u32, spp: u32, seed: u64) -> PathBuf {
    dir.join(format!(
        "reference-{scene}-{size}px-{spp}spp-seed{seed}.xyz"
    ))
}

fn read_cache(path: &Path, size: u32) -> Option<Vec<Xyz>> {
    let bytes = std::fs::read(path).ok()?;
    let newline = bytes.iter().position(|&b| b == b'\n')?;
    let header = std::str::from_utf8(&bytes[..newline]).ok()?;
    if header != format!("{CACHE_MAGIC} {size} {size}") {
        return None;
    }
    let body = &bytes[newline + 1..];
    let pixels = size as usize * size as usize;
    if body.len() != pixels * 12 {
        return None;
    }
    let values: Vec<f64> = body
        .chunks_exact(4)
        .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
        .collect();
    Some(
        values
            .chunks_exact(3)
            .map(|c| Xyz::new(c[0], c[1], c[2]))
            .collect(),
    )
}

fn write_cache(path: &Path, size: u32, xyz: &[Xyz]) -> Result<(), CliError> {
    let mut bytes = format!("{CACHE_MAGIC} {size} {size}\n").into_bytes();
    for v in xyz {
        for c in v.to_array() {
            bytes.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    std::fs::write(path, bytes)
        .map_err(|e| CliError::input(format!("{}: cannot write: {e}", path.display())))
}

/// How a reference of `spp` samples per pixel is split: an even number of
/// chunks of at most [`REFERENCE_CHUNK_SPP`] each (`chunks`, `chunk_spp`).
pub fn reference_chunks(spp: u32) -> (u32, u32) {
    let chunks = spp.div_ceil(REFERENCE_CHUNK_SPP).max(2).next_multiple_of(2);
    (chunks, (spp / chunks).max(1))
}

fn mean_image(images: &[&Vec<Xyz>]) -> Vec<Xyz> {
    let n = images.len().max(1) as f64;
    let pixels = images.first().map_or(0, |i| i.len());
    (0..pixels)
        .map(|p| {
            let mut sum = [0.0; 3];
            for image in images {
                for (s, c) in sum.iter_mut().zip(image[p].to_array()) {
                    *s += c;
                }
            }
            Xyz::from_array(sum.map(|v| v / n))
        })
        .collect()
}

/// The reference of `scene_name` at `size`², about `spp` samples per pixel
/// in chunks ([`reference_chunks`]; chunk `i` has seed
/// `REFERENCE_SEED + i`), each from `cache_dir` when cached. Half A is the
/// even chunks, half B the odd ones.
pub fn reference(
    scene_name: &str,
    scene: &Scene,
    size: u32,
    spp: u32,
    threads: Option<usize>,
    cache_dir: &Path,
) -> Result<Reference, CliError> {
    std::fs::create_dir_all(cache_dir)
        .map_err(|e| CliError::input(format!("{}: {e}", cache_dir.display())))?;
    let (chunks, chunk_spp) = reference_chunks(spp);
    let mut images = Vec::with_capacity(chunks as usize);
    let mut seconds = 0.0;
    for i in 0..chunks {
        let seed = REFERENCE_SEED + u64::from(i);
        let path = cache_path(cache_dir, scene_name, size, chunk_spp, seed);
        if let Some(xyz) = read_cache(&path, size) {
            eprintln!("  reference {scene_name}: cached {}", path.display());
            images.push(xyz);
            continue;
        }
        eprintln!(
            "  reference {scene_name}: rendering {} at {size}×{size}, {chunk_spp} spp, seed {seed}",
            Method::reference().label()
        );
        let result = render_method(
            scene,
            Method::reference(),
            &settings(size, chunk_spp, seed, threads),
        )?;
        seconds += result.elapsed.as_secs_f64();
        write_cache(&path, size, &result.xyz)?;
        images.push(result.xyz);
    }
    let even: Vec<&Vec<Xyz>> = images.iter().step_by(2).collect();
    let odd: Vec<&Vec<Xyz>> = images.iter().skip(1).step_by(2).collect();
    let (a, b) = (mean_image(&even), mean_image(&odd));
    let all: Vec<&Vec<Xyz>> = images.iter().collect();
    let xyz = mean_image(&all);
    let halves = compare(&DisplayImage::new(&a), &DisplayImage::new(&b))?;
    let block = super::BIAS_BLOCK_PX;
    let halves_blocks = compare(
        &DisplayImage::new(&block_means(&a, size, block)),
        &DisplayImage::new(&block_means(&b, size, block)),
    )?;
    Ok(Reference {
        display: DisplayImage::new(&xyz),
        xyz,
        halves,
        halves_blocks,
        spp: chunks * chunk_spp,
        seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_compare_to_zero_and_the_cap() {
        let xyz = vec![Xyz::new(0.2, 0.3, 0.1), Xyz::new(2.0, 2.0, 2.0)];
        let d = DisplayImage::new(&xyz);
        let c = compare(&d, &d).unwrap();
        assert_eq!(c.delta_e2000, 0.0);
        assert_eq!(c.psnr_db, PSNR_CAP_DB);
        let other = DisplayImage::new(&[Xyz::new(0.0, 0.0, 0.0), Xyz::new(2.0, 2.0, 2.0)]);
        let c = compare(&other, &d).unwrap();
        assert!(c.delta_e2000 > 0.0 && c.psnr_db < 30.0);
        assert!(compare(&d, &DisplayImage::new(&xyz[..1])).is_err());
    }

    #[test]
    fn block_means_average_blocks() {
        let xyz: Vec<Xyz> = (0..16).map(|i| Xyz::new(f64::from(i), 0.0, 1.0)).collect();
        let b = block_means(&xyz, 4, 2);
        assert_eq!(b.len(), 4);
        assert_eq!(b[0].x, (0.0 + 1.0 + 4.0 + 5.0) / 4.0);
        assert_eq!(b[3].z, 1.0);
        assert_eq!(block_means(&xyz, 4, 16).len(), 1);
    }

    #[test]
    fn reference_chunks_are_even_and_at_most_the_chunk_spp() {
        assert_eq!(reference_chunks(256), (2, 128));
        assert_eq!(reference_chunks(512), (4, 128));
        assert_eq!(reference_chunks(4), (2, 2));
        assert_eq!(reference_chunks(300), (4, 75));
    }

    #[test]
    fn cache_round_trip() {
        let dir = test_support::ScratchDir::new("fspec-exp-cache", "round-trip").unwrap();
        let xyz = vec![Xyz::new(0.5, 0.25, 0.125); 4];
        let path = cache_path(&dir, "x", 2, 8, 1);
        write_cache(&path, 2, &xyz).unwrap();
        assert_eq!(read_cache(&path, 2).unwrap(), xyz);
        assert!(read_cache(&path, 3).is_none());
    }
}
