//! Hotplug: device nodes appearing, changing and going away, seen through inotify.
//!
//! A [`Watcher`] watches `ROOT/dev/input` (for `event*`) and `ROOT/dev` (for
//! `hidraw*`) for files created, moved in, deleted and changed (`IN_ATTRIB`: udev
//! setting group, mode or ACL), and, when udev runs, `ROOT/run/udev/data` for new
//! records, because a record appears when udev has finished with a node. Waiting is a
//! `poll` on the inotify descriptor: no polling loop, no sleeps.
//!
//! A new node goes through three states before it can be read:
//!
//! ```text
//!   created by the kernel ──► processed by udev ──► readable by us
//!   (devtmpfs, mode 0600,     (db record written,   (open succeeds; EACCES until
//!    owner root)               rules have run)       the rule's group/mode/ACL lands)
//! ```
//!
//! [`Watcher::wait_ready`] waits through them, re-checking after every inotify event,
//! and says which state it was stuck in when the time runs out.

use crate::input::udev::UdevDb;
use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags, PollTimeout};
use nix::sys::inotify::{AddWatchFlags, InitFlags, Inotify, InotifyEvent, WatchDescriptor};
use std::collections::VecDeque;
use std::os::fd::{AsFd, BorrowedFd};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A change to a device node or to udev's database.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HotplugEvent {
    /// A node appeared (created or moved in).
    Added(PathBuf),
    /// A node's attributes changed (udev set its group, mode or ACL).
    Changed(PathBuf),
    /// A node went away.
    Removed(PathBuf),
    /// udev wrote a database record (`ROOT/run/udev/data/c<major>:<minor>`): it has
    /// processed that device.
    UdevProcessed(PathBuf),
    /// The kernel's inotify queue overflowed and events were lost: rescan.
    Overflow,
}

/// The inotify machinery failed.
#[derive(Debug, thiserror::Error)]
pub enum HotplugError {
    /// inotify could not be set up (too many instances?).
    #[error("inotify: cannot initialise: {source}")]
    Init {
        /// Cause.
        #[source]
        source: Errno,
    },
    /// A directory could not be watched.
    #[error("{dir}: cannot watch for device nodes: {source}")]
    Watch {
        /// The directory.
        dir: PathBuf,
        /// Cause.
        #[source]
        source: Errno,
    },
    /// Reading inotify events failed.
    #[error("inotify: read failed: {source}")]
    Read {
        /// Cause.
        #[source]
        source: Errno,
    },
    /// Waiting for inotify events failed.
    #[error("inotify: poll failed: {source}")]
    Poll {
        /// Cause.
        #[source]
        source: Errno,
    },
}

/// Why a node did not become ready. Every variant names the node and how long was
/// waited.
#[derive(Debug, thiserror::Error)]
pub enum ReadyError {
    /// The node never appeared.
    #[error("{node}: did not appear within {waited_ms} ms")]
    Missing {
        /// The node.
        node: PathBuf,
        /// Time waited (ms).
        waited_ms: u64,
    },
    /// udev never wrote the node's database record.
    #[error("{node}: udev has not processed it after {waited_ms} ms (no {record}); is systemd-udevd running?")]
    NotProcessed {
        /// The node.
        node: PathBuf,
        /// The record that did not appear.
        record: PathBuf,
        /// Time waited (ms).
        waited_ms: u64,
    },
    /// The node stayed unreadable.
    #[error("{node}: permission denied, still after waiting {waited_ms} ms for udev to set its group and mode — is the crowdtouch udev rule installed, and is the service user in its group? ({source})")]
    PermissionDenied {
        /// The node.
        node: PathBuf,
        /// Time waited (ms).
        waited_ms: u64,
        /// The last open error.
        #[source]
        source: std::io::Error,
    },
    /// Opening failed for another reason (unplugged, busy, ...).
    #[error(transparent)]
    Open(#[from] crate::input::Error),
    /// The watcher failed.
    #[error(transparent)]
    Watch(#[from] HotplugError),
}

/// Flags for the node directories.
fn node_mask() -> AddWatchFlags {
    AddWatchFlags::IN_CREATE
        | AddWatchFlags::IN_ATTRIB
        | AddWatchFlags::IN_DELETE
        | AddWatchFlags::IN_MOVED_TO
        | AddWatchFlags::IN_MOVED_FROM
        | AddWatchFlags::IN_ONLYDIR
}

/// Flags for udev's database directory (`IN_CLOSE_WRITE` too, for records written in
/// place rather than renamed into place).
fn data_mask() -> AddWatchFlags {
    AddWatchFlags::IN_CREATE
        | AddWatchFlags::IN_MOVED_TO
        | AddWatchFlags::IN_CLOSE_WRITE
        | AddWatchFlags::IN_ONLYDIR
}

/// Whether `name` is `prefix` followed by one or more digits.
fn numbered(name: &str, prefix: &str) -> bool {
    name.strip_prefix(prefix)
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

/// Whether `name` is a character-device record name (`c13:69`).
fn record_name(name: &str) -> bool {
    name.strip_prefix('c').is_some_and(|rest| {
        rest.split_once(':').is_some_and(|(a, b)| {
            !a.is_empty()
                && !b.is_empty()
                && a.bytes().all(|c| c.is_ascii_digit())
                && b.bytes().all(|c| c.is_ascii_digit())
        })
    })
}

/// Watches for touch device nodes coming and going.
#[derive(Debug)]
pub struct Watcher {
    inotify: Inotify,
    root: PathBuf,
    dev_wd: WatchDescriptor,
    input_wd: Option<WatchDescriptor>,
    data_wd: Option<WatchDescriptor>,
    pending: VecDeque<HotplugEvent>,
}

impl AsFd for Watcher {
    /// The inotify descriptor, for callers that `poll` it with other descriptors
    /// (readable when [`Watcher::next`] has something).
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.inotify.as_fd()
    }
}

impl Watcher {
    /// Starts watching `ROOT/dev`, `ROOT/dev/input` (now, or as soon as it is
    /// created) and, when udev is present, `ROOT/run/udev/data`.
    ///
    /// # Errors
    /// [`HotplugError`] when inotify cannot be set up or `ROOT/dev` cannot be watched.
    pub fn new(root: &Path) -> Result<Watcher, HotplugError> {
        let inotify = Inotify::init(InitFlags::IN_NONBLOCK | InitFlags::IN_CLOEXEC)
            .map_err(|source| HotplugError::Init { source })?;
        let dev = root.join("dev");
        let dev_wd = inotify
            .add_watch(&dev, node_mask())
            .map_err(|source| HotplugError::Watch { dir: dev, source })?;
        let mut w = Watcher {
            inotify,
            root: root.to_path_buf(),
            dev_wd,
            input_wd: None,
            data_wd: None,
            pending: VecDeque::new(),
        };
        w.watch_input_dir(false)?;
        let udev = UdevDb::new(root);
        if udev.present() {
            let data = udev.data_dir();
            match w.inotify.add_watch(&data, data_mask()) {
                Ok(wd) => w.data_wd = Some(wd),
                Err(Errno::ENOENT) | Err(Errno::ENOTDIR) => {
                    log::debug!("{}: not there; not watching udev records", data.display())
                }
                Err(source) => return Err(HotplugError::Watch { dir: data, source }),
            }
        }
        Ok(w)
    }

    /// The root directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Adds the watch on `ROOT/dev/input` if it exists. With `announce`, queues
    /// `Added` for the `event*` nodes already in it (they may have been created before
    /// the watch was in place).
    fn watch_input_dir(&mut self, announce: bool) -> Result<(), HotplugError> {
        let dir = self.root.join("dev/input");
        match self.inotify.add_watch(&dir, node_mask()) {
            Ok(wd) => self.input_wd = Some(wd),
            Err(Errno::ENOENT) | Err(Errno::ENOTDIR) => return Ok(()),
            Err(source) => return Err(HotplugError::Watch { dir, source }),
        }
        if announce {
            let mut names: Vec<String> = std::fs::read_dir(&dir)
                .into_iter()
                .flatten()
                .filter_map(Result::ok)
                .filter_map(|e| e.file_name().into_string().ok())
                .filter(|n| numbered(n, "event"))
                .collect();
            names.sort();
            self.pending
                .extend(names.into_iter().map(|n| HotplugEvent::Added(dir.join(n))));
        }
        Ok(())
    }

    /// Turns one inotify event into zero or one hotplug event.
    fn translate(&mut self, ev: InotifyEvent) -> Result<(), HotplugError> {
        let m = ev.mask;
        if m.contains(AddWatchFlags::IN_Q_OVERFLOW) {
            self.pending.push_back(HotplugEvent::Overflow);
            return Ok(());
        }
        if m.contains(AddWatchFlags::IN_IGNORED) {
            // The watched directory went away (e.g. /dev/input removed).
            if Some(ev.wd) == self.input_wd {
                self.input_wd = None;
            }
            if Some(ev.wd) == self.data_wd {
                self.data_wd = None;
            }
            return Ok(());
        }
        let Some(name) = ev.name.as_ref().and_then(|n| n.to_str()) else {
            return Ok(());
        };
        let node_event = |path: PathBuf| {
            if m.intersects(AddWatchFlags::IN_CREATE | AddWatchFlags::IN_MOVED_TO) {
                Some(HotplugEvent::Added(path))
            } else if m.contains(AddWatchFlags::IN_ATTRIB) {
                Some(HotplugEvent::Changed(path))
            } else if m.intersects(AddWatchFlags::IN_DELETE | AddWatchFlags::IN_MOVED_FROM) {
                Some(HotplugEvent::Removed(path))
            } else {
                None
            }
        };
        let event = if ev.wd == self.dev_wd {
            if name == "input"
                && m.contains(AddWatchFlags::IN_ISDIR)
                && m.intersects(AddWatchFlags::IN_CREATE | AddWatchFlags::IN_MOVED_TO)
            {
                self.watch_input_dir(true)?;
                None
            } else if numbered(name, "hidraw") {
                node_event(self.root.join("dev").join(name))
            } else {
                None
            }
        } else if Some(ev.wd) == self.input_wd {
            numbered(name, "event")
                .then(|| node_event(self.root.join("dev/input").join(name)))
                .flatten()
        } else if Some(ev.wd) == self.data_wd {
            record_name(name)
                .then(|| HotplugEvent::UdevProcessed(UdevDb::new(&self.root).data_dir().join(name)))
        } else {
            None
        };
        self.pending.extend(event);
        Ok(())
    }

    /// Reads whatever inotify has, without blocking.
    fn drain(&mut self) -> Result<(), HotplugError> {
        loop {
            match self.inotify.read_events() {
                Ok(events) => {
                    for ev in events {
                        self.translate(ev)?;
                    }
                }
                Err(Errno::EAGAIN) => return Ok(()),
                Err(Errno::EINTR) => continue,
                Err(source) => return Err(HotplugError::Read { source }),
            }
        }
    }

    /// The next event, waiting at most `timeout` (blocked in `poll`); `Ok(None)` when
    /// the time ran out. `Duration::MAX` waits for ever.
    ///
    /// # Errors
    /// [`HotplugError::Read`] / [`HotplugError::Poll`] when inotify fails.
    pub fn next(&mut self, timeout: Duration) -> Result<Option<HotplugEvent>, HotplugError> {
        let deadline = Instant::now().checked_add(timeout);
        loop {
            if let Some(e) = self.pending.pop_front() {
                return Ok(Some(e));
            }
            self.drain()?;
            if !self.pending.is_empty() {
                continue;
            }
            let wait = match deadline {
                None => PollTimeout::NONE,
                Some(d) => {
                    let left = d.saturating_duration_since(Instant::now());
                    if left.is_zero() {
                        return Ok(None);
                    }
                    // Round up so a sub-millisecond remainder does not spin.
                    let ms = left.as_nanos().div_ceil(1_000_000);
                    PollTimeout::try_from(i32::try_from(ms).unwrap_or(i32::MAX))
                        .unwrap_or(PollTimeout::MAX)
                }
            };
            let mut fds = [PollFd::new(self.inotify.as_fd(), PollFlags::POLLIN)];
            match nix::poll::poll(&mut fds, wait) {
                Ok(_) | Err(Errno::EINTR) => {}
                Err(source) => return Err(HotplugError::Poll { source }),
            }
        }
    }

    /// Waits until `node` exists, udev has processed it (or udev is absent), and it
    /// opens (read-only for evdev; read-write for hidraw, as hidapi opens it).
    ///
    /// On `EACCES` it waits for the next change (udev setting group or mode) and tries
    /// again, until `timeout`.
    ///
    /// # Errors
    /// [`ReadyError`] saying which state the node was stuck in.
    pub fn wait_ready(
        &mut self,
        node: &Path,
        udev: &UdevDb,
        timeout: Duration,
    ) -> Result<(), ReadyError> {
        self.wait_ready_with(node, udev, timeout, open_node)
    }

    /// [`Watcher::wait_ready`] with the open check supplied (tests simulate an
    /// unprivileged user with it).
    ///
    /// # Errors
    /// As [`Watcher::wait_ready`].
    pub fn wait_ready_with(
        &mut self,
        node: &Path,
        udev: &UdevDb,
        timeout: Duration,
        mut open: impl FnMut(&Path) -> std::io::Result<()>,
    ) -> Result<(), ReadyError> {
        let start = Instant::now();
        let deadline = start.checked_add(timeout);
        loop {
            let stuck = match check(node, udev, &mut open)? {
                None => return Ok(()),
                Some(stuck) => stuck,
            };
            let left = deadline.map(|d| d.saturating_duration_since(Instant::now()));
            if left.is_some_and(|l| l.is_zero()) {
                let waited_ms = u64::try_from(start.elapsed().as_millis()).unwrap_or(u64::MAX);
                let node = node.to_path_buf();
                return Err(match stuck {
                    Stuck::Missing => ReadyError::Missing { node, waited_ms },
                    Stuck::NotProcessed(record) => ReadyError::NotProcessed {
                        node,
                        record,
                        waited_ms,
                    },
                    Stuck::Denied(source) => ReadyError::PermissionDenied {
                        node,
                        waited_ms,
                        source,
                    },
                });
            }
            // Any change (or the deadline) is a reason to look again.
            self.next(left.unwrap_or(Duration::MAX))?;
        }
    }
}

/// Where a node is stuck on its way to ready.
enum Stuck {
    Missing,
    NotProcessed(PathBuf),
    Denied(std::io::Error),
}

/// `Ok(None)` when ready.
fn check(
    node: &Path,
    udev: &UdevDb,
    open: &mut impl FnMut(&Path) -> std::io::Result<()>,
) -> Result<Option<Stuck>, ReadyError> {
    if !node.exists() {
        return Ok(Some(Stuck::Missing));
    }
    if udev.present() {
        if let Some((major, minor)) = udev.device_number(node) {
            if !udev.processed(major, minor) {
                return Ok(Some(Stuck::NotProcessed(udev.record_path(major, minor))));
            }
        }
    }
    match open(node) {
        Ok(()) => Ok(None),
        Err(e) if matches!(e.raw_os_error(), Some(nix::libc::EACCES | nix::libc::EPERM)) => {
            Ok(Some(Stuck::Denied(e)))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Some(Stuck::Missing)),
        Err(e) => Err(crate::input::Error::from_io(node, "open", e).into()),
    }
}

/// Opens the node the way its reader will (evdev read-only, hidraw read-write) and
/// closes it again.
fn open_node(node: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::OpenOptionsExt;
    let hidraw = node
        .file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.starts_with("hidraw"));
    std::fs::OpenOptions::new()
        .read(true)
        .write(hidraw)
        .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_CLOEXEC)
        .open(node)
        .map(drop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_filtered() {
        assert!(numbered("event12", "event"));
        assert!(!numbered("event", "event"));
        assert!(!numbered("mouse0", "event"));
        assert!(!numbered("event1x", "event"));
        assert!(numbered("hidraw0", "hidraw"));
        assert!(record_name("c13:69"));
        assert!(!record_name("c13"));
        assert!(!record_name(".#c13:69abc"));
        assert!(!record_name("b8:0"));
        assert!(!record_name("n3"));
    }
}
