//! Sending and receiving messages on Zenoh ports: encoded on the way out, decoded within
//! bounds on the way in ([`crate::decode`]).

use std::time::Duration;

use serde::Serialize;
use serde::de::DeserializeOwned;
use zenoh::Wait;
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::sample::Sample;

use crate::message::{MessageError, decode, encode};

/// Why a message could not be sent or received.
#[derive(Debug, thiserror::Error)]
pub enum PortError {
    /// The message could not be encoded.
    #[error(transparent)]
    Message(#[from] MessageError),
    /// Zenoh failed (the session is closed).
    #[error("zenoh: {0}")]
    Zenoh(String),
}

/// Encode `message` and put it on `publisher`.
pub fn send<T: Serialize>(publisher: &Publisher<'_>, message: &T) -> Result<(), PortError> {
    let bytes = encode(message)?;
    publisher
        .put(bytes)
        .wait()
        .map_err(|e| PortError::Zenoh(e.to_string()))
}

/// The next sample on `subscriber` within `timeout`, decoded: `None` when none came, the
/// decoding error when it is not a message (the caller logs and skips it: it came from
/// another process).
pub fn receive<T: DeserializeOwned>(
    subscriber: &Subscriber<FifoChannelHandler<Sample>>,
    timeout: Duration,
) -> Result<Option<Result<T, MessageError>>, PortError> {
    let sample = subscriber
        .recv_timeout(timeout)
        .map_err(|e| PortError::Zenoh(e.to_string()))?;
    Ok(sample.map(|s| decode(&s.payload().to_bytes())))
}
