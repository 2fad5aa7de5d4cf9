//! Tests of `fspec_cli::scene_file`: every example scene loads, builds and
//! renders; bare OBJ files become lit scenes; each class of error gives one
//! line `file:line: key: message`.

use std::error::Error;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use test_support::ScratchDir;

use fspec_cli::scene_file::{LoadedScene, RenderDefaults, load_obj_scene, load_scene_file};
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::shading::material::{Bsdf, Sides};
use simd_tracer::transport::FourierTransport;
use spectral_core::Spectrum;
use spectral_core::color::Xyz;
use spectral_core::registry::Builtin;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn Error>>;

/// A fresh, empty directory for one test, removed when the test drops it.
fn test_dir(name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new("fspec-scene", name)?)
}

fn write(dir: &Path, name: &str, text: &str) -> TestResult<PathBuf> {
    let path = dir.join(name);
    fs::write(&path, text)?;
    Ok(path)
}

/// 1-based line of the first line of `text` that contains `needle`.
fn line_of(text: &str, needle: &str) -> TestResult<usize> {
    text.lines()
        .position(|l| l.contains(needle))
        .map(|i| i + 1)
        .ok_or_else(|| format!("`{needle}` not in the scene text").into())
}

/// The error message of loading `path` (an error if it loads).
fn error_of(path: &Path) -> TestResult<String> {
    match load_scene_file(path) {
        Ok(_) => Err(format!("{} loaded, expected an error", path.display()).into()),
        Err(e) => {
            assert_eq!(e.exit_code(), 2);
            let message = e.to_string();
            assert!(!message.contains('\n'), "not one line: {message}");
            Ok(message)
        }
    }
}

/// Writes `text` as `name` in a fresh directory and returns the path and the
/// load error.
fn scene_error(test: &str, text: &str) -> TestResult<(PathBuf, String)> {
    let dir = test_dir(test)?;
    let path = write(&dir, "scene.toml", text)?;
    let message = error_of(&path)?;
    Ok((path, message))
}

/// Asserts `message` starts with `path:line_of(needle): key:`.
fn assert_at(message: &str, path: &Path, text: &str, needle: &str, key: &str) -> TestResult {
    let prefix = format!("{}:{}: {key}: ", path.display(), line_of(text, needle)?);
    assert!(
        message.starts_with(&prefix),
        "expected prefix `{prefix}`, got `{message}`"
    );
    Ok(())
}

/// A valid scene: a camera and one emitting quad.
const BASE: &str = r#"
[camera]
position = [0, 0, 3]
target = [0, 0, 0]
fov_deg = 40

[materials.white]
type = "lambert"
albedo = { constant = 0.5 }
emission = { constant = 1.0 }

[[quads]]
vertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
material = "white"
"#;

fn small_settings() -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 16,
        height: 16,
        spp: 2,
        integrator: IntegratorSettings {
            max_depth: 5,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed: 1,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    }
}

/// Renders at 16 × 16, 2 spp with an 8-coefficient Fourier transport.
fn render_small(scene: &Scene) -> TestResult<Vec<Xyz>> {
    let transport = FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    Ok(render(&transport, scene, &small_settings(), &mut |_| true)?.xyz)
}

/// Builds and renders; checks finite, non-negative luminance, not all black.
fn assert_renders(name: &str, loaded: LoadedScene) -> TestResult<Scene> {
    let scene = loaded.builder.build()?;
    let image = render_small(&scene)?;
    assert!(
        image
            .iter()
            .all(|p| p.to_array().iter().all(|v| v.is_finite())),
        "{name}: non-finite pixels"
    );
    let total_y: f64 = image.iter().map(|p| p.to_array()[1]).sum();
    assert!(total_y > 0.0, "{name}: all black (sum Y = {total_y})");
    Ok(scene)
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

// ---------------------------------------------------------------------------
// Examples and valid inputs
// ---------------------------------------------------------------------------

#[test]
fn every_example_scene_loads_builds_and_renders() -> TestResult {
    let mut paths: Vec<PathBuf> = fs::read_dir(scenes_dir())?
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    paths.retain(|p| p.extension().is_some_and(|e| e == "toml"));
    paths.sort();
    assert!(paths.len() >= 9, "only {} example scenes", paths.len());
    for path in &paths {
        let name = path.display().to_string();
        let loaded = load_scene_file(path).map_err(|e| format!("{name}: {e}"))?;
        assert!(
            loaded.warnings.is_empty(),
            "{name}: warnings {:?}",
            loaded.warnings
        );
        assert_renders(&name, loaded)?;
    }
    Ok(())
}

#[test]
fn render_defaults_are_read() -> TestResult {
    let loaded = load_scene_file(&scenes_dir().join("cornell.toml"))?;
    assert_eq!(
        loaded.render,
        RenderDefaults {
            width: Some(256),
            height: Some(256),
            spp: Some(64),
            max_depth: Some(8),
            seed: Some(1),
            hide_emitters: None,
            ..RenderDefaults::default()
        }
    );
    let dir = test_dir("defaults")?;
    let loaded = load_scene_file(&write(&dir, "s.toml", BASE)?)?;
    assert_eq!(loaded.render, RenderDefaults::default());
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    // The film mode, and a name that is none.
    let splat = format!("{BASE}\n[render]\nfilm = \"splat\"\n");
    let loaded = load_scene_file(&write(&dir, "splat.toml", &splat)?)?;
    assert_eq!(loaded.render.film, Some(simd_tracer::film::FilmMode::Splat));
    let (_, message) = scene_error("film-name", &format!("{BASE}\n[render]\nfilm = \"blur\"\n"))?;
    assert!(
        message.contains("film `blur`: use sample or splat"),
        "{message}"
    );
    // The filter, by each of its names (the same as `--filter`'s), and a
    // name that is none.
    use clap::ValueEnum;
    use fspec_cli::render_cmd::FilterKind;
    use fspec_cli::scene_file::{FILTER_NAMES, FilterChoice};
    for name in FILTER_NAMES {
        let text = format!("{BASE}\n[render]\nfilter = \"{name}\"\n");
        let loaded = load_scene_file(&write(&dir, &format!("{name}.toml"), &text)?)?;
        assert_eq!(loaded.render.filter, FilterChoice::named(name), "{name}");
        assert!(loaded.render.filter.is_some(), "{name}");
    }
    let flags: Vec<String> = FilterKind::value_variants()
        .iter()
        .filter_map(|kind| kind.to_possible_value().map(|v| v.get_name().to_string()))
        .collect();
    assert_eq!(
        flags, FILTER_NAMES,
        "--filter and [render] filter name the same filters"
    );
    for kind in FilterKind::value_variants() {
        let name = kind.to_possible_value().map(|v| v.get_name().to_string());
        assert_eq!(
            Some(FilterChoice::from(*kind)),
            name.as_deref().and_then(FilterChoice::named)
        );
    }
    assert_eq!(
        FilterChoice::named("mitchell"),
        Some(FilterChoice::Cubic {
            b: 1.0 / 3.0,
            c: 1.0 / 3.0
        })
    );
    let (_, message) = scene_error(
        "filter-name",
        &format!("{BASE}\n[render]\nfilter = \"sinc\"\n"),
    )?;
    assert!(
        message.contains("filter `sinc`: use box, tent, gaussian, mitchell, catmull-rom, lanczos"),
        "{message}"
    );
    Ok(())
}

/// A small OBJ: a unit quad (two triangles) facing +z, with an MTL.
const QUAD_OBJ: &str = "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl grey\nf 1/1 2/2 3/3 4/4\n";

#[test]
fn bare_obj_is_framed_and_lit_by_a_white_environment() -> TestResult {
    let dir = test_dir("bare-obj")?;
    write(&dir, "quad.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n")?;
    let path = write(&dir, "quad.obj", QUAD_OBJ)?;
    let loaded = load_obj_scene(&path)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let scene = assert_renders("bare OBJ", loaded)?;
    let environment = scene.environment().ok_or("no environment")?;
    // D65 with luminance Y = 1.
    let white = &scene.spectra()[environment.index()];
    let y_bar = Builtin::lookup("cie-y")?;
    let (mut num, mut den) = (0.0, 0.0);
    for l in 360..=830 {
        let y = y_bar.value(f64::from(l));
        num += f64::from(white.value(l as f32)) * y;
        den += y;
    }
    assert!(
        (num / den - 1.0).abs() < 0.01,
        "environment Y {}",
        num / den
    );
    let d65 = Builtin::lookup("d65")?;
    let ratio = |l: f64| f64::from(white.value(l as f32)) / d65.value(l);
    assert!(
        (ratio(450.0) / ratio(650.0) - 1.0).abs() < 0.02,
        "not D65-shaped"
    );
    // The camera is on +z looking at the centre, the quad fills the view.
    let p = scene.camera().position();
    assert!(p.x.abs() < 1e-6 && p.y.abs() < 1e-6 && p.z > 1.0, "{p}");
    assert_eq!(
        scene.camera().projection(),
        simd_tracer::scene::camera::Projection::Perspective { fov_deg: 40.0 }
    );
    let image = render_small(&scene)?;
    let centre = image[8 * 16 + 8].to_array()[1];
    assert!(centre > 0.0, "centre pixel is black");
    Ok(())
}

#[test]
fn bare_obj_with_an_emitter_has_no_environment() -> TestResult {
    let dir = test_dir("bare-obj-light")?;
    write(&dir, "quad.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n")?;
    let path = write(&dir, "quad.obj", QUAD_OBJ)?;
    let scene = assert_renders("bare OBJ with light", load_obj_scene(&path)?)?;
    assert!(scene.environment().is_none());
    assert_eq!(scene.lights().len(), 2);
    Ok(())
}

#[test]
fn bare_obj_errors() -> TestResult {
    let dir = test_dir("bare-obj-errors")?;
    let missing = dir.join("missing.obj");
    let message = load_obj_scene(&missing).err().ok_or("loaded")?.to_string();
    assert_eq!(message, format!("{}: no such file", missing.display()));
    let flat = write(&dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")?;
    let message = load_obj_scene(&flat).err().ok_or("loaded")?.to_string();
    assert_eq!(
        message,
        format!("{}: the OBJ has no usable triangle", flat.display())
    );
    Ok(())
}

/// Writes an 8-bit RGB PNG.
fn write_png_rgb(path: &Path, width: u32, height: u32, data: &[u8]) -> TestResult {
    let file = fs::File::create(path)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(data)?;
    writer.finish()?;
    Ok(())
}

#[test]
fn csv_spectrum_and_png_texture_load() -> TestResult {
    let dir = test_dir("csv-png")?;
    write(&dir, "lamp.csv", "nm,power\n400,0.5\n550,1.0\n700,0.8\n")?;
    write_png_rgb(
        &dir.join("wood.png"),
        2,
        2,
        &[200, 150, 100, 50, 40, 30, 255, 255, 255, 0, 0, 0],
    )?;
    let text = format!(
        "{BASE}\n[spectra.lamp]\ncsv = \"lamp.csv\"\nscale = 2\n\n\
         [materials.wood]\ntype = \"lambert\"\nalbedo_texture = \"wood.png\"\nemission = \"lamp\"\n\n\
         [[quads]]\nvertices = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]\nmaterial = \"wood\"\n"
    );
    let path = write(&dir, "scene.toml", &text)?;
    let loaded = load_scene_file(&path)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let scene = assert_renders("csv + png", loaded)?;
    assert_eq!(scene.textures().len(), 1);
    // The scaled CSV: twice the tabulated values.
    let lamp = scene
        .spectra()
        .iter()
        .find(|s| (s.value(550.0) - 2.0).abs() < 1e-4)
        .ok_or("no spectrum with value 2 at 550 nm")?;
    assert!((lamp.value(400.0) - 1.0).abs() < 1e-4);
    Ok(())
}

#[test]
fn scale_multiplies_every_source() -> TestResult {
    let dir = test_dir("scale")?;
    let sources = [
        "builtin = \"d65\"",
        "builtin = \"blackbody-4000\"",
        "values = [[400, 0.2], [700, 0.6]]",
        "blackbody_k = 3000",
        "rgb = [0.7, 0.3, 0.2]",
        "rgb_emission = [2.0, 1.0, 0.5]",
        "fourier = [0.5, 0.1, -0.05]",
        "constant = 0.25",
    ];
    for source in sources {
        let mut means = Vec::new();
        for scale in [1.0, 2.5] {
            let text =
                format!("{BASE}\n[environment]\nspectrum = {{ {source}, scale = {scale} }}\n");
            let path = write(&dir, "scene.toml", &text)?;
            let scene = load_scene_file(&path)?.builder.build()?;
            let id = scene.environment().ok_or("no environment")?;
            means.push(scene.spectra()[id.index()].mean());
        }
        let ratio = means[1] / means[0];
        assert!((ratio - 2.5).abs() < 1e-3, "{source}: ratio {ratio}");
    }
    // emission_scale and the environment's scale scale named and built-in spectra.
    let text = format!(
        "{BASE}\n[spectra.e]\nconstant = 0.5\n\n[materials.w2]\ntype = \"lambert\"\nalbedo = \"e\"\nemission = \"e\"\nemission_scale = 3\n\n\
         [[quads]]\nvertices = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]\nmaterial = \"w2\"\n\n\
         [environment]\nspectrum = \"e\"\nscale = 4\n"
    );
    let scene = load_scene_file(&write(&dir, "named.toml", &text)?)?
        .builder
        .build()?;
    let env = scene.environment().ok_or("no environment")?;
    assert!((scene.spectra()[env.index()].mean() - 2.0).abs() < 1e-9);
    let w2 = scene
        .materials()
        .iter()
        .find(|m| m.name == "w2")
        .ok_or("no w2")?;
    let emission = w2.emission.ok_or("no emission")?;
    assert!((scene.spectra()[emission.index()].mean() - 1.5).abs() < 1e-9);
    Ok(())
}

#[test]
fn texture_coordinates_of_obj_faces_are_kept() -> TestResult {
    let dir = test_dir("obj-uv")?;
    write(&dir, "quad.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n")?;
    write(&dir, "quad.obj", QUAD_OBJ)?;
    let text = format!("{BASE}\n[[meshes]]\nobj = \"quad.obj\"\n");
    let scene = load_scene_file(&write(&dir, "scene.toml", &text)?)?
        .builder
        .build()?;
    let uvs = (0..scene.triangle_count())
        .filter_map(|t| scene.uvs(t))
        .flatten()
        .map(|t| t.x + t.y)
        .sum::<f32>();
    assert!(uvs > 0.0, "texture coordinates were dropped");
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: files
// ---------------------------------------------------------------------------

#[test]
fn missing_scene_file() -> TestResult {
    let dir = test_dir("missing")?;
    let path = dir.join("nope.toml");
    assert_eq!(
        error_of(&path)?,
        format!("{}: no such file", path.display())
    );
    Ok(())
}

#[test]
fn unreadable_scene_file() -> TestResult {
    let dir = test_dir("unreadable")?;
    assert_eq!(
        error_of(&dir)?,
        format!("{}: is a directory", dir.display())
    );
    let path = dir.join("binary.toml");
    fs::write(&path, [0xff, 0xfe, 0x00, 0x41])?;
    assert_eq!(
        error_of(&path)?,
        format!("{}: not UTF-8 text", path.display())
    );
    Ok(())
}

#[test]
fn malformed_toml_names_the_line() -> TestResult {
    let text = "[camera]\nposition = [0, 0, 3]\nfov_deg = = 40\ntarget = [0, 0, 0]\n";
    let (path, message) = scene_error("syntax", text)?;
    let prefix = format!("{}:3: TOML syntax: ", path.display());
    assert!(message.starts_with(&prefix), "{message}");
    let text = "[camera]\nfov_deg = 40\nfov_deg = 41\n";
    let (path, message) = scene_error("duplicate", text)?;
    assert!(
        message.starts_with(&format!("{}:3: TOML syntax: duplicate key", path.display())),
        "{message}"
    );
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: keys and types
// ---------------------------------------------------------------------------

#[test]
fn unknown_keys_are_errors_with_their_line() -> TestResult {
    let text = BASE.replace("fov_deg = 40", "fov_deg = 40\nfov = 40");
    let (path, message) = scene_error("unknown-key", &text)?;
    assert_at(&message, &path, &text, "fov = 40", "camera.fov")?;
    assert!(message.contains("unknown key in [camera]"), "{message}");

    let text = format!(
        "{BASE}\n[materials.gold]\ntype = \"conductor\"\nmetal = \"gold\"\nroughnes = 0.1\n"
    );
    let (path, message) = scene_error("unknown-key-material", &text)?;
    assert_at(
        &message,
        &path,
        &text,
        "roughnes",
        "materials.gold.roughnes",
    )?;

    let text =
        format!("{BASE}\n[materials.m]\ntype = \"lambert\"\nalbedo = \"d65\"\nroughness = 0.1\n");
    let (path, message) = scene_error("key-of-other-type", &text)?;
    assert_at(
        &message,
        &path,
        &text,
        "roughness = 0.1",
        "materials.m.roughness",
    )?;
    assert!(message.contains("a lambert material"), "{message}");

    let text = format!("{BASE}\n[lights]\nx = 1\n");
    let (path, message) = scene_error("unknown-top", &text)?;
    assert_at(&message, &path, &text, "[lights]", "lights")?;
    Ok(())
}

#[test]
fn wrong_types_are_errors() -> TestResult {
    let text = BASE.replace("fov_deg = 40", "fov_deg = \"wide\"");
    let (path, message) = scene_error("wrong-type", &text)?;
    assert_at(&message, &path, &text, "fov_deg", "camera.fov_deg")?;
    assert!(
        message.ends_with("expected a number, found a string"),
        "{message}"
    );

    let text = BASE.replace("target = [0, 0, 0]", "target = [0, 0]");
    let (path, message) = scene_error("wrong-length", &text)?;
    assert_at(&message, &path, &text, "target", "camera.target")?;

    let text = format!("{BASE}\n[render]\nwidth = 0\n");
    let (path, message) = scene_error("render-width", &text)?;
    assert_at(&message, &path, &text, "width = 0", "render.width")?;

    let text = format!("{BASE}\n[render]\nspp = 1.5\n");
    let (path, message) = scene_error("render-spp", &text)?;
    assert_at(&message, &path, &text, "spp = 1.5", "render.spp")?;
    assert!(
        message.ends_with("expected an integer, found a float"),
        "{message}"
    );

    let text = format!("meshes = 3\n{BASE}");
    let (path, message) = scene_error("meshes-type", &text)?;
    assert_eq!(
        message,
        format!(
            "{}:1: meshes: expected an array, found an integer",
            path.display()
        )
    );
    Ok(())
}

#[test]
fn negative_roughness_is_an_error() -> TestResult {
    let text = format!(
        "{BASE}\n[materials.gold]\ntype = \"conductor\"\nmetal = \"gold\"\nroughness = -0.1\n"
    );
    let (path, message) = scene_error("roughness", &text)?;
    assert_eq!(
        message,
        format!(
            "{}:{}: materials.gold.roughness: must be a number >= 0",
            path.display(),
            line_of(&text, "roughness")?
        )
    );
    Ok(())
}

#[test]
fn missing_camera_is_an_error() -> TestResult {
    let text = "[[quads]]\nvertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]\nmaterial = \"x\"\n";
    let (path, message) = scene_error("no-camera", text)?;
    assert!(
        message.starts_with(&format!("{}:1: camera: missing", path.display())),
        "{message}"
    );
    let text = BASE.replace("fov_deg = 40\n", "");
    let (path, message) = scene_error("no-fov", &text)?;
    assert_at(&message, &path, &text, "[camera]", "camera.fov_deg")?;
    let text = BASE.replace("fov_deg = 40", "fov_deg = 180");
    let (path, message) = scene_error("bad-fov", &text)?;
    assert_at(&message, &path, &text, "fov_deg", "camera.fov_deg")?;
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: names
// ---------------------------------------------------------------------------

#[test]
fn unknown_spectrum_name() -> TestResult {
    let text = BASE.replace("albedo = { constant = 0.5 }", "albedo = \"gery\"");
    let (path, message) = scene_error("unknown-spectrum", &text)?;
    assert_eq!(
        message,
        format!(
            "{}:{}: materials.white.albedo: unknown spectrum \"gery\" (not in [spectra] and not a built-in)",
            path.display(),
            line_of(&text, "gery")?
        )
    );
    Ok(())
}

#[test]
fn unknown_material_name() -> TestResult {
    let text = BASE.replace("material = \"white\"", "material = \"whte\"");
    let (path, message) = scene_error("unknown-material", &text)?;
    assert_at(&message, &path, &text, "whte", "quads[0].material")?;
    assert!(message.ends_with("unknown material \"whte\" (not in [materials])"));

    let text = format!("{BASE}\n[materials.m]\ntype = \"plastic\"\n");
    let (path, message) = scene_error("unknown-type", &text)?;
    assert_at(&message, &path, &text, "plastic", "materials.m.type")?;
    Ok(())
}

#[test]
fn unknown_builtin_name() -> TestResult {
    let text = format!("{BASE}\n[spectra.lamp]\nbuiltin = \"d66\"\n");
    let (path, message) = scene_error("unknown-builtin", &text)?;
    assert_at(&message, &path, &text, "d66", "spectra.lamp.builtin")?;
    assert!(
        message.contains("unknown built-in spectrum \"d66\""),
        "{message}"
    );

    let text = BASE.replace("albedo = { constant = 0.5 }", "albedo = \"blackbody-hot\"");
    let (path, message) = scene_error("bad-blackbody", &text)?;
    assert_at(
        &message,
        &path,
        &text,
        "blackbody-hot",
        "materials.white.albedo",
    )?;
    assert!(message.contains("temperature"), "{message}");
    Ok(())
}

#[test]
fn unknown_metal() -> TestResult {
    let text = format!("{BASE}\n[materials.m]\ntype = \"conductor\"\nmetal = \"platinum\"\n");
    let (path, message) = scene_error("unknown-metal", &text)?;
    assert_at(&message, &path, &text, "platinum", "materials.m.metal")?;
    assert!(message.contains("unknown metal \"platinum\""), "{message}");

    let text = format!("{BASE}\n[materials.m]\ntype = \"conductor\"\nn = \"gold-n\"\n");
    let (path, message) = scene_error("conductor-no-k", &text)?;
    assert_at(&message, &path, &text, "[materials.m]", "materials.m.k")?;
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: spectra
// ---------------------------------------------------------------------------

#[test]
fn two_source_keys_in_one_spectrum() -> TestResult {
    let text = format!("{BASE}\n[spectra.s]\nconstant = 1\nrgb = [0.5, 0.5, 0.5]\n");
    let (path, message) = scene_error("two-sources", &text)?;
    assert_at(&message, &path, &text, "rgb = ", "spectra.s.rgb")?;
    assert!(message.contains("exactly one source key"), "{message}");

    let text = BASE.replace(
        "albedo = { constant = 0.5 }",
        "albedo = { constant = 0.5, builtin = \"d65\" }",
    );
    let (path, message) = scene_error("two-sources-inline", &text)?;
    assert_at(
        &message,
        &path,
        &text,
        "builtin",
        "materials.white.albedo.builtin",
    )?;

    let text = format!("{BASE}\n[spectra.s]\nscale = 2\n");
    let (path, message) = scene_error("no-source", &text)?;
    assert_at(&message, &path, &text, "[spectra.s]", "spectra.s")?;
    Ok(())
}

#[test]
fn bad_inline_spectra() -> TestResult {
    let text = format!("{BASE}\n[spectra.s]\nvalues = [[400, 0.5], [500, nan]]\n");
    let (path, message) = scene_error("inline-nan", &text)?;
    assert_at(&message, &path, &text, "nan", "spectra.s.values[1][1]")?;
    assert!(message.contains("finite"), "{message}");

    let text = format!("{BASE}\n[spectra.s]\nvalues = [\n  [400, 0.5],\n  [500, -1],\n]\n");
    let (path, message) = scene_error("inline-negative", &text)?;
    assert_eq!(
        message,
        format!(
            "{}:{}: spectra.s.values[1]: value -1 is negative (spectra must be non-negative)",
            path.display(),
            line_of(&text, "[500, -1]")?
        )
    );

    let text = format!("{BASE}\n[spectra.s]\nvalues = []\n");
    let (path, message) = scene_error("inline-empty", &text)?;
    assert_at(&message, &path, &text, "values = []", "spectra.s.values")?;

    let text = format!("{BASE}\n[spectra.s]\nvalues = [[500, 1], [400, 1]]\n");
    let (path, message) = scene_error("inline-unsorted", &text)?;
    assert_at(&message, &path, &text, "values", "spectra.s.values[1]")?;

    let text = format!("{BASE}\n[spectra.s]\nconstant = -2\n");
    let (path, message) = scene_error("negative-constant", &text)?;
    assert_at(
        &message,
        &path,
        &text,
        "constant = -2",
        "spectra.s.constant",
    )?;

    let text = format!("{BASE}\n[spectra.s]\nfourier = []\n");
    let (path, message) = scene_error("empty-fourier", &text)?;
    assert_at(&message, &path, &text, "fourier", "spectra.s.fourier")?;

    let text = format!("{BASE}\n[spectra.s]\nrgb = [1.5, 0, 0]\n");
    let (path, message) = scene_error("rgb-range", &text)?;
    assert_at(&message, &path, &text, "rgb", "spectra.s.rgb")?;
    Ok(())
}

#[test]
fn bad_csv_spectra() -> TestResult {
    for (name, csv, detail) in [
        (
            "csv-negative",
            "400,1\n500,2\n600,-1\n",
            "line 3: value -1 is negative",
        ),
        (
            "csv-nan",
            "400,1\n500,nan\n",
            "line 2: cell 2 is NaN or infinite",
        ),
        ("csv-empty", "# nothing\n", "no data rows"),
    ] {
        let dir = test_dir(name)?;
        let csv_path = write(&dir, "lamp.csv", csv)?;
        let text = format!("{BASE}\n[spectra.lamp]\ncsv = \"lamp.csv\"\n");
        let path = write(&dir, "scene.toml", &text)?;
        let message = error_of(&path)?;
        assert_eq!(
            message,
            format!(
                "{}:{}: spectra.lamp.csv: {}: {detail}{}",
                path.display(),
                line_of(&text, "lamp.csv")?,
                csv_path.display(),
                if detail.starts_with("no data") {
                    " (expected `wavelength_nm,value` lines)"
                } else if detail.contains("negative") {
                    " (spectra must be non-negative)"
                } else {
                    ""
                }
            )
        );
    }
    let dir = test_dir("csv-missing")?;
    let text = format!("{BASE}\n[spectra.lamp]\ncsv = \"nope.csv\"\n");
    let path = write(&dir, "scene.toml", &text)?;
    let message = error_of(&path)?;
    assert_at(&message, &path, &text, "nope.csv", "spectra.lamp.csv")?;
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: materials
// ---------------------------------------------------------------------------

#[test]
fn bad_ior() -> TestResult {
    let text = format!("{BASE}\n[materials.glass]\ntype = \"dielectric\"\nior = 0.9\n");
    let (path, message) = scene_error("ior-small", &text)?;
    assert_eq!(
        message,
        format!(
            "{}:{}: materials.glass.ior: index of refraction 0.9 must be >= 1",
            path.display(),
            line_of(&text, "ior = 0.9")?
        )
    );

    let text = format!(
        "{BASE}\n[materials.glass]\ntype = \"dielectric\"\nior = {{ cauchy = [0.5, 0.001] }}\n"
    );
    let (path, message) = scene_error("ior-cauchy", &text)?;
    assert_at(&message, &path, &text, "cauchy", "materials.glass.ior")?;
    assert!(message.contains("over 360–830 nm"), "{message}");

    let text = format!("{BASE}\n[materials.glass]\ntype = \"dielectric\"\nior = \"sf11\"\n");
    let (path, message) = scene_error("ior-name", &text)?;
    assert_at(&message, &path, &text, "sf11", "materials.glass.ior")?;

    let text = format!("{BASE}\n[materials.c]\ntype = \"coated\"\nalbedo = \"e\"\nior = \"bk7\"\n");
    let (path, message) = scene_error("ior-coat", &text)?;
    assert_at(&message, &path, &text, "bk7", "materials.c.ior")?;
    Ok(())
}

/// `thin-dielectric` takes `ior` (a number > 0, slab over outside, below 1
/// allowed); `sides = "front"` makes a reflective material one-sided
/// (default `both`).
#[test]
fn thin_dielectric_and_sides_load() -> TestResult {
    let dir = test_dir("thin-dielectric")?;
    let text = format!(
        "{BASE}\n[materials.pane]\ntype = \"thin-dielectric\"\nior = 1.5\nsides = \"front\"\n\
         [materials.bubble]\ntype = \"thin-dielectric\"\nior = 0.75\n\
         [materials.matte]\ntype = \"lambert\"\nalbedo = {{ constant = 0.5 }}\nsides = \"front\"\n\
         [[quads]]\nvertices = [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]]\nmaterial = \"pane\"\n\
         [[quads]]\nvertices = [[-1, -1, 2], [1, -1, 2], [1, 1, 2], [-1, 1, 2]]\nmaterial = \"bubble\"\n\
         [[quads]]\nvertices = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]\nmaterial = \"matte\"\n"
    );
    let scene = load_scene_file(&write(&dir, "scene.toml", &text)?)?
        .builder
        .build()?;
    let material = |name: &str| {
        scene
            .materials()
            .iter()
            .find(|m| m.name == name)
            .ok_or(format!("no {name}"))
    };
    assert_eq!(
        material("pane")?.bsdf,
        Bsdf::ThinDielectric {
            eta: 1.5,
            tints: None
        }
    );
    assert_eq!(
        material("bubble")?.bsdf,
        Bsdf::ThinDielectric {
            eta: 0.75,
            tints: None
        }
    );
    assert_eq!(material("pane")?.sides, Sides::Front);
    assert!(!material("pane")?.front_only(), "a transmitting BSDF");
    assert!(material("matte")?.front_only());
    assert_eq!(material("white")?.sides, Sides::Both);
    Ok(())
}

#[test]
fn bad_thin_dielectrics_and_sides() -> TestResult {
    for (test, body, needle, key) in [
        ("thin-zero", "ior = 0", "ior = 0", "materials.pane.ior"),
        ("thin-name", "ior = \"bk7\"", "bk7", "materials.pane.ior"),
        (
            "thin-rough",
            "ior = 1.5\nroughness = 0.1",
            "roughness",
            "materials.pane.roughness",
        ),
        ("thin-missing", "", "[materials.pane]", "materials.pane.ior"),
        (
            "sides",
            "ior = 1.5\nsides = \"back\"",
            "sides",
            "materials.pane.sides",
        ),
    ] {
        let text = format!("{BASE}\n[materials.pane]\ntype = \"thin-dielectric\"\n{body}\n");
        let (path, message) = scene_error(test, &text)?;
        assert_at(&message, &path, &text, needle, key)?;
    }
    let text = format!("{BASE}\n[materials.pane]\ntype = \"thin-dielectric\"\nior = -2\n");
    let (_, message) = scene_error("thin-negative", &text)?;
    assert!(message.contains("must be a finite number > 0"), "{message}");
    Ok(())
}

#[test]
fn empty_film_layers() -> TestResult {
    let text = format!(
        "{BASE}\n[materials.f]\ntype = \"thin-film\"\nlayers = []\nsubstrate = {{ ior = 1.5 }}\n"
    );
    let (path, message) = scene_error("film-empty", &text)?;
    assert_at(&message, &path, &text, "layers = []", "materials.f.layers")?;
    assert!(message.ends_with("needs at least one layer"), "{message}");

    let text = format!(
        "{BASE}\n[materials.f]\ntype = \"thin-film\"\nlayers = [{{ ior = 1.3, thickness_nm = 300 }}]\nsubstrate = {{ ior = 1.5, k = 0.1 }}\nbase = \"transparent\"\n"
    );
    let (path, message) = scene_error("film-lossy", &text)?;
    assert_at(&message, &path, &text, "substrate", "materials.f.substrate")?;

    let text = format!(
        "{BASE}\n[materials.f]\ntype = \"thin-film\"\nlayers = [{{ ior = 1.3 }}]\nsubstrate = {{ ior = 1.5 }}\n"
    );
    let (path, message) = scene_error("film-thickness", &text)?;
    assert_at(
        &message,
        &path,
        &text,
        "layers",
        "materials.f.layers[0].thickness_nm",
    )?;
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: meshes
// ---------------------------------------------------------------------------

#[test]
fn missing_obj() -> TestResult {
    let dir = test_dir("obj-missing")?;
    let text = format!("{BASE}\n[[meshes]]\nobj = \"nope.obj\"\n");
    let path = write(&dir, "scene.toml", &text)?;
    assert_eq!(
        error_of(&path)?,
        format!(
            "{}:{}: meshes[0].obj: {}: no such file",
            path.display(),
            line_of(&text, "nope.obj")?,
            dir.join("nope.obj").display()
        )
    );
    Ok(())
}

#[test]
fn malformed_obj_and_mtl() -> TestResult {
    let dir = test_dir("obj-malformed")?;
    let text = format!("{BASE}\n[[meshes]]\nobj = \"bad.obj\"\n");
    let path = write(&dir, "scene.toml", &text)?;
    let line = line_of(&text, "bad.obj")?;
    let obj = dir.join("bad.obj");

    fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n")?;
    let message = error_of(&path)?;
    let prefix = format!(
        "{}:{line}: meshes[0].obj: {}: ",
        path.display(),
        obj.display()
    );
    assert!(message.starts_with(&prefix), "{message}");
    assert!(message.contains("(OBJ/MTL syntax)"), "{message}");

    fs::write(
        &obj,
        "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    )?;
    fs::write(dir.join("bad.mtl"), "newmtl m\nKd 1 x 1\n")?;
    let message = error_of(&path)?;
    assert!(message.starts_with(&prefix), "{message}");
    assert!(message.contains("material library"), "{message}");

    fs::write(dir.join("bad.mtl"), "newmtl m\nKd 0.5 -1 0.5\n")?;
    let message = error_of(&path)?;
    assert!(message.starts_with(&prefix), "{message}");
    assert!(message.contains("material `m`: Kd"), "{message}");

    fs::remove_file(dir.join("bad.mtl"))?;
    let message = error_of(&path)?;
    assert!(message.starts_with(&prefix), "{message}");
    assert!(message.contains("mtllib"), "{message}");
    Ok(())
}

#[test]
fn degenerate_triangles_are_counted_in_a_warning() -> TestResult {
    let dir = test_dir("degenerate")?;
    // One good triangle, two of zero area, one with a NaN vertex.
    write(
        &dir,
        "mesh.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv nan 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 2\nf 5 2 3\n",
    )?;
    let text = format!("{BASE}\n[[meshes]]\nobj = \"mesh.obj\"\nmaterial = \"white\"\n");
    let path = write(&dir, "scene.toml", &text)?;
    let loaded = load_scene_file(&path)?;
    assert_eq!(
        loaded.warnings,
        vec![format!(
            "{}:{}: meshes[0].obj: 3 degenerate triangle(s) (zero area or non-finite) are skipped",
            path.display(),
            line_of(&text, "mesh.obj")?
        )]
    );
    let scene = loaded.builder.build()?;
    assert_eq!(scene.skipped_triangles(), 3);

    // Nothing usable at all: an error.
    write(&dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")?;
    let text = "[camera]\nposition = [0, 0, 3]\ntarget = [0, 0, 0]\nfov_deg = 40\n\n[[meshes]]\nobj = \"flat.obj\"\n";
    let path = write(&dir, "flat.toml", text)?;
    let message = error_of(&path)?;
    assert!(
        message.starts_with(&format!(
            "{}:1: meshes: the scene has no usable triangle",
            path.display()
        )),
        "{message}"
    );
    Ok(())
}

// ---------------------------------------------------------------------------
// Errors: textures
// ---------------------------------------------------------------------------

fn textured_scene(dir: &Path, texture: &str) -> TestResult<(PathBuf, String)> {
    let text = BASE.replace(
        "albedo = { constant = 0.5 }",
        &format!("albedo_texture = \"{texture}\""),
    );
    Ok((write(dir, "scene.toml", &text)?, text))
}

/// CRC-32 (IEEE) of PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

fn png_chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) -> TestResult {
    out.extend_from_slice(&u32::try_from(data.len())?.to_be_bytes());
    let mut body = kind.to_vec();
    body.extend_from_slice(data);
    out.extend_from_slice(&body);
    out.extend_from_slice(&crc32(&body).to_be_bytes());
    Ok(())
}

#[test]
fn texture_errors() -> TestResult {
    let dir = test_dir("texture-errors")?;
    let key = "materials.white.albedo_texture";

    // Missing.
    let (path, text) = textured_scene(&dir, "nope.png")?;
    let message = error_of(&path)?;
    assert_at(&message, &path, &text, "nope.png", key)?;
    assert!(
        message.contains(&format!("{}: cannot read", dir.join("nope.png").display())),
        "{message}"
    );

    // Wrong format.
    write(&dir, "text.png", "not an image")?;
    let (path, text) = textured_scene(&dir, "text.png")?;
    let message = error_of(&path)?;
    assert_at(&message, &path, &text, "text.png", key)?;
    assert!(message.ends_with("not a PNG or OpenEXR file"), "{message}");

    // Corrupt PNG after a valid signature.
    let mut bad = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    bad.extend_from_slice(b"garbage");
    fs::write(dir.join("corrupt.png"), &bad)?;
    let (path, text) = textured_scene(&dir, "corrupt.png")?;
    let message = error_of(&path)?;
    assert_at(&message, &path, &text, "corrupt.png", key)?;
    assert!(message.contains("bad PNG"), "{message}");

    // Too many texels: a PNG header of 10000 × 10000.
    let mut huge = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&10_000u32.to_be_bytes());
    ihdr.extend_from_slice(&10_000u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    png_chunk(&mut huge, b"IHDR", &ihdr)?;
    png_chunk(&mut huge, b"IDAT", &[0x78, 0x9c, 0x03, 0x00])?;
    png_chunk(&mut huge, b"IEND", &[])?;
    fs::write(dir.join("huge.png"), &huge)?;
    let (path, text) = textured_scene(&dir, "huge.png")?;
    let message = error_of(&path)?;
    assert_at(&message, &path, &text, "huge.png", key)?;
    assert!(message.contains("10000x10000 texels"), "{message}");

    // Too large a file (sparse, nothing is read).
    let big = fs::File::create(dir.join("big.exr"))?;
    big.set_len(600 * 1024 * 1024)?;
    drop(big);
    let (path, text) = textured_scene(&dir, "big.exr")?;
    let message = error_of(&path)?;
    assert_at(&message, &path, &text, "big.exr", key)?;
    assert!(
        message.contains("larger than the 512 MiB limit"),
        "{message}"
    );
    fs::remove_file(dir.join("big.exr"))?;

    // A colour image as a film thickness.
    write_png_rgb(&dir.join("colour.png"), 1, 1, &[10, 20, 30])?;
    let text = format!(
        "{BASE}\n[materials.f]\ntype = \"thin-film\"\nlayers = [{{ ior = 1.3 }}]\nsubstrate = {{ ior = 1.5 }}\nthickness_texture = \"colour.png\"\nthickness_range_nm = [100, 500]\n"
    );
    let path = write(&dir, "film.toml", &text)?;
    let message = error_of(&path)?;
    assert_at(
        &message,
        &path,
        &text,
        "colour.png",
        "materials.f.thickness_texture",
    )?;
    assert!(message.contains("grey image"), "{message}");
    Ok(())
}

// ---------------------------------------------------------------------------
// Warnings
// ---------------------------------------------------------------------------

#[test]
fn warnings_for_unused_shadowing_and_darkness() -> TestResult {
    let dir = test_dir("warnings")?;
    let text = format!(
        "{BASE}\n[spectra.d65]\nconstant = 1\n\n[materials.unused]\ntype = \"lambert\"\nalbedo = {{ constant = 1.5 }}\n"
    );
    let path = write(&dir, "scene.toml", &text)?;
    let warnings = load_scene_file(&path)?.warnings;
    let p = path.display();
    assert_eq!(
        warnings,
        vec![
            format!(
                "{p}:{}: spectra.d65: shadows the built-in spectrum \"d65\" in this file",
                line_of(&text, "[spectra.d65]")?
            ),
            format!(
                "{p}:{}: materials.unused.albedo: reflectance exceeds 1 (max 1.500): the surface adds energy",
                line_of(&text, "constant = 1.5")?
            ),
            format!(
                "{p}:{}: spectra.d65: defined but never used",
                line_of(&text, "[spectra.d65]")?
            ),
            format!(
                "{p}:{}: materials.unused: defined but not used by any mesh or quad",
                line_of(&text, "[materials.unused]")?
            ),
        ]
    );

    let text = BASE.replace("emission = { constant = 1.0 }\n", "");
    let path = write(&dir, "dark.toml", &text)?;
    let warnings = load_scene_file(&path)?.warnings;
    assert_eq!(
        warnings,
        vec![format!(
            "{}: the scene has no light (no emissive triangle, [[lights]] or [environment]): it renders black",
            path.display()
        )]
    );

    // A `materials` name the MTL does not define.
    write(&dir, "quad.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n")?;
    write(&dir, "quad.obj", QUAD_OBJ)?;
    let text =
        format!("{BASE}\n[[meshes]]\nobj = \"quad.obj\"\nmaterials = {{ gray = \"white\" }}\n");
    let path = write(&dir, "mapped.toml", &text)?;
    let warnings = load_scene_file(&path)?.warnings;
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("meshes[0].materials.gray: the MTL"),
        "{warnings:?}"
    );
    Ok(())
}

#[test]
fn scene_files_never_panic_on_odd_values() -> TestResult {
    let dir = test_dir("odd")?;
    let odd = [
        "fov_deg = inf",
        "fov_deg = -inf",
        "fov_deg = 1e400",
        "fov_deg = 0x10",
        "fov_deg = 2024-01-01",
        "fov_deg = [1, 2]",
        "fov_deg = { a = 1 }",
        "fov_deg = 99999999999999999999",
    ];
    for replacement in odd {
        let text = BASE.replace("fov_deg = 40", replacement);
        let path = write(&dir, "scene.toml", &text)?;
        match load_scene_file(&path) {
            Ok(_) => assert_eq!(replacement, "fov_deg = 0x10"),
            Err(e) => assert!(
                e.to_string().starts_with(&format!("{}:", path.display())),
                "{e}"
            ),
        }
    }
    let mut file = fs::File::create(dir.join("nested.toml"))?;
    file.write_all("a = ".as_bytes())?;
    file.write_all("[".repeat(5000).as_bytes())?;
    drop(file);
    let message = error_of(&dir.join("nested.toml"))?;
    assert!(
        message.starts_with(&format!("{}:1: ", dir.join("nested.toml").display())),
        "{message}"
    );
    Ok(())
}

// ---------------------------------------------------------------------------
// Neural materials
// ---------------------------------------------------------------------------

/// A scene directory with the committed networks and thickness texture
/// copied next to `text`: the directory, which the test keeps until it is
/// done with the scene, and the scene's path.
fn neural_scene(test: &str, text: &str) -> TestResult<(ScratchDir, PathBuf)> {
    let dir = test_dir(test)?;
    for file in ["film-400nm.nn", "film-100-800nm.nn", "thickness.png"] {
        fs::copy(scenes_dir().join("assets").join(file), dir.join(file))?;
    }
    let path = write(&dir, "scene.toml", text)?;
    Ok((dir, path))
}

#[test]
fn neural_materials_load_in_every_form() -> TestResult {
    let text = format!(
        "{BASE}\n[materials.a]\ntype = \"neural\"\nnetwork = \"film-400nm.nn\"\nroughness = 0.2\n\
         [materials.b]\ntype = \"neural\"\nnetwork = \"film-100-800nm.nn\"\nthickness_nm = 300\n\
         [materials.c]\ntype = \"neural\"\nnetwork = \"film-100-800nm.nn\"\n\
         thickness_texture = \"thickness.png\"\nthickness_range_nm = [100, 800]\n\
         [[quads]]\nvertices = [[-1, -1, -1], [0, -1, -1], [0, 0, -1], [-1, 0, -1]]\nmaterial = \"a\"\n\
         [[quads]]\nvertices = [[0, -1, -1], [1, -1, -1], [1, 0, -1], [0, 0, -1]]\nmaterial = \"b\"\n\
         [[quads]]\nvertices = [[0, 0, -1], [1, 0, -1], [1, 1, -1], [0, 1, -1]]\nmaterial = \"c\"\n"
    );
    let (_dir, path) = neural_scene("neural-ok", &text)?;
    let loaded = load_scene_file(&path)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_renders("neural", loaded)?;
    Ok(())
}

#[test]
fn neural_material_errors_name_the_key() -> TestResult {
    let cases: [(&str, &str, &str, &str); 6] = [
        (
            "network = \"missing.nn\"",
            "network",
            "materials.n.network",
            "missing.nn",
        ),
        (
            "network = \"thickness.png\"",
            "network",
            "materials.n.network",
            "thickness.png",
        ),
        (
            "network = \"film-400nm.nn\"\nthickness_nm = 300",
            "thickness_nm",
            "materials.n.thickness_nm",
            "one input",
        ),
        (
            "network = \"film-100-800nm.nn\"",
            "type = \"neural\"",
            "materials.n",
            "takes a thickness",
        ),
        (
            "network = \"film-100-800nm.nn\"\nthickness_texture = \"thickness.png\"\n\
             thickness_range_nm = [100, 800]\nroughness = 0.1",
            "type = \"neural\"",
            "materials.n",
            "smooth",
        ),
        (
            "roughness = 0.1",
            "type = \"neural\"",
            "materials.n",
            "network",
        ),
    ];
    for (i, (keys, needle, key, detail)) in cases.iter().enumerate() {
        let text = format!("{BASE}\n[materials.n]\ntype = \"neural\"\n{keys}\n");
        let (_dir, path) = neural_scene(&format!("neural-bad-{i}"), &text)?;
        let message = error_of(&path)?;
        let at = if *needle == "type = \"neural\"" {
            // Table-level errors point at the table header's line or its type.
            message.starts_with(&format!("{}:", path.display()))
                && message.contains(&format!(": {key}"))
        } else {
            message.starts_with(&format!(
                "{}:{}: {key}: ",
                path.display(),
                line_of(&text, needle)?
            ))
        };
        assert!(at, "case {i}: {message}");
        assert!(message.contains(detail), "case {i}: {detail} in {message}");
    }
    Ok(())
}

#[test]
fn neural_thickness_outside_the_training_range_warns() -> TestResult {
    let text = format!(
        "{BASE}\n[materials.n]\ntype = \"neural\"\nnetwork = \"film-100-800nm.nn\"\nthickness_nm = 1500\n\
         [[quads]]\nvertices = [[-1, -1, -1], [0, -1, -1], [0, 0, -1], [-1, 0, -1]]\nmaterial = \"n\"\n"
    );
    let (_dir, path) = neural_scene("neural-warn", &text)?;
    let loaded = load_scene_file(&path)?;
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("trained on thicknesses 100–800 nm")),
        "{:?}",
        loaded.warnings
    );
    Ok(())
}

// ---------------------------------------------------------------------------
// Fluorescent materials
// ---------------------------------------------------------------------------

/// `fluorescent` materials: a built-in fluorophore by name (any case) and
/// an inline one load as fluorescent BSDFs with their own fluorophores; the
/// `quantum_yield` key overrides the fluorophore's.
#[test]
fn fluorescent_materials_load() -> TestResult {
    let text = format!(
        "{BASE}\n[materials.a]\ntype = \"fluorescent\"\nalbedo = {{ constant = 0.8 }}\nfluorophore = \"Fluorescein\"\nquantum_yield = 0.5\n\n\
         [materials.b]\ntype = \"fluorescent\"\nalbedo = {{ constant = 0.8 }}\nfluorophore = {{ absorption = [400, 20, 20], emission = [450, 20, 30], quantum_yield = 0.6 }}\nabsorptance = 0.5\n\n\
         [[quads]]\nvertices = [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]\nmaterial = \"a\"\n\n\
         [[quads]]\nvertices = [[-1, -1, -2], [1, -1, -2], [1, 1, -2], [-1, 1, -2]]\nmaterial = \"b\"\n"
    );
    let dir = test_dir("fluorescent_ok")?;
    let path = write(&dir, "scene.toml", &text)?;
    let loaded = load_scene_file(&path)?;
    let scene = loaded.builder.build()?;
    let fluorescent = scene
        .materials()
        .iter()
        .filter(|m| matches!(m.bsdf, Bsdf::Fluorescent { .. }))
        .count();
    assert_eq!(fluorescent, 2);
    let yields: Vec<f64> = scene
        .fluorophores()
        .iter()
        .map(|f| f.layer.fluorophore().quantum_yield)
        .collect();
    assert_eq!(yields, [0.5, 0.6]);
    Ok(())
}

/// Bad fluorescent materials: one line naming the file, line and key.
#[test]
fn fluorescent_material_errors() -> TestResult {
    let material = |body: &str| format!("{BASE}\n[materials.f]\ntype = \"fluorescent\"\n{body}\n");
    let cases = [
        (
            "albedo = { constant = 0.8 }\nfluorophore = \"quinine\"",
            "fluorophore = \"quinine\"",
            "unknown fluorophore",
        ),
        ("fluorophore = \"fluorescein\"", "[materials.f]", "albedo"),
        (
            "albedo = { constant = 0.8 }\nfluorophore = \"fluorescein\"\nabsorptance = 1.5",
            "fluorophore = \"fluorescein\"",
            "peak_absorptance",
        ),
        (
            "albedo = { constant = 0.8 }\nfluorophore = { absorption = [500, 20, 20], emission = [450, 20, 20], quantum_yield = 0.5 }",
            "fluorophore = {",
            "emission peak",
        ),
        (
            "albedo = { constant = 0.8 }\nfluorophore = { absorption = [400, 20], emission = [450, 20, 20], quantum_yield = 0.5 }",
            "fluorophore = {",
            "3 numbers",
        ),
        (
            "albedo = { constant = 0.8 }\nfluorophore = \"brightener\"\nquantum_yield = 2",
            "fluorophore = \"brightener\"",
            "quantum_yield",
        ),
    ];
    for (i, (body, needle, expected)) in cases.iter().enumerate() {
        let text = material(body);
        let (path, message) = scene_error(&format!("fluorescent_err_{i}"), &text)?;
        assert!(message.contains(expected), "case {i}: {message}");
        let prefix = format!("{}:{}:", path.display(), line_of(&text, needle)?);
        assert!(message.starts_with(&prefix), "case {i}: {message}");
    }
    Ok(())
}
