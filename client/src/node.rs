//! Render nodes: a [`Registration`] receives the frame jobs the server routes to this
//! node and takes back the results; a [`RenderNode`] keeps a node serving — it follows the
//! world, registers, renders each job once its mirror is quiescent at the job's
//! `min_version`, drops jobs past their deadline, and reconnects when the server goes
//! away, keeping the mirrored world so that a rejoin sends only what changed. How a frame
//! is made is the caller's: a closure renders a [`FrameSpec`] of a [`World`].

use crate::client::{FrameImage, FrameSpec};
use crate::connect::ServerAddress;
use crate::error::Error;
use crate::gpu::Mode;
use crate::{Client, Session};
use naadf_proto::DEFAULT_FRAME_DEADLINE;
use naadf_proto::v1::{FrameJob, FrameRequest, FrameResult, NodeMessage, node_message};
use naadf_world::World;
use std::fmt::Display;
use std::future::Future;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;

/// What a render node tells the server it can do.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeInfo {
    /// Adapter name and backend, shown on the server's status page.
    pub adapter: String,
    /// Modes it renders.
    pub modes: Vec<Mode>,
    /// Largest frame it renders (width, height).
    pub max_size: (u32, u32),
}

/// A frame job from the server.
#[derive(Clone, Debug)]
pub struct Job {
    id: u64,
    request: Option<FrameRequest>,
}

impl Job {
    /// The id its result names.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The oldest world version the frame may show.
    pub fn min_version(&self) -> u64 {
        self.request.as_ref().map_or(0, |r| r.min_version)
    }

    /// How long the server waits for the result after sending the job.
    pub fn deadline(&self) -> Duration {
        match self.request.as_ref().map_or(0, |r| r.timeout_ms) {
            0 => DEFAULT_FRAME_DEADLINE,
            ms => Duration::from_millis(u64::from(ms)),
        }
    }

    /// What to render, or why this client cannot.
    pub fn spec(&self) -> Result<FrameSpec, String> {
        FrameSpec::from_wire(self.request.as_ref().ok_or("the job has no request")?)
    }
}

/// A node's registration with the server ([`Client::register_node`]): jobs in, results
/// out. It ends when the server ends the job stream.
#[derive(Debug)]
pub struct Registration {
    jobs: tonic::Streaming<FrameJob>,
    results: mpsc::Sender<NodeMessage>,
}

impl Registration {
    pub(crate) fn new(jobs: tonic::Streaming<FrameJob>, results: mpsc::Sender<NodeMessage>) -> Self {
        Self { jobs, results }
    }

    /// The next job; `None` once the server ended the registration. Cancel-safe.
    pub async fn next_job(&mut self) -> Result<Option<Job>, Error> {
        Ok(self.jobs.message().await?.map(|j| Job {
            id: j.id,
            request: j.request,
        }))
    }

    /// Answers `job` with the frame rendered at world `version`, or with why it could not
    /// be rendered.
    pub async fn answer(&self, job: &Job, version: u64, frame: Result<FrameImage, String>) -> Result<(), Error> {
        let result = match frame {
            Ok(f) => FrameResult {
                id: job.id,
                version,
                width: f.width,
                height: f.height,
                image: f.data,
                error: String::new(),
            },
            Err(error) => FrameResult {
                id: job.id,
                error,
                ..FrameResult::default()
            },
        };
        self.results
            .send(NodeMessage {
                kind: Some(node_message::Kind::Result(result)),
            })
            .await
            .map_err(|_| Error::ConnectionLost("the server stopped taking results".into()))
    }
}

/// A render node that keeps itself registered with a server, rendering with `render`.
///
/// ```no_run
/// # async fn demo() {
/// use naadf_client::node::{NodeInfo, RenderNode};
/// use naadf_client::{FrameImage, ServerAddress, gpu::Mode};
/// let address = ServerAddress { url: "http://127.0.0.1:50051".into(), token: Some("node".into()), ca: None };
/// let info = NodeInfo { adapter: "a test pattern".into(), modes: vec![Mode::Albedo], max_size: (64, 64) };
/// let render = |_world: &naadf_world::World, spec: &naadf_client::FrameSpec| -> Result<FrameImage, String> {
///     let (width, height) = spec.size;
///     Ok(FrameImage { width, height, data: vec![255; (width * height * 4) as usize] })
/// };
/// let mut node = RenderNode::new(address, info, std::time::Duration::from_secs(1), render);
/// node.run(async { tokio::signal::ctrl_c().await.unwrap() }).await;
/// # }
/// ```
pub struct RenderNode<R> {
    address: ServerAddress,
    info: NodeInfo,
    retry: Duration,
    render: R,
    /// Kept across reconnections: its channel reconnects by itself.
    client: Option<Client>,
    /// Kept across reconnections, so that a rejoin announces the mirrored world.
    session: Option<Session>,
}

impl<R, E> RenderNode<R>
where
    R: FnMut(&World, &FrameSpec) -> Result<FrameImage, E>,
    E: Display,
{
    /// A node for the server at `address`, announcing `info`, retrying every `retry`
    /// after a connection ends, and making frames with `render` (its error becomes the
    /// job's error result, with `{:#}`).
    pub fn new(address: ServerAddress, info: NodeInfo, retry: Duration, render: R) -> Self {
        Self {
            address,
            info,
            retry,
            render,
            client: None,
            session: None,
        }
    }

    /// Serves until `stop` resolves, reconnecting whenever a connection ends.
    pub async fn run(&mut self, stop: impl Future<Output = ()>) {
        tokio::pin!(stop);
        loop {
            tokio::select! {
                r = self.connection() => match r {
                    Ok(()) => tracing::warn!("the server closed the connection; reconnecting"),
                    Err(e) => tracing::warn!("render node session ended: {e}; reconnecting"),
                },
                () = &mut stop => return,
            }
            tokio::select! {
                () = tokio::time::sleep(self.retry) => {}
                () = &mut stop => return,
            }
        }
    }

    /// One connection: join, register, serve jobs until either stream ends.
    async fn connection(&mut self) -> Result<(), Error> {
        let client = match &self.client {
            Some(c) => c.clone(),
            None => self.client.insert(self.address.connect().await?).clone(),
        };
        if let Some(s) = &mut self.session {
            s.rejoin().await?;
        } else {
            self.session = Some(client.join(None).await?);
        }
        let session = self.session.as_mut().expect("joined above");
        let mut registration = client.register_node(&self.info).await?;
        tracing::info!(adapter = %self.info.adapter, "registered as a render node");
        // Jobs waiting for the mirror to reach their version, with when they came.
        let mut waiting: Vec<(Instant, Job)> = Vec::new();
        loop {
            tokio::select! {
                p = session.next() => if p?.is_none() {
                    return Ok(());
                },
                j = registration.next_job() => match j? {
                    Some(j) => waiting.push((Instant::now(), j)),
                    None => return Ok(()),
                },
            }
            // A job past its deadline has been given up by the server: drop it (also while
            // the world is not quiescent, so that waiting jobs cannot pile up).
            waiting.retain(|(since, j)| since.elapsed() < j.deadline());
            // Serve every job whose version the quiescent mirror has reached: a frame shows
            // the quiescent state of its version, as a local render of that world would.
            let mirror = session.mirror();
            let Some(world) = mirror.world().filter(|_| mirror.is_quiescent()) else {
                continue;
            };
            let (ready, later): (Vec<_>, Vec<_>) =
                waiting.drain(..).partition(|(_, j)| j.min_version() <= world.version());
            waiting = later;
            for (_, job) in ready {
                let frame = job
                    .spec()
                    .and_then(|spec| (self.render)(world, &spec).map_err(|e| format!("{e:#}")));
                registration.answer(&job, world.version(), frame).await?;
            }
        }
    }
}
