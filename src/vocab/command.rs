//! What clients may ask of the control thread.

use serde::{Deserialize, Serialize};

/// A command a client may send (protocol `command` message).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    /// Mesh back to its rest pose; agents walk back (`hard: false`) or jump there.
    Reset {
        /// Move agents instantly.
        #[serde(default)]
        hard: bool,
    },
    /// Change the number of agents (resets the crowd).
    SetAgentCount {
        /// New count (1 ..= the configured maximum).
        count: u32,
    },
    /// Switch to a formation of the config's library (mesh-formation-control
    /// section 7.3: "a basic button interface"), or `start`.
    SetFormation {
        /// Formation name.
        formation: String,
    },
    /// Freeze agents.
    Pause,
    /// Unfreeze agents.
    Resume,
}

/// Identifies a connected client.
pub type ClientId = u64;

/// A command travelling from the publisher to the control thread.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandRequest {
    /// Who sent it.
    pub client: ClientId,
    /// The client's id for the command, echoed in the reply.
    pub id: serde_json::Value,
    /// The command.
    pub command: Command,
}
