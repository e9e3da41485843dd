//! `voxless serve`: explore a data set in a browser, rendered on the
//! machine that holds the data (server-side rendering: no GPU, no OpenGL,
//! no X server on either side, no build step for the page).
//!
//! **Model.** The server loads the scene once and serves one page. Each
//! browser tab opens a websocket and gets a *session*: its own view — a
//! [`SceneDesc`] (camera, transfer function, render and light settings)
//! and a frame number — over volumes every tab shares (immutable, `Sync`,
//! loaded once per data description and frame). The page sends
//! interactions (orbit, pan, zoom, settings as JSON merge patches of the
//! description, frames), each with an increasing sequence number; the
//! session applies them to its description and the tab's render worker
//! renders it progressively: a coarse JPEG at reduced resolution first,
//! then full-resolution passes up to the requested samples per pixel, and
//! a lossless PNG once converged. "Save scene" returns the description as
//! TOML, so `voxless render saved.toml` draws the converged image exactly.
//! Camera-path keyframes recorded from the view are part of that
//! description (`[[camera.keyframes]]`); a preview plays the path as coarse
//! images (`path`).
//!
//! **Invariants.**
//! - *Never stale*: an image is sent only for the latest interaction the
//!   session received; once the server has acknowledged interaction `n`, no
//!   image for an earlier one follows (`outbox`). A new interaction cancels
//!   the running render between tiles.
//! - *No stalls*: renders run on their own threads and hand images to
//!   latest-only slots; a client that reads slowly gets fewer images and
//!   delays nobody else.
//! - *Bounded input*: websocket messages over [`protocol::MAX_MESSAGE_BYTES`]
//!   close that socket; malformed ones get an error reply; neither reaches
//!   the renderer. A page can change the view but never which files are
//!   read (`patch`).
//! - *Access*: loopback (127.0.0.1:8080) by default. Any other address
//!   needs a random access token that every request and the websocket
//!   must carry (401 without, 403 when wrong); the URL printed at start
//!   carries it. Only the fixed routes exist (`http`): path traversal in any
//!   spelling is 404.

mod app;
mod encode;
mod http;
mod outbox;
mod patch;
mod path;
pub mod protocol;
mod render;
mod session;

use std::net::{IpAddr, SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use voxless::SceneDesc;

pub use protocol::{FrameHeader, unpack_frame};

/// Why the server could not start or went down.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    #[error("{0}")]
    Scene(#[from] voxless::SceneError),
    #[error("--host {host}: {message}")]
    Address { host: String, message: String },
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        addr: SocketAddr,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode an image: {0}")]
    Encode(String),
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// Where to listen, and the token.
#[derive(Clone, Debug)]
pub struct Options {
    /// Host name or IP address to bind (default 127.0.0.1).
    pub host: String,
    /// TCP port; 0 picks a free one.
    pub port: u16,
    /// The access token; generated when binding beyond loopback and not
    /// given.
    pub token: Option<String>,
    /// Where the full-resolution passes render (`--device`; the coarse
    /// stage stays on the CPU).
    pub device: voxless::device::Device,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            host: "127.0.0.1".into(),
            port: 8080,
            token: None,
            device: voxless::device::Device::cpu(),
        }
    }
}

/// A loaded scene ready to serve: what the CLI prints before listening.
pub struct Prepared {
    app: app::App,
    /// What loading said (defaults chosen, etc.).
    pub notes: Vec<String>,
    /// The kind of data and its frame count.
    pub kind: &'static str,
    pub frames: usize,
}

/// Loads frame 0 of `desc` (paths relative to `base`), so a bad scene fails
/// before the server listens. A view size and samples per pixel the
/// description leaves open get the viewer's defaults (the page sets the
/// size to its own).
pub fn prepare(mut desc: SceneDesc, base: PathBuf) -> Result<Prepared, ServeError> {
    // Progressive passes make more samples cheap to wait for: 4 spp unless
    // asked otherwise.
    desc.image.spp.get_or_insert(4);
    let frames = voxless::frame_count(&desc, &base)?;
    let volumes = app::Volumes::new(6);
    let loaded = volumes
        .get(&desc, &base, 0)
        .map_err(|message| voxless::SceneError::setting("scene", message))?;
    // Resolve once now: a setting the data cannot honour is an error at
    // start, not in the page.
    let resolved = loaded.resolve(&desc, &base)?;
    let colormap_file = match &desc.transfer.colormap_file {
        Some(f) => {
            let path = base.join(f);
            let text = std::fs::read_to_string(&path)?;
            let names = app::preset_names(&text, &path)
                .map_err(|m| voxless::SceneError::setting("transfer.colormap_file", m))?;
            Some((f.clone(), names))
        }
        None => None,
    };
    // Colour-field choices: only for plain particles (materials colour per
    // species); a file that cannot list them offers none.
    let particle_columns = match loaded.volume {
        voxless::AnyVolume::Particles(_) => {
            voxless::particle_columns(&desc, &base).unwrap_or_default()
        }
        _ => Vec::new(),
    };
    let framed = resolved.framed;
    let mut notes = loaded.notes.clone();
    notes.extend(resolved.notes);
    let kind = loaded.volume.kind();
    let app = app::App {
        base,
        initial_bounds: framed,
        initial_frame: loaded.frame,
        frames,
        volumes,
        token: None,
        loopback: true,
        colormap_file,
        particle_columns,
        current: Mutex::new((desc.clone(), 0)),
        initial: desc,
        busy: Default::default(),
        device: voxless::device::Device::cpu(),
    };
    Ok(Prepared {
        app,
        notes,
        kind,
        frames,
    })
}

/// A bound server: its address and the URL to open.
pub struct Bound {
    listener: tokio::net::TcpListener,
    app: Arc<app::App>,
    pub addr: SocketAddr,
    pub token: Option<String>,
}

impl Bound {
    /// The URL of the page (with the token, when there is one).
    pub fn url(&self) -> String {
        let host = match self.addr.ip() {
            IpAddr::V6(ip) => format!("[{ip}]"),
            IpAddr::V4(ip) => ip.to_string(),
        };
        match &self.token {
            Some(t) => format!("http://{host}:{}/?token={t}", self.addr.port()),
            None => format!("http://{host}:{}/", self.addr.port()),
        }
    }

    /// Serves until `shutdown` resolves. Open websockets do not hold it
    /// up: their tasks end with the runtime (a graceful shutdown would wait
    /// for every tab to close).
    pub async fn serve(
        self,
        shutdown: impl std::future::Future<Output = ()> + Send + 'static,
    ) -> Result<(), ServeError> {
        tokio::select! {
            served = axum::serve(self.listener, http::router(self.app)) => served?,
            () = shutdown => {}
        }
        Ok(())
    }
}

/// A random access token: 128 bits from the operating system, as hex.
fn random_token() -> Result<String, ServeError> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| std::io::Error::other(e.to_string()))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Binds `options.host:port` (inside a Tokio runtime). Beyond loopback a
/// token is required: the given one or a random one.
pub async fn bind(prepared: Prepared, options: &Options) -> Result<Bound, ServeError> {
    let addr = (options.host.as_str(), options.port)
        .to_socket_addrs()
        .map_err(|e| ServeError::Address {
            host: options.host.clone(),
            message: e.to_string(),
        })?
        .next()
        .ok_or_else(|| ServeError::Address {
            host: options.host.clone(),
            message: "names no address".into(),
        })?;
    let loopback = addr.ip().is_loopback();
    let token = match (&options.token, loopback) {
        (Some(t), _) if t.is_empty() || !t.chars().all(|c| c.is_ascii_alphanumeric()) => {
            return Err(ServeError::Address {
                host: options.host.clone(),
                message: "the token must be letters and digits".into(),
            });
        }
        (Some(t), _) => Some(t.clone()),
        (None, true) => None,
        (None, false) => Some(random_token()?),
    };
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .map_err(|source| ServeError::Bind { addr, source })?;
    let addr = listener.local_addr()?;
    let mut app = prepared.app;
    app.token = token.clone();
    app.loopback = loopback;
    app.device = options.device.clone();
    Ok(Bound {
        listener,
        app: Arc::new(app),
        addr,
        token,
    })
}

/// A server running on a thread of its own (for tests and benchmarks);
/// dropping it stops the server.
pub struct Running {
    pub addr: SocketAddr,
    pub token: Option<String>,
    pub url: String,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
    app: Arc<app::App>,
}

impl Running {
    /// Starts serving `prepared` with `options` in the background.
    pub fn start(prepared: Prepared, options: &Options) -> Result<Running, ServeError> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()?;
        let bound = runtime.block_on(bind(prepared, options))?;
        let (addr, token, url) = (bound.addr, bound.token.clone(), bound.url());
        let app = bound.app.clone();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::spawn(move || {
            let _ = runtime.block_on(bound.serve(async {
                let _ = stopped.await;
            }));
        });
        Ok(Running {
            addr,
            token,
            url,
            stop: Some(stop),
            thread: Some(thread),
            app,
        })
    }

    /// Renders running now, tabs' and `/frame.png`'s together (zero once
    /// every tab has closed and every request has gone).
    pub fn renders_running(&self) -> usize {
        self.app.busy.load(std::sync::atomic::Ordering::SeqCst)
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Serves until the process is stopped: what `voxless serve` runs.
/// `on_ready` sees the bound server (to print its URL) before serving.
pub fn run(
    prepared: Prepared,
    options: &Options,
    on_ready: impl FnOnce(&Bound),
) -> Result<(), ServeError> {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let served = runtime.block_on(async {
        let bound = bind(prepared, options).await?;
        on_ready(&bound);
        // Ctrl-C ends serving at once: open websockets and renders in
        // flight are not waited for (a graceful shutdown would wait for
        // every tab to close).
        tokio::select! {
            r = bound.serve(std::future::pending()) => r,
            _ = tokio::signal::ctrl_c() => Ok(()),
        }
    });
    // Renders still running on blocking threads get a moment to see their
    // cancellation, then the process goes on without them.
    runtime.shutdown_timeout(std::time::Duration::from_millis(500));
    served
}
