//! The messages between an agent's relay and the agent ([`Down`], [`Up`]), and their
//! encoding: bincode (standard configuration), every decode bounded by
//! [`MAX_MESSAGE_BYTES`] and refused if bytes are left over. A message comes from another
//! machine: it is untrusted, and [`decode`] is the only way in.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// Largest message decoded: the mission (the scenario's resolved TOML, at most 16 MiB
/// when it comes from a file) with room to spare. Larger ones are refused unread.
pub const MAX_MESSAGE_BYTES: usize = 32 << 20;

/// From the relay (on the coordinator's host) to the agent.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Down {
    /// Is the agent there? Sent until the agent answers [`Up::Hello`]; `nonce` names this
    /// relay (a new one after a respawn).
    Probe {
        /// The relay's nonce.
        nonce: u64,
    },
    /// The scenario as run, in its resolved form as JSON (the run's mission file); the
    /// agent answers [`Up::Ready`].
    Mission {
        /// The relay's nonce.
        nonce: u64,
        /// The mission file's text.
        json: String,
    },
    /// Take a turn.
    Turn(NetTurn),
    /// Leave now.
    Quit,
}

/// A turn as it crosses the network: the world the coordinator published for it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetTurn {
    /// The world's sequence number.
    pub seq: u64,
    /// The step.
    pub step: u64,
    /// The turn's token.
    pub token: u64,
    /// The formation centre: x, y (m), heading (rad).
    pub centre: [f64; 3],
    /// Where the agent faces (rad), if it has a heading.
    pub heading_rad: Option<f64>,
    /// The centre's next poses along its plan, as far as the agent looks ahead: x, y (m),
    /// heading (rad).
    pub ahead: Vec<[f64; 3]>,
    /// The agents this agent may sense, itself included: (index, [x, y] in m).
    pub bodies: Vec<(u32, [f64; 2])>,
    /// With simultaneous turns, how far each of `bodies` moved over the last step ([x,
    /// y] in m, same order); empty otherwise.
    pub velocities: Vec<[f64; 2]>,
    /// The agents of `bodies` frozen as obstacles (dead), by index.
    pub frozen: Vec<u32>,
}

/// From the agent to its relay.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Up {
    /// The agent is there: the answer to [`Down::Probe`].
    Hello {
        /// The agent's index.
        agent: u32,
        /// The nonce of the probe answered.
        nonce: u64,
    },
    /// The agent has the mission and takes turns: the answer to [`Down::Mission`].
    Ready {
        /// The agent's index.
        agent: u32,
        /// The nonce of the mission taken.
        nonce: u64,
    },
    /// The agent's move for a turn.
    Move(NetMove),
}

/// A move as it crosses the network: what the agent would publish over shared memory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetMove {
    /// The agent's index.
    pub agent: u32,
    /// The turn's world sequence number.
    pub seq: u64,
    /// The turn's step.
    pub step: u64,
    /// The turn's token.
    pub token: u64,
    /// The move's status code.
    pub status: u32,
    /// Time spent computing the move, ns.
    pub compute_ns: u64,
    /// The ideal slot, [x, y] in m.
    pub slot: [f64; 2],
    /// The best point, [x, y] in m.
    pub best: [f64; 2],
    /// Where the agent faces at the end of the move (rad), if it has a heading.
    pub end_heading_rad: Option<f64>,
    /// The path, [x, y] in m each.
    pub waypoints: Vec<[f64; 2]>,
}

/// Why bytes are not a message.
#[derive(Debug, thiserror::Error)]
pub enum MessageError {
    /// The bytes do not decode as the message, or claim more than
    /// [`MAX_MESSAGE_BYTES`].
    #[error("not a message: {0}")]
    Malformed(String),
    /// The message decoded but bytes were left over.
    #[error("{0} bytes left over after the message")]
    Trailing(usize),
    /// The message is larger than [`MAX_MESSAGE_BYTES`].
    #[error("a message of {0} bytes, more than the largest allowed")]
    TooLarge(usize),
}

fn config() -> impl bincode::config::Config {
    bincode::config::standard().with_limit::<MAX_MESSAGE_BYTES>()
}

/// Encode `message`.
pub fn encode<T: Serialize>(message: &T) -> Result<Vec<u8>, MessageError> {
    let bytes = bincode::serde::encode_to_vec(message, config())
        .map_err(|e| MessageError::Malformed(e.to_string()))?;
    if bytes.len() > MAX_MESSAGE_BYTES {
        return Err(MessageError::TooLarge(bytes.len()));
    }
    Ok(bytes)
}

/// Decode a message from `bytes`, all of them.
///
/// ```
/// use net::{Down, decode, encode};
/// let bytes = encode(&Down::Quit).unwrap();
/// assert_eq!(decode::<Down>(&bytes).unwrap(), Down::Quit);
/// assert!(decode::<Down>(&[0xff; 3]).is_err());
/// ```
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, MessageError> {
    if bytes.len() > MAX_MESSAGE_BYTES {
        return Err(MessageError::TooLarge(bytes.len()));
    }
    let (message, read) = bincode::serde::decode_from_slice(bytes, config())
        .map_err(|e| MessageError::Malformed(e.to_string()))?;
    if read != bytes.len() {
        return Err(MessageError::Trailing(bytes.len() - read));
    }
    Ok(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a_move() -> Up {
        Up::Move(NetMove {
            agent: 3,
            seq: 9,
            step: 4,
            token: 0xdead_beef,
            status: 1,
            compute_ns: 1234,
            slot: [1.0, -2.5],
            best: [0.1, f64::MIN_POSITIVE],
            end_heading_rad: Some(-3.0),
            waypoints: vec![[0.0, 0.0], [1.0, 1e-300]],
        })
    }

    #[test]
    fn messages_round_trip_to_the_bit() {
        let turn = Down::Turn(NetTurn {
            seq: 1,
            step: 2,
            token: u64::MAX,
            centre: [1.5, -0.25, std::f64::consts::PI],
            heading_rad: Some(0.75),
            ahead: vec![[1.75, -0.25, 3.0], [2.0, 1e-300, -0.5]],
            bodies: vec![(0, [0.3, 0.1]), (7, [-1.0, 2.0])],
            velocities: vec![[0.25, 0.0], [-0.5, 1e-300]],
            frozen: vec![7],
        });
        assert_eq!(decode::<Down>(&encode(&turn).unwrap()).unwrap(), turn);
        let up = a_move();
        assert_eq!(decode::<Up>(&encode(&up).unwrap()).unwrap(), up);
    }

    #[test]
    fn every_truncation_and_trailing_byte_is_refused() {
        let bytes = encode(&a_move()).unwrap();
        for cut in 0..bytes.len() {
            assert!(decode::<Up>(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(
            decode::<Up>(&longer),
            Err(MessageError::Trailing(1))
        ));
    }

    #[test]
    fn a_length_beyond_the_limit_is_refused_without_allocating_it() {
        // A mission claiming a 2^60-byte text: variant 1, nonce 0, then the length as a
        // bincode varint (0xfd: a u64 follows).
        let mut bytes = vec![1u8, 0, 0xfd];
        bytes.extend_from_slice(&(1u64 << 60).to_le_bytes());
        assert!(decode::<Down>(&bytes).is_err());
    }
}
