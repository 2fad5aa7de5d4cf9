//! Frames split across processes, end to end through the binary:
//! `fspec render --passes A..B` / `--crop` / `--out part.fspart`, `fspec
//! merge` and `fspec render --resume`. A frame split into 4 pass ranges, 4
//! crops, or both, and merged, equals the single render (the EXR bytes, and
//! the merged partial film's sums within the `f64` bound of
//! `simd_tracer::render::FilmState`); the merge does not depend on the
//! order of the files; a stopped render resumed equals the uninterrupted
//! one bit for bit; `tools/render_part.sh`, the job-array recipe of
//! docs/farm.md, run as 4 concurrent processes and merged gives the same
//! frame. Parts that do not belong together (seed, transport, scene, film),
//! overlap, leave gaps, or are corrupt are refused with one line and exit
//! code 2.

mod common;

use assert_cmd::Command;
use common::{TestResult, entries};
use fspec_cli::partial_file::PartialFilm;
use std::fs;
use std::path::Path;
use test_support::ScratchDir;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn test_dir(name: &str) -> TestResult<ScratchDir> {
    common::test_dir("split-merge", name)
}

/// The frame of every test: odd sides (tiles and packets cut at the far
/// edges), the `materials` scene (packets mix Lambertian and other BSDFs).
const FRAME: [&str; 6] = ["materials", "--width", "37", "--height", "29", "--seed"];
const SEED: &str = "5";
const PASSES: u32 = 12;

/// `fspec render` of the frame with `extra` options; panics with stderr on
/// failure.
fn render(dir: &Path, extra: &[&str]) -> TestResult {
    let output = render_cmd(dir)
        .args(["--threads", "2", "--quiet"])
        .args(extra)
        .output()?;
    assert!(
        output.status.success(),
        "render {extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    Ok(())
}

fn merge(dir: &Path, parts: &[String], out: &[&str]) -> TestResult<std::process::Output> {
    let mut command = fspec();
    command.current_dir(dir).arg("merge").args(parts);
    for path in out {
        command.args(["--out", path]);
    }
    Ok(command.output()?)
}

fn render_cmd(dir: &Path) -> Command {
    let mut command = fspec();
    command.current_dir(dir).arg("render").args(FRAME).arg(SEED);
    command
}

/// The single render: its EXR and partial film.
fn single(dir: &Path) -> TestResult {
    let output = render_cmd(dir)
        .args([
            "--spp",
            &PASSES.to_string(),
            "--out",
            "single.exr",
            "--out",
            "single.fspart",
            "-q",
        ])
        .output()?;
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    Ok(())
}

fn part(dir: &Path, name: &str, passes: &str, crop: Option<&str>) -> TestResult<String> {
    let file = format!("{name}.fspart");
    let mut command = render_cmd(dir);
    command.args(["--passes", passes, "--out", &file, "-q"]);
    if let Some(crop) = crop {
        command.args(["--crop", crop]);
    }
    let output = command.output()?;
    assert!(
        output.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    Ok(file)
}

fn merged_ok(dir: &Path, parts: &[String], out: &[&str]) -> TestResult {
    let output = merge(dir, parts, out)?;
    assert!(
        output.status.success(),
        "merge: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    Ok(())
}

/// The merged partial film's sums against the single render's: equal
/// within `2 (n − 1) u Σ|x|` per value (`Σ|x| ≤ n max|x|`, bounded by `n`
/// times the largest sum), and the count of values that differ at all.
fn sums_within_bound(dir: &Path, merged: &str) -> TestResult<usize> {
    let a = PartialFilm::read(&dir.join(merged))?;
    let b = PartialFilm::read(&dir.join("single.fspart"))?;
    assert_eq!(a.header, b.header);
    let n = f64::from(PASSES);
    let largest = b.state.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let bound = 2.0 * (n - 1.0) * (f64::EPSILON / 2.0) * n * largest;
    let mut differing = 0;
    for (x, y) in a.state.values.iter().zip(&b.state.values) {
        assert!((x - y).abs() <= bound, "{x} vs {y}");
        differing += usize::from(x != y);
    }
    Ok(differing)
}

#[test]
fn four_pass_ranges_merge_into_the_single_render() -> TestResult {
    let dir = test_dir("pass-ranges")?;
    single(&dir)?;
    let mut parts = Vec::new();
    for (k, passes) in ["0..2", "2..3", "3..8", "8..12"].iter().enumerate() {
        parts.push(part(&dir, &format!("p{k}"), passes, None)?);
    }
    merged_ok(&dir, &parts, &["merged.exr", "merged.fspart"])?;
    let differing = sums_within_bound(&dir, "merged.fspart")?;
    eprintln!("{differing} merged sums differ from the single render's");
    assert_eq!(
        fs::read(dir.join("merged.exr"))?,
        fs::read(dir.join("single.exr"))?
    );
    // The files in another order: the same bytes.
    parts.reverse();
    merged_ok(&dir, &parts, &["reversed.exr", "reversed.fspart"])?;
    assert_eq!(
        fs::read(dir.join("reversed.fspart"))?,
        fs::read(dir.join("merged.fspart"))?
    );
    Ok(())
}

#[test]
fn four_crops_and_mixed_parts_merge_bit_for_bit() -> TestResult {
    let dir = test_dir("crops")?;
    single(&dir)?;
    let all = format!("0..{PASSES}");
    // Cuts through tiles (16 px) and packets (4 × 2 px).
    let crops = ["0,0,13,9", "13,0,24,9", "0,9,13,20", "13,9,24,20"];
    let mut parts = Vec::new();
    for (k, crop) in crops.iter().enumerate() {
        parts.push(part(&dir, &format!("c{k}"), &all, Some(crop))?);
    }
    merged_ok(&dir, &parts, &["crops.exr", "crops.fspart"])?;
    assert_eq!(
        fs::read(dir.join("crops.exr"))?,
        fs::read(dir.join("single.exr"))?
    );
    assert_eq!(
        fs::read(dir.join("crops.fspart"))?,
        fs::read(dir.join("single.fspart"))?
    );
    // Two crops × two pass ranges, one crop split differently.
    let mixed = vec![
        part(&dir, "m0", "0..5", Some("0,0,37,10"))?,
        part(&dir, "m1", "5..12", Some("0,0,37,10"))?,
        part(&dir, "m2", "0..7", Some("0,10,37,19"))?,
        part(&dir, "m3", "7..12", Some("0,10,37,19"))?,
    ];
    merged_ok(&dir, &mixed, &["mixed.exr", "mixed.fspart"])?;
    sums_within_bound(&dir, "mixed.fspart")?;
    assert_eq!(
        fs::read(dir.join("mixed.exr"))?,
        fs::read(dir.join("single.exr"))?
    );
    Ok(())
}

#[test]
fn a_stopped_render_resumes_bit_for_bit() -> TestResult {
    let dir = test_dir("resume")?;
    single(&dir)?;
    // Stopped after 5 of 12 passes (as a time limit would), then resumed
    // to the passes it was asked for, twice over (the second resume has
    // nothing left to do).
    render(&dir, &["--passes", "0..5", "--out", "stopped.fspart"])?;
    let mut film = PartialFilm::read(&dir.join("stopped.fspart"))?;
    film.header.requested_passes = [0, PASSES];
    film.write(&dir.join("stopped.fspart"))?;
    for _ in 0..2 {
        let output = render_cmd(&dir)
            .args([
                "--resume",
                "stopped.fspart",
                "--out",
                "stopped.fspart",
                "--out",
                "resumed.exr",
                "-q",
            ])
            .output()?;
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        assert_eq!(
            fs::read(dir.join("resumed.exr"))?,
            fs::read(dir.join("single.exr"))?
        );
        assert_eq!(
            fs::read(dir.join("stopped.fspart"))?,
            fs::read(dir.join("single.fspart"))?
        );
    }
    // A real time limit: whatever it stopped at, the resumed frame is the
    // single render.
    let output = render_cmd(&dir)
        .args([
            "--passes",
            "0..12",
            "--time-limit",
            "0.001",
            "--out",
            "limited.fspart",
            "-q",
        ])
        .output()?;
    assert!(output.status.success());
    let limited = PartialFilm::read(&dir.join("limited.fspart"))?;
    assert!(limited.state.passes.end <= PASSES);
    render(
        &dir,
        &["--resume", "limited.fspart", "--out", "limited.exr"],
    )?;
    assert_eq!(
        fs::read(dir.join("limited.exr"))?,
        fs::read(dir.join("single.exr"))?
    );
    Ok(())
}

#[test]
fn the_job_array_recipe_renders_the_frame_in_concurrent_processes() -> TestResult {
    let dir = test_dir("recipe")?;
    single(&dir)?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/render_part.sh");
    let count = 4;
    let spawn = |index: u32| {
        std::process::Command::new("bash")
            .current_dir(&dir)
            .env("FSPEC", env!("CARGO_BIN_EXE_fspec"))
            .arg(&script)
            .args([
                &index.to_string(),
                &count.to_string(),
                &PASSES.to_string(),
                "parts",
            ])
            .args(FRAME)
            .arg(SEED)
            .args(["--threads", "1"])
            .spawn()
    };
    let children: Vec<_> = (0..count).map(spawn).collect::<Result<_, _>>()?;
    for child in children {
        let output = child.wait_with_output()?;
        assert!(output.status.success());
    }
    let parts: Vec<String> = (0..count)
        .map(|k| format!("parts/part-{k}.fspart"))
        .collect();
    merged_ok(&dir, &parts, &["farm.exr"])?;
    assert_eq!(
        fs::read(dir.join("farm.exr"))?,
        fs::read(dir.join("single.exr"))?
    );
    // Run again (a preempted job restarted): finished parts are resumed
    // with nothing to do and stay the same.
    let before = fs::read(dir.join("parts/part-0.fspart"))?;
    assert!(spawn(0)?.wait()?.success());
    assert_eq!(fs::read(dir.join("parts/part-0.fspart"))?, before);
    Ok(())
}

/// One line on stderr, exit code 2, and it mentions `needle`.
fn refused(output: &std::process::Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{needle}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains(needle), "expected '{needle}' in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn parts_that_do_not_belong_together_are_refused() -> TestResult {
    let dir = test_dir("refused")?;
    let a = part(&dir, "a", "0..2", None)?;
    let b = part(&dir, "b", "2..4", None)?;
    // Another seed, transport, size, scene, filter.
    let other = |name: &str, options: &[&str]| -> TestResult<String> {
        let file = format!("{name}.fspart");
        let mut command = fspec();
        command.current_dir(&dir).arg("render");
        let output = command
            .args(options)
            .args(["--passes", "2..4", "--out", &file, "-q"])
            .output()?;
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        Ok(file)
    };
    let base = ["materials", "--width", "37", "--height", "29"];
    for (name, options, needle) in [
        ("seed", vec!["--seed", "6"], "seed"),
        ("coeffs", vec!["--seed", "5", "--coeffs", "8"], "transport"),
        (
            "sampled",
            vec!["--seed", "5", "--transport", "sampled"],
            "transport",
        ),
        (
            "depth",
            vec!["--seed", "5", "--max-depth", "3"],
            "max_depth",
        ),
        ("filter", vec!["--seed", "5", "--filter", "box"], "filter"),
    ] {
        let mut all: Vec<&str> = base.to_vec();
        all.extend(options);
        let file = other(name, &all)?;
        refused(&merge(&dir, &[a.clone(), file], &["x.exr"])?, needle);
    }
    let cornell = other(
        "cornell",
        &["cornell", "--width", "37", "--height", "29", "--seed", "5"],
    )?;
    refused(
        &merge(&dir, &[a.clone(), cornell], &["x.exr"])?,
        "scene_fingerprint",
    );
    let wide = other(
        "wide",
        &[
            "materials",
            "--width",
            "38",
            "--height",
            "29",
            "--seed",
            "5",
        ],
    )?;
    // (Fields are compared in alphabetical order: the frame comes first.)
    refused(&merge(&dir, &[a.clone(), wide], &["x.exr"])?, "frame");
    // Overlaps, gaps in passes, a missing crop, unequal passes.
    refused(
        &merge(&dir, &[a.clone(), a.clone()], &["x.exr"])?,
        "overlap",
    );
    let c = part(&dir, "c", "1..3", None)?;
    refused(&merge(&dir, &[a.clone(), c], &["x.exr"])?, "overlap");
    let d = part(&dir, "d", "3..5", None)?;
    refused(&merge(&dir, &[a.clone(), d], &["x.exr"])?, "in no part");
    let left = part(&dir, "left", "0..2", Some("0,0,20,29"))?;
    refused(
        &merge(&dir, std::slice::from_ref(&left), &["x.exr"])?,
        "no part holds",
    );
    let right = part(&dir, "right", "0..3", Some("20,0,17,29"))?;
    refused(&merge(&dir, &[left, right], &["x.exr"])?, "same passes");
    // Resumed with other settings or another window (the parts have the
    // default `--coeffs auto`, 16 on this scene, never 4).
    let output = render_cmd(&dir)
        .args(["--resume", &b, "--coeffs", "4", "--out", "y.exr"])
        .output()?;
    refused(&output, "transport");
    let output = render_cmd(&dir)
        .args(["--resume", &a, "--crop", "0,0,8,8", "--out", "y.exr"])
        .output()?;
    refused(&output, "window");
    let output = render_cmd(&dir)
        .args(["--resume", &b, "--passes", "0..4", "--out", "y.exr"])
        .output()?;
    refused(&output, "do not start");
    // Control variates cannot split.
    let output = render_cmd(&dir)
        .args(["--transport", "cv", "--passes", "0..2", "--out", "y.exr"])
        .output()?;
    refused(&output, "control variates");
    // Bad ranges.
    for bad in ["3..3", "5..2", "a..4", "4"] {
        let output = render_cmd(&dir)
            .args(["--passes", bad, "--out", "y.exr"])
            .output()?;
        assert_eq!(output.status.code(), Some(2), "{bad}");
    }
    // No output and no temporary was left by any refusal.
    let left: Vec<String> = entries(&dir)?
        .into_iter()
        .filter(|name| !name.ends_with(".fspart"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    Ok(())
}

#[test]
fn corrupt_partial_films_are_refused() -> TestResult {
    let dir = test_dir("corrupt")?;
    let good = part(&dir, "good", "0..2", None)?;
    let bytes = fs::read(dir.join(&good))?;
    let header_end = bytes
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(1)
        .map(|(i, _)| i + 1)
        .ok_or("no header")?;
    let text = String::from_utf8_lossy(&bytes[..header_end]).into_owned();
    let with_header = |header: &str| -> Vec<u8> {
        let mut v = header.as_bytes().to_vec();
        v.extend_from_slice(&bytes[header_end..]);
        v
    };
    let mut nan = bytes.clone();
    nan[header_end..header_end + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "truncated",
            bytes[..bytes.len() - 3].to_vec(),
            "bytes of pixel data",
        ),
        ("empty", Vec::new(), "first line"),
        (
            "magic",
            with_header(&text.replacen("fspec partial film 1", "fspec partial film 2", 1)),
            "version 2",
        ),
        (
            "json",
            with_header(&text.replacen("\"seed\":5", "\"seed\":", 1)),
            "header",
        ),
        (
            "unknown field",
            with_header(&text.replacen("\"seed\":5", "\"seed\":5,\"colour\":1", 1)),
            "header",
        ),
        (
            "window",
            with_header(&text.replacen("\"window\":[0,0,37,29]", "\"window\":[0,0,38,29]", 1)),
            "window",
        ),
        (
            "passes",
            with_header(&text.replacen("\"passes\":[0,2]", "\"passes\":[2,0]", 1)),
            "passes",
        ),
        ("nan", nan, "finite samples"),
    ];
    for (name, content, needle) in cases {
        let path = format!("{name}.fspart");
        fs::write(dir.join(&path), content)?;
        refused(
            &merge(&dir, std::slice::from_ref(&path), &["x.exr"])?,
            needle,
        );
        let output = render_cmd(&dir)
            .args(["--resume", &path, "--out", "y.exr"])
            .output()?;
        refused(&output, needle);
    }
    refused(
        &merge(&dir, &["missing.fspart".into()], &["x.exr"])?,
        "cannot read",
    );
    Ok(())
}

/// Splatted parts (`--film splat`): four crops merge bit for bit into the
/// single splatted render (EXR and sums), a splatted part does not merge
/// with a sampled one, and control variates refuse to splat.
#[test]
fn splatted_crops_merge_bit_for_bit() -> TestResult {
    let dir = test_dir("splat")?;
    let all = format!("0..{PASSES}");
    let splat = |name: &str, extra: &[&str]| -> TestResult<String> {
        let file = format!("{name}.fspart");
        let exr = format!("{name}.exr");
        let options = [
            "--film", "splat", "--passes", &all, "--out", &file, "--out", &exr,
        ];
        render(&dir, &[&options[..], extra].concat())?;
        Ok(file)
    };
    splat("single", &[])?;
    let mut crops = Vec::new();
    for (k, crop) in ["0,0,13,9", "13,0,24,9", "0,9,13,20", "13,9,24,20"]
        .iter()
        .enumerate()
    {
        crops.push(splat(&format!("c{k}"), &["--crop", crop])?);
    }
    merged_ok(&dir, &crops, &["crops.exr", "crops.fspart"])?;
    assert_eq!(
        fs::read(dir.join("crops.fspart"))?,
        fs::read(dir.join("single.fspart"))?
    );
    assert_eq!(
        fs::read(dir.join("crops.exr"))?,
        fs::read(dir.join("single.exr"))?
    );
    // The sampled film of the same frame (`--film sample`: the default
    // is splat) is another image, its part another film.
    let sampled = |name: &str, extra: &[&str]| -> TestResult<String> {
        let file = format!("{name}.fspart");
        let options = ["--film", "sample", "--passes", &all, "--out", &file];
        render(&dir, &[&options[..], extra].concat())?;
        Ok(file)
    };
    sampled("sampled", &[])?;
    assert_ne!(
        fs::read(dir.join("sampled.fspart"))?,
        fs::read(dir.join("single.fspart"))?
    );
    let half = splat("half", &["--crop", "0,0,37,10"])?;
    let lower = sampled("lower", &["--crop", "0,10,37,19"])?;
    refused(&merge(&dir, &[half, lower], &["mixed.exr"])?, "film (");
    let cv = render_cmd(&dir)
        .args(["--film", "splat", "--transport", "cv", "--spp", "1", "-q"])
        .args(["--out", "cv.exr"])
        .output()?;
    refused(&cv, "--film splat");
    Ok(())
}

/// The filters with negative lobes (`--filter mitchell`, `catmull-rom`,
/// `lanczos`) render with the splatting film, the default, and are refused
/// with the sampling film in one line (their values are no density to
/// draw offsets from).
#[test]
fn negative_lobed_filters_splat_only() -> TestResult {
    let dir = test_dir("negative-lobes")?;
    for filter in ["mitchell", "catmull-rom", "lanczos"] {
        let render = |film: Option<&str>| -> TestResult<std::process::Output> {
            let mut command = fspec();
            command.current_dir(&dir).args([
                "render", "--quiet", "--width", "8", "--height", "8", "--spp", "1", "--filter",
                filter, "--out", "out.exr",
            ]);
            if let Some(film) = film {
                command.args(["--film", film]);
            }
            Ok(command.output()?)
        };
        let splat = render(None)?;
        assert!(
            splat.status.success(),
            "{filter}: {}",
            String::from_utf8_lossy(&splat.stderr)
        );
        refused(&render(Some("sample"))?, "negative lobes");
    }
    Ok(())
}
