//! `naadf replay SCRIPT [--world FILE [-o OUT.naadf] | --server URL] [--json]`: runs a
//! replay script (docs/REPLAY.md) in-process against a world file, or as one or several
//! clients of a live server. Both paths check digests at quiescence, so the same script
//! on the same world gives the same checkpoints either way.

use super::remote::{ServerArgs, quiescent_world};
use super::{load_world, print_json, progress, save_world, seconds};
use anyhow::{Context, Result, anyhow, bail};
use naadf_client::Client;
use naadf_client::connect::session_client_seq;
use naadf_client::gpu::Headless;
use naadf_client::{Frame, Mode};
use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::edit::{BatchKind, Histories};
use naadf_world::ops::{Batch, Limits};
use naadf_world::replay::hashdag::{HashdagMapping, to_script_lines};
use naadf_world::replay::script::{Line, ScriptLine, parse_line, parse_script};
use serde::Serialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Arguments of `replay`.
#[derive(clap::Args)]
pub struct Args {
    /// The script (JSON Lines, or a HashDAG CSV with `--format hashdag`).
    script: PathBuf,
    /// Replay in-process against this world file (instead of a server).
    #[arg(long)]
    world: Option<PathBuf>,
    /// With `--world`: write the final world here (after the distance fields converge).
    #[arg(short, long, requires = "world")]
    output: Option<PathBuf>,
    #[command(flatten)]
    server: ServerArgs,
    /// What the script file is.
    #[arg(long, default_value = "script", value_parser = ["script", "hashdag"])]
    format: String,
    /// HashDAG coordinates are multiplied by this.
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Then shifted by this (`X,Y,Z`).
    #[arg(long, default_value = "0,0,0", value_parser = parse_offset)]
    offset: [f64; 3],
    /// Material of HashDAG edits that add voxels.
    #[arg(long, default_value_t = 1)]
    material: u16,
    /// The user until the first `as_user` line. Against a server its client sends
    /// `--token` if given, otherwise this name as its token (docs/REPLAY.md, users).
    #[arg(long, default_value = "replay")]
    user: String,
    /// In-process, the limits of the server the script stands for.
    #[command(flatten)]
    limits: super::EditLimitArgs,
    /// Seconds to wait for a server to reach a version or quiescence.
    #[arg(long, default_value_t = 120.0)]
    timeout: f64,
    /// Print the checkpoints and a pass/fail summary as JSON on stdout.
    #[arg(long)]
    json: bool,
}

fn parse_offset(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|e| format!("'{p}': {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
        _ => Err("expected three finite numbers X,Y,Z".into()),
    }
}

/// One checked point of the run.
#[derive(Serialize)]
struct Checkpoint {
    /// Script line (0 for the end of the script).
    line: usize,
    /// `expect_digest`, `expect_image`, `wait_version` or `end`.
    kind: &'static str,
    version: u64,
    digest: String,
    /// What was expected (a digest, or the largest allowed image difference).
    #[serde(skip_serializing_if = "Option::is_none")]
    expected: Option<String>,
    /// The measured image difference.
    #[serde(skip_serializing_if = "Option::is_none")]
    measured: Option<f64>,
    ok: bool,
}

#[derive(Serialize)]
struct Report {
    target: &'static str,
    lines: usize,
    edits: u64,
    frames: u64,
    renders: u64,
    checkpoints: Vec<Checkpoint>,
    failures: usize,
    passed: bool,
    /// Seconds of the run (script lines; not parsing, not the end checkpoint).
    seconds: f64,
    edits_per_second: f64,
    /// Where the time went: reading and parsing the script, sending or applying edits,
    /// waiting for quiescence and mirrors at checkpoints (and renders), the rest.
    profile: Profile,
}

/// Seconds per phase.
#[derive(Serialize, Default)]
struct Profile {
    parse: f64,
    edits: f64,
    checkpoints: f64,
    other: f64,
}

/// Where a script's edits go.
trait Target {
    /// Applies `batch` as `user`; returns the version it produced.
    fn edit(&mut self, user: &str, batch: &Batch) -> Result<u64>;
    /// Undoes (or redoes) `user`'s latest edit (or undo); returns the version.
    fn history(&mut self, user: &str, redo: bool) -> Result<u64>;
    /// Returns once the world is at version `v` or later.
    fn wait_version(&mut self, v: u64) -> Result<()>;
    /// The world once quiescent, at the latest version this replay produced or later.
    fn settled(&mut self) -> Result<&World>;
}

/// In-process: the world and the per-user histories, as the server's actor keeps them.
struct Local {
    world: World,
    histories: Histories,
    limits: Limits,
}

impl Local {
    fn apply(&mut self, user: &str, batch: &Batch, kind: BatchKind) -> Result<u64> {
        let applied = self.world.apply(batch, &self.limits)?;
        let version = applied.change.version;
        self.histories.record(user, 0, kind, version, applied.undo);
        Ok(version)
    }
}

impl Target for Local {
    fn edit(&mut self, user: &str, batch: &Batch) -> Result<u64> {
        self.apply(user, batch, BatchKind::Edit)
    }

    fn history(&mut self, user: &str, redo: bool) -> Result<u64> {
        let (batch, kind) = self
            .histories
            .history_batch(user, redo, &self.world)
            .map_err(|e| anyhow!(e))?;
        self.apply(user, &batch, kind)
    }

    fn wait_version(&mut self, v: u64) -> Result<()> {
        if self.world.version() < v {
            bail!(
                "version {v} is never reached: in-process only this script edits, and the world is at {}",
                self.world.version()
            );
        }
        Ok(())
    }

    fn settled(&mut self) -> Result<&World> {
        self.world.grow_until_quiescent();
        Ok(&self.world)
    }
}

/// Against a server: one client per user (the user's name is its token), a mirror for
/// digests and renders.
struct Remote {
    server: ServerArgs,
    default_user: String,
    runtime: tokio::runtime::Runtime,
    clients: HashMap<String, Client>,
    next_seq: u64,
    /// The newest version this replay produced or waited for.
    version: u64,
    mirror: Option<World>,
    timeout: Duration,
}

impl Remote {
    fn client(&mut self, user: &str) -> Result<Client> {
        if let Some(c) = self.clients.get(user) {
            return Ok(c.clone());
        }
        // Every user's token is its name, except that the first user sends --token when
        // one is given (in open mode a token is the user name the server records).
        let mut args = self.server.clone();
        if user != self.default_user || args.token.is_none() {
            args.token = Some(user.to_owned());
        }
        let c = self.runtime.block_on(args.connect())?;
        self.clients.insert(user.to_owned(), c.clone());
        Ok(c)
    }

    fn seq(&mut self) -> u64 {
        self.next_seq += 1;
        self.next_seq
    }

    fn acked(&mut self, version: u64) -> u64 {
        self.version = self.version.max(version);
        version
    }
}

impl Target for Remote {
    fn edit(&mut self, user: &str, batch: &Batch) -> Result<u64> {
        let c = self.client(user)?;
        let seq = self.seq();
        let ack = self.runtime.block_on(c.edit(batch.to_json_line(), seq))?;
        Ok(self.acked(ack.version))
    }

    fn history(&mut self, user: &str, redo: bool) -> Result<u64> {
        let c = self.client(user)?;
        let seq = self.seq();
        let ack = if redo {
            self.runtime.block_on(c.redo(seq))
        } else {
            self.runtime.block_on(c.undo(seq))
        }?;
        Ok(self.acked(ack.version))
    }

    fn wait_version(&mut self, v: u64) -> Result<()> {
        let user = self.default_user.clone();
        let c = self.client(&user)?;
        let deadline = Instant::now() + self.timeout; // at most 1e9 s: `seconds` checked it
        loop {
            let s = self.runtime.block_on(c.status())?;
            if s.version >= v {
                self.version = self.version.max(v);
                return Ok(());
            }
            if Instant::now() > deadline {
                bail!(
                    "the server is at version {} after {:?}, not {v}",
                    s.version,
                    self.timeout
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn settled(&mut self) -> Result<&World> {
        let cache = self.mirror.take();
        let world = self
            .runtime
            .block_on(quiescent_world(&self.server, cache, self.version, self.timeout))?;
        Ok(self.mirror.insert(world))
    }
}

/// Frames paced at one rate since `start`.
struct Pace {
    fps: f64,
    start: Instant,
    frames: u64,
}

/// The run's state between lines.
struct Run<'a> {
    target: &'a mut dyn Target,
    folder: PathBuf,
    user: String,
    camera: Option<Camera>,
    headless: Option<Headless>,
    last_frame: Option<Frame>,
    pace: Option<Pace>,
    edits: u64,
    frames: u64,
    renders: u64,
    checkpoints: Vec<Checkpoint>,
    /// Time spent in edits, and in settling for checkpoints and renders.
    edit_time: Duration,
    settle_time: Duration,
}

impl Run<'_> {
    /// Runs `f` on the target, adding its time to `edit_time`.
    fn timed_edit<T>(&mut self, f: impl FnOnce(&mut dyn Target, &str) -> Result<T>) -> Result<T> {
        let t = Instant::now();
        let r = f(&mut *self.target, &self.user);
        self.edit_time += t.elapsed();
        r
    }

    /// The settled world, with the wait added to `settle_time`.
    fn settled(&mut self) -> Result<&World> {
        let t = Instant::now();
        let w = self.target.settled();
        self.settle_time += t.elapsed();
        w
    }

    fn line(&mut self, sl: &ScriptLine) -> Result<()> {
        match &sl.line {
            Line::Ops(batch) => {
                self.timed_edit(|t, user| t.edit(user, batch))?;
                self.edits += 1;
            }
            Line::RandomEdits(r) => {
                let w = self.settled()?;
                let batches = r.batches(w.size(), w.materials().len());
                self.timed_edit(|t, user| batches.iter().try_for_each(|b| t.edit(user, b).map(drop)))?;
                self.edits += batches.len() as u64;
            }
            Line::Undo | Line::Redo => {
                let redo = sl.line == Line::Redo;
                self.timed_edit(|t, user| t.history(user, redo))?;
                self.edits += 1;
            }
            Line::AsUser(u) => self.user = u.clone(),
            Line::Camera(c) => self.camera = Some(*c),
            Line::EndFrame { fps } => {
                self.frames += 1;
                match fps {
                    Some(fps) => {
                        // Pace against the start of this run of frames at this rate, so
                        // that delays do not add up; a new rate starts a new run.
                        let pace = match &mut self.pace {
                            Some(p) if p.fps == *fps => p,
                            slot => slot.insert(Pace {
                                fps: *fps,
                                start: Instant::now(),
                                frames: 0,
                            }),
                        };
                        pace.frames += 1;
                        let due = pace.start + Duration::from_secs_f64(pace.frames as f64 / pace.fps);
                        std::thread::sleep(due.saturating_duration_since(Instant::now()));
                    }
                    None => self.pace = None,
                }
            }
            Line::WaitVersion(v) => {
                self.target.wait_version(*v)?;
                self.checkpoint(sl.number, "wait_version", None, None, true)?;
            }
            Line::ExpectDigest(d) => {
                let got = self.settled()?.digest();
                self.checkpoint(sl.number, "expect_digest", Some(d.to_string()), None, got == *d)?;
            }
            Line::Render(r) => {
                let mode = Mode::parse(&r.mode).ok_or_else(|| anyhow!("unknown render mode '{}'", r.mode))?;
                let camera = r
                    .camera
                    .or(self.camera)
                    .ok_or_else(|| anyhow!("render: no camera (give one, or a camera line before)"))?;
                if self.headless.is_none() {
                    self.headless = Some(Headless::new().context("render: the GPU client is not available")?);
                }
                let t = Instant::now();
                let world = self.target.settled()?;
                self.settle_time += t.elapsed();
                let headless = self.headless.as_mut().expect("opened above");
                let frame = headless.frame(world, &camera, (r.size[0], r.size[1]), mode, false)?;
                let out = self.folder.join(&r.out);
                std::fs::write(&out, frame.png()?).with_context(|| format!("cannot write {}", out.display()))?;
                self.last_frame = Some(frame);
                self.renders += 1;
            }
            Line::ExpectImage(e) => {
                let frame = self
                    .last_frame
                    .as_ref()
                    .ok_or_else(|| anyhow!("expect_image: nothing was rendered before"))?;
                let path = self.folder.join(&e.file);
                let bytes = std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
                let reference = Frame::from_png(&bytes).with_context(|| path.display().to_string())?;
                let diff = frame.mean_abs_diff(&reference).ok_or_else(|| {
                    anyhow!(
                        "expect_image: {} is {}x{}, the frame {}x{}",
                        path.display(),
                        reference.width,
                        reference.height,
                        frame.width,
                        frame.height
                    )
                })?;
                let expected = format!("mean abs diff ≤ {}", e.max_mean_abs_diff);
                self.checkpoint(
                    sl.number,
                    "expect_image",
                    Some(expected),
                    Some(diff),
                    diff <= e.max_mean_abs_diff,
                )?;
            }
        }
        Ok(())
    }

    fn checkpoint(
        &mut self,
        line: usize,
        kind: &'static str,
        expected: Option<String>,
        measured: Option<f64>,
        ok: bool,
    ) -> Result<()> {
        let w = self.settled()?;
        let c = Checkpoint {
            line,
            kind,
            version: w.version(),
            digest: w.digest().to_string(),
            expected,
            measured,
            ok,
        };
        if !ok {
            tracing::warn!(line, kind, version = c.version, digest = %c.digest, expected = ?c.expected, "expectation failed");
        }
        self.checkpoints.push(c);
        Ok(())
    }
}

/// Reads the script file in the chosen format.
fn read_script(a: &Args) -> Result<Vec<ScriptLine>> {
    let text = std::fs::read_to_string(&a.script).with_context(|| format!("cannot read {}", a.script.display()))?;
    if a.format != "hashdag" {
        return Ok(parse_script(&text)?);
    }
    let m = HashdagMapping {
        scale: a.scale,
        offset: a.offset,
        material: a.material,
    };
    // Numbered by CSV row, so that run errors and checkpoints name the row.
    to_script_lines(&text, &m)?
        .into_iter()
        .map(|(row, l)| {
            parse_line(&l)
                .map(|line| ScriptLine { number: row, line })
                .map_err(|message| anyhow!("row {row}: {message}"))
        })
        .collect()
}

/// Runs `replay`.
pub fn run(a: Args) -> Result<()> {
    let t_parse = Instant::now();
    let lines = read_script(&a).with_context(|| a.script.display().to_string())?;
    let parse = t_parse.elapsed().as_secs_f64();
    let timeout = seconds(a.timeout, "--timeout")?;
    let mut local;
    let mut remote;
    let (target, name): (&mut dyn Target, _) = match &a.world {
        Some(path) => {
            local = Local {
                world: load_world(path)?,
                histories: Histories::default(),
                limits: a.limits.limits(),
            };
            (&mut local, "world")
        }
        None => {
            remote = Remote {
                server: a.server.clone(),
                default_user: a.user.clone(),
                runtime: tokio::runtime::Builder::new_multi_thread().enable_all().build()?,
                clients: HashMap::new(),
                next_seq: session_client_seq(),
                version: 0,
                mirror: None,
                timeout,
            };
            (&mut remote, "server")
        }
    };
    let folder = a.script.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut run = Run {
        target,
        folder,
        user: a.user.clone(),
        camera: None,
        headless: None,
        last_frame: None,
        pace: None,
        edits: 0,
        frames: 0,
        renders: 0,
        checkpoints: Vec::new(),
        edit_time: Duration::ZERO,
        settle_time: Duration::ZERO,
    };
    let t0 = Instant::now();
    let bar = progress(lines.len() as u64, "replaying", "lines");
    for sl in &lines {
        run.line(sl).with_context(|| format!("line {}", sl.number))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let seconds = t0.elapsed().as_secs_f64();
    let (edits, settling) = (run.edit_time.as_secs_f64(), run.settle_time.as_secs_f64());
    run.checkpoint(0, "end", None, None, true)?;
    if let Some(out) = &a.output {
        save_world(run.target.settled()?, out)?;
    }
    let failures = run.checkpoints.iter().filter(|c| !c.ok).count();
    let report = Report {
        target: name,
        lines: lines.len(),
        edits: run.edits,
        frames: run.frames,
        renders: run.renders,
        failures,
        passed: failures == 0,
        seconds,
        edits_per_second: run.edits as f64 / seconds.max(1e-9),
        profile: Profile {
            parse,
            edits,
            checkpoints: settling,
            other: (seconds - edits - settling).max(0.0),
        },
        checkpoints: run.checkpoints,
    };
    if a.json {
        print_json(&report)?;
    } else {
        let last = report.checkpoints.last().expect("the end checkpoint");
        println!(
            "{} lines, {} edits in {:.2} s ({:.0} edits/s); final version {} digest {}; {} of {} checkpoints failed",
            report.lines,
            report.edits,
            report.seconds,
            report.edits_per_second,
            last.version,
            last.digest,
            failures,
            report.checkpoints.len()
        );
    }
    if failures > 0 {
        bail!("{failures} expectation(s) failed");
    }
    Ok(())
}
