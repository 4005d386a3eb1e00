//! Output folders (`run --out`, `compare --out`): checked before anything runs, written
//! into a temporary sibling folder and renamed into place whole ([`OutDir`], [`Staging`]).

use std::path::{Path, PathBuf};

use anyhow::Context;

use crate::error::CliError;

/// An output folder (`run --out`, `compare --out`), checked before anything runs.
///
/// A folder *holds something* when it exists and is not an empty folder: a previous run,
/// an unrelated folder of the user's, a file or a symbolic link. Such a path is refused
/// (exit code 2, nothing touched) unless `--force` is given; with `--force` it is replaced
/// whole. Either way the new outputs are written into a fresh temporary sibling folder
/// ([`Staging`]) and renamed into place when complete, so no file of an older run
/// survives beside the new ones and the folder is never seen half-written.
#[derive(Debug, Clone)]
pub struct OutDir {
    dir: PathBuf,
    force: bool,
}

impl OutDir {
    /// Check `dir` (creating nothing): refuse, as a usage error, a path that holds
    /// something unless `force`, a path with no folder name of its own (`.`, `..`, `/`),
    /// a folder that contains the current directory, and a path below a file.
    pub fn check(dir: PathBuf, force: bool) -> Result<Self, CliError> {
        let shown = dir.display().to_string();
        let usage = |reason: &str| CliError::Usage(format!("{shown}: {reason}"));
        if dir.file_name().is_none() {
            return Err(usage("not a folder name to write a run into"));
        }
        match std::fs::symlink_metadata(&dir) {
            Ok(meta) => {
                let empty_folder = meta.is_dir()
                    && std::fs::read_dir(&dir)
                        .map_err(|e| usage(&e.to_string()))?
                        .next()
                        .is_none();
                if !empty_folder && !force {
                    let what = if meta.is_dir() {
                        "folder is not empty"
                    } else {
                        "exists and is not a folder"
                    };
                    return Err(usage(&format!(
                        "{what}; pass --force to replace it whole, or choose another --out"
                    )));
                }
                if meta.is_dir()
                    && let (Ok(cwd), Ok(target)) =
                        (std::env::current_dir(), std::fs::canonicalize(&dir))
                    && cwd.starts_with(&target)
                {
                    return Err(usage("contains the current directory; it is not replaced"));
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
                ) =>
            {
                // The nearest existing ancestor must be a folder, or nothing can be
                // created below it.
                if let Some(a) = dir
                    .ancestors()
                    .skip(1)
                    .filter(|a| !a.as_os_str().is_empty())
                    .find(|a| std::fs::symlink_metadata(a).is_ok())
                    && !a.is_dir()
                {
                    return Err(usage(&format!("{} is not a folder", a.display())));
                }
            }
            Err(e) => return Err(usage(&e.to_string())),
        }
        Ok(Self { dir, force })
    }

    /// The folder the outputs end up in.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Create the folder itself, for a run that writes into it as it goes (its log): a
    /// folder that holds something (allowed by `--force`) is removed first, so the new
    /// run's files never stand beside an older run's. A folder without `summary.json` is
    /// then a run under way, or one that was killed.
    pub fn create_in_place(&self) -> anyhow::Result<PathBuf> {
        if self.force && std::fs::symlink_metadata(&self.dir).is_ok() {
            remove_any(&self.dir)?;
        }
        std::fs::create_dir_all(&self.dir)
            .with_context(|| format!("creating {}", self.dir.display()))?;
        Ok(self.dir.clone())
    }

    /// Create the fresh temporary sibling folder (and any missing parent) to write the
    /// outputs into.
    pub fn begin(&self) -> anyhow::Result<Staging> {
        let parent = match self.dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("creating {}", parent.display()))?;
        let name = self
            .dir
            .file_name()
            .with_context(|| format!("{}: not a folder name", self.dir.display()))?
            .to_string_lossy()
            .into_owned();
        let sibling = |what: &str| parent.join(format!(".{name}.{what}-{}", std::process::id()));
        let tmp = sibling("tmp");
        // Only a run of a process with this id (long dead: it is us now) left it.
        if std::fs::symlink_metadata(&tmp).is_ok() {
            remove_any(&tmp)?;
        }
        std::fs::create_dir(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        Ok(Staging {
            tmp,
            old: sibling("old"),
            target: self.dir.clone(),
            force: self.force,
            done: false,
        })
    }
}

/// The temporary folder a run's outputs are written into; [`Staging::commit`] renames it
/// into place. Dropped without a commit (an error on the way), it is removed.
#[derive(Debug)]
pub struct Staging {
    tmp: PathBuf,
    old: PathBuf,
    target: PathBuf,
    force: bool,
    done: bool,
}

impl Staging {
    /// The folder to write into.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Put the complete folder in place: a rename onto a missing or empty target; with
    /// `--force`, an atomic exchange with whatever is there, which is then removed.
    /// Returns the final folder.
    pub fn commit(mut self) -> anyhow::Result<PathBuf> {
        self.done = true;
        let exists = std::fs::symlink_metadata(&self.target).is_ok();
        if !(exists && self.force) {
            // rename(2) replaces a missing or an empty folder and nothing else: a folder
            // filled since the check is not lost.
            return match std::fs::rename(&self.tmp, &self.target) {
                Ok(()) => Ok(self.target.clone()),
                Err(e) => Err(anyhow::anyhow!(
                    "{}: {e}; the outputs are in {}",
                    self.target.display(),
                    self.tmp.display()
                )),
            };
        }
        use nix::fcntl::{AT_FDCWD, RenameFlags, renameat2};
        match renameat2(
            AT_FDCWD,
            &self.tmp,
            AT_FDCWD,
            &self.target,
            RenameFlags::RENAME_EXCHANGE,
        ) {
            // The old contents are now at the temporary name.
            Ok(()) => remove_any(&self.tmp)?,
            // A file system without the exchange: two renames (a moment with no folder,
            // never a mixed or half-written one).
            Err(_) => {
                std::fs::rename(&self.target, &self.old).with_context(|| {
                    format!(
                        "moving {} aside; the outputs are in {}",
                        self.target.display(),
                        self.tmp.display()
                    )
                })?;
                std::fs::rename(&self.tmp, &self.target).with_context(|| {
                    format!(
                        "renaming {} to {} (the old one is in {})",
                        self.tmp.display(),
                        self.target.display(),
                        self.old.display()
                    )
                })?;
                remove_any(&self.old)?;
            }
        }
        Ok(self.target.clone())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

/// Remove `path` whatever it is (a folder with its contents, a file, a link).
fn remove_any(path: &Path) -> anyhow::Result<()> {
    let meta =
        std::fs::symlink_metadata(path).with_context(|| format!("reading {}", path.display()))?;
    if meta.is_dir() {
        std::fs::remove_dir_all(path)
    } else {
        std::fs::remove_file(path)
    }
    .with_context(|| format!("removing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch folder of this test, removed when dropped.
    struct Scratch(PathBuf);
    impl Scratch {
        fn new(name: &str) -> Self {
            let dir = std::env::temp_dir()
                .join(format!("coordinator-output-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).expect("scratch folder");
            Self(dir)
        }
        fn names(&self) -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(&self.0)
                .expect("read_dir")
                .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        }
    }
    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn an_abandoned_staging_folder_is_removed_and_the_target_never_appears() {
        let s = Scratch::new("abandon");
        let out = OutDir::check(s.0.join("run"), false).expect("a missing folder is fine");
        let staging = out.begin().expect("begin");
        std::fs::write(staging.path().join("half.csv"), b"1,2").expect("write");
        assert_eq!(s.names().len(), 1, "only the hidden temporary folder");
        drop(staging);
        assert!(s.names().is_empty(), "{:?}", s.names());
    }

    #[test]
    fn force_swaps_the_new_folder_in_whole() {
        let s = Scratch::new("force");
        let target = s.0.join("run");
        std::fs::create_dir_all(target.join("plots")).expect("mkdir");
        std::fs::write(target.join("plots").join("old.png"), b"old").expect("write");
        let refused = OutDir::check(target.clone(), false).expect_err("not empty");
        assert_eq!(refused.exit_code(), 2);
        let staging = OutDir::check(target.clone(), true)
            .expect("forced")
            .begin()
            .expect("begin");
        std::fs::write(staging.path().join("summary.json"), b"{}").expect("write");
        assert_eq!(staging.commit().expect("commit"), target);
        assert_eq!(s.names(), ["run"]);
        assert!(!target.join("plots").exists());
        assert_eq!(
            std::fs::read(target.join("summary.json")).expect("new"),
            b"{}"
        );
    }

    #[test]
    fn without_force_a_folder_filled_meanwhile_is_kept_and_the_new_one_named() {
        let s = Scratch::new("race");
        let target = s.0.join("run");
        let staging = OutDir::check(target.clone(), false)
            .expect("missing")
            .begin()
            .expect("begin");
        std::fs::create_dir(&target).expect("mkdir");
        std::fs::write(target.join("theirs"), b"x").expect("write");
        let tmp = staging.path().to_path_buf();
        let e = staging.commit().expect_err("not replaced without --force");
        assert!(e.to_string().contains(&tmp.display().to_string()), "{e}");
        assert_eq!(std::fs::read(target.join("theirs")).expect("kept"), b"x");
        assert!(
            tmp.is_dir(),
            "the new outputs are kept where the message says"
        );
    }

    #[test]
    fn names_that_are_no_folder_of_their_own_are_refused() {
        for dir in [".", "..", "/"] {
            let e = OutDir::check(PathBuf::from(dir), true).expect_err(dir);
            assert_eq!(e.exit_code(), 2, "{dir}");
        }
    }
}
