//! Who a relay's caller is: the relay holds no tokens, so it asks its upstream (a `Status`
//! call with the caller's `authorization`) and keeps the answer for a few seconds. A
//! relay therefore never widens a role: the upstream decides, and edits are decided there
//! again when they are forwarded.
//!
//! An open upstream (a server without tokens) makes every caller an admin, which a server
//! allows on loopback only. A relay in front of one would hand those rights to the
//! network, so it then admits callers from its own machine only ([`UpstreamAuth::admit`]).

use super::upstream::Upstream;
use crate::net::auth::{Caller, Role};
use naadf_proto::v1::StatusRequest;
use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Mutex;
use std::time::{Duration, Instant};
use tonic::metadata::MetadataMap;
use tonic::{Code, Status};

/// How long an upstream's answer about a token is reused (a token revoked upstream still
/// reads through a relay for at most this long; edits are checked upstream every time).
const TTL: Duration = Duration::from_secs(10);
/// Most tokens remembered; past it the memory starts over.
const MAX_TOKENS: usize = 10_000;

/// The upstream's answer about one token (`None`: no token), and when it was given.
type Answers = HashMap<Option<Vec<u8>>, (Instant, Result<Caller, Status>)>;

/// The upstream's answers about tokens.
#[derive(Debug)]
pub struct UpstreamAuth {
    upstream: Upstream,
    answers: Mutex<Answers>,
}

impl UpstreamAuth {
    /// Checks tokens against `upstream`.
    pub fn new(upstream: Upstream) -> Self {
        Self {
            upstream,
            answers: Mutex::default(),
        }
    }

    /// The caller with these request `metadata`, arriving from `peer`, as the upstream
    /// sees it, once [`admit`](Self::admit) lets `peer` in. An unreachable upstream gives
    /// UNAVAILABLE (and is asked again next time).
    pub async fn caller(&self, metadata: &MetadataMap, peer: Option<SocketAddr>) -> Result<Caller, Status> {
        self.admit(peer).await?;
        self.answer(metadata).await
    }

    /// Whether a caller from `peer` (unknown: `None`) may use this relay at all: always
    /// from loopback; from elsewhere only while the upstream refuses callers without a
    /// token. An open upstream takes any caller, token or not, as an admin, and would take
    /// this one the same way, through the relay, from the network.
    pub async fn admit(&self, peer: Option<SocketAddr>) -> Result<(), Status> {
        if peer.is_some_and(|p| p.ip().is_loopback()) {
            return Ok(());
        }
        match self.answer(&MetadataMap::new()).await {
            Ok(_) => Err(Status::permission_denied(
                "this relay's upstream serves without tokens (every caller is an admin there), so the relay \
                 admits callers from its own machine only; configure tokens on the server",
            )),
            Err(s) if s.code() == Code::Unauthenticated => Ok(()),
            Err(s) => Err(s),
        }
    }

    /// The upstream's answer about the token in `metadata` (none: an anonymous caller).
    async fn answer(&self, metadata: &MetadataMap) -> Result<Caller, Status> {
        let key = metadata.get("authorization").map(|v| v.as_bytes().to_vec());
        if let Some((at, answer)) = self.answers.lock().expect("token answers").get(&key)
            && at.elapsed() < TTL
        {
            return answer.clone();
        }
        let request = Upstream::as_caller(metadata, StatusRequest {});
        let answer = match self.upstream.client().status(request).await {
            Ok(reply) => {
                let reply = reply.into_inner();
                Role::parse(&reply.role)
                    .map(|role| Caller { user: reply.user, role })
                    .ok_or_else(|| Status::internal(format!("the upstream names an unknown role '{}'", reply.role)))
            }
            Err(s) => Err(super::upstream::upstream_error(s)),
        };
        let settled = match &answer {
            Ok(_) => true,
            Err(s) => matches!(s.code(), Code::Unauthenticated | Code::PermissionDenied),
        };
        if settled {
            let mut answers = self.answers.lock().expect("token answers");
            if answers.len() >= MAX_TOKENS {
                answers.clear();
            }
            answers.insert(key, (Instant::now(), answer.clone()));
        }
        answer
    }
}
