//! Why the daemon could not start.

use crate::input::recording::RecordingError;

/// Why the daemon could not start.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A recording named in the config could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The socket could not be set up.
    #[error(transparent)]
    Publish(#[from] crate::publish::Error),
    /// A TUIO output could not start (its target does not resolve).
    #[error(transparent)]
    TuioOutput(#[from] crate::publish::tuio::Error),
    /// A WebSocket output could not be set up.
    #[error(transparent)]
    WebSocket(#[from] crate::publish::websocket::Error),
    /// A thread could not be started.
    #[error("cannot start the {name} thread: {source}")]
    Thread {
        /// Which thread.
        name: &'static str,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// A TUIO input could not bind its port.
    #[error(transparent)]
    TuioInput(#[from] crate::input::tuio::Error),
    /// A TUIO input's listen address is not `ip:port` (the config check refuses it first).
    #[error("TUIO input: listen address must be ip:port, got {0:?}")]
    BadListen(String),
    /// A `library collect` session that cannot start.
    #[error("library collect: {0}")]
    Collect(String),
}
