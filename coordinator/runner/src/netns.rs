//! A second host on this machine, for tests and benchmarks of agents over the network:
//! a network namespace joined to this one by a veth pair, made with `ip netns` (iproute2;
//! needs root). Processes started in it also get a mount namespace of their own with a
//! fresh /dev/shm, so nothing is shared with this host but the veth link. Removed, with
//! the link, when dropped.

use std::net::Ipv4Addr;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};

use anyhow::{Context, bail};

static NEXT: AtomicU32 = AtomicU32::new(0);

/// A network namespace with one veth link to this host's namespace.
pub struct NetnsHost {
    /// The namespace's name.
    pub name: String,
    /// This host's end of the veth pair.
    pub local_link: String,
    /// This host's address on the link.
    pub local_ip: Ipv4Addr,
    /// The test host's address on the link.
    pub remote_ip: Ipv4Addr,
}

fn ip(args: &[&str]) -> anyhow::Result<()> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .with_context(|| format!("ip {}: iproute2 is needed", args.join(" ")))?;
    if !out.status.success() {
        bail!(
            "ip {}: {} (network namespaces need root)",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(())
}

impl NetnsHost {
    /// A new namespace with a veth link, addresses on a /30 of its own, and loopback up.
    pub fn new() -> anyhow::Result<Self> {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        let tag = format!("{:x}", (pid % 0xffff) * 16 + n % 16);
        let name = format!("fmt-{tag}");
        let local_link = format!("fv{tag}a");
        let remote_link = format!("fv{tag}b");
        // 10.(200 + n % 50).(pid % 250).{1,2}: distinct for the tests of one process.
        let (a, b) = (200 + (n % 50) as u8, (pid % 250) as u8);
        let local_ip = Ipv4Addr::new(10, a, b, 1);
        let remote_ip = Ipv4Addr::new(10, a, b, 2);
        let _ = Command::new("ip")
            .args(["netns", "del", &name])
            .stderr(Stdio::null())
            .status();
        ip(&["netns", "add", &name])?;
        let host = Self {
            name: name.clone(),
            local_link: local_link.clone(),
            local_ip,
            remote_ip,
        };
        // From here on, a failure removes what was made (drop).
        ip(&[
            "link",
            "add",
            &local_link,
            "type",
            "veth",
            "peer",
            "name",
            &remote_link,
        ])?;
        ip(&["link", "set", &remote_link, "netns", &name])?;
        ip(&["addr", "add", &format!("{local_ip}/30"), "dev", &local_link])?;
        ip(&["link", "set", &local_link, "up"])?;
        let inside = |args: &[&str]| {
            let mut all = vec!["netns", "exec", &name, "ip"];
            all.extend_from_slice(args);
            ip(&all)
        };
        inside(&[
            "addr",
            "add",
            &format!("{remote_ip}/30"),
            "dev",
            &remote_link,
        ])?;
        inside(&["link", "set", &remote_link, "up"])?;
        inside(&["link", "set", "lo", "up"])?;
        Ok(host)
    }

    /// Start `program args` on the test host, in a mount namespace of its own with a
    /// fresh /dev/shm. The child is the program itself (every wrapper execs).
    pub fn spawn(&self, program: &std::path::Path, args: &[String]) -> anyhow::Result<Child> {
        Command::new("ip")
            .args([
                "netns",
                "exec",
                &self.name,
                "unshare",
                "--mount",
                "--propagation",
                "private",
            ])
            .args([
                "sh",
                "-c",
                "mount -t tmpfs tmpfs /dev/shm && exec \"$0\" \"$@\"",
            ])
            .arg(program)
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .with_context(|| format!("starting {} in {}", program.display(), self.name))
    }

    /// Take the link down (from this host's end) or up again.
    pub fn set_link(&self, up: bool) -> anyhow::Result<()> {
        ip(&[
            "link",
            "set",
            &self.local_link,
            if up { "up" } else { "down" },
        ])
    }
}

impl Drop for NetnsHost {
    fn drop(&mut self) {
        // Deleting the namespace deletes the veth pair with it.
        let _ = Command::new("ip")
            .args(["link", "del", &self.local_link])
            .status();
        let _ = Command::new("ip")
            .args(["netns", "del", &self.name])
            .status();
    }
}
