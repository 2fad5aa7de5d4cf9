//! The render driver: one thread that waits for settings, renders them with
//! `simd_tracer::render::render_observed` on the renderer's own thread pool
//! (the passes, batches and film of `fspec render`), and publishes the
//! image after every batch.
//!
//! The server never waits on the render: a settings change bumps the
//! generation under a mutex held for microseconds and wakes the driver;
//! the render sees it after its current batch (batches aim at
//! [`VIEW_BATCH_TARGET`]) and stops; frames (at most one per
//! [`VIEW_FRAME_INTERVAL`], and always the first and the last pass's) go
//! out through a `watch`
//! channel (the latest replaces the one before, nothing queues), encoded
//! by whoever sends them. The driver also stops when the last page closes
//! (no event stream left) and starts again from pass 0 when one opens.
//!
//! **Split view at equal time** (`render_split`). The left half of the
//! image is rendered with the settings' transport, the right half with
//! the split transport, each as a crop window of the same film (so each
//! half's pixels are that transport's full render's). The halves take
//! turns of at most [`SPLIT_SLICE`], each resuming its own film state
//! (`PassJob::resume`), and each is charged the wall time of its whole
//! turn (pool start, film state, resolve included). The rule: the half
//! with less time so far renders next, so at every frame the two times
//! differ by at most one turn; when one half has its `max_passes`, the
//! other renders on until its time is at least as long (or it has its
//! passes too), then the render stops. The page shows each half's passes
//! and seconds. Control variates are refused in a split view: their film
//! weights each pass by `α` from all earlier passes and cannot resume.

use crate::error::CliError;
use crate::render_cmd::{self, TransportBasis, TransportSpec, TransportTask};
use crate::scene_file::MitsubaOptions;
use crate::scene_source::{SceneDefaults, resolve_scene};
use crate::sensor_file::ObserverChoice;
use crate::view::probe::ProbeScene;
use crate::view::settings::{ViewSettings, illuminant_source};
use simd_tracer::render::{
    FilmState, Observer, PartialImage, PassJob, PixelWindow, Progress, RenderResult,
    RenderSettings, ResolvePartial,
};
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::SceneOptions;
use simd_tracer::scene::camera::{Camera, Projection};
use simd_tracer::transport::Transport;
use spectral_core::SpectralRange;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock, PoisonError, RwLock};
use std::time::{Duration, Instant};
use tokio::sync::watch;

/// Wall time a batch of the viewer's render aims at: a change stops the
/// render within about this long (plus one pass), and frames come this
/// often. A tenth of a second is where a restart still feels immediate.
pub const VIEW_BATCH_TARGET: Duration = Duration::from_millis(100);

/// Shortest time between two frames of one render (its first and last
/// frames aside): a frame costs a resolve of the film on the driver thread
/// (the render's pool waits) and a PNG encoding beside it, about 75 ms of
/// CPU at 512² with 12 coefficients (docs/performance.md), so frames at
/// every 0.1 s batch would take most of a 2-core machine.
pub const VIEW_FRAME_INTERVAL: Duration = Duration::from_millis(250);

/// A frame's resolve may take at most this share of the render's time:
/// the interval between frames grows to this many times the last
/// resolve's duration when that exceeds [`VIEW_FRAME_INTERVAL`].
const RESOLVE_SHARE_INVERSE: u32 = 4;

/// Longest turn of one half of a split view (module docs): a frame comes
/// after every turn, so turns last as long as the interval between frames.
pub const SPLIT_SLICE: Duration = VIEW_FRAME_INTERVAL;

/// The camera a frame was rendered with, for the page to move it from.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CameraView {
    /// Centre of projection.
    pub position: [f32; 3],
    /// Unit viewing direction.
    pub forward: [f32; 3],
    /// Unit image up.
    pub up: [f32; 3],
    /// Field of view along the smaller axis, degrees.
    pub fov_deg: f32,
    /// The scene camera's up: the axis the page orbits about.
    pub world_up: [f32; 3],
    /// Distance to the centre of the scene's bounds (the orbit pivot).
    pub pivot_distance: f32,
}

/// One published image.
#[derive(Debug)]
pub struct Frame {
    /// The settings generation it belongs to.
    pub generation: u64,
    /// Passes in it.
    pub passes: u32,
    /// Passes the render will take.
    pub passes_total: u32,
    /// Render time so far.
    pub elapsed: Duration,
    /// The image so far.
    pub image: Arc<PartialImage>,
    /// The scene's spectral range (for spectra of pixels).
    pub range: SpectralRange,
    /// The settings it was rendered with (exposure and tone as of its
    /// publication).
    pub settings: ViewSettings,
    /// The camera it was rendered with.
    pub camera: CameraView,
    /// The PNG, base64, made once by the first stream that sends it.
    pub encoded: OnceLock<Result<String, String>>,
    /// Each half's passes and time in a split view.
    pub split: Option<SplitProgress>,
    /// The scene and settings it was rendered with, for a pixel's spectrum.
    pub probe: Arc<ProbeScene>,
}

/// One half of a split view as the page sees it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HalfProgress {
    /// Its transport.
    pub transport: TransportSpec,
    /// Passes (samples per pixel) so far.
    pub passes: u32,
    /// Wall time charged to it so far, seconds.
    pub seconds: f64,
}

/// Both halves of a split view.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SplitProgress {
    /// The settings' transport.
    pub left: HalfProgress,
    /// The split transport.
    pub right: HalfProgress,
    /// Whether the render has stopped (module docs' rule).
    pub done: bool,
}

impl Frame {
    /// The same image under other display settings (not yet encoded).
    pub fn redisplayed(&self, settings: &ViewSettings) -> Self {
        Self {
            generation: self.generation,
            passes: self.passes,
            passes_total: self.passes_total,
            elapsed: self.elapsed,
            image: Arc::clone(&self.image),
            range: self.range,
            settings: ViewSettings {
                exposure_stops: settings.exposure_stops,
                tone: settings.tone,
                ..self.settings.clone()
            },
            camera: self.camera,
            encoded: OnceLock::new(),
            split: self.split,
            probe: Arc::clone(&self.probe),
        }
    }
}

/// What the page is told.
#[derive(Debug, Clone, Default)]
pub enum Update {
    /// Nothing rendered yet.
    #[default]
    Nothing,
    /// The latest image.
    Frame(Arc<Frame>),
    /// The render of a generation failed (one line).
    Error {
        /// Its generation.
        generation: u64,
        /// Why.
        message: String,
    },
}

/// The settings and where the driver stands.
#[derive(Debug)]
pub struct Job {
    /// Current settings.
    pub settings: ViewSettings,
    /// Bumped by every change that restarts the render.
    pub generation: u64,
    /// The last generation rendered to its end (or failed): nothing to do
    /// until the generation changes.
    pub finished: Option<u64>,
}

/// State shared by the server and the driver.
#[derive(Debug)]
pub struct Shared {
    /// Settings and generation.
    pub job: Mutex<Job>,
    /// Wakes the driver (a change, a page opening or closing, shutdown).
    pub wake: Condvar,
    /// Open event streams (pages).
    pub viewers: AtomicUsize,
    /// Set once to stop everything.
    pub stopping: AtomicBool,
    /// The latest frame or error.
    pub updates: watch::Sender<Update>,
    /// The render's options that the page does not change.
    pub options: DriverOptions,
}

/// Options of the driver fixed at start.
#[derive(Debug, Clone)]
pub struct DriverOptions {
    /// Render threads (default: all cores).
    pub threads: Option<usize>,
    /// Mitsuba scene parameters and leniency.
    pub mitsuba: MitsubaOptions,
}

impl Shared {
    /// The job, even if a thread panicked while holding it (the settings
    /// are replaced whole, never left half-written).
    pub fn job(&self) -> MutexGuard<'_, Job> {
        self.job.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Wakes the driver after a change of the job, the viewers or
    /// `stopping`.
    pub fn notify(&self) {
        // Taking the lock orders the change before the driver's check.
        drop(self.job());
        self.wake.notify_all();
    }

    fn should_stop(&self, generation: u64) -> bool {
        self.stopping.load(Ordering::SeqCst)
            || self.viewers.load(Ordering::SeqCst) == 0
            || self.job().generation != generation
    }
}

/// The scene of some settings, built once per scene and illuminant.
struct BuiltScene {
    key: (String, Option<String>),
    /// Shared with the frames' probes, which read it beside the render;
    /// only setting the camera between renders writes it.
    scene: Arc<RwLock<Scene>>,
    defaults: SceneDefaults,
    camera: Camera,
    centre: glam::Vec3,
}

/// Builds `name` (relit by `illuminant`) as `fspec render` would.
fn build_scene(
    name: &str,
    illuminant: Option<&str>,
    mitsuba: &MitsubaOptions,
) -> Result<BuiltScene, CliError> {
    let (mut builder, defaults, _warnings) =
        resolve_scene(name, &SceneOptions::default(), mitsuba)?;
    if let Some(illuminant) = illuminant {
        let source = illuminant_source(illuminant)?;
        builder
            .relight(illuminant, &source)
            .map_err(|e| CliError::input(format!("{name}: {e}")))?;
    }
    let scene = builder
        .build()
        .map_err(|e| CliError::input(format!("{name}: {e}")))?;
    let (mut lo, mut hi) = (
        glam::Vec3::splat(f32::INFINITY),
        glam::Vec3::splat(f32::NEG_INFINITY),
    );
    for triangle in scene.triangles().iter() {
        for v in triangle {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    let camera = *scene.camera();
    let centre = if lo.cmple(hi).all() {
        0.5 * (lo + hi)
    } else {
        camera.position() + camera.axes().forward
    };
    Ok(BuiltScene {
        key: (name.to_string(), illuminant.map(String::from)),
        scene: Arc::new(RwLock::new(scene)),
        defaults,
        camera,
        centre,
    })
}

/// Runs the driver until `shared.stopping`.
pub fn run(shared: &Shared) {
    let mut built: Option<BuiltScene> = None;
    loop {
        let (settings, generation) = {
            let mut job = shared.job();
            loop {
                if shared.stopping.load(Ordering::SeqCst) {
                    return;
                }
                let idle = shared.viewers.load(Ordering::SeqCst) == 0
                    || job.finished == Some(job.generation);
                if !idle {
                    break;
                }
                job = shared
                    .wake
                    .wait(job)
                    .unwrap_or_else(PoisonError::into_inner);
            }
            (job.settings.clone(), job.generation)
        };
        match render_generation(shared, &mut built, &settings, generation) {
            Ok(completed) => {
                if completed {
                    let mut job = shared.job();
                    if job.generation == generation {
                        job.finished = Some(generation);
                    }
                }
            }
            Err(error) => {
                shared.updates.send_replace(Update::Error {
                    generation,
                    message: error.to_string(),
                });
                let mut job = shared.job();
                if job.generation == generation {
                    job.finished = Some(generation);
                }
            }
        }
    }
}

/// The observer of `settings`: the page's choice, else the scene's (as
/// `fspec render` chooses), else CIE 1931 2°.
fn observer_of(
    settings: &ViewSettings,
    defaults: &SceneDefaults,
) -> Result<spectral_core::observer::Observer, CliError> {
    let choice = match &settings.observer {
        Some(name) => ObserverChoice::standard(name)?,
        None => defaults.render.observer.clone().unwrap_or_default(),
    };
    choice.observer()
}

/// The scene's camera moved to where the page put it (`page`, a
/// perspective pinhole of the field of view the page was sent): the
/// scene camera's projection, lens (the same aperture and distance to the
/// plane in focus), film shift and clip planes are kept. The page's field
/// of view of an orthographic camera is only its unit of panning
/// ([`page_fov_deg`]).
fn moved_camera(page: Camera, scene: &Camera) -> Result<Camera, CliError> {
    scene
        .with_axes(page.axes())
        .map_err(|e| CliError::input(format!("camera: {e}")))
}

/// The distance of the page's orbit pivot: the scene's centre's, at least
/// a little above 0 and, for an orthographic camera, at least its view
/// size, so that [`page_fov_deg`] stays below 2 atan(1/2) ≈ 53° (a camera
/// at the centre would give 180°, which the page's camera refuses).
fn page_pivot_distance(camera: &Camera, distance_to_centre: f32) -> f32 {
    let floor = match camera.projection() {
        Projection::Perspective { .. } => f32::EPSILON,
        Projection::Orthographic { view_size } => view_size,
    };
    distance_to_centre.max(floor)
}

/// The field of view the page works with: a perspective camera's, and for
/// an orthographic one the angle its view size subtends at the orbit's
/// pivot, so that dragging moves the scene with the pointer there too.
fn page_fov_deg(camera: &Camera, pivot_distance: f32) -> f32 {
    match camera.projection() {
        Projection::Perspective { fov_deg } => fov_deg,
        Projection::Orthographic { view_size } => {
            (2.0 * (0.5 * view_size / pivot_distance).atan()).to_degrees()
        }
    }
}

/// Renders one generation; `Ok(true)` when it took all its passes.
fn render_generation(
    shared: &Shared,
    built: &mut Option<BuiltScene>,
    settings: &ViewSettings,
    generation: u64,
) -> Result<bool, CliError> {
    let key = (settings.scene.clone(), settings.illuminant.clone());
    if built.as_ref().is_none_or(|b| b.key != key) {
        *built = None;
        *built = Some(build_scene(
            &settings.scene,
            settings.illuminant.as_deref(),
            &shared.options.mitsuba,
        )?);
    }
    let Some(built) = built.as_mut() else {
        return Err(CliError::input("the scene could not be built"));
    };
    let camera = match &settings.camera {
        Some(spec) => moved_camera(spec.camera()?, &built.camera)?,
        None => built.camera,
    };
    built
        .scene
        .write()
        .unwrap_or_else(PoisonError::into_inner)
        .set_camera(camera);
    let args = settings.parse_render_args()?;
    let mut render_settings = render_cmd::settings_from(&args, &built.defaults)?;
    // The whole film (a scene's crop window is for files), the driver's
    // threads, no time limit: the page stops it.
    render_settings.window = None;
    render_settings.threads = shared.options.threads;
    if matches!(settings.transport, TransportSpec::Cv { .. }) {
        render_settings.film = simd_tracer::film::FilmMode::Sample;
    }
    let axes = camera.axes();
    let pivot_distance = page_pivot_distance(&camera, (built.centre - axes.position).length());
    let view = CameraView {
        position: axes.position.into(),
        forward: axes.forward.into(),
        up: axes.up.into(),
        fov_deg: page_fov_deg(&camera, pivot_distance),
        world_up: built.camera.axes().up.into(),
        pivot_distance,
    };
    let observer = Arc::new(observer_of(settings, &built.defaults)?);
    let scene = built.scene.read().unwrap_or_else(PoisonError::into_inner);
    let context = FrameContext {
        shared,
        view: settings,
        camera: view,
        generation,
        range: scene.range(),
        probe: Arc::new(ProbeScene {
            scene: Arc::clone(&built.scene),
            camera,
            settings: render_settings.clone(),
            transport: settings.transport,
            observer: Arc::clone(&observer),
        }),
    };
    // One density serves both halves of a split view (it is the scene's).
    let lights = match settings.transport.lights_density(&scene, &observer)? {
        Some(density) => Some(density),
        None => match &settings.split {
            Some(right) => right.lights_density(&scene, &observer)?,
            None => None,
        },
    };
    let basis = TransportBasis {
        range: scene.range(),
        observer: &observer,
        density: lights.as_ref(),
    };
    match settings.split {
        None => render_cmd::with_transport(
            &settings.transport,
            basis,
            ViewTask {
                context: &context,
                scene: &scene,
                settings: &render_settings,
            },
        ),
        Some(right) => render_split(&context, &scene, &render_settings, right, basis),
    }
}

/// What every frame of a generation shares.
struct FrameContext<'a> {
    shared: &'a Shared,
    view: &'a ViewSettings,
    camera: CameraView,
    generation: u64,
    range: SpectralRange,
    probe: Arc<ProbeScene>,
}

/// A frame's progress and pixels.
struct FrameImage {
    passes: u32,
    passes_total: u32,
    elapsed: Duration,
    image: PartialImage,
    split: Option<SplitProgress>,
}

impl FrameContext<'_> {
    /// Replaces the latest frame, with exposure and tone as of now (they
    /// change without a restart).
    fn publish(&self, frame: FrameImage) {
        let display = self.shared.job().settings.clone();
        let frame = Frame {
            generation: self.generation,
            passes: frame.passes,
            passes_total: frame.passes_total,
            elapsed: frame.elapsed,
            image: Arc::new(frame.image),
            range: self.range,
            settings: ViewSettings {
                exposure_stops: display.exposure_stops,
                tone: display.tone,
                ..self.view.clone()
            },
            camera: self.camera,
            encoded: OnceLock::new(),
            split: frame.split,
            probe: Arc::clone(&self.probe),
        };
        self.shared
            .updates
            .send_replace(Update::Frame(Arc::new(frame)));
    }
}

/// The render of one generation with the transport's concrete type.
struct ViewTask<'a> {
    context: &'a FrameContext<'a>,
    scene: &'a Scene,
    settings: &'a RenderSettings,
}

impl TransportTask for ViewTask<'_> {
    type Output = bool;

    fn run<T: Transport>(self, transport: &T) -> Result<bool, CliError> {
        let context = self.context;
        let shared = context.shared;
        let mut published_last = false;
        let mut last_frame: Option<(Instant, Duration)> = None;
        let mut after_batch = |progress: &Progress, resolve: ResolvePartial| {
            if shared.should_stop(context.generation) {
                return false;
            }
            let last_pass = progress.passes_done == progress.passes_total;
            if let Some((at, resolve_took)) = last_frame {
                let interval = VIEW_FRAME_INTERVAL.max(resolve_took * RESOLVE_SHARE_INVERSE);
                if !last_pass && at.elapsed() < interval {
                    return true;
                }
            }
            published_last = last_pass;
            let resolving = Instant::now();
            let image = resolve();
            last_frame = Some((resolving, resolving.elapsed()));
            context.publish(FrameImage {
                passes: progress.passes_done,
                passes_total: progress.passes_total,
                elapsed: progress.elapsed,
                image,
                split: None,
            });
            true
        };
        let observer = Observer {
            batch_target: VIEW_BATCH_TARGET,
            after_batch: &mut after_batch,
        };
        simd_tracer::render::render_observed(
            transport,
            self.scene,
            self.settings,
            &PassJob::default(),
            observer,
        )
        .map_err(|e| CliError::input(e.to_string()))?;
        // Finished only if the page saw the last pass (not stopped just
        // before publishing it).
        Ok(published_last)
    }
}

/// One half of a split view while it renders.
#[derive(Debug)]
struct Half {
    transport: TransportSpec,
    window: PixelWindow,
    /// Its film after its last turn.
    state: Option<FilmState>,
    passes: u32,
    /// Wall time of its turns.
    spent: Duration,
}

impl Half {
    fn progress(&self) -> HalfProgress {
        HalfProgress {
            transport: self.transport,
            passes: self.passes,
            seconds: self.spent.as_secs_f64(),
        }
    }
}

/// The equal-time rule (module docs): the half to render next and how
/// long its turn may be, or `None` when the split render is done.
fn next_turn(halves: &[Half; 2], max_passes: u32) -> Option<(usize, Duration)> {
    let finished = |h: &Half| h.passes >= max_passes;
    let [left, right] = halves;
    match (finished(left), finished(right)) {
        (true, true) => None,
        (false, false) => Some((usize::from(right.spent < left.spent), SPLIT_SLICE)),
        (true, false) => {
            (right.spent < left.spent).then(|| (1, (left.spent - right.spent).min(SPLIT_SLICE)))
        }
        (false, true) => {
            (left.spent < right.spent).then(|| (0, (right.spent - left.spent).min(SPLIT_SLICE)))
        }
    }
}

/// Renders a split view (module docs); `Ok(true)` when it finished.
fn render_split(
    context: &FrameContext,
    scene: &Scene,
    settings: &RenderSettings,
    right: TransportSpec,
    basis: TransportBasis,
) -> Result<bool, CliError> {
    let (width, height) = (settings.width, settings.height);
    let left_width = width / 2;
    let half = |transport, x, width| Half {
        transport,
        window: PixelWindow {
            x,
            y: 0,
            width,
            height,
        },
        state: None,
        passes: 0,
        spent: Duration::ZERO,
    };
    let mut halves = [
        half(context.view.transport, 0, left_width),
        half(right, left_width, width - left_width),
    ];
    let mut xyz = vec![spectral_core::color::Xyz::default(); (width * height) as usize];
    while let Some((next, budget)) = next_turn(&halves, settings.spp) {
        if context.shared.should_stop(context.generation) {
            return Ok(false);
        }
        let half = &mut halves[next];
        let windowed = RenderSettings {
            window: Some(half.window),
            ..settings.clone()
        };
        let started = Instant::now();
        let (result, state) = render_cmd::with_transport(
            &half.transport,
            basis,
            TurnTask {
                shared: context.shared,
                generation: context.generation,
                scene,
                settings: &windowed,
                resume: half.state.as_ref(),
                budget,
            },
        )?;
        half.spent += started.elapsed();
        half.passes = state.passes.end;
        half.state = Some(state);
        let window = half.window;
        for (row, pixels) in result.xyz.chunks_exact(window.width as usize).enumerate() {
            let start = (window.y as usize + row) * width as usize + window.x as usize;
            xyz[start..start + pixels.len()].copy_from_slice(pixels);
        }
        let done = next_turn(&halves, settings.spp).is_none();
        let [left, right] = &halves;
        context.publish(FrameImage {
            passes: left.passes.max(right.passes),
            passes_total: settings.spp,
            elapsed: left.spent + right.spent,
            image: PartialImage {
                width,
                height,
                xyz: xyz.clone(),
                coefficients: None,
            },
            split: Some(SplitProgress {
                left: left.progress(),
                right: right.progress(),
                done,
            }),
        });
    }
    Ok(true)
}

/// One turn of a split view's half: its window's passes from its saved
/// film on, until `budget` has passed (after at least one batch).
struct TurnTask<'a> {
    shared: &'a Shared,
    generation: u64,
    scene: &'a Scene,
    settings: &'a RenderSettings,
    resume: Option<&'a FilmState>,
    budget: Duration,
}

impl TransportTask for TurnTask<'_> {
    type Output = (RenderResult, FilmState);

    fn run<T: Transport>(self, transport: &T) -> Result<Self::Output, CliError> {
        let mut after_batch = |progress: &Progress, _: ResolvePartial| {
            !self.shared.should_stop(self.generation) && progress.elapsed < self.budget
        };
        let observer = Observer {
            batch_target: VIEW_BATCH_TARGET,
            after_batch: &mut after_batch,
        };
        let job = PassJob {
            first_pass: 0,
            resume: self.resume,
            keep_state: true,
            xyz_only: false,
        };
        let (result, state) = simd_tracer::render::render_observed(
            transport,
            self.scene,
            self.settings,
            &job,
            observer,
        )
        .map_err(|e| CliError::input(e.to_string()))?;
        let state = state.ok_or_else(|| CliError::input("the split view's film kept no state"))?;
        Ok((result, state))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render_cmd::Sampling;

    fn half(passes: u32, spent_ms: u64) -> Half {
        Half {
            transport: TransportSpec::Sampled {
                wavelengths: 4,
                sampling: Sampling::Hero,
            },
            window: PixelWindow::full(1, 1),
            state: None,
            passes,
            spent: Duration::from_millis(spent_ms),
        }
    }

    /// The page pans by `2 tan(fov/2) · pivot distance` per film: for an
    /// orthographic camera that is its view size, so a drag moves the
    /// scene with the pointer. A moved orthographic camera stays one.
    #[test]
    fn orthographic_cameras_pan_by_their_view_size_and_stay_orthographic() {
        let ortho = Camera::look_at_with(
            glam::Vec3::new(0.0, 0.0, 5.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
            Projection::Orthographic { view_size: 3.0 },
        )
        .unwrap();
        let pivot = page_pivot_distance(&ortho, 4.0);
        assert_eq!(pivot, 4.0);
        let fov = page_fov_deg(&ortho, pivot);
        let panned_size = 2.0 * (0.5 * fov).to_radians().tan() * pivot;
        assert!((panned_size - 3.0).abs() < 1e-5, "{panned_size}");
        let page = Camera::look_at(
            glam::Vec3::new(1.0, 0.0, 5.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
            fov,
        )
        .unwrap();
        let moved = moved_camera(page, &ortho).unwrap();
        assert_eq!(moved.projection(), ortho.projection());
        assert!((moved.position() - page.position()).length() < 1e-6);
        // At the scene's centre the pivot moves out to the view size.
        let centred = page_pivot_distance(&ortho, 0.0);
        assert_eq!(centred, 3.0);
        assert!(page_fov_deg(&ortho, centred) < 54.0);
        let perspective =
            Camera::look_at(glam::Vec3::Z, glam::Vec3::ZERO, glam::Vec3::Y, 35.0).unwrap();
        assert_eq!(page_fov_deg(&perspective, pivot), 35.0);
    }

    #[test]
    fn the_half_with_less_time_goes_next_until_both_had_equal_time() {
        let ms = Duration::from_millis;
        // Both running: the one behind, the left on a tie.
        assert_eq!(
            next_turn(&[half(0, 0), half(0, 0)], 8),
            Some((0, SPLIT_SLICE))
        );
        assert_eq!(
            next_turn(&[half(3, 300), half(9, 250)], 16),
            Some((1, SPLIT_SLICE))
        );
        assert_eq!(
            next_turn(&[half(3, 200), half(9, 250)], 16),
            Some((0, SPLIT_SLICE))
        );
        // The left has its passes: the right catches up, no longer than
        // the gap.
        assert_eq!(
            next_turn(&[half(8, 300), half(2, 250)], 8),
            Some((1, ms(50)))
        );
        assert_eq!(
            next_turn(&[half(8, 900), half(2, 250)], 8),
            Some((1, SPLIT_SLICE))
        );
        // ... and then the render stops.
        assert_eq!(next_turn(&[half(8, 300), half(4, 310)], 8), None);
        assert_eq!(next_turn(&[half(5, 400), half(8, 300)], 8), None);
        assert_eq!(next_turn(&[half(8, 100), half(8, 900)], 8), None);
    }
}
