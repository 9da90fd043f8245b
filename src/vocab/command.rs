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
        /// How: the config's `formations.method` when not given.
        #[serde(default)]
        method: Option<FormationMethod>,
        /// About how long a transform takes (s): its desired walking speed is set
        /// from it. Not given: `formations.transform.desired_speed_m_s`.
        #[serde(default)]
        duration: Option<f64>,
    },
    /// Freeze agents.
    Pause,
    /// Unfreeze agents.
    Resume,
    /// Edit mode (crowd-motion-editing): load a track file of the daemon's edit
    /// directory (the config's `edit.dir`); the crowd plays its people and
    /// fingers edit their tracks. A client names an entry, never a path.
    #[serde(rename = "edit.load")]
    EditLoad {
        /// The entry's name (JSON Lines, CSV `t,id,x,y` or ETH/UCY `frame id x
        /// y`): `A-Z a-z 0-9 . _ -`, no `/`, not starting with `.`. (The
        /// message's `name` is the command's.)
        entry: String,
    },
    /// Take back the last edit.
    #[serde(rename = "edit.undo")]
    EditUndo,
    /// Write the edited tracks (JSON Lines) to entry `entry` of the edit
    /// directory, or back to the entry they were loaded from (`overwrite` and the
    /// config's `edit.allow_overwrite` both needed to replace a file).
    #[serde(rename = "edit.save")]
    EditSave {
        /// The entry (a new file unless `overwrite`); `None`: the loaded entry.
        #[serde(default)]
        entry: Option<String>,
        /// Replace an existing entry (only when the config allows it).
        #[serde(default)]
        overwrite: bool,
    },
    /// A temporal edit (section 3.3) of the people `ids`, or of the selection
    /// when there is one, or of everyone: each one's time node nearest `at_s`
    /// goes to `to_s`, the first and last nodes stay (the paper's Fig. 14 retimes
    /// three people this way).
    #[serde(rename = "edit.retime")]
    EditRetime {
        /// The node nearest this time (s).
        at_s: f64,
        /// Goes here (s).
        to_s: f64,
        /// Only these people (ids, at most [`MAX_SELECT_IDS`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ids: Option<Vec<u64>>,
    },
    /// Selects people for the next grab (crowd-motion-editing section 3.2's
    /// selection): those with a sample inside `lasso` (metres, a closed polygon)
    /// and within `window_s` (seconds), among `ids`; every criterion is optional,
    /// and none clears the selection. The next grab on a selected person grabs
    /// the selection's samples in the window instead of the person's group.
    #[serde(rename = "edit.select")]
    EditSelect {
        /// The polygon, at least 3 and at most [`MAX_LASSO_VERTICES`] points `[x, y]` (m).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        lasso: Option<Vec<[f64; 2]>>,
        /// The time window `[start, end]` (s).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        window_s: Option<[f64; 2]>,
        /// Only these people (ids, at most [`MAX_SELECT_IDS`]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ids: Option<Vec<u64>>,
    },
    /// Keeps the edit shown as a preview (after a release or a retime).
    #[serde(rename = "edit.accept")]
    EditAccept,
    /// Leave edit mode: the crowd comes back.
    #[serde(rename = "edit.exit")]
    EditExit,
    /// `library collect`: the item shown is skipped; the next one is shown.
    #[serde(rename = "collect.skip")]
    CollectSkip,
    /// `library collect`: the last gesture recorded is removed from the library and
    /// its item asked for again.
    #[serde(rename = "collect.undo")]
    CollectUndo,
    /// `library collect`: the item's motion is shown again.
    #[serde(rename = "collect.again")]
    CollectAgain,
    /// `library collect`: a `collect` event with the session's state goes out now
    /// (a viewer that just connected learns where the session is).
    #[serde(rename = "collect.status")]
    CollectStatus,
    /// Touches from the client itself (a viewer page's mouse or fingers): the
    /// contacts down now on the client's own virtual surface, covering the table.
    /// A contact not listed any more is lifted; an empty list lifts them all.
    Touch {
        /// The contacts down, at most [`MAX_CLIENT_CONTACTS`].
        contacts: Vec<ClientContact>,
    },
}

/// Most points an `edit.select` lasso has.
pub const MAX_LASSO_VERTICES: usize = 1024;

/// Most ids an `edit.select` or `edit.retime` lists.
pub const MAX_SELECT_IDS: usize = 4096;

/// Most contacts one `touch` command lists.
pub const MAX_CLIENT_CONTACTS: usize = 10;

/// Largest contact id a client may use in a `touch` command.
pub const MAX_CLIENT_CONTACT_ID: u32 = 65_535;

/// One contact of a client's `touch` command, in table units.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClientContact {
    /// The client's id for the finger, `0..=`[`MAX_CLIENT_CONTACT_ID`], stable
    /// while it is down.
    pub id: u32,
    /// Horizontal position, `[0, 1]` left to right across the table.
    pub x: f64,
    /// Vertical position, `[0, 1]` top to bottom.
    pub y: f64,
}

/// How the crowd goes into a new formation.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FormationMethod {
    /// The formation transform of formation-transform (Xu et al. 2015): targets
    /// sampled in the shape, least-effort pairing, social forces with subgroups and
    /// mutual-information feedback; direct control resumes on the new shape when
    /// every agent arrived.
    Transform,
    /// The mesh switch (mesh-formation-control section 7.3): the new shape's mesh
    /// replaces the old one at once and the agents follow its goals.
    Mesh,
}

impl FormationMethod {
    /// The name on the wire and in files.
    pub fn as_str(self) -> &'static str {
        match self {
            FormationMethod::Transform => "transform",
            FormationMethod::Mesh => "mesh",
        }
    }
}

impl Command {
    /// The command's name on the wire.
    pub fn name(&self) -> &'static str {
        match self {
            Command::Reset { .. } => "reset",
            Command::SetAgentCount { .. } => "set_agent_count",
            Command::SetFormation { .. } => "set_formation",
            Command::Pause => "pause",
            Command::Resume => "resume",
            Command::EditLoad { .. } => "edit.load",
            Command::EditUndo => "edit.undo",
            Command::EditSave { .. } => "edit.save",
            Command::EditRetime { .. } => "edit.retime",
            Command::EditSelect { .. } => "edit.select",
            Command::EditAccept => "edit.accept",
            Command::EditExit => "edit.exit",
            Command::CollectSkip => "collect.skip",
            Command::CollectUndo => "collect.undo",
            Command::CollectAgain => "collect.again",
            Command::CollectStatus => "collect.status",
            Command::Touch { .. } => "touch",
        }
    }

    /// Every command name, in the order the protocol doc lists them.
    pub const NAMES: [&'static str; 17] = [
        "reset",
        "set_agent_count",
        "set_formation",
        "pause",
        "resume",
        "edit.load",
        "edit.undo",
        "edit.save",
        "edit.retime",
        "edit.select",
        "edit.accept",
        "edit.exit",
        "touch",
        "collect.skip",
        "collect.undo",
        "collect.again",
        "collect.status",
    ];
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
