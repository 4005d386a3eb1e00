//! The test modes that act on the agent's iceoryx2 ports rather than on its moves:
//! [`Tampered`] is the [`Channel`] decorator that writes raw waypoint counts into the
//! samples it sends (`raw-length`, `raw-length-ready`), sends the ready handshake in
//! another agent's name (`spoof-ready`) and drops the notice that the agent's turn comes
//! next (`deaf-to-prepare`).

use std::time::Duration;

use iceoryx2::port::listener::ListenerWaitError;
use wire::misbehave::Misbehave;
use wire::{AgentState, StateKind};

use crate::ipc::{Channel, Events};
use crate::transport::TurnInput;

/// The raw waypoint counts a tampering agent writes, in turn.
const RAW_COUNTS: [u64; 3] = [wire_capacity_plus_one(), 1 << 40, u64::MAX];

const fn wire_capacity_plus_one() -> u64 {
    shared::control::vocabulary::MAX_WAYPOINTS as u64 + 1
}

/// Write `state`'s waypoint count field raw, as a hostile process can.
fn write_raw_waypoint_count(state: &mut AgentState, count: u64) {
    let vec = std::ptr::addr_of_mut!(state.waypoints).cast::<u8>();
    let len_offset =
        std::mem::size_of::<[wire::WirePoint; shared::control::vocabulary::MAX_WAYPOINTS]>();
    // SAFETY: `StaticVec` is `repr(C)` { data: [_; CAPACITY], len: u64 }: the count lies
    // right after the array, inside the sample.
    unsafe { std::ptr::write_unaligned(vec.add(len_offset).cast::<u64>(), count) };
}

/// A [`Channel`] decorator: the ports `C`, tampered with as mode `mode` says (modes that
/// do not act on the ports pass everything through).
pub struct Tampered<C> {
    inner: C,
    mode: Misbehave,
    /// States sent so far (picks the raw count).
    sent: usize,
}

impl<C: Channel> Tampered<C> {
    /// `inner`, tampered with as `mode` says.
    pub fn new(inner: C, mode: Misbehave) -> Self {
        Self {
            inner,
            mode,
            sent: 0,
        }
    }
}

/// Change the filled state `state`, the `sent`-th this agent sends, as `mode` says.
fn tamper(mode: Misbehave, sent: usize, state: &mut AgentState) {
    let kind = state.kind;
    match mode {
        Misbehave::RawLength if kind == StateKind::Move as u32 => {
            write_raw_waypoint_count(state, RAW_COUNTS[sent % RAW_COUNTS.len()]);
        }
        Misbehave::RawLengthReady if kind == StateKind::Ready as u32 => {
            write_raw_waypoint_count(state, RAW_COUNTS[sent % RAW_COUNTS.len()]);
        }
        Misbehave::SpoofReady { victim } if kind == StateKind::Ready as u32 => {
            if let Ok(victim) = u32::try_from(victim) {
                state.agent = victim;
            }
        }
        _ => {}
    }
}

impl<C: Channel> Channel for Tampered<C> {
    fn wait(&mut self, timeout: Duration) -> (Events, Result<(), ListenerWaitError>) {
        let (mut events, woke) = self.inner.wait(timeout);
        if self.mode == Misbehave::DeafToPrepare {
            events.prepare = false;
        }
        (events, woke)
    }

    fn read_world(&mut self) -> anyhow::Result<Option<TurnInput>> {
        self.inner.read_world()
    }

    fn send_state(
        &mut self,
        fill: impl FnOnce(&mut AgentState) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        let (mode, sent) = (self.mode, self.sent);
        self.inner.send_state(|state| {
            fill(state)?;
            tamper(mode, sent, state);
            Ok(())
        })?;
        self.sent += 1;
        Ok(())
    }

    fn termination_requested(&self) -> bool {
        self.inner.termination_requested()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What was sent in one state: its kind, the agent it names, its raw waypoint count.
    type Sent = (u32, u32, u64);

    /// Ports that keep what is sent and hear what they are told to.
    #[derive(Default)]
    struct Recorded {
        heard: Events,
        sent: Vec<Sent>,
    }

    impl Channel for Recorded {
        fn wait(&mut self, _timeout: Duration) -> (Events, Result<(), ListenerWaitError>) {
            (self.heard, Ok(()))
        }
        fn read_world(&mut self) -> anyhow::Result<Option<TurnInput>> {
            Ok(None)
        }
        fn send_state(
            &mut self,
            fill: impl FnOnce(&mut AgentState) -> anyhow::Result<()>,
        ) -> anyhow::Result<()> {
            let mut state = AgentState {
                agent: 4,
                ..AgentState::default()
            };
            fill(&mut state)?;
            self.sent
                .push((state.kind, state.agent, raw_waypoint_count(&state)));
            // A count the drop can walk.
            write_raw_waypoint_count(&mut state, 0);
            Ok(())
        }
        fn termination_requested(&self) -> bool {
            false
        }
    }

    /// `state`'s waypoint count field as written (its slice methods trust it, so a raw
    /// count must not reach them).
    fn raw_waypoint_count(state: &AgentState) -> u64 {
        let vec = std::ptr::addr_of!(state.waypoints).cast::<u8>();
        let len_offset =
            std::mem::size_of::<[wire::WirePoint; shared::control::vocabulary::MAX_WAYPOINTS]>();
        // SAFETY: the count lies right after the array, inside the state (see
        // `write_raw_waypoint_count`).
        unsafe { std::ptr::read_unaligned(vec.add(len_offset).cast::<u64>()) }
    }

    /// Send a state of `kind` with one waypoint in a move.
    fn send(ports: &mut Tampered<Recorded>, kind: StateKind) {
        ports
            .send_state(|s| {
                s.kind = kind as u32;
                if kind == StateKind::Move {
                    s.set_waypoints(&[shared::geometry::Point::new(1.0, 2.0)])?;
                }
                Ok(())
            })
            .expect("sent");
    }

    fn counts(ports: &Tampered<Recorded>) -> Vec<u64> {
        ports.inner.sent.iter().map(|s| s.2).collect()
    }

    #[test]
    fn raw_counts_go_into_the_moves_in_turn_and_into_the_handshake_only_when_asked() {
        let mut moves = Tampered::new(Recorded::default(), Misbehave::RawLength);
        for kind in [
            StateKind::Ready,
            StateKind::Move,
            StateKind::Echo,
            StateKind::Move,
            StateKind::Move,
        ] {
            send(&mut moves, kind);
        }
        // The count follows every state sent, echoes and the handshake included.
        assert_eq!(
            counts(&moves),
            [0, 1 << 40, 0, MAX_WAYPOINTS_PLUS_ONE, 1 << 40]
        );
        let mut ready = Tampered::new(Recorded::default(), Misbehave::RawLengthReady);
        send(&mut ready, StateKind::Ready);
        send(&mut ready, StateKind::Move);
        assert_eq!(counts(&ready), [MAX_WAYPOINTS_PLUS_ONE, 1]);
        let mut honest = Tampered::new(Recorded::default(), Misbehave::Flood);
        send(&mut honest, StateKind::Ready);
        send(&mut honest, StateKind::Move);
        assert_eq!(counts(&honest), [0, 1]);
    }

    const MAX_WAYPOINTS_PLUS_ONE: u64 = shared::control::vocabulary::MAX_WAYPOINTS as u64 + 1;

    #[test]
    fn a_spoofed_handshake_names_the_victim_and_its_moves_name_the_agent() {
        let mut ports = Tampered::new(Recorded::default(), Misbehave::SpoofReady { victim: 1 });
        send(&mut ports, StateKind::Ready);
        send(&mut ports, StateKind::Move);
        let agents: Vec<u32> = ports.inner.sent.iter().map(|s| s.1).collect();
        assert_eq!(agents, [1, 4]);
    }

    #[test]
    fn only_a_deaf_agent_drops_the_prepare_notice() {
        let heard = Events {
            turn: true,
            prepare: true,
            ..Events::default()
        };
        let recorded = || Recorded {
            heard,
            ..Recorded::default()
        };
        let mut deaf = Tampered::new(recorded(), Misbehave::DeafToPrepare);
        let (events, woke) = deaf.wait(Duration::ZERO);
        assert!(woke.is_ok());
        assert_eq!(
            events,
            Events {
                prepare: false,
                ..heard
            }
        );
        let mut hearing = Tampered::new(recorded(), Misbehave::Flood);
        assert_eq!(hearing.wait(Duration::ZERO).0, heard);
    }
}
