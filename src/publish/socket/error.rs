//! Why the socket could not be set up.

use std::path::PathBuf;

/// Why the socket could not be set up.
///
/// Each message names the path and says everything, its cause included; the cause
/// is also the error's `source`, and the command line writes it once.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Another process (probably another crowdtouch) is listening on the path.
    #[error("{path}: another process is already listening on this socket (is crowdtouch already running?)")]
    InUse {
        /// Socket path.
        path: PathBuf,
    },
    /// Something other than a socket is at the path; it is left alone.
    #[error("{path}: is {kind}, not a socket; refusing to replace it")]
    NotASocket {
        /// The path.
        path: PathBuf,
        /// What is there (`a directory`, `a regular file`, `a symbolic link`, ...).
        kind: &'static str,
    },
    /// The path does not fit a Unix socket address.
    #[error(
        "{path}: socket path is {bytes} bytes, more than the {max} a Unix socket address holds"
    )]
    PathTooLong {
        /// The path.
        path: PathBuf,
        /// Its length.
        bytes: usize,
        /// The most a socket address holds.
        max: usize,
    },
    /// The directory the socket is to be created in is missing or is not a
    /// directory.
    #[error("{path}: the socket's directory {} {problem}", dir.display())]
    NoDirectory {
        /// Socket path.
        path: PathBuf,
        /// Its directory.
        dir: PathBuf,
        /// `does not exist` or `is not a directory`.
        problem: &'static str,
    },
    /// `bind` failed.
    #[error("{path}: cannot bind the socket: {source}")]
    Bind {
        /// Socket path.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The socket's mode could not be set.
    #[error("{path}: cannot set socket mode {mode:04o}: {source}")]
    Permissions {
        /// Socket path.
        path: PathBuf,
        /// Mode asked for.
        mode: u32,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// A user or group listed in `socket.privileged` does not exist (or cannot be
    /// looked up).
    #[error("{kind} `{name}` in socket.privileged.{kind}s: {reason}")]
    UnknownPeer {
        /// `user` or `group`.
        kind: &'static str,
        /// As configured.
        name: String,
        /// Why it cannot be resolved.
        reason: String,
    },
    /// The configured group does not exist.
    #[error("socket group `{group}` does not exist (config socket.group)")]
    UnknownGroup {
        /// Group name.
        group: String,
    },
    /// The group database could not be read.
    #[error("socket group `{group}` cannot be looked up: {source}")]
    GroupLookup {
        /// Group name.
        group: String,
        /// Cause.
        #[source]
        source: nix::errno::Errno,
    },
    /// The socket could not be given to the configured group.
    #[error("{path}: cannot give the socket to group `{group}`: {source}")]
    Group {
        /// Socket path.
        path: PathBuf,
        /// Group name.
        group: String,
        /// Cause (`EPERM` when the daemon is not a member of the group).
        #[source]
        source: nix::errno::Errno,
    },
    /// Another I/O step failed.
    #[error("{path}: cannot {op}: {source}")]
    Io {
        /// Path involved.
        path: PathBuf,
        /// What was being done (`remove the stale socket`, ...).
        op: &'static str,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}
