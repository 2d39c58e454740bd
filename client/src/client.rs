//! [`Client`]: the world service's calls as typed methods. Every method takes `&self` (the
//! client is a cheap handle to one connection; clone it for concurrent calls) and fails
//! with a typed [`Error`]. Beside it, what the calls take and answer: [`ServerAddress`]
//! (where to connect), edits, status and frames, and a render node's [`Registration`] with
//! its [`Job`]s.
//!
//! ```no_run
//! # async fn demo() -> Result<(), naadf_client::Error> {
//! use naadf_client::{Client, connect::session_client_seq};
//! let client = Client::connect("http://127.0.0.1:50051", Some("token"), None).await?;
//! let ack = client.edit(r#"{"op":"set","voxels":[[1,2,3,4]]}"#, session_client_seq()).await?;
//! let status = client.status().await?;
//! assert!(status.version >= ack.version);
//! # Ok(()) }
//! ```

use crate::connect::{self, RawClient};
use crate::error::Error;
use crate::frame::{FrameSpec, Mode};
use crate::session::{Session, WorldStream};
use naadf_proto::DEFAULT_FRAME_DEADLINE;
use naadf_proto::requests::{entity_pose, entity_spawn};
use naadf_proto::v1::{
    DespawnEntitiesRequest, EditReply, EditRequest, FrameJob, FrameReply, FrameRequest, FrameResult, HistoryRequest,
    JoinRequest, MoveEntitiesRequest, NodeHello, NodeMessage, PresenceRequest, SpawnEntitiesRequest, StatusRequest,
    node_message,
};
use naadf_world::World;
use naadf_world::digest::Digest;
use std::path::{Path, PathBuf};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tonic::codec::CompressionEncoding;

/// A connection to a server.
#[derive(Clone, Debug)]
pub struct Client {
    raw: RawClient,
    /// The same connection, compressing what it sends: for large edits only.
    compressed: RawClient,
    /// The largest world [`Client::join`] accepts.
    max_world_bytes: u64,
}

/// Edits of at least this many bytes of ops JSON go compressed (zstd). Below it,
/// compressing costs more than it saves: tonic starts a fresh zstd context for every
/// message, on both sides, which takes longer than sending a few hundred bytes.
pub const COMPRESS_EDITS_FROM: usize = 16 * 1024;

/// Where a server is and who we are to it.
#[derive(Clone, Debug)]
pub struct ServerAddress {
    /// Server URL (`http://` or `https://`).
    pub url: String,
    /// Bearer token.
    pub token: Option<String>,
    /// CA certificate (PEM) for `https://`.
    pub ca: Option<PathBuf>,
    /// The largest world (bytes of buffers) to accept from the server
    /// ([`Mirror::with_max_world_bytes`](crate::Mirror::with_max_world_bytes)).
    pub max_world_bytes: u64,
}

impl ServerAddress {
    /// Where `url` is, with no token, no extra CA and the default world limit.
    pub fn new(url: impl Into<String>) -> Self {
        Self {
            url: url.into(),
            token: None,
            ca: None,
            max_world_bytes: crate::mirror::DEFAULT_MAX_WORLD_BYTES,
        }
    }

    /// Connects ([`Client::connect`]), with this address's world limit.
    pub async fn connect(&self) -> Result<Client, Error> {
        let client = Client::connect(&self.url, self.token.as_deref(), self.ca.as_deref()).await?;
        Ok(client.with_max_world_bytes(self.max_world_bytes))
    }
}

/// The acknowledgement of a durable edit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ack {
    /// The version the edit produced.
    pub version: u64,
    /// The request repeated an earlier `client_seq`: it was not applied again, and
    /// `version` is the one it produced the first time.
    pub duplicate: bool,
}

/// The server's state ([`Client::status`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ServerStatus {
    /// The protocol version the server speaks.
    pub protocol_version: u32,
    /// World size in voxels.
    pub size: [u32; 3],
    /// The current edit version.
    pub version: u64,
    /// The current growth sub-step.
    pub growth_seq: u32,
    /// Whether no distance-field work is queued.
    pub quiescent: bool,
    /// The current digest.
    pub digest: Digest,
    /// Clients joined now.
    pub clients: u32,
    /// The caller's user name.
    pub user: String,
    /// The caller's role.
    pub role: String,
}

/// An entity's id and pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// The entity id.
    pub id: u32,
    /// World position of the model's local-origin corner.
    pub pos: [f64; 3],
    /// Rotation quaternion `[x, y, z, w]` (any non-zero length).
    pub rot: [f64; 4],
}

/// An entity to spawn.
#[derive(Clone, Debug, PartialEq)]
pub struct Spawn {
    /// The model it shows.
    pub model: String,
    /// Its id and pose.
    pub pose: Pose,
}

/// An encoded frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// PNG bytes, or raw RGBA8 rows from the top when [`FrameSpec::raw`] asked for them.
    pub data: Vec<u8>,
}

/// A frame the server had rendered ([`Client::frame`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderedFrame {
    /// The world version it shows (the quiescent state of that version).
    pub version: u64,
    /// The render node that made it (its adapter).
    pub node: String,
    /// The image.
    pub image: FrameImage,
}

/// Where a client is and what it points at, published with [`Client::publish`] for the
/// others to see (docs/PROTOCOL.md, "Presence"). The server stamps it with the caller's
/// user and forgets it 5 s after the last update.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PresenceUpdate {
    /// A number picked at random once per window or page, telling one user's sessions apart.
    pub session: u64,
    /// The name to show (64 characters are kept).
    pub name: String,
    /// The camera position in voxels.
    pub position: Option<[f64; 3]>,
    /// The camera's forward direction.
    pub forward: Option<[f64; 3]>,
    /// The voxel under the pointer.
    pub pointer: Option<[i64; 3]>,
    /// The tool in hand (32 characters are kept).
    pub tool: String,
}

impl From<&PresenceUpdate> for PresenceRequest {
    fn from(p: &PresenceUpdate) -> Self {
        PresenceRequest {
            session: p.session,
            name: p.name.clone(),
            position: p.position.map(Vec::from).unwrap_or_default(),
            forward: p.forward.map(Vec::from).unwrap_or_default(),
            pointer: p.pointer.map(Vec::from).unwrap_or_default(),
            tool: p.tool.clone(),
        }
    }
}

impl From<EditReply> for Ack {
    fn from(r: EditReply) -> Self {
        Ack {
            version: r.version,
            duplicate: r.duplicate,
        }
    }
}

impl Client {
    /// Connects to `url` (`http://host:port`, or `https://host:port` trusting `ca` (PEM) in
    /// addition to the system roots), sending `token` with every call.
    ///
    /// ```no_run
    /// # async fn demo() -> Result<(), naadf_client::Error> {
    /// let client = naadf_client::Client::connect("https://example.org:50051", Some("t"), None).await?;
    /// println!("at version {}", client.status().await?.version);
    /// # Ok(()) }
    /// ```
    pub async fn connect(url: &str, token: Option<&str>, ca: Option<&Path>) -> Result<Client, Error> {
        let raw = connect::connect(url, token, ca).await?;
        Ok(Client {
            compressed: raw.clone().send_compressed(CompressionEncoding::Zstd),
            raw,
            max_world_bytes: crate::mirror::DEFAULT_MAX_WORLD_BYTES,
        })
    }

    /// Makes [`Client::join`] refuse worlds whose buffers need more than `bytes` in all
    /// (default [`DEFAULT_MAX_WORLD_BYTES`](crate::mirror::DEFAULT_MAX_WORLD_BYTES)).
    pub fn with_max_world_bytes(mut self, bytes: u64) -> Self {
        self.max_world_bytes = bytes;
        self
    }

    /// Joins the world stream, announcing `cache` (a world from an earlier session) so
    /// that only what changed is sent, and returns the [`Session`] that applies it.
    ///
    /// ```no_run
    /// # async fn demo(client: naadf_client::Client) -> Result<(), naadf_client::Error> {
    /// let mut session = client.join(None).await?;
    /// let world = session.until_quiescent(0, std::time::Duration::from_secs(60)).await?;
    /// println!("version {} digest {}", world.version(), world.digest());
    /// # Ok(()) }
    /// ```
    pub async fn join(&self, cache: Option<World>) -> Result<Session, Error> {
        Session::start(self.raw.clone(), cache, self.max_world_bytes).await
    }

    /// Opens the world stream with `request` ([`crate::Mirror::join_request`]) and returns
    /// it unapplied: for a mirror that lives elsewhere (the viewer applies it on its window
    /// thread) or a relay that passes the messages on.
    pub async fn stream(&self, request: JoinRequest) -> Result<WorldStream, Error> {
        WorldStream::open(&self.raw, request).await
    }

    /// Applies `ops` (one ops-JSON line: an op or `{"batch":[...]}`) as one version, and
    /// returns once it is durable. A repeat of `client_seq` by the same user is answered
    /// with the original version and not applied again; 0 opts out.
    pub async fn edit(&self, ops: impl Into<String>, client_seq: u64) -> Result<Ack, Error> {
        let req = EditRequest {
            ops: ops.into(),
            client_seq,
        };
        let raw = if req.ops.len() >= COMPRESS_EDITS_FROM {
            &self.compressed
        } else {
            &self.raw
        };
        Ok(raw.clone().edit(req).await?.into_inner().into())
    }

    /// Undoes the caller's latest edit that is not undone yet (a new version).
    pub async fn undo(&self, client_seq: u64) -> Result<Ack, Error> {
        Ok(self
            .raw
            .clone()
            .undo(HistoryRequest { client_seq })
            .await?
            .into_inner()
            .into())
    }

    /// Redoes the caller's latest undone edit (a new version).
    pub async fn redo(&self, client_seq: u64) -> Result<Ack, Error> {
        Ok(self
            .raw
            .clone()
            .redo(HistoryRequest { client_seq })
            .await?
            .into_inner()
            .into())
    }

    /// Spawns entities (one version).
    pub async fn spawn_entities(&self, entities: &[Spawn], client_seq: u64) -> Result<Ack, Error> {
        let req = SpawnEntitiesRequest {
            entities: entities
                .iter()
                .map(|s| entity_spawn(s.pose.id, &s.model, s.pose.pos, s.pose.rot))
                .collect(),
            client_seq,
        };
        Ok(self.raw.clone().spawn_entities(req).await?.into_inner().into())
    }

    /// Moves entities (one version).
    pub async fn move_entities(&self, moves: &[Pose], client_seq: u64) -> Result<Ack, Error> {
        let req = MoveEntitiesRequest {
            moves: moves.iter().map(|p| entity_pose(p.id, p.pos, p.rot)).collect(),
            client_seq,
        };
        Ok(self.raw.clone().move_entities(req).await?.into_inner().into())
    }

    /// Despawns entities (one version).
    pub async fn despawn_entities(&self, ids: &[u32], client_seq: u64) -> Result<Ack, Error> {
        let req = DespawnEntitiesRequest {
            ids: ids.to_vec(),
            client_seq,
        };
        Ok(self.raw.clone().despawn_entities(req).await?.into_inner().into())
    }

    /// Publishes where this client is (any role may). About 10 times a second is plenty;
    /// faster updates only replace this session's entry.
    ///
    /// ```no_run
    /// # async fn demo(client: naadf_client::Client) -> Result<(), naadf_client::Error> {
    /// use naadf_client::PresenceUpdate;
    /// client
    ///     .publish(&PresenceUpdate {
    ///         session: 7,
    ///         name: "ada".into(),
    ///         position: Some([64.0, 40.0, 64.0]),
    ///         ..PresenceUpdate::default()
    ///     })
    ///     .await?;
    /// # Ok(()) }
    /// ```
    pub async fn publish(&self, update: &PresenceUpdate) -> Result<(), Error> {
        self.raw.clone().publish(PresenceRequest::from(update)).await?;
        Ok(())
    }

    /// The server's state.
    pub async fn status(&self) -> Result<ServerStatus, Error> {
        let s = self.raw.clone().status(StatusRequest {}).await?.into_inner();
        Ok(ServerStatus {
            protocol_version: s.protocol_version,
            size: s
                .size
                .as_slice()
                .try_into()
                .map_err(|_| Error::Malformed(format!("a world size of {} numbers", s.size.len())))?,
            version: s.version,
            growth_seq: s.growth_seq,
            quiescent: s.quiescent,
            digest: s.digest.parse().map_err(Error::Malformed)?,
            clients: s.clients,
            user: s.user,
            role: s.role,
        })
    }

    /// Has one of the server's render nodes render a frame. The server refuses with
    /// UNAVAILABLE when no node can take it, RESOURCE_EXHAUSTED ([`Error::RateLimited`])
    /// when its render queue is full, DEADLINE_EXCEEDED past the deadline.
    ///
    /// ```no_run
    /// # async fn demo(client: naadf_client::Client) -> Result<(), naadf_client::Error> {
    /// use naadf_client::{FrameSpec, Mode};
    /// let camera = naadf_world::camera::Camera::from_json(r#"{"pos":[0,80,0],"yaw":45,"pitch":-30}"#).unwrap();
    /// let frame = client.frame(&FrameSpec::new(camera, (640, 480), Mode::Albedo)).await?;
    /// std::fs::write("frame.png", &frame.image.data).unwrap();
    /// # Ok(()) }
    /// ```
    pub async fn frame(&self, spec: &FrameSpec) -> Result<RenderedFrame, Error> {
        let FrameReply {
            version,
            width,
            height,
            image,
            node,
        } = self.raw.clone().render_frame(spec.to_wire()).await?.into_inner();
        Ok(RenderedFrame {
            version,
            node,
            image: FrameImage {
                width,
                height,
                data: image,
            },
        })
    }

    /// Registers as a render node that can do what `info` says; the server then sends it
    /// jobs ([`Registration`]). Needs the render-node or admin role. A program that renders
    /// frames runs a [`crate::node::RenderNode`], which keeps a node registered.
    pub async fn register_node(&self, info: &NodeInfo) -> Result<Registration, Error> {
        let (results, rx) = mpsc::channel(16);
        let hello = NodeHello {
            adapter: info.adapter.clone(),
            modes: info.modes.iter().map(|m| m.name().to_owned()).collect(),
            max_width: info.max_size.0,
            max_height: info.max_size.1,
        };
        results
            .try_send(NodeMessage {
                kind: Some(node_message::Kind::Hello(hello)),
            })
            .expect("a new channel has room");
        let jobs = self
            .raw
            .clone()
            .register_node(ReceiverStream::new(rx))
            .await?
            .into_inner();
        Ok(Registration { jobs, results })
    }
}

/// What a render node tells the server it can do ([`Client::register_node`]).
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
