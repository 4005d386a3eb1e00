//! A granted turn and its answer: waiting for it, and what the agent's channel holds.
//! Every sample is published by the agent's own process or recorded as an
//! impersonation; during a turn the first sample carrying the turn's token is the
//! answer; anything else is counted.

use std::time::{Duration, Instant};

use shared::run::record::{FaultKind, Recorder};
use wire::{MalformedState, StateKind, StateMsg};

use super::driver::Driver;
use super::options::LIVENESS_SLICE;
use crate::agents::Exit;
use crate::ipc::{Grant, Incoming};

/// One granted turn, until its answer is judged.
pub(super) struct Turn {
    /// The agent whose turn it is.
    pub(super) agent: usize,
    /// Its process when the turn was granted.
    pub(super) pid: Option<u32>,
    /// What the answer must carry: the world's sequence number and the turn's token.
    pub(super) grant: Grant,
    /// When the world was published (stamped before it existed).
    pub(super) granted_at: Instant,
    /// The same moment on the monotonic clock the agents stamp their states with, ns.
    pub(super) granted_ns: u64,
    /// Whether the turn was rung (else the agent was polling its recorder).
    pub(super) rung: bool,
}

/// What the coordinator learned while waiting for a move.
pub(super) enum Answer {
    /// The move arrived.
    Move(Box<StateMsg>),
    /// The agent answered its turn with a sample that failed the checks.
    Malformed(String),
    /// The agent's process is gone; detected after this long.
    Dead(Duration),
    /// The deadline passed with the process alive.
    Missed,
    /// SIGINT or SIGTERM reached the coordinator.
    Interrupted,
}

/// What a sample from the agent's own process means during its turn.
enum Judged {
    /// It ends the turn.
    Answer(Answer),
    /// It answers no turn (a replay, a guess, a handshake): counted, ignored.
    Unsolicited,
    /// A late echo: no fault.
    Ignore,
}

/// Judge `incoming` during the turn of `grant` at `step`, from the agent's process `pid`.
fn judge_answer(incoming: Incoming, grant: Grant, step: usize, pid: Option<u32>) -> Judged {
    let msg = match incoming.msg {
        Ok(msg) => msg,
        Err(why) => return Judged::Answer(Answer::Malformed(why.to_string())),
    };
    match msg.kind {
        StateKind::Echo => Judged::Ignore,
        StateKind::Move if msg.token == grant.token => {
            let bad = if msg.seq != grant.seq {
                Some(format!(
                    "answers recorder {} in turn {}",
                    msg.seq, grant.seq
                ))
            } else if msg.step != step as u64 {
                Some(format!("answers step {} at step {step}", msg.step))
            } else if Some(msg.pid) != pid {
                Some(format!("claims process {}, not {pid:?}", msg.pid))
            } else {
                None
            };
            match bad {
                Some(why) => Judged::Answer(Answer::Malformed(why)),
                None => Judged::Answer(Answer::Move(Box::new(msg))),
            }
        }
        StateKind::Move | StateKind::Ready => Judged::Unsolicited,
    }
}

impl Driver<'_> {
    /// The next sample on `agent`'s channel published by the agent's own process (or one
    /// that could not be received at all); samples of any other process are recorded
    /// as `impersonation` on the way and dropped.
    pub(super) fn receive_own(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
    ) -> anyhow::Result<Option<Incoming>> {
        let pid = self.procs.pid(agent);
        while let Some(incoming) = self.ipc.receive(agent) {
            match incoming.publisher_pid {
                Some(from) if Some(from) != pid => {
                    self.on_impersonation(recorder, step, agent, from)?
                }
                _ => return Ok(Some(incoming)),
            }
        }
        Ok(None)
    }

    /// Take in whatever `agent`'s channel holds between turns: none of it answers a
    /// turn. Recorded, never used.
    pub(super) fn drain(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
    ) -> anyhow::Result<()> {
        let (mut extra, mut malformed) = (0usize, Vec::new());
        while let Some(incoming) = self.receive_own(recorder, step, agent)? {
            match incoming.msg {
                Ok(msg) if msg.kind == StateKind::Echo => {}
                Ok(_) => extra += 1,
                Err(why) => {
                    let unreadable = matches!(why, MalformedState::Unreadable(_));
                    malformed.push(why.to_string());
                    if unreadable {
                        break;
                    }
                }
            }
        }
        if extra > 0 {
            recorder.note_fault(
                step,
                agent,
                FaultKind::Unsolicited,
                format!(
                    "{extra} state(s) arrived between turns (an extra move, or an answer to a turn not yet granted); ignored"
                ),
                None,
            );
        }
        if let Some(first) = malformed.first() {
            recorder.note_fault(
                step,
                agent,
                FaultKind::Malformed,
                format!(
                    "{} sample(s) between turns failed the checks, first: {first}",
                    malformed.len()
                ),
                None,
            );
        }
        Ok(())
    }

    /// Wait for the answer to `turn`, checking the agent's process every slice. A turn
    /// not rung (the agent was polling its recorder) is rung once the spin budget is spent,
    /// in case the agent stopped polling before the world came.
    pub(super) fn wait_answer(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        turn: &Turn,
    ) -> anyhow::Result<Answer> {
        let (agent, grant, granted, mut rung) =
            (turn.agent, turn.grant, turn.granted_at, turn.rung);
        let deadline = granted + self.options.turn_deadline;
        let pid = self.procs.pid(agent);
        let mut unsolicited = 0usize;
        let answer = loop {
            let mut found = None;
            while let Some(incoming) = self.receive_own(recorder, step, agent)? {
                match judge_answer(incoming, grant, step, pid) {
                    Judged::Answer(a) => {
                        found = Some(a);
                        break;
                    }
                    Judged::Unsolicited => unsolicited += 1,
                    Judged::Ignore => {}
                }
            }
            if let Some(a) = found {
                break a;
            }
            // Spinning: look again at once (yielding the core to whoever needs it) until
            // the budget is spent, then wait as usual; liveness is looked at then.
            if self.hand_over.keeps_spinning(granted) {
                std::thread::yield_now();
                continue;
            }
            if !rung {
                rung = true;
                // A ring that fails changes nothing: the agent's process is looked at next.
                if let Err(e) = self.ipc.notify_turn(agent) {
                    tracing::debug!("step {step}: ringing agent {agent}'s turn late: {e:#}");
                }
                continue;
            }
            if self.ipc.termination_requested() {
                break Answer::Interrupted;
            }
            if self.procs.poll(agent) == Exit::Exited {
                break Answer::Dead(granted.elapsed());
            }
            let now = Instant::now();
            if now >= deadline {
                break Answer::Missed;
            }
            self.ipc
                .wait_done(agent, (now + LIVENESS_SLICE).min(deadline));
        };
        if unsolicited > 0 {
            recorder.note_fault(
                step,
                agent,
                FaultKind::Unsolicited,
                format!(
                    "{unsolicited} state(s) during the turn carried no valid token for it (replayed or guessed); ignored"
                ),
                None,
            );
        }
        Ok(answer)
    }
}
