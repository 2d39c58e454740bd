//! One module per subcommand, plus the pieces they share: the shared arguments (`args`),
//! logging, progress bars, world file I/O with context, error reporting, and what a server
//! or relay does once it listens and when it is told to stop.

pub mod apply;
pub mod args;
#[cfg(feature = "gpu")]
pub mod bench;
pub mod data;
pub mod edit;
pub mod export;
pub mod export_log;
pub mod frame;
pub mod generate;
pub mod import;
pub mod info;
pub mod mirror;
pub mod raycast;
pub mod record;
pub mod relay;
pub mod remote;
#[cfg(feature = "gpu")]
pub mod render;
#[cfg(feature = "gpu")]
pub mod render_node;
#[cfg(feature = "gpu")]
pub mod replay;
pub mod serve;
pub mod status;
#[cfg(feature = "gpu")]
pub mod view;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use naadf_server::Bound;
use naadf_world::ops::Limits;
use naadf_world::{ChunkSource, World, file};
use std::path::Path;
use std::process::ExitCode;

/// Logs go to stderr through `tracing`; `RUST_LOG` selects the level (default: `default`).
pub fn init_logging(default: &str) {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| default.into()))
        .init();
}

/// Turns a command's result into an exit code, printing the error chain to stderr.
pub fn finish(result: Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A closed stdout (e.g. `| head`) is not an error worth reporting.
            if e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// A progress bar on stderr counting `unit`s (hidden when stderr is not a terminal).
pub fn progress(total: u64, what: &str, unit: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{msg}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {unit} ({{eta}})"
        ))
        .expect("valid template"),
    );
    bar.set_message(what.to_string());
    bar
}

/// A chunk progress bar on stderr.
pub fn chunk_progress(total: u64, what: &str) -> ProgressBar {
    progress(total, what, "chunks")
}

/// The default of `--max-chunks`: 2²⁴ chunks, e.g. a 4096 × 1024 × 4096 world.
pub const DEFAULT_MAX_CHUNKS: u64 = 1 << 24;

/// How large a world a command may build from a description: a preset and its size, or a
/// scene file whose extent sets the size.
///
/// Building costs memory and time in proportion to the world's chunk count, about 50 bytes
/// a chunk for the chunk cells and their distance fields, even where the world is empty. A
/// scene file of a few hundred bytes can place two models at opposite corners of the largest
/// world (268 million chunks, over 13 GB), so the size a file asks for is checked against
/// this bound before anything is built.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct BuildLimit {
    /// Refuse to build a world of more chunks (16³ voxels each) than this; building takes
    /// about 50 bytes of memory per chunk, empty or not.
    #[arg(long, default_value_t = DEFAULT_MAX_CHUNKS)]
    pub max_chunks: u64,
}

impl BuildLimit {
    /// Builds `source` with a progress bar, once its size is within the bound; `what` names
    /// the source in the refusal.
    pub fn build(&self, source: &dyn ChunkSource, what: &str) -> Result<World> {
        let size = source.size();
        let chunks = size.chunk_count() as u64;
        if chunks > self.max_chunks {
            anyhow::bail!(
                "{what} needs a {size} world: {chunks} chunks, more than --max-chunks {} allows \
                 (building takes about {:.1} GB of memory, empty space included); pass \
                 --max-chunks {chunks} to build it anyway",
                self.max_chunks,
                chunks as f64 * 50.0 / 1e9
            );
        }
        let bar = chunk_progress(chunks, "building");
        let world = World::build(source, &|n| bar.set_position(n))?;
        bar.finish_and_clear();
        Ok(world)
    }
}

/// The edit limits a server enforces (`naadf serve`) and an in-process replay applies
/// (`naadf replay --world`), with the same defaults.
#[derive(clap::Args, Clone, Debug)]
pub struct EditLimitArgs {
    /// Most ops per request (batch).
    #[arg(long, default_value_t = Limits::default().max_ops)]
    pub max_ops: usize,
    /// Most voxels one fill op may cover.
    #[arg(long, default_value_t = Limits::default().max_fill_volume)]
    pub max_fill: u64,
}

impl EditLimitArgs {
    /// The limits: the defaults with these two set.
    pub fn limits(&self) -> Limits {
        Limits {
            max_ops: self.max_ops,
            max_fill_volume: self.max_fill,
            ..Limits::default()
        }
    }
}

/// A number of seconds from the command line, checked: finite, not negative, at most
/// about 30 years (so that adding it to a clock cannot overflow).
pub fn seconds(v: f64, what: &str) -> Result<std::time::Duration> {
    if !(0.0..=1e9).contains(&v) {
        anyhow::bail!("{what}: {v} is not a number of seconds between 0 and 1e9");
    }
    Ok(std::time::Duration::from_secs_f64(v))
}

/// Loads a world file, naming it in any error.
pub fn load_world(path: &Path) -> Result<World> {
    file::load(path).with_context(|| format!("cannot load world {}", path.display()))
}

/// Saves a world file, naming it in any error.
pub fn save_world(world: &World, path: &Path) -> Result<()> {
    file::save(world, path).with_context(|| format!("cannot write world {}", path.display()))
}

/// Prints one JSON value on stdout.
pub fn print_json(v: &impl serde::Serialize) -> Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, v)?;
    writeln!(out)?;
    Ok(())
}

/// Gives the GPU stack a private, empty runtime directory when the environment has no usable
/// `XDG_RUNTIME_DIR`, and returns it (it is removed when the guard drops).
///
/// Mesa's software Vulkan driver (lavapipe) looks for a Wayland display while it starts, and
/// libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set in the environment` when
/// that variable is missing, which is the normal case on a headless machine. Nothing failed,
/// but a user reads "error". With the variable pointing at an empty directory the probe finds
/// no display and says nothing, as on a desktop without Wayland.
///
/// Call it before any thread starts: it sets an environment variable.
#[cfg(feature = "gpu")]
pub fn quiet_headless_gpu() -> Option<tempfile::TempDir> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| Path::new(&d).is_dir()) {
        return None;
    }
    let dir = tempfile::Builder::new().prefix("naadf-runtime-").tempdir().ok()?;
    // SAFETY: called from `main` before any other thread exists, so nothing reads the
    // environment concurrently.
    unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir.path()) };
    Some(dir)
}

/// What a server or relay does once it listens: with `json`, print its bound addresses as
/// one JSON line (`{"grpc": ADDR, "http": ADDR}`), which scripts and tests wait for.
pub fn announce(json: bool) -> impl FnOnce(Bound) {
    move |b: Bound| {
        if json {
            let _ = print_json(&serde_json::json!({
                "grpc": b.grpc.to_string(),
                "http": b.http.to_string(),
            }));
        }
    }
}

/// A future that resolves on Ctrl-C or SIGTERM. The handlers are installed now, before the
/// server announces its addresses: a signal sent right after the announcement must stop
/// the server cleanly, not find the default action (death by the signal) still in place.
pub fn shutdown_signal() -> std::io::Result<impl std::future::Future<Output = ()>> {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        let mut term = signal(SignalKind::terminate())?;
        let mut interrupt = signal(SignalKind::interrupt())?;
        Ok(async move {
            tokio::select! {
                _ = term.recv() => {}
                _ = interrupt.recv() => {}
            }
        })
    }
    #[cfg(not(unix))]
    Ok(async {
        let _ = tokio::signal::ctrl_c().await;
    })
}
