//! Threads and queues: input → control → outputs, and the workers.
//!
//! ```text
//!  input thread ──FrameQueue──► control thread ──Outputs──► output threads ──► clients
//!  (one per source)  bounded      (Engine::tick)   one bounded   (publish::Output: the
//!                                    │  ▲          queue each     Unix socket, ...)
//!                          AssignJob │  │ AssignJob (solved)
//!                                    ▼  │
//!                              assignment worker   (and the formation thread)
//! ```
//! The supervisor (the thread that called [`Daemon::start`]) merges the stage
//! statistics once per interval, publishes `stats`, reloads the config and feeds the
//! systemd watchdog from the control thread's heartbeat.
//!
//! Every channel states its policy where it is created (`daemon.rs`).

mod client_touch;
mod control;
mod daemon;
pub mod device;
mod error;
mod outputs;
mod preflight;
mod queue;
mod reload;
mod report;
mod sources;
pub mod timing;
mod touch_sources;
mod workers;

pub use client_touch::{CLIENT_TOUCH_TIMEOUT_US, MAX_TOUCHING_CLIENTS};
pub use control::{ControlStats, INTERNAL_CLIENT};
pub use daemon::{Daemon, DaemonOptions, COMMAND_CAPACITY, SHUTDOWN_BUDGET_MS};
pub use error::Error;
pub use outputs::socket_options;
pub use preflight::{online_cpus, preflight, Finding, Preflight, Severity};
pub use queue::{FrameQueue, InputCounters, BACKLOG_FRAMES};
pub use sources::{sources_from_config, SourceSpec};
pub use touch_sources::{TouchSources, WebSocketTouch};
pub use workers::AssignJob;
