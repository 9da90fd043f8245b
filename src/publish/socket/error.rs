//! Why the socket could not be set up.

use std::path::PathBuf;

/// Why the socket could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Another process (probably another crowdtouch) is listening on the path.
    #[error("{path}: another process is already listening on this socket (is crowdtouch already running?)")]
    InUse {
        /// Socket path.
        path: PathBuf,
    },
    /// Something other than a socket is at the path; it is left alone.
    #[error("{path}: exists and is not a socket; refusing to replace it")]
    NotASocket {
        /// The path.
        path: PathBuf,
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
    /// The configured group does not exist.
    #[error("socket group `{group}` does not exist (config socket.group)")]
    UnknownGroup {
        /// Group name.
        group: String,
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
