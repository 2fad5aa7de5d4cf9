//! `fspec view SCENE`: an interactive preview in the browser.
//!
//! A local web server (loopback only unless `--listen` says otherwise)
//! serves one page, embedded in the binary, that shows the render as it
//! refines pass after pass and restarts it on any change: camera (orbit,
//! pan, zoom with the mouse), transport and its sizes, conversion route,
//! illuminant of the scene's lights, observer, image size, split view
//! (Fourier | sampled at equal time, [`driver`]); exposure and tone map
//! re-display the current image without a restart. A click shows the
//! pixel's spectrum, traced again both ways ([`probe`]): the Fourier curve
//! and the sampled estimate per wavelength bin; the image downloads as
//! PNG, EXR or spectral EXR.
//!
//! Why this shape:
//!
//! * **One renderer.** The driver ([`driver`]) renders with
//!   `simd_tracer::render::render_observed`, the function behind
//!   `fspec render`, whose observer sees the image after every batch of
//!   passes; settings become a `fspec render` argument line parsed by its
//!   own parser ([`settings`]), so the viewer's image after `P` passes is
//!   `fspec render … --spp P`'s, bit for bit (tested).
//! * **Push, not poll.** Frames go to the page as server-sent events (a
//!   PNG in base64 with its pass count): one long response, no request
//!   loop, reconnected by the browser; changes go back as small JSON
//!   POSTs, each answered (an error line and a 400 for a bad one).
//!   Server-sent events need nothing beyond axum's core, where a WebSocket
//!   would add a protocol crate for a channel used one way.
//! * **The render never waits.** Handlers take the settings' mutex for
//!   microseconds; frames pass through a `watch` channel (latest wins);
//!   PNG encoding runs on the runtime's blocking threads, once per frame.
//!   The render stops within a batch (about 0.1 s) of a change, and when
//!   the last page closes.
//! * **In the CLI crate.** The viewer reuses the CLI's scene loaders,
//!   transport visitor and image writers, and `fspec view` is a
//!   subcommand of the one binary; a crate of its own would have to
//!   split those out of the CLI first. The HTTP stack is axum on tokio
//!   with only HTTP/1, JSON and query features.

pub mod driver;
pub mod probe;
pub mod server;
pub mod settings;

use crate::error::CliError;
use crate::render_cmd::{self, ToneKind};
use crate::scene_file::MitsubaOptions;
use driver::{DriverOptions, Job, Shared, Update};
use settings::{DEFAULT_MAX_PASSES, ViewSettings, default_transport, scene_names};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use tokio::sync::watch;

/// Threads of the server's runtime: it only parses small requests and
/// moves frames; encoding runs on its blocking pool.
const SERVER_THREADS: usize = 2;

/// Arguments of `fspec view`.
#[derive(Debug, Clone, clap::Args)]
pub struct ViewArgs {
    /// A built-in scene (`fspec scenes`), a TOML scene file, a Mitsuba 3
    /// scene file (.xml) or a bare .obj, as for `fspec render`.
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Port to listen on (default: a free one, printed).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
    /// Address to listen on (default 127.0.0.1: this machine only). Any
    /// other address lets other machines render on this one: a warning is
    /// printed.
    #[arg(long, value_name = "ADDR")]
    pub listen: Option<IpAddr>,
    /// Image width in pixels (default: the scene's, else 512).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (default: the scene's, else 512).
    #[arg(long)]
    pub height: Option<u32>,
    /// Passes after which the render stops until something changes.
    #[arg(long, default_value_t = DEFAULT_MAX_PASSES)]
    pub max_passes: u32,
    /// Render threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// A parameter of a Mitsuba scene file, `name=value` (as for
    /// `fspec render`).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Mitsuba scene files: unsupported plugins become warnings.
    #[arg(long)]
    pub lenient: bool,
}

/// A running viewer: its server and render driver. Stopped by
/// [`ViewServer::stop`] or when dropped.
pub struct ViewServer {
    address: SocketAddr,
    shared: Arc<Shared>,
    stop: watch::Sender<bool>,
    server: Option<JoinHandle<Result<(), String>>>,
    driver: Option<JoinHandle<()>>,
}

impl ViewServer {
    /// Checks `args`, builds the scene once (so a bad scene fails here, not
    /// in the page), binds the address and starts the server and the
    /// driver.
    pub fn start(args: &ViewArgs) -> Result<Self, CliError> {
        let mitsuba = MitsubaOptions {
            defines: args
                .define
                .iter()
                .map(|d| render_cmd::parse_define(d))
                .collect::<Result<_, _>>()?,
            lenient: args.lenient,
        };
        if args.threads == Some(0) {
            return Err(CliError::input("--threads must be at least 1"));
        }
        let (_, defaults, warnings) = crate::scene_source::resolve_scene(
            &args.scene,
            &simd_tracer::scene::builtin::SceneOptions::default(),
            &mitsuba,
        )?;
        for warning in &warnings {
            eprintln!("fspec: warning: {warning}");
        }
        let scenes = scene_names(&args.scene);
        let settings = ViewSettings {
            scene: args.scene.clone(),
            width: args
                .width
                .or(defaults.render.width)
                .unwrap_or(settings::DEFAULT_SIDE),
            height: args
                .height
                .or(defaults.render.height)
                .unwrap_or(settings::DEFAULT_SIDE),
            transport: default_transport(),
            exposure_stops: 0.0,
            tone: ToneKind::Clamp,
            illuminant: None,
            camera: None,
            max_passes: args.max_passes,
            split: None,
            observer: None,
        };
        let memory_limit_bytes = render_cmd::memory_limit_bytes();
        settings.validate(&scenes, memory_limit_bytes)?;
        let address = SocketAddr::new(
            args.listen.unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST)),
            args.port,
        );
        let listener = TcpListener::bind(address)
            .map_err(|e| CliError::input(format!("cannot listen on {address}: {e}")))?;
        let address = listener
            .local_addr()
            .map_err(|e| CliError::input(format!("cannot read the bound address: {e}")))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| CliError::input(format!("cannot listen on {address}: {e}")))?;
        let (updates, _) = watch::channel(Update::Nothing);
        let shared = Arc::new(Shared {
            job: Mutex::new(Job {
                settings,
                generation: 0,
                finished: None,
            }),
            wake: Condvar::new(),
            viewers: AtomicUsize::new(0),
            stopping: AtomicBool::new(false),
            updates,
            options: DriverOptions {
                threads: args.threads,
                mitsuba,
            },
        });
        let (stop, stopping) = watch::channel(false);
        let app = Arc::new(server::App {
            shared: Arc::clone(&shared),
            scenes,
            memory_limit_bytes,
            stopping: stopping.clone(),
            probing: AtomicBool::new(false),
        });
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(SERVER_THREADS)
            .enable_all()
            .build()
            .map_err(|e| CliError::input(format!("cannot start the server's threads: {e}")))?;
        let server = std::thread::Builder::new()
            .name("fspec-view-server".into())
            .spawn(move || {
                runtime.block_on(async move {
                    let listener =
                        tokio::net::TcpListener::from_std(listener).map_err(|e| e.to_string())?;
                    let mut stopping = stopping;
                    axum::serve(listener, server::router(app))
                        .with_graceful_shutdown(async move {
                            // An error means the sender is gone: stop too.
                            let _ = stopping.wait_for(|stop| *stop).await;
                        })
                        .await
                        .map_err(|e| e.to_string())
                })
            })
            .map_err(|e| CliError::input(format!("cannot start the server thread: {e}")))?;
        let driven = Arc::clone(&shared);
        let driver = std::thread::Builder::new()
            .name("fspec-view-render".into())
            .spawn(move || driver::run(&driven))
            .map_err(|e| CliError::input(format!("cannot start the render thread: {e}")))?;
        Ok(Self {
            address,
            shared,
            stop,
            server: Some(server),
            driver: Some(driver),
        })
    }

    /// The address the server listens on.
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Stops the render (after its current batch) and the server (open
    /// event streams end), and waits for both threads.
    pub fn stop(mut self) -> Result<(), CliError> {
        self.shut_down()
    }

    fn shut_down(&mut self) -> Result<(), CliError> {
        self.shared.stopping.store(true, Ordering::SeqCst);
        self.shared.notify();
        self.stop.send_replace(true);
        let mut outcome = Ok(());
        if let Some(driver) = self.driver.take() {
            if driver.join().is_err() {
                outcome = Err(CliError::input("the render thread panicked"));
            }
        }
        if let Some(server) = self.server.take() {
            match server.join() {
                Ok(Ok(())) => {}
                Ok(Err(e)) => outcome = Err(CliError::input(format!("server: {e}"))),
                Err(_) => outcome = Err(CliError::input("the server thread panicked")),
            }
        }
        outcome
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        // Errors were reported by `stop` when it was called; a drop after a
        // failed test has nobody to tell.
        let _ = self.shut_down();
    }
}

/// Runs `fspec view` until Ctrl-C.
pub fn run(args: &ViewArgs) -> Result<(), CliError> {
    let (interrupt, interrupted) = std::sync::mpsc::channel();
    ctrlc::set_handler(move || {
        // The receiver only goes away once the server has stopped.
        let _ = interrupt.send(());
    })
    .map_err(|e| CliError::input(format!("cannot install the Ctrl-C handler: {e}")))?;
    let server = ViewServer::start(args)?;
    let address = server.address();
    if !address.ip().is_loopback() {
        eprintln!(
            "fspec: warning: listening on {address}: any machine that reaches it can use this renderer (there is no authentication)"
        );
    }
    println!("fspec view: open http://{address}/ (Ctrl-C to stop)");
    // A closed channel means the handler is gone: stop as for Ctrl-C.
    let _ = interrupted.recv();
    eprintln!("fspec view: stopping");
    server.stop()
}
