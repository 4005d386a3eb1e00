//! An agent's message to the coordinator (its handshake, its move, an echo), and the
//! checked copy the coordinator reads it through.
//!
//! Everything an agent writes is untrusted: the coordinator reads a state sample only
//! through [`AgentState::read_checked`], which copies it out of shared memory and checks
//! every field before anything uses it.

use iceoryx2::prelude::*;
use iceoryx2_bb_container::vector::{StaticVec, Vector};
use shared::control::vocabulary::{MAX_WAYPOINTS, MoveStatus};
use shared::geometry::Point;

use crate::{CapacityError, WirePoint};

/// What an agent's state message is.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateKind {
    /// The agent has opened every service and waits for turns.
    Ready = 0,
    /// The agent's move for the turn with sequence number `seq`.
    Move = 1,
    /// The answer to an [`EVENT_ECHO`](crate::EVENT_ECHO): timestamps only.
    Echo = 2,
}

/// An agent's message to the coordinator: its ready handshake or its move.
///
/// Written by another process: read it only through [`AgentState::read_checked`].
#[repr(C)]
#[derive(Debug, Default, ZeroCopySend, PlacementDefault)]
#[type_name("formation::AgentState")]
pub struct AgentState {
    /// The world's `seq` this answers (0 for the handshake).
    pub seq: u64,
    /// The step this answers.
    pub step: u64,
    /// The world's `token` this answers (0 for the handshake and echoes).
    pub token: u64,
    /// Time the agent spent computing the move, in nanoseconds.
    pub compute_ns: u64,
    /// When the agent woke for this turn, on the machine's monotonic clock
    /// ([`monotonic_ns`](crate::monotonic_ns)); 0 if unknown.
    pub woke_ns: u64,
    /// When the agent sent this state, on the machine's monotonic clock; 0 if unknown.
    pub sent_ns: u64,
    /// The agent's index.
    pub agent: u32,
    /// A [`StateKind`] code.
    pub kind: u32,
    /// A [`MoveStatus`] code.
    pub status: u32,
    /// The agent's process id.
    pub pid: u32,
    /// 1 when the move ends with the heading `end_heading_rad` (an agent with a heading),
    /// 0 when it has none (a holonomic agent, a handshake, an echo).
    pub has_end_heading: u32,
    /// Padding, always 0.
    pub reserved: u32,
    /// Where the agent faces at the end of its move, in rad, when `has_end_heading` is 1.
    pub end_heading_rad: f64,
    /// The ideal slot at this step.
    pub slot: WirePoint,
    /// The point the agent moves to.
    pub best: WirePoint,
    /// The polyline it follows, from its position to `best`.
    pub waypoints: StaticVec<WirePoint, MAX_WAYPOINTS>,
}

/// A state message copied out of shared memory and checked field by field
/// ([`AgentState::read_checked`]): plain values no other process can change any more.
#[derive(Clone, Debug, PartialEq)]
pub struct StateMsg {
    /// What the message is.
    pub kind: StateKind,
    /// The world's `seq` it answers.
    pub seq: u64,
    /// The step it answers.
    pub step: u64,
    /// The world's token it answers.
    pub token: u64,
    /// The agent's compute time for the move, in nanoseconds, as the agent reports it
    /// (bounded by [`MAX_COMPUTE_NS`]; the coordinator also bounds it by the turn).
    pub compute_ns: u64,
    /// When the agent woke, on the monotonic clock (0: unknown).
    pub woke_ns: u64,
    /// When the agent sent it, on the monotonic clock (0: unknown).
    pub sent_ns: u64,
    /// The process id the agent claims.
    pub pid: u32,
    /// The move status code, as sent (checked against [`MoveStatus`] by the monitor's
    /// caller, which refuses unknown codes as unsafe moves).
    pub status: u32,
    /// Where it faces at the end of its move (`None`: it sent no heading). Any value, as
    /// sent: the recorder checks it against the agent's kinematics.
    pub end_heading_rad: Option<f64>,
    /// The ideal slot the agent computed.
    pub slot: Point,
    /// The point it moves to.
    pub best: Point,
    /// Its path, from where it stands to `best`.
    pub waypoints: Vec<Point>,
}

impl StateMsg {
    /// The move status, if the code is known.
    pub fn move_status(&self) -> Option<MoveStatus> {
        u8::try_from(self.status)
            .ok()
            .and_then(MoveStatus::from_code)
    }
}

/// Largest compute time an agent may report for one move: an hour, in nanoseconds.
/// Anything above is a corrupt value, not a slow controller.
pub const MAX_COMPUTE_NS: u64 = 3_600 * 1_000_000_000;

/// Why a state sample was refused before anything used it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MalformedState {
    /// The message kind code is none of [`StateKind`]'s.
    #[error("unknown message kind code {0}")]
    Kind(u32),
    /// The sample names another agent than the one whose channel carried it.
    #[error("the message claims to be from agent {claimed}, on agent {channel}'s channel")]
    Agent {
        /// The agent index written in the sample.
        claimed: u32,
        /// The agent whose channel it came on.
        channel: usize,
    },
    /// The waypoint count is beyond the message's capacity.
    #[error("waypoint count {0} exceeds the capacity of {MAX_WAYPOINTS}")]
    WaypointCount(u64),
    /// The reported compute time is beyond [`MAX_COMPUTE_NS`].
    #[error("compute time {0} ns is beyond any turn")]
    ComputeTime(u64),
    /// The agent's two timestamps are out of order.
    #[error("woke at {woke_ns} ns but sent at {sent_ns} ns")]
    Timestamps {
        /// When it claims it woke.
        woke_ns: u64,
        /// When it claims it sent.
        sent_ns: u64,
    },
    /// The sample could not be taken from the channel at all (the publisher's memory
    /// could not be mapped, for instance).
    #[error("the sample could not be received: {0}")]
    Unreadable(String),
    /// The heading flag is neither 0 nor 1, or a handshake or echo carries a heading.
    #[error("heading flag {flag} on a {kind:?} message")]
    HeadingFlag {
        /// The message kind.
        kind: StateKind,
        /// The flag as written.
        flag: u32,
    },
    /// A handshake or echo carries a move (waypoints).
    #[error("a {kind:?} message carries {count} waypoints")]
    UnexpectedWaypoints {
        /// The message kind.
        kind: StateKind,
        /// How many waypoints it carries.
        count: usize,
    },
}

impl AgentState {
    /// Copy this sample out of shared memory and check it, as the message of agent
    /// `channel_agent` (the agent whose channel carried it). Every field is read once;
    /// the waypoint count is checked against the capacity before any waypoint is read,
    /// so no value written by another process can make the reader panic or read out of
    /// bounds. The values themselves (finite, in the field, safe) are the safety
    /// monitor's to judge.
    pub fn read_checked(&self, channel_agent: usize) -> Result<StateMsg, MalformedState> {
        let kind = match self.kind {
            0 => StateKind::Ready,
            1 => StateKind::Move,
            2 => StateKind::Echo,
            other => return Err(MalformedState::Kind(other)),
        };
        let claimed = self.agent;
        if usize::try_from(claimed).ok() != Some(channel_agent) {
            return Err(MalformedState::Agent {
                claimed,
                channel: channel_agent,
            });
        }
        let count = self.raw_waypoint_count();
        let len = match usize::try_from(count) {
            Ok(len) if len <= MAX_WAYPOINTS => len,
            _ => return Err(MalformedState::WaypointCount(count)),
        };
        if kind != StateKind::Move && len > 0 {
            return Err(MalformedState::UnexpectedWaypoints { kind, count: len });
        }
        let flag = self.has_end_heading;
        let end_heading_rad = match (flag, kind) {
            (0, _) => None,
            (1, StateKind::Move) => Some(self.end_heading_rad),
            _ => return Err(MalformedState::HeadingFlag { kind, flag }),
        };
        let compute_ns = self.compute_ns;
        if compute_ns > MAX_COMPUTE_NS {
            return Err(MalformedState::ComputeTime(compute_ns));
        }
        let (woke_ns, sent_ns) = (self.woke_ns, self.sent_ns);
        if woke_ns != 0 && sent_ns != 0 && woke_ns > sent_ns {
            return Err(MalformedState::Timestamps { woke_ns, sent_ns });
        }
        let base = std::ptr::addr_of!(self.waypoints).cast::<WirePoint>();
        let waypoints = (0..len)
            .map(|i| {
                // SAFETY: `StaticVec` is `repr(C)` with its element array first (checked
                // by a test below), so `base` points at element 0 of an array of
                // MAX_WAYPOINTS points, and `i < len <= MAX_WAYPOINTS`. Every bit
                // pattern is a valid pair of f64. A volatile read: another process may
                // write this memory while it is read.
                Point::from(unsafe { std::ptr::read_volatile(base.add(i)) })
            })
            .collect();
        Ok(StateMsg {
            kind,
            seq: self.seq,
            step: self.step,
            token: self.token,
            compute_ns,
            woke_ns,
            sent_ns,
            pid: self.pid,
            status: self.status,
            end_heading_rad,
            slot: self.slot.into(),
            best: self.best.into(),
            waypoints,
        })
    }

    /// The waypoint count field as written, which may exceed the capacity.
    fn raw_waypoint_count(&self) -> u64 {
        // `len()` only reads the field; it is the slicing methods that trust it.
        self.waypoints.len() as u64
    }

    /// Set the end heading (`None`: the agent has none).
    pub fn set_end_heading(&mut self, end_heading_rad: Option<f64>) {
        self.has_end_heading = u32::from(end_heading_rad.is_some());
        self.end_heading_rad = end_heading_rad.unwrap_or(0.0);
    }

    /// Replace the waypoints.
    pub fn set_waypoints(&mut self, points: &[Point]) -> Result<(), CapacityError> {
        self.waypoints.clear();
        for &p in points {
            self.waypoints
                .push(p.into())
                .map_err(|_| CapacityError::Waypoints(points.len()))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Write the waypoint count field raw, as a hostile process can.
    fn write_raw_count(st: &mut AgentState, count: u64) {
        let vec = std::ptr::addr_of_mut!(st.waypoints).cast::<u8>();
        let len_offset = std::mem::size_of::<[WirePoint; MAX_WAYPOINTS]>();
        // SAFETY: `StaticVec` is `repr(C)` { data, len: u64 }: the count lies right after
        // the array, inside the struct.
        unsafe { std::ptr::write_unaligned(vec.add(len_offset).cast::<u64>(), count) };
    }

    fn a_move(agent: u32, points: &[Point]) -> AgentState {
        let mut st = AgentState {
            kind: StateKind::Move as u32,
            agent,
            seq: 7,
            token: 99,
            ..AgentState::default()
        };
        st.set_waypoints(points).unwrap();
        st
    }

    #[test]
    fn waypoints_beyond_capacity_are_an_error_not_a_truncation() {
        let mut st = AgentState::default();
        let many = vec![Point::new(1.0, 2.0); MAX_WAYPOINTS + 1];
        assert_eq!(
            st.set_waypoints(&many),
            Err(CapacityError::Waypoints(MAX_WAYPOINTS + 1))
        );
        st.set_waypoints(&many[..3]).unwrap();
        st.kind = StateKind::Move as u32;
        assert_eq!(st.read_checked(0).unwrap().waypoints, many[..3].to_vec());
    }

    #[test]
    fn a_checked_read_copies_every_field() {
        let points = [Point::new(1.0, 2.0), Point::new(3.5, -4.25)];
        let mut st = a_move(3, &points);
        st.step = 5;
        st.compute_ns = 1234;
        st.woke_ns = 10;
        st.sent_ns = 20;
        st.pid = 42;
        st.status = MoveStatus::AtSlot as u32;
        st.best = points[1].into();
        st.set_end_heading(Some(0.5));
        let m = st.read_checked(3).unwrap();
        assert_eq!(
            m,
            StateMsg {
                kind: StateKind::Move,
                seq: 7,
                step: 5,
                token: 99,
                compute_ns: 1234,
                woke_ns: 10,
                sent_ns: 20,
                pid: 42,
                status: MoveStatus::AtSlot as u32,
                end_heading_rad: Some(0.5),
                slot: Point::new(0.0, 0.0),
                best: points[1],
                waypoints: points.to_vec(),
            }
        );
        assert_eq!(m.move_status(), Some(MoveStatus::AtSlot));
    }

    #[test]
    fn the_raw_count_writer_hits_the_count_field() {
        // The layout the checked read relies on: the count right after the array.
        let mut st = a_move(0, &[Point::new(1.0, 1.0); 5]);
        write_raw_count(&mut st, 2);
        assert_eq!(st.waypoints.len(), 2);
        assert_eq!(st.read_checked(0).unwrap().waypoints.len(), 2);
    }

    #[test]
    fn hostile_counts_kinds_and_agents_are_refused_not_panicked_on() {
        for count in [MAX_WAYPOINTS as u64 + 1, 1 << 40, u64::MAX] {
            let mut st = a_move(0, &[Point::new(1.0, 1.0)]);
            write_raw_count(&mut st, count);
            assert_eq!(
                st.read_checked(0),
                Err(MalformedState::WaypointCount(count))
            );
            // Leave a count the drop can walk.
            write_raw_count(&mut st, 0);
        }
        let mut st = a_move(0, &[]);
        st.kind = 7;
        assert_eq!(st.read_checked(0), Err(MalformedState::Kind(7)));
        let st = a_move(4, &[]);
        assert_eq!(
            st.read_checked(1),
            Err(MalformedState::Agent {
                claimed: 4,
                channel: 1
            })
        );
        let mut st = a_move(0, &[]);
        st.compute_ns = u64::MAX;
        assert_eq!(
            st.read_checked(0),
            Err(MalformedState::ComputeTime(u64::MAX))
        );
        let mut st = a_move(0, &[]);
        (st.woke_ns, st.sent_ns) = (20, 10);
        assert!(matches!(
            st.read_checked(0),
            Err(MalformedState::Timestamps { .. })
        ));
        let mut st = a_move(0, &[]);
        st.has_end_heading = 2;
        assert_eq!(
            st.read_checked(0),
            Err(MalformedState::HeadingFlag {
                kind: StateKind::Move,
                flag: 2
            })
        );
        let mut st = a_move(0, &[]);
        st.kind = StateKind::Echo as u32;
        st.set_end_heading(Some(1.0));
        assert!(matches!(
            st.read_checked(0),
            Err(MalformedState::HeadingFlag { .. })
        ));
        let mut st = a_move(0, &[Point::new(0.0, 0.0)]);
        st.kind = StateKind::Ready as u32;
        assert!(matches!(
            st.read_checked(0),
            Err(MalformedState::UnexpectedWaypoints { .. })
        ));
    }
}
