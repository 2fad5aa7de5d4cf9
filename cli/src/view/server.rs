//! The HTTP side: axum routes on a small tokio runtime of its own.
//!
//! | route | what |
//! | --- | --- |
//! | `GET /`, `/app.js`, `/style.css` | the page (embedded, no CDN) |
//! | `GET /api/state` | settings, scene and illuminant lists, the equivalent `fspec render` line, open pages, the latest frame's passes |
//! | `POST /api/settings` | a JSON [`SettingsPatch`]: 200 with the generation, or 400 and one error line |
//! | `GET /api/events` | server-sent events: `frame` (PNG in base64 and its pass count), `error` |
//! | `GET /api/spectrum?x=&y=` | a pixel's spectrum, traced again both ways ([`probe`](crate::view::probe)): the Fourier curve (360–830 nm) and the sampled estimate per 10 nm bin with its standard error; 429 while another is traced |
//! | `GET /api/save?format=png\|exr\|spectral` | the current image as a download |
//!
//! Every reply to a bad request is a JSON `{"error": "…"}` with a 4xx
//! status; nothing a request carries can stop the server. An event stream
//! ends when the page closes it or the server stops (so graceful shutdown
//! never waits on an open page).

use crate::error::CliError;
use crate::image_out::{Exposure, XyzImage, png_bytes, write_exr, write_spectral_exr};
use crate::render_cmd::spectral_planes;
use crate::view::driver::{Frame, Shared, Update};
use crate::view::settings::{Change, SettingsPatch, illuminant_names, observer_names};
use axum::Router;
use axum::body::Bytes;
use axum::extract::rejection::QueryRejection;
use axum::extract::{Query, State};
use axum::http::{StatusCode, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use base64::Engine;
use futures_util::Stream;
use serde::Deserialize;
use serde_json::json;
use std::convert::Infallible;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use tokio::sync::watch;

/// The page.
const INDEX_HTML: &str = include_str!("assets/index.html");
/// Its script.
const APP_JS: &str = include_str!("assets/app.js");
/// Its style.
const STYLE_CSS: &str = include_str!("assets/style.css");

/// Wavelength step of a pixel's spectrum on the page, nm (the CIE tables'
/// 5 nm).
const SPECTRUM_STEP_NM: f64 = 5.0;

/// Wavelength step of the spectral EXR download, nm (`fspec render`'s
/// `--spectral-step-nm` default).
const SPECTRAL_EXR_STEP_NM: f64 = 10.0;

/// What the handlers share.
pub struct App {
    /// Settings, frames and the driver.
    pub shared: Arc<Shared>,
    /// Scenes the page may choose.
    pub scenes: Vec<String>,
    /// Memory a render may use, bytes.
    pub memory_limit_bytes: u64,
    /// Becomes `true` when the server stops.
    pub stopping: watch::Receiver<bool>,
    /// A pixel's spectrum is being traced (one at a time: each costs up
    /// to twice `probe::PROBE_TIME_LIMIT` of a core).
    pub probing: AtomicBool,
}

/// The routes of the viewer.
pub fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(|| async { html(INDEX_HTML) }))
        .route("/index.html", get(|| async { html(INDEX_HTML) }))
        .route(
            "/app.js",
            get(|| async { asset("text/javascript; charset=utf-8", APP_JS) }),
        )
        .route(
            "/style.css",
            get(|| async { asset("text/css; charset=utf-8", STYLE_CSS) }),
        )
        .route("/api/state", get(state))
        .route("/api/settings", post(settings))
        .route("/api/events", get(events))
        .route("/api/spectrum", get(spectrum))
        .route("/api/save", get(save))
        .fallback(|| async { error(StatusCode::NOT_FOUND, "no such page") })
        .with_state(app)
}

fn html(text: &'static str) -> Response {
    asset("text/html; charset=utf-8", text)
}

fn asset(content_type: &'static str, text: &'static str) -> Response {
    ([(header::CONTENT_TYPE, content_type)], text).into_response()
}

/// A JSON error reply.
fn error(status: StatusCode, message: impl Into<String>) -> Response {
    let body = json!({ "error": message.into() });
    (status, axum::Json(body)).into_response()
}

/// `GET /api/state`.
async fn state(State(app): State<Arc<App>>) -> Response {
    let (settings, generation) = {
        let job = app.shared.job();
        (job.settings.clone(), job.generation)
    };
    let latest = match &*app.shared.updates.borrow() {
        Update::Frame(frame) => json!({ "generation": frame.generation, "passes": frame.passes }),
        _ => serde_json::Value::Null,
    };
    axum::Json(json!({
        "settings": settings,
        "generation": generation,
        "latest_frame": latest,
        "viewers": app.shared.viewers.load(Ordering::SeqCst),
        "scenes": app.scenes,
        "illuminants": illuminant_names(),
        "observers": observer_names(),
        "render_command": render_command(&settings),
    }))
    .into_response()
}

/// The `fspec render` line of `settings`, when one renders the same image
/// (the page's camera, a relit scene and a split view have no flag).
fn render_command(settings: &crate::view::settings::ViewSettings) -> Option<String> {
    (settings.camera.is_none() && settings.illuminant.is_none() && settings.split.is_none())
        .then(|| format!("fspec render {}", settings.render_args().join(" ")))
}

/// `POST /api/settings`.
async fn settings(State(app): State<Arc<App>>, body: Bytes) -> Response {
    let patch: SettingsPatch = match serde_json::from_slice(&body) {
        Ok(patch) => patch,
        Err(e) => return error(StatusCode::BAD_REQUEST, format!("malformed settings: {e}")),
    };
    let shared = &app.shared;
    let (generation, change) = {
        let mut job = shared.job();
        let (next, change) = match job
            .settings
            .apply(&patch, &app.scenes, app.memory_limit_bytes)
        {
            Ok(applied) => applied,
            Err(e) => return error(StatusCode::BAD_REQUEST, e.to_string()),
        };
        job.settings = next.clone();
        match change {
            Change::Render => {
                job.generation += 1;
                job.finished = None;
            }
            Change::Display => {
                // The same image under the new display settings.
                shared.updates.send_modify(|update| {
                    if let Update::Frame(frame) = update {
                        *update = Update::Frame(Arc::new(frame.redisplayed(&next)));
                    }
                });
            }
            Change::None => {}
        }
        (job.generation, change)
    };
    if change == Change::Render {
        shared.wake.notify_all();
    }
    let change = match change {
        Change::None => "none",
        Change::Display => "display",
        Change::Render => "render",
    };
    axum::Json(json!({ "generation": generation, "change": change })).into_response()
}

/// Counts an open event stream while it lives (the driver renders only
/// while some page watches).
struct Viewer(Arc<Shared>);

impl Viewer {
    fn new(shared: Arc<Shared>) -> Self {
        shared.viewers.fetch_add(1, Ordering::SeqCst);
        shared.notify();
        Self(shared)
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        self.0.viewers.fetch_sub(1, Ordering::SeqCst);
        self.0.notify();
    }
}

/// `GET /api/events`: the latest update now, then each new one; ends when
/// the server stops.
async fn events(State(app): State<Arc<App>>) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let viewer = Viewer::new(Arc::clone(&app.shared));
    let updates = app.shared.updates.subscribe();
    let stopping = app.stopping.clone();
    let stream = futures_util::stream::unfold(
        (updates, stopping, viewer, true),
        |(mut updates, mut stopping, viewer, first)| async move {
            if !first {
                tokio::select! {
                    changed = updates.changed() => changed.ok()?,
                    _ = stopping.changed() => return None,
                }
            }
            if *stopping.borrow() {
                return None;
            }
            let update = updates.borrow_and_update().clone();
            let event = event_of(update).await;
            Some((Ok(event), (updates, stopping, viewer, false)))
        },
    );
    Sse::new(stream).keep_alive(KeepAlive::default())
}

/// The event of an update (a frame's PNG encoded off the async threads,
/// once per frame whatever the number of pages).
async fn event_of(update: Update) -> Event {
    match update {
        Update::Nothing => Event::default().event("waiting").data("{}"),
        Update::Error {
            generation,
            message,
        } => Event::default()
            .event("error")
            .data(json!({ "generation": generation, "error": message }).to_string()),
        Update::Frame(frame) => {
            let encoding = Arc::clone(&frame);
            let png = tokio::task::spawn_blocking(move || {
                encoding.encoded.get_or_init(|| encode(&encoding)).clone()
            })
            .await
            .unwrap_or_else(|e| Err(e.to_string()));
            match png {
                Ok(png) => Event::default()
                    .event("frame")
                    .data(frame_json(&frame, &png).to_string()),
                Err(message) => Event::default()
                    .event("error")
                    .data(json!({ "generation": frame.generation, "error": message }).to_string()),
            }
        }
    }
}

/// A frame's PNG in base64.
fn encode(frame: &Frame) -> Result<String, String> {
    let image = XyzImage {
        width: frame.image.width,
        height: frame.image.height,
        xyz: &frame.image.xyz,
    };
    let exposure = Exposure {
        stops: frame.settings.exposure_stops,
    };
    let png = png_bytes(&image, exposure, frame.settings.tone.into())?;
    Ok(base64::engine::general_purpose::STANDARD.encode(png))
}

fn frame_json(frame: &Frame, png: &str) -> serde_json::Value {
    json!({
        "generation": frame.generation,
        "passes": frame.passes,
        "passes_total": frame.passes_total,
        "elapsed_ms": frame.elapsed.as_secs_f64() * 1e3,
        "width": frame.image.width,
        "height": frame.image.height,
        "settings": frame.settings,
        "camera": frame.camera,
        "coefficients": frame.image.coefficients.as_ref().map(|(n, _)| *n),
        "render_command": render_command(&frame.settings),
        "split": frame.split,
        "png": png,
    })
}

/// The latest frame, if any.
fn latest_frame(app: &App) -> Option<Arc<Frame>> {
    match &*app.shared.updates.borrow() {
        Update::Frame(frame) => Some(Arc::clone(frame)),
        _ => None,
    }
}

/// The reply when no frame exists yet.
fn no_frame() -> Response {
    error(StatusCode::CONFLICT, "no image rendered yet")
}

/// A pixel of the image.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Pixel {
    x: u32,
    y: u32,
}

/// Clears [`App::probing`] when a probe ends, however it ends.
struct ProbeTurn<'a>(&'a AtomicBool);

impl Drop for ProbeTurn<'_> {
    fn drop(&mut self) {
        self.0.store(false, Ordering::SeqCst);
    }
}

/// `GET /api/spectrum?x=&y=`.
async fn spectrum(
    State(app): State<Arc<App>>,
    pixel: Result<Query<Pixel>, QueryRejection>,
) -> Response {
    let Ok(Query(Pixel { x, y })) = pixel else {
        return error(
            StatusCode::BAD_REQUEST,
            "expected ?x=COLUMN&y=ROW (whole numbers)",
        );
    };
    let Some(frame) = latest_frame(&app) else {
        return no_frame();
    };
    let image = &frame.image;
    if x >= image.width || y >= image.height {
        return error(
            StatusCode::BAD_REQUEST,
            format!(
                "pixel ({x}, {y}) is outside the {}×{} image",
                image.width, image.height
            ),
        );
    }
    if !frame.probe.is_current() {
        return error(
            StatusCode::CONFLICT,
            "the camera has moved since this image: click the new one",
        );
    }
    if app.probing.swap(true, Ordering::SeqCst) {
        return error(
            StatusCode::TOO_MANY_REQUESTS,
            "another pixel's spectrum is being traced: try again in a moment",
        );
    }
    let traced = {
        let app = Arc::clone(&app);
        let frame = Arc::clone(&frame);
        tokio::task::spawn_blocking(move || {
            let _turn = ProbeTurn(&app.probing);
            frame.probe.trace(x, y)
        })
        .await
    };
    let traced = match traced {
        Ok(Ok(traced)) => traced,
        Ok(Err(e)) => return error(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
        Err(e) => return error(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    };
    let xyz = image.xyz[(y * image.width + x) as usize];
    let range = frame.range;
    let steps = (range.width_nm() / SPECTRUM_STEP_NM).round() as usize;
    let wavelengths: Vec<f64> = (0..=steps)
        .map(|i| range.min_nm() + i as f64 * SPECTRUM_STEP_NM)
        .collect();
    let n = traced.coefficients.len();
    let radiance = spectral_planes(&range, n, &traced.coefficients, &wavelengths);
    let bins = traced.bins;
    axum::Json(json!({
        "x": x,
        "y": y,
        "passes": frame.passes,
        "lambda_nm": wavelengths,
        "radiance": radiance,
        "coefficients": traced.coefficients,
        "fourier_paths": traced.fourier_paths,
        "sampled": {
            "bin_centre_nm": (0..bins.count()).map(|b| bins.centre_nm(b)).collect::<Vec<_>>(),
            "bin_width_nm": bins.width_nm(),
            "radiance": traced.sampled.radiance,
            "std_error": traced.sampled.std_error,
            "paths": traced.sampled.paths,
            "wavelengths_per_path": crate::view::probe::PROBE_WAVELENGTHS,
            "sampling": traced.sampling,
        },
        "xyz": [xyz.x, xyz.y, xyz.z],
    }))
    .into_response()
}

/// `?format=` of a download.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SaveFormat {
    format: String,
}

/// Names of temporary EXR files (one per download).
static DOWNLOADS: AtomicU64 = AtomicU64::new(0);

/// `GET /api/save?format=png|exr|spectral`.
async fn save(
    State(app): State<Arc<App>>,
    format: Result<Query<SaveFormat>, QueryRejection>,
) -> Response {
    let Ok(Query(SaveFormat { format })) = format else {
        return error(StatusCode::BAD_REQUEST, "expected ?format=png|exr|spectral");
    };
    let (name, content_type) = match format.as_str() {
        "png" => ("fspec-view.png", "image/png"),
        "exr" => ("fspec-view.exr", "image/x-exr"),
        "spectral" => ("fspec-view-spectral.exr", "image/x-exr"),
        other => {
            return error(
                StatusCode::BAD_REQUEST,
                format!("format `{other}`: use png, exr or spectral"),
            );
        }
    };
    let Some(frame) = latest_frame(&app) else {
        return no_frame();
    };
    if format == "spectral" && frame.image.coefficients.is_none() {
        return error(
            StatusCode::CONFLICT,
            "a spectral EXR needs the Fourier transport with a spectral buffer",
        );
    }
    let bytes = tokio::task::spawn_blocking(move || file_bytes(&frame, &format))
        .await
        .unwrap_or_else(|e| Err(CliError::input(e.to_string())));
    match bytes {
        Ok(bytes) => (
            [
                (header::CONTENT_TYPE, content_type.to_string()),
                (
                    header::CONTENT_DISPOSITION,
                    format!("attachment; filename=\"{name}\""),
                ),
            ],
            bytes,
        )
            .into_response(),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    }
}

/// The bytes of a download: the PNG as the page shows it, or an EXR
/// written by `fspec render`'s writers to a temporary file and read back.
fn file_bytes(frame: &Frame, format: &str) -> Result<Vec<u8>, CliError> {
    let image = XyzImage {
        width: frame.image.width,
        height: frame.image.height,
        xyz: &frame.image.xyz,
    };
    if format == "png" {
        let exposure = Exposure {
            stops: frame.settings.exposure_stops,
        };
        return png_bytes(&image, exposure, frame.settings.tone.into()).map_err(CliError::input);
    }
    let path: PathBuf = std::env::temp_dir().join(format!(
        "fspec-view-{}-{}.exr",
        std::process::id(),
        DOWNLOADS.fetch_add(1, Ordering::Relaxed)
    ));
    let written = match (&frame.image.coefficients, format) {
        (Some((n, coefficients)), "spectral") => {
            let range = frame.range;
            let steps = (range.width_nm() / SPECTRAL_EXR_STEP_NM).floor() as usize;
            let wavelengths: Vec<f64> = (0..=steps)
                .map(|i| range.min_nm() + i as f64 * SPECTRAL_EXR_STEP_NM)
                .collect();
            let radiance = spectral_planes(&range, *n, coefficients, &wavelengths);
            write_spectral_exr(
                &path,
                image.width,
                image.height,
                &wavelengths,
                &radiance,
                &image,
            )
        }
        _ => write_exr(&path, &image, false),
    };
    let bytes = written.and_then(|()| {
        std::fs::read(&path)
            .map_err(|e| CliError::input(format!("cannot read {}: {e}", path.display())))
    });
    // Best effort: the file may not exist after a failed write.
    let _ = std::fs::remove_file(&path);
    bytes
}
