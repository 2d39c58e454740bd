//! [`Backoff`]: the pauses between attempts to reach a peer that is out of reach — a
//! relay re-joining its upstream, a mirror re-joining its server, an edit retried with its
//! `client_seq`. Each pause doubles the last, up to a longest one, so that a short outage
//! costs little and a long one does not flood the peer once it is back.

use std::time::Duration;

/// Doubling pauses from `first` up to `max`, optionally jittered.
///
/// ```
/// use naadf_proto::backoff::Backoff;
/// use std::time::Duration;
/// let ms = Duration::from_millis;
/// let mut b = Backoff::new(ms(100), ms(300));
/// assert_eq!(b.upcoming(), ms(100));
/// let pauses: Vec<_> = (0..4).map(|_| b.pause()).collect();
/// assert_eq!(pauses, [ms(100), ms(200), ms(300), ms(300)]);
/// b.reset();
/// assert_eq!(b.pause(), ms(100));
/// ```
#[derive(Clone, Debug)]
pub struct Backoff {
    first: Duration,
    max: Duration,
    next: Duration,
    jitter: bool,
}

impl Backoff {
    /// Pauses from `first`, doubling up to `max`.
    pub const fn new(first: Duration, max: Duration) -> Self {
        Self {
            first,
            max,
            next: first,
            jitter: false,
        }
    }

    /// The same pauses, each lengthened by up to a quarter, so that many peers cut off
    /// together do not all come back at the same instant.
    ///
    /// ```
    /// use naadf_proto::backoff::Backoff;
    /// use std::time::Duration;
    /// let mut b = Backoff::new(Duration::from_millis(100), Duration::from_secs(5)).jittered();
    /// let p = b.pause();
    /// assert!(p >= Duration::from_millis(100) && p <= Duration::from_millis(125));
    /// ```
    pub const fn jittered(mut self) -> Self {
        self.jitter = true;
        self
    }

    /// The next pause before jitter, without taking it.
    pub fn upcoming(&self) -> Duration {
        self.next
    }

    /// Takes the next pause: returns it (jittered if asked) and doubles the one after.
    pub fn pause(&mut self) -> Duration {
        let pause = self.next;
        self.next = (self.next * 2).min(self.max);
        if !self.jitter {
            return pause;
        }
        // The clock's sub-second digits are random enough to spread peers apart.
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |t| t.subsec_nanos());
        pause + pause.mul_f64(f64::from(nanos % 1000) / 4000.0)
    }

    /// Starts again from the first pause (after an attempt that succeeded).
    pub fn reset(&mut self) {
        self.next = self.first;
    }
}

/// Consecutive identical refusals after which [`Retries`] stops retrying at the usual pace.
pub const SAME_REFUSALS: u32 = 5;

/// The pauses of a peer that keeps trying to reach another: the usual [`Backoff`], until
/// the other side refuses the same way [`SAME_REFUSALS`] times in a row (a revoked token,
/// a protocol mismatch): then a long backoff, since trying again every few seconds would
/// change nothing but fill the log.
///
/// ```
/// use naadf_proto::backoff::{Backoff, Retries, SAME_REFUSALS};
/// use std::time::Duration;
/// let ms = Duration::from_millis;
/// let mut r = Retries::new(Backoff::new(ms(10), ms(20)), Backoff::new(ms(1000), ms(4000)));
/// for _ in 1..SAME_REFUSALS {
///     assert!(r.after(Some("unknown token")) <= ms(20));
/// }
/// assert!(r.refused().is_none());
/// assert_eq!(r.after(Some("unknown token")), ms(1000));
/// assert_eq!(r.refused(), Some("unknown token"));
/// assert_eq!(r.after(Some("unknown token")), ms(2000));
/// // Another answer, or a success, starts over.
/// assert_eq!(r.after(None), ms(20));
/// assert!(r.refused().is_none());
/// r.reset();
/// assert_eq!(r.after(Some("unknown token")), ms(10));
/// ```
#[derive(Clone, Debug)]
pub struct Retries {
    usual: Backoff,
    refused: Backoff,
    /// The last refusal and how many times in a row it came.
    last: Option<(String, u32)>,
}

impl Retries {
    /// The `usual` pauses, and the `refused` ones after a repeated refusal.
    pub const fn new(usual: Backoff, refused: Backoff) -> Self {
        Self {
            usual,
            refused,
            last: None,
        }
    }

    /// The pause after a failed attempt: `refusal` is the other side's answer when it
    /// refused (its code and message), `None` when it could not be reached.
    pub fn after(&mut self, refusal: Option<&str>) -> Duration {
        self.last = match (self.last.take(), refusal) {
            (Some((last, n)), Some(now)) if last == now => Some((last, n + 1)),
            (_, Some(now)) => Some((now.to_owned(), 1)),
            (_, None) => None,
        };
        if self.refused().is_some() {
            return self.refused.pause();
        }
        self.refused.reset();
        self.usual.pause()
    }

    /// The refusal that came [`SAME_REFUSALS`] times in a row or more, if the last
    /// attempts met one.
    pub fn refused(&self) -> Option<&str> {
        self.last
            .as_ref()
            .filter(|(_, n)| *n >= SAME_REFUSALS)
            .map(|(why, _)| why.as_str())
    }

    /// Starts over, after an attempt that succeeded.
    pub fn reset(&mut self) {
        self.usual.reset();
        self.refused.reset();
        self.last = None;
    }
}
