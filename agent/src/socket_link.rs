//! The link between a sandboxed agent and its relay: one Unix stream socket (a
//! `socketpair` the relay made), carrying [`net`]'s messages as frames, each a 4-byte
//! little-endian length and that many bytes. The relay reads the agent's frames as
//! untrusted input: bounded in size, whole within a deadline, decoded by [`net::decode`]
//! only.

use std::io::{ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Largest frame a relay reads from its agent: a move of [`MAX_WAYPOINTS`] waypoints with
/// room to spare.
///
/// [`MAX_WAYPOINTS`]: shared::control::vocabulary::MAX_WAYPOINTS
pub const MAX_UP_FRAME_BYTES: usize = 64 << 10;

/// How long a frame, once begun, may take to arrive whole.
pub const FRAME_DEADLINE: Duration = Duration::from_secs(1);

/// Why a frame could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The other end closed the socket.
    #[error("the other end closed the link")]
    Closed,
    /// A frame claimed more bytes than allowed.
    #[error("a frame of {0} bytes, more than the {1} allowed")]
    TooLarge(usize, usize),
    /// A frame began but did not arrive whole within [`FRAME_DEADLINE`].
    #[error("a frame that did not arrive whole within {FRAME_DEADLINE:?}")]
    Truncated,
    /// A frame arrived whole but is not a message.
    #[error("{0}")]
    Malformed(#[from] net::MessageError),
    /// The socket failed.
    #[error("the link: {0}")]
    Io(#[from] std::io::Error),
}

/// One end of the link.
pub struct SocketLink {
    stream: UnixStream,
}

impl SocketLink {
    /// The link over `stream`.
    pub fn new(stream: UnixStream) -> Self {
        Self { stream }
    }

    /// Send `message` as one frame.
    pub fn send<T: Serialize>(&mut self, message: &T) -> Result<(), LinkError> {
        let bytes = net::encode(message)?;
        let len = u32::try_from(bytes.len()).map_err(|_| LinkError::TooLarge(bytes.len(), 0))?;
        let mut frame = Vec::with_capacity(4 + bytes.len());
        frame.extend_from_slice(&len.to_le_bytes());
        frame.extend_from_slice(&bytes);
        self.stream.set_write_timeout(Some(FRAME_DEADLINE))?;
        match self.stream.write_all(&frame) {
            Err(e) if e.kind() == ErrorKind::BrokenPipe => Err(LinkError::Closed),
            other => Ok(other?),
        }
    }

    /// The next message, of at most `max_bytes`, waiting for its first byte at most
    /// `wait` (forever when `None`); `Ok(None)` when none began by then.
    pub fn receive<T: DeserializeOwned>(
        &mut self,
        max_bytes: usize,
        wait: Option<Duration>,
    ) -> Result<Option<T>, LinkError> {
        if !readable(&self.stream, wait)? {
            return Ok(None);
        }
        let deadline = Instant::now() + FRAME_DEADLINE;
        let mut len = [0u8; 4];
        self.read_exact_by(&mut len, deadline)?;
        let len = u32::from_le_bytes(len) as usize;
        if len > max_bytes {
            return Err(LinkError::TooLarge(len, max_bytes));
        }
        let mut bytes = vec![0u8; len];
        self.read_exact_by(&mut bytes, deadline)?;
        Ok(Some(net::decode(&bytes)?))
    }

    fn read_exact_by(&mut self, buf: &mut [u8], deadline: Instant) -> Result<(), LinkError> {
        let mut filled = 0;
        while filled < buf.len() {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(LinkError::Truncated);
            }
            self.stream.set_read_timeout(Some(left))?;
            match self.stream.read(&mut buf[filled..]) {
                Ok(0) => return Err(LinkError::Closed),
                Ok(n) => filled += n,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    return Err(LinkError::Truncated);
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
        Ok(())
    }

    /// The socket's descriptor (to hand to a child).
    pub fn raw_fd(&self) -> i32 {
        self.stream.as_raw_fd()
    }
}

/// Whether `stream` has something to read (or was closed) within `wait`.
fn readable(stream: &UnixStream, wait: Option<Duration>) -> Result<bool, LinkError> {
    let timeout_ms = match wait {
        None => -1,
        Some(d) => i32::try_from(d.as_millis()).unwrap_or(i32::MAX),
    };
    let mut fd = libc::pollfd {
        fd: stream.as_raw_fd(),
        events: libc::POLLIN,
        revents: 0,
    };
    loop {
        // SAFETY: poll(2) on one descriptor the stream keeps open.
        match unsafe { libc::poll(&mut fd, 1, timeout_ms) } {
            0 => return Ok(false),
            n if n > 0 => return Ok(true),
            _ => {
                let e = std::io::Error::last_os_error();
                if e.kind() != ErrorKind::Interrupted {
                    return Err(e.into());
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use net::{Down, Up};

    #[test]
    fn a_frame_goes_through_and_a_bad_one_is_refused_by_kind() {
        let (a, b) = UnixStream::pair().expect("socketpair");
        let (mut a, mut b) = (SocketLink::new(a), SocketLink::new(b));
        a.send(&Down::Quit).expect("send");
        let got: Option<Down> = b
            .receive(1024, Some(Duration::from_secs(5)))
            .expect("receive");
        assert_eq!(got, Some(Down::Quit));
        // Nothing sent: none within the wait.
        let none: Option<Down> = b
            .receive(1024, Some(Duration::from_millis(10)))
            .expect("wait");
        assert_eq!(none, None);
        // Too large, claimed.
        a.stream
            .write_all(&(1_000_000u32).to_le_bytes())
            .expect("write");
        assert!(matches!(
            b.receive::<Up>(1024, Some(Duration::from_secs(5))),
            Err(LinkError::TooLarge(1_000_000, 1024))
        ));
        // Begun, never finished.
        let (c, d) = UnixStream::pair().expect("socketpair");
        let (mut c, mut d) = (c, SocketLink::new(d));
        c.write_all(&[8, 0, 0, 0, 1]).expect("write");
        assert!(matches!(
            d.receive::<Up>(1024, Some(Duration::from_secs(5))),
            Err(LinkError::Truncated)
        ));
        drop(c);
    }

    #[test]
    fn a_frame_that_is_not_a_message_is_malformed_and_a_closed_link_is_closed() {
        let (mut raw, other) = UnixStream::pair().expect("socketpair");
        let mut link = SocketLink::new(other);
        raw.write_all(&[2, 0, 0, 0, 0xff, 0xff]).expect("write");
        assert!(matches!(
            link.receive::<Up>(1024, Some(Duration::from_secs(5))),
            Err(LinkError::Malformed(_))
        ));
        drop(raw);
        assert!(matches!(
            link.receive::<Up>(1024, Some(Duration::from_secs(5))),
            Err(LinkError::Closed)
        ));
    }
}
