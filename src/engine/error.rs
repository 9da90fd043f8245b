//! Why a command or a formation switch could not be applied. The messages go to the
//! client that asked (as an `error` reply) and to the log.

use crate::crowd::mesh::MeshError;
use crate::crowd::transform::TransformError;

/// Why a client command could not be applied.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CommandError {
    /// `set_agent_count` outside `1..=max`.
    #[error("agent count {count} is out of range 1..={max}")]
    AgentCount {
        /// Requested.
        count: u32,
        /// Maximum.
        max: u32,
    },
    /// `set_formation` named a formation the config does not define.
    #[error("no formation is called `{}`; the config defines {known}", shorten(.name))]
    UnknownFormation {
        /// The name asked for.
        name: String,
        /// The formations the config defines (`start, square, …`).
        known: String,
    },
    /// `set_formation`'s `duration` is not a positive number of seconds up to the
    /// limit.
    #[error("duration must be in (0, {max_s}] s, got {duration_s}")]
    Duration {
        /// Asked for (s).
        duration_s: f64,
        /// The longest (s).
        max_s: f64,
    },
    /// An edit-mode command that cannot be applied now (no tracks loaded, an edit
    /// under way, nothing to undo, bad arguments).
    #[error("{}", crate::located::EscapedLines(.0))]
    Edit(String),
    /// A `collect.*` command that cannot be applied now (no session, the session
    /// finished, nothing to undo).
    #[error("{0}")]
    Collect(&'static str),
    /// A command the control loop handles itself reached the engine (an internal bug).
    #[error("internal bug: `{0}` reached the engine")]
    NotHere(&'static str),
    /// The formation could not be laid out for the crowd (without the formation
    /// thread; with it, the failure is logged when the switch arrives).
    #[error("formation `{}` could not be built: {why}", shorten(.name))]
    FormationNotBuilt {
        /// The formation.
        name: String,
        /// Why.
        why: SwitchError,
    },
}

/// Why a formation switch could not be made; the crowd keeps its formation.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SwitchError {
    /// A checkpoint names a formation the library does not hold.
    #[error("the config defines no formation of that name")]
    NotInLibrary,
    /// The shape could not be meshed for the crowd.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A transform could not be prepared (targets sampled, agents paired).
    #[error(transparent)]
    Transform(#[from] TransformError),
}

/// A client-given name as shown in a message: at most 64 characters, `…` when cut,
/// control characters escaped.
fn shorten(name: &str) -> String {
    let shown: String = name.chars().take(64).collect();
    let cut = if shown.len() < name.len() { "…" } else { "" };
    format!("{}{cut}", crate::located::Escaped(&shown))
}
