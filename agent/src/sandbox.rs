//! Starting an agent in its sandbox: a user of its own, a control group of its own with
//! limits, no new privileges, no descriptor but its socket, an environment with only what
//! it needs, a session of its own (no terminal), and a view of the file system of its own:
//! every file system read-only, a small private `/tmp`, `/var/tmp` and `/dev/shm`, and
//! private System V and POSIX message-queue IPC, all gone with it. The relay (the
//! coordinator's user) starts it and is its only link to the run: the agent's user can
//! open none of the run's files, and what it writes (its output, its temporary files) is
//! bounded and charged to it.

use std::ffi::CString;
use std::os::fd::{AsRawFd, OwnedFd};
use std::os::unix::net::UnixStream;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};

use anyhow::Context;
use wire::cgroup::{CgroupDirs, Limits, join_opened, raw_fds};

/// The descriptor the sandboxed agent finds its socket on.
pub const AGENT_SOCKET_FD: i32 = 3;

/// How much of a sandboxed agent's output (stdout and stderr, one pipe) its relay passes
/// on to its own stderr; the rest is counted and dropped, so an agent that floods its
/// output costs the run's log no more than this and writes nothing to the coordinator's
/// stdout.
pub const MAX_AGENT_LOG_BYTES: u64 = 64 << 10;

/// The size of each of the agent's private temporary file systems (`/tmp`, `/var/tmp`,
/// `/dev/shm`): memory, charged to the agent's control group, freed when it dies.
pub const PRIVATE_TMP_BYTES: u64 = 16 << 20;

/// The folders that get a private temporary file system, if they exist.
const PRIVATE_TMP_DIRS: [&std::ffi::CStr; 3] = [c"/tmp", c"/var/tmp", c"/dev/shm"];

/// The environment variables an agent keeps (all others are dropped).
const KEPT_ENV: [&str; 2] = ["RUST_LOG", "RUST_BACKTRACE"];

/// Where and how an agent is sandboxed.
#[derive(Clone, Debug)]
pub struct Sandbox {
    /// Its user and group id.
    pub uid: u32,
    /// Its control group (made and limited before it starts), if cgroups are usable.
    pub cgroup: Option<CgroupDirs>,
    /// The limits (also the per-user process limit, which holds without cgroups).
    pub limits: Limits,
}

/// A sandboxed agent process: killed (with everything in its group) and reaped when
/// dropped.
pub struct SandboxedAgent {
    child: Child,
    cgroup: Option<CgroupDirs>,
    /// The thread passing its output on (and saying at the end how much it dropped).
    output_relay: Option<std::thread::JoinHandle<()>>,
}

impl SandboxedAgent {
    /// Its process id.
    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// Whether it has exited (reaping it).
    pub fn exited(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(Some(_)))
    }
}

impl Drop for SandboxedAgent {
    fn drop(&mut self) {
        // The agent first, and reaped (a killed child stays in its group until then);
        // then whatever else is in its group. Every wait looks with growing pauses: at
        // the end of a large run a thousand relays wait at once on two cores.
        let _ = self.child.kill();
        let child = &mut self.child;
        let reaped = wire::poll_until(ORPHANS_TIMEOUT, || {
            matches!(child.try_wait(), Ok(Some(_)) | Err(_))
        });
        if let Some(group) = &self.cgroup
            && let Err(e) = group.kill_all(ORPHANS_TIMEOUT)
        {
            tracing::warn!("sandboxed agent {}: {e}", self.child.id());
        }
        if !reaped {
            let _ = self.child.wait();
        }
        // Without a control group nothing here killed the agent's other processes: the
        // dead ones are reaped, the live ones left to the coordinator's sweep.
        reap_adopted_orphans(match self.cgroup {
            Some(_) => ORPHANS_TIMEOUT,
            None => std::time::Duration::ZERO,
        });
        // Let the output relay drain what the agent wrote and report what it dropped
        // before this process goes; not for ever (a child it left may hold the pipe).
        if let Some(relay) = self.output_relay.take()
            && wire::poll_until(ORPHANS_TIMEOUT, || relay.is_finished())
        {
            let _ = relay.join();
        }
    }
}

/// How long a relay waits for its sandboxed agent's processes to die and be reaped.
const ORPHANS_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(2);

/// Make this process (a relay) a child subreaper: whatever its sandboxed agent starts
/// and leaves behind is handed to it, not to the coordinator, so the relay, which kills
/// them, also reaps them before it exits (the coordinator cannot tell a dead process of
/// the run from any other zombie, and would leave it unreaped until it exits itself).
pub fn adopt_orphans() {
    if let Err(e) = nix::sys::prctl::set_child_subreaper(true) {
        tracing::warn!("cannot become a child subreaper ({e}): the agent's orphans go up");
    }
}

/// Reap every child of this process, the agent's orphans it adopted included, until it
/// has none or `timeout` passes (a child still alive after the kill). A relay has no
/// child of its own but the agent, so waiting for any child touches nothing else.
fn reap_adopted_orphans(timeout: std::time::Duration) {
    use nix::sys::wait::{WaitPidFlag, WaitStatus, waitpid};
    let all_reaped = wire::poll_until(timeout, || {
        loop {
            match waitpid(None, Some(WaitPidFlag::WNOHANG)) {
                // Children left, none dead yet: look again after a pause.
                Ok(WaitStatus::StillAlive) => return false,
                // One reaped: look for the next at once.
                Ok(_) => {}
                // No child left.
                Err(_) => return true,
            }
        }
    });
    if !all_reaped {
        tracing::warn!("the sandboxed agent left processes that would not die");
    }
}

/// Start `exe` with `args` in `sandbox`, its end of the link as descriptor
/// [`AGENT_SOCKET_FD`].
pub fn spawn_sandboxed(
    exe: &Path,
    args: &[String],
    socket: UnixStream,
    sandbox: &Sandbox,
) -> anyhow::Result<SandboxedAgent> {
    let procs: Vec<OwnedFd> = match &sandbox.cgroup {
        Some(group) => {
            group.create().context("the agent's control group")?;
            group.limit(&sandbox.limits).context("the agent's limits")?;
            group.open_procs().context("the agent's control group")?
        }
        None => Vec::new(),
    };
    let procs_raw = raw_fds(&procs);
    let socket_fd = socket.as_raw_fd();
    let (uid, nproc) = (sandbox.uid, u64::from(sandbox.limits.pids_max));
    let relay_pid = std::process::id();
    // The agent is started from a descriptor opened here, as the relay's user: its own
    // user need not reach the executable's folders (a build under /root, 0700).
    let exe_file = std::fs::File::open(exe)
        .with_context(|| format!("opening the agent executable {}", exe.display()))?;
    let mut env: Vec<(String, std::ffi::OsString)> = KEPT_ENV
        .iter()
        .filter_map(|k| Some((k.to_string(), std::env::var_os(k)?)))
        .collect();
    if let Some(run) = std::env::var_os(wire::RUN_ENV) {
        env.push((wire::RUN_ENV.to_string(), run));
    }
    let image = ExecImage::new(exe, args, &env)?;
    let tmpfs_options = CString::new(format!("size={PRIVATE_TMP_BYTES},nr_inodes=4096,mode=1777"))
        .context("the temporary file systems' options")?;
    // Its stdout and stderr are one pipe, read by a thread of this relay that passes on a
    // bounded part: it never writes to the coordinator's terminal or stdout.
    let (output, output_writer) = std::io::pipe().context("the agent's output pipe")?;
    let output_writer_too = output_writer
        .try_clone()
        .context("the agent's output pipe")?;
    // Never on the socket's place: the child puts the socket there first.
    let _held = (exe_file.as_raw_fd() == AGENT_SOCKET_FD)
        .then(|| exe_file.try_clone())
        .transpose()
        .context("the agent executable")?;
    let exe_fd = match &_held {
        Some(clone) => clone.as_raw_fd(),
        None => exe_file.as_raw_fd(),
    };
    let mut command = Command::new(exe);
    // Its parent is this relay, not the coordinator: it is not told the coordinator's
    // process to check against (`wire::PARENT_ENV`).
    command
        .current_dir("/")
        .env_remove(wire::PARENT_ENV)
        .stdin(Stdio::null())
        .stdout(output_writer)
        .stderr(output_writer_too);
    // SAFETY: between fork and exec the closure makes only async-signal-safe system
    // calls (write, dup2, fcntl, setrlimit, setsid, unshare, mount, mount_setattr,
    // setgroups, setresgid, setresuid, prctl, close_range, fexecve) on values made before
    // the fork; it allocates nothing.
    unsafe {
        command.pre_exec(move || {
            enter_sandbox(&procs_raw, socket_fd, uid, nproc, relay_pid, &tmpfs_options)?;
            image.exec(exe_fd)
        });
    }
    let child = command
        .spawn()
        .with_context(|| format!("starting the sandboxed agent as user {uid}"))?;
    // The pipe's write ends are the agent's alone now: this relay's copies go with the
    // command, so the reader sees the end when the agent (and what it left) closes them.
    drop(command);
    let output_relay = {
        let pid = child.id();
        Some(std::thread::spawn(move || {
            pass_on_bounded(output, pid, MAX_AGENT_LOG_BYTES)
        }))
    };
    drop(socket);
    drop(procs);
    drop(exe_file);
    Ok(SandboxedAgent {
        child,
        cgroup: sandbox.cgroup.clone(),
        output_relay,
    })
}

/// The argument and environment vectors of the agent, made before the fork.
struct ExecImage {
    _strings: Vec<CString>,
    argv: Vec<*const libc::c_char>,
    envp: Vec<*const libc::c_char>,
}

// SAFETY: the pointers point into `_strings`, owned by the same value and never changed;
// the value is only read, by the child after the fork.
unsafe impl Send for ExecImage {}
// SAFETY: as for Send: nothing is ever written through the pointers.
unsafe impl Sync for ExecImage {}

impl ExecImage {
    fn new(
        exe: &Path,
        args: &[String],
        env: &[(String, std::ffi::OsString)],
    ) -> anyhow::Result<Self> {
        use std::os::unix::ffi::OsStrExt;
        let c = |bytes: &[u8]| CString::new(bytes).context("a NUL byte in the agent's arguments");
        let argv_strings: Vec<CString> = std::iter::once(c(exe.as_os_str().as_bytes()))
            .chain(args.iter().map(|a| c(a.as_bytes())))
            .collect::<anyhow::Result<_>>()?;
        let env_strings: Vec<CString> = env
            .iter()
            .map(|(k, v)| c(&[k.as_bytes(), b"=", v.as_bytes()].concat()))
            .collect::<anyhow::Result<_>>()?;
        let pointers = |strings: &[CString]| -> Vec<*const libc::c_char> {
            strings
                .iter()
                .map(|s| s.as_ptr())
                .chain(std::iter::once(std::ptr::null()))
                .collect()
        };
        let (argv, envp) = (pointers(&argv_strings), pointers(&env_strings));
        let mut strings = argv_strings;
        strings.extend(env_strings);
        Ok(Self {
            _strings: strings,
            argv,
            envp,
        })
    }

    /// Replace this process by the agent (returns only on failure).
    fn exec(&self, exe_fd: i32) -> std::io::Result<()> {
        // SAFETY: both vectors are NULL-terminated arrays of C strings that live as long
        // as `self`.
        unsafe { libc::fexecve(exe_fd, self.argv.as_ptr(), self.envp.as_ptr()) };
        Err(std::io::Error::last_os_error())
    }
}

/// In the child, before exec: join the group (while still privileged), take the
/// socket as descriptor 3, leave the coordinator's session and terminal, see the file
/// systems read-only with private temporary ones, become the agent's user for good, and
/// close the door behind.
fn enter_sandbox(
    procs: &[i32],
    socket_fd: i32,
    uid: u32,
    nproc: u64,
    relay_pid: u32,
    tmpfs_options: &std::ffi::CStr,
) -> std::io::Result<()> {
    let check = |r: libc::c_int| {
        if r < 0 {
            Err(std::io::Error::last_os_error())
        } else {
            Ok(())
        }
    };
    join_opened(procs)?;
    // SAFETY: plain system calls on integers and static values, nothing allocated.
    unsafe {
        if socket_fd == AGENT_SOCKET_FD {
            // Keep it across exec.
            check(libc::fcntl(AGENT_SOCKET_FD, libc::F_SETFD, 0))?;
        } else {
            check(libc::dup2(socket_fd, AGENT_SOCKET_FD))?;
        }
        // Every other descriptor closes at exec (ENOSYS on an old kernel: the coordinator
        // already marked its own close-on-exec).
        let _ = wire::mark_cloexec_from(AGENT_SOCKET_FD + 1);
        let limit = libc::rlimit {
            rlim_cur: nproc,
            rlim_max: nproc,
        };
        check(libc::setrlimit(libc::RLIMIT_NPROC, &limit))?;
        let no_core = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        check(libc::setrlimit(libc::RLIMIT_CORE, &no_core))?;
        // A session of its own: no controlling terminal, so none to push input into
        // (TIOCSTI) or to signal; its stdin is /dev/null and its output a pipe.
        check(libc::setsid())?;
        private_file_systems(tmpfs_options)?;
        check(libc::setgroups(0, std::ptr::null()))?;
        check(libc::setresgid(uid, uid, uid))?;
        check(libc::setresuid(uid, uid, uid))?;
        check(libc::prctl(libc::PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0))?;
        // Set after the change of user, which clears it.
        check(libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0))?;
        if libc::getppid() as u32 != relay_pid {
            // The relay died before the signal was armed.
            libc::_exit(1);
        }
    }
    Ok(())
}

/// `mount_setattr(2)`'s argument (linux/mount.h).
#[repr(C)]
struct MountAttr {
    attr_set: u64,
    attr_clr: u64,
    propagation: u64,
    userns_fd: u64,
}

/// `MOUNT_ATTR_RDONLY` (linux/mount.h).
const MOUNT_ATTR_RDONLY: u64 = 0x1;

/// In the child, still privileged: a mount and IPC namespace of its own, in which every
/// file system is read-only (`mount_setattr(2)` with `AT_RECURSIVE`, Linux 5.12) and
/// [`PRIVATE_TMP_DIRS`] are small private tmpfs ([`PRIVATE_TMP_BYTES`]): whatever the
/// agent writes is memory charged to its control group and is gone with its namespace,
/// as are its System V IPC objects and POSIX message queues. Nothing it writes outlives
/// it, fills a disk or the host's `/dev/shm`.
///
/// # Safety
///
/// Only between fork and exec: async-signal-safe system calls on values made before.
unsafe fn private_file_systems(tmpfs_options: &std::ffi::CStr) -> std::io::Result<()> {
    let check = |r: libc::c_long| {
        if r < 0 {
            Err(std::io::Error::last_os_error())
        } else {
            Ok(())
        }
    };
    // SAFETY: plain system calls on static strings, `tmpfs_options` and a local struct.
    unsafe {
        check(libc::unshare(libc::CLONE_NEWNS | libc::CLONE_NEWIPC).into())?;
        // Nothing done here propagates back to the host's mounts.
        check(
            libc::mount(
                c"none".as_ptr(),
                c"/".as_ptr(),
                std::ptr::null(),
                libc::MS_REC | libc::MS_PRIVATE,
                std::ptr::null(),
            )
            .into(),
        )?;
        let read_only = MountAttr {
            attr_set: MOUNT_ATTR_RDONLY,
            attr_clr: 0,
            propagation: 0,
            userns_fd: 0,
        };
        check(libc::syscall(
            libc::SYS_mount_setattr,
            libc::AT_FDCWD,
            c"/".as_ptr(),
            libc::AT_RECURSIVE,
            &read_only as *const MountAttr,
            std::mem::size_of::<MountAttr>(),
        ))?;
        for dir in PRIVATE_TMP_DIRS {
            let mounted = libc::mount(
                c"tmpfs".as_ptr(),
                dir.as_ptr(),
                c"tmpfs".as_ptr(),
                libc::MS_NOSUID | libc::MS_NODEV,
                tmpfs_options.as_ptr().cast(),
            );
            if mounted < 0 && *libc::__errno_location() != libc::ENOENT {
                return Err(std::io::Error::last_os_error());
            }
        }
    }
    Ok(())
}

/// Pass the first `limit` bytes of `from` (a sandboxed agent's stdout and stderr) on to
/// this process's stderr, whole lines only, and count the rest; say how much was dropped
/// once the agent closes it.
fn pass_on_bounded(from: impl std::io::Read, pid: u32, limit: u64) {
    use std::io::{BufRead, Read, Write};
    let mut reader = std::io::BufReader::new(from);
    let (mut passed, mut dropped) = (0u64, 0u64);
    let mut line = Vec::new();
    loop {
        line.clear();
        // A line is read at most 4 KiB at a time: an endless line is bounded too.
        match Read::by_ref(&mut reader)
            .take(4096)
            .read_until(b'\n', &mut line)
        {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                if passed + n as u64 <= limit {
                    passed += n as u64;
                    let _ = std::io::stderr().write_all(&line);
                } else {
                    dropped += n as u64;
                }
            }
        }
    }
    if dropped > 0 {
        tracing::warn!(
            "sandboxed agent {pid}: {dropped} bytes of its output dropped (past the first {limit})"
        );
    }
}
