//! Replays the committed fuzz corpora through the fuzz target bodies, so the
//! seeds (and every crash turned regression input) run in CI on stable Rust.
//! The walk is `test_support::replay_corpus`: every file, and an error if a
//! corpus directory is missing or empty.

use test_support::{corpus_dir, replay_corpus};

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

#[test]
fn csv_spectrum_corpus() -> TestResult {
    let count = replay_corpus("csv_spectrum", fspec_cli::spectrum_file::fuzz_csv_spectrum)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

#[test]
fn sensor_csv_corpus() -> TestResult {
    let count = replay_corpus("sensor_csv", fspec_cli::sensor_file::fuzz_sensor_csv)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

#[test]
fn scene_toml_corpus() -> TestResult {
    let count = replay_corpus("scene_toml", fspec_cli::scene_file::fuzz_scene_toml)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

/// The hand-written seeds are complete scenes (no file references), so the
/// fuzzer starts from inputs that reach the scene build.
#[test]
fn scene_toml_seeds_are_scenes() -> TestResult {
    for seed in [
        "minimal.toml",
        "render-environment.toml",
        "coated.toml",
        "conductors.toml",
        "dielectrics.toml",
        "thin-film.toml",
        "spectra.toml",
        "checkerboard.toml",
        "lights.toml",
        "lens.toml",
        "orthographic.toml",
        "mask.toml",
    ] {
        let loaded = fspec_cli::scene_file::load_scene_file(&corpus_dir("scene_toml").join(seed))
            .map_err(|e| format!("{seed}: {e}"))?;
        loaded.builder.build().map_err(|e| format!("{seed}: {e}"))?;
    }
    Ok(())
}

#[test]
fn scene_xml_corpus() -> TestResult {
    let count = replay_corpus("scene_xml", fspec_cli::scene_file::fuzz_scene_xml)?;
    assert!(count >= 4, "only {count} seeds");
    Ok(())
}

/// The hand-written Mitsuba seeds other than `errors.xml` are complete
/// scenes (no file references) that load and build.
#[test]
fn scene_xml_seeds_are_scenes() -> TestResult {
    for seed in [
        "minimal.xml",
        "materials.xml",
        "textures.xml",
        "lights.xml",
        "lens.xml",
        "orthographic.xml",
        "camera-shift.xml",
        "mask.xml",
    ] {
        let loaded = fspec_cli::scene_file::load_mitsuba_scene(
            &corpus_dir("scene_xml").join(seed),
            &fspec_cli::scene_file::MitsubaOptions::default(),
        )
        .map_err(|e| format!("{seed}: {e}"))?;
        loaded.builder.build().map_err(|e| format!("{seed}: {e}"))?;
    }
    Ok(())
}

#[test]
fn coefficient_exr_corpus() -> TestResult {
    let count = replay_corpus(
        "coefficient_exr",
        fspec_cli::texture_file::fuzz_coefficient_exr,
    )?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

#[test]
fn spectral_exr_corpus() -> TestResult {
    let count = replay_corpus("spectral_exr", fspec_cli::spectral_image::fuzz_spectral_exr)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

/// The spectral seeds written by the project's writers read back.
#[test]
fn spectral_exr_seeds_read_back() -> TestResult {
    use fspec_cli::spectral_image::{SpectralKind, read_spectral_exr};
    for (seed, kind, bands) in [
        ("s0-6x4-31", SpectralKind::Emissive, 31),
        ("s0-cornell-3x2", SpectralKind::Emissive, 48),
        ("t-5x4-31", SpectralKind::Reflective, 31),
        ("t-unsorted-names", SpectralKind::Reflective, 3),
    ] {
        let image = read_spectral_exr(&corpus_dir("spectral_exr").join(seed), kind)
            .map_err(|e| format!("{seed}: {e}"))?;
        assert_eq!(
            (image.kind, image.wavelengths_nm.len()),
            (kind, bands),
            "{seed}"
        );
    }
    Ok(())
}

/// The coefficient seeds written by the project's writer read back.
#[test]
fn coefficient_exr_seeds_read_back() -> TestResult {
    for (seed, n) in [
        ("coeffs-2x2-n4", 4),
        ("coeffs-1x1-n1", 1),
        ("coeffs-f16-tiled", 2),
    ] {
        let image =
            fspec_cli::image_out::read_coefficients_exr(&corpus_dir("coefficient_exr").join(seed))
                .map_err(|e| format!("{seed}: {e}"))?;
        assert_eq!(image.n, n, "{seed}");
    }
    Ok(())
}

#[test]
fn rgbe_corpus() -> TestResult {
    let count = replay_corpus("rgbe", fspec_cli::hdr_image::fuzz_rgbe)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

#[test]
fn rgb_image_corpus() -> TestResult {
    let count = replay_corpus("rgb_image", fspec_cli::hdr_image::fuzz_rgb_image)?;
    assert!(count >= 10, "only {count} seeds");
    Ok(())
}

/// The seeds of `tools/rgb_image_seeds.py` are what their names say, read
/// from their files as a scene's maps are: `valid-*` files load, `broken-*`
/// files are refused with one line that names the file.
#[test]
fn rgb_image_seeds_load_or_fail_as_named() -> TestResult {
    let (mut valid, mut broken) = (0, 0);
    for entry in std::fs::read_dir(corpus_dir("rgb_image"))? {
        let path = entry?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let loaded = fspec_cli::hdr_image::load_rgb_image(&path);
        if name.starts_with("valid-") {
            let image = loaded.map_err(|e| format!("{name}: {e}"))?;
            assert!(image.width > 0 && image.height > 0, "{name}");
            assert_eq!(
                image.texels.len(),
                image.width as usize * image.height as usize,
                "{name}"
            );
            valid += 1;
        } else {
            let message = match loaded {
                Ok(image) => {
                    return Err(format!("{name}: loaded {}x{}", image.width, image.height).into());
                }
                Err(e) => e.to_string(),
            };
            assert!(
                message.starts_with(&path.display().to_string()),
                "{message}"
            );
            assert!(!message.trim_end().contains('\n'), "{message}");
            broken += 1;
        }
    }
    // Every format among the valid seeds, and broken ones besides.
    assert!(valid >= 6 && broken >= 5, "{valid} valid, {broken} broken");
    Ok(())
}

/// The hand-written seeds are what their names say: `valid-*` files parse,
/// `broken-*` files are refused.
#[test]
fn rgbe_seeds_parse_or_fail_as_named() -> TestResult {
    let mut seen = 0;
    for entry in std::fs::read_dir(corpus_dir("rgbe"))? {
        let path = entry?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let parsed = fspec_cli::hdr_image::parse_rgbe(&std::fs::read(&path)?);
        if name.starts_with("valid-") {
            let image = parsed.map_err(|e| format!("{name}: {e}"))?;
            assert_eq!(
                image.texels.len(),
                image.width as usize * image.height as usize
            );
            seen += 1;
        } else if name.starts_with("broken-") {
            assert!(parsed.is_err(), "{name} parsed");
            seen += 1;
        }
    }
    assert!(seen >= 10, "only {seen} named seeds");
    Ok(())
}

#[test]
fn partial_film_corpus() -> TestResult {
    let count = replay_corpus("partial_film", fspec_cli::partial_file::fuzz_partial_film)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

#[test]
fn equal_time_manifest_corpus() -> TestResult {
    let count = replay_corpus(
        "equal_time_manifest",
        fspec_cli::experiment::equal_time::fuzz_manifest,
    )?;
    assert!(count >= 5, "only {count} seeds");
    // The seeds are what their names say.
    for entry in std::fs::read_dir(corpus_dir("equal_time_manifest"))? {
        let path = entry?.path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        let text = String::from_utf8_lossy(&std::fs::read(&path)?).into_owned();
        let parsed = fspec_cli::experiment::equal_time::Manifest::parse(&text, name);
        assert_eq!(
            parsed.is_ok(),
            name.starts_with("valid-"),
            "{name}: {parsed:?}"
        );
    }
    Ok(())
}

/// The partial-film seeds are what their names say: `valid-*` files parse,
/// `broken-*` files are refused.
#[test]
fn partial_film_seeds_parse_or_fail_as_named() -> TestResult {
    let mut seen = 0;
    for entry in std::fs::read_dir(corpus_dir("partial_film"))? {
        let path = entry?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let parsed = fspec_cli::partial_file::PartialFilm::from_bytes(&std::fs::read(&path)?);
        if name.starts_with("valid-") {
            assert!(parsed.is_ok(), "{name}: {:?}", parsed.err());
            seen += 1;
        } else if name.starts_with("broken-") {
            assert!(parsed.is_err(), "{name}");
            seen += 1;
        }
    }
    assert!(seen >= 8, "{seen}");
    Ok(())
}
