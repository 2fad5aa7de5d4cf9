//! Tests of `fspec_cli::image_out`: PNG / EXR / spectral EXR / coefficient
//! EXR writers, the coefficient reader, atomic writes and error messages.

mod common;

use common::{TestResult, entries};
use std::fs;
use std::path::Path;
use test_support::ScratchDir;

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    ReadChannels, ReadLayers, Text, WritableImage, read,
};
use fspec_cli::image_out::{
    CoefficientImage, Exposure, FOURIER_CONVENTION, Tone, XyzImage, parse_spectral_channel_name,
    read_coefficients_exr, write_by_extension, write_coefficients_exr, write_exr, write_png,
    write_spectral_exr,
};
use spectral_core::color::{LinearSrgb, Xyz};

type ExrImage = Image<Layer<AnyChannels<FlatSamples>>>;

fn test_dir(name: &str) -> TestResult<ScratchDir> {
    common::test_dir("image-out", name)
}

/// Decodes a PNG: (width, height, color type, bit depth, bytes).
fn decode_png(path: &Path) -> TestResult<(u32, u32, png::ColorType, png::BitDepth, Vec<u8>)> {
    let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(path)?));
    let mut reader = decoder.read_info()?;
    let mut buffer = vec![0; reader.output_buffer_size().ok_or("PNG too large")?];
    let info = reader.next_frame(&mut buffer)?;
    buffer.truncate(info.buffer_size());
    Ok((
        info.width,
        info.height,
        info.color_type,
        info.bit_depth,
        buffer,
    ))
}

fn read_exr(path: &Path) -> TestResult<ExrImage> {
    Ok(read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)?)
}

fn channel_names(image: &ExrImage) -> Vec<String> {
    image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect()
}

fn channel(image: &ExrImage, name: &str) -> TestResult<Vec<f32>> {
    let channel = image
        .layer_data
        .channel_data
        .list
        .iter()
        .find(|c| c.name.eq(name))
        .ok_or_else(|| format!("no channel {name}"))?;
    Ok(channel.sample_data.values_as_f32().collect())
}

fn text_attribute(image: &ExrImage, name: &str) -> TestResult<String> {
    let key = Text::new_or_none(name).ok_or("bad name")?;
    match image.layer_data.attributes.other.get(&key) {
        Some(AttributeValue::Text(value)) => Ok(value.to_string()),
        other => Err(format!("attribute {name}: {other:?}").into()),
    }
}

/// Writes an EXR with the given f32 channels (all `width * height` long) and
/// optional string attributes, using only the exr crate.
fn write_raw_exr(
    path: &Path,
    size: (usize, usize),
    channels: &[(&str, Vec<f32>)],
    attributes: &[(&str, &str)],
) -> TestResult<()> {
    let mut list = Vec::new();
    for (name, values) in channels {
        let name = Text::new_or_none(name).ok_or("bad channel name")?;
        list.push(AnyChannel::new(name, FlatSamples::F32(values.clone())));
    }
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in attributes {
        layer_attributes.other.insert(
            Text::new_or_none(name).ok_or("bad attribute name")?,
            AttributeValue::Text(Text::new_or_none(value).ok_or("bad attribute value")?),
        );
    }
    let layer = Layer::new(
        size,
        layer_attributes,
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(list.into()),
    );
    Image::from_layer(layer).write().to_file(path)?;
    Ok(())
}

/// IEC 61966-2-1 encoding to 8 bits, written independently of spectral-core.
fn srgb8(linear: f64) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let encoded = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round() as u8
}

fn assert_close_u8(actual: &[u8], expected: &[u8]) {
    assert_eq!(actual.len(), expected.len());
    for (a, e) in actual.iter().zip(expected) {
        assert!(a.abs_diff(*e) <= 1, "{actual:?} vs {expected:?}");
    }
}

fn xyz_of_linear(r: f64, g: f64, b: f64) -> Xyz {
    LinearSrgb::new(r, g, b).to_xyz()
}

/// A 3×2 test image with distinct, in-gamut pixels.
fn test_pixels() -> Vec<Xyz> {
    (0..6)
        .map(|i| {
            let t = f64::from(i);
            xyz_of_linear(0.05 + 0.1 * t, 0.5 - 0.07 * t, 0.02 * t * t + 0.01)
        })
        .collect()
}

// ---------------------------------------------------------------------------
// PNG
// ---------------------------------------------------------------------------

#[test]
fn png_round_trip_known_pixel() {
    let dir = test_dir("png-known").unwrap();
    let path = dir.join("known.png");
    let mut pixels = vec![Xyz::default(); 4 * 3];
    pixels[4 + 2] = xyz_of_linear(0.5, 0.25, 1.0); // (x, y) = (2, 1)
    pixels[4 * 3 - 1] = xyz_of_linear(1.0, 1.0, 1.0);
    let image = XyzImage {
        width: 4,
        height: 3,
        xyz: &pixels,
    };
    write_png(&path, &image, Exposure::default(), Tone::Clamp).unwrap();
    let (width, height, color, depth, bytes) = decode_png(&path).unwrap();
    assert_eq!((width, height), (4, 3));
    assert_eq!(color, png::ColorType::Rgb);
    assert_eq!(color.samples(), 3);
    assert_eq!(depth, png::BitDepth::Eight);
    assert_eq!(bytes.len(), 4 * 3 * 3);
    let at = |x: usize, y: usize| &bytes[(y * 4 + x) * 3..(y * 4 + x) * 3 + 3];
    assert_close_u8(at(2, 1), &[srgb8(0.5), srgb8(0.25), srgb8(1.0)]);
    assert_close_u8(at(2, 1), &[188, 137, 255]);
    assert_close_u8(at(3, 2), &[255, 255, 255]);
    assert_eq!(at(0, 0), &[0, 0, 0]);
    assert_eq!(entries(&dir).unwrap(), ["known.png"]);
}

#[test]
fn png_exposure_plus_one_doubles_linear_values() {
    let dir = test_dir("png-exposure").unwrap();
    let pixels = [xyz_of_linear(0.2, 0.1, 0.3), xyz_of_linear(0.05, 0.4, 0.01)];
    let image = XyzImage {
        width: 2,
        height: 1,
        xyz: &pixels,
    };
    let plus = dir.join("plus.png");
    write_png(&plus, &image, Exposure { stops: 1.0 }, Tone::Clamp).unwrap();
    let (_, _, _, _, bytes) = decode_png(&plus).unwrap();
    assert_close_u8(
        &bytes,
        &[
            srgb8(0.4),
            srgb8(0.2),
            srgb8(0.6),
            srgb8(0.1),
            srgb8(0.8),
            srgb8(0.02),
        ],
    );
    let minus = dir.join("minus.png");
    write_png(&minus, &image, Exposure { stops: -2.0 }, Tone::Clamp).unwrap();
    let (_, _, _, _, bytes) = decode_png(&minus).unwrap();
    assert_close_u8(&bytes[..3], &[srgb8(0.05), srgb8(0.025), srgb8(0.075)]);
}

#[test]
fn png_reinhard_maps_one_to_half_and_clamp_saturates() {
    let dir = test_dir("png-tone").unwrap();
    let pixels = [
        xyz_of_linear(1.0, 1.0, 1.0),
        xyz_of_linear(3.0, 0.0, 2.0),
        xyz_of_linear(-0.5, 0.5, 0.25),
    ];
    let image = XyzImage {
        width: 3,
        height: 1,
        xyz: &pixels,
    };
    let reinhard = dir.join("reinhard.png");
    write_png(&reinhard, &image, Exposure::default(), Tone::Reinhard).unwrap();
    let (_, _, _, _, bytes) = decode_png(&reinhard).unwrap();
    assert_close_u8(&bytes[..3], &[srgb8(0.5); 3]);
    assert_close_u8(&bytes[3..6], &[srgb8(0.75), 0, srgb8(2.0 / 3.0)]);
    assert_close_u8(&bytes[6..], &[0, srgb8(1.0 / 3.0), srgb8(0.2)]);
    // Exposure comes before the tone map: 0.5 at +1 stop is 1.0 → 0.5.
    let half = [xyz_of_linear(0.5, 0.5, 0.5)];
    let image = XyzImage {
        width: 1,
        height: 1,
        xyz: &half,
    };
    write_png(&reinhard, &image, Exposure { stops: 1.0 }, Tone::Reinhard).unwrap();
    let (_, _, _, _, bytes) = decode_png(&reinhard).unwrap();
    assert_close_u8(&bytes, &[srgb8(0.5); 3]);

    let clamp = dir.join("clamp.png");
    let image = XyzImage {
        width: 3,
        height: 1,
        xyz: &pixels,
    };
    write_png(&clamp, &image, Exposure::default(), Tone::Clamp).unwrap();
    let (_, _, _, _, bytes) = decode_png(&clamp).unwrap();
    assert_close_u8(&bytes[3..6], &[255, 0, 255]);
    assert_close_u8(&bytes[6..], &[0, srgb8(0.5), srgb8(0.25)]);
}

#[test]
fn png_maps_nan_to_zero() {
    let dir = test_dir("png-nan").unwrap();
    let path = dir.join("nan.png");
    let pixels = [Xyz::new(f64::NAN, 0.5, 0.5), xyz_of_linear(0.5, 0.5, 0.5)];
    let image = XyzImage {
        width: 1,
        height: 2,
        xyz: &pixels,
    };
    for tone in [Tone::Clamp, Tone::Reinhard] {
        write_png(&path, &image, Exposure::default(), tone).unwrap();
        let (_, _, _, _, bytes) = decode_png(&path).unwrap();
        assert_eq!(&bytes[..3], &[0, 0, 0]);
        assert!(bytes[3] > 0);
    }
}

// ---------------------------------------------------------------------------
// RGB / XYZ EXR
// ---------------------------------------------------------------------------

#[test]
fn exr_round_trip_rgb_and_xyz() {
    let dir = test_dir("exr-rgb").unwrap();
    let pixels = test_pixels();
    let image = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    for with_xyz in [false, true] {
        let path = dir.join(format!("render-{with_xyz}.exr"));
        write_exr(&path, &image, with_xyz).unwrap();
        let exr = read_exr(&path).unwrap();
        assert_eq!(exr.layer_data.size.0, 3);
        assert_eq!(exr.layer_data.size.1, 2);
        let mut expected = vec!["B", "G", "R"];
        if with_xyz {
            expected = vec!["B", "G", "R", "X", "Y", "Z"];
        }
        assert_eq!(channel_names(&exr), expected);
        let (r, g, b) = (
            channel(&exr, "R").unwrap(),
            channel(&exr, "G").unwrap(),
            channel(&exr, "B").unwrap(),
        );
        for (i, xyz) in pixels.iter().enumerate() {
            let rgb = xyz.to_linear_srgb();
            for (got, want) in [(r[i], rgb.r), (g[i], rgb.g), (b[i], rgb.b)] {
                assert!(
                    (f64::from(got) - want).abs() <= 1e-7 * want.abs().max(1e-3),
                    "{got} vs {want}"
                );
            }
        }
        if with_xyz {
            let (x, y, z) = (
                channel(&exr, "X").unwrap(),
                channel(&exr, "Y").unwrap(),
                channel(&exr, "Z").unwrap(),
            );
            for (i, xyz) in pixels.iter().enumerate() {
                assert_eq!(x[i], xyz.x as f32);
                assert_eq!(y[i], xyz.y as f32);
                assert_eq!(z[i], xyz.z as f32);
            }
        }
    }
}

#[test]
fn exr_writers_refuse_non_finite_values_naming_the_pixel() {
    let dir = test_dir("exr-nonfinite").unwrap();
    let mut pixels = test_pixels();
    pixels[4] = Xyz::new(0.1, f64::INFINITY, 0.1);
    let image = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    let path = dir.join("bad.exr");
    let error = write_exr(&path, &image, true).unwrap_err().to_string();
    assert!(error.contains("bad.exr"), "{error}");
    assert!(error.contains("pixel (1, 1)"), "{error}");
    assert_eq!(error.lines().count(), 1);
    let mut coeffs = vec![0.5f32; 6 * 2];
    coeffs[5 * 2 + 1] = f32::NAN;
    let error = write_coefficients_exr(&path, 3, 2, 2, &coeffs, (360.0, 830.0))
        .unwrap_err()
        .to_string();
    assert!(error.contains("F1 of pixel (2, 1)"), "{error}");
    assert!(entries(&dir).unwrap().is_empty());
}

// ---------------------------------------------------------------------------
// Spectral EXR
// ---------------------------------------------------------------------------

#[test]
fn spectral_exr_follows_the_layout() {
    let dir = test_dir("spectral").unwrap();
    let path = dir.join("spectral.exr");
    let wavelengths = [380.0, 455.5, 550.0, 600.25, 1000.0];
    let (width, height) = (3u32, 2u32);
    let pixels = test_pixels();
    let radiance: Vec<f32> = (0..6 * wavelengths.len())
        .map(|i| 0.125 * i as f32 + 0.01)
        .collect();
    let preview = XyzImage {
        width,
        height,
        xyz: &pixels,
    };
    write_spectral_exr(&path, width, height, &wavelengths, &radiance, &preview).unwrap();

    let exr = read_exr(&path).unwrap();
    let names = channel_names(&exr);
    for name in [
        "S0.380,000000nm",
        "S0.455,500000nm",
        "S0.550,000000nm",
        "S0.600,250000nm",
        "S0.1000,000000nm",
        "R",
        "G",
        "B",
    ] {
        assert!(names.iter().any(|n| n == name), "{name} in {names:?}");
    }
    assert_eq!(names.len(), wavelengths.len() + 3);
    // Readers recover the wavelengths by replacing ',' with '.' and sorting.
    let mut parsed: Vec<f64> = names
        .iter()
        .filter_map(|n| {
            let v = n.strip_prefix("S0.")?.strip_suffix("nm")?;
            v.replace(',', ".").parse().ok()
        })
        .collect();
    parsed.sort_by(f64::total_cmp);
    assert_eq!(parsed, wavelengths);
    assert_eq!(
        names
            .iter()
            .filter_map(|n| parse_spectral_channel_name(n))
            .count(),
        wavelengths.len()
    );
    assert_eq!(
        text_attribute(&exr, "spectralLayoutVersion").unwrap(),
        "1.0"
    );
    assert_eq!(
        text_attribute(&exr, "emissiveUnits").unwrap(),
        "W.m^-2.sr^-1"
    );
    // Values: pixel-major input, one plane per wavelength.
    for (k, lambda) in wavelengths.iter().enumerate() {
        let name = format!("S0.{}nm", format!("{lambda:.6}").replace('.', ","));
        let plane = channel(&exr, &name).unwrap();
        for pixel in 0..6 {
            assert_eq!(plane[pixel], radiance[pixel * wavelengths.len() + k]);
        }
    }
    let r = channel(&exr, "R").unwrap();
    assert_eq!(r[4], pixels[4].to_linear_srgb().r as f32);
}

#[test]
fn spectral_exr_validates_its_inputs() {
    let dir = test_dir("spectral-bad").unwrap();
    let path = dir.join("s.exr");
    let pixels = test_pixels();
    let preview = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    let radiance = vec![1.0f32; 12];
    // Wrong length for 3 wavelengths.
    assert!(write_spectral_exr(&path, 3, 2, &[400.0, 500.0, 600.0], &radiance, &preview).is_err());
    // Preview of another size.
    let small = XyzImage {
        width: 2,
        height: 3,
        xyz: &pixels,
    };
    assert!(write_spectral_exr(&path, 3, 2, &[400.0, 500.0], &radiance, &small).is_err());
    // Duplicate channel names.
    assert!(write_spectral_exr(&path, 3, 2, &[500.0, 500.0], &radiance, &preview).is_err());
    // Non-finite radiance names the pixel and wavelength.
    let mut bad = radiance.clone();
    bad[2 * 2 + 1] = f32::INFINITY;
    let error = write_spectral_exr(&path, 3, 2, &[400.0, 500.0], &bad, &preview)
        .unwrap_err()
        .to_string();
    assert!(error.contains("pixel (2, 0) at 500 nm"), "{error}");
    assert!(entries(&dir).unwrap().is_empty());
}

// ---------------------------------------------------------------------------
// Coefficient EXR
// ---------------------------------------------------------------------------

#[test]
fn coefficients_exr_round_trip() {
    let dir = test_dir("coeffs").unwrap();
    for (n, range) in [
        (12usize, (360.0, 830.0)),
        (1, (400.5, 700.0)),
        (11, (380.0, 780.0)),
    ] {
        let (width, height) = (5u32, 3u32);
        let coeffs: Vec<f32> = (0..15 * n)
            .map(|i| ((i * 7919) % 1000) as f32 / 333.0 - 1.5)
            .collect();
        let path = dir.join(format!("c{n}.exr"));
        write_coefficients_exr(&path, width, height, n, &coeffs, range).unwrap();
        let back = read_coefficients_exr(&path).unwrap();
        assert_eq!(
            back,
            CoefficientImage {
                width,
                height,
                n,
                coeffs: coeffs.clone(),
                range_nm: range,
            }
        );
        let exr = read_exr(&path).unwrap();
        assert_eq!(
            text_attribute(&exr, "fourierConvention").unwrap(),
            FOURIER_CONVENTION
        );
        assert_eq!(channel_names(&exr).len(), n);
    }
    let exr = read_exr(&dir.join("c12.exr")).unwrap();
    assert_eq!(text_attribute(&exr, "fourierRangeNm").unwrap(), "360,830");
    assert!(FOURIER_CONVENTION.starts_with("c_j = (1/pi) int_{-pi}^{0} g(phi) cos(j phi) dphi"));
}

#[test]
fn coefficient_reader_accepts_foreign_files() {
    let dir = test_dir("coeffs-foreign").unwrap();
    let path = dir.join("foreign.exr");
    // No range attribute, extra channels, and an F channel that is not part of
    // the series (non-canonical name).
    write_raw_exr(
        &path,
        (2, 1),
        &[
            ("F0", vec![1.0, 2.0]),
            ("F1", vec![3.0, 4.0]),
            ("F01", vec![9.0, 9.0]),
            ("R", vec![0.5, 0.5]),
        ],
        &[],
    )
    .unwrap();
    let back = read_coefficients_exr(&path).unwrap();
    assert_eq!(back.n, 2);
    assert_eq!((back.width, back.height), (2, 1));
    assert_eq!(back.coeffs, [1.0, 3.0, 2.0, 4.0]);
    assert_eq!(back.range_nm, (360.0, 830.0));
}

#[test]
fn coefficient_reader_errors_name_the_file() {
    let dir = test_dir("coeffs-errors").unwrap();

    // A PNG renamed .exr.
    let png_path = dir.join("image.png");
    let pixels = [xyz_of_linear(0.5, 0.5, 0.5)];
    let image = XyzImage {
        width: 1,
        height: 1,
        xyz: &pixels,
    };
    write_png(&png_path, &image, Exposure::default(), Tone::Clamp).unwrap();
    let renamed = dir.join("renamed.exr");
    fs::rename(&png_path, &renamed).unwrap();
    let error = read_coefficients_exr(&renamed).unwrap_err().to_string();
    assert!(error.contains("renamed.exr"), "{error}");
    assert!(error.contains("not an OpenEXR file"), "{error}");

    // No F0 channel.
    let rgb = dir.join("rgb.exr");
    write_raw_exr(
        &rgb,
        (1, 1),
        &[("R", vec![0.0]), ("G", vec![0.0]), ("B", vec![0.0])],
        &[],
    )
    .unwrap();
    let error = read_coefficients_exr(&rgb).unwrap_err().to_string();
    assert!(
        error.contains("rgb.exr") && error.contains("no F0"),
        "{error}"
    );

    // A gap F0, F2.
    let gap = dir.join("gap.exr");
    write_raw_exr(&gap, (1, 1), &[("F0", vec![0.0]), ("F2", vec![0.0])], &[]).unwrap();
    let error = read_coefficients_exr(&gap).unwrap_err().to_string();
    assert!(
        error.contains("gap.exr") && error.contains("F1 is missing"),
        "{error}"
    );

    // Non-finite values.
    let nan = dir.join("nan.exr");
    write_raw_exr(
        &nan,
        (2, 2),
        &[("F0", vec![0.0, 0.0, 0.0, f32::NAN]), ("F1", vec![0.0; 4])],
        &[],
    )
    .unwrap();
    let error = read_coefficients_exr(&nan).unwrap_err().to_string();
    assert!(
        error.contains("nan.exr") && error.contains("F0 of pixel (1, 1)"),
        "{error}"
    );

    // A malformed range attribute.
    let range = dir.join("range.exr");
    write_raw_exr(
        &range,
        (1, 1),
        &[("F0", vec![0.0])],
        &[("fourierRangeNm", "830,360")],
    )
    .unwrap();
    let error = read_coefficients_exr(&range).unwrap_err().to_string();
    assert!(
        error.contains("range.exr") && error.contains("fourierRangeNm"),
        "{error}"
    );

    // Missing and empty files.
    let missing = dir.join("missing.exr");
    let error = read_coefficients_exr(&missing).unwrap_err().to_string();
    assert!(error.contains("missing.exr"), "{error}");
    let empty = dir.join("empty.exr");
    fs::write(&empty, b"").unwrap();
    let error = read_coefficients_exr(&empty).unwrap_err().to_string();
    assert!(
        error.contains("empty.exr") && error.contains("not an OpenEXR"),
        "{error}"
    );

    // Every message is one line.
    for path in [&renamed, &rgb, &gap, &nan, &range, &missing, &empty] {
        let message = read_coefficients_exr(path).unwrap_err().to_string();
        assert_eq!(message.lines().count(), 1, "{message}");
    }
}

/// Rewrites the `dataWindow` of an uncompressed 1×1 scan-line file to claim
/// `width × height` pixels.
fn patch_data_window(bytes: &mut [u8], width: i32, height: i32) -> TestResult<()> {
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .ok_or("no dataWindow")?;
    // name, type, i32 size (16), then xMin yMin xMax yMax.
    let values = at + key.len() + 4;
    bytes[values + 8..values + 12].copy_from_slice(&(width - 1).to_le_bytes());
    bytes[values + 12..values + 16].copy_from_slice(&(height - 1).to_le_bytes());
    Ok(())
}

#[test]
fn coefficient_reader_refuses_absurd_sizes() {
    let dir = test_dir("coeffs-huge").unwrap();
    let path = dir.join("huge.exr");
    write_raw_exr(&path, (1, 1), &[("F0", vec![0.5])], &[]).unwrap();
    let mut bytes = fs::read(&path).unwrap();
    patch_data_window(&mut bytes, 20_000, 20_000).unwrap();
    fs::write(&path, &bytes).unwrap();
    let error = read_coefficients_exr(&path).unwrap_err().to_string();
    assert!(error.contains("huge.exr"), "{error}");
    assert!(error.contains("20000x20000"), "{error}");
}

// ---------------------------------------------------------------------------
// Atomic writes, validation and dispatch
// ---------------------------------------------------------------------------

#[test]
fn writing_into_a_missing_directory_fails_and_leaves_nothing() {
    let dir = test_dir("missing-dir").unwrap();
    let pixels = test_pixels();
    let image = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    for name in ["render.png", "render.exr"] {
        let path = dir.join("no-such-dir").join(name);
        let error =
            write_by_extension(&path, &image, Exposure::default(), Tone::Clamp, false).unwrap_err();
        let message = error.to_string();
        assert_eq!(error.exit_code(), 2);
        assert!(message.starts_with("cannot write "), "{message}");
        assert!(message.contains(&path.display().to_string()), "{message}");
        assert!(message.contains("does not exist"), "{message}");
        assert_eq!(message.lines().count(), 1);
    }
    assert!(entries(&dir).unwrap().is_empty());
}

#[test]
fn writing_over_an_existing_file_replaces_it() {
    let dir = test_dir("replace").unwrap();
    let pixels = test_pixels();
    let image = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    let png_path = dir.join("out.png");
    fs::write(&png_path, b"old contents that are not a PNG").unwrap();
    write_png(&png_path, &image, Exposure::default(), Tone::Clamp).unwrap();
    let (width, height, _, _, _) = decode_png(&png_path).unwrap();
    assert_eq!((width, height), (3, 2));

    let exr_path = dir.join("out.exr");
    fs::write(&exr_path, b"old").unwrap();
    write_exr(&exr_path, &image, false).unwrap();
    assert_eq!(channel_names(&read_exr(&exr_path).unwrap()).len(), 3);
    write_exr(&exr_path, &image, true).unwrap();
    assert_eq!(channel_names(&read_exr(&exr_path).unwrap()).len(), 6);

    // No temporaries are left behind.
    assert_eq!(entries(&dir).unwrap(), ["out.exr", "out.png"]);
}

#[test]
fn failed_write_keeps_the_previous_file() {
    let dir = test_dir("keep").unwrap();
    let path = dir.join("keep.png");
    fs::write(&path, b"previous").unwrap();
    let pixels = test_pixels();
    let wrong = XyzImage {
        width: 4,
        height: 2,
        xyz: &pixels,
    };
    let error = write_png(&path, &wrong, Exposure::default(), Tone::Clamp)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("keep.png") && error.contains("4x2"),
        "{error}"
    );
    // The target is a directory: the rename fails, the temporary is removed.
    let target_dir = dir.join("sub.exr");
    fs::create_dir(&target_dir).unwrap();
    let image = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    let error = write_exr(&target_dir, &image, false)
        .unwrap_err()
        .to_string();
    assert!(error.contains("sub.exr"), "{error}");
    assert_eq!(fs::read(&path).unwrap(), b"previous");
    assert_eq!(entries(&dir).unwrap(), ["keep.png", "sub.exr"]);
    assert!(entries(&target_dir).unwrap().is_empty());
}

#[test]
fn sizes_are_validated() {
    let dir = test_dir("sizes").unwrap();
    let pixels = test_pixels();
    for (width, height) in [(0, 6), (6, 0), (2, 2), (7, 1)] {
        let image = XyzImage {
            width,
            height,
            xyz: &pixels,
        };
        assert!(write_png(&dir.join("a.png"), &image, Exposure::default(), Tone::Clamp).is_err());
        assert!(write_exr(&dir.join("a.exr"), &image, true).is_err());
    }
    assert!(write_coefficients_exr(&dir.join("c.exr"), 3, 2, 0, &[], (360.0, 830.0)).is_err());
    assert!(
        write_coefficients_exr(&dir.join("c.exr"), 3, 2, 2, &[0.0; 11], (360.0, 830.0)).is_err()
    );
    assert!(
        write_coefficients_exr(&dir.join("c.exr"), 3, 2, 2, &[0.0; 12], (830.0, 360.0)).is_err()
    );
    let error = write_png(
        &dir.join("e.png"),
        &XyzImage {
            width: 1,
            height: 6,
            xyz: &pixels,
        },
        Exposure { stops: f32::NAN },
        Tone::Clamp,
    )
    .unwrap_err()
    .to_string();
    assert!(error.contains("exposure"), "{error}");
    assert!(entries(&dir).unwrap().is_empty());
}

#[test]
fn write_by_extension_dispatches_and_rejects_unknown_extensions() {
    let dir = test_dir("dispatch").unwrap();
    let pixels = test_pixels();
    let image = XyzImage {
        width: 3,
        height: 2,
        xyz: &pixels,
    };
    let png_path = dir.join("a.PNG");
    write_by_extension(
        &png_path,
        &image,
        Exposure::default(),
        Tone::Reinhard,
        false,
    )
    .unwrap();
    assert!(fs::read(&png_path).unwrap().starts_with(b"\x89PNG"));
    let exr_path = dir.join("a.exr");
    write_by_extension(&exr_path, &image, Exposure::default(), Tone::Clamp, true).unwrap();
    assert!(
        fs::read(&exr_path)
            .unwrap()
            .starts_with(&[0x76, 0x2f, 0x31, 0x01])
    );
    assert_eq!(channel_names(&read_exr(&exr_path).unwrap()).len(), 6);

    for name in ["a.tif", "noextension"] {
        let path = dir.join(name);
        let error = write_by_extension(&path, &image, Exposure::default(), Tone::Clamp, false)
            .unwrap_err()
            .to_string();
        assert!(error.contains(&path.display().to_string()), "{error}");
        assert!(error.contains(".png") && error.contains(".exr"), "{error}");
    }
    assert!(error_free_listing(&dir).unwrap());
}

/// Only the two written files exist.
fn error_free_listing(dir: &Path) -> TestResult<bool> {
    Ok(entries(dir)? == ["a.PNG", "a.exr"])
}
