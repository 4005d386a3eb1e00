//! How late each agent's last turns were: the k-of-n rules that make an agent `hung`
//! (it missed k of its last n deadlines) or `slow` (it answered k of its last n turns
//! later than the slow bound), so that a rogue that is late only now and then, or
//! always just in time, is named and stopped as surely as one that falls silent.

use std::collections::VecDeque;

/// How one turn of an agent went, by the clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lateness {
    /// Answered within the slow bound (or answered malformed: an answer all the same).
    OnTime,
    /// Answered, but later than the slow bound.
    Slow,
    /// No answer by the deadline.
    Missed,
}

/// What an agent's last turns add up to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Verdict {
    /// Nothing to do.
    Fine,
    /// Missed `k` of the last `n` turns.
    Hung {
        /// Turns missed in the window.
        missed: usize,
    },
    /// Answered `k` of the last `n` turns later than the slow bound.
    Slow {
        /// Late answers in the window.
        late: usize,
    },
}

/// The last turns of every agent.
#[derive(Clone, Debug)]
pub(super) struct TurnHistory {
    /// `k`: how many bad turns in the window make a verdict.
    limit: usize,
    /// `n`: how many turns the window holds.
    window: usize,
    turns: Vec<VecDeque<Lateness>>,
}

impl TurnHistory {
    /// Room for `agents` agents; `limit` bad turns of the last `window` make a verdict.
    pub(super) fn new(agents: usize, limit: usize, window: usize) -> Self {
        let window = window.max(limit).max(1);
        Self {
            limit: limit.max(1),
            window,
            turns: vec![VecDeque::with_capacity(window); agents],
        }
    }

    /// Note how `agent`'s turn went, and what its window now says. A verdict empties the
    /// window (the agent is then stopped; a replacement starts afresh).
    pub(super) fn record(&mut self, agent: usize, turn: Lateness) -> Verdict {
        let Some(last) = self.turns.get_mut(agent) else {
            return Verdict::Fine;
        };
        if last.len() == self.window {
            last.pop_front();
        }
        last.push_back(turn);
        let count = |kind| last.iter().filter(|&&t| t == kind).count();
        let (missed, late) = (count(Lateness::Missed), count(Lateness::Slow));
        let verdict = if missed >= self.limit {
            Verdict::Hung { missed }
        } else if late >= self.limit {
            Verdict::Slow { late }
        } else {
            Verdict::Fine
        };
        if verdict != Verdict::Fine {
            last.clear();
        }
        verdict
    }

    /// Forget `agent`'s turns (its process died; a replacement starts afresh).
    pub(super) fn forget(&mut self, agent: usize) {
        if let Some(last) = self.turns.get_mut(agent) {
            last.clear();
        }
    }

    /// The window, in turns.
    pub(super) fn window(&self) -> usize {
        self.window
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_bad_turns_of_the_last_n_make_a_verdict_whether_in_a_row_or_not() {
        use Lateness::{Missed, OnTime, Slow};
        let mut h = TurnHistory::new(1, 3, 10);
        // Two of three late answers missed, answered in between: not yet.
        for t in [Missed, OnTime, Missed, OnTime, OnTime] {
            assert_eq!(h.record(0, t), Verdict::Fine);
        }
        // The third miss within ten turns: hung, though never two in a row.
        assert_eq!(h.record(0, Missed), Verdict::Hung { missed: 3 });
        // The window starts afresh.
        assert_eq!(h.record(0, Missed), Verdict::Fine);
        h.forget(0);
        // Two late of every three, for ever: slow at the third.
        assert_eq!(h.record(0, Slow), Verdict::Fine);
        assert_eq!(h.record(0, OnTime), Verdict::Fine);
        assert_eq!(h.record(0, Slow), Verdict::Fine);
        assert_eq!(h.record(0, Slow), Verdict::Slow { late: 3 });
        // Bad turns that fell out of the window count no more.
        let mut h = TurnHistory::new(1, 3, 4);
        for t in [Missed, Missed, OnTime, OnTime, OnTime, Missed] {
            assert_eq!(h.record(0, t), Verdict::Fine, "{t:?}");
        }
        // An agent that does not exist is never judged.
        assert_eq!(h.record(7, Missed), Verdict::Fine);
    }
}
