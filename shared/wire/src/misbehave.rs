//! The test modes in which an agent process misbehaves or attacks on purpose
//! (`agent --misbehave MODE`, `coordinator run --misbehave AGENT=MODE`), so users and the
//! integration tests can check that the coordinator survives every one of them. Only an
//! agent built with its `misbehave` feature carries them out; the shipping agent refuses
//! them.
//!
//! The first seven publish unsafe or nonsensical moves through the normal protocol (the
//! safety monitor must refuse them); the others attack the protocol itself, as a
//! compromised or buggy agent process could.

use std::fmt;
use std::str::FromStr;

use shared::control::vocabulary::Named;

/// How an agent misbehaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Misbehave {
    /// Waypoints full of NaN.
    Nan,
    /// Jump: the move starts far from where the agent stands.
    Teleport,
    /// A straight line through the nearest obstacle.
    ThroughObstacle,
    /// Never answer a turn (alive but silent).
    Silent,
    /// Nonsense: an unknown status code and random-looking waypoints.
    Garbage,
    /// Too fast: follow the honest path forth and back again (9 passes, fewer if the
    /// waypoint capacity asks), ending where the honest move ends. The move covers the
    /// honest move's ground and nothing else, so it is safe but for its length, which
    /// is beyond a top speed whenever the honest move is longer than a ninth of it.
    Overspeed,
    /// Spin too far: the honest move, ending half a turn from the heading it honestly
    /// ends at (a holonomic agent: ending with a heading, where none belongs). The ground
    /// covered is the honest move's; the turning needs more than the step's time whenever
    /// `max_turn_rad` is under half a turn.
    OverTurn,
    /// Write the waypoint count of every move raw, beyond the capacity (513, 2^40,
    /// `u64::MAX` in turn).
    RawLength,
    /// The same raw count in the ready handshake.
    RawLengthReady,
    /// Publish the previous turn's move again (its old token) before the honest move.
    Replay,
    /// After each move, publish a guessed answer to the next turn before it is granted.
    Early,
    /// Publish every move four times.
    Flood,
    /// Open agent `victim`'s channel and publish as that agent.
    Impersonate {
        /// The agent whose channel is attacked.
        victim: usize,
    },
    /// Send a ready handshake in agent `victim`'s name on its own channel.
    SpoofReady {
        /// The agent named in the forged handshake.
        victim: usize,
    },
    /// Open as many ports as the run allows on every other agent's services.
    Hoard,
    /// Start children that ignore SIGTERM, one of which leaves the process group.
    Fork,
    /// Open its services, then exit before the ready handshake.
    ExitBeforeReady,
    /// Make a publisher on its own state service, leave an empty segment for one of its
    /// connections (as a process killed between iceoryx2's `shm_open` and its sizing of
    /// the segment does), then kill itself (SIGKILL) before the ready handshake.
    KilledConnecting,
    /// Ignore the notice that its turn comes next (`--wait spin`) and sleep until its turn
    /// is rung, as an agent that does not know the notice would; its moves are honest.
    DeafToPrepare,
    /// Before it starts, write random bytes over every file of the run's folder it can
    /// open (the iceoryx2 segments, the mission), then serve honestly. Only against a
    /// sandboxed run (`--sandbox`): a trusted agent can crash the coordinator so.
    Scribble,
    /// Before it starts, send SIGSTOP to every other process of the run, then serve
    /// honestly.
    StopOthers,
    /// Before it starts, rewrite the mission file without its obstacles, then serve
    /// honestly.
    RewriteMission,
    /// Before it starts, fork children that sleep until no more can be forked (at most
    /// 4096), then serve honestly. Only against a sandboxed run: a trusted agent is
    /// bounded by no limit of its own.
    ForkBomb,
    /// Answer two turns of every three 1.3 s after they are granted (past a 1 s
    /// deadline), the third at once: never three misses in a row.
    LateSome,
    /// Answer every turn 200 ms after it is granted: within the default deadline, later
    /// than the default slow bound.
    Sluggish,
    /// Before it starts, write 16 MiB of lines to stderr and 16 MiB to stdout, then serve
    /// honestly.
    LogFlood,
    /// Before it starts, push a line into its terminal's input (`TIOCSTI`, on
    /// `/dev/tty` and on its standard descriptors), as if typed at the shell that
    /// started the run, then serve honestly.
    TtyPush,
    /// Before it starts, write up to 256 MiB into each of `/dev/shm`, `/tmp` and
    /// `/var/tmp` and leave the files there, then serve honestly.
    FillTmp,
    /// Before it starts, SIGKILL every other process that runs under its own user id
    /// (another run's agent of the same index, if the runs shared ids), then serve
    /// honestly. Only against a sandboxed run: a trusted agent runs as the coordinator's
    /// user, and would kill it.
    KillTwin,
}

/// A mode name that is none of [`Misbehave::ALL`]'s.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{given:?} is not a misbehave mode: one of {}", Misbehave::usage().join(", "))]
pub struct UnknownMisbehave {
    /// What was given.
    pub given: String,
}

impl Misbehave {
    /// Every mode, in the order of the documentation; the modes that name a victim name
    /// agent 0.
    pub const ALL: [Self; 29] = [
        Self::Nan,
        Self::Teleport,
        Self::ThroughObstacle,
        Self::Silent,
        Self::Garbage,
        Self::Overspeed,
        Self::OverTurn,
        Self::RawLength,
        Self::RawLengthReady,
        Self::Replay,
        Self::Early,
        Self::Flood,
        Self::Impersonate { victim: 0 },
        Self::SpoofReady { victim: 0 },
        Self::Hoard,
        Self::Fork,
        Self::ExitBeforeReady,
        Self::KilledConnecting,
        Self::DeafToPrepare,
        Self::Scribble,
        Self::StopOthers,
        Self::RewriteMission,
        Self::ForkBomb,
        Self::LateSome,
        Self::Sluggish,
        Self::LogFlood,
        Self::TtyPush,
        Self::FillTmp,
        Self::KillTwin,
    ];

    /// The mode's name on the command line, without the victim (`impersonate` and
    /// `spoof-ready` are written `NAME=AGENT`). The one place the names are written.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Nan => "nan",
            Self::Teleport => "teleport",
            Self::ThroughObstacle => "through-obstacle",
            Self::Silent => "silent",
            Self::Garbage => "garbage",
            Self::Overspeed => "overspeed",
            Self::OverTurn => "over-turn",
            Self::RawLength => "raw-length",
            Self::RawLengthReady => "raw-length-ready",
            Self::Replay => "replay",
            Self::Early => "early",
            Self::Flood => "flood",
            Self::Impersonate { .. } => "impersonate",
            Self::SpoofReady { .. } => "spoof-ready",
            Self::Hoard => "hoard",
            Self::Fork => "fork",
            Self::ExitBeforeReady => "exit-before-ready",
            Self::KilledConnecting => "killed-connecting",
            Self::DeafToPrepare => "deaf-to-prepare",
            Self::Scribble => "scribble",
            Self::StopOthers => "stop-others",
            Self::RewriteMission => "rewrite-mission",
            Self::ForkBomb => "fork-bomb",
            Self::LateSome => "late-some",
            Self::Sluggish => "sluggish",
            Self::LogFlood => "log-flood",
            Self::TtyPush => "tty-push",
            Self::FillTmp => "fill-tmp",
            Self::KillTwin => "kill-twin",
        }
    }

    /// The agent this mode attacks, if it names one.
    pub fn victim(&self) -> Option<usize> {
        match self {
            Self::Impersonate { victim } | Self::SpoofReady { victim } => Some(*victim),
            _ => None,
        }
    }

    /// Every mode as written on the command line, `AGENT` standing for a victim.
    fn usage() -> Vec<String> {
        Self::ALL
            .iter()
            .map(|m| match m.victim() {
                Some(_) => format!("{}=AGENT", m.name()),
                None => m.name().to_string(),
            })
            .collect()
    }
}

impl FromStr for Misbehave {
    type Err = UnknownMisbehave;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || UnknownMisbehave {
            given: s.to_string(),
        };
        let (name, victim) = match s.split_once('=') {
            Some((name, victim)) => (name, Some(victim.parse().map_err(|_| unknown())?)),
            None => (s, None),
        };
        let mode = <Self as Named>::from_name(name).ok_or_else(unknown)?;
        match (mode, victim) {
            (Self::Impersonate { .. }, Some(victim)) => Ok(Self::Impersonate { victim }),
            (Self::SpoofReady { .. }, Some(victim)) => Ok(Self::SpoofReady { victim }),
            (mode, None) if mode.victim().is_none() => Ok(mode),
            _ => Err(unknown()),
        }
    }
}

impl Named for Misbehave {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "misbehave mode";

    fn name(&self) -> &'static str {
        Misbehave::name(self)
    }
}

impl fmt::Display for Misbehave {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())?;
        match self.victim() {
            Some(victim) => write!(f, "={victim}"),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_named_mode_parses_and_prints_back() {
        for name in Misbehave::usage() {
            let name = name.replace("AGENT", "4");
            let mode: Misbehave = name.parse().expect(&name);
            assert_eq!(mode.to_string(), name);
        }
        assert_eq!(
            "impersonate=2".parse::<Misbehave>().unwrap().victim(),
            Some(2)
        );
    }

    #[test]
    fn unknown_modes_and_bad_victims_are_refused() {
        for bad in [
            "",
            "NaN",
            "impersonate",
            "impersonate=x",
            "hoard=1",
            "nan=1",
        ] {
            assert!(bad.parse::<Misbehave>().is_err(), "{bad:?}");
        }
    }
}
