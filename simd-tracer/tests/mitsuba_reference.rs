//! The `cornell` scene against Mitsuba 3's `mi.cornell_box()`.
//!
//! `tests/data/mitsuba-cornell-64x64-8192spp.exr` is Mitsuba 3.9.1's
//! `scalar_spectral` render of its built-in Cornell box at 64 × 64, 8192 spp,
//! max depth 8, Gaussian filter (σ = 0.5 px), linear sRGB (made by
//! `tools/mitsuba_cornell.py`; see `tests/data/README.md`). This test renders
//! our `cornell` scene in-process with the same camera, filter and depth
//! (Fourier N = 12, the default transport) at fewer samples, converts XYZ to
//! linear sRGB with `spectral_core::color` and compares the image's
//! per-channel means and the means of 16 × 16-pixel blocks.
//!
//! Measured at high sample counts (ours 4096 spp vs the reference), the
//! agreement is: image-mean R, G, B ratios 1.000, 0.998, 1.004 (sampled
//! transport, 4 hero wavelengths: 0.999, 0.998, 0.993); ΔE2000 of 8 × 8
//! block means: mean 0.17, max 1.05; of 16 × 16 blocks: max 0.39. Two
//! systematic differences are left, neither a bug:
//! (a) the blue channel of the red wall (reflectance 0.044) is ~25 % higher
//! in Fourier N = 12 (ΔE2000 ≤ 0.4): truncation of the series of the
//! upsampled red (the sampled transport is within 7 % there, its noise);
//! (b) the pixel row above the light's edge is 4 % darker in ours and the
//! light's middle row 1 % brighter, as expected from Mitsuba tabulating its
//! Gaussian (31 piecewise-constant steps over the radius, evaluated at each
//! step's inner end: effective σ 0.512 px, which predicts 4.6 % here); the
//! light's total is equal within 0.3 %.
//!
//! Tolerances: noise of this test's own render measured over 8 seeds at
//! `SPP` = 64 (`noise_over_seeds`) plus the systematic part above.
//! * Image-mean channel ratio: systematic ≤ 0.4 %, σ ≤ 0.6 % over seeds,
//!   so 0.4 % + 4σ = 2.8 % → 3 %.
//! * Block ΔE2000 (16 × 16 blocks): mean over seeds ≤ 0.39 per block, σ
//!   ≤ 0.19 (the blocks of the light), max over blocks of mean + 4σ = 1.06
//!   → 1.2.
//!
//! The render is deterministic for a seed, so the test cannot flake; the
//! margins are for changes of sampling that keep the expected image. A light
//! 10 % too bright (ratios 1.10, block ΔE up to 2.5) or red and green walls
//! swapped (block ΔE up to 36) fail: the second test renders both.

use simd_tracer::film::Buffer;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::builtin::{CORNELL_MTL, CORNELL_OBJ, cornell_camera};
use simd_tracer::scene::obj::{ObjSource, load_obj};
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::color::LinearSrgb;
use spectral_core::delta_e::delta_e2000;
use spectral_core::xyz::XyzRoute;
use std::path::PathBuf;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const SIZE: usize = 64;
const BLOCK: usize = 16;
const BLOCKS: usize = SIZE / BLOCK;
const REFERENCE: &str = "tests/data/mitsuba-cornell-64x64-8192spp.exr";
/// Samples per pixel of our side.
const SPP: u32 = 64;
/// Largest relative difference of an image-mean channel (module docs).
const MEAN_TOLERANCE: f64 = 0.03;
/// Largest ΔE2000 of a block mean (module docs).
const BLOCK_DE_TOLERANCE: f64 = 1.2;

/// The reference image, linear sRGB, row-major from the top-left.
fn reference() -> TestResult<Vec<[f64; 3]>> {
    use exr::prelude::read_first_rgba_layer_from_file;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(REFERENCE);
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| vec![[0.0f64; 3]; resolution.width() * resolution.height()],
        |pixels, position, (r, g, b, _a): (f32, f32, f32, f32)| {
            pixels[position.y() * SIZE + position.x()] = [r, g, b].map(f64::from);
        },
    )?;
    let size = image.layer_data.size;
    if (size.width(), size.height()) != (SIZE, SIZE) {
        return Err(format!("{REFERENCE}: {size:?}, expected {SIZE} × {SIZE}").into());
    }
    Ok(image.layer_data.channel_data.pixels)
}

/// The Cornell box with the MTL text `mtl`.
fn cornell(range: SpectralRange, mtl: &str) -> TestResult<Scene> {
    let mut builder = SceneBuilder::new(range);
    let source = ObjSource::Text {
        name: "cornell.obj",
        obj: CORNELL_OBJ,
        mtl,
    };
    load_obj(&mut builder, source, &|_| None)?;
    builder.set_camera(cornell_camera()?);
    Ok(builder.build()?)
}

/// Our render of `scene` at the reference's settings, linear sRGB.
fn ours(scene: &Scene, spp: u32, seed: u64) -> TestResult<Vec<[f64; 3]>> {
    let range = SpectralRange::VISIBLE;
    let transport = FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let settings = RenderSettings {
        width: SIZE as u32,
        height: SIZE as u32,
        spp,
        seed,
        // Mitsuba's defaults for this scene: max depth 8, roulette from
        // depth 5, Gaussian σ = 0.5 px.
        ..RenderSettings::default()
    };
    let result = render(&transport, scene, &settings, &mut |_| true)?;
    Ok(result
        .xyz
        .iter()
        .map(|xyz| {
            let LinearSrgb { r, g, b } = xyz.to_linear_srgb();
            [r, g, b]
        })
        .collect())
}

fn mean(image: &[[f64; 3]]) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for p in image {
        for c in 0..3 {
            sum[c] += p[c];
        }
    }
    sum.map(|s| s / image.len() as f64)
}

/// Block means, row-major.
fn blocks(image: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(BLOCKS * BLOCKS);
    for by in 0..BLOCKS {
        for bx in 0..BLOCKS {
            let pixels: Vec<[f64; 3]> = (by * BLOCK..(by + 1) * BLOCK)
                .flat_map(|y| (bx * BLOCK..(bx + 1) * BLOCK).map(move |x| image[y * SIZE + x]))
                .collect();
            out.push(mean(&pixels));
        }
    }
    out
}

/// ΔE2000 of two linear-sRGB colours (Lab white: D65 with Y = 1; the
/// reference image's mean Y is about 0.15).
fn delta_e(a: [f64; 3], b: [f64; 3]) -> f64 {
    let white = LinearSrgb::new(1.0, 1.0, 1.0).to_xyz();
    let lab = |c: [f64; 3]| LinearSrgb::new(c[0], c[1], c[2]).to_xyz().to_lab(white);
    delta_e2000(lab(a), lab(b))
}

/// How `image` differs from `reference`: the image-mean channel ratios and
/// the block ΔE2000s.
struct Comparison {
    ratios: [f64; 3],
    block_de: Vec<f64>,
}

impl Comparison {
    fn new(image: &[[f64; 3]], reference: &[[f64; 3]]) -> Self {
        let (m, r) = (mean(image), mean(reference));
        let ratios = [0, 1, 2].map(|c| m[c] / r[c]);
        let block_de = blocks(image)
            .iter()
            .zip(blocks(reference))
            .map(|(a, b)| delta_e(*a, b))
            .collect();
        Self { ratios, block_de }
    }

    fn max_de(&self) -> f64 {
        self.block_de.iter().copied().fold(0.0, f64::max)
    }

    fn passes(&self) -> bool {
        self.ratios
            .iter()
            .all(|r| (r - 1.0).abs() <= MEAN_TOLERANCE)
            && self.max_de() <= BLOCK_DE_TOLERANCE
    }

    fn report(&self, label: &str) {
        println!(
            "{label}: mean ratios R {:.4} G {:.4} B {:.4}, block ΔE2000 max {:.3}",
            self.ratios[0],
            self.ratios[1],
            self.ratios[2],
            self.max_de()
        );
        for row in self.block_de.chunks(BLOCKS) {
            let cells: Vec<String> = row.iter().map(|d| format!("{d:5.2}")).collect();
            println!("  {}", cells.join(" "));
        }
    }
}

#[test]
fn cornell_matches_mitsuba_3() -> TestResult {
    let reference = reference()?;
    let range = SpectralRange::VISIBLE;
    let scene = cornell(range, CORNELL_MTL)?;
    let comparison = Comparison::new(&ours(&scene, SPP, 1)?, &reference);
    comparison.report("cornell vs Mitsuba 3");
    assert!(
        comparison.passes(),
        "cornell differs from Mitsuba 3's mi.cornell_box(): ratios {:?}, block ΔE2000 {:?}",
        comparison.ratios,
        comparison.block_de
    );
    Ok(())
}

#[test]
fn the_comparison_rejects_a_brighter_light_and_swapped_walls() -> TestResult {
    let reference = reference()?;
    let range = SpectralRange::VISIBLE;
    let red = "Kd 0.570068 0.043014 0.044371";
    let green = "Kd 0.105421 0.377980 0.076425";
    let light = "Ke 18.38700 13.98730 6.75357";
    for needle in [red, green, light] {
        if !CORNELL_MTL.contains(needle) {
            return Err(format!("cornell.mtl has no line `{needle}`").into());
        }
    }
    let brighter = CORNELL_MTL.replace(light, "Ke 20.22570 15.38603 7.42893");
    let swapped = CORNELL_MTL
        .replace(red, "Kd swap")
        .replace(green, red)
        .replace("Kd swap", green);
    for (label, mtl) in [
        ("light 10 % brighter", brighter),
        ("walls swapped", swapped),
    ] {
        let scene = cornell(range, &mtl)?;
        let comparison = Comparison::new(&ours(&scene, SPP, 1)?, &reference);
        comparison.report(label);
        assert!(!comparison.passes(), "{label}: not detected");
    }
    Ok(())
}

/// Noise of this test's render: image-mean ratios and block ΔE2000 over
/// seeds (`cargo test -p simd-tracer --test mitsuba_reference -- --ignored
/// --nocapture`); the basis of the tolerances.
#[test]
#[ignore = "measurement, not a check"]
fn noise_over_seeds() -> TestResult {
    let reference = reference()?;
    let scene = cornell(SpectralRange::VISIBLE, CORNELL_MTL)?;
    for seed in 1..=8 {
        Comparison::new(&ours(&scene, SPP, seed)?, &reference).report(&format!("seed {seed}"));
    }
    Ok(())
}
