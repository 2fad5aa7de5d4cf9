//! The thin-lens camera against its geometry: a lens images every point of
//! an object at depth `z` as the pinhole does, shifted by `L (1/f − 1/z)`
//! for the aperture point `L` (`scene::camera`'s module docs), so its image
//! is the pinhole image convolved with a uniform disk of radius
//! `R = A |1/f − 1/z|` (tangent units): the same total light, the same
//! centroid, and a second moment larger by `R²/2` (a uniform disk's,
//! summed over both axes). In focus (`f = z`) the image is the pinhole's.
//! Negative controls: a smaller aperture and another focus distance miss
//! the predicted moment.

mod glowing_squares;

use glam::Vec3;
use glowing_squares::{SIZE, TestResult, luminance};
use simd_tracer::scene::Scene;
use simd_tracer::scene::camera::Camera;

/// Field of view along the smaller axis, degrees.
const FOV_DEG: f32 = 40.0;
/// Depth of the glowing square in front of the camera.
const DEPTH: f32 = 4.0;
/// Edge of the glowing square (6.6 px on the film at `DEPTH`).
const EDGE: f32 = 0.4;
/// Samples per pixel.
const SPP: u32 = 256;

/// The camera at the origin looking down `−z` at a glowing square of edge
/// [`EDGE`] at depth [`DEPTH`], on black; with a lens of `aperture_radius`
/// focused at `focus_distance` (aperture 0: the pinhole).
fn scene(aperture_radius: f32, focus_distance: f32) -> TestResult<Scene> {
    let camera = Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, FOV_DEG)?
        .with_lens(aperture_radius, focus_distance)?;
    glowing_squares::scene(camera, EDGE, &[(DEPTH, 0.0)])
}

/// Luminance `Y` of every pixel, row by row.
fn image(scene: &Scene, seed: u64) -> TestResult<Vec<f64>> {
    luminance(scene, SPP, seed)
}

/// Total, centroid (px) and second moment about the centroid (px², both
/// axes summed) of an image.
fn moments(image: &[f64]) -> (f64, [f64; 2], f64) {
    let at = |index: usize| {
        let (x, y) = (index as u32 % SIZE, index as u32 / SIZE);
        [f64::from(x) + 0.5, f64::from(y) + 0.5]
    };
    let total: f64 = image.iter().sum();
    let mut centroid = [0.0; 2];
    for (index, value) in image.iter().enumerate() {
        let p = at(index);
        centroid[0] += value * p[0] / total;
        centroid[1] += value * p[1] / total;
    }
    let second = image
        .iter()
        .enumerate()
        .map(|(index, value)| {
            let p = at(index);
            value * ((p[0] - centroid[0]).powi(2) + (p[1] - centroid[1]).powi(2)) / total
        })
        .sum();
    (total, centroid, second)
}

/// The blur radius in pixels of a lens (module docs).
fn blur_radius_px(aperture_radius: f32, focus_distance: f32) -> f64 {
    let tangent_per_px = 2.0 * (0.5 * f64::from(FOV_DEG)).to_radians().tan() / f64::from(SIZE);
    f64::from(aperture_radius) * (1.0 / f64::from(focus_distance) - 1.0 / f64::from(DEPTH)).abs()
        / tangent_per_px
}

#[test]
fn a_thin_lens_blurs_by_its_circle_of_confusion() -> TestResult {
    let (aperture, focus) = (0.4f32, 2.0f32);
    let pinhole = moments(&image(&scene(0.0, 1.0)?, 1)?);
    let radius = blur_radius_px(aperture, focus);
    assert!(radius > 6.0 && radius < 10.0, "{radius}");
    let expected = pinhole.2 + 0.5 * radius * radius;
    let blurred = moments(&image(&scene(aperture, focus)?, 2)?);
    println!("pinhole {pinhole:?}, blurred {blurred:?}, expected moment {expected:.3}");
    assert!(
        (blurred.0 / pinhole.0 - 1.0).abs() < 0.01,
        "total {} vs {}",
        blurred.0,
        pinhole.0
    );
    for axis in 0..2 {
        assert!(
            (blurred.1[axis] - pinhole.1[axis]).abs() < 0.1,
            "centroid {blurred:?}"
        );
    }
    // Over eight seeds the blurred moment spread by 0.7 % (one standard
    // deviation) and their mean sat 0.7 % below the prediction (pixel
    // binning of the square's sharp edges in the pinhole image): 3 % is
    // about four deviations.
    let tolerance = 0.03 * expected;
    assert!(
        (blurred.2 - expected).abs() < tolerance,
        "moment {} vs {expected}",
        blurred.2
    );
    // Negative controls: a 0.3 aperture and a focus at 2.5 blur less.
    for (a, f) in [(0.3, focus), (aperture, 2.5)] {
        let wrong = moments(&image(&scene(a, f)?, 2)?);
        assert!(
            (wrong.2 - expected).abs() > tolerance,
            "{a} {f}: {}",
            wrong.2
        );
    }
    Ok(())
}

#[test]
fn in_focus_the_lens_images_as_the_pinhole() -> TestResult {
    let pinhole = image(&scene(0.0, 1.0)?, 3)?;
    let focused = image(&scene(0.4, DEPTH)?, 4)?;
    let (p, f) = (moments(&pinhole), moments(&focused));
    println!("pinhole {p:?}, focused {f:?}");
    assert!((f.0 / p.0 - 1.0).abs() < 0.01);
    assert!((f.2 - p.2).abs() < 0.03 * p.2, "{} vs {}", f.2, p.2);
    // Pixel by pixel: the square's inside is as bright through both.
    let centre = (SIZE / 2 * SIZE + SIZE / 2) as usize;
    assert!((focused[centre] / pinhole[centre] - 1.0).abs() < 0.02);
    // Negative control: focused at half the depth the centre dims.
    let blurred = image(&scene(0.4, 0.5 * DEPTH)?, 4)?;
    assert!(blurred[centre] < 0.9 * pinhole[centre]);
    Ok(())
}
