//! The Mitsuba 3 importer's file handling: `<include>`, `<default>` and
//! `-D`, `<path>`, references, unused and unsupported parts, `--lenient`,
//! and every kind of bad input giving one line `file:line: …` with exit
//! code 2 (`docs/bad-inputs.md`). How the imported scenes render against
//! Mitsuba is `mitsuba_conformance.rs`.

mod common;

use assert_cmd::Command;
use common::{TestResult, entries};
use fspec_cli::scene_file::{LoadedScene, MitsubaOptions, load_mitsuba_scene};
use std::fs;
use std::path::{Path, PathBuf};
use test_support::ScratchDir;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn test_dir(name: &str) -> TestResult<ScratchDir> {
    common::test_dir("mitsuba-import", name)
}

fn write(dir: &Path, name: &str, text: &str) -> TestResult<PathBuf> {
    let path = dir.join(name);
    fs::write(&path, text)?;
    Ok(path)
}

/// A scene around `body`: a small camera and film, and whatever `body` adds.
fn scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
{body}
</scene>
"#
    )
}

/// A lit quad.
const LIT_QUAD: &str = r#"    <shape type="rectangle"><bsdf type="diffuse"/></shape>
    <emitter type="constant"/>"#;

fn load(path: &Path, defines: &[(&str, &str)], lenient: bool) -> Result<LoadedScene, String> {
    let options = MitsubaOptions {
        defines: defines
            .iter()
            .map(|(n, v)| (n.to_string(), v.to_string()))
            .collect(),
        lenient,
    };
    load_mitsuba_scene(path, &options).map_err(|e| e.to_string())
}

/// Loads `text` as `name` in a fresh folder and expects an error that starts
/// with `file:line:` and contains every needle, on one line.
fn refused(test: &str, text: &str, line: usize, needles: &[&str]) -> TestResult {
    let dir = test_dir(test)?;
    let path = write(&dir, "s.xml", text)?;
    let message = match load(&path, &[], false) {
        Ok(_) => return Err(format!("{test}: accepted").into()),
        Err(message) => message,
    };
    let prefix = format!("{}:{line}:", path.display());
    assert!(
        message.starts_with(&prefix),
        "{test}: {message:?} should start with {prefix:?}"
    );
    assert!(!message.contains('\n'), "{test}: {message:?}");
    for needle in needles {
        assert!(
            message.contains(needle),
            "{test}: {needle:?} not in {message:?}"
        );
    }
    Ok(())
}

#[test]
fn malformed_files_name_their_line() -> TestResult {
    refused(
        "xml",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n</scene>\n",
        3,
        &["malformed XML"],
    )?;
    refused(
        "root",
        "<bsdf version=\"3.0.0\" type=\"diffuse\"/>\n",
        1,
        &["expected <scene>"],
    )?;
    refused(
        "version",
        "<scene version=\"0.6.0\">\n</scene>\n",
        1,
        &["Mitsuba 0.x"],
    )?;
    refused("no-version", "<scene>\n</scene>\n", 1, &["version"])?;
    let text = scene("    <shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>");
    refused("undefined", &text, 8, &["`$r` has no value", "-D r="])?;
    let text = scene("    <shape type=\"sphere\"><ref id=\"nothing\"/></shape>");
    refused(
        "ref",
        &text,
        8,
        &["<ref id=\"nothing\">", "no object has this id"],
    )?;
    let text =
        scene("    <bsdf type=\"diffuse\" id=\"a\"/>\n    <bsdf type=\"diffuse\" id=\"a\"/>");
    refused(
        "duplicate",
        &text,
        9,
        &["id \"a\" is defined twice", "line 8"],
    )?;
    let text = scene("    <shape type=\"sphere\"><float name=\"radius\" value=\"big\"/></shape>");
    refused("number", &text, 8, &["\"big\" is not a finite number"])?;
    let text = scene("    <shape type=\"sphere\"><float name=\"radius\" value=\"nan\"/></shape>");
    refused("nan", &text, 8, &["not a finite number"])?;
    let text = scene("    <shape type=\"sphere\"><string name=\"radius\" value=\"1\"/></shape>");
    refused(
        "type",
        &text,
        8,
        &["property \"radius\"", "expected a float, got a string"],
    )?;
    let text = scene("    <shape type=\"sphere\"><bsdf type=\"hair\"/></shape>");
    refused(
        "plugin",
        &text,
        8,
        &["bsdf type \"hair\" is not supported", "--lenient"],
    )?;
    let text = scene("    <shape type=\"sphere\"><float name=\"radiuss\" value=\"1\"/></shape>");
    refused(
        "unknown-parameter",
        &text,
        8,
        &["parameter \"radiuss\" is not supported"],
    )?;
    let text =
        scene("    <shape type=\"obj\"><string name=\"filename\" value=\"missing.obj\"/></shape>");
    refused("missing-file", &text, 8, &["missing.obj", "no such file"])?;
    let text = scene(LIT_QUAD).replace(
        "value=\"8\"/><integer name=\"height\"",
        "value=\"100000000\"/><integer name=\"height\"",
    );
    refused(
        "absurd-size",
        &text,
        6,
        &["width 100000000", "must be 1 … 65536"],
    )?;
    let text = scene("    <shape type=\"sphere\"><rgb name=\"radius\" value=\"1, 2\"/></shape>");
    refused("rgb", &text, 8, &["<rgb> needs 1 or 3 values"])?;
    let text = scene(
        "    <shape type=\"sphere\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"2, 0, 0\"/></bsdf></shape>",
    );
    refused("reflectance", &text, 8, &["outside [0, 1]"])?;
    let lens = |sensor: &str| {
        scene(LIT_QUAD).replace(
            "<sensor type=\"perspective\">",
            &format!("<sensor type=\"thinlens\">{sensor}"),
        )
    };
    refused("lens-missing", &lens(""), 3, &["needs `aperture_radius`"])?;
    refused(
        "lens-negative",
        &lens("<float name=\"aperture_radius\" value=\"-1\"/>"),
        3,
        &["aperture_radius -1", "must be finite and >= 0"],
    )?;
    refused(
        "lens-focus",
        &lens(
            "<float name=\"aperture_radius\" value=\"0.1\"/><float name=\"focus_distance\" value=\"0\"/>",
        ),
        3,
        &["focus_distance 0"],
    )?;
    let scaled = lens("<float name=\"aperture_radius\" value=\"0.1\"/>")
        .replace("up=\"0, 1, 0\"/>", "up=\"0, 1, 0\"/><scale value=\"2\"/>");
    refused(
        "lens-scaled",
        &scaled,
        3,
        &["scale factors in to_world are not allowed"],
    )?;
    let ortho = scene(LIT_QUAD).replace(
        "<sensor type=\"perspective\">\n        <float name=\"fov\" value=\"40\"/>",
        "<sensor type=\"orthographic\">",
    );
    assert!(ortho.contains("orthographic"));
    refused(
        "ortho-unequal",
        &ortho.replace(
            "up=\"0, 1, 0\"/>",
            "up=\"0, 1, 0\"/><scale x=\"2\" y=\"1\"/>",
        ),
        3,
        &["orthographic", "unequal scales"],
    )?;
    refused(
        "ortho-fov",
        &scene(LIT_QUAD).replace("\"perspective\"", "\"orthographic\""),
        4,
        &["parameter \"fov\" is not supported"],
    )?;
    let sensor = |params: &str| {
        scene(LIT_QUAD).replace(
            "<float name=\"fov\" value=\"40\"/>",
            &format!("<float name=\"fov\" value=\"40\"/>{params}"),
        )
    };
    refused(
        "near-zero",
        &sensor("<float name=\"near_clip\" value=\"0\"/>"),
        3,
        &["near_clip 0", "need 0 < near_clip < far_clip"],
    )?;
    refused(
        "near-far",
        &sensor("<float name=\"near_clip\" value=\"5\"/><float name=\"far_clip\" value=\"2\"/>"),
        3,
        &["near_clip 5, far_clip 2"],
    )?;
    refused(
        "shift-absurd",
        &sensor("<float name=\"principal_point_offset_x\" value=\"1e9\"/>"),
        3,
        &["principal_point_offset", "within ±16 films"],
    )?;
    refused(
        "shift-thinlens",
        &lens(
            "<float name=\"aperture_radius\" value=\"0.1\"/><float name=\"principal_point_offset_x\" value=\"0.1\"/>",
        ),
        3,
        &["principal_point_offset_x", "not supported"],
    )?;
    refused(
        "cylinder-ends",
        &scene("    <shape type=\"cylinder\"><point name=\"p1\" x=\"0\" y=\"0\" z=\"0\"/></shape>"),
        8,
        &["p0 and p1 must differ"],
    )?;
    refused(
        "cylinder-radius",
        &scene("    <shape type=\"cylinder\"><float name=\"radius\" value=\"-1\"/></shape>"),
        8,
        &["radius -1", "finite and > 0"],
    )?;
    let spot = |params: &str| scene(&format!("    <emitter type=\"spot\">{params}</emitter>"));
    refused(
        "spot-beam",
        &spot(
            "<float name=\"cutoff_angle\" value=\"20\"/><float name=\"beam_width\" value=\"25\"/>",
        ),
        8,
        &[
            "emitter",
            "spot",
            "beam width 25°: must be at least 0 and at most the cutoff angle 20°",
        ],
    )?;
    refused(
        "spot-cutoff",
        &spot("<float name=\"cutoff_angle\" value=\"-10\"/>"),
        8,
        &["cutoff angle -10°"],
    )?;
    refused(
        "spot-singular",
        &spot("<transform name=\"to_world\"><scale value=\"0\"/></transform>"),
        8,
        &["transform"],
    )?;
    refused(
        "spot-texture",
        &spot("<texture type=\"checkerboard\" name=\"texture\"/>"),
        8,
        &["parameter \"texture\" is not supported"],
    )?;
    Ok(())
}

/// An `obj` shape's file is read in parallel when its text is in the
/// parallel reader's grammar and by tobj otherwise: valid text loads either
/// way, and malformed text gets tobj's message on the shape's line.
#[test]
fn obj_files_load_or_are_refused_by_either_reader() -> TestResult {
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let shape = "    <shape type=\"obj\"><string name=\"filename\" value=\"m.obj\"/></shape>\n    <emitter type=\"constant\"/>";
    let cases: [(&str, String, Option<&str>); 4] = [
        // Inside the grammar: the parallel reader.
        ("plain", format!("{triangle}f 1 2 3\n"), None),
        // A line (`l`) is outside it, and valid: tobj reads it.
        ("line", format!("{triangle}l 1 2\nf 1 2 3\n"), None),
        (
            "short-vertex",
            "v 0 0\nf 1 2 3\n".to_string(),
            Some("position parse error"),
        ),
        (
            "index",
            format!("{triangle}f 1 2 9\n"),
            Some("face vertex index out of bounds"),
        ),
    ];
    for (name, obj, error) in cases {
        let dir = test_dir(&format!("obj-{name}"))?;
        write(&dir, "m.obj", &obj)?;
        let path = write(&dir, "s.xml", &scene(shape))?;
        match (load(&path, &[], false), error) {
            (Ok(_), None) => {}
            (Err(message), Some(needle)) => {
                let prefix = format!("{}:8:", path.display());
                assert!(message.starts_with(&prefix), "{name}: {message:?}");
                assert!(
                    message.contains(needle) && message.contains("(OBJ syntax)"),
                    "{name}: {message:?}"
                );
            }
            (Ok(_), Some(needle)) => return Err(format!("{name}: accepted, not {needle}").into()),
            (Err(message), None) => return Err(format!("{name}: refused: {message}").into()),
        }
    }
    Ok(())
}

#[test]
fn includes_defaults_and_defines() -> TestResult {
    let dir = test_dir("include")?;
    fs::create_dir_all(dir.join("parts"))?;
    // An included file's defaults are visible after it; plugin file names
    // in it resolve against the main scene's folder (as in Mitsuba).
    write(
        &dir.join("parts"),
        "geometry.xml",
        r#"<scene version="3.0.0">
    <default name="radius" value="0.5"/>
    <shape type="ply"><string name="filename" value="mesh.ply"/></shape>
</scene>"#,
    )?;
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    write(&dir, "mesh.ply", ply)?;
    let text = scene(
        r#"    <default name="emission" value="2"/>
    <include filename="parts/geometry.xml"/>
    <shape type="sphere"><float name="radius" value="$radius"/></shape>
    <emitter type="constant"><float name="radiance" value="$emission"/></emitter>"#,
    );
    let path = write(&dir, "s.xml", &text)?;
    let loaded = load(&path, &[], false)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    loaded.builder.build()?;
    // -D wins over <default>; an unused -D is a warning.
    let loaded = load(&path, &[("radius", "2"), ("unused", "1")], false)?;
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(
        loaded.warnings[0].contains("-D unused=…"),
        "{:?}",
        loaded.warnings
    );
    let err = load(&path, &[("radius", "-1")], false)
        .err()
        .unwrap_or_default();
    assert!(err.contains("radius -1: must be > 0"), "{err}");
    // A cycle.
    write(
        &dir,
        "a.xml",
        "<scene version=\"3.0.0\"><include filename=\"b.xml\"/></scene>",
    )?;
    write(
        &dir,
        "b.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"a.xml\"/></scene>",
    )?;
    let err = load(&dir.join("a.xml"), &[], false)
        .err()
        .unwrap_or_default();
    assert!(
        err.contains("b.xml:2:") && err.contains("cyclic include"),
        "{err}"
    );
    // A missing include names the including line.
    let text = scene("    <include filename=\"nope.xml\"/>");
    let err = load(&write(&dir, "m.xml", &text)?, &[], false)
        .err()
        .unwrap_or_default();
    assert!(
        err.contains("m.xml:8:") && err.contains("nope.xml: no such file"),
        "{err}"
    );
    Ok(())
}

#[test]
fn unused_definitions_warn_and_lenient_substitutes() -> TestResult {
    let dir = test_dir("lenient")?;
    let text = scene(
        r#"    <bsdf type="diffuse" id="unused"/>
    <texture type="checkerboard" id="also-unused"/>
    <shape type="rectangle"><bsdf type="hair"><float name="eumelanin" value="1"/></bsdf></shape>
    <shape type="sphere"><float name="radius" value="0.5"/><float name="wobble" value="1"/></shape>
    <emitter type="projector"/>
    <emitter type="constant"/>"#,
    );
    let path = write(&dir, "s.xml", &text)?;
    let strict = load(&path, &[], false).err().unwrap_or_default();
    assert!(
        strict.contains("bsdf type \"hair\" is not supported"),
        "{strict}"
    );
    let loaded = load(&path, &[], true)?;
    let warnings = loaded.warnings.join("\n");
    for needle in [
        "s.xml:8: <bsdf id=\"unused\"> is defined but never used",
        "s.xml:9: <texture id=\"also-unused\"> is defined but never used",
        "s.xml:10: bsdf type \"hair\" is not supported; rendered as a grey diffuse BSDF",
        "s.xml:11: shape \"sphere\": parameter \"wobble\" is not supported; ignored",
        "s.xml:12: emitter type \"projector\" is not supported; the emitter is skipped",
    ] {
        assert!(warnings.contains(needle), "{needle:?} not in\n{warnings}");
    }
    assert_eq!(loaded.warnings.len(), 5, "{warnings}");
    loaded.builder.build()?;
    Ok(())
}

#[test]
fn the_command_line_takes_defines_and_reports_one_line() -> TestResult {
    let dir = test_dir("cli")?;
    let text = scene(
        r#"    <default name="r" value="0.5"/>
    <shape type="sphere"><float name="radius" value="$r"/></shape>
    <emitter type="constant"/>"#,
    );
    let path = write(&dir, "s.xml", &text)?;
    let out = dir.join("o.exr");
    let ok = fspec()
        .args(["render", "--quiet", "--spp", "1", "-D", "r=0.25"])
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .output()?;
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(out.exists());
    let bad = fspec()
        .args(["render", "--quiet", "--spp", "1", "-D", "r=-3"])
        .arg(&path)
        .arg("--out")
        .arg(dir.join("p.exr"))
        .output()?;
    let stderr = String::from_utf8(bad.stderr)?;
    assert_eq!(bad.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("s.xml:9:") && stderr.contains("radius -3"),
        "{stderr}"
    );
    assert_eq!(
        entries(&dir)?,
        ["o.exr", "s.xml"],
        "a refused render left a file"
    );
    let bad_define = fspec()
        .args(["render", "-D", "noequals"])
        .arg(&path)
        .output()?;
    assert_eq!(bad_define.status.code(), Some(2));
    Ok(())
}

/// Mitsuba's samplers: each rounds `sample_count` as Mitsuba does (a
/// warning when it changes), accepts its own parameters only, and a
/// sampler Mitsuba does not have is an error (a warning with `--lenient`).
#[test]
fn samplers_round_their_counts_as_mitsuba() -> TestResult {
    let with_sampler = |sampler: &str| {
        scene(LIT_QUAD).replace(
            "<film type=\"hdrfilm\">",
            &format!("{sampler}<film type=\"hdrfilm\">"),
        )
    };
    let dir = test_dir("samplers")?;
    for (name, sampler, spp, rounded) in [
        (
            "ld",
            "<sampler type=\"ldsampler\"><integer name=\"sample_count\" value=\"5\"/></sampler>",
            16,
            true,
        ),
        (
            "strat",
            "<sampler type=\"stratified\"><integer name=\"sample_count\" value=\"16\"/><boolean name=\"jitter\" value=\"false\"/></sampler>",
            16,
            false,
        ),
        (
            "ortho",
            "<sampler type=\"orthogonal\"><integer name=\"sample_count\" value=\"10\"/><integer name=\"strength\" value=\"2\"/></sampler>",
            25,
            true,
        ),
        (
            "indep",
            "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"7\"/></sampler>",
            7,
            false,
        ),
    ] {
        let path = write(&dir, &format!("{name}.xml"), &with_sampler(sampler))?;
        let loaded = load(&path, &[], false)?;
        assert_eq!(loaded.render.spp, Some(spp), "{name}");
        let warned = loaded.warnings.iter().any(|w| w.contains("rounded to"));
        assert_eq!(warned, rounded, "{name}: {:?}", loaded.warnings);
    }
    let sobol = with_sampler(
        "<sampler type=\"sobol\"><integer name=\"sample_count\" value=\"8\"/></sampler>",
    );
    let path = write(&dir, "sobol.xml", &sobol)?;
    let error = load(&path, &[], false).err().ok_or("sobol: accepted")?;
    assert!(
        error.contains("sampler type \"sobol\" is not supported"),
        "{error}"
    );
    let lenient = load(&path, &[], true)?;
    assert_eq!(lenient.render.spp, Some(8));
    assert!(lenient.warnings.iter().any(|w| w.contains("sobol")));
    let jitter = with_sampler(
        "<sampler type=\"ldsampler\"><boolean name=\"jitter\" value=\"true\"/></sampler>",
    );
    let path = write(&dir, "jitter.xml", &jitter)?;
    let error = load(&path, &[], false)
        .err()
        .ok_or("jitter on ldsampler: accepted")?;
    assert!(
        error.contains("parameter \"jitter\" is not supported"),
        "{error}"
    );
    Ok(())
}

/// Mitsuba's clip planes: an orthographic sensor's rays start at local
/// `z = near_clip` scaled by `to_world` and run `far_clip − near_clip`
/// along their unit direction (`orthographic.cpp`); it takes a
/// `focus_distance` (read by every projective sensor, unused here). A
/// scaled `perspective` is refused, as Mitsuba refuses it.
#[test]
fn clip_planes_and_scales_follow_mitsuba() -> TestResult {
    let ortho = scene(LIT_QUAD)
        .replace(
            "<sensor type=\"perspective\">\n        <float name=\"fov\" value=\"40\"/>",
            "<sensor type=\"orthographic\"><float name=\"near_clip\" value=\"0.5\"/>\
             <float name=\"far_clip\" value=\"5\"/><float name=\"focus_distance\" value=\"3\"/>",
        )
        .replace("up=\"0, 1, 0\"/>", "up=\"0, 1, 0\"/><scale value=\"2\"/>");
    assert!(ortho.contains("orthographic") && ortho.contains("<scale value=\"2\"/>"));
    let dir = test_dir("clip-scales")?;
    let path = write(&dir, "ortho.xml", &ortho)?;
    let loaded = load(&path, &[], false)?;
    let built = loaded.builder.build()?;
    let clip = built.camera().clip().ok_or("no clip planes")?;
    // Near: 0.5 × 2; far: that plus 5 − 0.5 (not 5 × 2).
    assert!(
        (clip.near - 1.0).abs() < 1e-5 && (clip.far - 5.5).abs() < 1e-5,
        "{clip:?}"
    );
    refused(
        "perspective-scaled",
        &scene(LIT_QUAD).replace("up=\"0, 1, 0\"/>", "up=\"0, 1, 0\"/><scale value=\"2\"/>"),
        3,
        &["perspective: scale factors in to_world are not allowed"],
    )?;
    // A mirror is no scale.
    let mirrored = scene(LIT_QUAD).replace("up=\"0, 1, 0\"/>", "up=\"0, 1, 0\"/><scale x=\"-1\"/>");
    let path = write(&dir, "mirror.xml", &mirrored)?;
    load(&path, &[], false)?;
    Ok(())
}

/// The conformance suite's textures (`conformance/scenes/textures/`).
fn suite_texture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/conformance/scenes/textures")
        .join(name)
        .display()
        .to_string()
}

/// `mask` as Mitsuba 3.9.1 reads it: the nested BSDF keeps its sides (a
/// one-sided diffuse stays black from behind, `twosided` inside the mask
/// makes it two-sided), a constant opacity outside [0, 1] is clamped with
/// a warning, a grey bitmap's opacities are sRGB-decoded unless `raw`.
/// Refused as Mitsuba refuses them: a mask without one nested BSDF, a mask
/// inside `twosided`, a colour opacity bitmap without `raw`; and opacity
/// textures other than `bitmap`.
#[test]
fn masks_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction};
    let dir = test_dir("masks")?;
    let masked = |opacity: &str, nested: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"mask\">{opacity}{nested}</bsdf></shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let diffuse = "<bsdf type=\"diffuse\"/>";
    let two_sided = "<bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf>";
    let mask_of = |text: &str,
                   name: &str|
     -> TestResult<(
        simd_tracer::shading::material::Mask,
        Vec<String>,
        simd_tracer::scene::Scene,
    )> {
        let path = write(&dir, name, text)?;
        let loaded = load(&path, &[], false)?;
        let warnings = loaded.warnings.clone();
        let built = loaded.builder.build()?;
        let mask = built
            .materials()
            .iter()
            .find_map(|m| match &m.bsdf {
                Bsdf::Mask(mask) => Some((**mask).clone()),
                _ => None,
            })
            .ok_or("no mask")?;
        Ok((mask, warnings, built))
    };
    let (one, warnings, _) = mask_of(
        &masked("<float name=\"opacity\" value=\"0.25\"/>", diffuse),
        "one.xml",
    )?;
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(one.opacity, Fraction::Constant(0.25));
    assert!(one.nested_front_only);
    let (two, ..) = mask_of(&masked("", two_sided), "two.xml")?;
    assert_eq!(two.opacity, Fraction::Constant(0.5), "Mitsuba's default");
    assert!(!two.nested_front_only);
    let (clamped, warnings, _) = mask_of(
        &masked("<float name=\"opacity\" value=\"1.5\"/>", diffuse),
        "clamped.xml",
    )?;
    assert_eq!(clamped.opacity, Fraction::Constant(1.0));
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("opacity 1.5 is clamped to 1")),
        "{warnings:?}"
    );
    // grey.png's top-left texel is 230: sRGB-decoded, or as stored.
    let grey = suite_texture("grey.png");
    for (raw, expected) in [
        ("false", srgb_decode(230.0 / 255.0)),
        ("true", 230.0 / 255.0),
    ] {
        let bitmap = format!(
            "<texture type=\"bitmap\" name=\"opacity\"><string name=\"filename\" value=\"{grey}\"/>\
             <boolean name=\"raw\" value=\"{raw}\"/><string name=\"filter_type\" value=\"nearest\"/></texture>"
        );
        let (textured, _, built) = mask_of(&masked(&bitmap, diffuse), &format!("raw-{raw}.xml"))?;
        let Fraction::Texture(id) = textured.opacity else {
            return Err("not a texture".into());
        };
        let texture = &built.material_tables().textures[id.index()];
        // Mitsuba's v = 0 is the image's top row.
        let value = f64::from(texture.scalar_at(0.125, 0.125));
        assert!(
            (value - expected).abs() < 1e-5,
            "raw {raw}: {value} vs {expected}"
        );
    }
    let colours = suite_texture("colours.png");
    let colour_bitmap = |raw: &str| {
        format!(
            "<texture type=\"bitmap\" name=\"opacity\"><string name=\"filename\" value=\"{colours}\"/>{raw}</texture>"
        )
    };
    refused(
        "mask-colour",
        &masked(&colour_bitmap(""), diffuse),
        8,
        &["a colour image as an opacity, weight or roughness needs raw=true"],
    )?;
    mask_of(
        &masked(
            &colour_bitmap("<boolean name=\"raw\" value=\"true\"/>"),
            diffuse,
        ),
        "colour-raw.xml",
    )?;
    refused(
        "mask-empty",
        &masked("", ""),
        8,
        &["mask", "needs one nested BSDF"],
    )?;
    refused(
        "mask-two",
        &masked("", &format!("{diffuse}{diffuse}")),
        8,
        &["needs one nested BSDF"],
    )?;
    refused(
        "mask-mesh-attribute",
        &masked(
            "<texture type=\"mesh_attribute\" name=\"opacity\"><string name=\"name\" value=\"vertex_color\"/></texture>",
            diffuse,
        ),
        8,
        &[
            "is not supported as an opacity, weight or roughness (bitmap, checkerboard, rawconstant)",
        ],
    )?;
    refused(
        "mask-nan",
        &masked("<float name=\"opacity\" value=\"nan\"/>", diffuse),
        8,
        &["not a finite number"],
    )?;
    refused(
        "twosided-mask",
        &scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"twosided\"><bsdf type=\"mask\">{diffuse}</bsdf></bsdf></shape>"
        )),
        8,
        &["twosided", "only BSDFs without transmission can be nested"],
    )?;
    Ok(())
}

/// Mitsuba's `normalmap`: a raw bitmap's texels as stored, the nested
/// BSDF's sides, the frame turned to the viewer inside a `twosided` and
/// kept on the surface outside one, both switches read; every way to get
/// it wrong is one line.
#[test]
fn normal_maps_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, MapFrame, NormalMap};
    let dir = test_dir("normal-maps")?;
    let bumps = suite_texture("normal_bumps.png");
    let bitmap = |raw: &str| {
        format!(
            "<texture type=\"bitmap\" name=\"normalmap\"><string name=\"filename\" value=\"{bumps}\"/>{raw}</texture>"
        )
    };
    let raw = bitmap("<boolean name=\"raw\" value=\"true\"/>");
    let mapped = |inner: &str| format!("<bsdf type=\"normalmap\">{raw}{inner}</bsdf>");
    let diffuse = "<bsdf type=\"diffuse\"/>";
    let on_rectangle = |bsdf: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\">{bsdf}</shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let map_of = |bsdf: &str, name: &str| -> TestResult<(NormalMap, simd_tracer::scene::Scene)> {
        let path = write(&dir, name, &on_rectangle(bsdf))?;
        let built = load(&path, &[], false)?.builder.build()?;
        let map = built
            .materials()
            .iter()
            .find_map(|m| m.bsdf.normal_maps().first().map(|&map| map.clone()))
            .ok_or("no normal map")?;
        Ok((map, built))
    };
    let (plain, built) = map_of(&mapped(diffuse), "plain.xml")?;
    assert_eq!(plain.frame, MapFrame::Surface);
    assert!(plain.flip_invalid && plain.shadowing, "Mitsuba's defaults");
    assert!(plain.nested_front_only);
    assert!(matches!(plain.nested, Bsdf::Lambert { .. }));
    assert!(built.needs_tangent());
    // normal_bumps.png's texel in column 2, row 3 (Mitsuba's v = 0 is the
    // top row), inside a dome: (n + 1)/2 in bytes, as stored (no sRGB
    // decoding); tools/mitsuba_conformance.py wrote it.
    let texture = &built.material_tables().textures[plain.relief.texture().index()];
    let got = texture
        .vector_at(2.5 / 16.0, 3.5 / 16.0)
        .ok_or("not a vector texture")?;
    let (x, y) = (2.0 * 2.5 / 8.0 - 1.0, 2.0 * 3.5 / 8.0 - 1.0);
    let n = glam::Vec3::new(1.2 * x, 1.2 * y, 1.0).normalize();
    let expected = ((n + glam::Vec3::ONE) / 2.0 * 255.0).round() / 255.0;
    assert!(
        (glam::Vec3::from_array(got) - expected).length() < 1e-6,
        "{got:?} against {expected}"
    );
    let (outside, _) = map_of(
        &mapped("<bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf>"),
        "outside.xml",
    )?;
    assert_eq!(outside.frame, MapFrame::Surface);
    assert!(!outside.nested_front_only);
    let (inside_twosided, _) = map_of(
        &format!("<bsdf type=\"twosided\">{}</bsdf>", mapped(diffuse)),
        "inside.xml",
    )?;
    assert_eq!(inside_twosided.frame, MapFrame::Viewer);
    assert!(inside_twosided.nested_front_only);
    let (switched, _) = map_of(
        &format!(
            "<bsdf type=\"normalmap\">{raw}<boolean name=\"flip_invalid_normals\" value=\"false\"/>\
             <boolean name=\"use_shadowing_function\" value=\"false\"/>{diffuse}</bsdf>"
        ),
        "switched.xml",
    )?;
    assert!(!switched.flip_invalid && !switched.shadowing);
    refused(
        "normalmap-not-raw",
        &on_rectangle(&format!(
            "<bsdf type=\"normalmap\">{}{diffuse}</bsdf>",
            bitmap("")
        )),
        8,
        &["a normal map needs raw=true"],
    )?;
    refused(
        "normalmap-missing",
        &on_rectangle(&format!("<bsdf type=\"normalmap\">{diffuse}</bsdf>")),
        8,
        &["normalmap", "needs a `normalmap` texture"],
    )?;
    refused(
        "normalmap-nested",
        &on_rectangle(&mapped(&mapped(diffuse))),
        8,
        &["a normalmap or bumpmap inside a normalmap or bumpmap is not supported"],
    )?;
    refused(
        "normalmap-two",
        &on_rectangle(&mapped(&format!("{diffuse}{diffuse}"))),
        8,
        &["needs one nested BSDF"],
    )?;
    refused(
        "normalmap-checkerboard",
        &on_rectangle(&format!(
            "<bsdf type=\"normalmap\"><texture type=\"checkerboard\" name=\"normalmap\"/>{diffuse}</bsdf>"
        )),
        8,
        &["is not supported as a normal map (bitmap, rawconstant)"],
    )?;
    Ok(())
}

/// Mitsuba's `bumpmap`: one texture of any name read as heights (a grey
/// bitmap's values sRGB-decoded unless `raw`, not clamped), `scale` and
/// the switches; a colour bitmap without `raw`, a second texture, a
/// missing BSDF or a non-finite scale are one line each.
#[test]
fn bump_maps_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{MapFrame, Relief};
    let dir = test_dir("bump-maps")?;
    let grey = suite_texture("grey.png");
    let colours = suite_texture("colours.png");
    let bitmap = |file: &str, extra: &str| {
        format!(
            "<texture type=\"bitmap\" name=\"heights\"><string name=\"filename\" value=\"{file}\"/>{extra}</texture>"
        )
    };
    let diffuse = "<bsdf type=\"diffuse\"/>";
    let on_rectangle = |bsdf: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\">{bsdf}</shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let path = write(
        &dir,
        "bumps.xml",
        &on_rectangle(&format!(
            "<bsdf type=\"twosided\"><bsdf type=\"bumpmap\">{}<float name=\"scale\" value=\"0.25\"/>{diffuse}</bsdf></bsdf>",
            bitmap(&grey, "")
        )),
    )?;
    let built = load(&path, &[], false)?.builder.build()?;
    let map = built
        .materials()
        .iter()
        .find_map(|m| m.bsdf.normal_maps().first().map(|&map| map.clone()))
        .ok_or("no bump map")?;
    let Relief::Heights { texture, scale } = map.relief else {
        return Err("not a bump map".into());
    };
    assert_eq!(scale, 0.25);
    assert_eq!(map.frame, MapFrame::Viewer, "inside a twosided");
    assert!(map.flip_invalid && map.shadowing);
    // grey.png's top-left texel is 230, sRGB-decoded (no clamp needed).
    let value = built.material_tables().textures[texture.index()].scalar_at(0.125, 0.125);
    assert!((f64::from(value) - srgb_decode(230.0 / 255.0)).abs() < 1e-5);
    refused(
        "bumpmap-colour",
        &on_rectangle(&format!(
            "<bsdf type=\"bumpmap\">{}{diffuse}</bsdf>",
            bitmap(&colours, "")
        )),
        8,
        &["a colour image as a bump map needs raw=true"],
    )?;
    refused(
        "bumpmap-two-textures",
        &on_rectangle(&format!(
            "<bsdf type=\"bumpmap\">{}{}{diffuse}</bsdf>",
            bitmap(&grey, ""),
            bitmap(&grey, "").replace("heights", "more")
        )),
        8,
        &["needs one nested texture and one nested BSDF"],
    )?;
    refused(
        "bumpmap-no-bsdf",
        &on_rectangle(&format!(
            "<bsdf type=\"bumpmap\">{}</bsdf>",
            bitmap(&grey, "")
        )),
        8,
        &["needs one nested texture and one nested BSDF"],
    )?;
    refused(
        "bumpmap-nan",
        &on_rectangle(&format!(
            "<bsdf type=\"bumpmap\">{}<float name=\"scale\" value=\"nan\"/>{diffuse}</bsdf>",
            bitmap(&grey, "")
        )),
        8,
        &["\"nan\" is not a finite number"],
    )?;
    Ok(())
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
fn srgb_decode(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// A conductor's `specular_reflectance` multiplies its Fresnel term (the
/// tint alone on the default material `none`, where `F = 1`); a textured
/// one is refused.
#[test]
fn conductor_tints_multiply_the_fresnel_term() -> TestResult {
    use simd_tracer::shading::material::Bsdf;
    let dir = test_dir("tints")?;
    let conductor = |params: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"conductor\">{params}</bsdf></shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let fresnel_at = |text: &str, name: &str, cos: f32, lambda_nm: f32| -> TestResult<f32> {
        let path = write(&dir, name, text)?;
        let built = load(&path, &[], false)?.builder.build()?;
        let fresnel = built
            .materials()
            .iter()
            .find_map(|m| match m.bsdf {
                Bsdf::Conductor { fresnel, .. } => Some(fresnel),
                _ => None,
            })
            .ok_or("no conductor")?;
        Ok(built.material_tables().angular[fresnel.index()].eval(cos, lambda_nm, 0.0))
    };
    let tinted = conductor("<float name=\"specular_reflectance\" value=\"0.5\"/>");
    let copper = "<string name=\"material\" value=\"Cu\"/>";
    let tinted_copper = conductor(&format!(
        "{copper}<float name=\"specular_reflectance\" value=\"0.5\"/>"
    ));
    for cos in [1.0f32, 0.5, 0.1] {
        for lambda_nm in [450.0f32, 600.0] {
            let mirror = fresnel_at(&tinted, "mirror.xml", cos, lambda_nm)?;
            assert!((mirror - 0.5).abs() < 1e-6, "{mirror}");
            let plain = fresnel_at(&conductor(copper), "cu.xml", cos, lambda_nm)?;
            let half = fresnel_at(&tinted_copper, "cu-half.xml", cos, lambda_nm)?;
            assert!((half - 0.5 * plain).abs() < 1e-6, "{half} vs {plain}");
        }
    }
    refused(
        "tint-texture",
        &conductor("<texture type=\"checkerboard\" name=\"specular_reflectance\"/>"),
        8,
        &["a textured specular_reflectance is not supported"],
    )?;
    Ok(())
}

/// A dielectric's `specular_reflectance` and `specular_transmittance`
/// become its [`SpecularTints`] (reflectances, as Mitsuba reads them; the
/// one not given is 1), on `dielectric`, `roughdielectric` and
/// `thindielectric`; none given, none built; a textured one is refused.
#[test]
fn dielectric_tints_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, SpecularTints};
    let dir = test_dir("dielectric-tints")?;
    let with = |plugin: &str, params: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"{plugin}\">{params}</bsdf></shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    // The tints' values at 550 nm, or `None` without tints.
    let tints_of = |plugin: &str, params: &str| -> TestResult<Option<(f32, f32)>> {
        let path = write(&dir, &format!("{plugin}.xml"), &with(plugin, params))?;
        let built = load(&path, &[], false)?.builder.build()?;
        let tints = built
            .materials()
            .iter()
            .find_map(|m| match m.bsdf {
                Bsdf::Dielectric { tints, .. } | Bsdf::ThinDielectric { tints, .. } => Some(tints),
                _ => None,
            })
            .ok_or("no dielectric")?;
        let value = |id: simd_tracer::ids::SpectrumId| built.spectra()[id.index()].value(550.0);
        Ok(tints.map(
            |SpecularTints {
                 reflectance,
                 transmittance,
             }| { (value(reflectance), value(transmittance)) },
        ))
    };
    for plugin in ["dielectric", "roughdielectric", "thindielectric"] {
        assert_eq!(tints_of(plugin, "")?, None, "{plugin}");
        assert_eq!(
            tints_of(
                plugin,
                "<float name=\"specular_transmittance\" value=\"0.25\"/>"
            )?,
            Some((1.0, 0.25)),
            "{plugin}"
        );
        assert_eq!(
            tints_of(
                plugin,
                "<spectrum name=\"specular_reflectance\" value=\"0.5\"/>"
            )?,
            Some((0.5, 1.0)),
            "{plugin}"
        );
    }
    refused(
        "dielectric-tint-texture",
        &scene(
            "    <shape type=\"rectangle\"><bsdf type=\"dielectric\"><texture type=\"checkerboard\" name=\"specular_transmittance\"/></bsdf></shape>",
        ),
        8,
        &["a textured specular_transmittance is not supported"],
    )?;
    Ok(())
}

/// `twosided` with two nested BSDFs puts the first on the front face and
/// the second on the back (one BSDF, or the same one twice, is that BSDF
/// on both faces); three nested BSDFs, or a transmitting one, are refused.
/// `null` is a mask of opacity 0.
#[test]
fn twosided_faces_and_null_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction};
    let dir = test_dir("faces")?;
    let red = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.1, 0.1\"/></bsdf>";
    let metal = "<bsdf type=\"conductor\"/>";
    let two_sided = |nested: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"twosided\">{nested}</bsdf></shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let bsdf_of = |text: &str, name: &str| -> TestResult<Bsdf> {
        let path = write(&dir, name, text)?;
        let built = load(&path, &[], false)?.builder.build()?;
        let material = built.materials().first().ok_or("no material")?;
        Ok(material.bsdf.clone())
    };
    let Bsdf::Faces(faces) = bsdf_of(&two_sided(&format!("{red}{metal}")), "two.xml")? else {
        return Err("two BSDFs are not two faces".into());
    };
    assert!(matches!(faces[0], Bsdf::Lambert { .. }), "{:?}", faces[0]);
    assert!(matches!(faces[1], Bsdf::Conductor { .. }), "{:?}", faces[1]);
    let one = bsdf_of(&two_sided(red), "one.xml")?;
    assert!(matches!(one, Bsdf::Lambert { .. }), "{one:?}");
    let same = scene(
        "    <bsdf type=\"diffuse\" id=\"d\"/>\n    <shape type=\"rectangle\"><bsdf type=\"twosided\"><ref id=\"d\"/><ref id=\"d\"/></bsdf></shape>\n    <emitter type=\"constant\"/>",
    );
    assert!(matches!(bsdf_of(&same, "same.xml")?, Bsdf::Lambert { .. }));
    refused(
        "twosided-three",
        &two_sided(&format!("{red}{red}{metal}")),
        8,
        &["needs one or two nested BSDFs"],
    )?;
    refused(
        "twosided-glass",
        &two_sided(&format!("{red}<bsdf type=\"dielectric\"/>")),
        8,
        &["only BSDFs without transmission can be nested"],
    )?;
    let null = scene(
        "    <shape type=\"rectangle\"><bsdf type=\"null\"/></shape>\n    <shape type=\"sphere\"/>\n    <emitter type=\"constant\"/>",
    );
    let Bsdf::Mask(mask) = bsdf_of(&null, "null.xml")? else {
        return Err("null is not a mask".into());
    };
    assert_eq!(mask.opacity, Fraction::Constant(0.0));
    Ok(())
}

/// `blendbsdf`: a required `weight` (a number, clamped as Mitsuba clamps
/// it, or a bitmap) of the second of two nested BSDFs; refused without a
/// weight, with other than two BSDFs, or with a one-sided and a two-sided
/// BSDF (fspec's materials have one sidedness).
#[test]
fn blends_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction};
    let dir = test_dir("blends")?;
    let blend = |params: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"blendbsdf\">{params}</bsdf></shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let diffuse = "<bsdf type=\"diffuse\"/>";
    let metal = "<bsdf type=\"roughconductor\"/>";
    let weight = "<float name=\"weight\" value=\"0.25\"/>";
    let path = write(
        &dir,
        "blend.xml",
        &blend(&format!("{weight}{diffuse}{metal}")),
    )?;
    let built = load(&path, &[], false)?.builder.build()?;
    let material = built.materials().first().ok_or("no material")?;
    let Bsdf::Blend(b) = &material.bsdf else {
        return Err(format!("not a blend: {:?}", material.bsdf).into());
    };
    assert_eq!(b.weight, Fraction::Constant(0.25));
    assert!(matches!(b.bsdfs[0], Bsdf::Lambert { .. }));
    assert!(matches!(b.bsdfs[1], Bsdf::Conductor { .. }));
    assert!(material.front_only(), "two one-sided BSDFs blend into one");
    refused(
        "blend-no-weight",
        &blend(&format!("{diffuse}{metal}")),
        8,
        &["needs `weight`"],
    )?;
    refused(
        "blend-one",
        &blend(&format!("{weight}{diffuse}")),
        8,
        &["needs two nested BSDFs"],
    )?;
    refused(
        "blend-sides",
        &blend(&format!(
            "{weight}{diffuse}<bsdf type=\"twosided\">{metal}</bsdf>"
        )),
        8,
        &["a one-sided and a two-sided BSDF cannot be blended"],
    )?;
    // A dielectric scatters from both faces, a diffuse BSDF from one.
    refused(
        "blend-glass",
        &blend(&format!("{weight}{diffuse}<bsdf type=\"dielectric\"/>")),
        8,
        &["a one-sided and a two-sided BSDF cannot be blended"],
    )?;
    Ok(())
}

/// The principled BSDF of a scene's one material.
fn principled_of(
    built: &simd_tracer::scene::Scene,
) -> TestResult<simd_tracer::shading::material::Principled> {
    use simd_tracer::shading::material::Bsdf;
    built
        .materials()
        .iter()
        .find_map(|m| match &m.bsdf {
            Bsdf::Principled(p) => Some((**p).clone()),
            _ => None,
        })
        .ok_or_else(|| "no principled BSDF".into())
}

/// `principled`: Mitsuba's defaults and its `specular` → `η` map, the
/// stand-ins for an index of 1 with transmission, `√ρ` of the base colour
/// where it transmits, sides, textured fractions, and one line for each
/// refused combination.
#[test]
fn principled_follows_mitsuba() -> TestResult {
    use simd_tracer::shading::material::Fraction;
    let dir = test_dir("principled")?;
    let on_rectangle = |bsdf: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\">{bsdf}</shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let principled = |params: &str| format!("<bsdf type=\"principled\">{params}</bsdf>");
    let load_one =
        |name: &str, params: &str| -> TestResult<(simd_tracer::scene::Scene, Vec<String>)> {
            let path = write(&dir, name, &on_rectangle(&principled(params)))?;
            let loaded = load(&path, &[], false)?;
            Ok((loaded.builder.build()?, loaded.warnings))
        };
    // Defaults: specular 0.5 is η = 1.5; roughness 0.5; base 0.5; opaque,
    // so only the front face scatters.
    let (built, warnings) = load_one("defaults.xml", "")?;
    assert!(warnings.is_empty(), "{warnings:?}");
    let p = principled_of(&built)?;
    assert!((p.eta - 1.5).abs() < 1e-6, "{}", p.eta);
    assert_eq!(p.roughness, Fraction::Constant(0.5));
    assert_eq!(p.spec_trans, Fraction::Constant(0.0));
    assert!(p.base_color_sqrt.is_none());
    assert!(built.materials().iter().all(|m| m.front_only()));
    // Transmission: `eta` 1 becomes 1.001, `√ρ` is tabulated, both faces
    // scatter.
    let (built, _) = load_one(
        "glass.xml",
        "<rgb name=\"base_color\" value=\"1, 1, 1\"/><float name=\"spec_trans\" value=\"1\"/><float name=\"eta\" value=\"1\"/>",
    )?;
    let p = principled_of(&built)?;
    assert!((p.eta - 1.001).abs() < 1e-6, "{}", p.eta);
    assert!(
        (p.base_luminance - 1.0).abs() < 0.01,
        "{}",
        p.base_luminance
    );
    assert!(built.materials().iter().all(|m| !m.front_only()));
    let tables = built.material_tables();
    let base = match p.base_color {
        simd_tracer::shading::material::Albedo::Spectrum(id) => &tables.spectra[id.index()],
        _ => return Err("base colour not a spectrum".into()),
    };
    let root = &tables.spectra[p.base_color_sqrt.ok_or("no √ρ")?.index()];
    for lambda_nm in [420.0f32, 550.0, 680.0] {
        let expected = base.value(lambda_nm).sqrt();
        assert!(
            (root.value(lambda_nm) - expected).abs() < 1e-3,
            "{lambda_nm} nm"
        );
    }
    // `specular` 0 with transmission is 10⁻³ (η = 2/(1 − √(8·10⁻⁵)) − 1).
    let (built, _) = load_one(
        "specular0.xml",
        "<float name=\"spec_trans\" value=\"0.5\"/><float name=\"specular\" value=\"0\"/>",
    )?;
    let expected = 2.0 / (1.0 - (0.08f64 * 1e-3).sqrt()) - 1.0;
    assert!((f64::from(principled_of(&built)?.eta) - expected).abs() < 1e-6);
    // A textured roughness and an anisotropic lobe, which needs the
    // surface's tangent.
    let grey = suite_texture("grey.png");
    let (built, warnings) = load_one(
        "textured.xml",
        &format!(
            "<texture type=\"bitmap\" name=\"roughness\"><string name=\"filename\" value=\"{grey}\"/></texture><float name=\"anisotropic\" value=\"0.5\"/>"
        ),
    )?;
    let p = principled_of(&built)?;
    assert!(matches!(p.roughness, Fraction::Texture(_)));
    assert_eq!(p.anisotropic, Fraction::Constant(0.5));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(built.needs_tangent());
    // Refused, one line each.
    let colours = suite_texture("colours.png");
    let textured_base = format!(
        "<texture type=\"bitmap\" name=\"base_color\"><string name=\"filename\" value=\"{colours}\"/></texture>"
    );
    for (test, params, needle) in [
        (
            "principled-eta-and-specular",
            "<float name=\"eta\" value=\"1.4\"/><float name=\"specular\" value=\"0.5\"/>"
                .to_string(),
            "either `eta` or `specular`",
        ),
        (
            "principled-metallic-range",
            "<float name=\"metallic\" value=\"1.5\"/>".to_string(),
            "metallic 1.5: must be in [0, 1]",
        ),
        (
            "principled-eta-zero",
            "<float name=\"eta\" value=\"0\"/>".to_string(),
            "eta 0: must be a positive number",
        ),
        (
            "principled-specular-range",
            "<float name=\"specular\" value=\"13\"/>".to_string(),
            "specular 13: must be in [0, 12.5)",
        ),
        (
            "principled-sampling-rate",
            "<float name=\"clearcoat_sampling_rate\" value=\"-1\"/>".to_string(),
            "clearcoat_sampling_rate -1: must be a number >= 0",
        ),
        (
            "principled-textured-glass",
            format!("{textured_base}<float name=\"spec_trans\" value=\"1\"/>"),
            "transmission with a textured base colour",
        ),
        (
            "principled-textured-tint",
            format!("{textured_base}<float name=\"spec_tint\" value=\"0.3\"/>"),
            "tint with a textured base colour",
        ),
    ] {
        refused(test, &on_rectangle(&principled(&params)), 8, &[needle])?;
    }
    Ok(())
}

/// `alpha_u` and `alpha_v` of rough conductors and dielectrics are an
/// anisotropic lobe oriented by the surface's tangent (no warning); a
/// rough plastic, isotropic in Mitsuba, refuses them; one of the two
/// alone, or a negative one, is one line.
#[test]
fn anisotropic_roughness_follows_mitsuba() -> TestResult {
    use simd_tracer::shading::material::Bsdf;
    let dir = test_dir("anisotropic")?;
    let on_rectangle = |bsdf: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\">{bsdf}</shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    for plugin in ["roughconductor", "roughdielectric"] {
        let path = write(
            &dir,
            &format!("{plugin}.xml"),
            &on_rectangle(&format!(
                "<bsdf type=\"{plugin}\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alpha_u\" value=\"0.05\"/><float name=\"alpha_v\" value=\"0.3\"/></bsdf>"
            )),
        )?;
        let loaded = load(&path, &[], false)?;
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let built = loaded.builder.build()?;
        let model = built
            .materials()
            .iter()
            .find_map(|m| match &m.bsdf {
                Bsdf::Conductor { microfacet, .. } | Bsdf::Dielectric { microfacet, .. } => {
                    Some(*microfacet)
                }
                _ => None,
            })
            .ok_or("no microfacet BSDF")?;
        assert_eq!((model.alpha, model.alpha_y), (0.05, 0.3), "{plugin}");
        assert!(built.needs_tangent(), "{plugin}");
    }
    for (test, bsdf, needle) in [
        (
            "anisotropic-plastic",
            "<bsdf type=\"roughplastic\"><float name=\"alpha_u\" value=\"0.1\"/><float name=\"alpha_v\" value=\"0.2\"/></bsdf>",
            "a rough plastic is isotropic",
        ),
        (
            "anisotropic-one",
            "<bsdf type=\"roughconductor\"><float name=\"alpha_u\" value=\"0.1\"/></bsdf>",
            "give `alpha`, or both `alpha_u` and `alpha_v`",
        ),
        (
            "anisotropic-negative",
            "<bsdf type=\"roughconductor\"><float name=\"alpha_u\" value=\"0.1\"/><float name=\"alpha_v\" value=\"-0.2\"/></bsdf>",
            "alpha_v -0.2: must be >= 0",
        ),
    ] {
        refused(test, &on_rectangle(bsdf), 8, &[needle])?;
    }
    Ok(())
}

/// A textured `alpha` (or `alpha_u`/`alpha_v`) of `roughconductor` and
/// `roughdielectric` becomes a [`RoughnessMap`] around the BSDF, reading
/// the bitmap as a fraction; a number beside a textured `alpha_u` is the
/// constant `α_v`. `roughplastic` takes numbers only (as Mitsuba's), a
/// number outside [0, 1] beside a texture and `alpha` with `alpha_u` are
/// refused, each on one line.
#[test]
fn roughness_maps_follow_mitsuba() -> TestResult {
    use simd_tracer::shading::material::{Bsdf, Fraction, RoughnessMap};
    let dir = test_dir("roughness-maps")?;
    let grey = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/conformance/scenes/textures/grey.png")
        .display()
        .to_string();
    let bitmap = |name: &str| {
        format!(
            "<texture type=\"bitmap\" name=\"{name}\"><string name=\"filename\" value=\"{grey}\"/><boolean name=\"raw\" value=\"true\"/></texture>"
        )
    };
    let with = |plugin: &str, params: &str| {
        scene(&format!(
            "    <shape type=\"rectangle\"><bsdf type=\"{plugin}\">{params}</bsdf></shape>\n    <emitter type=\"constant\"/>"
        ))
    };
    let map_of = |plugin: &str, params: &str| -> TestResult<RoughnessMap> {
        let path = write(&dir, &format!("{plugin}.xml"), &with(plugin, params))?;
        let loaded = load(&path, &[], false)?;
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let built = loaded.builder.build()?;
        built
            .materials()
            .iter()
            .find_map(|m| match &m.bsdf {
                Bsdf::RoughnessMap(map) => Some((**map).clone()),
                _ => None,
            })
            .ok_or_else(|| format!("{plugin}: no roughness map").into())
    };
    for plugin in ["roughconductor", "roughdielectric"] {
        let map = map_of(plugin, &bitmap("alpha"))?;
        assert!(matches!(map.alpha_u, Fraction::Texture(_)), "{plugin}");
        assert_eq!(map.alpha_u, map.alpha_v, "{plugin}");
        let nested_fits = matches!(
            (plugin, &map.nested),
            ("roughconductor", Bsdf::Conductor { .. })
                | ("roughdielectric", Bsdf::Dielectric { .. })
        );
        assert!(nested_fits, "{plugin}: {:?}", map.nested);
        let anisotropic = map_of(
            plugin,
            &format!(
                "{}<float name=\"alpha_v\" value=\"0.05\"/>",
                bitmap("alpha_u")
            ),
        )?;
        assert!(matches!(anisotropic.alpha_u, Fraction::Texture(_)));
        assert_eq!(anisotropic.alpha_v, Fraction::Constant(0.05));
        assert!(anisotropic.is_anisotropic());
    }
    // Without textures there is no map.
    let path = write(
        &dir,
        "plain.xml",
        &with("roughconductor", "<float name=\"alpha\" value=\"0.2\"/>"),
    )?;
    let built = load(&path, &[], false)?.builder.build()?;
    assert!(
        built
            .materials()
            .iter()
            .all(|m| !matches!(m.bsdf, Bsdf::RoughnessMap(_)))
    );
    for (name, plugin, params, needle) in [
        (
            "roughplastic-map",
            "roughplastic",
            bitmap("alpha"),
            "a textured alpha is not supported on a rough plastic",
        ),
        (
            "alpha-and-alpha-u",
            "roughconductor",
            format!("{}<float name=\"alpha_u\" value=\"0.1\"/>", bitmap("alpha")),
            "give `alpha`, or both `alpha_u` and `alpha_v`",
        ),
        (
            "alpha-v-range",
            "roughconductor",
            format!(
                "{}<float name=\"alpha_v\" value=\"1.5\"/>",
                bitmap("alpha_u")
            ),
            "alpha_v 1.5: must be in [0, 1] beside a textured roughness",
        ),
    ] {
        refused(name, &with(plugin, &params), 8, &[needle])?;
    }
    Ok(())
}

/// A `checkerboard` read as a fraction (here a roughness) follows
/// Mitsuba's `eval_1`, which puts `color0` where exactly one coordinate's
/// fractional part is above ½, the opposite of its `eval` for colours:
/// looked up at points of each kind, the roughness texture reads `color1`
/// where a reflectance checkerboard of the same colours reads `color0`
/// (the negative control of the orientation), and it repeats.
#[test]
fn checkerboard_fractions_follow_mitsubas_eval_1() -> TestResult {
    let dir = test_dir("checkerboard-fractions")?;
    let checker = |name: &str| {
        format!(
            "<texture type=\"checkerboard\" name=\"{name}\"><float name=\"color0\" value=\"0.05\"/><float name=\"color1\" value=\"0.3\"/><transform name=\"to_uv\"><scale x=\"2\" y=\"2\"/></transform></texture>"
        )
    };
    let body = format!(
        "    <shape type=\"rectangle\"><bsdf type=\"roughconductor\">{}</bsdf></shape>\n    <shape type=\"sphere\"><bsdf type=\"diffuse\">{}</bsdf></shape>\n    <emitter type=\"constant\"/>",
        checker("alpha"),
        checker("reflectance")
    );
    let path = write(&dir, "checker.xml", &scene(&body))?;
    let loaded = load(&path, &[], false)?;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let built = loaded.builder.build()?;
    let [fraction, albedo] = [0, 1].map(|k| &built.textures()[k]);
    // Mitsuba's (u, v), the point's `to_uv` image (scale 2), eval_1's value.
    for (u, v, expected) in [
        (0.1, 0.1, 0.3),   // (0.2, 0.2): neither above ½
        (0.35, 0.1, 0.05), // (0.7, 0.2): one
        (0.1, 0.35, 0.05), // (0.2, 0.7): the other
        (0.35, 0.35, 0.3), // (0.7, 0.7): both
        (0.6, 0.1, 0.3),   // (1.2, 0.2): repeated
    ] {
        let got = fraction.scalar_at(u, v);
        assert!((got - expected).abs() < 1e-6, "({u}, {v}): {got}");
        // The reflectance checkerboard reads the other colour there.
        let colour = albedo.value_at(u, v, 550.0);
        let other = if expected == 0.3 { 0.05 } else { 0.3 };
        assert!((colour - other).abs() < 0.01, "({u}, {v}): {colour}");
    }
    // `rawconstant`: the value as it is, a fraction or a normal map's vector.
    let raw = scene(
        "    <shape type=\"rectangle\"><bsdf type=\"normalmap\"><texture name=\"normalmap\" type=\"rawconstant\"><vector name=\"value\" value=\"0.5, 0.25, 1\"/></texture><bsdf type=\"roughconductor\"><texture name=\"alpha\" type=\"rawconstant\"><float name=\"value\" value=\"0.2\"/></texture></bsdf></bsdf></shape>\n    <emitter type=\"constant\"/>",
    );
    let path = write(&dir, "raw.xml", &raw)?;
    let built = load(&path, &[], false)?.builder.build()?;
    let values: Vec<_> = built
        .textures()
        .iter()
        .map(|t| (t.scalar_at(0.3, 0.7), t.vector_at(0.3, 0.7)))
        .collect();
    let near = |a: f32, b: f32| (a - b).abs() < 1e-6;
    assert!(
        values.iter().any(|&(s, v)| near(s, 0.2) && v.is_none()),
        "{values:?}"
    );
    assert!(
        values
            .iter()
            .any(|(_, v)| v
                .is_some_and(|v| v.iter().zip([0.5, 0.25, 1.0]).all(|(&a, b)| near(a, b)))),
        "{values:?}"
    );
    refused(
        "rawconstant-vector-alpha",
        &scene(
            "    <shape type=\"rectangle\"><bsdf type=\"roughconductor\"><texture name=\"alpha\" type=\"rawconstant\"><vector name=\"value\" value=\"1, 2, 3\"/></texture></bsdf></shape>",
        ),
        8,
        &["expected a float"],
    )?;
    refused(
        "checkerboard-bump",
        &scene(
            "    <shape type=\"rectangle\"><bsdf type=\"bumpmap\"><texture type=\"checkerboard\"/><bsdf type=\"diffuse\"/></bsdf></shape>",
        ),
        8,
        &["is not supported as a bump map (bitmap, rawconstant)"],
    )?;
    Ok(())
}

/// Mitsuba's own test and documentation scenes wrap their integrator in
/// `moment` or `aov`, reference a scene-level sampler from the sensor and
/// give a plastic's `specular_reflectance` as a grey `<rgb>`: each loads as
/// the integrator, sampler and number it names, with a warning for the
/// channels that are not written; a coloured `<rgb>` and a wrapper without
/// a nested integrator are refused.
#[test]
fn wrapped_integrators_and_referenced_samplers_load() -> TestResult {
    let dir = test_dir("wrapped-integrators")?;
    let file = |integrator: &str, extra: &str| {
        format!(
            r#"<scene version="3.0.0">
    {integrator}
    <sampler type="independent" id="my_sampler"><integer name="sample_count" value="7"/></sampler>
    <sensor type="perspective">
        <ref id="my_sampler"/>
        <film type="hdrfilm" id="film"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <shape type="rectangle"><bsdf type="roughplastic"><rgb name="specular_reflectance" value="{extra}"/></bsdf></shape>
    <emitter type="constant"/>
</scene>
"#
        )
    };
    for (name, integrator, warning) in [
        (
            "moment",
            "<integrator type=\"moment\"><integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator></integrator>",
            Some("the second-moment channels are not written"),
        ),
        (
            "aov",
            "<integrator type=\"aov\"><string name=\"aovs\" value=\"dd.y:depth\"/><integrator type=\"path\" name=\"image\"><integer name=\"max_depth\" value=\"3\"/></integrator></integrator>",
            Some("the AOV channels are not written"),
        ),
        (
            "ptracer",
            "<integrator type=\"ptracer\"><integer name=\"max_depth\" value=\"3\"/></integrator>",
            Some("integrator \"ptracer\" renders as \"path\""),
        ),
        (
            "path",
            "<integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator>",
            None,
        ),
    ] {
        let path = write(&dir, &format!("{name}.xml"), &file(integrator, "0.5"))?;
        let loaded = load(&path, &[], false)?;
        let render = &loaded.render;
        assert_eq!(render.max_depth, Some(3), "{name}");
        assert_eq!(render.spp, Some(7), "{name}: the referenced sampler");
        assert_eq!(
            loaded
                .warnings
                .iter()
                .any(|w| warning.is_some_and(|n| w.contains(n))),
            warning.is_some(),
            "{name}: {:?}",
            loaded.warnings
        );
        assert_eq!(
            loaded.warnings.len(),
            usize::from(warning.is_some()),
            "{name}"
        );
    }
    refused(
        "coloured-specular",
        &file("<integrator type=\"path\"/>", "0.5, 0.4, 0.3"),
        8,
        &["must be a number or a grey <rgb> here"],
    )?;
    refused(
        "empty-moment",
        &file("<integrator type=\"moment\"/>", "1"),
        2,
        &["needs exactly one nested <integrator> to render (it has 0)"],
    )?;
    Ok(())
}

/// A conductor whose `eta` and `k` samples end inside the spectral range
/// (Mitsuba's documentation's gold, 300 to 800 nm: zero beyond, where the
/// index is 0) loads, and reflects everything there, the Fresnel limit
/// and Mitsuba's value; inside the samples it is gold. It was refused as
/// "NaN" before.
#[test]
fn a_conductor_past_its_samples_reflects_everything() -> TestResult {
    use simd_tracer::shading::material::Bsdf;
    let dir = test_dir("conductor-past-samples")?;
    let body = r#"    <shape type="rectangle"><bsdf type="conductor">
        <spectrum name="eta" value="300:1.8, 400:1.65, 500:0.9, 600:0.2, 700:0.16, 800:0.18"/>
        <spectrum name="k" value="300:1.92, 400:1.95, 500:1.95, 600:2.97, 700:3.8, 800:5.12"/>
    </bsdf></shape>
    <emitter type="constant"/>"#;
    let path = write(&dir, "gold.xml", &scene(body))?;
    let built = load(&path, &[], false)?.builder.build()?;
    let conductor = built
        .materials()
        .iter()
        .find(|m| matches!(m.bsdf, Bsdf::Conductor { .. }))
        .ok_or("no conductor")?;
    let Bsdf::Conductor { fresnel, .. } = conductor.bsdf else {
        return Err("no conductor".into());
    };
    let function = built.angular()[fresnel.index()].function();
    for cos in [0.2, 0.6, 1.0] {
        let past = function.eval(cos, 820.0, None);
        assert_eq!(past, 1.0, "820 nm, cos {cos}");
        let inside = function.eval(cos, 650.0, None);
        assert!(inside > 0.5 && inside < 0.99, "650 nm, cos {cos}: {inside}");
    }
    Ok(())
}

/// A `sphere` with an `area` emitter is one spherical light, sampled in
/// its cone, at its centre and radius after `to_world`; stretched into an
/// ellipsoid, or facing inwards (`flip_normals`), it stays emissive
/// triangles.
#[test]
fn emitting_spheres_are_spherical_lights() -> TestResult {
    let dir = test_dir("emitting_spheres")?;
    let lamp = |transform: &str, flip: bool| {
        format!(
            r#"    <shape type="sphere">
        <point name="center" x="0.5" y="0" z="0"/><float name="radius" value="0.25"/>
        <transform name="to_world">{transform}</transform>
        <boolean name="flip_normals" value="{flip}"/>
        <emitter type="area"><rgb name="radiance" value="5"/></emitter>
    </shape>
    <shape type="rectangle"><bsdf type="diffuse"/></shape>"#
        )
    };
    let similar = r#"<scale value="2"/><rotate y="1" angle="30"/><translate x="1" y="2" z="-3"/>"#;
    let path = write(&dir, "sphere.xml", &scene(&lamp(similar, false)))?;
    let built = load(&path, &[], false)?.builder.build()?;
    let spheres = built.light_sampler().spheres();
    assert_eq!(spheres.len(), 1);
    let center = glam::Vec3::new(1.0 + 3f32.sqrt() / 2.0, 2.0, -3.0 - 0.5);
    assert!(
        (spheres[0].center - center).length() < 1e-5,
        "{}",
        spheres[0].center
    );
    assert!((spheres[0].radius - 0.5).abs() < 1e-6);
    let stretched = r#"<scale x="2" y="1" z="1"/>"#;
    for (transform, flip) in [(stretched, false), (similar, true)] {
        let path = write(&dir, "other.xml", &scene(&lamp(transform, flip)))?;
        let built = load(&path, &[], false)?.builder.build()?;
        assert!(built.light_sampler().spheres().is_empty());
        assert!(!built.lights().is_empty(), "{transform} {flip}");
    }
    Ok(())
}
