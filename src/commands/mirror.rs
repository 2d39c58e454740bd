//! `naadf mirror --server URL [--verify] [--json] [--once -o OUT.naadf [--timeout S]]`

use super::remote::{ServerArgs, block_on, status_error};
use super::{print_json, save_world};
use anyhow::{Context, Result, bail};
use naadf_client::{Ended, Mirror};
use naadf_world::{World, file};
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `mirror`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Check, at every quiescent point, the digest from scratch and the distance-field
    /// safety invariant (on top of the per-delta digest check, which always runs).
    #[arg(long)]
    verify: bool,
    /// Print state as JSON lines (one per quiescent point; with --once, one at the end).
    #[arg(long)]
    json: bool,
    /// Exit once the mirror is live and the server quiescent, writing the world (-o).
    #[arg(long, requires = "output")]
    once: bool,
    /// World file to write with --once.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Give up after this many seconds (with --once).
    #[arg(long)]
    timeout: Option<f64>,
    /// Page cache directory (default: $XDG_CACHE_HOME/naadf or ~/.cache/naadf).
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Neither read nor write the page cache.
    #[arg(long, conflicts_with = "cache")]
    no_cache: bool,
}

#[derive(serde::Serialize)]
struct State {
    version: u64,
    digest: String,
    quiescent: bool,
    bytes: u64,
    pages: u64,
    snapshots: u64,
    deltas: u64,
}

/// The cache file for `server` in `dir`.
fn cache_file(dir: Option<&PathBuf>, server: &str) -> Option<PathBuf> {
    let dir = match dir {
        Some(d) => d.clone(),
        None => std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?
            .join("naadf"),
    };
    Some(dir.join(format!(
        "mirror-{:016x}.naadf",
        xxhash_rust::xxh3::xxh3_64(server.as_bytes())
    )))
}

fn state(m: &Mirror) -> State {
    let w = m.world().expect("live mirror");
    State {
        version: w.version(),
        digest: w.digest().to_string(),
        quiescent: m.is_quiescent(),
        bytes: m.stats.bytes,
        pages: m.stats.pages,
        snapshots: m.stats.snapshots,
        deltas: m.stats.deltas,
    }
}

fn verify(w: &World) -> Result<()> {
    let scratch = w.digest_from_scratch();
    if scratch != w.digest() {
        bail!(
            "verify: digest from scratch {scratch} differs from the incremental {}",
            w.digest()
        );
    }
    if let Some(c) = w.unsafe_chunk_aadf() {
        bail!("verify: chunk {c}'s distance field reaches a non-empty chunk");
    }
    Ok(())
}

/// Joins and mirrors until the stream ends (or, with --once, until quiescent).
pub fn run(a: Args) -> Result<()> {
    let cache = if a.no_cache {
        None
    } else {
        cache_file(a.cache.as_ref(), &a.server.server)
    };
    let cached = cache.as_ref().filter(|p| p.exists()).and_then(|p| match file::load(p) {
        Ok(w) => Some(w),
        Err(e) => {
            tracing::warn!("ignoring the page cache: {e}");
            None
        }
    });
    let mut mirror = Mirror::new(cached);
    let result = block_on(follow(&a, &mut mirror));
    if let (Some(path), Some(w)) = (&cache, mirror.world())
        && mirror.is_live()
    {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        if let Err(e) = file::save(w, path) {
            tracing::warn!("cannot write the page cache: {e}");
        }
    }
    result?;
    if a.once {
        let w = mirror.world().expect("--once ends live");
        save_world(w, a.output.as_ref().expect("clap requires -o"))?;
        if a.json {
            print_json(&state(&mirror))?;
        } else {
            println!("version {} digest {}", w.version(), w.digest());
        }
    }
    Ok(())
}

/// Why following stopped early.
enum Stop {
    Timeout,
    Interrupted,
}

async fn follow(a: &Args, mirror: &mut Mirror) -> Result<()> {
    let mut client = a.server.connect().await?;
    let mut stream = client
        .join(mirror.join_request())
        .await
        .map_err(status_error)?
        .into_inner();
    let deadline = a
        .timeout
        .map(|s| tokio::time::Instant::now() + Duration::from_secs_f64(s));
    let stop = async {
        tokio::select! {
            _ = async {
                match deadline {
                    Some(d) => tokio::time::sleep_until(d).await,
                    None => std::future::pending().await,
                }
            } => Stop::Timeout,
            _ = tokio::signal::ctrl_c() => Stop::Interrupted,
        }
    };
    let mut last_reported = None;
    let ended = mirror
        .follow(&mut stream, stop, |mirror| -> Result<ControlFlow<()>> {
            if !mirror.is_quiescent() {
                return Ok(ControlFlow::Continue(()));
            }
            let w = mirror.world().expect("live");
            let point = (w.version(), mirror.growth_seq());
            if last_reported == Some(point) {
                return Ok(ControlFlow::Continue(()));
            }
            last_reported = Some(point);
            if a.verify {
                verify(w)?;
            }
            if a.once {
                return Ok(ControlFlow::Break(()));
            }
            if a.json {
                print_json(&state(mirror))?;
            } else {
                println!("version {} digest {} (quiescent)", w.version(), w.digest());
            }
            Ok(ControlFlow::Continue(()))
        })
        .await?;
    match ended {
        Ended::Stopped(Stop::Timeout) => bail!(
            "timed out after {} s before the server was quiescent",
            a.timeout.unwrap_or_default()
        ),
        Ended::Stream if a.once => bail!("the server ended the stream before it was quiescent"),
        _ => Ok(()),
    }
}
