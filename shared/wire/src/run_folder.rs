//! A run's files on the RAM file system: its private folder, and the segments iceoryx2
//! puts beside it in /dev/shm.

use crate::prefix::is_valid_prefix;

/// The folder where run `prefix` keeps iceoryx2's files (node and service descriptions,
/// event sockets): `/dev/shm/<prefix>iox2`, on the RAM file system, or `None` (iceoryx2's
/// default, `/tmp/iceoryx2`) where there is no `/dev/shm`. iceoryx2 syncs every such file
/// to disk as it creates it, about 5 N of them per run: on a disk that makes start-up
/// several times slower (6 s instead of 1.8 s for 200 agents here). A folder per run
/// also means that removing the run removes the folder ([`remove_run_root`]).
/// An invalid prefix ([`ipc_config`](crate::ipc_config) refuses it) has no folder.
pub fn run_root(prefix: &str) -> Option<std::path::PathBuf> {
    let shm = std::path::Path::new("/dev/shm");
    (is_valid_prefix(prefix) && shm.is_dir()).then(|| shm.join(format!("{prefix}iox2")))
}

/// Remove run `prefix`'s folder ([`run_root`]) once nothing of the run is left in it but
/// empty folders; a no-op where there is no such folder.
pub fn remove_run_root(prefix: &str) -> std::io::Result<()> {
    match run_root(prefix) {
        Some(root) if root.exists() => std::fs::remove_dir_all(root),
        _ => Ok(()),
    }
}

/// Why a run's folder or one of its files in /dev/shm cannot be trusted.
#[derive(Debug, thiserror::Error)]
pub enum RunFilesError {
    /// The run folder does not exist.
    #[error("{} does not exist (no such run; the coordinator starts agents)", .0.display())]
    Missing(std::path::PathBuf),
    /// The coordinator found the folder of its new run already there.
    #[error(
        "{} already exists: this run did not make it, so it will not use it (nor delete it)",
        .0.display()
    )]
    Exists(std::path::PathBuf),
    /// Not a directory, or a file that is not a regular file (e.g. a symbolic link).
    #[error("{} is not what the run made (a symbolic link?): refusing it", .0.display())]
    WrongType(std::path::PathBuf),
    /// Owned by another user than this process's effective user.
    #[error(
        "{} belongs to user {owner}, not to this process's user {euid}: refusing it",
        path.display()
    )]
    Owner {
        /// The folder or file.
        path: std::path::PathBuf,
        /// Its owner.
        owner: u32,
        /// This process's effective user id.
        euid: u32,
    },
    /// A run folder whose mode is not exactly 0700.
    #[error(
        "{} has mode {mode:04o}, not 0700 (other users could reach the run's files): refusing it",
        path.display()
    )]
    Mode {
        /// The folder.
        path: std::path::PathBuf,
        /// Its permission bits.
        mode: u32,
    },
    /// The file system refused an operation.
    #[error("{}: {source}", path.display())]
    Io {
        /// The folder or file.
        path: std::path::PathBuf,
        /// What failed.
        source: std::io::Error,
    },
}

/// This process's effective user id.
pub fn effective_uid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// What is wrong with a file of a run's private folder, by its metadata (read from the
/// opened file, not from its path): not a regular file, another user's, or readable or
/// writable by anyone but its owner (a mode other than 0600). `None`: nothing.
pub fn private_file_problem(meta: &std::fs::Metadata) -> Option<String> {
    use std::os::unix::fs::MetadataExt;
    if !meta.file_type().is_file() {
        return Some("not a regular file".into());
    }
    if meta.uid() != effective_uid() {
        return Some(format!("owned by user {}", meta.uid()));
    }
    let mode = meta.mode() & 0o7777;
    (mode != 0o600).then(|| format!("mode {mode:04o}, not 0600"))
}

/// Check that `path` is a run folder no other user can reach: a directory, not a symbolic
/// link (lstat), owned by this process's effective user, mode exactly 0700. Every agent
/// checks it before it opens anything. Checking the path and then using it is safe here:
/// /dev/shm is sticky, so only the folder's owner (this user) can rename or remove it.
pub fn check_run_root(path: &std::path::Path) -> Result<(), RunFilesError> {
    use std::os::unix::fs::MetadataExt;
    let meta = match std::fs::symlink_metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(RunFilesError::Missing(path.to_path_buf()));
        }
        Err(source) => {
            return Err(RunFilesError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    if !meta.file_type().is_dir() {
        return Err(RunFilesError::WrongType(path.to_path_buf()));
    }
    let euid = effective_uid();
    if meta.uid() != euid {
        return Err(RunFilesError::Owner {
            path: path.to_path_buf(),
            owner: meta.uid(),
            euid,
        });
    }
    let mode = meta.mode() & 0o7777;
    if mode != 0o700 {
        return Err(RunFilesError::Mode {
            path: path.to_path_buf(),
            mode,
        });
    }
    Ok(())
}

/// The run folder ([`run_root`]) as the coordinator makes it, before anything else of the
/// run (before its iceoryx2 node): exclusively, so a folder that is already there (made by
/// someone else, or a leftover) is refused and left alone; mode 0700; then checked
/// ([`check_run_root`]). Dropping it removes the folder and everything in it (removing
/// it earlier with [`remove_run_root`] is fine). Where there is no /dev/shm there is no
/// folder (iceoryx2's default root is used, shared with other users).
#[derive(Debug)]
pub struct RunRoot {
    path: Option<std::path::PathBuf>,
}

impl RunRoot {
    /// Make run `prefix`'s folder.
    pub fn create(prefix: &str) -> Result<Self, RunFilesError> {
        use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
        let Some(path) = run_root(prefix) else {
            return Ok(Self { path: None });
        };
        if let Err(source) = std::fs::DirBuilder::new().mode(0o700).create(&path) {
            return Err(if source.kind() == std::io::ErrorKind::AlreadyExists {
                RunFilesError::Exists(path)
            } else {
                RunFilesError::Io { path, source }
            });
        }
        // Ours from here on: dropping `root` removes it, whatever fails below.
        let root = Self {
            path: Some(path.clone()),
        };
        // The umask may have taken bits off 0700.
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o700)).map_err(
            |source| RunFilesError::Io {
                path: path.clone(),
                source,
            },
        )?;
        check_run_root(&path)?;
        Ok(root)
    }

    /// The folder (`None` where there is no /dev/shm).
    pub fn path(&self) -> Option<&std::path::Path> {
        self.path.as_deref()
    }
}

impl Drop for RunRoot {
    fn drop(&mut self) {
        if let Some(path) = &self.path
            && let Err(e) = std::fs::remove_dir_all(path)
            && e.kind() != std::io::ErrorKind::NotFound
        {
            tracing::warn!("removing the run folder {}: {e}", path.display());
        }
    }
}

/// The files of run `prefix` directly in /dev/shm (not in its folder), with their
/// metadata (lstat): iceoryx2's shared-memory segments, which `shm_open` puts there
/// whatever the configured root.
fn run_files_in_shm(prefix: &str) -> Vec<(std::path::PathBuf, std::fs::Metadata)> {
    let root = run_root(prefix);
    let Ok(entries) = std::fs::read_dir("/dev/shm") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .filter(|e| Some(e.path()) != root)
        .filter_map(|e| Some((e.path(), std::fs::symlink_metadata(e.path()).ok()?)))
        .collect()
}

/// Take group and other permissions off every file of run `prefix` directly in /dev/shm
/// (not in its folder: the segments `shm_open` puts there); returns how many were
/// changed. iceoryx2 0.10 makes the
/// management segment (`<prefix>node.<version>.global_mgmt`) there readable and writable
/// by everyone (`enable_global_access`, 0666); its other segments are 0600 already. Call
/// it right after the coordinator's node is made (that makes the segment), before any
/// agent starts. A file of the run that is not this user's, or not a regular file, is an
/// error: someone else made it.
///
/// Limit: between iceoryx2's `fchmod(0666)` and this call, a process of another user that
/// watches /dev/shm could open the segment and keep it open. It could then change the
/// counter iceoryx2 numbers the run's nodes with (so that an agent's node might fail to
/// start: a denial of service), but not read or write the run's data: the services'
/// segments are 0600 from their creation.
pub fn make_run_files_private(prefix: &str) -> Result<usize, RunFilesError> {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let euid = effective_uid();
    let mut changed = 0;
    for (path, meta) in run_files_in_shm(prefix) {
        if meta.uid() != euid {
            return Err(RunFilesError::Owner {
                path,
                owner: meta.uid(),
                euid,
            });
        }
        if !meta.file_type().is_file() {
            return Err(RunFilesError::WrongType(path));
        }
        let mode = meta.mode() & 0o7777;
        if mode & 0o077 != 0 {
            // By path, not by descriptor: the file is this user's in the sticky /dev/shm,
            // so no one else can swap it meanwhile.
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode & 0o700))
                .map_err(|source| RunFilesError::Io {
                    path: path.clone(),
                    source,
                })?;
            changed += 1;
        }
    }
    Ok(changed)
}

/// Remove this user's regular files of run `prefix` left directly in /dev/shm (what
/// iceoryx2's dead-node cleanup can miss, e.g. a segment of a process killed while it was
/// connecting); returns how many were removed. Call it once every process of the run has
/// exited: the prefix is the run's alone.
pub fn remove_run_files_in_shm(prefix: &str) -> usize {
    use std::os::unix::fs::MetadataExt;
    let euid = effective_uid();
    run_files_in_shm(prefix)
        .into_iter()
        .filter(|(_, meta)| meta.uid() == euid && meta.file_type().is_file())
        .filter(|(path, _)| std::fs::remove_file(path).is_ok())
        .count()
}

/// Remove the files of run `prefix` in /dev/shm that a process killed while it made
/// them left empty (size zero) and that no process holds open any more; returns how many
/// were removed.
///
/// iceoryx2 0.10 creates a segment with `shm_open` and only then sizes it. A process
/// killed between the two leaves a file of size zero, and iceoryx2's dead-node cleanup,
/// opening that file to detach the dead port, waits for it to be sized without a
/// deadline: the cleaner hangs. A live process making a segment holds it open from
/// `shm_open` on, so an empty file no process holds open can only be abandoned. Call it
/// once the processes that died are gone (not merely dying: an exiting process closes its
/// files one by one).
pub fn remove_abandoned_shm_files(prefix: &str) -> usize {
    let empty: Vec<std::path::PathBuf> = run_files_in_shm(prefix)
        .into_iter()
        .filter(|(_, meta)| meta.file_type().is_file() && meta.len() == 0)
        .map(|(path, _)| path)
        .collect();
    if empty.is_empty() {
        return 0;
    }
    let open = files_held_open(&empty);
    empty
        .iter()
        .filter(|path| !open.contains(*path))
        .filter(|path| std::fs::remove_file(path).is_ok())
        .count()
}

/// Which of `paths` some process on this machine holds open (by its /proc/PID/fd links;
/// those of processes this user may not read are not seen).
fn files_held_open(paths: &[std::path::PathBuf]) -> Vec<std::path::PathBuf> {
    let mut open = Vec::new();
    let Ok(processes) = std::fs::read_dir("/proc") else {
        return open;
    };
    for process in processes.flatten() {
        if !process
            .file_name()
            .to_string_lossy()
            .bytes()
            .all(|b| b.is_ascii_digit())
        {
            continue;
        }
        let Ok(fds) = std::fs::read_dir(process.path().join("fd")) else {
            continue;
        };
        for fd in fds.flatten() {
            if let Ok(target) = std::fs::read_link(fd.path())
                && paths.contains(&target)
                && !open.contains(&target)
            {
                open.push(target);
            }
        }
    }
    open
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RunPrefix;

    /// A fresh prefix whose folder and files no run uses, for the file tests below.
    fn test_prefix() -> Option<RunPrefix> {
        let p = RunPrefix::new_random().expect("OS random source");
        run_root(p.as_str()).map(|_| p)
    }

    #[test]
    fn only_empty_files_no_process_holds_open_are_abandoned() {
        let Some(prefix) = test_prefix() else { return };
        let shm = std::path::Path::new("/dev/shm");
        let held = shm.join(format!("{prefix}held.connection"));
        let left = shm.join(format!("{prefix}left.connection"));
        let sized = shm.join(format!("{prefix}sized.connection"));
        let holder = std::fs::File::create(&held).expect("an empty file, held open");
        drop(std::fs::File::create(&left).expect("an empty file, closed"));
        std::fs::write(&sized, b"made").expect("a sized file");
        assert_eq!(remove_abandoned_shm_files(prefix.as_str()), 1);
        assert!(held.exists(), "a file being made is left alone");
        assert!(!left.exists(), "an abandoned file is removed");
        assert!(sized.exists(), "a finished segment is left alone");
        drop(holder);
        assert_eq!(remove_abandoned_shm_files(prefix.as_str()), 1);
        assert!(!held.exists(), "closed, it is abandoned too");
        std::fs::remove_file(&sized).expect("clean up");
    }

    #[test]
    fn a_new_run_folder_is_private_and_goes_with_its_guard() {
        use std::os::unix::fs::MetadataExt;
        let Some(prefix) = test_prefix() else { return };
        let root = RunRoot::create(prefix.as_str()).expect("run folder");
        let path = root.path().expect("a folder on /dev/shm").to_path_buf();
        let meta = std::fs::symlink_metadata(&path).expect("made");
        assert!(meta.is_dir());
        assert_eq!(meta.mode() & 0o7777, 0o700);
        assert_eq!(meta.uid(), effective_uid());
        check_run_root(&path).expect("passes its own check");
        std::fs::write(path.join("inside"), b"x").expect("usable");
        drop(root);
        assert!(!path.exists(), "the guard removes the folder");
    }

    #[test]
    fn a_run_folder_that_already_exists_is_refused_and_left_alone() {
        use std::os::unix::fs::DirBuilderExt;
        let Some(prefix) = test_prefix() else { return };
        let path = run_root(prefix.as_str()).expect("a folder on /dev/shm");
        std::fs::DirBuilder::new()
            .mode(0o700)
            .create(&path)
            .expect("squat");
        std::fs::write(path.join("theirs"), b"x").expect("a file in it");
        let err = RunRoot::create(prefix.as_str()).expect_err("an existing folder");
        assert!(matches!(err, RunFilesError::Exists(_)), "{err:?}");
        assert!(
            err.to_string().contains(&path.display().to_string()),
            "{err}"
        );
        assert!(path.join("theirs").exists(), "nothing of it deleted");
        std::fs::remove_dir_all(&path).expect("clean up");
    }

    #[test]
    fn a_run_folder_others_could_reach_or_that_is_a_link_is_refused() {
        use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
        let Some(prefix) = test_prefix() else { return };
        let path = run_root(prefix.as_str()).expect("a folder on /dev/shm");
        assert!(matches!(
            check_run_root(&path),
            Err(RunFilesError::Missing(_))
        ));
        std::fs::DirBuilder::new()
            .mode(0o700)
            .create(&path)
            .expect("folder");
        for mode in [0o777, 0o750, 0o701, 0o1700, 0o500] {
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).expect("chmod");
            let err = check_run_root(&path).expect_err("not 0700");
            assert!(
                matches!(err, RunFilesError::Mode { mode: m, .. } if m == mode),
                "{err:?}"
            );
            assert!(err.to_string().contains(&path.display().to_string()));
        }
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o700)).expect("chmod");
        check_run_root(&path).expect("0700");
        // Another user's folder, 0700 or not, is refused (only root can make one here).
        if effective_uid() == 0 {
            std::os::unix::fs::chown(&path, Some(65534), None).expect("chown");
            let err = check_run_root(&path).expect_err("not ours");
            assert!(
                matches!(
                    err,
                    RunFilesError::Owner {
                        owner: 65534,
                        euid: 0,
                        ..
                    }
                ),
                "{err:?}"
            );
            std::os::unix::fs::chown(&path, Some(0), None).expect("chown back");
        }
        // A link to a good folder is still refused: it is not the folder.
        let link = std::path::PathBuf::from(format!("{}link", path.display()));
        std::os::unix::fs::symlink(&path, &link).expect("symlink");
        assert!(matches!(
            check_run_root(&link),
            Err(RunFilesError::WrongType(_))
        ));
        std::fs::remove_file(&link).expect("clean up");
        std::fs::remove_dir_all(&path).expect("clean up");
    }

    #[test]
    fn the_run_files_in_dev_shm_are_made_private_and_foreign_ones_refused() {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let Some(prefix) = test_prefix() else { return };
        let mgmt = std::path::PathBuf::from(format!("/dev/shm/{prefix}node.global_mgmt"));
        let data = std::path::PathBuf::from(format!("/dev/shm/{prefix}data"));
        for (file, mode) in [(&mgmt, 0o666), (&data, 0o600)] {
            std::fs::write(file, b"x").expect("file");
            std::fs::set_permissions(file, std::fs::Permissions::from_mode(mode)).expect("chmod");
        }
        assert_eq!(run_files_in_shm(prefix.as_str()).len(), 2);
        assert_eq!(make_run_files_private(prefix.as_str()).expect("private"), 1);
        for file in [&mgmt, &data] {
            let mode = std::fs::metadata(file).expect("file").mode();
            assert_eq!(mode & 0o777, 0o600, "{}", file.display());
        }
        // A symbolic link among them is not followed but refused.
        let link = std::path::PathBuf::from(format!("/dev/shm/{prefix}link"));
        std::os::unix::fs::symlink(&data, &link).expect("symlink");
        assert!(matches!(
            make_run_files_private(prefix.as_str()),
            Err(RunFilesError::WrongType(_))
        ));
        for file in [&mgmt, &data, &link] {
            std::fs::remove_file(file).expect("clean up");
        }
    }
}
