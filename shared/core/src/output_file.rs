//! Writing into a folder that may hold someone else's links (a run folder handed to
//! `render` or `run --resume`): nothing is ever written through a symbolic link.
//!
//! A file is written under a temporary name created new (`O_CREAT | O_EXCL`, which never
//! follows a link: a link left at that name makes the creation fail, and a stale one is
//! removed first, the link itself) and renamed over the file's name (a rename replaces a
//! link, never follows it). A folder written into must be a real folder: a link in its
//! place is refused.

use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

/// Write `bytes` to `path` through a temporary file beside it (`.NAME.part-PID`), created
/// new, and a rename; never through a link at either name.
///
/// ```
/// use shared::output_file::write_replacing;
/// let dir = std::env::temp_dir().join(format!("output-file-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let elsewhere = dir.join("elsewhere");
/// std::fs::write(&elsewhere, b"kept").unwrap();
/// // A link at the name is replaced by the file; what it pointed at is untouched.
/// std::os::unix::fs::symlink(&elsewhere, dir.join("out.csv")).unwrap();
/// write_replacing(&dir.join("out.csv"), b"new").unwrap();
/// assert_eq!(std::fs::read(&elsewhere).unwrap(), b"kept");
/// assert_eq!(std::fs::read(dir.join("out.csv")).unwrap(), b"new");
/// assert!(!std::fs::symlink_metadata(dir.join("out.csv")).unwrap().is_symlink());
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_replacing(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path.file_name().ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: not a file name", path.display()),
        )
    })?;
    let part = path.with_file_name(format!(
        ".{}.part-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let mut file = create_new(&part)?;
    let written = file.write_all(bytes).and_then(|()| file.flush());
    drop(file);
    if let Err(e) = written.and_then(|()| std::fs::rename(&part, path)) {
        let _ = std::fs::remove_file(&part);
        return Err(e);
    }
    Ok(())
}

/// Create the file `path` new and empty (mode 0644 less the umask), first removing
/// whatever stands at that name if it is a file or a link (the link itself, never its
/// target); a folder there is an error.
pub fn create_new(path: &Path) -> std::io::Result<std::fs::File> {
    match std::fs::remove_file(path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(e),
    }
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o644)
        .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
        .open(path)
}

/// Make sure `path` is a real folder, creating it (not its parents) if it is missing: a
/// symbolic link in its place, even to a folder, or anything else is refused.
pub fn real_folder(path: &Path) -> std::io::Result<()> {
    match std::fs::create_dir(path) {
        Ok(()) => return Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(e),
    }
    let meta = std::fs::symlink_metadata(path)?;
    if meta.is_dir() {
        Ok(())
    } else {
        let what = if meta.is_symlink() {
            "is a symbolic link; nothing is written through one"
        } else {
            "is not a folder"
        };
        Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!("{} {what}", path.display()),
        ))
    }
}
