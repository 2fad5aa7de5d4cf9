//! Tests of texture tables in scene files (`albedo_texture`,
//! `thickness_texture`): the sampling keys reach the textures, image files
//! are shared per file, use and sampling, checkerboards resolve their two
//! spectrum references, and each malformed table is one error line
//! `file:line: key: message` with exit code 2.

use std::error::Error;
use std::fs;
use std::path::Path;
use test_support::ScratchDir;

use fspec_cli::scene_file::load_scene_file;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::spectra::texture::{
    FilterMode, Texture, TextureData, TextureSampling, UvTransform, WrapMode,
};
use simd_tracer::spectra::{SceneSpectrum, SpectrumSource};
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::registry::Builtin;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn Error>>;

/// A fresh, empty directory for one test, removed when the test drops it.
fn test_dir(name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new("fspec-texture", name)?)
}

/// Writes an 8-bit PNG of `color` (grey or RGB).
fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    color: png::ColorType,
    data: &[u8],
) -> TestResult {
    let file = fs::File::create(path)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(color);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(data)?;
    writer.finish()?;
    Ok(())
}

/// A directory with `rgb.png` (2 × 2 colour) and `grey.png` (2 × 1 grey).
fn texture_dir(name: &str) -> TestResult<ScratchDir> {
    let dir = test_dir(name)?;
    write_png(
        &dir.join("rgb.png"),
        2,
        2,
        png::ColorType::Rgb,
        &[200, 150, 100, 50, 40, 30, 255, 255, 255, 0, 0, 0],
    )?;
    write_png(
        &dir.join("grey.png"),
        2,
        1,
        png::ColorType::Grayscale,
        &[0, 255],
    )?;
    Ok(dir)
}

/// 1-based line of the first line of `text` that contains `needle`.
fn line_of(text: &str, needle: &str) -> TestResult<usize> {
    text.lines()
        .position(|l| l.contains(needle))
        .map(|i| i + 1)
        .ok_or_else(|| format!("`{needle}` not in the scene text").into())
}

/// A camera and one emitting quad whose albedo is `albedo_texture = …`.
fn scene_text(albedo_texture: &str) -> String {
    format!(
        "[camera]\nposition = [0, 0, 3]\ntarget = [0, 0, 0]\nfov_deg = 40\n\n\
         [materials.white]\ntype = \"lambert\"\nalbedo_texture = {albedo_texture}\n\
         emission = {{ constant = 1.0 }}\n\n\
         [[quads]]\nvertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]\nmaterial = \"white\"\n"
    )
}

/// Loads `text` (as `scene.toml` in `dir`) and expects an error: one line,
/// exit code 2, starting `path:line_of(needle): key: ` and containing
/// `contains`.
fn assert_error(dir: &Path, text: &str, needle: &str, key: &str, contains: &str) -> TestResult {
    let path = dir.join("scene.toml");
    fs::write(&path, text)?;
    let error = match load_scene_file(&path) {
        Ok(_) => return Err(format!("loaded, expected an error: {text}").into()),
        Err(e) => e,
    };
    assert_eq!(error.exit_code(), 2);
    let message = error.to_string();
    assert!(!message.contains('\n'), "not one line: {message}");
    let prefix = format!("{}:{}: {key}: ", path.display(), line_of(text, needle)?);
    assert!(
        message.starts_with(&prefix),
        "expected prefix `{prefix}`, got `{message}`"
    );
    assert!(
        message.contains(contains),
        "`{contains}` not in `{message}`"
    );
    Ok(())
}

fn small_render(scene: &Scene) -> TestResult<f64> {
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 16,
        height: 16,
        spp: 2,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed: 1,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    };
    let transport = FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let image = render(&transport, scene, &settings, &mut |_| true)?.xyz;
    assert!(
        image
            .iter()
            .all(|p| p.to_array().iter().all(|v| v.is_finite()))
    );
    Ok(image.iter().map(|p| p.to_array()[1]).sum())
}

fn spectrum(source: SpectrumSource) -> TestResult<SceneSpectrum> {
    Ok(SceneSpectrum::new(source, SpectralRange::VISIBLE)?)
}

/// The texture of the material called `name`'s albedo or film thickness.
fn texture_of<'s>(scene: &'s Scene, name: &str) -> TestResult<&'s Texture> {
    use simd_tracer::shading::material::{Albedo, Bsdf};
    let material = scene
        .materials()
        .iter()
        .find(|m| m.name == name)
        .ok_or_else(|| format!("no material {name}"))?;
    let id = match &material.bsdf {
        Bsdf::Lambert {
            albedo: Albedo::Texture(id),
        }
        | Bsdf::Coated {
            albedo: Albedo::Texture(id),
            ..
        }
        | Bsdf::ThinFilm {
            thickness: Some(id),
            ..
        } => *id,
        _ => return Err(format!("{name} has no texture").into()),
    };
    Ok(&scene.textures()[id.index()])
}

#[test]
fn texture_tables_set_the_sampling_and_checkerboards_resolve_their_spectra() -> TestResult {
    let dir = texture_dir("valid")?;
    let text = scene_text(
        "{ file = \"rgb.png\", wrap = \"mirror\", filter = \"nearest\", uv_scale = [4, 4], uv_offset = [0.5, 0], uv_rotation_deg = 30 }",
    ) + "\n[spectra.skin]\nbuiltin = \"colorchecker-2\"\n\n\
         [materials.same]\ntype = \"coated\"\nior = 1.5\n\
         albedo_texture = { file = \"rgb.png\", wrap = \"mirror\", filter = \"nearest\", uv_scale = [4, 4], uv_offset = [0.5, 0], uv_rotation_deg = 30 }\n\n\
         [materials.plain]\ntype = \"lambert\"\nalbedo_texture = \"rgb.png\"\n\n\
         [materials.plain_table]\ntype = \"lambert\"\nalbedo_texture = { file = \"rgb.png\" }\n\n\
         [materials.board]\ntype = \"lambert\"\n\
         albedo_texture = { checkerboard = [\"skin\", { rgb = [0.1, 0.1, 0.1] }], uv_scale = [8, 8] }\n\n\
         [materials.film]\ntype = \"thin-film\"\nlayers = [{ ior = 1.4 }]\nsubstrate = { ior = 1.5 }\n\
         thickness_texture = { file = \"grey.png\", wrap = \"clamp\" }\nthickness_range_nm = [100, 500]\n\n\
         [materials.film_board]\ntype = \"thin-film\"\nlayers = [{ ior = 1.4 }]\nsubstrate = { ior = 1.5 }\n\
         thickness_texture = { checkerboard = [{ constant = 0.2 }, { constant = 0.8 }] }\nthickness_range_nm = [100, 500]\n";
    let mut text = text;
    for (i, name) in [
        "same",
        "plain",
        "plain_table",
        "board",
        "film",
        "film_board",
    ]
    .iter()
    .enumerate()
    {
        let x = 2.0 * i as f64 - 6.0;
        text += &format!(
            "\n[[quads]]\nvertices = [[{x}, -1, -1], [{}, -1, -1], [{}, 1, -1], [{x}, 1, -1]]\nmaterial = \"{name}\"\n",
            x + 1.5,
            x + 1.5
        );
    }
    let path = dir.join("scene.toml");
    fs::write(&path, &text)?;
    let loaded = load_scene_file(&path)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let scene = loaded.builder.build()?;
    assert!(small_render(&scene)? > 0.0);

    // The table's sampling, with the transform built as documented.
    let textured = texture_of(&scene, "white")?;
    let expected = TextureSampling {
        wrap: WrapMode::Mirror,
        filter: FilterMode::Nearest,
        uv: UvTransform::new([4.0, 4.0], [0.5, 0.0], 30.0)?,
    };
    assert_eq!(textured.sampling(), expected);
    // One file per use and sampling: the same table shares the texture, a
    // plain name and a table of defaults share another.
    assert!(std::ptr::eq(textured, texture_of(&scene, "same")?));
    let plain = texture_of(&scene, "plain")?;
    assert_eq!(plain.sampling(), TextureSampling::default());
    assert!(std::ptr::eq(plain, texture_of(&scene, "plain_table")?));
    assert_eq!(textured.data(), plain.data());
    // 5 textures: rgb.png twice, the checkerboard, grey.png, the thickness board.
    assert_eq!(scene.textures().len(), 5);

    // The checkerboard: colorchecker-2 where the halves agree (scale 8:
    // squares of 1/16).
    let board = texture_of(&scene, "board")?;
    let TextureData::Checkerboard { color0, color1 } = board.data() else {
        return Err("not a checkerboard".into());
    };
    let skin = spectrum(SpectrumSource::Builtin(Builtin::lookup("colorchecker-2")?))?;
    let grey = spectrum(SpectrumSource::RgbReflectance([0.1, 0.1, 0.1]))?;
    assert_eq!(color0.coefficients_f32(), skin.coefficients_f32());
    assert_eq!(color1.coefficients_f32(), grey.coefficients_f32());
    let at = |u: f32, v: f32| board.fourier_at(u, v);
    assert_eq!(&at(0.03, 0.03), skin.coefficients_f32());
    assert_eq!(&at(0.09, 0.03), grey.coefficients_f32());
    assert_eq!(&at(0.03, 0.09), grey.coefficients_f32());
    assert_eq!(&at(0.09, 0.09), skin.coefficients_f32());
    assert_eq!(
        board.value_at(0.09, 0.03, 600.0).to_bits(),
        grey.value(600.0).to_bits()
    );

    // Thickness textures: the table's wrap mode; a board of constants.
    let film = texture_of(&scene, "film")?;
    assert_eq!(film.sampling().wrap, WrapMode::Clamp);
    assert!((film.scalar_at(-3.0, 0.5) - 0.0).abs() < 1e-6);
    assert!((film.scalar_at(3.0, 0.5) - 1.0).abs() < 1e-6);
    let film_board = texture_of(&scene, "film_board")?;
    assert!((film_board.scalar_at(0.25, 0.25) - 0.2).abs() < 1e-6);
    assert!((film_board.scalar_at(0.75, 0.25) - 0.8).abs() < 1e-6);
    Ok(())
}

#[test]
fn a_checkerboard_albedo_above_one_warns_at_its_spectrum() -> TestResult {
    let dir = test_dir("warning")?;
    let text = scene_text("{ checkerboard = [{ constant = 1.5 }, { constant = 0.5 }] }");
    let path = dir.join("scene.toml");
    fs::write(&path, &text)?;
    let loaded = load_scene_file(&path)?;
    assert_eq!(
        loaded.warnings,
        vec![format!(
            "{}:{}: materials.white.albedo_texture.checkerboard[0]: reflectance exceeds 1 (max 1.500): the surface adds energy",
            path.display(),
            line_of(&text, "checkerboard")?
        )]
    );
    Ok(())
}

#[test]
fn malformed_texture_tables_are_errors_naming_the_key() -> TestResult {
    let dir = texture_dir("errors")?;
    let key = "materials.white.albedo_texture";
    let cases: &[(&str, &str, &str)] = &[
        // Keys and the choice of file or checkerboard.
        (
            "{ file = \"rgb.png\", wrapp = \"mirror\" }",
            "wrapp",
            "unknown key in a texture (expected one of: file, checkerboard, wrap, filter, uv_scale, uv_offset, uv_rotation_deg)",
        ),
        (
            "{ file = \"rgb.png\", checkerboard = [\"d65\", \"d65\"] }",
            "checkerboard",
            "give either `file` or `checkerboard`, not both",
        ),
        (
            "{ wrap = \"mirror\" }",
            "file",
            "missing (a texture table needs `file` or `checkerboard`)",
        ),
        // Names.
        (
            "{ file = \"rgb.png\", wrap = \"tile\" }",
            "wrap",
            "unknown wrap mode \"tile\" (repeat, mirror or clamp)",
        ),
        (
            "{ file = \"rgb.png\", filter = \"cubic\" }",
            "filter",
            "unknown filter \"cubic\" (bilinear or nearest)",
        ),
        (
            "{ file = \"rgb.png\", wrap = \"Mirror\" }",
            "wrap",
            "unknown wrap mode \"Mirror\"",
        ),
        // Types and lengths.
        ("5", "", "expected a texture (a file name, or a table"),
        (
            "{ file = \"rgb.png\", wrap = 3 }",
            "wrap",
            "expected a string, found an integer",
        ),
        (
            "{ file = 3 }",
            "file",
            "expected a string, found an integer",
        ),
        (
            "{ file = \"rgb.png\", uv_scale = 2 }",
            "uv_scale",
            "expected an array, found an integer",
        ),
        (
            "{ file = \"rgb.png\", uv_scale = [1, 2, 3] }",
            "uv_scale",
            "expected an array of 2 numbers, found 3",
        ),
        (
            "{ file = \"rgb.png\", uv_offset = [\"a\", 0] }",
            "uv_offset[0]",
            "expected a number, found a string",
        ),
        (
            "{ file = \"rgb.png\", uv_offset = [1e39, 0] }",
            "uv_offset",
            "in magnitude (single precision)",
        ),
        (
            "{ file = \"rgb.png\", uv_rotation_deg = \"30\" }",
            "uv_rotation_deg",
            "expected a number, found a string",
        ),
        (
            "{ file = \"rgb.png\", uv_rotation_deg = inf }",
            "uv_rotation_deg",
            "must be a finite number",
        ),
        // Checkerboards.
        (
            "{ checkerboard = [\"d65\"] }",
            "checkerboard",
            "expected an array of 2 spectrum references, found 1",
        ),
        (
            "{ checkerboard = \"d65\" }",
            "checkerboard",
            "expected an array, found a string",
        ),
        (
            "{ checkerboard = [\"colorchecker-2\", \"nope\"] }",
            "checkerboard[1]",
            "unknown spectrum \"nope\"",
        ),
        (
            "{ checkerboard = [\"colorchecker-2\", 3] }",
            "checkerboard[1]",
            "expected a spectrum",
        ),
        (
            "{ checkerboard = [\"colorchecker-2\", \"colorchecker-3\"], filter = \"nearest\" }",
            "filter",
            "a checkerboard repeats and is not filtered",
        ),
        (
            "{ checkerboard = [\"colorchecker-2\", \"colorchecker-3\"], wrap = \"clamp\" }",
            "wrap",
            "`wrap` and `filter` are for image files",
        ),
        // The file inside a table.
        ("{ file = \"nope.png\" }", "file", "cannot read"),
    ];
    for &(table, sub_key, contains) in cases {
        let text = scene_text(table);
        let full_key = if sub_key.is_empty() {
            key.to_string()
        } else {
            format!("{key}.{sub_key}")
        };
        assert_error(&dir, &text, "albedo_texture", &full_key, contains)?;
    }

    // A thickness texture table.
    let text = scene_text("\"rgb.png\"")
        + "\n[materials.f]\ntype = \"thin-film\"\nlayers = [{ ior = 1.3 }]\nsubstrate = { ior = 1.5 }\n\
           thickness_texture = { file = \"grey.png\", filter = \"cubic\" }\nthickness_range_nm = [100, 500]\n";
    assert_error(
        &dir,
        &text,
        "thickness_texture",
        "materials.f.thickness_texture.filter",
        "unknown filter \"cubic\"",
    )?;
    // A colour image as a thickness, through a table.
    let text = scene_text("\"rgb.png\"")
        + "\n[materials.f]\ntype = \"thin-film\"\nlayers = [{ ior = 1.3 }]\nsubstrate = { ior = 1.5 }\n\
           thickness_texture = { file = \"rgb.png\", wrap = \"mirror\" }\nthickness_range_nm = [100, 500]\n";
    assert_error(
        &dir,
        &text,
        "thickness_texture",
        "materials.f.thickness_texture.file",
        "grey image",
    )?;
    Ok(())
}
