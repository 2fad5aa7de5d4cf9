//! `fspec render` and `fspec scenes` end to end: the binary renders every
//! built-in scene in every transport without NaN, writes PNG / EXR /
//! spectral EXR / coefficient EXR files that read back with the right size,
//! channels and attributes, and refuses each class of bad input with one
//! clear message, exit code 2, no panic and no file left behind.

mod common;

use assert_cmd::Command;
use common::{TestResult, entries};
use exr::prelude::{
    AnyChannels, AttributeValue, FlatSamples, Image, Layer, ReadChannels, ReadLayers, Text, read,
};
use std::fs;
use std::path::Path;
use test_support::ScratchDir;

type ExrImage = Image<Layer<AnyChannels<FlatSamples>>>;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn test_dir(name: &str) -> TestResult<ScratchDir> {
    common::test_dir("render-cli", name)
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

fn exr_size(image: &ExrImage) -> (usize, usize) {
    let size = image.layer_data.size;
    (size.0, size.1)
}

/// Decodes a PNG: (width, height, colour type, bit depth).
fn png_info(path: &Path) -> TestResult<(u32, u32, png::ColorType, png::BitDepth)> {
    let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(path)?));
    let mut reader = decoder.read_info()?;
    let mut buffer = vec![0; reader.output_buffer_size().ok_or("PNG too large")?];
    let info = reader.next_frame(&mut buffer)?;
    Ok((info.width, info.height, info.color_type, info.bit_depth))
}

/// Runs `fspec render` in `dir` with `args`; returns stdout and stderr.
fn render_ok(dir: &Path, args: &[&str]) -> TestResult<(String, String)> {
    let output = fspec().current_dir(dir).arg("render").args(args).output()?;
    let stdout = String::from_utf8(output.stdout)?;
    let stderr = String::from_utf8(output.stderr)?;
    if !output.status.success() {
        return Err(format!("fspec render {args:?} failed: {stderr}").into());
    }
    Ok((stdout, stderr))
}

/// Runs `fspec` with `args` in `dir`, expects exit code 2 with one
/// `fspec: error:` line containing every string of `needles`, no panic, and
/// no new file in `dir`. Returns the message.
fn refused(dir: &Path, args: &[&str], needles: &[&str]) -> TestResult<String> {
    let before = entries(dir)?;
    let output = fspec().current_dir(dir).args(args).output()?;
    let stderr = String::from_utf8(output.stderr)?;
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("fspec: error:"))
        .collect();
    assert_eq!(errors.len(), 1, "{args:?}: {stderr}");
    for needle in needles {
        assert!(
            errors[0].contains(needle),
            "{args:?}: {needle:?} in {stderr}"
        );
    }
    assert_eq!(entries(dir)?, before, "{args:?} left files behind");
    Ok(errors[0].to_string())
}

/// Every value of every channel finite (linear sRGB may be negative for
/// colours outside the sRGB gamut).
fn assert_clean(image: &ExrImage, what: &str) -> TestResult {
    for name in channel_names(image) {
        let values = channel(image, &name)?;
        let bad = values.iter().filter(|v| !v.is_finite()).count();
        assert_eq!(bad, 0, "{what}: {bad} bad values in channel {name}");
    }
    Ok(())
}

fn builtin_names() -> TestResult<Vec<String>> {
    let output = fspec().arg("scenes").output()?;
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout)?;
    Ok(text
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect())
}

#[test]
fn scenes_lists_every_builtin_with_a_description() -> TestResult {
    let output = fspec().arg("scenes").output()?;
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout)?;
    for name in [
        "cornell",
        "lamps",
        "laser",
        "materials",
        "colorchecker",
        "fluorescence",
        "prism",
    ] {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .ok_or_else(|| format!("{name} missing from {text}"))?;
        assert!(
            line.split_whitespace().count() > 3,
            "no description: {line}"
        );
    }
    assert_eq!(builtin_names()?.len(), 7);
    Ok(())
}

#[test]
fn default_render_writes_png_and_exr_in_the_current_folder() -> TestResult {
    let dir = test_dir("default")?;
    let (stdout, _) = render_ok(&dir, &["--width", "40", "--height", "30", "--spp", "2"])?;
    assert!(stdout.contains("render.png"), "{stdout}");
    assert!(stdout.contains("render.exr"), "{stdout}");
    assert!(stdout.contains("samples/s"), "{stdout}");
    assert_eq!(entries(&dir)?, ["render.exr", "render.png"]);
    assert_eq!(
        png_info(&dir.join("render.png"))?,
        (40, 30, png::ColorType::Rgb, png::BitDepth::Eight)
    );
    let exr = read_exr(&dir.join("render.exr"))?;
    assert_eq!(exr_size(&exr), (40, 30));
    let mut names = channel_names(&exr);
    names.sort();
    assert_eq!(names, ["B", "G", "R"]);
    assert_clean(&exr, "default")?;
    // The Cornell box is lit: the image is not black.
    let mean_g = channel(&exr, "G")?.iter().sum::<f32>() / (40.0 * 30.0);
    assert!(mean_g > 0.01, "mean G {mean_g}");
    Ok(())
}

#[test]
fn every_builtin_scene_renders_clean_in_every_transport() -> TestResult {
    let dir = test_dir("builtins")?;
    let transports: [&[&str]; 6] = [
        &["--transport", "fourier", "--coeffs", "8"],
        &[
            "--transport",
            "fourier",
            "--buffer",
            "rgb",
            "--to-color",
            "mese",
        ],
        &["--transport", "sampled", "--wavelengths", "4"],
        &[
            "--transport",
            "sampled",
            "--sampling",
            "stratified",
            "--wavelengths",
            "8",
        ],
        &["--transport", "cv"],
        &["--transport", "sampled", "--sampling", "lights"],
    ];
    for scene in builtin_names()? {
        for (t, transport) in transports.iter().enumerate() {
            let out = dir.join(format!("{scene}-{t}.exr"));
            let out_arg = out.to_string_lossy().into_owned();
            let mut args = vec![scene.as_str(), "--width", "24", "--height", "16"];
            args.extend(["--spp", "2", "--out", &out_arg, "--exr-xyz"]);
            args.extend(transport.iter());
            let (stdout, _) = render_ok(&dir, &args)?;
            assert!(
                !stdout.contains("rejected"),
                "{scene} {transport:?}: {stdout}"
            );
            let exr = read_exr(&out)?;
            assert_eq!(exr_size(&exr), (24, 16));
            let mut names = channel_names(&exr);
            names.sort();
            assert_eq!(names, ["B", "G", "R", "X", "Y", "Z"]);
            assert_clean(&exr, &format!("{scene} {transport:?}"))?;
        }
    }
    Ok(())
}

#[test]
fn spectral_and_coefficient_exr_follow_their_layouts() -> TestResult {
    let dir = test_dir("spectral")?;
    let (stdout, stderr) = render_ok(
        &dir,
        &[
            "lamps",
            "--width",
            "16",
            "--height",
            "12",
            "--spp",
            "2",
            "--out",
            "lamps.png",
            "--spectral-exr",
            "lamps-spectral.exr",
            "--spectral-step-nm",
            "5",
            "--coefficients-exr",
            "lamps-coeffs.exr",
        ],
    )?;
    for file in ["lamps.png", "lamps-spectral.exr", "lamps-coeffs.exr"] {
        assert!(stdout.contains(file), "{file} in {stdout}");
    }
    let spectral = read_exr(&dir.join("lamps-spectral.exr"))?;
    assert_eq!(exr_size(&spectral), (16, 12));
    assert_eq!(text_attribute(&spectral, "spectralLayoutVersion")?, "1.0");
    assert_eq!(text_attribute(&spectral, "emissiveUnits")?, "W.m^-2.sr^-1");
    let names = channel_names(&spectral);
    let mut wavelengths: Vec<f64> = names
        .iter()
        .filter_map(|n| {
            let value = n.strip_prefix("S0.")?.strip_suffix("nm")?;
            value.replace(',', ".").parse().ok()
        })
        .collect();
    wavelengths.sort_by(f64::total_cmp);
    // 360, 365, …, 830 nm: 95 planes, plus the R, G, B preview.
    let expected: Vec<f64> = (0..=94).map(|i| 360.0 + 5.0 * f64::from(i)).collect();
    assert_eq!(wavelengths, expected);
    assert!(names.iter().any(|n| n == "S0.550,000000nm"), "{names:?}");
    assert_eq!(names.len(), expected.len() + 3);
    assert_clean(&spectral, "spectral")?;

    let coeffs = read_exr(&dir.join("lamps-coeffs.exr"))?;
    let mut names = channel_names(&coeffs);
    names.sort_by_key(|n| {
        n.trim_start_matches('F')
            .parse::<usize>()
            .unwrap_or(usize::MAX)
    });
    // N planes, N as `--coeffs auto` chose it and reported it.
    let note = "coefficients: N = ";
    let at = stderr.find(note).ok_or("no coefficient note")? + note.len();
    let n: usize = stderr[at..]
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .ok_or("no N")?
        .parse()?;
    let expected: Vec<String> = (0..n).map(|j| format!("F{j}")).collect();
    assert_eq!(names, expected);
    // The zeroth coefficient is the mean radiance over the range: never
    // negative, and positive somewhere in a lit scene.
    let f0 = channel(&coeffs, "F0")?;
    assert!(f0.iter().all(|v| v.is_finite() && *v >= 0.0));
    assert!(f0.iter().any(|v| *v > 0.0));
    Ok(())
}

#[test]
fn same_seed_gives_identical_files_with_one_and_two_threads() -> TestResult {
    let dir = test_dir("determinism")?;
    let common = ["materials", "--width", "20", "--height", "20", "--spp", "3"];
    for (name, threads) in [("a.exr", "1"), ("b.exr", "2"), ("c.exr", "2")] {
        let mut args = common.to_vec();
        args.extend(["--seed", "7", "--threads", threads, "--out", name]);
        render_ok(&dir, &args)?;
    }
    let a = fs::read(dir.join("a.exr"))?;
    assert_eq!(a, fs::read(dir.join("b.exr"))?);
    assert_eq!(a, fs::read(dir.join("c.exr"))?);
    let mut args = common.to_vec();
    args.extend(["--seed", "8", "--out", "d.exr"]);
    render_ok(&dir, &args)?;
    assert_ne!(a, fs::read(dir.join("d.exr"))?);
    Ok(())
}

/// The hybrid draws its split's wavelengths from the scene's lights
/// density unless `--sampling` says otherwise: the default's image is
/// `--sampling lights`'s byte for byte, and `--sampling hero`'s differs
/// (the comparison can fail).
#[test]
fn the_hybrid_draws_from_the_lights_by_default() -> TestResult {
    let dir = test_dir("hybrid-lights")?;
    let render = |sampling: &[&str], out: &str| -> TestResult<Vec<u8>> {
        let mut args = vec![
            "prism",
            "--transport",
            "hybrid",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "4",
            "--seed",
            "5",
            "--out",
            out,
        ];
        args.extend_from_slice(sampling);
        render_ok(&dir, &args)?;
        Ok(fs::read(dir.join(out))?)
    };
    let default = render(&[], "default.exr")?;
    assert_eq!(default, render(&["--sampling", "lights"], "lights.exr")?);
    assert_ne!(default, render(&["--sampling", "hero"], "hero.exr")?);
    Ok(())
}

/// `--transport hybrid` on a scene where no material disperses runs as
/// the Fourier transport with the hybrid's N (a line says so) and writes
/// the Fourier image byte for byte. Negative controls: on `prism` (SF11
/// glass) and for a partial film (whose identity records the transport) it
/// stays hybrid, and no line is printed.
#[test]
fn hybrid_without_dispersion_renders_as_fourier() -> TestResult {
    let dir = test_dir("hybrid-dispatch")?;
    let note = "no material of the scene disperses";
    let render = |scene: &str, transport: &[&str], out: &str| -> TestResult<String> {
        let mut args = vec![
            scene, "--width", "16", "--height", "16", "--spp", "2", "--seed", "3", "--out", out,
        ];
        args.extend_from_slice(transport);
        Ok(render_ok(&dir, &args)?.1)
    };
    // `--coeffs auto` (the default) gives the hybrid the Fourier
    // transport's N.
    let chosen = |stderr: &str| -> Option<String> {
        let at = stderr.find("coefficients: N = ")?;
        stderr[at..].split_whitespace().nth(3).map(str::to_owned)
    };
    let fourier = render("cornell", &[], "fourier.exr")?;
    assert!(!fourier.contains(note), "{fourier}");
    let hybrid = render("cornell", &["--transport", "hybrid"], "hybrid.exr")?;
    assert!(hybrid.contains(note), "{hybrid}");
    assert_eq!(chosen(&hybrid), chosen(&fourier), "{hybrid}");
    assert_eq!(
        fs::read(dir.join("fourier.exr"))?,
        fs::read(dir.join("hybrid.exr"))?
    );
    // N = 12 is not the Fourier default on this scene, so the images differ.
    let twelve = render(
        "cornell",
        &["--transport", "hybrid", "--coeffs", "12"],
        "12.exr",
    )?;
    assert!(twelve.contains(note), "{twelve}");
    assert_ne!(
        fs::read(dir.join("12.exr"))?,
        fs::read(dir.join("hybrid.exr"))?
    );
    let prism = render("prism", &["--transport", "hybrid"], "prism.exr")?;
    assert!(!prism.contains(note), "{prism}");
    let prism_fourier = render("prism", &[], "prism-fourier.exr")?;
    assert_eq!(chosen(&prism), chosen(&prism_fourier), "{prism}");
    assert_ne!(chosen(&prism).as_deref(), Some("12"), "{prism}");
    let one = render(
        "prism",
        &["--transport", "hybrid", "--wavelengths", "1"],
        "one.exr",
    )?;
    assert!(one.contains("with C = 1 takes N = 12"), "{one}");
    let part = render("cornell", &["--transport", "hybrid"], "part.fspart")?;
    assert!(!part.contains(note), "{part}");
    Ok(())
}

/// `--crop X,Y,W,H` writes W × H images whose pixels are the full
/// render's at the same seed, float for float; a window outside the film
/// and a malformed one are refused.
#[test]
fn crop_renders_the_window_of_the_full_image() -> TestResult {
    let dir = test_dir("crop")?;
    let common = [
        "materials",
        "--width",
        "30",
        "--height",
        "20",
        "--spp",
        "2",
        "--seed",
        "3",
    ];
    let mut full = common.to_vec();
    full.extend(["--out", "full.exr"]);
    render_ok(&dir, &full)?;
    let (x0, y0, w, h) = (7usize, 5usize, 13usize, 9usize);
    let mut crop = common.to_vec();
    crop.extend([
        "--crop", "7,5,13,9", "--out", "crop.exr", "--out", "crop.png",
    ]);
    render_ok(&dir, &crop)?;
    let (full, crop) = (
        read_exr(&dir.join("full.exr"))?,
        read_exr(&dir.join("crop.exr"))?,
    );
    assert_eq!(exr_size(&crop), (w, h));
    assert_eq!(png_info(&dir.join("crop.png"))?.0, w as u32);
    for name in ["R", "G", "B"] {
        let (f, c) = (channel(&full, name)?, channel(&crop, name)?);
        for y in 0..h {
            for x in 0..w {
                assert_eq!(
                    c[y * w + x].to_bits(),
                    f[(y0 + y) * 30 + x0 + x].to_bits(),
                    "{name} ({x}, {y})"
                );
            }
        }
    }
    refused(
        &dir,
        &[
            "render",
            "--width",
            "30",
            "--height",
            "20",
            "--crop",
            "20,0,11,4",
        ],
        &["--crop", "11×4 at (20, 0)", "30×20"],
    )?;
    refused(
        &dir,
        &[
            "render", "--width", "30", "--height", "20", "--crop", "0,0,0,4",
        ],
        &["--crop", "non-empty"],
    )?;
    let before = entries(&dir)?;
    let output = fspec()
        .current_dir(&dir)
        .args(["render", "--crop", "1,2,3"])
        .output()?;
    let stderr = String::from_utf8(output.stderr)?;
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("X,Y,W,H"), "{stderr}");
    assert_eq!(entries(&dir)?, before);
    Ok(())
}

#[test]
fn time_limit_stops_after_a_pass_and_writes_the_image() -> TestResult {
    let dir = test_dir("time-limit")?;
    let (stdout, _) = render_ok(
        &dir,
        &[
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "100000",
            "--time-limit",
            "0.2",
            "--out",
            "t.exr",
        ],
    )?;
    let passes: u32 = stdout
        .split_whitespace()
        .nth(1)
        .ok_or("no pass count")?
        .parse()?;
    assert!((1..100_000).contains(&passes), "{stdout}");
    assert_clean(&read_exr(&dir.join("t.exr"))?, "time limit")?;
    assert_eq!(entries(&dir)?, ["t.exr"]);
    Ok(())
}

#[test]
fn degenerate_triangles_are_skipped_with_a_warning() -> TestResult {
    let dir = test_dir("degenerate")?;
    // A lit quad, one zero-area triangle and one with a repeated vertex.
    fs::write(
        dir.join("mesh.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 5 5 5\nv 6 6 6\nv 7 7 7\n\
         f 1 2 3\nf 1 3 4\nf 5 6 7\nf 1 1 2\n",
    )?;
    let (_, stderr) = render_ok(
        &dir,
        &[
            "mesh.obj", "--width", "16", "--height", "16", "--spp", "2", "--out", "m.exr",
        ],
    )?;
    assert!(stderr.contains("degenerate"), "{stderr}");
    assert_clean(&read_exr(&dir.join("m.exr"))?, "degenerate")?;
    Ok(())
}

#[test]
fn missing_and_unreadable_files_are_refused() -> TestResult {
    let dir = test_dir("missing")?;
    refused(
        &dir,
        &["render", "no-such-scene.toml"],
        &["no-such-scene.toml"],
    )?;
    refused(&dir, &["render", "no-such-mesh.obj"], &["no-such-mesh.obj"])?;
    refused(&dir, &["render", "no-such-scene"], &["no-such-scene"])?;
    fs::create_dir(dir.join("folder.toml"))?;
    refused(&dir, &["render", "folder.toml"], &["folder.toml"])?;
    refused(
        &dir,
        &["render", "colorchecker", "--illuminant", "missing.csv"],
        &["missing.csv"],
    )?;
    Ok(())
}

#[test]
fn malformed_files_are_refused_naming_the_file() -> TestResult {
    let dir = test_dir("malformed")?;
    fs::write(dir.join("bad.toml"), "[camera\nfov = 40\n")?;
    refused(&dir, &["render", "bad.toml"], &["bad.toml:1:", "TOML"])?;
    fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")?;
    refused(&dir, &["render", "bad.obj"], &["bad.obj"])?;
    fs::write(
        dir.join("bad-mtl.obj"),
        "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    )?;
    fs::write(dir.join("bad.mtl"), "newmtl red\nKd 0.5 zero 0.5\n")?;
    refused(&dir, &["render", "bad-mtl.obj"], &["bad-mtl.obj"])?;
    fs::write(dir.join("empty.obj"), "# nothing\n")?;
    refused(&dir, &["render", "empty.obj"], &["empty.obj"])?;
    Ok(())
}

#[test]
fn bad_spectra_are_refused() -> TestResult {
    let dir = test_dir("spectra")?;
    let cases = [
        ("nan.csv", "400,1\n500,nan\n600,1\n"),
        ("negative.csv", "400,1\n500,-0.5\n600,1\n"),
        ("empty.csv", "# no rows\n"),
        ("unsorted.csv", "500,1\n400,1\n"),
        ("text.csv", "400,one\n"),
    ];
    for (name, text) in cases {
        fs::write(dir.join(name), text)?;
        refused(
            &dir,
            &["render", "colorchecker", "--illuminant", name],
            &[name],
        )?;
    }
    refused(
        &dir,
        &["render", "colorchecker", "--illuminant", "no-such-lamp"],
        &["no-such-lamp"],
    )?;
    Ok(())
}

#[test]
fn unknown_names_in_scene_files_are_refused() -> TestResult {
    let dir = test_dir("names")?;
    let camera = "[camera]\nposition = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_deg = 40\n";
    fs::write(
        dir.join("spectrum.toml"),
        format!(
            "{camera}\n[materials.lamp]\ntype = \"lambert\"\nalbedo = {{ constant = 0.5 }}\nemission = \"no-such-spectrum\"\n"
        ),
    )?;
    refused(
        &dir,
        &["render", "spectrum.toml"],
        &["spectrum.toml", "no-such-spectrum"],
    )?;
    Ok(())
}

#[test]
fn absurd_sizes_and_options_are_refused() -> TestResult {
    let dir = test_dir("sizes")?;
    let message = refused(
        &dir,
        &[
            "render", "--width", "32768", "--height", "32768", "--coeffs", "32",
        ],
        &["GiB"],
    )?;
    assert!(message.contains("32768"), "{message}");
    refused(&dir, &["render", "--width", "40000"], &["40000"])?;
    refused(&dir, &["render", "--spp", "0"], &["--spp"])?;
    refused(&dir, &["render", "--coeffs", "5"], &["--coeffs 5"])?;
    refused(
        &dir,
        &["render", "--transport", "sampled", "--wavelengths", "3"],
        &["--wavelengths 3"],
    )?;
    refused(&dir, &["render", "--max-depth", "0"], &["--max-depth"])?;
    refused(&dir, &["render", "--time-limit", "nan"], &["--time-limit"])?;
    refused(&dir, &["render", "--threads", "0"], &["--threads"])?;
    Ok(())
}

#[test]
fn unwritable_outputs_are_refused_and_leave_nothing() -> TestResult {
    let dir = test_dir("unwritable")?;
    let small = ["--width", "8", "--height", "8", "--spp", "1"];
    let mut args = vec!["render"];
    args.extend(small);
    args.extend(["--out", "missing-folder/out.png"]);
    refused(&dir, &args, &["missing-folder"])?;
    let mut args = vec!["render"];
    args.extend(small);
    args.extend(["--out", "image.jpg"]);
    refused(&dir, &args, &["image.jpg"])?;
    let mut args = vec!["render"];
    args.extend(small);
    args.extend(["--transport", "sampled", "--spectral-exr", "s.exr"]);
    refused(&dir, &args, &["--spectral-exr"])?;
    Ok(())
}

#[test]
fn ctrl_c_stops_after_the_pass_and_writes_the_image() -> TestResult {
    let dir = test_dir("ctrl-c")?;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_fspec"))
        .current_dir(&dir)
        .args(["render", "--width", "64", "--height", "64"])
        .args(["--spp", "1000000", "--out", "i.exr", "--out", "i.png"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()?;
    // Long enough for the handler to be installed and a pass to finish.
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()?;
    assert!(status.success());
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while child.try_wait()?.is_none() {
        if std::time::Instant::now() > deadline {
            child.kill()?;
            return Err("render did not stop after Ctrl-C".into());
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let output = child.wait_with_output()?;
    let stdout = String::from_utf8(output.stdout)?;
    let stderr = String::from_utf8(output.stderr)?;
    assert_eq!(output.status.code(), Some(130), "{stdout} {stderr}");
    assert!(stdout.contains("(interrupted)"), "{stdout}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert_eq!(entries(&dir)?, ["i.exr", "i.png"]);
    let exr = read_exr(&dir.join("i.exr"))?;
    assert_eq!(exr_size(&exr), (64, 64));
    assert_clean(&exr, "interrupted")?;
    assert_eq!(png_info(&dir.join("i.png"))?.0, 64);
    Ok(())
}
