//! Routing frame requests to render nodes.
//!
//! Nodes register over a bidirectional stream (`RegisterNode`): a hello with their
//! capabilities, then one result per job the router sends them. A `RenderFrame` request
//! goes to the least loaded node that supports its mode and size. It fails fast with
//! UNAVAILABLE when no node can take it and with RESOURCE_EXHAUSTED when the jobs in
//! flight reach the queue bound; a node that answers with an error is believed, but a node
//! that leaves or misses the deadline has the request retried once on another node.

use crate::metrics::Metrics;
use naadf_proto::v1::{FrameJob, FrameReply, FrameRequest, FrameResult, NodeHello};
use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{mpsc, oneshot};
use tonic::Status;

/// Jobs in flight over all nodes before new requests are refused.
pub const DEFAULT_QUEUE: usize = 64;
/// Deadline of a request that names none (the protocol's, which render nodes keep too).
pub const DEFAULT_DEADLINE: Duration = naadf_proto::DEFAULT_FRAME_DEADLINE;
/// Largest frame edge a request may ask for.
pub const MAX_FRAME_EDGE: u32 = 16384;

/// Checks what the server can check of a request before routing it: the camera and the
/// size (the mode is whatever some node advertises).
pub fn check_request(req: &FrameRequest) -> Result<(), Status> {
    naadf_world::camera::Camera::from_json(&req.camera)
        .map_err(|e| Status::invalid_argument(format!("camera: {e}")))?;
    if !(1..=MAX_FRAME_EDGE).contains(&req.width) || !(1..=MAX_FRAME_EDGE).contains(&req.height) {
        return Err(Status::invalid_argument(format!(
            "frame size {}x{}: each edge must be 1..={MAX_FRAME_EDGE}",
            req.width, req.height
        )));
    }
    Ok(())
}

/// A node's answer, or why there is none.
type Answer = Result<FrameResult, Gone>;

/// The node left, or its stream broke, before answering.
#[derive(Debug)]
struct Gone;

/// A registered node.
struct Node {
    hello: NodeHello,
    user: String,
    jobs: mpsc::Sender<Result<FrameJob, Status>>,
    inflight: usize,
    served: u64,
    last_error: String,
}

/// A node as the status page shows it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct NodeView {
    /// Registration id.
    pub id: u64,
    /// The registering user.
    pub user: String,
    /// Adapter name and backend.
    pub adapter: String,
    /// Jobs in flight.
    pub inflight: usize,
    /// Frames served.
    pub served: u64,
    /// The last error it reported.
    pub last_error: String,
}

#[derive(Default)]
struct Inner {
    nodes: BTreeMap<u64, Node>,
    /// Job id → (node, where its answer goes).
    pending: HashMap<u64, (u64, oneshot::Sender<Answer>)>,
    /// Camera stream → the node that renders it (it keeps the stream's history).
    streams: HashMap<String, u64>,
    next_id: u64,
}

/// Most camera streams the router remembers; past it, one is forgotten per new stream
/// (its next frame may then go to another node and start a new history there).
const MAX_STREAMS: usize = 4096;

/// The router.
pub struct Router {
    inner: Mutex<Inner>,
    queue: usize,
    metrics: Arc<Metrics>,
}

impl Router {
    /// A router refusing requests beyond `queue` jobs in flight, recording into `metrics`.
    pub fn new(queue: usize, metrics: Arc<Metrics>) -> Self {
        Router {
            inner: Mutex::default(),
            queue: queue.max(1),
            metrics,
        }
    }

    /// Publishes node `node`'s jobs in flight and the total.
    fn gauge(&self, g: &Inner, node: u64) {
        let total = g.nodes.values().map(|n| n.inflight).sum();
        let jobs = g.nodes.get(&node).map_or(0, |n| n.inflight);
        self.metrics.in_flight(node, jobs, total);
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // The state stays consistent under every panic-free path; a poisoned lock only
        // means another request panicked mid-update, and the maps are still valid.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Adds a node; jobs for it go to `jobs`. Returns its id.
    pub fn register(&self, user: &str, hello: NodeHello, jobs: mpsc::Sender<Result<FrameJob, Status>>) -> u64 {
        let mut g = self.lock();
        g.next_id += 1;
        let id = g.next_id;
        tracing::info!(node = id, user, adapter = %hello.adapter, "render node registered");
        g.nodes.insert(
            id,
            Node {
                hello,
                user: user.to_owned(),
                jobs,
                inflight: 0,
                served: 0,
                last_error: String::new(),
            },
        );
        id
    }

    /// Removes node `id`; its jobs in flight are answered as gone (and retried elsewhere).
    pub fn unregister(&self, id: u64) {
        let mut g = self.lock();
        g.nodes.remove(&id);
        g.streams.retain(|_, node| *node != id);
        let gone: Vec<u64> = g
            .pending
            .iter()
            .filter(|(_, (n, _))| *n == id)
            .map(|(j, _)| *j)
            .collect();
        for j in gone {
            if let Some((_, tx)) = g.pending.remove(&j) {
                let _ = tx.send(Err(Gone));
            }
        }
        self.gauge(&g, id);
        tracing::info!(node = id, "render node left");
    }

    /// Delivers a node's result to the waiting request (unknown ids are late answers to
    /// requests that gave up, and are dropped).
    pub fn deliver(&self, node: u64, result: FrameResult) {
        let mut g = self.lock();
        // Only the node a job went to may answer it, and only once (an abandoned job's
        // counters were settled when it was abandoned).
        if g.pending.get(&result.id).is_none_or(|(owner, _)| *owner != node) {
            return;
        }
        let Some((_, tx)) = g.pending.remove(&result.id) else {
            return;
        };
        if let Some(n) = g.nodes.get_mut(&node) {
            n.inflight = n.inflight.saturating_sub(1);
            if result.error.is_empty() {
                n.served += 1;
            } else {
                n.last_error = result.error.clone();
            }
        }
        self.gauge(&g, node);
        let _ = tx.send(Ok(result));
    }

    /// The registered nodes.
    pub fn nodes(&self) -> Vec<NodeView> {
        self.lock()
            .nodes
            .iter()
            .map(|(&id, n)| NodeView {
                id,
                user: n.user.clone(),
                adapter: n.hello.adapter.clone(),
                inflight: n.inflight,
                served: n.served,
                last_error: n.last_error.clone(),
            })
            .collect()
    }

    /// Sends `req` to the node of its camera stream if it has one that can still take it,
    /// else to the least loaded node that can, other than `avoid`; returns the node and
    /// where its answer arrives.
    fn dispatch(
        &self,
        req: &FrameRequest,
        avoid: Option<u64>,
    ) -> Result<(u64, u64, oneshot::Receiver<Answer>), Status> {
        let mut g = self.lock();
        let inflight: usize = g.nodes.values().map(|n| n.inflight).sum();
        let fits = |n: &Node| {
            n.hello.modes.contains(&req.mode) && req.width <= n.hello.max_width && req.height <= n.hello.max_height
        };
        let sticky = (!req.stream.is_empty())
            .then(|| g.streams.get(&req.stream).copied())
            .flatten()
            .filter(|id| Some(*id) != avoid && g.nodes.get(id).is_some_and(fits));
        let least_loaded = || {
            g.nodes
                .iter()
                .filter(|(id, n)| Some(**id) != avoid && fits(n))
                .min_by_key(|(id, n)| (n.inflight, **id))
                .map(|(&id, _)| id)
        };
        let Some(node) = sticky.or_else(least_loaded) else {
            return Err(Status::unavailable(format!(
                "no render node can take a {}x{} {} frame ({} registered)",
                req.width,
                req.height,
                req.mode,
                g.nodes.len()
            )));
        };
        if inflight >= self.queue {
            return Err(Status::resource_exhausted(format!(
                "the render queue is full ({inflight} frames in flight); retry later"
            )));
        }
        if !req.stream.is_empty() && g.streams.get(&req.stream) != Some(&node) {
            if g.streams.len() >= MAX_STREAMS
                && let Some(old) = g.streams.keys().next().cloned()
            {
                g.streams.remove(&old);
            }
            g.streams.insert(req.stream.clone(), node);
        }
        g.next_id += 1;
        let id = g.next_id;
        let job = FrameJob {
            id,
            request: Some(req.clone()),
        };
        let n = g.nodes.get_mut(&node).expect("chosen above");
        if n.jobs.try_send(Ok(job)).is_err() {
            return Err(Status::unavailable("the chosen render node is not reading its jobs"));
        }
        n.inflight += 1;
        let (tx, rx) = oneshot::channel();
        g.pending.insert(id, (node, tx));
        self.gauge(&g, node);
        Ok((node, id, rx))
    }

    /// Forgets job `id` of `node` (its deadline passed).
    fn abandon(&self, node: u64, id: u64) {
        let mut g = self.lock();
        if g.pending.remove(&id).is_some()
            && let Some(n) = g.nodes.get_mut(&node)
        {
            n.inflight = n.inflight.saturating_sub(1);
            n.last_error = "missed a deadline".into();
        }
        self.gauge(&g, node);
    }

    /// Renders `req` on a node: one retry on another node if the first leaves or misses
    /// the deadline (each attempt gets the whole deadline).
    pub async fn render(&self, req: FrameRequest) -> Result<FrameReply, Status> {
        let deadline = match req.timeout_ms {
            0 => DEFAULT_DEADLINE,
            ms => Duration::from_millis(u64::from(ms)),
        };
        let mut avoid = None;
        let mut failure = None;
        let start = Instant::now();
        for _attempt in 0..2 {
            let (node, id, rx) = match self.dispatch(&req, avoid) {
                Ok(d) => d,
                // A retry with no other node reports why the first attempt failed.
                Err(e) => return Err(failure.unwrap_or(e)),
            };
            match tokio::time::timeout(deadline, rx).await {
                Ok(Ok(Ok(r))) if r.error.is_empty() => {
                    self.metrics.frame_served(node, start.elapsed().as_secs_f64());
                    let adapter = self
                        .lock()
                        .nodes
                        .get(&node)
                        .map(|n| n.hello.adapter.clone())
                        .unwrap_or_default();
                    return Ok(FrameReply {
                        version: r.version,
                        width: r.width,
                        height: r.height,
                        image: r.image,
                        node: adapter,
                    });
                }
                Ok(Ok(Ok(r))) => {
                    return Err(Status::failed_precondition(format!(
                        "the render node refused: {}",
                        r.error
                    )));
                }
                Ok(_) => failure = Some(Status::unavailable("the render node left mid-request")),
                Err(_) => {
                    self.abandon(node, id);
                    failure = Some(Status::deadline_exceeded(format!(
                        "no frame within {} ms",
                        deadline.as_millis()
                    )));
                }
            }
            avoid = Some(node);
        }
        Err(failure.unwrap_or_else(|| Status::unavailable("no render node answered")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tonic::Code;

    fn hello(modes: &[&str]) -> NodeHello {
        NodeHello {
            adapter: format!("test node ({})", modes.join(",")),
            modes: modes.iter().map(|m| m.to_string()).collect(),
            max_width: 64,
            max_height: 64,
        }
    }

    fn req(mode: &str, timeout_ms: u32) -> FrameRequest {
        FrameRequest {
            camera: r#"{"pos":[1,2,3],"yaw":0,"pitch":0}"#.into(),
            width: 8,
            height: 8,
            mode: mode.into(),
            min_version: 0,
            raw: true,
            timeout_ms,
            ..Default::default()
        }
    }

    /// Registers a node; with `version`, a task answers each of its jobs with a frame of
    /// that version, otherwise the node never answers.
    fn node(router: &Arc<Router>, modes: &[&str], version: Option<u64>) -> u64 {
        let (tx, mut rx) = mpsc::channel(8);
        let id = router.register("node", hello(modes), tx);
        let r = router.clone();
        tokio::spawn(async move {
            while let Some(Ok(job)) = rx.recv().await {
                if let Some(version) = version {
                    r.deliver(
                        id,
                        FrameResult {
                            id: job.id,
                            version,
                            width: 8,
                            height: 8,
                            image: vec![0; 256],
                            error: String::new(),
                        },
                    );
                }
            }
        });
        id
    }

    #[tokio::test]
    async fn without_a_fitting_node_requests_fail_fast() {
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        assert_eq!(r.render(req("albedo", 0)).await.unwrap_err().code(), Code::Unavailable);
        node(&r, &["material"], Some(1));
        let e = r.render(req("albedo", 0)).await.unwrap_err();
        assert_eq!(e.code(), Code::Unavailable, "no node renders albedo: {e:?}");
        let mut big = req("material", 0);
        big.width = 65;
        assert_eq!(r.render(big).await.unwrap_err().code(), Code::Unavailable);
        assert_eq!(r.render(req("material", 0)).await.unwrap().version, 1);
    }

    #[tokio::test]
    async fn a_camera_stream_stays_on_its_node_while_the_node_can_take_it() {
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        let first = node(&r, &["baseline"], Some(5));
        node(&r, &["baseline"], Some(6));
        let stream = |name: &str| FrameRequest {
            stream: name.into(),
            ..req("baseline", 0)
        };
        assert_eq!(r.render(stream("s")).await.unwrap().version, 5);
        // The stream's node is now the busier one; the stream stays, others go elsewhere.
        r.lock().nodes.get_mut(&first).unwrap().inflight = 3;
        assert_eq!(r.render(stream("s")).await.unwrap().version, 5);
        assert_eq!(r.render(stream("t")).await.unwrap().version, 6);
        assert_eq!(r.render(req("baseline", 0)).await.unwrap().version, 6);
        // When the node leaves, the stream moves and stays on its new node.
        r.unregister(first);
        assert_eq!(r.render(stream("s")).await.unwrap().version, 6);
        let g = r.lock();
        assert_eq!(g.streams.get("s"), g.streams.get("t"));
    }

    #[tokio::test]
    async fn the_least_loaded_fitting_node_serves() {
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        let silent = node(&r, &["albedo", "steps"], None);
        node(&r, &["albedo"], Some(7));
        // The silent node holds a job, so the other one is less loaded for albedo.
        let held = tokio::spawn({
            let r = r.clone();
            async move { r.render(req("steps", 100)).await }
        });
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert_eq!(r.nodes().iter().find(|n| n.id == silent).unwrap().inflight, 1);
        let ok = r.render(req("albedo", 0)).await.unwrap();
        assert_eq!(ok.version, 7);
        assert!(ok.node.contains("albedo"));
        assert_eq!(held.await.unwrap().unwrap_err().code(), Code::DeadlineExceeded);
        let views = r.nodes();
        assert_eq!(views.iter().map(|n| n.served).sum::<u64>(), 1);
        assert_eq!(
            views.iter().find(|n| n.id == silent).unwrap().last_error,
            "missed a deadline"
        );
    }

    #[tokio::test]
    async fn a_node_that_leaves_mid_request_is_retried_once_elsewhere() {
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        let first = node(&r, &["albedo"], None);
        let pending = tokio::spawn({
            let r = r.clone();
            async move { r.render(req("albedo", 5000)).await }
        });
        tokio::time::sleep(Duration::from_millis(20)).await;
        node(&r, &["albedo"], Some(3));
        r.unregister(first);
        let reply = pending.await.unwrap().unwrap();
        assert_eq!(reply.version, 3, "served by the second node");
        // With no other node, the failure itself is reported.
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        let only = node(&r, &["albedo"], None);
        let pending = tokio::spawn({
            let r = r.clone();
            async move { r.render(req("albedo", 5000)).await }
        });
        tokio::time::sleep(Duration::from_millis(20)).await;
        r.unregister(only);
        let e = pending.await.unwrap().unwrap_err();
        assert_eq!(e.code(), Code::Unavailable);
        assert!(e.message().contains("left"), "{e:?}");
    }

    #[tokio::test]
    async fn a_full_queue_is_resource_exhausted() {
        let r = Arc::new(Router::new(1, Arc::default()));
        node(&r, &["albedo"], None);
        let held = tokio::spawn({
            let r = r.clone();
            async move { r.render(req("albedo", 200)).await }
        });
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert_eq!(
            r.render(req("albedo", 0)).await.unwrap_err().code(),
            Code::ResourceExhausted
        );
        assert_eq!(held.await.unwrap().unwrap_err().code(), Code::DeadlineExceeded);
    }

    #[tokio::test]
    async fn a_node_error_is_reported_not_retried() {
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        let (tx, mut rx) = mpsc::channel(8);
        let id = r.register("node", hello(&["albedo"]), tx);
        let answering = r.clone();
        tokio::spawn(async move {
            while let Some(Ok(job)) = rx.recv().await {
                answering.deliver(
                    id,
                    FrameResult {
                        id: job.id,
                        error: "no GPU memory".into(),
                        ..FrameResult::default()
                    },
                );
            }
        });
        let e = r.render(req("albedo", 0)).await.unwrap_err();
        assert_eq!(e.code(), Code::FailedPrecondition);
        assert!(e.message().contains("no GPU memory"));
        assert_eq!(r.nodes()[0].last_error, "no GPU memory");
    }

    #[tokio::test]
    async fn a_late_answer_to_an_abandoned_job_is_dropped() {
        let r = Arc::new(Router::new(DEFAULT_QUEUE, Arc::default()));
        let (tx, mut rx) = mpsc::channel(8);
        let id = r.register("node", hello(&["albedo"]), tx);
        let e = r.render(req("albedo", 30)).await.unwrap_err();
        assert_eq!(e.code(), Code::DeadlineExceeded);
        let job = rx.recv().await.unwrap().unwrap();
        r.deliver(
            id,
            FrameResult {
                id: job.id,
                version: 1,
                ..FrameResult::default()
            },
        );
        let n = &r.nodes()[0];
        assert_eq!((n.inflight, n.served), (0, 0), "counted once, when abandoned");
        // Another node's answer to this node's job is ignored too.
        r.deliver(
            id + 1,
            FrameResult {
                id: job.id,
                ..FrameResult::default()
            },
        );
        assert_eq!(r.nodes()[0].inflight, 0);
    }
}
