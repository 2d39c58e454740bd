//! `naadf data check DIR [--json]` and `naadf data repair DIR [--apply]`: what a server's data
//! directory holds, whether `naadf serve` would start on it, and the repairs that make it
//! servable and tidy. `naadf_server::data::fsck` judges, the same way the server's startup does.

use super::print_json;
use anyhow::{Context, Result, anyhow, bail};
use naadf_server::data::fsck::{self, Inspection, Verdict};
use naadf_server::data::layout::{Lock, StoreError};
use naadf_server::data::store;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The `data` subcommands.
#[derive(clap::Subcommand)]
pub enum Data {
    /// Report what a data directory holds and whether `naadf serve` would start on it.
    ///
    /// Lists the snapshots (complete or not), the log segments with their versions and any
    /// torn write at the end, temporary files, orphans and other files, then what `serve`
    /// would do. Loads the newest complete snapshot to verify it (and, if it is damaged,
    /// looks for an older road). Ignores the quarantine/ folder. Exits with status 1 when
    /// `serve` would not start.
    Check(CheckArgs),
    /// Cut a torn write off the log, settle orphan files and take an older road past a
    /// damaged snapshot (a dry run unless --apply).
    ///
    /// Judges the directory as `check` does (loading the snapshot `serve` would resume
    /// from). Deletes only the temporary files of unfinished snapshot writes; anything else
    /// it cannot explain (an incomplete snapshot's file, a damaged snapshot when an older
    /// snapshot and the log after it reach every logged version) is moved into the
    /// directory's quarantine/ folder. A directory that cannot be made servable is left as
    /// it is, with what the operator can do instead.
    Repair(RepairArgs),
}

/// Arguments of `data check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// The data directory (read only; a server may keep running on it).
    dir: PathBuf,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
}

/// Arguments of `data repair`.
#[derive(clap::Args)]
pub struct RepairArgs {
    /// The data directory (no server may run on it for --apply).
    dir: PathBuf,
    /// Make the changes; without it, only print them.
    #[arg(long)]
    apply: bool,
}

/// Runs a `data` subcommand.
pub fn run(d: Data) -> Result<()> {
    match d {
        Data::Check(a) => check(&a),
        Data::Repair(a) => repair(&a),
    }
}

/// The report of `data check`, as `--json` prints it.
#[derive(Serialize)]
struct Report {
    dir: String,
    /// Whether a running server holds the directory (the report is then one moment's view).
    in_use: bool,
    snapshots: Vec<SnapshotReport>,
    segments: Vec<SegmentReport>,
    temporary: Vec<String>,
    other: Vec<String>,
    /// How many entries the quarantine/ folder holds (ignored by the judgement).
    quarantined: usize,
    /// What the next start (or `data repair --apply`) deletes or moves into quarantine/.
    orphans: Vec<OrphanReport>,
    /// With a damaged newest snapshot: the older snapshot `data repair --apply` resumes
    /// from instead, and the logged records that follow it.
    road: Option<RoadReport>,
    serve: ServeReport,
}

#[derive(Serialize)]
struct SnapshotReport {
    version: u64,
    world: bool,
    state: bool,
    complete: bool,
}

#[derive(Serialize)]
struct SegmentReport {
    file: String,
    base: u64,
    bytes: u64,
    records: u64,
    first: Option<u64>,
    last: Option<u64>,
    /// It holds only versions the newest complete snapshot covers (the next snapshot
    /// deletes it).
    covered: bool,
    torn: Option<TornReport>,
    error: Option<String>,
}

#[derive(Serialize)]
struct TornReport {
    at: u64,
    bytes: u64,
}

#[derive(Serialize)]
struct OrphanReport {
    file: String,
    why: String,
    /// Moved into quarantine/ (false: deleted, a temporary file).
    quarantine: bool,
}

#[derive(Serialize)]
struct RoadReport {
    snapshot: u64,
    replay: u64,
}

#[derive(Serialize)]
struct ServeReport {
    starts: bool,
    /// `new`, `resume` or `refuse`.
    verdict: &'static str,
    snapshot: Option<u64>,
    replay: Option<u64>,
    message: String,
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Whether a running server holds the lock of `dir` (probing takes it for an instant).
fn in_use(dir: &Path) -> bool {
    matches!(Lock::existing(dir), Err(StoreError::Locked(_)))
}

/// What `naadf serve` would do, in words.
fn serve_words(verdict: &Verdict) -> String {
    match verdict {
        Verdict::New => "serve would start a new world".into(),
        Verdict::Resume { snapshot, records } => {
            format!("serve would resume from snapshot {snapshot} and replay {records} logged record(s)")
        }
        Verdict::Refuse(r) => format!("serve would refuse: {r}"),
    }
}

/// Inspects `dir` and, for a directory that resumes, loads its snapshot as the server
/// would, so that a damaged one counts in the verdict (`check` and `repair` alike).
fn look(dir: &Path) -> Result<Inspection> {
    Ok(verified(fsck::inspect(dir)?, dir))
}

/// `inspection` of `dir` with the snapshot it would resume from loaded.
fn verified(mut inspection: Inspection, dir: &Path) -> Inspection {
    verify(&mut inspection, dir);
    inspection
}

/// Loads the snapshot `inspection` of `dir` would resume from (and, if it is damaged, the
/// older ones that may replace it).
fn verify(inspection: &mut Inspection, dir: &Path) {
    inspection.verify(|v| store::load_snapshot(dir, v).map(drop).map_err(|e| e.to_string()));
}

fn report(dir: &Path) -> Result<Report> {
    let in_use = in_use(dir);
    let mut inspection = look(dir)?;
    // A running server may write a newer snapshot and delete this one between the look and
    // the load: then look again.
    for _ in 0..3 {
        if !(in_use && inspection.damaged.is_some()) {
            break;
        }
        inspection = look(dir)?;
    }
    let verdict = inspection.verdict();
    let newest = inspection.newest_complete();
    let first_needed = newest.map(|s| inspection.first_needed(s));
    let segments = inspection
        .segments
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let read = s.read.as_ref().ok();
            let versions = read.and_then(|r| r.versions());
            SegmentReport {
                file: file_name(&s.path),
                base: s.base,
                bytes: read.map_or_else(|| std::fs::metadata(&s.path).map_or(0, |m| m.len()), |r| r.len),
                records: read.map_or(0, |r| r.entries.len() as u64),
                first: versions.map(|v| v.0),
                last: versions.map(|v| v.1),
                covered: first_needed.is_some_and(|f| i < f),
                torn: read.and_then(|r| r.torn.map(|at| TornReport { at, bytes: r.len - at })),
                error: s.read.as_ref().err().map(ToString::to_string),
            }
        })
        .collect();
    let (kind, snapshot, replay) = match verdict {
        Verdict::New => ("new", None, None),
        Verdict::Resume { snapshot, records } => ("resume", Some(snapshot), Some(records)),
        Verdict::Refuse(_) => ("refuse", None, None),
    };
    Ok(Report {
        dir: dir.display().to_string(),
        in_use,
        snapshots: inspection
            .snapshots
            .iter()
            .map(|s| SnapshotReport {
                version: s.version,
                world: s.world,
                state: s.state,
                complete: s.complete(),
            })
            .collect(),
        segments,
        temporary: inspection.temporary.iter().map(|p| file_name(p)).collect(),
        other: inspection.other.iter().map(|p| file_name(p)).collect(),
        quarantined: inspection.quarantined,
        orphans: inspection
            .orphans()
            .into_iter()
            .map(|o| OrphanReport {
                file: file_name(&o.path),
                why: o.why,
                quarantine: o.quarantine,
            })
            .collect(),
        road: inspection
            .road
            .map(|(snapshot, replay)| RoadReport { snapshot, replay }),
        serve: ServeReport {
            starts: kind != "refuse",
            verdict: kind,
            snapshot,
            replay,
            message: serve_words(&inspection.verdict()),
        },
    })
}

fn print_report(r: &Report) {
    println!(
        "data directory {}{}",
        r.dir,
        if r.in_use { " (in use by a running server)" } else { "" }
    );
    if !r.snapshots.is_empty() {
        println!("snapshots");
        for s in &r.snapshots {
            let state = match (s.world, s.state) {
                (true, true) => "complete",
                (true, false) => "incomplete: its .state is missing",
                _ => "incomplete: its .naadf is missing",
            };
            println!("  version {:<20} {state}", s.version);
        }
    }
    if !r.segments.is_empty() {
        println!("write-ahead log");
        for s in &r.segments {
            let mut line = match (&s.error, s.first.zip(s.last)) {
                (Some(e), _) => format!("damaged: {e}"),
                (None, Some((a, b))) => format!("{} record(s), versions {a}–{b}", s.records),
                (None, None) => "no records".into(),
            };
            if let Some(t) = &s.torn {
                line.push_str(&format!(
                    "; torn write at the end: {} bytes from byte {}",
                    t.bytes, t.at
                ));
            }
            if s.covered {
                line.push_str("; covered by the newest snapshot");
            }
            println!("  {}  {line}", s.file);
        }
    }
    for (heading, names) in [
        ("temporary files", &r.temporary),
        ("other files (left alone)", &r.other),
    ] {
        if !names.is_empty() {
            println!("{heading}");
            for n in names {
                println!("  {n}");
            }
        }
    }
    if r.quarantined > 0 {
        println!("quarantine/: {} file(s) moved aside earlier (ignored)", r.quarantined);
    }
    if !r.orphans.is_empty() {
        println!("orphans (the next start settles them, as does `naadf data repair --apply`)");
        for o in &r.orphans {
            let fate = if o.quarantine { "to quarantine/" } else { "to delete" };
            println!("  {} ({fate}): {}", o.file, o.why);
        }
    }
    if let Some(road) = &r.road {
        println!(
            "older road: snapshot {} and {} logged record(s) after it reach every logged version",
            road.snapshot, road.replay
        );
    }
    println!("{}", r.serve.message);
}

fn check(a: &CheckArgs) -> Result<()> {
    let r = report(&a.dir)?;
    if a.json {
        print_json(&r)?;
    } else {
        print_report(&r);
    }
    if !r.serve.starts {
        bail!("`naadf serve` would not start on {}", a.dir.display());
    }
    Ok(())
}

fn repair(a: &RepairArgs) -> Result<()> {
    let dir = &a.dir;
    let cannot = |r| anyhow!("cannot make {} servable; nothing was changed. {r}", dir.display());
    if !a.apply {
        let inspection = look(dir)?;
        let actions = inspection.repair().map_err(cannot)?;
        if actions.is_empty() {
            println!("nothing to repair; {}", serve_words(&inspection.verdict()));
            return Ok(());
        }
        println!("would make these changes:");
        for action in &actions {
            println!("  {action}");
        }
        if let Some((snapshot, records)) = inspection.road {
            println!("then serve would resume from snapshot {snapshot} and replay {records} logged record(s)");
        }
        if in_use(dir) {
            println!("a running server holds the directory: stop it before --apply");
        }
        println!("`naadf data repair {} --apply` makes them", dir.display());
        return Ok(());
    }
    // Held until the changes are made: no server may start on the directory meanwhile.
    let (_lock, inspection) = fsck::inspect_locked(dir, |i| {
        verify(i, dir);
        i.repair().is_ok_and(|a| !a.is_empty())
    })
    .with_context(|| format!("cannot repair {}", dir.display()))?;
    let inspection = verified(inspection, dir);
    let actions = inspection.repair().map_err(cannot)?;
    if actions.is_empty() {
        println!("nothing to repair; {}", serve_words(&inspection.verdict()));
        return Ok(());
    }
    for action in &actions {
        action.apply()?;
        println!("done: {action}");
    }
    println!("{}", serve_words(&fsck::inspect(dir)?.verdict()));
    Ok(())
}
