//! The gRPC service: authentication, roles, request limits, and the hand-off to the actor.

use crate::net::auth::Caller;
use crate::shared::Shared;
use crate::stream::join;
use crate::stream::messages::{Action, Request};
use governor::clock::Clock;
use naadf_proto::requests::{despawn_batch, move_batch, spawn_batch};
use naadf_proto::v1::world_service_server::WorldService;
use naadf_proto::v1::{
    DespawnEntitiesRequest, EditReply, EditRequest, FrameJob, FrameReply, FrameRequest, HistoryRequest, JoinRequest,
    MoveEntitiesRequest, NodeMessage, PresenceReply, PresenceRequest, SpawnEntitiesRequest, StatusReply, StatusRequest,
    WorldMessage, node_message,
};
use naadf_proto::{PROTOCOL_VERSION, RETRY_AFTER_MS};
use naadf_world::ops::{Batch, Op};
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{mpsc, oneshot};
use tokio_stream::Stream;
use tokio_stream::wrappers::ReceiverStream;
use tonic::{Request as Req, Response, Status};

/// Messages buffered per render node's job stream.
const STREAM_BUFFER: usize = 64;

/// Longest status message the service sends, in bytes. The message travels in a response
/// header (`grpc-message`), and HTTP/2 peers drop a connection whose headers are too big;
/// errors quote client input (clipped where they are made), and this is the backstop.
pub const MAX_STATUS_MESSAGE: usize = 1024;

/// `s` with its message cut to [`MAX_STATUS_MESSAGE`] bytes (at a character boundary,
/// with an ellipsis); its code and metadata are kept.
pub fn bounded(s: Status) -> Status {
    if s.message().len() <= MAX_STATUS_MESSAGE {
        return s;
    }
    let mut cut = MAX_STATUS_MESSAGE - '…'.len_utf8();
    while !s.message().is_char_boundary(cut) {
        cut -= 1;
    }
    let message = format!("{}…", &s.message()[..cut]);
    let mut out = Status::new(s.code(), message);
    *out.metadata_mut() = s.metadata().clone();
    out
}

/// Every reply of the service passes here: a refusal leaves with a bounded message.
fn reply<T>(r: Result<T, Status>) -> Result<T, Status> {
    r.map_err(bounded)
}

/// Checks a frame request before routing it: camera and size
/// ([`crate::render_router::check_request`]) and a mode of the protocol
/// ([`naadf_proto::FRAME_MODES`]), so that a mode no node could ever render is a bad
/// request, not an unavailable node.
pub fn check_frame(req: &FrameRequest) -> Result<(), Status> {
    crate::render_router::check_request(req)?;
    if !naadf_proto::FRAME_MODES.contains(&req.mode.as_str()) {
        return Err(Status::invalid_argument(format!(
            "mode '{}': expected one of {}",
            naadf_world::ops::clip_input(&req.mode, naadf_world::ops::MAX_QUOTED_CHARS),
            naadf_proto::FRAME_MODES.join(", ")
        )));
    }
    use naadf_proto::{MAX_FRAME_FRAMES, MAX_FRAME_SPP, MAX_FRAME_STRING};
    if req.spp > MAX_FRAME_SPP || req.frames > MAX_FRAME_FRAMES {
        return Err(Status::invalid_argument(format!(
            "{} spp and {} frames: at most {MAX_FRAME_SPP} and {MAX_FRAME_FRAMES}",
            req.spp, req.frames
        )));
    }
    if [&req.sky, &req.sun, &req.stream]
        .iter()
        .any(|s| s.len() > MAX_FRAME_STRING)
    {
        return Err(Status::invalid_argument(format!(
            "sky, sun and stream are at most {MAX_FRAME_STRING} bytes each"
        )));
    }
    Ok(())
}

/// How long a caller turned away by a full render queue is asked to wait: about a frame.
const RENDER_RETRY: Duration = Duration::from_millis(100);

/// A RESOURCE_EXHAUSTED refusal that a retry after `after` may pass: it carries
/// [`RETRY_AFTER_MS`], which tells clients to back off rather than give up.
pub fn retry_later(message: String, after: Duration) -> Status {
    let mut s = Status::resource_exhausted(message);
    let ms = after.as_millis().max(1).to_string();
    s.metadata_mut()
        .insert(RETRY_AFTER_MS, ms.parse().expect("digits are valid metadata"));
    s
}

/// The `WorldService` implementation.
#[derive(Clone)]
pub struct WorldServer {
    shared: Arc<Shared>,
    actor: mpsc::Sender<Request>,
}

impl WorldServer {
    /// A service handing requests to `actor`.
    pub fn new(shared: Arc<Shared>, actor: mpsc::Sender<Request>) -> Self {
        Self { shared, actor }
    }

    fn caller<T>(&self, r: &Req<T>) -> Result<Caller, Status> {
        self.shared.auth.caller(r.metadata())
    }

    /// Counts a refused edit request (any error: auth, role, parse, limits, the batch).
    fn count<T>(&self, r: Result<T, Status>) -> Result<T, Status> {
        if r.is_err() {
            self.shared.metrics.refused.inc();
        }
        reply(r)
    }

    /// Checks role and rate, then has the actor apply `action`.
    async fn submit(&self, caller: Caller, client_seq: u64, action: Action) -> Result<Response<EditReply>, Status> {
        caller.require_editor()?;
        if let Action::Batch(b) = &action
            && let Some(op) = b
                .ops
                .iter()
                .find(|o| matches!(o, Op::DefineMaterial { .. } | Op::DefineModel { .. }))
        {
            caller.require_admin(op.name())?;
        }
        if let Err(not_until) = self.shared.limiter.check_key(&caller.user) {
            let wait = not_until.wait_time_from(self.shared.limiter.clock().now());
            return Err(retry_later(
                format!(
                    "user '{}' is over the request rate limit ({} edits/s); slow down",
                    caller.quoted_user(),
                    self.shared.rate
                ),
                wait,
            ));
        }
        let (reply, rx) = oneshot::channel();
        self.actor
            .send(Request::Edit {
                user: caller.user,
                client_seq,
                action,
                reply,
            })
            .await
            .map_err(|_| Status::unavailable("the server is shutting down"))?;
        let r = rx
            .await
            .map_err(|_| Status::unavailable("the server is shutting down"))??;
        Ok(Response::new(r))
    }
}

fn bad(e: impl std::fmt::Display) -> Status {
    Status::invalid_argument(e.to_string())
}

/// A client's world stream, as the service returns it.
pub type WorldStream = Pin<Box<dyn Stream<Item = Result<WorldMessage, Status>> + Send>>;
type JobStream = Pin<Box<dyn Stream<Item = Result<FrameJob, Status>> + Send>>;

#[tonic::async_trait]
impl WorldService for WorldServer {
    type JoinStream = WorldStream;
    type RegisterNodeStream = JobStream;

    async fn register_node(&self, r: Req<tonic::Streaming<NodeMessage>>) -> Result<Response<JobStream>, Status> {
        reply(self.register_node_inner(r).await)
    }

    async fn render_frame(&self, r: Req<FrameRequest>) -> Result<Response<FrameReply>, Status> {
        let result = async {
            self.caller(&r)?;
            let req = r.into_inner();
            check_frame(&req)?;
            self.shared.router.render(req).await.map(Response::new).map_err(|s| {
                // The router's only RESOURCE_EXHAUSTED is a full queue, which drains.
                if s.code() == tonic::Code::ResourceExhausted {
                    retry_later(s.message().to_owned(), RENDER_RETRY)
                } else {
                    s
                }
            })
        }
        .await;
        reply(result)
    }

    async fn join(&self, r: Req<JoinRequest>) -> Result<Response<WorldStream>, Status> {
        reply(self.join_inner(r).await)
    }

    async fn publish(&self, r: Req<PresenceRequest>) -> Result<Response<PresenceReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            // Without tokens the "user" is whatever the caller sent: the name stands alone.
            let user = (!self.shared.auth.is_open()).then_some(caller.user.as_str());
            self.shared.presence.publish(user, r.into_inner())?;
            Ok(Response::new(PresenceReply {}))
        }
        .await;
        reply(result)
    }

    async fn edit(&self, r: Req<EditRequest>) -> Result<Response<EditReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            let req = r.into_inner();
            let batch = Batch::parse_line(&req.ops).map_err(bad)?;
            self.submit(caller, req.client_seq, Action::Batch(batch)).await
        }
        .await;
        self.count(result)
    }

    async fn spawn_entities(&self, r: Req<SpawnEntitiesRequest>) -> Result<Response<EditReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            let req = r.into_inner();
            let batch = spawn_batch(&req).map_err(bad)?;
            self.submit(caller, req.client_seq, Action::Batch(batch)).await
        }
        .await;
        self.count(result)
    }

    async fn move_entities(&self, r: Req<MoveEntitiesRequest>) -> Result<Response<EditReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            let req = r.into_inner();
            let batch = move_batch(&req).map_err(bad)?;
            self.submit(caller, req.client_seq, Action::Batch(batch)).await
        }
        .await;
        self.count(result)
    }

    async fn despawn_entities(&self, r: Req<DespawnEntitiesRequest>) -> Result<Response<EditReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            let req = r.into_inner();
            self.submit(caller, req.client_seq, Action::Batch(despawn_batch(&req)))
                .await
        }
        .await;
        self.count(result)
    }

    async fn undo(&self, r: Req<HistoryRequest>) -> Result<Response<EditReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            self.submit(caller, r.into_inner().client_seq, Action::Undo).await
        }
        .await;
        self.count(result)
    }

    async fn redo(&self, r: Req<HistoryRequest>) -> Result<Response<EditReply>, Status> {
        let result = async {
            let caller = self.caller(&r)?;
            self.submit(caller, r.into_inner().client_seq, Action::Redo).await
        }
        .await;
        self.count(result)
    }

    async fn status(&self, r: Req<StatusRequest>) -> Result<Response<StatusReply>, Status> {
        reply(self.status_inner(r).await)
    }
}

impl WorldServer {
    /// A render node's registration: its hello, then its results until it leaves.
    async fn register_node_inner(&self, r: Req<tonic::Streaming<NodeMessage>>) -> Result<Response<JobStream>, Status> {
        let caller = self.caller(&r)?;
        caller.require_render_node()?;
        let mut inbound = r.into_inner();
        let hello = match inbound.message().await? {
            Some(NodeMessage {
                kind: Some(node_message::Kind::Hello(h)),
            }) => h,
            _ => return Err(Status::invalid_argument("a render node must start with a NodeHello")),
        };
        let (tx, rx) = mpsc::channel(STREAM_BUFFER);
        let id = self.shared.router.register(&caller.user, hello, tx);
        let shared = self.shared.clone();
        tokio::spawn(async move {
            // Results until the node leaves; a second hello is ignored.
            while let Ok(Some(m)) = inbound.message().await {
                if let Some(node_message::Kind::Result(res)) = m.kind {
                    shared.router.deliver(id, res);
                }
            }
            shared.router.unregister(id);
        });
        Ok(Response::new(Box::pin(ReceiverStream::new(rx))))
    }

    async fn join_inner(&self, r: Req<JoinRequest>) -> Result<Response<WorldStream>, Status> {
        let caller = self.caller(&r)?;
        let stream = join::start(self.shared.clone(), self.actor.clone(), caller.user, r.into_inner())?;
        Ok(Response::new(Box::pin(stream)))
    }

    async fn status_inner(&self, r: Req<StatusRequest>) -> Result<Response<StatusReply>, Status> {
        let caller = self.caller(&r)?;
        let s = crate::stream::messages::status(&self.actor)
            .await
            .ok_or_else(|| Status::unavailable("the server is shutting down"))?;
        Ok(Response::new(status_reply(&s, &self.shared, caller)))
    }
}

/// The `Status` answer for `caller` about the world state `s`, with the clients joined to
/// this process (a server or a relay).
pub fn status_reply(s: &crate::stream::messages::StatusInfo, shared: &Shared, caller: Caller) -> StatusReply {
    StatusReply {
        protocol_version: PROTOCOL_VERSION,
        size: s.size.to_vec(),
        version: s.version,
        growth_seq: s.growth_seq,
        quiescent: s.quiescent,
        digest: s.digest.to_string(),
        clients: shared.metrics.clients.get().max(0) as u32,
        user: caller.user,
        role: caller.role.name().to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_status_messages_are_cut_and_keep_code_and_metadata() {
        let short = bounded(Status::invalid_argument("fine"));
        assert_eq!((short.code(), short.message()), (tonic::Code::InvalidArgument, "fine"));
        let long = retry_later("é".repeat(20_000), Duration::from_millis(7));
        let cut = bounded(long);
        assert_eq!(cut.code(), tonic::Code::ResourceExhausted);
        assert!(cut.message().len() <= MAX_STATUS_MESSAGE, "{}", cut.message().len());
        assert!(cut.message().len() > MAX_STATUS_MESSAGE - 8);
        assert!(cut.message().ends_with("é…"), "{}", cut.message());
        assert_eq!(cut.metadata().get(RETRY_AFTER_MS).unwrap(), "7");
    }
}
