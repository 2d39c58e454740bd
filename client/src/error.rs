//! [`Error`]: why a call to the server failed, sorted by what a caller does about it —
//! reconnect and retry (a lost connection), back off (a rate limit), give up or fix the
//! request (a refusal), or distrust the stream (a mirror error). [`ConnectError`] says why
//! no connection could be made.

use crate::mirror::MirrorError;
use std::time::Duration;

/// The gRPC status codes [`Error::Refused`] carries.
pub use tonic::Code;

/// Errors while connecting.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    /// The URL is not usable.
    #[error("bad server URL '{0}': {1}")]
    Url(String, String),
    /// The token cannot be sent as a header.
    #[error("the token must be visible ASCII")]
    Token,
    /// The CA certificate cannot be read.
    #[error("cannot read CA certificate {0}: {1}")]
    Ca(String, std::io::Error),
    /// The connection failed.
    #[error("cannot connect to {0}: {1}")]
    Transport(String, tonic::transport::Error),
}

/// Errors of the client.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// No connection could be made: a bad URL, token or CA certificate, or no server
    /// listening.
    #[error(transparent)]
    Connect(#[from] ConnectError),
    /// The connection broke during a call, or could not be made again: whether the server
    /// acted on the call is unknown. Retrying an edit with the same `client_seq` is safe
    /// (the server answers a repeat with the original version); the client reconnects by
    /// itself on the next call.
    #[error("connection lost: {0}")]
    ConnectionLost(String),
    /// The server turned the request away with RESOURCE_EXHAUSTED and asked for a retry
    /// (the status carries [`naadf_proto::RETRY_AFTER_MS`]): the caller is over its rate
    /// limit, or the render queue is full. Back off and retry. A RESOURCE_EXHAUSTED without
    /// it (a batch over the server's edit limits, which no retry fixes) is
    /// [`Error::Refused`].
    #[error("server refused: ResourceExhausted: {0}")]
    RateLimited(String),
    /// The server refused the request: its gRPC code and message.
    #[error("server refused: {code:?}: {message}")]
    Refused {
        /// The gRPC status code.
        code: Code,
        /// The server's explanation.
        message: String,
    },
    /// The server ended the world stream with `ABORTED` because this client fell behind
    /// it (it read too slowly, or not at all). Join again announcing the world held
    /// ([`crate::Session::rejoin`]): the server resumes it or sends what differs.
    #[error("the server ended the stream: {0}")]
    FellBehind(String),
    /// The world stream broke the protocol, or the mirror diverged from the server.
    #[error(transparent)]
    Mirror(#[from] MirrorError),
    /// The server ended the world stream before the mirror was quiescent at the version
    /// waited for.
    #[error("the server ended the stream before it was quiescent")]
    StreamEnded,
    /// The mirror was not quiescent at the version waited for within this time.
    #[error("timed out after {} s before the server was quiescent", .0.as_secs_f64())]
    Timeout(Duration),
    /// A reply that does not hold what the protocol promises.
    #[error("malformed reply from the server: {0}")]
    Malformed(String),
}

impl Error {
    /// Whether the server was out of reach: the connection was lost, or the server said it
    /// is unavailable (shutting down). A retry after a pause may succeed; a rate limit is
    /// [`Error::RateLimited`] instead.
    pub fn is_unavailable(&self) -> bool {
        matches!(
            self,
            Error::ConnectionLost(_)
                | Error::Refused {
                    code: Code::Unavailable,
                    ..
                }
        )
    }

    /// The gRPC code of a refusal by the server (none for the other errors).
    pub fn code(&self) -> Option<Code> {
        match self {
            Error::Refused { code, .. } => Some(*code),
            Error::RateLimited(_) => Some(Code::ResourceExhausted),
            Error::FellBehind(_) => Some(Code::Aborted),
            _ => None,
        }
    }
}

impl From<tonic::Status> for Error {
    /// Sorts a failed call: a status that tonic made itself from a transport failure
    /// carries that failure as its source; a status the server sent has none.
    fn from(s: tonic::Status) -> Self {
        if let Some(mut cause) = std::error::Error::source(&s) {
            let mut why = s.message().to_owned();
            loop {
                let text = cause.to_string();
                if !why.contains(&text) {
                    why = format!("{why}: {text}");
                }
                match cause.source() {
                    Some(c) => cause = c,
                    None => return Error::ConnectionLost(why),
                }
            }
        }
        match s.code() {
            Code::ResourceExhausted if s.metadata().contains_key(naadf_proto::RETRY_AFTER_MS) => {
                Error::RateLimited(s.message().to_owned())
            }
            Code::Aborted => Error::FellBehind(s.message().to_owned()),
            code => Error::Refused {
                code,
                message: s.message().to_owned(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_from_the_server_are_refusals() {
        let e = Error::from(tonic::Status::invalid_argument("voxel outside the world"));
        assert_eq!(e.code(), Some(Code::InvalidArgument));
        assert_eq!(
            e.to_string(),
            "server refused: InvalidArgument: voxel outside the world"
        );
        let mut limited = tonic::Status::resource_exhausted("over the rate limit");
        limited
            .metadata_mut()
            .insert(naadf_proto::RETRY_AFTER_MS, "20".parse().unwrap());
        let e = Error::from(limited);
        assert!(matches!(e, Error::RateLimited(_)), "{e:?}");
        assert_eq!(e.to_string(), "server refused: ResourceExhausted: over the rate limit");
        // Without the retry hint, RESOURCE_EXHAUSTED is a batch over the edit limits:
        // a refusal that no retry fixes.
        let e = Error::from(tonic::Status::resource_exhausted(
            "over limit: a batch holds at most 4 ops",
        ));
        assert!(
            matches!(
                e,
                Error::Refused {
                    code: Code::ResourceExhausted,
                    ..
                }
            ),
            "{e:?}"
        );
        assert_eq!(e.code(), Some(Code::ResourceExhausted));
        // The server's own UNAVAILABLE (no render node) is a refusal, not a lost connection.
        let e = Error::from(tonic::Status::unavailable("no render node"));
        assert_eq!(e.code(), Some(Code::Unavailable));
        assert!(e.is_unavailable());
        // ABORTED ends the stream of a client that fell behind: it joins again.
        let e = Error::from(tonic::Status::aborted("fell behind"));
        assert!(matches!(e, Error::FellBehind(_)), "{e:?}");
        assert_eq!(e.code(), Some(Code::Aborted));
    }

    #[test]
    fn statuses_with_a_transport_cause_are_lost_connections() {
        let io = std::io::Error::new(std::io::ErrorKind::ConnectionReset, "connection reset by peer");
        let e = Error::from(tonic::Status::from_error(Box::new(io)));
        assert!(matches!(e, Error::ConnectionLost(_)), "{e:?}");
        assert_eq!(e.code(), None);
        assert!(e.is_unavailable());
        assert_eq!(e.to_string(), "connection lost: connection reset by peer");
    }
}
