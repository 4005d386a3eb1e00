//! Faults injected into a run on purpose ([`FaultInjection`]): kills and deaths at
//! chosen steps, and agents started in a test mode. Kept apart from how a run is
//! carried out ([`super::RunOptions`]): a run without them is a plain run.

use wire::misbehave::Misbehave;

/// The faults a run injects; the default injects none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaultInjection {
    /// Kill agent `.0` with SIGKILL right after granting its turn at step `.1` (the kill
    /// races with the agent's answer: its move may get out first).
    pub kills: Vec<(usize, usize)>,
    /// Agent `.0` dies at step `.1` before its turn. Its process is killed with SIGKILL
    /// (and waited for) once the step's groups are formed, just before its group's turns
    /// are granted, so the death is always detected during its turn and its group mates
    /// still move: the run equals [`shared::run::simulate::simulate_along_with_deaths`] to
    /// the bit.
    pub deaths: Vec<(usize, usize)>,
    /// Start agent `.0` with `--misbehave .1` (an agent built with its test modes; its
    /// replacements behave).
    pub misbehave: Vec<(usize, Misbehave)>,
}

impl FaultInjection {
    /// Whether `agent` is killed right after its turn at `step` is granted.
    pub fn kills_during_turn(&self, agent: usize, step: usize) -> bool {
        self.kills.contains(&(agent, step))
    }

    /// Whether `agent` dies at `step` before its group's turns.
    pub fn dies_before_turn(&self, agent: usize, step: usize) -> bool {
        self.deaths.contains(&(agent, step))
    }

    /// The test mode `agent` starts in, if any.
    pub fn misbehaviour_of(&self, agent: usize) -> Option<Misbehave> {
        self.misbehave
            .iter()
            .find(|(a, _)| *a == agent)
            .map(|(_, mode)| *mode)
    }

    /// Every agent the faults name: those killed, those that die, those in a test mode
    /// and their victims.
    pub fn agents_named(&self) -> impl Iterator<Item = usize> + '_ {
        self.kills
            .iter()
            .chain(&self.deaths)
            .map(|(a, _)| *a)
            .chain(
                self.misbehave
                    .iter()
                    .flat_map(|(a, mode)| std::iter::once(*a).chain(mode.victim())),
            )
    }
}
