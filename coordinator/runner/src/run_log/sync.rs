//! Syncing the log to the disk once a second without holding up the step loop
//! ([`BackgroundSync`]).
//!
//! A step's chunk is in the file (the kernel's page cache) when the step ends, which is
//! all a crash of the coordinator needs; `fsync` only bounds what a power cut costs. On
//! this project's 2-vCPU machines one `fsync` of a second of `swarm200`'s log (about
//! 2.5 MB) held the loop for tens of milliseconds, so a thread of its own does it.

use std::fs::File;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::thread::JoinHandle;
use std::time::Duration;

/// A thread that syncs a file's data to the disk every `period` while something was
/// written since the last sync ([`Self::note_written`]); stopped (and joined) on drop.
pub struct BackgroundSync {
    written: Arc<AtomicBool>,
    stop: Option<mpsc::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl BackgroundSync {
    /// Start syncing `file` (a handle of its own on the log) every `period`.
    pub fn start(file: File, period: Duration) -> std::io::Result<Self> {
        let written = Arc::new(AtomicBool::new(false));
        let (stop, stopped) = mpsc::channel::<()>();
        let flag = Arc::clone(&written);
        let thread = std::thread::Builder::new()
            .name("run-log-sync".into())
            .spawn(move || {
                while let Err(RecvTimeoutError::Timeout) = stopped.recv_timeout(period) {
                    if flag.swap(false, Ordering::AcqRel)
                        && let Err(e) = file.sync_data()
                    {
                        tracing::warn!("syncing the run log: {e}");
                    }
                }
            })?;
        Ok(Self {
            written,
            stop: Some(stop),
            thread: Some(thread),
        })
    }

    /// Something was written: the next round syncs it.
    pub fn note_written(&self) {
        self.written.store(true, Ordering::Release);
    }
}

impl Drop for BackgroundSync {
    fn drop(&mut self) {
        // Dropping the sender ends the thread's wait at once.
        self.stop.take();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_file(name: &str) -> (std::path::PathBuf, File) {
        let path = std::env::temp_dir().join(format!("run-log-sync-{name}-{}", std::process::id()));
        let file = File::create(&path).expect("a file");
        (path, file)
    }

    #[test]
    fn what_was_written_is_synced_by_the_thread() {
        let (path, file) = scratch_file("synced");
        let sync = BackgroundSync::start(file, Duration::from_millis(5)).expect("start");
        sync.note_written();
        // The thread takes the mark when it syncs.
        while sync.written.load(Ordering::Acquire) {
            std::thread::sleep(Duration::from_millis(1));
        }
        drop(sync);
        let _ = std::fs::remove_file(path);
    }

    #[test]
    fn dropping_stops_the_thread_without_waiting_for_its_period() {
        let (path, file) = scratch_file("stopped");
        // Were the drop to wait for the period, this test would hang for an hour.
        let sync = BackgroundSync::start(file, Duration::from_secs(3600)).expect("start");
        sync.note_written();
        drop(sync);
        let _ = std::fs::remove_file(path);
    }
}
