//! `--sampler` and `[render] sampler`: the measured default (Sobol, but
//! independent for control variates), the scene file's key, and bad names
//! refused with one error line.

use std::path::Path;
use std::process::Command;
use test_support::ScratchDir;

use fspec_cli::scene_file::load_scene_file;
use simd_tracer::sampling::sampler::SamplerKind;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn out_dir(name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new("fspec-sampler-test", name)?)
}

fn render_bytes(dir: &Path, name: &str, scene: &str, args: &[&str]) -> TestResult<Vec<u8>> {
    let path = dir.join(name);
    let output = fspec()
        .args(["render", scene, "--width", "8", "--height", "8", "-q"])
        .args(["--spp", "4", "--seed", "3"])
        .args(args)
        .arg("--out")
        .arg(&path)
        .output()?;
    assert!(output.status.success(), "{output:?}");
    Ok(std::fs::read(path)?)
}

/// The default is Sobol (the explicit flag's image); independent is
/// another image (the negative control); control variates default to
/// independent.
#[test]
fn render_defaults_to_the_measured_best_sampler() -> TestResult {
    let dir = out_dir("defaults")?;
    let default = render_bytes(&dir, "default.exr", "cornell", &[])?;
    let sobol = render_bytes(&dir, "sobol.exr", "cornell", &["--sampler", "sobol"])?;
    let independent = render_bytes(&dir, "ind.exr", "cornell", &["--sampler", "independent"])?;
    assert_eq!(default, sobol);
    assert_ne!(default, independent);
    let cv = ["--transport", "cv", "--wavelengths", "8", "--coeffs", "4"];
    let cv_default = render_bytes(&dir, "cv.exr", "cornell", &cv)?;
    let cv_independent = render_bytes(
        &dir,
        "cv-ind.exr",
        "cornell",
        &[&cv[..], &["--sampler", "independent"]].concat(),
    )?;
    assert_eq!(cv_default, cv_independent);
    Ok(())
}

const SCENE: &str = r#"
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

/// `[render] sampler` is read, used by `fspec render` unless the flag
/// says otherwise, and a name that is none is one error line at its key.
#[test]
fn scene_files_name_the_sampler() -> TestResult {
    let dir = out_dir("scene")?;
    let independent = dir.join("independent.toml");
    std::fs::write(
        &independent,
        format!("{SCENE}\n[render]\nsampler = \"independent\"\n"),
    )?;
    let loaded = load_scene_file(&independent)?;
    assert_eq!(loaded.render.sampler, Some(SamplerKind::Independent));
    let scene = independent.to_string_lossy().into_owned();
    let from_file = render_bytes(&dir, "file.exr", &scene, &[])?;
    let flag = render_bytes(&dir, "flag.exr", &scene, &["--sampler", "independent"])?;
    let sobol = render_bytes(&dir, "sobol.exr", &scene, &["--sampler", "sobol"])?;
    assert_eq!(from_file, flag);
    assert_ne!(from_file, sobol);

    let bad = dir.join("bad.toml");
    std::fs::write(&bad, format!("{SCENE}\n[render]\nsampler = \"halton\"\n"))?;
    let output = fspec()
        .args(["render", &bad.to_string_lossy(), "-q", "--out"])
        .arg(dir.join("bad.png"))
        .output()?;
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8(output.stderr)?;
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("sampler `halton`: use independent or sobol"),
        "{stderr}"
    );
    let output = fspec()
        .args(["render", "cornell", "--sampler", "halton", "-q"])
        .output()?;
    assert_eq!(output.status.code(), Some(2));
    Ok(())
}
