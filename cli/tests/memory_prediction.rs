//! The memory `fspec render` predicts before it starts is not an
//! underestimate of what the render really takes, and not a gross
//! overestimate either: two in-process renders (one where the film
//! dominates, one where the spectral and coefficient EXR writers dominate)
//! are measured by the growth of the process's peak resident set
//! (`VmHWM` in `/proc/self/status`, Linux only).
//!
//! This file holds a single test so that its process runs nothing else
//! while it measures. Tolerance: the measured growth may exceed the
//! predicted data by [`ALLOCATOR_TOLERANCE_BYTES`] (allocator bookkeeping,
//! a worker thread's stack and per-thread arena, code paged in for the first
//! time); the process baseline itself is not part of the growth.

#[cfg(target_os = "linux")]
mod linux {
    use clap::Parser;
    use fspec_cli::render_cmd::{self, MemoryPrediction, RenderArgs};
    use std::fs;
    use test_support::ScratchDir;

    type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

    /// Slack for what the prediction does not model (module docs).
    const ALLOCATOR_TOLERANCE_BYTES: u64 = 4 << 20;

    /// The prediction may be at most this many times the measured growth
    /// (its copy factors for the image writers are upper bounds).
    const MAX_OVERESTIMATE: f64 = 2.0;

    /// Bytes per KiB of `/proc/self/status`.
    const KIB: u64 = 1024;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        render: RenderArgs,
    }

    /// A field of `/proc/self/status` in bytes (`VmHWM`, `VmRSS`).
    fn status_bytes(field: &str) -> TestResult<u64> {
        let status = fs::read_to_string("/proc/self/status")?;
        let line = status
            .lines()
            .find(|l| l.starts_with(field))
            .ok_or_else(|| format!("no {field} in /proc/self/status"))?;
        let kib: u64 = line.split_whitespace().nth(1).ok_or("no value")?.parse()?;
        Ok(kib * KIB)
    }

    fn dir(name: &str) -> TestResult<ScratchDir> {
        Ok(ScratchDir::new("fspec-memory", name)?)
    }

    /// Renders with `args` (paths relative to `dir`); returns the prediction
    /// and the growth of the peak resident set over the resident set before.
    fn measure(dir: &std::path::Path, args: &[&str]) -> TestResult<(MemoryPrediction, u64)> {
        let mut argv = vec!["render".to_string()];
        for a in args {
            argv.push(if a.ends_with(".exr") || a.ends_with(".png") {
                dir.join(a).display().to_string()
            } else {
                (*a).to_string()
            });
        }
        let cli = Cli::try_parse_from(&argv)?;
        // Resets VmHWM to the current resident set (Linux >= 4.0); where it
        // is refused, the growth below is still an upper bound of the truth.
        let _ = fs::write("/proc/self/clear_refs", "5");
        let before = status_bytes("VmRSS:")?;
        let summary = render_cmd::run(&cli.render)?;
        let peak = status_bytes("VmHWM:")?;
        Ok((summary.memory, peak.saturating_sub(before)))
    }

    #[test]
    fn predicted_memory_bounds_the_measured_peak() -> TestResult {
        let dir = dir("peak")?;
        let small = [
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "1",
            "--threads",
            "2",
        ];
        let outputs = [
            "--out",
            "a.png",
            "--out",
            "a.exr",
            "--exr-xyz",
            "--spectral-exr",
            "s.exr",
            "--coefficients-exr",
            "c.exr",
        ];
        // Warm-up: pages in the code of every writer and starts the allocator
        // arenas, which would otherwise count as growth.
        let mut args = small.to_vec();
        args.extend(["-q"]);
        args.extend(outputs);
        measure(&dir, &args)?;

        let size = [
            "--width",
            "256",
            "--height",
            "256",
            "--spp",
            "1",
            "--threads",
            "2",
        ];
        let film_only = [size.as_slice(), &["-q", "--out", "f.exr"]].concat();
        let with_spectra = [size.as_slice(), &["-q"], outputs.as_slice()].concat();
        let mut predictions: Vec<MemoryPrediction> = Vec::new();
        for (what, args) in [("film", film_only), ("spectral outputs", with_spectra)] {
            let (prediction, growth) = measure(&dir, &args)?;
            let predicted = prediction.data_bytes();
            eprintln!(
                "{what}: predicted {prediction:?} = {predicted} B, measured growth {growth} B"
            );
            assert!(
                growth <= predicted + ALLOCATOR_TOLERANCE_BYTES,
                "{what}: underestimate: measured {growth} B > predicted {predicted} B + tolerance"
            );
            assert!(
                predicted as f64 <= MAX_OVERESTIMATE * growth as f64,
                "{what}: gross overestimate: predicted {predicted} B, measured {growth} B"
            );
            assert!(prediction.peak_bytes() > predicted, "{what}: no baseline");
            predictions.push(prediction);
        }
        // The film dominates an EXR output; the spectral EXR writer dominates
        // when it is asked for: both phases are exercised above.
        assert!(predictions[0].render_bytes > predictions[0].output_bytes);
        assert!(predictions[1].output_bytes > predictions[1].render_bytes);
        fs::remove_dir_all(&dir)?;
        Ok(())
    }
}
