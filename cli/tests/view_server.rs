//! `fspec view`'s server, driven over plain HTTP/1.1 from the test: the
//! page and assets, frames over server-sent events, restarts on a change,
//! error replies to bad requests (and the server going on), the image
//! against `fspec render`'s, a closed page stopping the render. Every test
//! stops its server (`ViewServer` stops on drop too) and every read has a
//! deadline.

mod common;

use base64::Engine;
use common::TestResult;
use fspec_cli::view::{ViewArgs, ViewServer};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

/// The longest any single step may take (a debug build on a loaded machine).
const DEADLINE: Duration = Duration::from_secs(120);

fn args(scene: &str, side: u32, max_passes: u32) -> ViewArgs {
    ViewArgs {
        scene: scene.into(),
        port: 0,
        listen: None,
        width: Some(side),
        height: Some(side),
        max_passes,
        threads: Some(1),
        define: Vec::new(),
        lenient: false,
    }
}

/// One request with `Connection: close`: status and body.
fn request(
    address: SocketAddr,
    method: &str,
    path: &str,
    body: &str,
) -> TestResult<(u16, Vec<u8>)> {
    let mut stream = TcpStream::connect(address)?;
    stream.set_read_timeout(Some(DEADLINE))?;
    write!(
        stream,
        "{method} {path} HTTP/1.1\r\nHost: {address}\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )?;
    let mut reply = Vec::new();
    stream.read_to_end(&mut reply)?;
    let split = reply
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .ok_or("no end of headers")?;
    let head = String::from_utf8_lossy(&reply[..split]).to_string();
    let status: u16 = head.split_whitespace().nth(1).ok_or("no status")?.parse()?;
    let mut body = reply[split + 4..].to_vec();
    if head
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        body = dechunk(&body)?;
    }
    Ok((status, body))
}

fn dechunk(mut data: &[u8]) -> TestResult<Vec<u8>> {
    let mut out = Vec::new();
    loop {
        let line_end = data
            .windows(2)
            .position(|w| w == b"\r\n")
            .ok_or("chunk size")?;
        let size = usize::from_str_radix(std::str::from_utf8(&data[..line_end])?.trim(), 16)?;
        data = &data[line_end + 2..];
        if size == 0 {
            return Ok(out);
        }
        out.extend_from_slice(data.get(..size).ok_or("short chunk")?);
        data = &data[size + 2..];
    }
}

fn json(
    address: SocketAddr,
    method: &str,
    path: &str,
    body: &str,
) -> TestResult<(u16, serde_json::Value)> {
    let (status, body) = request(address, method, path, body)?;
    Ok((status, serde_json::from_slice(&body)?))
}

/// An open event stream (`GET /api/events`), read line by line.
struct Events {
    reader: BufReader<TcpStream>,
}

impl Events {
    fn open(address: SocketAddr) -> TestResult<Self> {
        let mut stream = TcpStream::connect(address)?;
        stream.set_read_timeout(Some(DEADLINE))?;
        write!(
            stream,
            "GET /api/events HTTP/1.1\r\nHost: {address}\r\n\r\n"
        )?;
        let mut reader = BufReader::new(stream);
        let mut line = String::new();
        reader.read_line(&mut line)?;
        assert!(line.contains("200"), "{line}");
        // Headers end at an empty line.
        while {
            line.clear();
            reader.read_line(&mut line)?;
            line.trim() != ""
        } {}
        Ok(Self { reader })
    }

    /// The next event of kind `frame` or `error` (chunk sizes, comments
    /// and keep-alives skipped), before the deadline.
    fn next(&mut self) -> TestResult<(String, serde_json::Value)> {
        let start = Instant::now();
        let mut kind = String::new();
        let mut line = String::new();
        while start.elapsed() < DEADLINE {
            line.clear();
            if self.reader.read_line(&mut line)? == 0 {
                return Err("event stream ended".into());
            }
            let line = line.trim_end();
            if let Some(k) = line.strip_prefix("event:") {
                kind = k.trim().to_string();
            } else if let Some(data) = line.strip_prefix("data:") {
                if kind == "frame" || kind == "error" {
                    return Ok((kind.clone(), serde_json::from_str(data.trim())?));
                }
            }
        }
        Err("no event before the deadline".into())
    }

    /// The next frame of `generation` (frames of others skipped).
    fn frame_of(&mut self, generation: u64) -> TestResult<serde_json::Value> {
        let start = Instant::now();
        while start.elapsed() < DEADLINE {
            let (kind, data) = self.next()?;
            if kind == "error" {
                return Err(format!("render error: {data}").into());
            }
            if data["generation"] == generation {
                return Ok(data);
            }
        }
        Err("no frame of that generation".into())
    }
}

/// A frame's PNG decoded: width, height, RGB bytes.
fn pixels_of(frame: &serde_json::Value) -> TestResult<(u32, u32, Vec<u8>)> {
    let png =
        base64::engine::general_purpose::STANDARD.decode(frame["png"].as_str().ok_or("png")?)?;
    decode_png(&png)
}

fn decode_png(bytes: &[u8]) -> TestResult<(u32, u32, Vec<u8>)> {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info()?;
    let mut buffer = vec![0; reader.output_buffer_size().ok_or("size")?];
    let info = reader.next_frame(&mut buffer)?;
    buffer.truncate(info.buffer_size());
    Ok((info.width, info.height, buffer))
}

#[test]
fn the_page_and_its_assets_are_served() -> TestResult {
    let server = ViewServer::start(&args("cornell", 16, 4))?;
    let address = server.address();
    assert!(address.ip().is_loopback());
    let (status, page) = request(address, "GET", "/", "")?;
    let page = String::from_utf8(page)?;
    assert_eq!(status, 200);
    assert!(page.contains(r#"<script src="/app.js">"#), "{page}");
    assert!(
        !page.contains("http://") && !page.contains("https://"),
        "no CDN"
    );
    let (status, script) = request(address, "GET", "/app.js", "")?;
    assert_eq!(status, 200);
    assert!(String::from_utf8(script)?.contains("EventSource"));
    assert_eq!(request(address, "GET", "/style.css", "")?.0, 200);
    let (status, missing) = json(address, "GET", "/nosuchpage", "")?;
    assert_eq!(status, 404);
    assert!(missing["error"].is_string());
    let (status, state) = json(address, "GET", "/api/state", "")?;
    assert_eq!(status, 200);
    assert!(
        state["scenes"]
            .as_array()
            .ok_or("scenes")?
            .contains(&"lamps".into())
    );
    assert!(
        state["illuminants"]
            .as_array()
            .ok_or("illuminants")?
            .contains(&"led-b4".into())
    );
    server.stop()?;
    Ok(())
}

#[test]
fn frames_refine_and_a_scene_change_restarts_the_passes() -> TestResult {
    let server = ViewServer::start(&args("cornell", 16, 100_000))?;
    let address = server.address();
    let mut events = Events::open(address)?;
    let mut passes = 0;
    while passes < 3 {
        let frame = events.frame_of(0)?;
        let now = frame["passes"].as_u64().ok_or("passes")?;
        assert!(now > passes, "passes only grow within a generation");
        passes = now;
    }
    let (status, reply) = json(address, "POST", "/api/settings", r#"{"scene": "lamps"}"#)?;
    assert_eq!(status, 200, "{reply}");
    assert_eq!(reply["generation"], 1);
    assert_eq!(reply["change"], "render");
    let first = events.frame_of(1)?;
    assert_eq!(
        first["passes"], 1,
        "the render restarts from its first pass"
    );
    assert_eq!(first["settings"]["scene"], "lamps");
    let (width, height, rgb) = pixels_of(&first)?;
    assert_eq!((width, height), (16, 16));
    assert!(rgb.iter().any(|&v| v > 0), "not black");
    // Exposure re-displays the same passes: no restart.
    let (status, reply) = json(address, "POST", "/api/settings", r#"{"exposure_stops": 2}"#)?;
    assert_eq!((status, reply["change"].as_str()), (200, Some("display")));
    assert_eq!(reply["generation"], 1);
    server.stop()?;
    Ok(())
}

#[test]
fn bad_requests_get_an_error_and_the_server_goes_on() -> TestResult {
    let server = ViewServer::start(&args("cornell", 16, 4))?;
    let address = server.address();
    for (body, expected) in [
        (r#"{"scene": "nosuchscene"}"#, "unknown scene"),
        (r#"{"width": 100000}"#, "width 100000"),
        (r#"{"height": 0}"#, "height 0"),
        (r#"{"width": -5}"#, "malformed"),
        (
            r#"{"transport": {"kind": "fourier", "coeffs": 7, "buffer": "spectral", "to_color": "zeroth"}}"#,
            "--coeffs 7",
        ),
        (
            r#"{"illuminant": "../../etc/passwd"}"#,
            "not a built-in illuminant",
        ),
        (
            r#"{"camera": {"position": [0,0,0], "target": [0,0,0], "up": [0,1,0], "fov_deg": 40}}"#,
            "camera",
        ),
        (r#"{"exposure_stops": 1e9}"#, "exposure"),
        (r#"{"max_passes": 0}"#, "max_passes"),
        (r#"{"no_such_field": 1}"#, "malformed"),
        ("{not json", "malformed"),
        ("", "malformed"),
    ] {
        let (status, reply) = json(address, "POST", "/api/settings", body)?;
        assert_eq!(status, 400, "{body}: {reply}");
        let message = reply["error"].as_str().ok_or("error")?;
        assert!(message.contains(expected), "{body}: {message}");
        assert!(!message.contains('\n'), "one line: {message}");
    }
    for path in [
        "/api/spectrum",
        "/api/spectrum?x=abc&y=1",
        "/api/save?format=gif",
        "/api/save",
    ] {
        let (status, reply) = json(address, "GET", path, "")?;
        assert_eq!(status, 400, "{path}: {reply}");
    }
    // Nothing changed and the server still answers.
    let (status, state) = json(address, "GET", "/api/state", "")?;
    assert_eq!(status, 200);
    assert_eq!(state["generation"], 0);
    assert_eq!(state["settings"]["scene"], "cornell");
    assert_eq!(state["settings"]["width"], 16);
    let mut events = Events::open(address)?;
    let frame = events.frame_of(0)?;
    let (status, reply) = json(address, "GET", "/api/spectrum?x=16&y=0", "")?;
    assert_eq!(status, 400, "outside the image: {reply}");
    assert!(frame["passes"].as_u64().ok_or("passes")? >= 1);
    server.stop()?;
    Ok(())
}

/// The viewer's last frame is `fspec render`'s image of the same command
/// line, pixel for pixel, and not that of one pass fewer.
#[test]
fn the_frame_equals_the_file_render_of_the_same_settings() -> TestResult {
    const PASSES: u32 = 4;
    let server = ViewServer::start(&args("cornell", 24, PASSES))?;
    let address = server.address();
    let mut events = Events::open(address)?;
    let mut frame = events.frame_of(0)?;
    while frame["passes"] != PASSES {
        frame = events.frame_of(0)?;
    }
    let (_, _, viewed) = pixels_of(&frame)?;
    let command = frame["render_command"]
        .as_str()
        .ok_or("render command")?
        .to_string();
    server.stop()?;
    let dir = common::test_dir("view", "file-render")?;
    let render = |spp: u32, name: &str| -> TestResult<Vec<u8>> {
        let out = dir.join(name);
        let mut line: Vec<String> = command
            .split_whitespace()
            .skip(1)
            .map(String::from)
            .collect();
        let at = line.iter().position(|w| w == "--spp").ok_or("--spp")?;
        line[at + 1] = spp.to_string();
        line.extend([
            "--quiet".to_string(),
            "--out".to_string(),
            out.display().to_string(),
        ]);
        let status = assert_cmd::Command::cargo_bin("fspec")?
            .args(&line)
            .output()?;
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
        Ok(decode_png(&std::fs::read(&out)?)?.2)
    };
    assert_eq!(viewed, render(PASSES, "same.png")?);
    assert_ne!(viewed, render(PASSES - 1, "fewer.png")?);
    assert_eq!(common::entries(&dir)?, ["fewer.png", "same.png"]);
    Ok(())
}

#[test]
fn closing_the_page_stops_the_render() -> TestResult {
    let server = ViewServer::start(&args("cornell", 16, 1_000_000))?;
    let address = server.address();
    let passes = || -> TestResult<(u64, u64)> {
        let (_, state) = json(address, "GET", "/api/state", "")?;
        Ok((
            state["viewers"].as_u64().ok_or("viewers")?,
            state["latest_frame"]["passes"].as_u64().unwrap_or(0),
        ))
    };
    let mut events = Events::open(address)?;
    let first = events.frame_of(0)?["passes"].as_u64().ok_or("passes")?;
    let later = loop {
        let now = events.frame_of(0)?["passes"].as_u64().ok_or("passes")?;
        if now > first {
            break now;
        }
    };
    assert!(later > first, "an open page sees the passes grow");
    drop(events);
    let start = Instant::now();
    while passes()?.0 != 0 {
        assert!(
            start.elapsed() < DEADLINE,
            "the closed page is never noticed"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // After the batch in flight, the pass count stands still.
    std::thread::sleep(Duration::from_millis(1500));
    let settled = passes()?.1;
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(passes()?.1, settled, "no page, no render");
    server.stop()?;
    Ok(())
}

#[test]
fn spectra_and_downloads_of_the_current_image() -> TestResult {
    let server = ViewServer::start(&args("cornell", 16, 2))?;
    let address = server.address();
    let mut events = Events::open(address)?;
    events.frame_of(0)?;
    let (status, spectrum) = json(address, "GET", "/api/spectrum?x=8&y=4", "")?;
    assert_eq!(status, 200, "{spectrum}");
    let lambda = spectrum["lambda_nm"].as_array().ok_or("lambda")?;
    assert_eq!(lambda.first().and_then(|v| v.as_f64()), Some(360.0));
    assert_eq!(lambda.last().and_then(|v| v.as_f64()), Some(830.0));
    assert_eq!(
        spectrum["radiance"].as_array().ok_or("radiance")?.len(),
        lambda.len()
    );
    assert_eq!(
        spectrum["coefficients"]
            .as_array()
            .ok_or("coefficients")?
            .len(),
        12
    );
    let (status, png) = request(address, "GET", "/api/save?format=png", "")?;
    assert_eq!((status, &png[1..4]), (200, &b"PNG"[..]));
    let exr_magic = [0x76, 0x2f, 0x31, 0x01];
    for format in ["exr", "spectral"] {
        let (status, exr) = request(address, "GET", &format!("/api/save?format={format}"), "")?;
        assert_eq!((status, &exr[..4]), (200, &exr_magic[..]), "{format}");
    }
    check_sampled_estimate(&spectrum)?;
    // A sampled film keeps no coefficients: the pixel is traced both ways
    // all the same (the Fourier side with the default 12 coefficients).
    let body = r#"{"transport": {"kind": "sampled", "wavelengths": 4, "sampling": "visible"}}"#;
    assert_eq!(json(address, "POST", "/api/settings", body)?.0, 200);
    events.frame_of(1)?;
    let (status, spectrum) = json(address, "GET", "/api/spectrum?x=8&y=4", "")?;
    assert_eq!(status, 200, "{spectrum}");
    assert_eq!(
        spectrum["coefficients"]
            .as_array()
            .ok_or("coefficients")?
            .len(),
        12
    );
    assert_eq!(spectrum["sampled"]["sampling"], "visible");
    check_sampled_estimate(&spectrum)?;
    // Bad pixels: outside the image either way, negative, not a number.
    for path in [
        "/api/spectrum?x=16&y=0",
        "/api/spectrum?x=0&y=16",
        "/api/spectrum?x=-1&y=0",
        "/api/spectrum?x=1.5&y=0",
        "/api/spectrum?x=1",
    ] {
        let (status, reply) = json(address, "GET", path, "")?;
        assert_eq!(status, 400, "{path}: {reply}");
        assert!(reply["error"].is_string(), "{path}: {reply}");
    }
    server.stop()?;
    Ok(())
}

/// Fewest paths a probe of the 16-pixel Cornell box is expected to trace
/// within its time limit (2 s), for the loose check below: a debug build
/// under a load of 8 on 2 cores traced 2319.
const MIN_PROBE_PATHS: f64 = 256.0;

/// The sampled half of a spectrum reply: 47 bins of 10 nm over 360–830
/// nm, finite and non-negative, with standard errors, and a Fourier curve
/// of the same order of magnitude: the means over the range agree within
/// 20 % (a loose check: the unit test in simd-tracer compares them bin by
/// bin within noise).
fn check_sampled_estimate(spectrum: &serde_json::Value) -> TestResult {
    let sampled = &spectrum["sampled"];
    let values = |v: &serde_json::Value| -> TestResult<Vec<f64>> {
        v.as_array()
            .ok_or("array")?
            .iter()
            .map(|x| x.as_f64().ok_or_else(|| "number".into()))
            .collect()
    };
    let centres = values(&sampled["bin_centre_nm"])?;
    let radiance = values(&sampled["radiance"])?;
    let errors = values(&sampled["std_error"])?;
    assert_eq!(centres.len(), 47);
    assert_eq!((centres[0], centres[46]), (365.0, 825.0));
    assert_eq!(sampled["bin_width_nm"], 10.0);
    assert_eq!((radiance.len(), errors.len()), (47, 47));
    assert!(
        radiance
            .iter()
            .chain(&errors)
            .all(|v| v.is_finite() && *v >= 0.0)
    );
    assert!(errors.iter().any(|&e| e > 0.0), "noise is measured");
    // Each probe stops at 4096 paths or its time limit (2 s), whichever
    // comes first: a debug build on a loaded machine gets a few hundred
    // at least.
    for paths in [
        sampled["paths"].as_f64().ok_or("paths")?,
        spectrum["fourier_paths"].as_f64().ok_or("paths")?,
    ] {
        assert!((MIN_PROBE_PATHS..=4096.0).contains(&paths), "{paths} paths");
    }
    let curve = values(&spectrum["radiance"])?;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (sampled_mean, fourier_mean) = (mean(&radiance), mean(&curve));
    assert!(fourier_mean > 0.0, "a lit pixel");
    assert!(
        (sampled_mean / fourier_mean - 1.0).abs() < 0.2,
        "sampled {sampled_mean}, Fourier {fourier_mean}"
    );
    Ok(())
}

/// Split view: accepted with a sampled right half and refused with control
/// variates or a one-pixel-wide image; the halves' times stay within one
/// turn of each other at every frame; the finished frame's halves are the
/// file renders of each transport at each half's passes, pixel for pixel;
/// no `fspec render` line stands for the split image.
#[test]
fn split_view_renders_both_halves_at_equal_time() -> TestResult {
    let server = ViewServer::start(&args("cornell", 24, 1_000_000))?;
    let address = server.address();
    let sampled = r#"{"kind": "sampled", "wavelengths": 4, "sampling": "hero"}"#;
    let cv = r#"{"kind": "cv", "wavelengths": 4, "coeffs": 8, "sampling": "hero", "alpha_per_pixel": false}"#;
    for (body, expected) in [
        (format!(r#"{{"split": {cv}}}"#), "cv"),
        (
            format!(r#"{{"split": {sampled}, "transport": {cv}}}"#),
            "cv",
        ),
        (format!(r#"{{"split": {sampled}, "width": 1}}"#), "halves"),
        (r#"{"observer": "nosuchobserver"}"#.to_string(), "observer"),
    ] {
        let (status, reply) = json(address, "POST", "/api/settings", &body)?;
        assert_eq!(status, 400, "{body}: {reply}");
        let message = reply["error"].as_str().ok_or("error")?;
        assert!(message.contains(expected), "{body}: {message}");
    }
    let mut events = Events::open(address)?;
    let (status, reply) = json(
        address,
        "POST",
        "/api/settings",
        &format!(r#"{{"split": {sampled}}}"#),
    )?;
    assert_eq!(
        (status, reply["change"].as_str()),
        (200, Some("render")),
        "{reply}"
    );
    let generation = reply["generation"].as_u64().ok_or("generation")?;
    // Frames for a while: each turn adds to one half's time; the two stay
    // within the longest turn of each other.
    let seconds = |frame: &serde_json::Value, half: &str| -> TestResult<f64> {
        Ok(frame["split"][half]["seconds"].as_f64().ok_or("seconds")?)
    };
    let mut previous = (0.0, 0.0);
    let mut longest_turn: f64 = 0.0;
    let mut frames = 0;
    let start = Instant::now();
    while frames < 12 || start.elapsed() < Duration::from_secs(3) {
        let frame = events.frame_of(generation)?;
        assert!(frame["render_command"].is_null(), "{frame}");
        assert_eq!(frame["split"]["left"]["transport"]["kind"], "fourier");
        assert_eq!(frame["split"]["right"]["transport"]["kind"], "sampled");
        let now = (seconds(&frame, "left")?, seconds(&frame, "right")?);
        longest_turn = longest_turn.max(now.0 - previous.0).max(now.1 - previous.1);
        assert!(
            (now.0 - now.1).abs() <= longest_turn + 1e-9,
            "left {} s, right {} s, longest turn {longest_turn} s",
            now.0,
            now.1
        );
        previous = now;
        frames += 1;
    }
    assert!(previous.0 > 0.0 && previous.1 > 0.0, "both halves rendered");
    // A short split render to its end: each half against its file render.
    const PASSES: u32 = 6;
    let (status, reply) = json(
        address,
        "POST",
        "/api/settings",
        &format!(r#"{{"max_passes": {PASSES}}}"#),
    )?;
    assert_eq!(status, 200, "{reply}");
    let generation = reply["generation"].as_u64().ok_or("generation")?;
    let mut frame = events.frame_of(generation)?;
    while frame["split"]["done"] != true {
        frame = events.frame_of(generation)?;
    }
    let (width, height, viewed) = pixels_of(&frame)?;
    assert_eq!((width, height), (24, 24));
    assert!(viewed.iter().any(|&v| v > 0), "not black");
    let (left, right) = (&frame["split"]["left"], &frame["split"]["right"]);
    let left_passes = left["passes"].as_u64().ok_or("passes")?;
    let right_passes = right["passes"].as_u64().ok_or("passes")?;
    assert!(left_passes == u64::from(PASSES) || right_passes == u64::from(PASSES));
    // The rule's end: a half short of its passes has had at least the
    // other's time.
    if left_passes < u64::from(PASSES) {
        assert!(
            seconds(&frame, "left")? >= seconds(&frame, "right")?,
            "{frame}"
        );
    }
    if right_passes < u64::from(PASSES) {
        assert!(
            seconds(&frame, "right")? >= seconds(&frame, "left")?,
            "{frame}"
        );
    }
    server.stop()?;
    let dir = common::test_dir("view", "split")?;
    let render = |transport: &[&str], spp: u64, name: &str| -> TestResult<Vec<u8>> {
        let out = dir.join(name);
        let spp = spp.to_string();
        let mut line = vec![
            "render", "cornell", "--width", "24", "--height", "24", "--spp", &spp,
        ];
        line.extend_from_slice(transport);
        let out_arg = out.display().to_string();
        line.extend(["--quiet", "--out", &out_arg]);
        let status = assert_cmd::Command::cargo_bin("fspec")?
            .args(&line)
            .output()?;
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
        Ok(decode_png(&std::fs::read(&out)?)?.2)
    };
    let fourier = render(
        &["--transport", "fourier", "--coeffs", "12"],
        left_passes,
        "fourier.png",
    )?;
    let sampled = render(
        &[
            "--transport",
            "sampled",
            "--wavelengths",
            "4",
            "--sampling",
            "hero",
        ],
        right_passes,
        "sampled.png",
    )?;
    let row_bytes = 24 * 3;
    let half_bytes = 12 * 3;
    for row in 0..24 {
        let at = row * row_bytes;
        assert_eq!(
            viewed[at..at + half_bytes],
            fourier[at..at + half_bytes],
            "left half, row {row}"
        );
        assert_eq!(
            viewed[at + half_bytes..at + row_bytes],
            sampled[at + half_bytes..at + row_bytes],
            "right half, row {row}"
        );
    }
    // The halves are not one transport's image: the right half of the
    // Fourier render differs from the viewed right half.
    assert_ne!(
        (0..24)
            .flat_map(|row| viewed[row * row_bytes + half_bytes..(row + 1) * row_bytes].to_vec())
            .collect::<Vec<_>>(),
        (0..24)
            .flat_map(|row| fourier[row * row_bytes + half_bytes..(row + 1) * row_bytes].to_vec())
            .collect::<Vec<_>>()
    );
    Ok(())
}

/// The observer setting reaches the render line and changes the colours.
#[test]
fn the_observer_setting_changes_the_image_and_its_render_line() -> TestResult {
    let server = ViewServer::start(&args("cornell", 16, 2))?;
    let address = server.address();
    let (_, state) = json(address, "GET", "/api/state", "")?;
    assert!(
        state["observers"]
            .as_array()
            .ok_or("observers")?
            .contains(&"cie1964-10".into())
    );
    let mut events = Events::open(address)?;
    let mut first = events.frame_of(0)?;
    while first["passes"] != 2 {
        first = events.frame_of(0)?;
    }
    let (status, reply) = json(
        address,
        "POST",
        "/api/settings",
        r#"{"observer": "cie1964-10"}"#,
    )?;
    assert_eq!(
        (status, reply["change"].as_str()),
        (200, Some("render")),
        "{reply}"
    );
    let mut frame = events.frame_of(1)?;
    while frame["passes"] != 2 {
        frame = events.frame_of(1)?;
    }
    let command = frame["render_command"].as_str().ok_or("render command")?;
    assert!(command.contains("--observer cie1964-10"), "{command}");
    assert_ne!(pixels_of(&first)?.2, pixels_of(&frame)?.2, "other colours");
    server.stop()?;
    Ok(())
}

#[test]
fn a_bad_scene_or_a_taken_port_fails_before_serving() -> TestResult {
    let error = ViewServer::start(&args("nosuchscene", 16, 4))
        .err()
        .ok_or("started")?;
    assert!(error.to_string().contains("nosuchscene"), "{error}");
    let server = ViewServer::start(&args("cornell", 16, 4))?;
    let taken = ViewArgs {
        port: server.address().port(),
        ..args("cornell", 16, 4)
    };
    let error = ViewServer::start(&taken)
        .err()
        .ok_or("two servers on one port")?;
    assert!(error.to_string().contains("cannot listen"), "{error}");
    // The first server still answers.
    assert_eq!(request(server.address(), "GET", "/api/state", "")?.0, 200);
    server.stop()?;
    Ok(())
}
