//! The formation controller between hosts: an agent on another machine takes its turns
//! over Zenoh.
//!
//! On one host everything goes through iceoryx2 shared memory. An agent elsewhere is
//! represented on the coordinator's host by a *relay*: a process that opens the agent's
//! iceoryx2 channel exactly as a local agent would, and forwards each turn to the agent
//! and its move back over Zenoh. The coordinator's protocol, checks and deadlines are
//! the same for both; the relay adds one hop on the coordinator's host.
//!
//! The coordinator runs a Zenoh router on an explicit endpoint (`open_router`); relays
//! and agents are its clients (`open_client`; both with the feature `zenoh`). Per agent I:
//! - `formation/agent/I/down`: relay to agent ([`Down`]: probe, mission, turn, quit);
//! - `formation/agent/I/up`: agent to relay ([`Up`]: hello, ready, move);
//! - `formation/agent/I/alive`: the agent's liveliness token, gone with its session;
//! - `formation/coordinator/alive`: the coordinator's.
//!
//! One concept per module:
//! - `endpoint`: `tcp/HOST:PORT` and `tls/HOST:PORT` ([`Endpoint`]);
//! - `message`: the messages and their bounded decoding ([`decode`]);
//! - `port`: sending and receiving them on Zenoh ports (`send`, `receive`; feature `zenoh`);
//! - `keys`: the key expressions;
//! - `security`: plain or TLS, the files and names of each side ([`Security`], [`Role`]);
//! - `session`: opening the router and the clients (feature `zenoh`);
//! - `authority`: a run's own TLS authority, made on the fly ([`make_run_authority`];
//!   feature `zenoh`).
//!
//! Without the feature `zenoh` only the parts that need no Zenoh are built (endpoints,
//! messages, security): enough for the coordinator's and the agent's command lines.
#![warn(missing_docs)]

#[cfg(feature = "zenoh")]
mod authority;
mod endpoint;
mod keys;
mod message;
#[cfg(feature = "zenoh")]
mod port;
mod security;
#[cfg(feature = "zenoh")]
mod session;

#[cfg(feature = "zenoh")]
pub use authority::{AuthorityError, make_run_authority};
pub use endpoint::{Endpoint, EndpointError, LinkProtocol};
pub use keys::{COORDINATOR_ALIVE_KEY, agent_alive_key, agent_down_key, agent_up_key};
pub use message::{Down, MAX_MESSAGE_BYTES, MessageError, NetMove, NetTurn, Up, decode, encode};
#[cfg(feature = "zenoh")]
pub use port::{PortError, receive, send};
pub use security::{Role, Security, SessionError, TlsFiles, check_security};
#[cfg(feature = "zenoh")]
pub use session::{CONNECT_TIMEOUT, LINK_LEASE, open_client, open_router};
#[cfg(feature = "zenoh")]
pub use zenoh;
