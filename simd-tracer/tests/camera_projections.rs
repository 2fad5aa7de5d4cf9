//! Cameras against their geometry (`scene::camera`'s module docs), on
//! glowing squares seen face-on:
//!
//! * orthographic: its rays are parallel, so a square of edge `E` covers
//!   `(E · SIZE / V)²` pixels of a `SIZE`-pixel film of view size `V` at
//!   every depth, centred at its lateral offset times `SIZE / V` pixels
//!   from the film's centre. Negative control: the perspective camera at
//!   the same place sees the far square smaller by the ratio of the depths.
//! * film shift `(a, b)`: the image moves by `(−a, −b)` films, perspective
//!   and orthographic alike.
//! * clip planes: a square in front of the near clip or behind the far
//!   clip vanishes; one between them is whole.

mod glowing_squares;

use glam::Vec3;
use glowing_squares::{SIZE, TestResult, luminance, scene as scene_with_edge};
use simd_tracer::scene::Scene;
use simd_tracer::scene::camera::{Camera, Projection};

/// The orthographic view size, scene units.
const VIEW_SIZE: f32 = 2.0;
/// Edge of the glowing square: 12 px on the film.
const EDGE: f32 = 0.5;
/// The square's offset to the right of the view's axis: 6 px.
const OFFSET_X: f32 = 0.25;

/// A perspective or orthographic camera at the origin looking down `−z`
/// at a glowing square of edge [`EDGE`] at `depth`, [`OFFSET_X`] to the
/// right, on black.
fn scene(projection: Projection, depth: f32) -> TestResult<Scene> {
    scene_with(
        Camera::look_at_with(Vec3::ZERO, -Vec3::Z, Vec3::Y, projection)?,
        &[(depth, OFFSET_X)],
    )
}

/// `camera` looking at glowing squares of edge [`EDGE`] at `(depth,
/// offset to the right)`, on black.
fn scene_with(camera: Camera, squares: &[(f32, f32)]) -> TestResult<Scene> {
    scene_with_edge(camera, EDGE, squares)
}

/// Luminance `Y` of every pixel, row by row (64 spp, seed 3).
fn image(scene: &Scene) -> TestResult<Vec<f64>> {
    luminance(scene, 64, 3)
}

/// Area the square covers (pixels: the total over a lit pixel's value)
/// and its centroid's column (px from the left edge).
fn area_and_centre_x(image: &[f64]) -> (f64, f64) {
    let lit = image.iter().copied().fold(0.0, f64::max);
    let total: f64 = image.iter().sum();
    let centre_x = image
        .iter()
        .enumerate()
        .map(|(index, value)| value * (f64::from(index as u32 % SIZE) + 0.5))
        .sum::<f64>()
        / total;
    (total / lit, centre_x)
}

#[test]
fn orthographic_images_keep_their_size_at_every_depth() -> TestResult {
    let orthographic = Projection::Orthographic {
        view_size: VIEW_SIZE,
    };
    let px_per_unit = f64::from(SIZE) / f64::from(VIEW_SIZE);
    let area = (f64::from(EDGE) * px_per_unit).powi(2);
    let centre_x = 0.5 * f64::from(SIZE) + f64::from(OFFSET_X) * px_per_unit;
    for depth in [1.5, 6.0, 40.0] {
        let (found_area, found_x) = area_and_centre_x(&image(&scene(orthographic, depth)?)?);
        assert!(
            (found_area / area - 1.0).abs() < 0.01,
            "depth {depth}: {found_area} px, expected {area}"
        );
        assert!(
            (found_x - centre_x).abs() < 0.05,
            "depth {depth}: centre {found_x} px, expected {centre_x}"
        );
    }
    // Negative control: a perspective camera shrinks the far square by
    // the ratio of the depths, 4, in area by 16.
    let perspective = Projection::Perspective { fov_deg: 40.0 };
    let (near, _) = area_and_centre_x(&image(&scene(perspective, 1.5)?)?);
    let (far, _) = area_and_centre_x(&image(&scene(perspective, 6.0)?)?);
    assert!(
        (near / far / 16.0 - 1.0).abs() < 0.05,
        "perspective: {near} and {far} px"
    );
    Ok(())
}

/// A film shift moves the image by `(−a, −b)` films (module docs): the
/// square's centroid moves left by `a · SIZE` pixels, perspective and
/// orthographic alike, and its area stays. Negative control: the
/// unshifted camera's centroid.
#[test]
fn a_film_shift_moves_the_image() -> TestResult {
    let shift = [0.125f32, 0.0];
    for projection in [
        Projection::Orthographic {
            view_size: VIEW_SIZE,
        },
        Projection::Perspective { fov_deg: 40.0 },
    ] {
        let plain = Camera::look_at_with(Vec3::ZERO, -Vec3::Z, Vec3::Y, projection)?;
        let (area, x) = area_and_centre_x(&image(&scene_with(plain, &[(3.0, OFFSET_X)])?)?);
        let shifted = plain.with_shift(shift)?;
        let (shifted_area, shifted_x) =
            area_and_centre_x(&image(&scene_with(shifted, &[(3.0, OFFSET_X)])?)?);
        let expected = x - f64::from(shift[0]) * f64::from(SIZE);
        assert!(
            (shifted_x - expected).abs() < 0.05,
            "{projection:?}: centre {shifted_x} px, expected {expected} (unshifted {x})"
        );
        assert!((shifted_area / area - 1.0).abs() < 0.01);
    }
    Ok(())
}

/// Clip planes: squares at depths 1.5 (to the right) and 6 (to the left,
/// apart on the film) seen through clip planes [near, far]: each is seen
/// whole exactly when its depth lies between the planes (the light of one
/// square, of both or none), for both projections.
#[test]
fn clip_planes_hide_what_lies_outside_them() -> TestResult {
    let squares = [(1.5f32, OFFSET_X), (6.0f32, -OFFSET_X)];
    for projection in [
        Projection::Orthographic {
            view_size: VIEW_SIZE,
        },
        Projection::Perspective { fov_deg: 40.0 },
    ] {
        let camera = Camera::look_at_with(Vec3::ZERO, -Vec3::Z, Vec3::Y, projection)?;
        let total = |camera: Camera| -> TestResult<f64> {
            Ok(image(&scene_with(camera, &squares)?)?.iter().sum())
        };
        let alone = |square: (f32, f32)| -> TestResult<f64> {
            Ok(image(&scene_with(camera, &[square])?)?.iter().sum())
        };
        let (near_alone, far_alone) = (alone(squares[0])?, alone(squares[1])?);
        let both = total(camera)?;
        for (near, far, expected, what) in [
            (1.0, 10.0, both, "both"),
            (2.0, 10.0, far_alone, "the far square"),
            (1.0, 5.0, near_alone, "the near square"),
            (2.0, 5.0, 0.0, "none"),
        ] {
            let found = total(camera.with_clip(near, far)?)?;
            assert!(
                (found - expected).abs() <= 0.01 * both,
                "{projection:?}, clip [{near}, {far}]: {found}, expected {what} ({expected})"
            );
        }
        // Negative control: each clipped expectation differs from the
        // unclipped image (both squares are seen apart).
        assert!((both - near_alone - far_alone).abs() < 0.01 * both);
        assert!(near_alone > 0.05 * both && far_alone > 0.05 * both);
    }
    Ok(())
}
