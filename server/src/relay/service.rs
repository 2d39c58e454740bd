//! The relay's gRPC service: the read side served from its own mirror (Join through the
//! server's own join tasks, Status of the mirror), every write and frame request forwarded
//! upstream with the caller's metadata, the upstream's answer returned unchanged.

use super::gate::UpstreamAuth;
use super::upstream::{Upstream, upstream_error};
use crate::net::service::{WorldStream, bounded, status_reply};
use crate::shared::Shared;
use crate::stream::join;
use crate::stream::messages::Request;
use naadf_proto::v1::world_service_server::WorldService;
use naadf_proto::v1::{
    DespawnEntitiesRequest, EditReply, EditRequest, FrameJob, FrameReply, FrameRequest, HistoryRequest, JoinRequest,
    MoveEntitiesRequest, NodeMessage, PresenceReply, PresenceRequest, SpawnEntitiesRequest, StatusReply, StatusRequest,
};
use std::pin::Pin;
use std::sync::Arc;
use tokio::sync::mpsc;
use tokio_stream::Stream;
use tonic::{Request as Req, Response, Status};

/// The `WorldService` of a relay.
#[derive(Clone)]
pub struct RelayService {
    shared: Arc<Shared>,
    hub: mpsc::Sender<Request>,
    upstream: Upstream,
    auth: Arc<UpstreamAuth>,
}

impl RelayService {
    /// A service reading from `hub` and forwarding to `upstream`, whose answers about
    /// tokens `auth` keeps.
    pub fn new(shared: Arc<Shared>, hub: mpsc::Sender<Request>, upstream: Upstream, auth: Arc<UpstreamAuth>) -> Self {
        Self {
            shared,
            hub,
            upstream,
            auth,
        }
    }

    /// Counts a refused forwarded request, as the server counts refused edits.
    fn count<T>(&self, r: Result<T, Status>) -> Result<T, Status> {
        if r.is_err() {
            self.shared.metrics.refused.inc();
        }
        r
    }

    async fn join_inner(&self, r: Req<JoinRequest>) -> Result<Response<WorldStream>, Status> {
        let caller = self.auth.caller(r.metadata(), r.remote_addr()).await?;
        let stream = join::start(self.shared.clone(), self.hub.clone(), caller.user, r.into_inner())?;
        Ok(Response::new(Box::pin(stream)))
    }

    async fn status_inner(&self, r: Req<StatusRequest>) -> Result<Response<StatusReply>, Status> {
        let caller = self.auth.caller(r.metadata(), r.remote_addr()).await?;
        let s = crate::stream::messages::status(&self.hub)
            .await
            .ok_or_else(|| Status::unavailable("the relay has no world from its upstream yet"))?;
        Ok(Response::new(status_reply(&s, &self.shared, caller)))
    }
}

type JobStream = Pin<Box<dyn Stream<Item = Result<FrameJob, Status>> + Send>>;

/// Forwards a write RPC upstream: the caller's request as it came, the upstream's answer
/// (or refusal) as it went.
macro_rules! forward {
    ($self:ident, $r:ident, $rpc:ident) => {{
        $self.auth.admit($r.remote_addr()).await?;
        let answer = $self.upstream.client().$rpc(Upstream::forwarded($r)).await;
        $self.count(answer.map_err(upstream_error))
    }};
}

#[tonic::async_trait]
impl WorldService for RelayService {
    type JoinStream = WorldStream;
    type RegisterNodeStream = JobStream;

    async fn join(&self, r: Req<JoinRequest>) -> Result<Response<WorldStream>, Status> {
        self.join_inner(r).await.map_err(bounded)
    }

    async fn status(&self, r: Req<StatusRequest>) -> Result<Response<StatusReply>, Status> {
        self.status_inner(r).await.map_err(bounded)
    }

    async fn edit(&self, r: Req<EditRequest>) -> Result<Response<EditReply>, Status> {
        forward!(self, r, edit)
    }

    async fn spawn_entities(&self, r: Req<SpawnEntitiesRequest>) -> Result<Response<EditReply>, Status> {
        forward!(self, r, spawn_entities)
    }

    async fn move_entities(&self, r: Req<MoveEntitiesRequest>) -> Result<Response<EditReply>, Status> {
        forward!(self, r, move_entities)
    }

    async fn despawn_entities(&self, r: Req<DespawnEntitiesRequest>) -> Result<Response<EditReply>, Status> {
        forward!(self, r, despawn_entities)
    }

    async fn undo(&self, r: Req<HistoryRequest>) -> Result<Response<EditReply>, Status> {
        forward!(self, r, undo)
    }

    async fn redo(&self, r: Req<HistoryRequest>) -> Result<Response<EditReply>, Status> {
        forward!(self, r, redo)
    }

    async fn publish(&self, r: Req<PresenceRequest>) -> Result<Response<PresenceReply>, Status> {
        // The upstream stamps the caller and sends the table back down the relay's join.
        self.auth.admit(r.remote_addr()).await?;
        let answer = self.upstream.client().publish(Upstream::forwarded(r)).await;
        answer.map_err(upstream_error)
    }

    async fn render_frame(&self, r: Req<FrameRequest>) -> Result<Response<FrameReply>, Status> {
        self.auth.admit(r.remote_addr()).await?;
        let answer = self.upstream.client().render_frame(Upstream::forwarded(r)).await;
        answer.map_err(upstream_error)
    }

    async fn register_node(&self, _: Req<tonic::Streaming<NodeMessage>>) -> Result<Response<JobStream>, Status> {
        Err(Status::unimplemented(
            "a relay takes no render nodes: register the node with the server",
        ))
    }
}
