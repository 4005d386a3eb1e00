//! The user ids a run's sandboxed agents run as, claimed by the run for as long as it
//! runs: agents of two runs never share a user (an agent could otherwise signal, trace or
//! take the descriptors of another run's agent of the same user).
//!
//! A claim on a user id is an abstract Unix socket bound under a name made of it: the
//! kernel lets one socket at a time hold a name and frees it when its holder dies,
//! however it dies, so nothing is left behind. A run asks for `count` ids from `first`
//! (`--agent-uids`); if one of them is claimed by another run, or a live process runs
//! under it, the run takes the next `count` ids, and so on.

use std::os::linux::net::SocketAddrExt;
use std::os::unix::net::{SocketAddr, UnixListener};

/// How many blocks of ids after the first a run looks at before it gives up.
const MAX_BLOCKS_TRIED: u64 = 256;

/// Why no block of user ids could be claimed.
#[derive(Debug, thiserror::Error)]
pub enum ClaimUidsError {
    /// Every block looked at is taken, or the ids would pass the largest user id.
    #[error(
        "no {count} free user ids for the agents from {first} on ({MAX_BLOCKS_TRIED} blocks looked at: every one is claimed by another run or used by a live process); choose others with --agent-uids"
    )]
    NoneFree {
        /// The first id asked for.
        first: u32,
        /// How many.
        count: usize,
    },
}

/// The user ids of a run's agents, agent `i` as `first + i`, claimed while this lives.
#[derive(Debug)]
pub struct AgentUids {
    first: u32,
    _claims: Vec<UnixListener>,
}

impl AgentUids {
    /// Claim `count` consecutive user ids: from `first` if they are all free, else the
    /// first free block of `count` after it.
    pub fn claim(first: u32, count: usize) -> Result<Self, ClaimUidsError> {
        let in_use = crate::procfs::user_ids_in_use();
        let count_u64 = count as u64;
        for block in 0..MAX_BLOCKS_TRIED {
            let start = u64::from(first) + block * count_u64.max(1);
            let Ok(start) = u32::try_from(start) else {
                break;
            };
            if u64::from(start) + count_u64 > u64::from(u32::MAX) {
                break;
            }
            let ids = start..start + count as u32;
            if ids.clone().any(|uid| in_use.contains(&uid)) {
                continue;
            }
            let claims: Option<Vec<UnixListener>> = ids.map(claim_one).collect();
            if let Some(claims) = claims {
                return Ok(Self {
                    first: start,
                    _claims: claims,
                });
            }
        }
        Err(ClaimUidsError::NoneFree { first, count })
    }

    /// The first agent's user id.
    pub fn first(&self) -> u32 {
        self.first
    }
}

/// The claim on `uid`, if no other process holds it.
fn claim_one(uid: u32) -> Option<UnixListener> {
    let name = format!("formation-agent-uid-{uid}");
    let addr = SocketAddr::from_abstract_name(name.as_bytes()).ok()?;
    UnixListener::bind_addr(&addr).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_claims_from_the_same_first_id_get_disjoint_ids_and_a_freed_one_is_claimed_again() {
        // Far from any id a test or system uses.
        let first = 3_000_000_000 + std::process::id() % 1000 * 100;
        let a = AgentUids::claim(first, 5).expect("a first claim");
        let b = AgentUids::claim(first, 5).expect("a second claim");
        assert_eq!(a.first(), first);
        assert!(
            b.first() >= first + 5,
            "{} overlaps {first}..{}",
            b.first(),
            first + 5
        );
        drop(a);
        // Freed when the last copy of its sockets closes: a process this test binary
        // forks meanwhile (other tests start processes) holds copies until it execs.
        let mut again = None;
        wire::poll_until(std::time::Duration::from_secs(10), || {
            again = AgentUids::claim(first, 5)
                .ok()
                .filter(|c| c.first() == first);
            again.is_some()
        });
        assert!(again.is_some(), "the ids from {first} were never freed");
        drop(b);
    }

    #[test]
    fn the_ids_of_a_live_process_are_skipped() {
        // This process's own user id is in use (by this process).
        // SAFETY: getuid(2) cannot fail.
        let own = unsafe { libc::getuid() };
        let claimed = AgentUids::claim(own, 1).expect("a claim");
        assert_ne!(claimed.first(), own);
    }
}
