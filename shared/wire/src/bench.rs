//! The services and the sample of `coordinator bench`'s latency floor.

use iceoryx2::prelude::*;

/// Benchmark floor (`coordinator bench`): coordinator to ping-pong process, one small
/// sample per round trip.
pub const BENCH_PING_SERVICE: &str = "bench/ping";
/// Benchmark floor: ping-pong process to coordinator (the ready handshake has `seq` 0).
pub const BENCH_PONG_SERVICE: &str = "bench/pong";
/// Benchmark floor: event "a ping is published" (or [`EVENT_QUIT`](crate::EVENT_QUIT)).
pub const BENCH_PING_EVENT: &str = "bench/ping-event";
/// Benchmark floor: event "the pong is published".
pub const BENCH_PONG_EVENT: &str = "bench/pong-event";
/// Event id on [`BENCH_PING_EVENT`]: answer framed requests on the Unix socket now,
/// until the coordinator sends the frame header [`BENCH_SOCKET_DONE`].
pub const BENCH_EVENT_SOCKET: usize = 3;
/// Request length in a socket frame header meaning "back to the iceoryx2 ping-pong".
pub const BENCH_SOCKET_DONE: u32 = u32::MAX;
/// Event id on [`BENCH_PING_EVENT`]: busy-poll the ping subscriber and publish each pong
/// at once, no event either way (the busy-poll publish-subscribe floor), until the ping
/// [`BENCH_SPIN_DONE`] comes (answered, then back to the blocking ping-pong).
pub const BENCH_EVENT_SPIN: usize = 4;
/// Event id on [`BENCH_PING_EVENT`]: take the pings' rings from the session's doorbells
/// (agent 0's word of [`crate::Doorbells`], rung with [`EVENT_TURN`](crate::EVENT_TURN))
/// and count each pong on their answer counter, no iceoryx2 event either way (the floor
/// of turns rung by doorbells), until the doorbell rings this id itself (then back to
/// the event ping-pong).
pub const BENCH_EVENT_DOORBELL: usize = 5;
/// The `seq` of the ping that ends the busy-poll ping-pong.
pub const BENCH_SPIN_DONE: u64 = u64::MAX;

/// The small sample of the benchmark floor's ping-pong, each way.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::BenchPing")]
pub struct BenchPing {
    /// Round trip number (0: the ping-pong process's ready handshake).
    pub seq: u64,
    /// Filler, so the sample is as small as a turn's header.
    pub payload: [u64; 3],
}
