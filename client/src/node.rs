//! Render nodes: a [`RenderNode`] keeps a node serving — it follows the world, registers
//! ([`Client::register_node`]), renders each job once its mirror is quiescent at the job's
//! `min_version`, drops jobs past their deadline, and reconnects when the server goes
//! away, keeping the mirrored world so that a rejoin sends only what changed. How a frame
//! is made is the caller's: a closure renders a [`FrameSpec`] of a [`World`].

use crate::client::{Client, FrameImage, Job, NodeInfo, ServerAddress};
use crate::error::Error;
use crate::frame::FrameSpec;
use crate::session::Session;
use naadf_world::World;
use std::fmt::Display;
use std::future::Future;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// What a render node says of itself (for a health endpoint): kept current as it serves,
/// shared with whoever reports it ([`RenderNode::health`]).
#[derive(Debug, Default)]
pub struct NodeHealth {
    registered: AtomicBool,
    version: AtomicU64,
    frames: AtomicU64,
    failed: AtomicU64,
}

impl NodeHealth {
    /// Whether the node is registered with its server now (it is not while it reconnects).
    pub fn registered(&self) -> bool {
        self.registered.load(Ordering::Relaxed)
    }

    /// The version of the newest quiescent world the node's mirror held.
    pub fn version(&self) -> u64 {
        self.version.load(Ordering::Relaxed)
    }

    /// Frames rendered and sent back (a frame is counted as its answer leaves, so a
    /// requester that has it finds it counted).
    pub fn frames(&self) -> u64 {
        self.frames.load(Ordering::Relaxed)
    }

    /// Jobs answered with an error (the renderer failed or the spec was bad).
    pub fn failed(&self) -> u64 {
        self.failed.load(Ordering::Relaxed)
    }
}

/// A render node that keeps itself registered with a server, rendering with `render`.
///
/// ```no_run
/// # async fn demo() {
/// use naadf_client::node::RenderNode;
/// use naadf_client::{FrameImage, Mode, NodeInfo, ServerAddress};
/// let address = ServerAddress { token: Some("node".into()), ..ServerAddress::new("http://127.0.0.1:50051") };
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
    health: Arc<NodeHealth>,
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
            health: Arc::default(),
        }
    }

    /// The node's health, kept current while it runs.
    pub fn health(&self) -> Arc<NodeHealth> {
        self.health.clone()
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
            self.health.registered.store(false, Ordering::Relaxed);
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
        self.health.registered.store(true, Ordering::Relaxed);
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
            self.health.version.store(world.version(), Ordering::Relaxed);
            let (ready, later): (Vec<_>, Vec<_>) =
                waiting.drain(..).partition(|(_, j)| j.min_version() <= world.version());
            waiting = later;
            for (_, job) in ready {
                let frame = job
                    .spec()
                    .and_then(|spec| (self.render)(world, &spec).map_err(|e| format!("{e:#}")));
                let counter = if frame.is_ok() {
                    &self.health.frames
                } else {
                    &self.health.failed
                };
                // Counted before the answer leaves, so that whoever holds the frame finds it
                // counted; taken back if it could not be sent.
                counter.fetch_add(1, Ordering::Relaxed);
                registration
                    .answer(&job, world.version(), frame)
                    .await
                    .inspect_err(|_| {
                        counter.fetch_sub(1, Ordering::Relaxed);
                    })?;
            }
        }
    }
}
