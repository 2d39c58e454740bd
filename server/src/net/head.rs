//! [`HeadScan`]: whether the bytes a client sent so far hold one complete request head,
//! for HTTP/1 and for HTTP/2 alike, without parsing the request itself.
//!
//! A connection is only worth its descriptor once a request has arrived; until then it is
//! held to the request deadline and may be closed to make room (see
//! [`crate::net::conn`]). The HTTP servers do not say when a connection's first request
//! head is complete, so the plaintext a connection delivers is scanned for it here:
//! - **HTTP/1:** the empty line that ends the head (`\r\n\r\n`, or bare `\n` line ends);
//! - **HTTP/2:** after the connection preface, the end of a `HEADERS` or `CONTINUATION`
//!   frame that carries `END_HEADERS`. Pings, settings and window updates do not count.
//!
//! The scan stops at the first complete head; it costs nothing afterwards.

/// The HTTP/2 connection preface.
const PREFACE: &[u8; 24] = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n";
/// Frame types that carry a header block, and the flag that ends one.
const HEADERS: u8 = 0x1;
const CONTINUATION: u8 = 0x9;
const END_HEADERS: u8 = 0x4;

/// Scans a connection's bytes, in order, for the end of its first request head.
///
/// ```
/// use naadf_server::net::head::HeadScan;
/// let mut scan = HeadScan::default();
/// assert!(!scan.feed(b"GET /health HTTP/1.1\r\nHost: x\r\n"));
/// assert!(scan.feed(b"\r\n"));
/// ```
#[derive(Clone, Debug, Default)]
pub struct HeadScan {
    state: State,
}

#[derive(Clone, Debug)]
enum State {
    /// Matching the HTTP/2 preface: this many bytes of it so far.
    Preface(usize),
    /// HTTP/1: whether the request line has begun, and the current line's length
    /// (carriage returns not counted).
    Http1 { begun: bool, line: usize },
    /// HTTP/2 frames: the frame header being read, the payload bytes left of the current
    /// frame, and whether that frame ends a header block.
    Frames {
        header: [u8; 9],
        have: usize,
        payload: usize,
        ends_head: bool,
    },
    /// A head was complete.
    Done,
}

impl Default for State {
    fn default() -> Self {
        State::Preface(0)
    }
}

impl HeadScan {
    /// Takes the next bytes the client sent; whether a complete request head has arrived
    /// (with these or before).
    pub fn feed(&mut self, bytes: &[u8]) -> bool {
        let mut rest = bytes;
        while !rest.is_empty() {
            match &mut self.state {
                State::Done => return true,
                State::Preface(seen) => {
                    let b = rest[0];
                    if b == PREFACE[*seen] {
                        *seen += 1;
                        rest = &rest[1..];
                        if *seen == PREFACE.len() {
                            self.state = State::Frames {
                                header: [0; 9],
                                have: 0,
                                payload: 0,
                                ends_head: false,
                            };
                        }
                    } else {
                        // Not HTTP/2: read what matched so far as HTTP/1, then go on.
                        let matched = *seen;
                        self.state = State::Http1 { begun: false, line: 0 };
                        self.feed(&PREFACE[..matched]);
                    }
                }
                State::Http1 { begun, line } => {
                    let b = rest[0];
                    rest = &rest[1..];
                    match b {
                        b'\n' if *begun && *line == 0 => self.state = State::Done,
                        b'\n' => *line = 0,
                        b'\r' => {}
                        _ => {
                            *begun = true;
                            *line += 1;
                        }
                    }
                }
                State::Frames {
                    header,
                    have,
                    payload,
                    ends_head,
                } => {
                    if *have < header.len() {
                        let n = (header.len() - *have).min(rest.len());
                        header[*have..*have + n].copy_from_slice(&rest[..n]);
                        *have += n;
                        rest = &rest[n..];
                        if *have == header.len() {
                            *payload = u32::from_be_bytes([0, header[0], header[1], header[2]]) as usize;
                            *ends_head = matches!(header[3], HEADERS | CONTINUATION) && header[4] & END_HEADERS != 0;
                        }
                    } else {
                        let n = (*payload).min(rest.len());
                        *payload -= n;
                        rest = &rest[n..];
                    }
                    if *have == header.len() && *payload == 0 {
                        if *ends_head {
                            self.state = State::Done;
                        } else {
                            *have = 0;
                        }
                    }
                }
            }
        }
        matches!(self.state, State::Done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An HTTP/2 frame header.
    fn frame(len: u32, kind: u8, flags: u8) -> Vec<u8> {
        let l = len.to_be_bytes();
        vec![l[1], l[2], l[3], kind, flags, 0, 0, 0, 1]
    }

    /// Whether `bytes` hold a complete head, fed whole and fed one byte at a time (the
    /// two must agree: a head split anywhere is still a head).
    fn complete(bytes: &[u8]) -> bool {
        let whole = HeadScan::default().feed(bytes);
        let mut scan = HeadScan::default();
        let bytewise = bytes.iter().fold(false, |_, b| scan.feed(std::slice::from_ref(b)));
        assert_eq!(whole, bytewise, "{:?}", String::from_utf8_lossy(bytes));
        whole
    }

    #[test]
    fn http1_heads_end_at_the_empty_line() {
        assert!(complete(b"GET /health HTTP/1.1\r\nHost: x\r\n\r\n"));
        assert!(complete(b"GET / HTTP/1.0\n\n"), "bare line feeds");
        assert!(
            complete(b"\r\nGET / HTTP/1.1\r\n\r\n"),
            "a leading empty line is skipped"
        );
        assert!(
            !complete(b"GET /health HTTP/1.1\r\nHost: x\r\n"),
            "slowloris: headers, no end"
        );
        assert!(!complete(b"\r\n\r\n"), "no request line");
        // A method that starts like the HTTP/2 preface is HTTP/1 all the same.
        assert!(complete(b"PRIVATE / HTTP/1.1\r\n\r\n"));
        // A preface broken after its first blank line reads as that HTTP/1 head (which the
        // server then refuses), not as a connection still on its way.
        assert!(complete(b"PRI * HTTP/2.0\r\n\r\nSX"));
    }

    #[test]
    fn http2_heads_end_with_end_headers() {
        let mut bytes = PREFACE.to_vec();
        assert!(!complete(&bytes), "the preface alone");
        // SETTINGS, a PING and a WINDOW_UPDATE: the handshake and keepalive, no request.
        bytes.extend(frame(6, 0x4, 0));
        bytes.extend([0; 6]);
        bytes.extend(frame(8, 0x6, 0));
        bytes.extend([7; 8]);
        bytes.extend(frame(4, 0x8, 0));
        bytes.extend([0, 0, 1, 0]);
        assert!(!complete(&bytes), "pings and settings are not a request");
        // HEADERS without END_HEADERS, then its CONTINUATION with it.
        bytes.extend(frame(3, HEADERS, 0));
        bytes.extend([1, 2, 3]);
        assert!(!complete(&bytes), "a header block not ended");
        let mut ended = bytes.clone();
        ended.extend(frame(2, CONTINUATION, END_HEADERS));
        assert!(!complete(&ended), "its last frame's payload has not arrived");
        ended.extend([4, 5]);
        assert!(complete(&ended));
        // A single HEADERS frame with END_HEADERS (and END_STREAM).
        let mut single = PREFACE.to_vec();
        single.extend(frame(5, HEADERS, END_HEADERS | 0x1));
        single.extend([0xff; 5]);
        assert!(complete(&single));
        // The flag on a DATA frame means something else.
        let mut data = PREFACE.to_vec();
        data.extend(frame(1, 0x0, END_HEADERS));
        data.extend([0]);
        assert!(!complete(&data));
    }
}
