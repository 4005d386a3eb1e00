//! The mission (the scenario as run) handed to the agents as a file in the run's private
//! folder, not over a shared-memory service: it is read once, at start-up, and a service
//! per agent would hold five open files per agent in the coordinator for the whole run
//! (the coordinator's open-file limit is what bounds the number of agents).
//!
//! The file is the scenario's resolved form as JSON ([`Scenario::to_mission_json`]),
//! which loads back to the same scenario bit for bit; it is written under a temporary
//! name and renamed, mode 0600, in the folder only this user can reach
//! ([`check_run_root`]), before any agent starts. An agent reads it with the same checks
//! as a file a user hands in: regular file, owned by this user, mode 0600, at most
//! [`MAX_MISSION_BYTES`], and its SHA-256 digest the one its coordinator handed it. Then
//! it is the very text the coordinator validated, so each value is checked but not the
//! rules relating the parts ([`Checks::Values`]: at 1000 agents, every agent parsing
//! the TOML form and checking the slot pairs was the largest share of the start-up).

use std::io::Read as _;
use std::path::{Path, PathBuf};

use shared::world::scenario::{Checks, Scenario, ScenarioError};

use crate::prefix::{PrefixError, is_valid_prefix};
use crate::run_folder::{RunFilesError, check_run_root, private_file_problem, run_root};

/// The mission file's name in the run folder.
pub const MISSION_FILE_NAME: &str = "mission.json";

/// Largest mission file an agent reads: far more than the largest scenario the
/// capacities allow (16 384 obstacles and 1 024 agents take about 1.5 MB).
pub const MAX_MISSION_BYTES: u64 = 16 << 20;

/// Why the mission file cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum MissionFileError {
    /// The run prefix is not one a run can have.
    #[error(transparent)]
    Prefix(#[from] PrefixError),
    /// There is no private run folder (no /dev/shm on this machine).
    #[error("run {0}: no private run folder (/dev/shm) to hand the mission over in")]
    NoRunFolder(String),
    /// The run folder is not what the coordinator made.
    #[error(transparent)]
    Folder(#[from] RunFilesError),
    /// The scenario has no resolved form (only a scenario built by hand can meet this).
    #[error("the scenario cannot be written as a file: {0}")]
    NotRepresentable(String),
    /// The file is not a regular file of this user with mode 0600, or is too large.
    #[error("{}: {why}: refusing it", path.display())]
    Untrusted {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
    },
    /// The file system refused an operation.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// The file is not a valid scenario.
    #[error("the mission file is not a valid scenario: {0}")]
    Invalid(#[from] ScenarioError),
    /// The file is not the one the coordinator wrote: its digest differs from the one the
    /// coordinator handed this process.
    #[error("{}: changed since the coordinator wrote it (SHA-256 {found}, not {expected}): refusing it", path.display())]
    Changed {
        /// The file.
        path: PathBuf,
        /// The digest the coordinator handed over.
        expected: MissionDigest,
        /// The file's.
        found: MissionDigest,
    },
}

/// The SHA-256 digest of a mission file's bytes, handed by the coordinator to every
/// process it starts (`--mission-sha256 HEX`), which refuses a file that does not match.
///
/// ```
/// use wire::MissionDigest;
/// let d = MissionDigest::of(b"abc");
/// assert_eq!(d.to_string(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
/// assert_eq!(d.to_string().parse::<MissionDigest>(), Ok(d));
/// assert!("ba78".parse::<MissionDigest>().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MissionDigest([u8; 32]);

impl MissionDigest {
    /// The digest of `bytes`.
    pub fn of(bytes: &[u8]) -> Self {
        use sha2::Digest as _;
        Self(sha2::Sha256::digest(bytes).into())
    }
}

impl std::fmt::Display for MissionDigest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

/// A digest that is not 64 hexadecimal digits.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0:?} is not a SHA-256 digest (64 hexadecimal digits)")]
pub struct BadMissionDigest(pub String);

impl std::str::FromStr for MissionDigest {
    type Err = BadMissionDigest;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || BadMissionDigest(s.chars().take(80).collect());
        if s.len() != 64 || !s.is_ascii() {
            return Err(bad());
        }
        let mut out = [0u8; 32];
        for (i, byte) in out.iter_mut().enumerate() {
            *byte = u8::from_str_radix(&s[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
        }
        Ok(Self(out))
    }
}

/// The mission file of run `prefix` (`None` without a run folder).
pub fn mission_path(prefix: &str) -> Option<PathBuf> {
    run_root(prefix).map(|root| root.join(MISSION_FILE_NAME))
}

/// The mission file of run `prefix`, in its checked private folder ([`check_run_root`]);
/// an invalid prefix is refused by name, not taken for a missing folder.
fn private_mission_path(prefix: &str) -> Result<PathBuf, MissionFileError> {
    if !is_valid_prefix(prefix) {
        return Err(PrefixError::Invalid(prefix.to_string()).into());
    }
    let path = mission_path(prefix).ok_or_else(|| MissionFileError::NoRunFolder(prefix.into()))?;
    if let Some(folder) = path.parent() {
        check_run_root(folder)?;
    }
    Ok(path)
}

/// Write `scenario` as run `prefix`'s mission file (the coordinator, before any agent
/// starts); returns its digest, for the processes that will read it.
pub fn write_mission(prefix: &str, scenario: &Scenario) -> Result<MissionDigest, MissionFileError> {
    use std::io::Write as _;
    use std::os::unix::fs::OpenOptionsExt;
    let path = private_mission_path(prefix)?;
    let text = scenario
        .to_mission_json()
        .map_err(|e| MissionFileError::NotRepresentable(e.to_string()))?;
    let temporary = path.with_extension("json.tmp");
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| MissionFileError::Io { path, source }
    };
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .open(&temporary)
        .map_err(io(&temporary))?;
    file.write_all(text.as_bytes()).map_err(io(&temporary))?;
    drop(file);
    std::fs::rename(&temporary, &path).map_err(io(&path))?;
    Ok(MissionDigest::of(text.as_bytes()))
}

/// Read run `prefix`'s mission file (an agent, at start-up) into a [`Scenario`],
/// refusing it if its digest is not `expected` (when given).
///
/// A file whose digest matches is the text the coordinator validated whole before it
/// wrote it: each value is checked but not the O(n^2) rules relating the parts
/// ([`Checks::Values`]). Without a digest it is validated whole.
pub fn read_mission(
    prefix: &str,
    expected: Option<MissionDigest>,
) -> Result<Scenario, MissionFileError> {
    read_mission_text(prefix, expected)?.parse()
}

/// Run `prefix`'s mission file as read: its text, and whether its digest was checked.
#[derive(Clone, Debug)]
pub struct MissionText {
    /// The file's path, named in errors.
    pub path: PathBuf,
    /// The file's text, the scenario's resolved form as JSON.
    pub text: String,
    /// Whether the text's digest matched the one the coordinator handed over (then the
    /// coordinator validated this very text).
    pub digest_checked: bool,
}

impl MissionText {
    /// The scenario: its values checked when the digest was ([`Checks::Values`]),
    /// validated whole otherwise.
    pub fn parse(&self) -> Result<Scenario, MissionFileError> {
        let checks = if self.digest_checked {
            Checks::Values
        } else {
            Checks::All
        };
        let file = self.path.display().to_string();
        Ok(Scenario::from_mission_json(&self.text, &file, checks)?)
    }
}

/// Read run `prefix`'s mission file, refusing it if it is not a regular file of this
/// user's with mode 0600, is too large, or its digest is not `expected` (when given).
pub fn read_mission_text(
    prefix: &str,
    expected: Option<MissionDigest>,
) -> Result<MissionText, MissionFileError> {
    use shared::input_file::{Links, ReadInputError, open_input};
    let path = private_mission_path(prefix)?;
    let untrusted = |why: String| MissionFileError::Untrusted {
        path: path.clone(),
        why,
    };
    let io = |source| MissionFileError::Io {
        path: path.clone(),
        source,
    };
    // Opened without following a link or blocking on a FIFO (a trusted agent of this
    // user could put one there), a regular file within the bound; then this user's, 0600.
    let mut file = open_input(&path, MAX_MISSION_BYTES, Links::Refuse).map_err(|e| match e {
        ReadInputError::Io(source) => io(source),
        // As open(2) with O_NOFOLLOW says it.
        ReadInputError::SymbolicLink => io(std::io::Error::from_raw_os_error(libc::ELOOP)),
        refused => untrusted(refused.to_string()),
    })?;
    let meta = file.get_ref().metadata().map_err(io)?;
    if let Some(why) = private_file_problem(&meta) {
        return Err(untrusted(why));
    }
    let mut text = String::new();
    file.read_to_string(&mut text).map_err(io)?;
    if let Some(expected) = expected {
        let found = MissionDigest::of(text.as_bytes());
        if found != expected {
            return Err(MissionFileError::Changed {
                path,
                expected,
                found,
            });
        }
    }
    Ok(MissionText {
        path,
        text,
        digest_checked: expected.is_some(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{RunPrefix, RunRoot};

    #[test]
    fn a_mission_round_trips_the_scenario_exactly_and_a_tampered_file_is_refused() {
        let prefix = RunPrefix::new_random().expect("prefix").to_string();
        let root = RunRoot::create(&prefix).expect("run folder");
        if root.path().is_none() {
            return; // no /dev/shm: nowhere to hand a mission over
        }
        let mut scenario = Scenario::paper();
        scenario.agents[1].max_step_m = Some(0.25);
        let digest = write_mission(&prefix, &scenario).expect("written");
        let path = mission_path(&prefix).expect("a run folder");
        assert_eq!(read_mission(&prefix, Some(digest)).expect("read"), scenario);
        // A file of another digest is refused, naming both.
        let other = MissionDigest::of(b"another mission");
        assert!(matches!(
            read_mission(&prefix, Some(other)),
            Err(MissionFileError::Changed { expected, found, .. }) if expected == other && found == digest
        ));
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).expect("chmod");
        assert!(matches!(
            read_mission(&prefix, None),
            Err(MissionFileError::Untrusted { .. })
        ));
        std::fs::remove_file(&path).expect("rm");
        std::os::unix::fs::symlink("/etc/passwd", &path).expect("symlink");
        assert!(matches!(
            read_mission(&prefix, None),
            Err(MissionFileError::Io { .. })
        ));
        std::fs::remove_file(&path).expect("rm");
        std::fs::write(&path, "name = 1").expect("write");
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).expect("chmod");
        assert!(matches!(
            read_mission(&prefix, None),
            Err(MissionFileError::Invalid(_))
        ));
    }
}
