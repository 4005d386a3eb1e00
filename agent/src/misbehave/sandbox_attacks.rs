//! The attacks a sandbox (`coordinator run --sandbox`) must hold against, tried before the
//! agent starts serving honestly: [`Misbehave::Scribble`], [`Misbehave::StopOthers`],
//! [`Misbehave::RewriteMission`], [`Misbehave::ForkBomb`], [`Misbehave::LogFlood`],
//! [`Misbehave::TtyPush`], [`Misbehave::FillTmp`], [`Misbehave::KillTwin`]. Each says on stderr, at warn
//! level, what it reached (`scribble: wrote into 0 of 0 files`), so a test can tell an
//! attack that was stopped from one that was never tried.

use std::io::{Read, Seek, SeekFrom, Write};
use std::path::PathBuf;

use wire::misbehave::Misbehave;

/// At most this many children for [`Misbehave::ForkBomb`].
const MAX_FORKS: usize = 4096;

/// Carry out `mode` if it is one of this module's, as agent `agent` of run `prefix`.
pub fn before_opening(prefix: &str, agent: usize, mode: Misbehave) {
    match mode {
        Misbehave::Scribble => scribble(prefix, agent),
        Misbehave::StopOthers => stop_others(prefix, agent),
        Misbehave::RewriteMission => rewrite_mission(prefix, agent),
        Misbehave::ForkBomb => fork_bomb(agent),
        Misbehave::LogFlood => log_flood(agent),
        Misbehave::TtyPush => tty_push(agent),
        Misbehave::FillTmp => fill_tmp(agent),
        Misbehave::KillTwin => kill_twin(agent),
        _ => {}
    }
}

/// Every file below the run's folder, as far as this process can list it.
fn run_files(prefix: &str) -> (Vec<PathBuf>, usize) {
    let mut files = Vec::new();
    let mut unreadable = 0;
    let mut pending: Vec<PathBuf> = wire::run_root(prefix).into_iter().collect();
    while let Some(dir) = pending.pop() {
        match std::fs::read_dir(&dir) {
            Ok(entries) => {
                for path in entries.flatten().map(|e| e.path()) {
                    if path.is_dir() {
                        pending.push(path);
                    } else {
                        files.push(path);
                    }
                }
            }
            Err(_) => unreadable += 1,
        }
    }
    (files, unreadable)
}

fn scribble(prefix: &str, agent: usize) {
    let (files, unreadable) = run_files(prefix);
    let mut noise = vec![0u8; 64 << 10];
    if let Ok(mut random) = std::fs::File::open("/dev/urandom") {
        let _ = random.read_exact(&mut noise);
    }
    let mut written = 0;
    for file in &files {
        let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(file) else {
            continue;
        };
        let len = f.metadata().map(|m| m.len()).unwrap_or(0) as usize;
        let mut at = 0;
        while at < len {
            let n = (len - at).min(noise.len());
            if f.seek(SeekFrom::Start(at as u64)).is_err() || f.write_all(&noise[..n]).is_err() {
                break;
            }
            at += n;
        }
        written += 1;
    }
    tracing::warn!(
        "agent {agent} (scribble): wrote into {written} of {} files ({unreadable} folders unreadable)",
        files.len()
    );
}

/// Every process in `/proc` but this one.
fn other_processes() -> impl Iterator<Item = u32> {
    let me = std::process::id();
    std::fs::read_dir("/proc")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(move |&pid| pid != me)
}

fn stop_others(prefix: &str, agent: usize) {
    let needle = format!("--prefix\0{prefix}\0");
    let (mut tried, mut stopped) = (0, 0);
    for pid in other_processes() {
        let Ok(cmdline) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
            continue;
        };
        if !cmdline
            .windows(needle.len())
            .any(|w| w == needle.as_bytes())
        {
            continue;
        }
        tried += 1;
        // SAFETY: kill(2) with a pid read from /proc and a plain signal.
        if unsafe { libc::kill(pid as libc::pid_t, libc::SIGSTOP) } == 0 {
            stopped += 1;
        }
    }
    tracing::warn!(
        "agent {agent} (stop-others): stopped {stopped} of {tried} processes of the run"
    );
}

/// Rewrite run `prefix`'s mission file without its disk obstacles, saying on stderr
/// whether it could.
pub fn rewrite_mission(prefix: &str, agent: usize) {
    let outcome = match wire::mission_path(prefix) {
        None => "no mission path".to_string(),
        Some(path) => match std::fs::read_to_string(&path) {
            Err(e) => format!("cannot read it: {e}"),
            Ok(text) => {
                // The mission without its disk obstacles: a forgery that still parses.
                let cut = match serde_json::from_str::<serde_json::Value>(&text) {
                    Ok(mut mission) => {
                        if let Some(obstacles) = mission.get_mut("obstacles") {
                            obstacles["disk"] = serde_json::Value::Array(Vec::new());
                        }
                        mission.to_string()
                    }
                    Err(_) => String::new(),
                };
                match std::fs::write(&path, cut) {
                    Ok(()) => "rewritten".to_string(),
                    Err(e) => format!("cannot write it: {e}"),
                }
            }
        },
    };
    tracing::warn!("agent {agent} (rewrite-mission): {outcome}");
}

fn fork_bomb(agent: usize) {
    let mut forked = 0;
    while forked < MAX_FORKS {
        // SAFETY: fork(2); the child only calls pause(2) in a loop, then never returns.
        match unsafe { libc::fork() } {
            0 => loop {
                // SAFETY: pause(2) waits for a signal; nothing else happens here.
                unsafe { libc::pause() };
            },
            pid if pid > 0 => forked += 1,
            _ => break,
        }
    }
    tracing::warn!("agent {agent} (fork-bomb): forked {forked} children before fork failed");
}

fn log_flood(agent: usize) {
    let line = format!("agent {agent} (log-flood): {}\n", "x".repeat(100));
    let flood = |out: &mut dyn std::io::Write| {
        let mut written = 0usize;
        while written < 16 << 20 {
            if out.write_all(line.as_bytes()).is_err() {
                break;
            }
            written += line.len();
        }
        let _ = out.flush();
    };
    flood(&mut std::io::stderr().lock());
    flood(&mut std::io::stdout().lock());
}

/// What `tty-push` types: a comment, harmless if a shell runs it.
const TTY_LINE: &[u8] = b"# pushed by a sandboxed agent\n";

fn tty_push(agent: usize) {
    use std::os::fd::AsRawFd;
    let tty = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open("/dev/tty");
    let opened = match &tty {
        Ok(_) => "opened /dev/tty".to_string(),
        Err(e) => format!("cannot open /dev/tty ({e})"),
    };
    let fds: Vec<i32> = tty.iter().map(|f| f.as_raw_fd()).chain([0, 1, 2]).collect();
    let mut pushed = 0;
    for fd in fds {
        let push = |b: &u8| {
            // SAFETY: ioctl(2) TIOCSTI with a pointer to one byte that outlives the call.
            unsafe { libc::ioctl(fd, libc::TIOCSTI, b as *const u8) == 0 }
        };
        if TTY_LINE.iter().all(push) {
            pushed += 1;
        }
    }
    tracing::warn!("agent {agent} (tty-push): {opened}; pushed a line into {pushed} terminals");
}

/// The most `fill-tmp` writes into each folder.
const FILL_BYTES: usize = 256 << 20;

fn fill_tmp(agent: usize) {
    use std::io::Write as _;
    let block = vec![0x5au8; 1 << 20];
    let mut report = Vec::new();
    for dir in ["/dev/shm", "/tmp", "/var/tmp"] {
        let path = format!("{dir}/formation-fill-tmp-{}", std::process::id());
        let mut written = 0usize;
        if let Ok(mut file) = std::fs::File::create(&path) {
            while written < FILL_BYTES && file.write_all(&block).is_ok() {
                written += block.len();
            }
        }
        report.push(format!("{} MiB into {dir}", written >> 20));
    }
    tracing::warn!("agent {agent} (fill-tmp): wrote {}", report.join(", "));
}

fn kill_twin(agent: usize) {
    // SAFETY: getuid(2) cannot fail.
    let uid = unsafe { libc::getuid() };
    let (mut found, mut killed) = (0, 0);
    for pid in other_processes() {
        let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else {
            continue;
        };
        let real_uid = status
            .lines()
            .find_map(|l| l.strip_prefix("Uid:"))
            .and_then(|ids| ids.split_whitespace().next()?.parse::<u32>().ok());
        if real_uid != Some(uid) {
            continue;
        }
        found += 1;
        // SAFETY: kill(2) with a pid read from /proc and a plain signal.
        if unsafe { libc::kill(pid as libc::pid_t, libc::SIGKILL) } == 0 {
            killed += 1;
        }
    }
    tracing::warn!(
        "agent {agent} (kill-twin): killed {killed} of {found} other processes of user {uid}"
    );
}
