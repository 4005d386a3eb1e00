//! Reading a file a user (or a folder someone else made) hands in: whole, with a bound on
//! its size that holds before any memory is spent.
//!
//! A length read from the path's metadata is no bound: a device (`/dev/zero`) reports 0
//! and never ends, a FIFO blocks the opener until someone writes, and a sparse file
//! reports its full length while costing nothing on disk. So the file is opened without
//! blocking and without taking a terminal, asked through the open descriptor what it is
//! (only a regular file is read), its length checked against the bound, and then read
//! through a reader that stops one byte past the bound, in case it grew meanwhile.

use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// Whether the last part of the path may be a symbolic link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Links {
    /// Follow it: a path the user typed, whose links are the user's own.
    Follow,
    /// Refuse it: a file inside a folder that may have been made by someone else (a run
    /// folder handed to `render` or `run --resume`), where a link could lead anywhere.
    Refuse,
}

/// Why a file was not read. The path is not part of the message: the caller names it.
#[derive(Debug, thiserror::Error)]
pub enum ReadInputError {
    /// It is not a regular file: a folder, a FIFO, a device or a socket.
    #[error("is {0}, not a regular file")]
    NotRegular(&'static str),
    /// It is a symbolic link, and [`Links::Refuse`] was asked.
    #[error("is a symbolic link, which is not followed here")]
    SymbolicLink,
    /// It holds more than the bound.
    #[error("holds {bytes} bytes, more than the {max_bytes} such a file may")]
    TooLarge {
        /// Its length (at least; it may have grown while being read).
        bytes: u64,
        /// The bound.
        max_bytes: u64,
    },
    /// Its text is not UTF-8 ([`read_input_text`]).
    #[error("is not UTF-8 text")]
    NotUtf8,
    /// Opening, inspecting or reading it failed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// The bytes of the regular file at `path`, at most `max_bytes` of them.
///
/// ```
/// use shared::input_file::{Links, ReadInputError, read_input};
/// let dir = std::env::temp_dir().join(format!("input-file-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("five");
/// std::fs::write(&path, b"12345").unwrap();
/// assert_eq!(read_input(&path, 5, Links::Follow).unwrap(), b"12345");
/// assert!(matches!(
///     read_input(&path, 4, Links::Follow),
///     Err(ReadInputError::TooLarge { bytes: 5, max_bytes: 4 })
/// ));
/// // A device reports no length and never ends: refused without reading a byte.
/// assert!(matches!(
///     read_input(std::path::Path::new("/dev/zero"), 4, Links::Follow),
///     Err(ReadInputError::NotRegular("a character device"))
/// ));
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn read_input(path: &Path, max_bytes: u64, links: Links) -> Result<Vec<u8>, ReadInputError> {
    let (file, len) = open_regular(path, max_bytes, links)?;
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(ReadInputError::TooLarge {
            bytes: bytes.len() as u64,
            max_bytes,
        });
    }
    Ok(bytes)
}

/// The regular file at `path`, checked as [`read_input`] checks it, to be read as a
/// stream (a table read row by row): reading stops after `max_bytes`, should the file
/// have grown since it was checked.
pub fn open_input(
    path: &Path,
    max_bytes: u64,
    links: Links,
) -> Result<std::io::Take<std::fs::File>, ReadInputError> {
    Ok(open_regular(path, max_bytes, links)?.0.take(max_bytes))
}

/// Open `path` without blocking (a FIFO) and without taking a terminal, and check through
/// the descriptor that it is a regular file of at most `max_bytes`; with its length.
fn open_regular(
    path: &Path,
    max_bytes: u64,
    links: Links,
) -> Result<(std::fs::File, u64), ReadInputError> {
    let mut flags = libc::O_NONBLOCK | libc::O_NOCTTY | libc::O_CLOEXEC;
    if links == Links::Refuse {
        flags |= libc::O_NOFOLLOW;
    }
    let file = match std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(flags)
        .open(path)
    {
        Ok(file) => file,
        // O_NOFOLLOW on a link fails with ELOOP.
        Err(e) if links == Links::Refuse && e.raw_os_error() == Some(libc::ELOOP) => {
            return Err(ReadInputError::SymbolicLink);
        }
        Err(e) => return Err(e.into()),
    };
    let meta = file.metadata()?;
    let kind = meta.file_type();
    if !kind.is_file() {
        return Err(ReadInputError::NotRegular(if kind.is_dir() {
            "a folder"
        } else if kind.is_fifo() {
            "a FIFO"
        } else if kind.is_char_device() {
            "a character device"
        } else if kind.is_block_device() {
            "a block device"
        } else if kind.is_socket() {
            "a socket"
        } else {
            "something else"
        }));
    }
    if meta.len() > max_bytes {
        return Err(ReadInputError::TooLarge {
            bytes: meta.len(),
            max_bytes,
        });
    }
    Ok((file, meta.len()))
}

/// The UTF-8 text of the regular file at `path`, at most `max_bytes` of it.
pub fn read_input_text(
    path: &Path,
    max_bytes: u64,
    links: Links,
) -> Result<String, ReadInputError> {
    String::from_utf8(read_input(path, max_bytes, links)?).map_err(|_| ReadInputError::NotUtf8)
}
