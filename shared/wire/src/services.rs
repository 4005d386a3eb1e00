//! The names of one agent's channel and the events rung on it.
//!
//! Every agent has a channel of its own: three services below the run's prefix (set in the
//! iceoryx2 config, [`crate::ipc_config`]), named after the agent and the generation of its
//! process (0 for the first, one more for every replacement); the static scenario comes
//! as a file in the run's private folder ([`crate::read_mission`]):
//! - `world`: publish-subscribe, coordinator to agent: the world of its turn, with the
//!   turn's token;
//! - `turn`: event, coordinator to agent: "your turn" / "quit" / "echo" / "you are next";
//! - `state`: publish-subscribe, agent to coordinator: its handshake and its moves.
//!
//! One service is shared by the run, [`DONE_SERVICE`]: event, agents to coordinator,
//! "my state is published", rung with the agent's index as the event id. A done service
//! per agent would cost the coordinator five open files per agent for the whole run, and its
//! open-file limit is what bounds the number of agents. An agent ringing another's id
//! only wakes the coordinator early: it then looks at that agent's own state channel,
//! which holds nothing of the ringer's.
//!
//! Those two event services ring a run started with `--wake event`. By default the same
//! events are rung on the run's doorbells ([`crate::Doorbells`]): the event ids below
//! are then bits of the agent's doorbell word, and "my state is published" is a count on
//! the run's answer counter. The `turn` and done services are made either way (an agent
//! rung by doorbells opens neither), so a process that opens or hoards their ports is
//! still seen.

/// The names of the three services of one agent's channel (see the crate documentation).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AgentServiceNames {
    /// Coordinator to agent: the [`World`](crate::World) of each turn.
    pub world: String,
    /// Event, coordinator to agent: [`EVENT_TURN`], [`EVENT_QUIT`], [`EVENT_ECHO`],
    /// [`EVENT_PREPARE`].
    pub turn: String,
    /// Agent to coordinator: its [`AgentState`](crate::AgentState) (handshake, moves, echoes).
    pub state: String,
}

impl AgentServiceNames {
    /// The services of agent `agent` served by its `generation`-th process (0 for the
    /// first; a replacement gets the next generation and so services of its own).
    pub fn new(agent: usize, generation: u32) -> Self {
        let base = format!("formation/agent/{agent}/{generation}");
        Self {
            world: format!("{base}/world"),
            turn: format!("{base}/turn"),
            state: format!("{base}/state"),
        }
    }
}

/// Event id on a turn service: take your turn (the world is published).
pub const EVENT_TURN: usize = 1;
/// Event id on a turn service: leave cleanly now.
pub const EVENT_QUIT: usize = 2;
/// Event id on a turn service: answer at once with an empty [`StateKind::Echo`](crate::StateKind::Echo) state,
/// without reading the world or planning (`coordinator bench`: the wake-up alone).
pub const EVENT_ECHO: usize = 3;
/// Event id on a turn service: your turn comes next (the agent before you has just been
/// granted its turn); poll the world for [`PREPARE_SPIN`] instead of sleeping, so the
/// grant costs neither a wake-up nor a ring (`coordinator run --wait spin`).
pub const EVENT_PREPARE: usize = 4;

/// How long an agent told it is next ([`EVENT_PREPARE`]) polls its world after waking,
/// before it sleeps again: a few turns' worth.
pub const PREPARE_SPIN: std::time::Duration = std::time::Duration::from_millis(2);

/// How long after ringing [`EVENT_PREPARE`] the coordinator may grant that agent's turn
/// by publishing its world alone, without ringing [`EVENT_TURN`]: within this window the
/// agent is still polling (it woke after the ring and polls for [`PREPARE_SPIN`]) or has
/// yet to wake (and then looks at its world first). Later, the turn is rung as usual.
pub const PREPARED_GRANT_WINDOW: std::time::Duration = std::time::Duration::from_micros(1500);

const _: () = assert!(PREPARED_GRANT_WINDOW.as_nanos() < PREPARE_SPIN.as_nanos());

/// The run's one done service: event, agents to coordinator, "my state is published",
/// the event id being the agent's index.
pub const DONE_SERVICE: &str = "formation/done";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_agent_generation_has_services_of_its_own() {
        let a = AgentServiceNames::new(3, 0);
        let b = AgentServiceNames::new(3, 1);
        let c = AgentServiceNames::new(4, 0);
        let all = |n: &AgentServiceNames| [n.world.clone(), n.turn.clone(), n.state.clone()];
        let mut names: Vec<String> = [all(&a), all(&b), all(&c)].concat();
        let count = names.len();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), count);
    }
}
