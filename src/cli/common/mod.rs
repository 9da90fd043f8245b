//! What every command family shares: output that handles a closed pipe, finding
//! and loading the config, starting and supervising the daemon, the socket client.
//! Nothing here imports a family.

pub mod config;
pub mod journal;
pub mod output;
pub mod process;
pub mod running;
pub mod socket;
