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
    /// The config has no input.
    #[error("the config has no inputs: add a Replay(...) input")]
    NoInputs,
}
