//! `naadf mirror --server URL [--verify] [--json] [--once -o OUT.naadf [--timeout S]]`

use super::remote::{ServerArgs, block_on};
use super::{print_json, save_world};
use anyhow::{Result, bail};
use naadf_client::{Backoff, Ended, Mirror, PageCache, Session};
use naadf_world::World;
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
    /// Without it the mirror follows until interrupted, and joins again by itself when the
    /// stream breaks or ends (a restarted server, a lost connection).
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
    /// Also print a JSON line for every version the mirror applies, with the wall-clock
    /// time it was applied: `{"version":V,"applied_unix_ns":T}` (what `bench moves
    /// --mirror-processes` measures latency with).
    #[arg(long)]
    log_versions: bool,
}

/// One line of --log-versions.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Applied {
    /// The version applied.
    pub version: u64,
    /// When, in nanoseconds since the Unix epoch.
    pub applied_unix_ns: u64,
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

/// Joins and mirrors until interrupted, joining again whenever the stream breaks (or, with
/// --once, until quiescent).
pub fn run(a: Args) -> Result<()> {
    let cache = if a.no_cache {
        None
    } else {
        PageCache::for_server(a.cache.as_deref(), &a.server.server)
    };
    let mirror = block_on(async {
        let cached = cache.as_ref().and_then(PageCache::load);
        let mut session = a.server.connect().await?.join(cached).await?;
        let followed = follow(&a, &mut session).await;
        // What was mirrored is worth caching even when following failed later on.
        let mirror = session.into_mirror();
        if let (Some(cache), Some(w)) = (&cache, mirror.world().filter(|_| mirror.is_live()))
            && let Err(e) = cache.save(w)
        {
            tracing::warn!("cannot write the page cache: {e}");
        }
        followed.map(|()| mirror)
    })?;
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

/// The pauses before a following mirror joins again: 100 ms, doubling up to 5 s, jittered
/// so that the mirrors of a restarted server do not all come back at the same instant.
const REJOIN_BACKOFF: Backoff = Backoff::new(Duration::from_millis(100), Duration::from_secs(5)).jittered();

/// Whether a following mirror may go on after `e` by joining again: the connection was
/// lost or the server is going away, the mirror fell behind, or the stream broke the
/// protocol or the digests (the re-join announces the mirror's pages, and the server sends
/// again those that differ). A refusal (a revoked token, say) and a failed `--verify` end
/// it.
fn rejoinable(e: &anyhow::Error) -> bool {
    use naadf_client::Error::{FellBehind, Mirror};
    e.downcast_ref::<naadf_client::Error>()
        .is_some_and(|e| e.is_unavailable() || matches!(e, Mirror(_) | FellBehind(_)))
}

/// Follows the session until a stop, with --once until the first quiescent point. Without
/// --once a broken or ended stream is joined again, after a pause of [`REJOIN_BACKOFF`]
/// that starts over once a message arrives; with --once it is an error.
async fn follow(a: &Args, session: &mut Session) -> Result<()> {
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
    tokio::pin!(stop);
    let stopped = |why: Stop| match why {
        Stop::Timeout => bail!(
            "timed out after {} s before the server was quiescent",
            a.timeout.unwrap_or_default()
        ),
        Stop::Interrupted => Ok(()),
    };
    let mut last_reported = None;
    let mut last_logged = None;
    let mut backoff = REJOIN_BACKOFF;
    loop {
        let ended = session
            .follow(stop.as_mut(), |mirror| -> Result<ControlFlow<()>> {
                backoff.reset();
                if a.log_versions {
                    log_version(mirror, &mut last_logged)?;
                }
                report(a, mirror, &mut last_reported)
            })
            .await;
        let mut why = match ended {
            Ok(Ended::Stopped(why)) => return stopped(why),
            Ok(Ended::Done) => return Ok(()),
            Ok(Ended::Stream) if a.once => bail!("the server ended the stream before it was quiescent"),
            Ok(Ended::Stream) => "the server ended the stream".to_owned(),
            Err(e) if !a.once && rejoinable(&e) => format!("{e:#}"),
            Err(e) => return Err(e),
        };
        // Join again until a join is answered; the mirror keeps its world meanwhile.
        loop {
            let pause = backoff.pause();
            tracing::warn!(retry_in = ?pause, "{why}; joining again");
            tokio::select! {
                () = tokio::time::sleep(pause) => {}
                v = stop.as_mut() => return stopped(v),
            }
            match session.rejoin().await {
                Ok(()) => break,
                Err(e) if e.is_unavailable() => why = e.to_string(),
                Err(e) => return Err(e.into()),
            }
        }
    }
}

/// Prints the --log-versions line of a live mirror's version when it is new.
fn log_version(mirror: &Mirror, last: &mut Option<u64>) -> Result<()> {
    let Some(w) = mirror.world().filter(|_| mirror.is_live()) else {
        return Ok(());
    };
    if last.is_none_or(|l| l < w.version()) {
        *last = Some(w.version());
        let applied_unix_ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)?
            .as_nanos() as u64;
        print_json(&Applied {
            version: w.version(),
            applied_unix_ns,
        })?;
    }
    Ok(())
}

/// What follows every message: at each new quiescent point, the --verify checks and the
/// state printed (or, with --once, the end).
fn report(a: &Args, mirror: &Mirror, last_reported: &mut Option<(u64, u32)>) -> Result<ControlFlow<()>> {
    if !mirror.is_quiescent() {
        return Ok(ControlFlow::Continue(()));
    }
    let w = mirror.world().expect("live");
    let point = (w.version(), mirror.growth_seq());
    if *last_reported == Some(point) {
        return Ok(ControlFlow::Continue(()));
    }
    *last_reported = Some(point);
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
}
