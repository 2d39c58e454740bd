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
