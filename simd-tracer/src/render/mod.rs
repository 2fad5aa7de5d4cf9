//! Progressive rendering: passes of one sample per pixel over 32 × 32 tiles
//! in parallel (rayon), packets of 8 pixels (4 × 2), traced
//! [`crate::integrator::GROUP`] packets at a time (their bounce and shadow
//! rays compacted, [`crate::integrator::compaction`]). Passes run in
//! batches: each tile takes every pass of a batch in a row, so its pixels
//! stay in cache (a 512² Fourier film is 32 MiB; one pass at a time streamed
//! it through memory every pass). A batch is one pass for transports whose
//! passes interact (control variates end every pass over all pixels) and
//! otherwise as many passes as fit in half a second at the measured speed,
//! up to 16.
//!
//! Determinism: every sample draws its random numbers from streams keyed by
//! (seed, pixel, pass) ([`crate::sampling::rng`]), the filter is importance-sampled so
//! a sample only touches its own pixel (splatting: below), and each tile is
//! owned by one task per pass: the image depends only on the seed, never on the thread count
//! or scheduling (tested bit for bit).
//!
//! **Splatting** ([`RenderSettings::film`] = [`FilmMode::Splat`], Mitsuba's
//! film): a sample, placed uniformly in its pixel, adds `w·L` and `w` to
//! every pixel within the filter's margin `M`
//! ([`Filter::splat_margin_px`]). Its camera ray is the box filter's (the
//! same offsets, so a box splat equals a box-sampled render bit for bit,
//! tested). A sample now touches pixels of neighbouring tiles, which other
//! tasks own, and `f64` addition is not associative, so the order in which
//! a pixel's contributions are added must not depend on scheduling:
//!
//! * each tile splats into its own pixels directly and into a ring of its
//!   own for the rest of its apron (the tile grown by `M` on every side,
//!   less the tile), in the fixed order of its packets and lanes; the ring
//!   is emptied before every pass;
//! * films whose sums are linear in the samples (the Fourier and hybrid
//!   films: [`Film::scratch_len`]) gather a pass's splats over the tile's
//!   whole apron in an `f32` scratch first and add it to the tile's
//!   pixels and ring once at the end of the pass, in apron order: a pixel
//!   receives about `(2M + 1)²` splats a pass, which round in `f32` at
//!   about that many `ε` of their size (bound tested), and the splat's
//!   inner loop then runs on `4 (N + 1)` bytes a pixel instead of
//!   `8 (N + 1)`. The order is still fixed by the pass, tile and lane;
//! * after every pass the rings are added into the film's pixels: each
//!   tile (in parallel) adds, pixel by pixel, the rings that cover it in
//!   the fixed order of the tiles (row-major on the film's tile grid).
//!
//! A pixel's sum is thus `(…((S + s₁) + s₂) … + r₁) + r₂ …)` over passes:
//! its own tile's splats in their order, then the other tiles' rings in
//! theirs, whatever the thread count and whatever the batch sizes, which
//! the measured speed sets and only the progress callback sees: the flush
//! happens per pass inside a batch, never per batch. Per pass rather than
//! per group of passes: a group would need its passes aligned to absolute
//! pass indices so that `--passes` ranges and resumed renders stop at its
//! edges. The flush is one `f64` add per value of the ring, about
//! `(1 + 2M/T)² − 1` of the film per pass for tiles of `T` × `T` pixels,
//! and the rings cost that much memory beside the film: 0.27 of it with
//! the default Gaussian (`M` = 2) and `T` = [`TILE_SIZE`] = 32, against
//! 0.56 with tiles of 16, whose rings' clearing and flush took a twentieth
//! of a Cornell-box render (`docs/performance.md`). Whole aprons, tile
//! included, cost 1.56 of it at `T` = 16, the largest part of a small
//! scene's peak memory, and a clearing and a flush of the tile's own
//! pixels every pass.
//!
//! A cropped splat render traces the window grown by `M` (on the packet
//! grid, clipped to the film) and flushes into the window only. A window
//! pixel's contributions are the full render's, in the same order: the
//! samples that reach it are all traced, the cut tiles keep the full
//! tiles' order of their packets (`packet_origins`: squares on the
//! film's grid), and a tile of the full render missing from the crop
//! holds no sample that reaches the window (adding its zeros would change
//! no bit: sums start at `+0`, never become `−0`). So crops are exact
//! (tested). Samples are counted (and rejected) in the pixel that traced
//! them, so parts over disjoint windows count each sample once.
//!
//! A crop window ([`RenderSettings::window`], Mitsuba's `hdrfilm`
//! `crop_offset_x/y`, `crop_width/height`) renders part of the film: the
//! camera and the random streams stay those of the full film (streams are
//! keyed by the pixel's index in the full film), tiles and packets stay on
//! the full film's grid, and the result holds the window's pixels only,
//! each equal bit for bit to the same pixel of the full render (tested).
//! A packet (4 × 2 pixels) that straddles the window's edge is traced
//! whole and its outside pixels dropped: a lane's result may depend on its
//! packet-mates (all-Lambert packets shade 8-wide, mixed ones per lane with
//! the scalar forms, which round differently), so a packet is only ever
//! traced as the full render traces it. Rays cast count those lanes too.
//! One exception: control variates with the pooled α
//! ([`crate::film::AlphaMode::Shared`]) pool it over the window's pixels,
//! so their crop is a render of the window, not a cut of the full image
//! (per-pixel α crops bit for bit).
//!
//! A render may also cover a range of passes of the seeded sequence, keep
//! its film as plain sums, or continue from such sums ([`PassJob`],
//! [`render_passes`], [`FilmState`]): parts of a frame rendered apart,
//! over disjoint windows or pass ranges, merge into the frame.
//!
//! After each batch the `progress` callback sees the totals and may stop
//! the render; a time limit stops after the batch that crosses it (batches
//! are sized not to run past the limit at the measured speed). Samples with
//! NaN or infinite values never reach the film: they are counted in
//! [`RenderResult::rejected`].

mod film_state;
mod light_film;

pub use film_state::FilmState;
use light_film::LightFilm;

use crate::film::filter::{Filter, FilterError, MAX_SPLAT_MARGIN_PX};
use crate::film::{Film, FilmMode};
use crate::integrator::light_paths::{FilmHit, LightPathSettings, LightPaths};
use crate::integrator::{
    CausticLanes, GROUP, GroupStart, GroupState, IntegratorSettings, PathContext, RayCounts,
    trace_group, trace_group_from,
};
use crate::packet::RayPacket;
use crate::sampling::disk::concentric_disk_x8;
use crate::sampling::sampler::{LENS_FIRST, PIXEL_X, PIXEL_Y, PassKeys, PathSampler, SamplerKind};
use crate::scene::Scene;
use crate::simd::Vec3x8;
use crate::simd::{LANES, LaneMask};
use crate::transport::{FilmPixel, FilmSample, Transport};
use glam::Vec3;
use rayon::prelude::*;
use spectral_core::color::Xyz;
use std::borrow::Cow;
use std::sync::{Mutex, TryLockError};
use std::time::{Duration, Instant};
use wide::f32x8;

/// Tile edge, pixels: a multiple of the packet's 4 × 2 footprint (a
/// 32 × 32 tile is four [`GROUP`]s of 32 × 8 pixels). Why 32 and not 16:
/// a splatting render's per-pass ring flush and clearing scale with
/// `(1 + 2M/T)² − 1` (module docs), and 32 halves them; a tile's pixels
/// (32² × 136 bytes at N = 16) and its `f32` apron scratch still fit a
/// core's L2, and a 512² image still has 256 tiles to share among the
/// threads.
pub const TILE_SIZE: u32 = 32;

/// Packet footprint: 4 × 2 pixels.
const PACKET_WIDTH: u32 = 4;
const PACKET_HEIGHT: u32 = 2;

/// What and how to render.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel (one per pass).
    pub spp: u32,
    /// Depth and roulette.
    pub integrator: IntegratorSettings,
    /// Seed of every random stream.
    pub seed: u64,
    /// Pixel filter.
    pub filter: Filter,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// Stop after the batch of passes during which this much time has passed.
    pub time_limit: Option<Duration>,
    /// Render only this part of the `width × height` film (`None`: all of
    /// it); the result is the window's size (module docs).
    pub window: Option<PixelWindow>,
    /// Importance-sample the filter or splat (module docs).
    pub film: FilmMode,
    /// Independent or Sobol numbers (`sampling::sampler`).
    pub sampler: SamplerKind,
}

/// A rectangle of the film, pixels: columns `x .. x + width`, rows
/// `y .. y + height`, counted from the top-left of the full film.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelWindow {
    /// First column.
    pub x: u32,
    /// First row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl PixelWindow {
    /// The whole `width × height` film.
    pub fn full(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// One past the last column and row (`u64`: no overflow).
    fn end(&self) -> (u64, u64) {
        (
            u64::from(self.x) + u64::from(self.width),
            u64::from(self.y) + u64::from(self.height),
        )
    }

    /// Whether pixel `(x, y)` of the film lies in the window.
    #[inline]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        let (x_end, y_end) = self.end();
        x >= self.x && y >= self.y && u64::from(x) < x_end && u64::from(y) < y_end
    }

    /// Whether every pixel of `other` lies in this window.
    pub fn covers(&self, other: &PixelWindow) -> bool {
        let (x_end, y_end) = self.end();
        let (other_x_end, other_y_end) = other.end();
        other.x >= self.x && other.y >= self.y && other_x_end <= x_end && other_y_end <= y_end
    }

    /// Pixels in the window.
    pub fn pixel_count(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// The window if it is non-empty and inside a `width × height` film.
    pub fn validate(self, width: u32, height: u32) -> Result<Self, RenderError> {
        let (x_end, y_end) = self.end();
        if self.width == 0
            || self.height == 0
            || x_end > u64::from(width)
            || y_end > u64::from(height)
        {
            return Err(RenderError::Window {
                window: self,
                width,
                height,
            });
        }
        Ok(self)
    }

    /// The window grown by `margin` pixels on every side, clipped to a
    /// `width × height` film.
    fn grown(self, margin: u32, width: u32, height: u32) -> Self {
        let (x_end, y_end) = self.end();
        let (x, y) = (self.x.saturating_sub(margin), self.y.saturating_sub(margin));
        // Clipped to the film, whose sides are `u32`.
        let x_end = (x_end + u64::from(margin)).min(u64::from(width)) as u32;
        let y_end = (y_end + u64::from(margin)).min(u64::from(height)) as u32;
        Self {
            x,
            y,
            width: x_end - x,
            height: y_end - y,
        }
    }

    /// The window grown outwards to whole packets of the film's packet
    /// grid (4 × 2 pixels from the film's corner), clipped to the film:
    /// the pixels a cropped render traces.
    fn to_packet_grid(self, width: u32, height: u32) -> Self {
        let (x_end, y_end) = self.end();
        let (x, y) = (
            self.x / PACKET_WIDTH * PACKET_WIDTH,
            self.y / PACKET_HEIGHT * PACKET_HEIGHT,
        );
        let x_end = x_end.div_ceil(u64::from(PACKET_WIDTH)) * u64::from(PACKET_WIDTH);
        let y_end = y_end.div_ceil(u64::from(PACKET_HEIGHT)) * u64::from(PACKET_HEIGHT);
        // Clipped to the film, whose sides are `u32`.
        let x_end = x_end.min(u64::from(width)) as u32;
        let y_end = y_end.min(u64::from(height)) as u32;
        Self {
            x,
            y,
            width: x_end - x,
            height: y_end - y,
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            spp: 16,
            integrator: IntegratorSettings::default(),
            seed: 0,
            filter: Filter::gaussian(),
            threads: None,
            time_limit: None,
            window: None,
            film: FilmMode::Sample,
            sampler: SamplerKind::default(),
        }
    }
}

impl RenderSettings {
    /// The pixels rendered: the window, or the whole film.
    pub fn film_window(&self) -> PixelWindow {
        self.window
            .unwrap_or_else(|| PixelWindow::full(self.width, self.height))
    }
}

/// Why a render could not run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RenderError {
    /// Width, height or samples per pixel is zero.
    EmptyImage,
    /// The thread pool could not be created.
    Threads(String),
    /// A filter parameter is out of range.
    Filter(FilterError),
    /// A filter with negative lobes on the sampling film, which draws
    /// offsets from the filter as a density.
    SampledNegativeLobes,
    /// The transport's film cannot render a range of passes apart or keep
    /// its state (control variates weight each pass by all earlier ones).
    NotSplittable,
    /// A film state to continue from does not fit the render (why).
    State(String),
    /// The transport's film cannot splat (control variates weight each
    /// pass by `α` from the earlier ones; their pixels are no weighted
    /// sums).
    CannotSplat,
    /// The crop window is empty or leaves the film.
    Window {
        /// The window asked for.
        window: PixelWindow,
        /// Film width, pixels.
        width: u32,
        /// Film height, pixels.
        height: u32,
    },
}

impl core::fmt::Display for RenderError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::EmptyImage => write!(f, "width, height and samples per pixel must be at least 1"),
            Self::Threads(e) => write!(f, "cannot start worker threads: {e}"),
            Self::Filter(e) => write!(f, "{e}"),
            Self::SampledNegativeLobes => write!(
                f,
                "the filter has negative lobes, which cannot be drawn as sample offsets: render it with the splatting film (--film splat, the default but with control variates)"
            ),
            Self::NotSplittable => write!(
                f,
                "control variates weight each pass by every earlier pass: this transport cannot render a range of passes apart, continue a render or keep its film"
            ),
            Self::State(why) => write!(f, "the film state to continue from does not fit: {why}"),
            Self::CannotSplat => write!(
                f,
                "control variates weight each pass by every earlier pass: their film cannot splat samples into neighbouring pixels (use the importance-sampled filter)"
            ),
            Self::Window {
                window,
                width,
                height,
            } => write!(
                f,
                "crop window {}×{} at ({}, {}) must be non-empty and inside the {width}×{height} film",
                window.width, window.height, window.x, window.y
            ),
        }
    }
}

impl std::error::Error for RenderError {}

/// Render progress after a batch of passes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Passes finished.
    pub passes_done: u32,
    /// Passes requested.
    pub passes_total: u32,
    /// Samples traced so far.
    pub samples: u64,
    /// Time since the start.
    pub elapsed: Duration,
}

/// A finished render.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderResult {
    /// Width, pixels (the window's when cropped).
    pub width: u32,
    /// Height, pixels (the window's when cropped).
    pub height: u32,
    /// XYZ per pixel of the window (or film), row-major from its top-left.
    pub xyz: Vec<Xyz>,
    /// Mean Fourier coefficients per pixel (`N` per pixel, row-major), when
    /// the transport keeps a spectral buffer.
    pub coefficients: Option<(usize, Vec<f32>)>,
    /// Passes completed (samples per pixel actually taken).
    pub passes: u32,
    /// Samples traced.
    pub samples: u64,
    /// Samples rejected for NaN or infinite values.
    pub rejected: u64,
    /// Rays cast.
    pub rays: RayCounts,
    /// Wall time.
    pub elapsed: Duration,
}

struct Tile<P> {
    x0: u32,
    y0: u32,
    width: u32,
    height: u32,
    pixels: Vec<P>,
    /// Splatting: the current pass's splats over the tile grown by the
    /// margin `M` on every side but outside the tile, laid out by
    /// [`Ring`] (module docs); empty when sampling.
    ring: Vec<P>,
    rejected: u64,
    rays: RayCounts,
}

impl<P> Tile<P> {
    /// The tile's pixels inside `window`, with their film coordinates.
    fn window_pixels<'a>(
        &'a self,
        window: &'a PixelWindow,
    ) -> impl Iterator<Item = ((u32, u32), &'a P)> + 'a {
        self.pixels
            .iter()
            .enumerate()
            .filter_map(move |(index, pixel)| {
                let (x, y) = (
                    self.x0 + index as u32 % self.width,
                    self.y0 + index as u32 / self.width,
                );
                window.contains(x, y).then_some(((x, y), pixel))
            })
    }
}

/// The camera rays of a packet: lane `l` goes through pixel `lanes[l]` of
/// `tile` (inactive where `None`) at an offset drawn from the filter
/// (splatting: uniform in the pixel, the box's) with the lane's path
/// stream (two numbers, x then y; a thin lens then draws its aperture
/// point from two more), all 8 lanes at once, cut to the camera's clip
/// planes; with the offsets from the pixels' centres, px.
fn camera_packet<P>(
    scene: &Scene,
    settings: &RenderSettings,
    tile: &Tile<P>,
    lanes: &[Option<(u32, u32)>; LANES],
    path_rngs: &mut PathSampler,
) -> (RayPacket, [f32x8; 2]) {
    // Drawn in every lane; lanes without a pixel are never read again.
    let (u, v) = (path_rngs.draw(PIXEL_X), path_rngs.draw(PIXEL_Y));
    let mut pixel_x = [0.0f32; LANES];
    let mut pixel_y = [0.0f32; LANES];
    let mut active = LaneMask::NONE;
    for (lane, slot) in lanes.iter().enumerate() {
        if let Some((lx, ly)) = *slot {
            pixel_x[lane] = (tile.x0 + lx) as f32 + 0.5;
            pixel_y[lane] = (tile.y0 + ly) as f32 + 0.5;
            active = active.with(lane);
        }
    }
    let (dx, dy) = match settings.film {
        FilmMode::Sample => settings.filter.sample_offset_x8(u, v),
        FilmMode::Splat => Filter::Box.sample_offset_x8(u, v),
    };
    let camera = scene.camera();
    let (origin, direction) = camera.film_ray_x8(
        f32x8::new(pixel_x) + dx,
        f32x8::new(pixel_y) + dy,
        settings.width,
        settings.height,
    );
    let (origin, direction) = match camera.lens() {
        None => (origin, direction),
        Some(lens) => {
            let aperture = (path_rngs.draw(LENS_FIRST), path_rngs.draw(LENS_FIRST + 1));
            camera.lens_ray_x8(lens, direction, concentric_disk_x8(aperture.0, aperture.1))
        }
    };
    let (origin, t_max) = match camera.clip() {
        None => (origin, f32x8::splat(f32::INFINITY)),
        Some(clip) => camera.clip_ray_x8(clip, (origin, direction)),
    };
    let live = active.to_simd();
    let packet = RayPacket {
        origin: Vec3x8::select(live, origin, Vec3x8::splat(camera.position())).to_array(),
        direction: Vec3x8::select(live, direction, Vec3x8::splat(Vec3::Z)).to_array(),
        t_max: live.select(t_max, f32x8::ZERO),
        active,
    };
    (packet, [dx, dy])
}

/// Stack of each render thread. A group's rays, hits, wavelengths and
/// radiance ([`GROUP`] packets) live on it (its path states on the heap,
/// [`ThreadStates`]): with 32 coefficients or 32 wavelengths and groups of
/// 32 packets a release build needed 2–3 MiB when the path states were
/// there too (found by shrinking `RUST_MIN_STACK` until it overflowed),
/// more than a spawned thread's default 2 MiB. 16 MiB leaves room for
/// debug builds' larger frames; only the pages a thread touches are
/// committed.
const RENDER_THREAD_STACK_BYTES: usize = 16 << 20;

/// One group state per render thread, on the heap, built at the thread's
/// first tile and kept for the whole render ([`GroupState`] is reset by
/// [`trace_group`] for every group). A state holds [`GROUP`] path states,
/// a few hundred kilobytes; rayon's `for_each_init` built one on the
/// worker's stack for every split of every pass, so the state and its
/// construction's temporaries sat in the frames of the tiles' traversal
/// and were written anew each pass.
struct ThreadStates<S> {
    slots: Vec<Mutex<Option<Box<GroupState<S, GROUP>>>>>,
}

impl<S: Copy> ThreadStates<S> {
    /// Empty slots for a pool of `threads` threads.
    fn new(threads: usize) -> Self {
        Self {
            slots: (0..threads.max(1)).map(|_| Mutex::new(None)).collect(),
        }
    }

    /// Runs `f` with the calling render thread's state. A thread that
    /// finds its slot taken (a tile started inside another's wait, which
    /// the renderer does not do today) gets a state of its own for the
    /// call instead of blocking on itself.
    fn with<T: Transport<Spectra = S>>(
        &self,
        transport: &T,
        f: impl FnOnce(&mut GroupState<S, GROUP>),
    ) {
        let index = rayon::current_thread_index().unwrap_or(0);
        let slot = self.slots.get(index).map(|slot| match slot.try_lock() {
            Ok(guard) => Some(guard),
            Err(TryLockError::Poisoned(poisoned)) => Some(poisoned.into_inner()),
            Err(TryLockError::WouldBlock) => None,
        });
        match slot.flatten() {
            Some(mut guard) => f(guard.get_or_insert_with(|| Self::boxed(transport))),
            None => f(&mut Self::boxed(transport)),
        }
    }

    /// A new state on the heap. Not inlined: the state is built in this
    /// frame before it is moved, and inlined into the tile loop that frame
    /// would stay on the stack under every tile.
    #[inline(never)]
    fn boxed<T: Transport<Spectra = S>>(transport: &T) -> Box<GroupState<S, GROUP>> {
        Box::new(GroupState::new(transport))
    }
}

/// Wall time a batch of passes aims at: the progress callback (and so the
/// CLI's progress display, Ctrl-C and the time limit) sees the render at
/// least this often, give or take one pass. An [`Observer`] may ask for
/// shorter batches (a viewer's frame rate and restart latency).
pub const BATCH_TARGET: Duration = Duration::from_millis(500);
/// Most passes per batch.
const MAX_BATCH: u32 = 16;

/// Passes in the next batch: as many as fit in `target` (normally
/// [`BATCH_TARGET`]) at the last batch's speed (at most [`MAX_BATCH`], and
/// not past a time limit).
fn next_batch(
    batch: u32,
    took: Duration,
    settings: &RenderSettings,
    elapsed: Duration,
    target: Duration,
) -> u32 {
    let per_pass = took.as_secs_f64() / f64::from(batch.max(1));
    let mut budget = target.as_secs_f64();
    if let Some(limit) = settings.time_limit {
        budget = budget.min(limit.saturating_sub(elapsed).as_secs_f64());
    }
    if per_pass <= 0.0 {
        return MAX_BATCH;
    }
    ((budget / per_pass).floor() as u32).clamp(1, MAX_BATCH)
}

fn render_tile<T: Transport>(
    context: &PathContext<'_, T>,
    settings: &RenderSettings,
    pass: u32,
    state: &mut GroupState<T::Spectra, GROUP>,
    tile: &mut Tile<FilmPixel<T>>,
) {
    let PathContext {
        transport, scene, ..
    } = *context;
    // The tile's packets in block order ([`packet_origins`]), traced GROUP
    // at a time; the last group is padded with packets without pixels.
    let mut origins = packet_origins(tile.x0, tile.y0, tile.width, tile.height);
    let (x0, y0) = (tile.x0, tile.y0);
    let pixel_index =
        |(lx, ly): (u32, u32)| u64::from(y0 + ly) * u64::from(settings.width) + u64::from(x0 + lx);
    let window = settings.film_window();
    let keys = PassKeys::new(settings.sampler, settings.seed, pass);
    let splat = Splat::new(settings, tile, transport.film());
    if splat.is_some() {
        let film = transport.film();
        tile.ring.iter_mut().for_each(|p| *p = film.empty_pixel());
    }
    let mut scratch = splat.as_ref().map_or_else(Vec::new, Splat::empty_scratch);
    // The group's finished samples, refilled in place for each group (an
    // array made per group is written once and copied whole, tens of KB).
    let mut group_samples: Vec<[FilmSample<T>; LANES]> = Vec::with_capacity(GROUP);
    loop {
        let group: [Option<(u32, u32)>; GROUP] = core::array::from_fn(|_| origins.next());
        if group[0].is_none() {
            break;
        }
        let lanes: [[Option<(u32, u32)>; LANES]; GROUP] = core::array::from_fn(|g| {
            let mut lanes = [None; LANES];
            if let Some((bx, by)) = group[g] {
                for (lane, slot) in lanes.iter_mut().enumerate() {
                    let (lx, ly) = (
                        bx + lane as u32 % PACKET_WIDTH,
                        by + lane as u32 / PACKET_WIDTH,
                    );
                    if lx < tile.width && ly < tile.height {
                        *slot = Some((lx, ly));
                    }
                }
            }
            lanes
        });
        // A lane without a pixel draws from a stream no pixel has.
        let pixels = |lanes: &[Option<(u32, u32)>; LANES]| -> [u64; LANES] {
            core::array::from_fn(|lane| lanes[lane].map_or(u64::MAX - lane as u64, pixel_index))
        };
        let mut path_rngs: [PathSampler; GROUP] =
            core::array::from_fn(|g| keys.path_sampler(&pixels(&lanes[g])));
        // Each lane's offset from its pixel's centre, px (x, y).
        let mut offsets = [[f32x8::ZERO; 2]; GROUP];
        let camera_rays: [RayPacket; GROUP] = core::array::from_fn(|g| {
            let (rays, offset) = camera_packet(scene, settings, tile, &lanes[g], &mut path_rngs[g]);
            offsets[g] = offset;
            rays
        });
        let mut wavelengths: [T::Wavelengths; GROUP] = core::array::from_fn(|g| {
            let pixels = pixels(&lanes[g]);
            transport.sample_wavelengths(|lane| keys.wavelength_stream(pixels[lane]))
        });
        let radiance = trace_group(
            context,
            state,
            &camera_rays,
            &mut path_rngs,
            &mut wavelengths,
            &mut tile.rays,
        );
        group_samples.clear();
        group_samples.extend(
            radiance
                .iter()
                .zip(&wavelengths)
                .map(|(radiance, wavelengths)| transport.samples(radiance, wavelengths)),
        );
        if !state.children.is_empty() {
            let parents = |packet: usize, lane: usize| pixels(&lanes[packet % GROUP])[lane % LANES];
            trace_children(
                context,
                state,
                (&keys, &parents),
                &mut group_samples,
                &mut tile.rays,
            );
        }
        for (g, samples) in group_samples.iter().enumerate() {
            let finite = transport.finite_lanes(&radiance[g], samples);
            if let Some(splat) = &splat {
                let weights = splat.packet_weights((offsets[g][0], offsets[g][1]));
                let [dx, dy] = offsets[g].map(|o| o.to_array());
                for (lane, slot) in lanes[g].iter().enumerate() {
                    let Some((lx, ly)) = *slot else { continue };
                    if finite.contains(lane) {
                        let into = (&mut *tile, &mut scratch[..]);
                        match &weights {
                            Some(weights) => splat.spread(
                                transport.film(),
                                into,
                                (lx, ly),
                                (&weights.rows[lane], &weights.columns[lane]),
                                &samples[lane],
                            ),
                            None => splat.add(
                                transport.film(),
                                into,
                                (lx, ly),
                                (dx[lane], dy[lane]),
                                &samples[lane],
                            ),
                        }
                    } else if window.contains(tile.x0 + lx, tile.y0 + ly) {
                        // Counted by the window that holds its pixel.
                        tile.rejected += 1;
                    }
                }
                continue;
            }
            for (lane, slot) in lanes[g].iter().enumerate() {
                // Lanes outside a crop window were traced for their
                // packet-mates' sake only (module docs).
                let kept = slot.filter(|&(lx, ly)| window.contains(tile.x0 + lx, tile.y0 + ly));
                if let Some((lx, ly)) = kept {
                    if finite.contains(lane) {
                        let index = (ly * tile.width + lx) as usize;
                        transport
                            .film()
                            .accumulate(&mut tile.pixels[index], &samples[lane]);
                    } else {
                        tile.rejected += 1;
                    }
                }
            }
        }
    }
    if let Some(splat) = &splat {
        splat.flush_scratch(transport.film(), tile, &scratch);
    }
}

/// Edge of the film-aligned squares whose packets a tile traces one after
/// another, pixels: 16 × 16 pixels are [`GROUP`]'s 32 packets of 4 × 2,
/// so a whole square is one group, whose camera rays stay as coherent as
/// a square can make them (a group of 32 × 8 pixels, a row of packets of
/// a 32-pixel tile, rendered the instanced bunnies 3 % slower).
const GROUP_BLOCK: u32 = 16;

/// The packets' top-left corners, relative to the tile at `(x0, y0)` of
/// `width` × `height` pixels: the [`GROUP_BLOCK`] squares of the film's
/// grid that meet the tile in row-major order, and each square's packets
/// (its part inside the tile) in row-major order. The squares sit on the
/// film's grid, not the tile's, so a tile cut by a crop keeps the order
/// of the full tile's packets that it holds (module docs: crops are
/// exact). `x0` and `y0` lie on the packet grid.
fn packet_origins(x0: u32, y0: u32, width: u32, height: u32) -> impl Iterator<Item = (u32, u32)> {
    let (x_end, y_end) = (x0 + width, y0 + height);
    let square = GROUP_BLOCK as usize;
    (y0 / GROUP_BLOCK * GROUP_BLOCK..y_end)
        .step_by(square)
        .flat_map(move |sy| {
            (x0 / GROUP_BLOCK * GROUP_BLOCK..x_end)
                .step_by(square)
                .flat_map(move |sx| {
                    let columns = sx.max(x0)..(sx + GROUP_BLOCK).min(x_end);
                    (sy.max(y0)..(sy + GROUP_BLOCK).min(y_end))
                        .step_by(PACKET_HEIGHT as usize)
                        .flat_map(move |y| {
                            columns
                                .clone()
                                .step_by(PACKET_WIDTH as usize)
                                .map(move |x| (x - x0, y - y0))
                        })
                })
        })
}

/// The high bit of a child's sampler key: no pixel's key has it (the
/// padding lanes' keys do, with every other bit but the lane's set).
const CHILD_KEY: u64 = 1 << 63;

/// Traces the children the group's lanes spawned (`state.children`,
/// [`crate::integrator::ChildPath`]) in groups of their own, one per
/// first-segment depth, and adds each child's sample to its parent's in
/// `samples`. A child's random numbers come from the stream of the key
/// `CHILD_KEY | parent_pixel << 4 | slot` (a lane spawns once per pass
/// and slot; `parents` gives the parent lane's pixel key). Not inlined:
/// its packets' arrays would otherwise enlarge the tile loop's frame for
/// the renders that spawn no child.
#[inline(never)]
fn trace_children<T: Transport>(
    context: &PathContext<'_, T>,
    state: &mut GroupState<T::Spectra, GROUP>,
    (keys, parents): (&PassKeys, &dyn Fn(usize, usize) -> u64),
    samples: &mut [[FilmSample<T>; LANES]],
    counts: &mut RayCounts,
) {
    let transport = context.transport;
    let mut children = core::mem::take(&mut state.children);
    children.sort_by_key(|child| child.depth);
    for same_depth in children.chunk_by(|a, b| a.depth == b.depth) {
        for batch in same_depth.chunks(GROUP * LANES) {
            let depth = batch.first().map_or(1, |child| child.depth);
            let mut origins = [[Vec3::ZERO; LANES]; GROUP];
            let mut directions = [[Vec3::Z; LANES]; GROUP];
            let mut seeds = [[None; LANES]; GROUP];
            let mut stream_keys: [[u64; LANES]; GROUP] =
                [core::array::from_fn(|lane| u64::MAX - lane as u64); GROUP];
            let mut active = [LaneMask::NONE; GROUP];
            let mut caustics = [(LaneMask::NONE, LaneMask::NONE); GROUP];
            for (k, child) in batch.iter().enumerate() {
                let (p, lane) = (k / LANES, k % LANES);
                let (scattered_first, chain) = child.caustic_state;
                if scattered_first {
                    caustics[p].0 = caustics[p].0.with(lane);
                }
                if chain {
                    caustics[p].1 = caustics[p].1.with(lane);
                }
                origins[p][lane] = child.origin;
                directions[p][lane] = child.direction;
                seeds[p][lane] = Some((child.lambda_nm, child.pdf_per_nm, child.value));
                stream_keys[p][lane] =
                    CHILD_KEY | parents(child.packet, child.lane) << 4 | child.slot as u64;
                active[p] = active[p].with(lane);
            }
            let packets: [Option<(T::Wavelengths, T::Spectra)>; GROUP] =
                core::array::from_fn(|p| transport.child_packet(&seeds[p]));
            let mut wavelengths = Vec::with_capacity(GROUP);
            let mut throughput = Vec::with_capacity(GROUP);
            for (w, t) in packets.into_iter().flatten() {
                wavelengths.push(w);
                throughput.push(t);
            }
            let (Ok(mut wavelengths), Ok(throughput)) = (
                <[T::Wavelengths; GROUP]>::try_from(wavelengths),
                <[T::Spectra; GROUP]>::try_from(throughput),
            ) else {
                // A transport that spawns no children.
                return;
            };
            let rays: [RayPacket; GROUP] = core::array::from_fn(|p| RayPacket {
                origin: Vec3x8::from_lanes(&origins[p]).to_array(),
                direction: Vec3x8::from_lanes(&directions[p]).to_array(),
                t_max: f32x8::splat(f32::INFINITY),
                active: active[p],
            });
            let mut rngs: [PathSampler; GROUP] =
                core::array::from_fn(|p| keys.path_sampler(&stream_keys[p]));
            let start = GroupStart {
                depth,
                throughput: Some(&throughput),
                caustics: caustics.map(|(first, chain)| CausticLanes::of_children(first, chain)),
            };
            let radiance = trace_group_from(
                context,
                state,
                &start,
                &rays,
                (&mut rngs, &mut wavelengths),
                counts,
            );
            for (p, radiance) in radiance.iter().enumerate() {
                let child_samples = transport.samples(radiance, &wavelengths[p]);
                for lane in active[p].iter() {
                    if let Some(child) = batch.get(p * LANES + lane)
                        && let Some(parent) = samples
                            .get_mut(child.packet)
                            .and_then(|packet| packet.get_mut(child.lane))
                    {
                        transport.add_child_sample(parent, &child_samples[lane]);
                    }
                }
            }
        }
    }
    children.clear();
    state.children = children;
}

/// A splatting tile's filter and margin (module docs).
/// Slots for one row's or column's splat weights: `2M + 1` rounded up to
/// whole 8-lane chunks.
const SPLAT_WEIGHT_SLOTS: usize = (2 * MAX_SPLAT_MARGIN_PX as usize + 1).div_ceil(LANES) * LANES;

/// `0, 1, …, 7`: the lane offsets of one chunk of splat weights.
/// A packet's footprint weights per lane ([`Splat::packet_weights`]):
/// `columns[lane][k]` for footprint columns `k < 2M + 1`, `rows` alike.
struct PacketWeights {
    columns: [[f32; LANES]; LANES],
    rows: [[f32; LANES]; LANES],
}

const LANE_INDEX: f32x8 = f32x8::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);

/// Where a tile's apron pixels outside the tile live in its ring: the `M`
/// rows above the tile (apron width each), then for each of the tile's
/// rows its `M` pixels left and `M` right, then the `M` rows below.
/// Apron coordinates `(ax, ay)` count from the apron's corner
/// `(x0 − M, y0 − M)`.
#[derive(Debug, Clone, Copy)]
struct Ring {
    /// `M`, px.
    margin: usize,
    /// The tile's width, px.
    width: usize,
    /// The tile's height, px.
    height: usize,
}

impl Ring {
    fn of<P>(tile: &Tile<P>, margin: u32) -> Self {
        Self {
            margin: margin as usize,
            width: tile.width as usize,
            height: tile.height as usize,
        }
    }

    /// Pixels of the ring.
    fn len(&self) -> usize {
        let apron_width = self.width + 2 * self.margin;
        2 * self.margin * (apron_width + self.height)
    }

    /// The tile pixel of apron pixel `(ax, ay)` (`Ok`, row-major in the
    /// tile) or its ring slot (`Err`); the pixel is in the apron.
    #[inline(always)]
    fn place(&self, ax: usize, ay: usize) -> Result<usize, usize> {
        let (m, w, h) = (self.margin, self.width, self.height);
        let apron_width = w + 2 * m;
        debug_assert!(ax < apron_width && ay < h + 2 * m);
        if ay < m {
            return Err(ay * apron_width + ax);
        }
        if ay >= m + h {
            return Err(m * apron_width + 2 * m * h + (ay - m - h) * apron_width + ax);
        }
        let row = m * apron_width + (ay - m) * 2 * m;
        if ax < m {
            Err(row + ax)
        } else if ax >= m + w {
            Err(row + m + (ax - m - w))
        } else {
            Ok((ay - m) * w + (ax - m))
        }
    }
}

struct Splat<'a> {
    filter: &'a Filter,
    /// `M`, px.
    margin: u32,
    /// The tile's apron less the tile.
    ring: Ring,
    /// `f32` values per apron pixel of the pass's scratch
    /// ([`Film::scratch_len`]; 0: splats go straight into the pixels).
    scratch_len: usize,
}

impl<'a> Splat<'a> {
    /// The splat of `tile` into `film` when `settings` splat.
    fn new<F: Film>(settings: &'a RenderSettings, tile: &Tile<F::Pixel>, film: &F) -> Option<Self> {
        (settings.film == FilmMode::Splat).then(|| {
            let margin = settings.filter.splat_margin_px();
            Self {
                filter: &settings.filter,
                margin,
                ring: Ring::of(tile, margin),
                scratch_len: film.scratch_len(),
            }
        })
    }

    /// The tile's apron: width and height, px.
    fn apron(&self) -> (usize, usize) {
        let margin = 2 * self.margin as usize;
        (self.ring.width + margin, self.ring.height + margin)
    }

    /// A zeroed pass scratch over the apron (empty when the film has none).
    fn empty_scratch(&self) -> Vec<f32> {
        let (width, height) = self.apron();
        vec![0.0; width * height * self.scratch_len]
    }

    /// Adds the pass's `scratch` to the tile's pixels and ring.
    fn flush_scratch<F: Film>(&self, film: &F, tile: &mut Tile<F::Pixel>, scratch: &[f32]) {
        if self.scratch_len == 0 {
            return;
        }
        let (width, height) = self.apron();
        let len = self.scratch_len;
        // Rows and columns counted, not derived from the scratch index: a
        // division per pixel (and `chunks_exact`'s own, by a length known
        // only at run time) costs more than the add it locates.
        for ay in 0..height {
            for ax in 0..width {
                let at = (ay * width + ax) * len;
                let Some(values) = scratch.get(at..at + len) else {
                    return;
                };
                let pixel = match self.ring.place(ax, ay) {
                    Ok(own) => tile.pixels.get_mut(own),
                    Err(slot) => tile.ring.get_mut(slot),
                };
                if let Some(pixel) = pixel {
                    film.add_scratch(pixel, values);
                }
            }
        }
    }

    /// Adds `sample`, traced at `offset` px from the centre of the tile's
    /// pixel `(lx, ly)`, to every apron pixel `(lx + i, ly + j)`,
    /// `i, j ∈ −M ..= M`, with weight `f(dx − i) f(dy − j)` (the offset
    /// from that pixel's centre), skipping zero weights: the footprints
    /// wider than 8 lanes (`M` ≤ [`MAX_SPLAT_MARGIN_PX`]), whose weights
    /// are computed per sample, 8 columns at a time; narrower ones (the
    /// Gaussian's and the default tent's) are spread with their packet's
    /// weights ([`Splat::packet_weights`]).
    fn add<F: Film>(
        &self,
        film: &F,
        (tile, scratch): (&mut Tile<F::Pixel>, &mut [f32]),
        (lx, ly): (u32, u32),
        (dx, dy): (f32, f32),
        sample: &F::Sample,
    ) {
        let reach = self.reach();
        let weights = |offset: f32| {
            let mut weights = [0.0f32; SPLAT_WEIGHT_SLOTS];
            for (chunk, slots) in weights.chunks_exact_mut(LANES).enumerate() {
                if chunk * LANES >= reach {
                    break;
                }
                slots.copy_from_slice(&self.weight_chunk(offset, chunk * LANES).to_array());
            }
            weights
        };
        let (rows, columns) = (weights(dy), weights(dx));
        self.spread(film, (tile, scratch), (lx, ly), (&rows, &columns), sample);
    }

    /// The footprint weights of a packet's 8 samples at once, at offsets
    /// `(dx, dy)` px from their pixels' centres, where the footprint fits
    /// 8 lanes (else `None`): `columns[lane][k]` and `rows[lane][k]`, each
    /// the lane's own [`Splat::weight_chunk`] bit for bit (the same
    /// lane-wise operations on the same values). One exponential per
    /// footprint column across the lanes instead of one per lane across
    /// the columns: 2 (2M + 1) of them a packet instead of 16, none
    /// waiting on another.
    fn packet_weights(&self, (dx, dy): (f32x8, f32x8)) -> Option<PacketWeights> {
        let reach = self.reach();
        if reach > LANES {
            return None;
        }
        let along = |offset: f32x8| {
            let shifted = offset - f32x8::splat(-(self.margin as f32));
            let per_k: [f32x8; LANES] = core::array::from_fn(|k| {
                if k < reach {
                    self.filter.weight_x8(shifted - f32x8::splat(k as f32))
                } else {
                    f32x8::ZERO
                }
            });
            f32x8::transpose(per_k).map(|lane| lane.to_array())
        };
        Some(PacketWeights {
            columns: along(dx),
            rows: along(dy),
        })
    }

    /// The footprint's width, px: `2M + 1`.
    fn reach(&self) -> usize {
        (2 * self.margin + 1) as usize
    }

    /// The weights of footprint columns (or rows) `first .. first + 8` for a
    /// sample at `offset` px from its pixel's centre: `f(offset − (k − M))`.
    fn weight_chunk(&self, offset: f32, first: usize) -> f32x8 {
        let x = f32x8::splat(offset - (first as f32 - self.margin as f32)) - LANE_INDEX;
        self.filter.weight_x8(x)
    }

    /// Adds `sample` with weight `rows[j] · columns[i]` to apron pixel
    /// `(lx + i, ly + j)` (the apron is shifted by `M` in both axes), for
    /// `i, j` below the footprint's width: the tile's own pixel or its ring
    /// slot, skipping zero weights.
    fn spread<F: Film>(
        &self,
        film: &F,
        (tile, scratch): (&mut Tile<F::Pixel>, &mut [f32]),
        (lx, ly): (u32, u32),
        (rows, columns): (&[f32], &[f32]),
        sample: &F::Sample,
    ) {
        let reach = self.reach();
        let (rows, columns) = (
            &rows[..reach.min(rows.len())],
            &columns[..reach.min(columns.len())],
        );
        if self.scratch_len > 0 {
            let (width, _) = self.apron();
            let len = self.scratch_len;
            for (j, &wy) in rows.iter().enumerate() {
                if wy == 0.0 {
                    continue;
                }
                // The footprint's pixels in this row, consecutive records
                // of `len` values (those past the scratch's end are none),
                // located by offset: `chunks_exact_mut` by a length known
                // only at run time divides once per row.
                let start = ((ly as usize + j) * width + lx as usize) * len;
                for (i, &wx) in columns.iter().enumerate() {
                    let w = wx * wy;
                    let at = start + i * len;
                    if w != 0.0
                        && let Some(values) = scratch.get_mut(at..at + len)
                    {
                        film.accumulate_scratch(values, sample, w);
                    }
                }
            }
            return;
        }
        for (j, &wy) in rows.iter().enumerate() {
            if wy == 0.0 {
                continue;
            }
            for (i, &wx) in columns.iter().enumerate() {
                let w = wx * wy;
                if w == 0.0 {
                    continue;
                }
                let pixel = match self.ring.place(lx as usize + i, ly as usize + j) {
                    Ok(own) => &mut tile.pixels[own],
                    Err(slot) => &mut tile.ring[slot],
                };
                film.accumulate_weighted(pixel, sample, w);
            }
        }
    }
}

/// Adds every tile's ring into the pixels of `window` it covers (module
/// docs): `sources[t]` lists, in tile order, the other tiles whose rings
/// cover some of tile `t`'s window pixels ([`ring_sources`]).
fn flush_rings<F: Film>(
    film: &F,
    tiles: &mut [Tile<F::Pixel>],
    sources: &[Vec<usize>],
    margin: u32,
    window: &PixelWindow,
) {
    let rings: Vec<(u32, u32, Ring, Vec<F::Pixel>)> = tiles
        .iter_mut()
        .map(|t| (t.x0, t.y0, Ring::of(t, margin), std::mem::take(&mut t.ring)))
        .collect();
    tiles
        .par_iter_mut()
        .zip(sources.par_iter())
        .for_each(|(tile, sources)| {
            // The tile's pixels in the window, film coordinates (i64: the
            // aprons reach past the film's corner).
            let (x0, y0) = (i64::from(tile.x0), i64::from(tile.y0));
            let (wx0, wy0) = (i64::from(window.x), i64::from(window.y));
            let kept_x =
                x0.max(wx0)..(x0 + i64::from(tile.width)).min(wx0 + i64::from(window.width));
            let kept_y =
                y0.max(wy0)..(y0 + i64::from(tile.height)).min(wy0 + i64::from(window.height));
            let margin = i64::from(margin);
            for &source in sources {
                let (sx0, sy0, geometry, ring) = &rings[source];
                let apron_width = (geometry.width + 2 * geometry.margin) as i64;
                let apron_height = (geometry.height + 2 * geometry.margin) as i64;
                // The apron's corner in film coordinates, and its overlap
                // with the kept pixels.
                let (ax0, ay0) = (i64::from(*sx0) - margin, i64::from(*sy0) - margin);
                let columns = kept_x.start.max(ax0)..kept_x.end.min(ax0 + apron_width);
                for y in kept_y.start.max(ay0)..kept_y.end.min(ay0 + apron_height) {
                    for x in columns.clone() {
                        let place = geometry.place((x - ax0) as usize, (y - ay0) as usize);
                        // The source's own pixels are not in its ring.
                        let Err(slot) = place else { continue };
                        let at = ((y - y0) * i64::from(tile.width) + x - x0) as usize;
                        film.add_pixel(&mut tile.pixels[at], &ring[slot]);
                    }
                }
            }
        });
    for (tile, (.., ring)) in tiles.iter_mut().zip(rings) {
        tile.ring = ring;
    }
}

/// For each tile, the other tiles (in order) whose aprons, the tiles grown
/// by `margin`, overlap its pixels in `window`: the rings that reach it (a
/// tile's own ring lies outside it).
fn ring_sources<P>(tiles: &[Tile<P>], margin: u32, window: &PixelWindow) -> Vec<Vec<usize>> {
    let rect = |t: &Tile<P>, grow: u32| {
        (
            i64::from(t.x0) - i64::from(grow),
            i64::from(t.y0) - i64::from(grow),
            i64::from(t.x0) + i64::from(t.width) + i64::from(grow),
            i64::from(t.y0) + i64::from(t.height) + i64::from(grow),
        )
    };
    let (wx0, wy0) = (i64::from(window.x), i64::from(window.y));
    let (wx1, wy1) = (
        wx0 + i64::from(window.width),
        wy0 + i64::from(window.height),
    );
    tiles
        .iter()
        .enumerate()
        .map(|(own, tile)| {
            let (x0, y0, x1, y1) = rect(tile, 0);
            let (x0, y0, x1, y1) = (x0.max(wx0), y0.max(wy0), x1.min(wx1), y1.min(wy1));
            if x0 >= x1 || y0 >= y1 {
                return Vec::new();
            }
            tiles
                .iter()
                .enumerate()
                .filter(|&(index, source)| {
                    let (sx0, sy0, sx1, sy1) = rect(source, margin);
                    index != own && sx0 < x1 && x0 < sx1 && sy0 < y1 && y0 < sy1
                })
                .map(|(index, _)| index)
                .collect()
        })
        .collect()
}

/// Which passes a render takes and what it starts from (module docs):
/// passes `first_pass .. first_pass + spp` of the seeded sequence
/// ([`RenderSettings::spp`] counts them), continuing `resume` (which must
/// cover `first_pass ..` some pass of that range, for the same window), and
/// whether to return the film's state.
#[derive(Debug, Clone, Copy, Default)]
pub struct PassJob<'a> {
    /// Index of the first pass.
    pub first_pass: u32,
    /// The state of a render of the same window and settings over passes
    /// `first_pass .. k`, to continue from pass `k`.
    pub resume: Option<&'a FilmState>,
    /// Return the film's state with the result.
    pub keep_state: bool,
    /// Resolve the XYZ image only, without the coefficient planes a
    /// spectral film would return too ([`RenderResult::coefficients`]
    /// `None`): `N` floats a pixel that only spectral outputs read.
    pub xyz_only: bool,
}

/// Renders `scene` with `transport`. `progress` runs after every batch of
/// passes (module docs) and returns whether to continue.
pub fn render<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &RenderSettings,
    progress: &mut dyn FnMut(&Progress) -> bool,
) -> Result<RenderResult, RenderError> {
    render_passes(transport, scene, settings, &PassJob::default(), progress).map(|(r, _)| r)
}

/// Renders the passes of `job` (module docs), returning the film's state
/// when `job.keep_state`: the state's passes are those of `job.resume`
/// followed by the passes done here (fewer than asked when stopped early).
pub fn render_passes<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &RenderSettings,
    job: &PassJob,
    progress: &mut dyn FnMut(&Progress) -> bool,
) -> Result<(RenderResult, Option<FilmState>), RenderError> {
    let observer = Observer {
        batch_target: BATCH_TARGET,
        after_batch: &mut |p, _| progress(p),
    };
    render_observed(transport, scene, settings, job, observer)
}

/// The image of a render so far, as the final result would resolve it
/// (a viewer's frame): XYZ per pixel of the window and the mean
/// coefficients when the film keeps them ([`RenderResult`]'s fields).
#[derive(Debug, Clone, PartialEq)]
pub struct PartialImage {
    /// Width, pixels (the window's).
    pub width: u32,
    /// Height, pixels (the window's).
    pub height: u32,
    /// XYZ per pixel, row-major from the window's top-left.
    pub xyz: Vec<Xyz>,
    /// Mean Fourier coefficients per pixel (`N` per pixel), when kept.
    pub coefficients: Option<(usize, Vec<f32>)>,
}

/// Resolves the image so far on request (only when a viewer wants it).
pub type ResolvePartial<'a> = &'a dyn Fn() -> PartialImage;

/// What watches a render: after every batch of passes `after_batch` sees
/// the progress and may resolve the image so far, and returns whether to
/// continue; batches aim at `batch_target` of wall time (a viewer asks for
/// less than [`BATCH_TARGET`] to restart quickly after a change).
pub struct Observer<'a> {
    /// Wall time a batch aims at (at least one pass, at most
    /// 16 passes).
    pub batch_target: Duration,
    /// Called after every batch; `false` stops the render.
    pub after_batch: &'a mut dyn FnMut(&Progress, ResolvePartial) -> bool,
}

/// [`render_passes`] with an [`Observer`] that may see the image after
/// every batch: the same passes in the same order, so the result does not
/// depend on the observer (only where the render stops does).
pub fn render_observed<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &RenderSettings,
    job: &PassJob,
    observer: Observer,
) -> Result<(RenderResult, Option<FilmState>), RenderError> {
    let Observer {
        batch_target,
        after_batch,
    } = observer;
    if settings.width == 0 || settings.height == 0 || settings.spp == 0 {
        return Err(RenderError::EmptyImage);
    }
    settings.filter.validate().map_err(RenderError::Filter)?;
    if settings.film == FilmMode::Sample && settings.filter.has_negative_lobes() {
        return Err(RenderError::SampledNegativeLobes);
    }
    let window = settings
        .film_window()
        .validate(settings.width, settings.height)?;
    let film = transport.film();
    let state_len = film.state_len();
    let splat = settings.film == FilmMode::Splat;
    if splat && state_len.is_none() {
        return Err(RenderError::CannotSplat);
    }
    if (job.first_pass != 0 || job.resume.is_some() || job.keep_state) && state_len.is_none() {
        return Err(RenderError::NotSplittable);
    }
    let last_pass = job.first_pass.checked_add(settings.spp).ok_or_else(|| {
        RenderError::State(format!(
            "pass {} + {} passes overflows",
            job.first_pass, settings.spp
        ))
    })?;
    let resumed = match job.resume {
        None => None,
        Some(state) => {
            if state.window != window {
                return Err(RenderError::State(format!(
                    "it holds the window {}×{} at ({}, {}), the render {}×{} at ({}, {})",
                    state.window.width,
                    state.window.height,
                    state.window.x,
                    state.window.y,
                    window.width,
                    window.height,
                    window.x,
                    window.y
                )));
            }
            if state.mode != settings.film {
                return Err(RenderError::State(format!(
                    "it holds a {} film, the render makes a {} film",
                    state.mode.name(),
                    settings.film.name()
                )));
            }
            if state.passes.start != job.first_pass || state.passes.end > last_pass {
                return Err(RenderError::State(format!(
                    "it holds passes {}..{}, not a start of {}..{last_pass}",
                    state.passes.start, state.passes.end, job.first_pass
                )));
            }
            Some((state, state.load(film)?))
        }
    };
    let mut builder = rayon::ThreadPoolBuilder::new().stack_size(RENDER_THREAD_STACK_BYTES);
    if let Some(threads) = settings.threads {
        builder = builder.num_threads(threads.max(1));
    }
    let pool = builder
        .build()
        .map_err(|e| RenderError::Threads(e.to_string()))?;
    let states = ThreadStates::new(pool.current_num_threads());
    let start = Instant::now();
    let light_paths = LightPaths::new(
        scene,
        LightPathSettings {
            spectra: transport.light_path_spectra(),
            integrator: settings.integrator,
            seed: settings.seed,
            width: settings.width,
            height: settings.height,
        },
    );
    let mut light_film = light_paths.as_ref().map(|_| {
        LightFilm::new(
            window,
            (settings.width, settings.height),
            settings.filter.clone(),
            settings.film,
        )
    });
    let mut light_rays = RayCounts::default();
    let context = PathContext {
        transport,
        scene,
        settings: &settings.integrator,
        light_traced_caustics: light_paths.is_some(),
    };
    // The film's tiles cut to the traced pixels (splatting: those within
    // the margin of the window): each starts on the film's packet grid, so
    // its packets are the full render's.
    let margin = if splat {
        settings.filter.splat_margin_px()
    } else {
        0
    };
    let traced = window
        .grown(margin, settings.width, settings.height)
        .to_packet_grid(settings.width, settings.height);
    let (traced_x_end, traced_y_end) = (traced.x + traced.width, traced.y + traced.height);
    let mut tiles = Vec::new();
    for tile_y in (0..settings.height).step_by(TILE_SIZE as usize) {
        for tile_x in (0..settings.width).step_by(TILE_SIZE as usize) {
            let (x0, y0) = (tile_x.max(traced.x), tile_y.max(traced.y));
            let x_end = tile_x.saturating_add(TILE_SIZE).min(traced_x_end);
            let y_end = tile_y.saturating_add(TILE_SIZE).min(traced_y_end);
            if x0 >= x_end || y0 >= y_end {
                continue;
            }
            let (width, height) = (x_end - x0, y_end - y0);
            let mut tile = Tile {
                x0,
                y0,
                width,
                height,
                pixels: vec![film.empty_pixel(); (width * height) as usize],
                ring: Vec::new(),
                rejected: 0,
                rays: RayCounts::default(),
            };
            if splat {
                tile.ring = vec![film.empty_pixel(); Ring::of(&tile, margin).len()];
            }
            tiles.push(tile);
        }
    }
    let sources = if splat {
        ring_sources(&tiles, margin, &window)
    } else {
        Vec::new()
    };
    let pixel_count = window.pixel_count();
    let mut passes = 0;
    let mut resumed_rejected = 0;
    if let Some((state, pixels)) = resumed {
        for tile in &mut tiles {
            let (x0, y0, width) = (tile.x0, tile.y0, tile.width);
            for (index, pixel) in tile.pixels.iter_mut().enumerate() {
                let (x, y) = (x0 + index as u32 % width, y0 + index as u32 / width);
                if window.contains(x, y) {
                    *pixel = pixels[window_index(&window, x, y)].clone();
                }
            }
        }
        passes = state.passes.end - state.passes.start;
        resumed_rejected = state.rejected;
    }
    let mut batch = 1;
    while passes < settings.spp {
        let first = job.first_pass + passes;
        let end = first.saturating_add(batch).min(last_pass);
        let batch_start = Instant::now();
        pool.install(|| {
            if splat {
                // One pass at a time, its rings flushed before the next
                // (module docs): the batch never reaches the sums.
                for pass in first..end {
                    tiles.par_iter_mut().for_each(|tile| {
                        states.with(transport, |state| {
                            render_tile(&context, settings, pass, state, tile);
                        });
                    });
                    flush_rings(film, &mut tiles, &sources, margin, &window);
                }
            } else {
                tiles.par_iter_mut().for_each(|tile| {
                    states.with(transport, |state| {
                        for pass in first..end {
                            render_tile(&context, settings, pass, state, tile);
                        }
                    });
                });
            }
            if let (Some(paths), Some(film)) = (&light_paths, &mut light_film) {
                for pass in first..end {
                    trace_light_paths(paths, pass, film, &mut light_rays);
                }
            }
        });
        if film.passes_interact() {
            debug_assert_eq!(end, first + 1);
            let shared = film.pass_shared(
                &mut tiles
                    .iter()
                    .flat_map(|tile| tile.window_pixels(&window).map(|(_, pixel)| pixel)),
            );
            for tile in &mut tiles {
                let (x0, y0, width) = (tile.x0, tile.y0, tile.width);
                for (index, pixel) in tile.pixels.iter_mut().enumerate() {
                    let (lx, ly) = (index as u32 % width, index as u32 / width);
                    if window.contains(x0 + lx, y0 + ly) {
                        film.end_pass(pixel, &shared);
                    }
                }
            }
        }
        passes = end - job.first_pass;
        let elapsed = start.elapsed();
        let resolve = || {
            let lit = with_light_paths(film, &tiles, &window, light_film.as_ref());
            let pixels = lit.iter().map(|(index, pixel)| (*index, pixel.as_ref()));
            let (xyz, coefficients) = resolve_pixels(film, &window, pixels, !job.xyz_only);
            PartialImage {
                width: window.width,
                height: window.height,
                xyz,
                coefficients,
            }
        };
        let progress = Progress {
            passes_done: passes,
            passes_total: settings.spp,
            samples: pixel_count * u64::from(passes),
            elapsed,
        };
        let keep_going = after_batch(&progress, &resolve);
        if !keep_going || settings.time_limit.is_some_and(|limit| elapsed >= limit) {
            break;
        }
        if !film.passes_interact() {
            batch = next_batch(
                batch,
                batch_start.elapsed(),
                settings,
                elapsed,
                batch_target,
            );
        }
    }
    // The splat rings are spent: freed before the resolve's buffers are
    // made, so the two never coexist at the end of a render.
    for tile in &mut tiles {
        tile.ring = Vec::new();
    }
    if let Some(light) = &light_film {
        for tile in &mut tiles {
            let (x0, y0, width) = (tile.x0, tile.y0, tile.width);
            for (index, pixel) in tile.pixels.iter_mut().enumerate() {
                let (x, y) = (x0 + index as u32 % width, y0 + index as u32 / width);
                if window.contains(x, y) {
                    film.add_light_paths(pixel, light.at(x, y));
                }
            }
        }
    }
    let mut rejected = resumed_rejected;
    let mut rays = light_rays;
    for tile in &tiles {
        rejected += tile.rejected;
        rays.add(&tile.rays);
    }
    let pixels = tiles
        .iter()
        .flat_map(|tile| tile.window_pixels(&window))
        .map(|((x, y), pixel)| (window_index(&window, x, y), pixel));
    let (xyz, coefficients) = resolve_pixels(film, &window, pixels, !job.xyz_only);
    let state = match (job.keep_state, state_len) {
        (true, Some(values_per_pixel)) => {
            let mut state =
                FilmState::empty(window, job.first_pass, values_per_pixel, settings.film);
            state.passes.end = job.first_pass + passes;
            state.rejected = rejected;
            for tile in &tiles {
                for ((x, y), pixel) in tile.window_pixels(&window) {
                    let at = window_index(&window, x, y) * values_per_pixel;
                    film.save_state(pixel, &mut state.values[at..at + values_per_pixel]);
                }
            }
            Some(state)
        }
        _ => None,
    };
    let result = RenderResult {
        width: window.width,
        height: window.height,
        xyz,
        coefficients,
        passes,
        samples: (pixel_count * u64::from(passes)).saturating_sub(rejected),
        rejected,
        rays,
        elapsed: start.elapsed(),
    };
    Ok((result, state))
}

/// Light paths a task of the light-path pass traces
/// ([`trace_light_paths`]): enough to spread a pass over the threads, few
/// enough that a task's hits stay small.
const LIGHT_PATH_CHUNK: u64 = 4096;

/// Traces pass `pass`'s light paths in parallel chunks and adds their hits
/// to `film` in the order of the paths (`light_film.rs`: the bits do not
/// depend on the threads).
fn trace_light_paths(paths: &LightPaths, pass: u32, film: &mut LightFilm, rays: &mut RayCounts) {
    let starts: Vec<u64> = (0..paths.per_pass())
        .step_by(LIGHT_PATH_CHUNK as usize)
        .collect();
    let chunks: Vec<(Vec<FilmHit>, RayCounts)> = starts
        .into_par_iter()
        .map(|start| {
            let end = start.saturating_add(LIGHT_PATH_CHUNK).min(paths.per_pass());
            let (mut hits, mut counts) = (Vec::new(), RayCounts::default());
            paths.trace(pass, start..end, &mut hits, &mut counts);
            (hits, counts)
        })
        .collect();
    for (hits, counts) in &chunks {
        for hit in hits {
            film.add(hit);
        }
        rays.add(counts);
    }
}

/// The window's pixels with their index, copied with the light paths'
/// sums added where there are any (an image resolved before the end of
/// the render: the tiles keep their camera sums alone until then).
fn with_light_paths<'a, F: Film>(
    film: &F,
    tiles: &'a [Tile<F::Pixel>],
    window: &'a PixelWindow,
    light: Option<&LightFilm>,
) -> Vec<(usize, Cow<'a, F::Pixel>)> {
    tiles
        .iter()
        .flat_map(|tile| tile.window_pixels(window))
        .map(|((x, y), pixel)| {
            let pixel = match light {
                Some(light) => {
                    let mut lit = pixel.clone();
                    film.add_light_paths(&mut lit, light.at(x, y));
                    Cow::Owned(lit)
                }
                None => Cow::Borrowed(pixel),
            };
            (window_index(window, x, y), pixel)
        })
        .collect()
}

/// The index of film pixel `(x, y)` in `window`, row-major from its corner.
fn window_index(window: &PixelWindow, x: u32, y: u32) -> usize {
    ((y - window.y) * window.width + x - window.x) as usize
}

/// XYZ and, if the film keeps them and `with_coefficients`, the mean
/// coefficients of `window`'s pixels, given with their row-major indices in
/// the window.
fn resolve_pixels<'a, F: Film>(
    film: &F,
    window: &PixelWindow,
    pixels: impl Iterator<Item = (usize, &'a F::Pixel)>,
    with_coefficients: bool,
) -> (Vec<Xyz>, Option<(usize, Vec<f32>)>)
where
    F::Pixel: 'a,
{
    let pixel_count = window.pixel_count() as usize;
    let mut xyz = vec![Xyz::default(); pixel_count];
    let mut planes: Option<(usize, Vec<f32>)> = None;
    for (index, pixel) in pixels {
        xyz[index] = film.resolve(pixel);
        if let Some(c) = film.coefficients(pixel).filter(|_| with_coefficients) {
            let (n, data) =
                planes.get_or_insert_with(|| (c.len(), vec![0.0; pixel_count * c.len()]));
            for (j, &v) in c.iter().enumerate().take(*n) {
                data[index * *n + j] = v as f32;
            }
        }
    }
    (xyz, planes)
}

/// The image of a film state, as [`render`] would resolve it (nothing is
/// traced: the rays are zero, the time is that of the resolve).
pub fn resolve_state<T: Transport>(
    transport: &T,
    state: &FilmState,
) -> Result<RenderResult, RenderError> {
    let start = Instant::now();
    let film = transport.film();
    if film.state_len().is_none() {
        return Err(RenderError::NotSplittable);
    }
    let pixels = state.load(film)?;
    let (xyz, coefficients) = resolve_pixels(film, &state.window, pixels.iter().enumerate(), true);
    let passes = state.passes.end - state.passes.start;
    Ok(RenderResult {
        width: state.window.width,
        height: state.window.height,
        xyz,
        coefficients,
        passes,
        samples: (state.window.pixel_count() * u64::from(passes)).saturating_sub(state.rejected),
        rejected: state.rejected,
        rays: RayCounts::default(),
        elapsed: start.elapsed(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A packet's weights are each lane's own per-sample weights bit for
    /// bit, for the filters whose footprint fits 8 lanes; wider ones have
    /// none. The comparison discriminates: the weights of offsets moved by
    /// a hundredth of a pixel differ.
    #[test]
    fn packet_weights_are_each_lanes_weights() {
        let offsets = |seed: f32| {
            f32x8::new(core::array::from_fn(|lane| {
                (seed * (lane as f32 + 1.7)).sin() * 0.5
            }))
        };
        let filters = [
            Filter::gaussian(),
            Filter::Box,
            Filter::tent(2.5).expect("a valid tent"),
            Filter::gaussian_with_stddev(0.8).expect("a valid Gaussian"),
        ];
        // The splat of a whole tile with `filter`'s margin, no scratch.
        let splat_of = |filter| {
            let margin = Filter::splat_margin_px(filter);
            Splat {
                filter,
                margin,
                ring: Ring {
                    margin: margin as usize,
                    width: TILE_SIZE as usize,
                    height: TILE_SIZE as usize,
                },
                scratch_len: 0,
            }
        };
        for filter in &filters {
            let splat = splat_of(filter);
            let margin = splat.margin;
            let reach = (2 * margin + 1) as usize;
            assert!(reach <= LANES, "{filter:?}");
            let (dx, dy) = (offsets(0.37), offsets(1.91));
            let weights = splat.packet_weights((dx, dy)).expect("fits 8 lanes");
            let moved = splat
                .packet_weights((dx + f32x8::splat(0.01), dy))
                .expect("fits 8 lanes");
            for lane in 0..LANES {
                let columns = splat.weight_chunk(dx.to_array()[lane], 0).to_array();
                let rows = splat.weight_chunk(dy.to_array()[lane], 0).to_array();
                for k in 0..reach {
                    assert_eq!(weights.columns[lane][k].to_bits(), columns[k].to_bits());
                    assert_eq!(weights.rows[lane][k].to_bits(), rows[k].to_bits());
                }
                if *filter != Filter::Box {
                    assert_ne!(moved.columns[lane][..reach], weights.columns[lane][..reach]);
                }
            }
        }
        let wide = Filter::gaussian_with_stddev(2.0).expect("a valid Gaussian");
        let splat = splat_of(&wide);
        assert!(2 * splat.margin + 1 > LANES as u32);
        assert!(splat.packet_weights((f32x8::ZERO, f32x8::ZERO)).is_none());
    }

    /// Every packet of a tile once, in whole squares of one group each, and
    /// a tile cut by a crop keeps the full tile's order of the packets it
    /// holds. Negative control: squares on the tile's own grid would break
    /// the cut tile's order (checked by hand: anchoring at `x0` fails the
    /// last assertion).
    #[test]
    fn packets_come_square_by_square_in_the_full_tiles_order() {
        let full: Vec<(u32, u32)> = packet_origins(32, 64, TILE_SIZE, TILE_SIZE).collect();
        let mut expected = Vec::new();
        for y in (0..TILE_SIZE).step_by(PACKET_HEIGHT as usize) {
            for x in (0..TILE_SIZE).step_by(PACKET_WIDTH as usize) {
                expected.push((x, y));
            }
        }
        let mut sorted = full.clone();
        sorted.sort_by_key(|&(x, y)| (y, x));
        assert_eq!(sorted, expected, "each packet once");
        for (group, packets) in full.chunks(GROUP).enumerate() {
            let (x_min, y_min) = (packets[0].0, packets[0].1);
            assert_eq!((x_min % GROUP_BLOCK, y_min % GROUP_BLOCK), (0, 0));
            for &(x, y) in packets {
                assert!(
                    (x_min..x_min + GROUP_BLOCK).contains(&x)
                        && (y_min..y_min + GROUP_BLOCK).contains(&y),
                    "group {group}: packet ({x}, {y}) outside its square"
                );
            }
        }
        // The same tile cut to columns 44.. and rows 70..83 (a crop's
        // traced region on the packet grid): its packets in film
        // coordinates are the full tile's that it holds, in the same order.
        let (cx0, cy0, cw, ch) = (44, 70, 32 + TILE_SIZE - 44, 14);
        let cut: Vec<(u32, u32)> = packet_origins(cx0, cy0, cw, ch)
            .map(|(x, y)| (x + cx0, y + cy0))
            .collect();
        let kept: Vec<(u32, u32)> = full
            .iter()
            .map(|&(x, y)| (x + 32, y + 64))
            .filter(|&(x, y)| x >= cx0 && y >= cy0 && y < cy0 + ch)
            .collect();
        assert!(!cut.is_empty());
        assert_eq!(cut, kept);
    }

    #[test]
    fn batches_fill_half_a_second_within_bounds() {
        let settings = RenderSettings::default();
        let ms = Duration::from_millis;
        // 4 passes took 200 ms: 50 ms each, 10 fit in 500 ms.
        assert_eq!(
            next_batch(4, ms(200), &settings, ms(1000), BATCH_TARGET),
            10
        );
        // Slow passes: never fewer than one.
        assert_eq!(
            next_batch(1, ms(2000), &settings, ms(2000), BATCH_TARGET),
            1
        );
        // Fast passes: at most MAX_BATCH.
        assert_eq!(
            next_batch(2, ms(1), &settings, ms(10), BATCH_TARGET),
            MAX_BATCH
        );
        assert_eq!(
            next_batch(1, Duration::ZERO, &settings, ms(10), BATCH_TARGET),
            MAX_BATCH
        );
        // Not past a time limit: 100 ms left at 30 ms per pass.
        let limited = RenderSettings {
            time_limit: Some(ms(1100)),
            ..RenderSettings::default()
        };
        assert_eq!(next_batch(1, ms(30), &limited, ms(1000), BATCH_TARGET), 3);
        assert_eq!(next_batch(1, ms(30), &limited, ms(1200), BATCH_TARGET), 1);
    }

    /// The built-in Cornell box and a 4-coefficient Fourier transport, the
    /// small setup of the batch and observer tests.
    fn cornell_with_fourier4() -> (Scene, crate::transport::FourierTransport<4>) {
        use crate::film::Buffer;
        use crate::transport::FourierTransport;
        use spectral_core::xyz::XyzRoute;
        let range = spectral_core::SpectralRange::VISIBLE;
        let (Ok(scene), Ok(transport)) = (
            crate::scene::builtin::cornell_box(range),
            FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth),
        ) else {
            panic!("Cornell box and transport");
        };
        (scene, transport)
    }

    /// A render thread gets the same heap state at every call; a call
    /// made while its slot is taken gets a state of its own instead of
    /// waiting on itself.
    #[test]
    fn a_thread_keeps_its_state_and_a_nested_call_gets_its_own() {
        let (_, transport) = cornell_with_fourier4();
        let states = ThreadStates::new(1);
        let address = |state: &mut GroupState<_, GROUP>| core::ptr::from_mut(state) as usize;
        // A mark a fresh state does not have (a freed box's address may be
        // reused, so the address alone would not tell).
        const MARK: usize = 7;
        let mut seen = Vec::new();
        states.with(&transport, |state| {
            state.children.reserve(MARK);
            seen.push(address(state));
        });
        states.with(&transport, |state| {
            assert!(state.children.capacity() >= MARK, "a new state");
            seen.push(address(state));
        });
        states.with(&transport, |outer| {
            seen.push(address(outer));
            states.with(&transport, |inner| {
                assert_eq!(inner.children.capacity(), 0, "the taken state");
                seen.push(address(inner));
            });
        });
        assert_eq!(seen[0], seen[1]);
        assert_eq!(seen[0], seen[2]);
        assert_ne!(seen[2], seen[3], "the nested call shares the taken state");
    }

    #[test]
    fn progress_reports_every_batch_up_to_the_requested_passes() -> Result<(), RenderError> {
        let (scene, transport) = cornell_with_fourier4();
        let settings = RenderSettings {
            width: 16,
            height: 8,
            spp: 37,
            ..RenderSettings::default()
        };
        let mut seen = Vec::new();
        let result = render(&transport, &scene, &settings, &mut |p| {
            seen.push(p.passes_done);
            true
        })?;
        assert_eq!(result.passes, 37);
        assert_eq!(seen.first(), Some(&1));
        assert_eq!(seen.last(), Some(&37));
        assert!(
            seen.windows(2)
                .all(|w| w[0] < w[1] && w[1] - w[0] <= MAX_BATCH)
        );
        // Tiny passes: batches grow to the maximum.
        assert!(seen.len() < 37, "{seen:?}");

        // Stopping after the first batch keeps exactly its passes.
        let first = render(&transport, &scene, &settings, &mut |_| false)?;
        assert_eq!(first.passes, 1);
        Ok(())
    }

    #[test]
    fn an_observer_sees_the_image_the_same_passes_render() -> Result<(), RenderError> {
        let (scene, transport) = cornell_with_fourier4();
        let settings = RenderSettings {
            width: 24,
            height: 16,
            spp: 40,
            ..RenderSettings::default()
        };
        // Stop after the second batch, keeping what the observer saw then.
        let mut seen: Vec<(u32, PartialImage)> = Vec::new();
        let mut after_batch = |p: &Progress, resolve: ResolvePartial| {
            seen.push((p.passes_done, resolve()));
            seen.len() < 2
        };
        let observer = Observer {
            batch_target: Duration::from_millis(1),
            after_batch: &mut after_batch,
        };
        let (observed, _) =
            render_observed(&transport, &scene, &settings, &PassJob::default(), observer)?;
        let Some((passes, last)) = seen.last() else {
            panic!("no batch seen");
        };
        assert_eq!(*passes, observed.passes);
        assert_eq!(last.xyz, observed.xyz);
        assert_eq!(last.coefficients, observed.coefficients);
        // The frame is the image of that many passes, bit for bit …
        let same = RenderSettings {
            spp: *passes,
            ..settings.clone()
        };
        let full = render(&transport, &scene, &same, &mut |_| true)?;
        assert_eq!(last.xyz, full.xyz);
        assert_eq!((last.width, last.height), (24, 16));
        // … and not that of one pass more (the negative control).
        let more = RenderSettings {
            spp: *passes + 1,
            ..settings
        };
        let other = render(&transport, &scene, &more, &mut |_| true)?;
        assert_ne!(last.xyz, other.xyz);
        Ok(())
    }
}
