//! The run prefix: every resource of a run is named after it.

/// Why a run prefix cannot name iceoryx2 resources.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PrefixError {
    /// The prefix is not a valid file name, or longer than [`MAX_PREFIX_LEN`].
    #[error("run prefix {0:?} must be 1 to 24 characters of [A-Za-z0-9_-]")]
    Invalid(String),
    /// The OS random source failed to give the random part of a new prefix.
    #[error("no random run prefix: the OS random source failed: {0}")]
    Random(String),
}

/// Longest run prefix accepted: socket paths built from it must fit in 108 bytes.
pub const MAX_PREFIX_LEN: usize = 24;

/// A prefix is 1 to [`MAX_PREFIX_LEN`] ASCII letters, digits, `_` or `-` (a file name
/// that cannot leave its folder).
pub(crate) fn is_valid_prefix(prefix: &str) -> bool {
    !prefix.is_empty()
        && prefix.len() <= MAX_PREFIX_LEN
        && prefix
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
}

/// Environment variable the coordinator sets on every agent process: the run's prefix.
/// Whatever an agent starts inherits it (unless it clears its environment), so at the end
/// of the run the coordinator finds, kills and reaps every process the run left behind.
pub const RUN_ENV: &str = "FORMATION_RUN";

/// Environment variable the coordinator sets on every agent process it starts: its own
/// process id. The agent asks to be killed with its parent, then exits at once if its
/// parent is already another process (the coordinator died before the agent's first
/// instruction). Done in the agent rather than between fork and exec, so that the
/// coordinator starts agents with `posix_spawn` (no copy of its page tables: with 1000
/// agents' shared memory mapped, a fork took about 40 ms).
pub const PARENT_ENV: &str = "FORMATION_COORDINATOR_PID";

/// A run prefix: `fc<coordinator pid>x<random hex>_`, the one place that writes and reads
/// the format. The pid tells a crashed run's leftovers (its coordinator is gone) from a
/// live run's; the random part, from the OS random source, makes the names of a run's
/// files unpredictable, so no other local user can make them first (squat the run folder
/// or the management segment before the coordinator does).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunPrefix {
    text: String,
    pid: u32,
}

impl RunPrefix {
    /// Start of every run prefix.
    const STEM: &'static str = "fc";
    /// Most hex digits in the random part (64 bits); fewer when the pid is long, so that
    /// the prefix fits in [`MAX_PREFIX_LEN`]: at least 10 (40 bits) for any `u32` pid,
    /// 13 or more for the usual pids of up to 7 digits.
    const MAX_RANDOM_DIGITS: usize = 16;
    /// Most digits of a `u32` pid.
    const MAX_PID_DIGITS: usize = 10;

    /// A new prefix for a run coordinated by this process.
    pub fn new_random() -> Result<Self, PrefixError> {
        use rand::TryRngCore;
        let mut bytes = [0u8; 8];
        rand::rngs::OsRng
            .try_fill_bytes(&mut bytes)
            .map_err(|e| PrefixError::Random(e.to_string()))?;
        Ok(Self::with_random(
            std::process::id(),
            u64::from_le_bytes(bytes),
        ))
    }

    /// The start of every prefix of the runs coordinated by process `pid`,
    /// `fc<pid>x`: it finds their files and their processes.
    pub fn head(pid: u32) -> String {
        format!("{}{pid}x", Self::STEM)
    }

    fn with_random(pid: u32, random: u64) -> Self {
        let head = Self::head(pid);
        let digits = (MAX_PREFIX_LEN - 1 - head.len()).min(Self::MAX_RANDOM_DIGITS);
        let hex = format!("{random:016x}");
        Self {
            text: format!("{head}{}_", &hex[..digits]),
            pid,
        }
    }

    /// The run prefix that `name` (a file or folder of a run, `<prefix><anything>`) starts
    /// with, if any. Also reads the prefixes of earlier versions, whose random part was a
    /// decimal counter, so their leftovers are still cleaned.
    pub fn parse(name: &str) -> Option<Self> {
        let rest = name.strip_prefix(Self::STEM)?;
        let pid_digits = rest.bytes().take_while(u8::is_ascii_digit).count();
        let (pid, rest) = rest.split_at(pid_digits);
        let rest = rest.strip_prefix('x')?;
        let hex_digits = rest
            .bytes()
            .take_while(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(b))
            .count();
        if !(1..=Self::MAX_PID_DIGITS).contains(&pid_digits)
            || !(1..=Self::MAX_RANDOM_DIGITS).contains(&hex_digits)
            || rest.as_bytes().get(hex_digits) != Some(&b'_')
        {
            return None;
        }
        let pid = pid.parse::<u32>().ok().filter(|&p| p > 0)?;
        // Every byte counted is ASCII, so `len` is a character boundary.
        let len = Self::STEM.len() + pid_digits + 1 + hex_digits + 1;
        (len <= MAX_PREFIX_LEN).then(|| Self {
            text: name[..len].to_string(),
            pid,
        })
    }

    /// The process id of the run's coordinator.
    pub fn pid(&self) -> u32 {
        self.pid
    }

    /// The prefix itself.
    pub fn as_str(&self) -> &str {
        &self.text
    }
}

impl std::fmt::Display for RunPrefix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Role, ipc_config};

    #[test]
    fn two_run_prefixes_differ_in_their_random_part_and_parse_back_to_the_pid() {
        let a = RunPrefix::new_random().expect("OS random source");
        let b = RunPrefix::new_random().expect("OS random source");
        let head = format!("fc{}x", std::process::id());
        assert_eq!(RunPrefix::head(std::process::id()), head);
        let random_part = |p: &RunPrefix| {
            let s = p.as_str();
            s[head.len()..s.len() - 1].to_string()
        };
        for p in [&a, &b] {
            assert!(p.as_str().starts_with(&head), "{p}");
            assert!(p.as_str().ends_with('_'), "{p}");
            assert!(p.as_str().len() <= MAX_PREFIX_LEN, "{p}");
            assert!(ipc_config(p.as_str(), Role::Coordinator).is_ok(), "{p}");
            assert_eq!(p.pid(), std::process::id());
            assert_eq!(RunPrefix::parse(p.as_str()).as_ref(), Some(p));
            let file = format!("{p}node.0_10_0.global_mgmt");
            assert_eq!(RunPrefix::parse(&file).as_ref(), Some(p), "{file}");
            // At least 10 hex digits (40 bits), 13 for the usual pids of up to 7 digits.
            assert!(random_part(p).len() >= 10, "{p}");
        }
        assert_ne!(random_part(&a), random_part(&b));
        // The longest pid still leaves 10 random digits within the limit.
        let long = RunPrefix::with_random(u32::MAX, 0x0123_4567_89ab_cdef);
        assert_eq!(long.as_str(), "fc4294967295x0123456789_");
        assert_eq!(RunPrefix::parse(long.as_str()), Some(long));
        // A prefix of an earlier version (a decimal counter) is still recognised.
        let old = RunPrefix::parse("fc123x4_iox2").expect("old format");
        assert_eq!((old.as_str(), old.pid()), ("fc123x4_", 123));
        for bad in [
            "",
            "fc",
            "fcx1_",
            "fc12x_",
            "fc12x12",
            "fc0x1_",
            "fc12xg_",
            "fc12X1_",
            "fc12x0123456789abcdef0_",
            "fc12345678901x1_",
            "xfc12x1_",
            "fc4294967296x1_",
        ] {
            assert_eq!(RunPrefix::parse(bad), None, "{bad:?}");
        }
    }
}
