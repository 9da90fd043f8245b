//! The engine's formation-transform state (`transform.rs` drives it): the settings
//! from the config, a request out on the formation thread, the run in progress, the
//! mesh being rebuilt after it, and what is published about it.

use super::params::{ap_params, move_params, pair_cost};
use super::pool::ArcPool;
use crate::config::Config;
use crate::crowd::motion::RemeshRequest;
use crate::crowd::transform::{
    ApParams, MoveParams, PairCost, StepReport, TransformRequest, TransformRun,
};
use crate::geom::Vec2;
use crate::vocab::{FormationMethod, TransformSummary, TransformView};
use std::sync::Arc;

/// The config's transform settings.
#[derive(Clone, Debug)]
pub(super) struct TransformSettings {
    /// `formations.method`.
    pub(super) method: FormationMethod,
    /// `formations.cost` with `formations.lambda`.
    pub(super) cost: PairCost,
    /// Its wire name.
    pub(super) cost_name: &'static str,
    /// `formations.transform` (the radius is set when a run starts).
    pub(super) moves: MoveParams,
    /// `formations.subgroups` (`None`: off).
    pub(super) ap: Option<ApParams>,
    /// `formations.gestures`: recognised classes that start a transform.
    pub(super) gestures: Vec<(String, String)>,
}

impl TransformSettings {
    pub(super) fn from_config(cfg: &Config, radius_m: f64) -> TransformSettings {
        TransformSettings {
            method: cfg.formations.method,
            cost: pair_cost(cfg),
            cost_name: cfg.formations.cost.as_str(),
            moves: move_params(cfg, radius_m),
            ap: ap_params(cfg),
            gestures: cfg
                .formations
                .gestures
                .iter()
                .map(|g| (g.class.clone(), g.formation.clone()))
                .collect(),
        }
    }
}

/// A transform asked for, being prepared.
#[derive(Clone, Debug)]
pub(super) struct PendingTransform {
    /// The formation.
    pub(super) name: String,
    /// The checkpoint that asked, if one did.
    pub(super) checkpoint: Option<String>,
    /// `set_formation`'s `duration` (s), if given.
    pub(super) duration_s: Option<f64>,
}

/// A transform driving the agents.
#[derive(Debug)]
pub(super) struct RunningTransform {
    /// The formation.
    pub(super) name: Arc<str>,
    /// The checkpoint that asked, if one did.
    pub(super) checkpoint: Option<String>,
    /// The run (its targets are the snapshot's goals).
    pub(super) run: TransformRun,
    /// Subgroups of the plan.
    pub(super) subgroups: u32,
    /// Each agent's subgroup (published with every progress message).
    pub(super) agent_subgroups: Arc<Vec<u32>>,
    /// The pairing cost's wire name.
    pub(super) cost_name: &'static str,
    /// The desired speed it runs at (m/s).
    pub(super) speed_m_s: f64,
    /// The last step's report.
    pub(super) last: StepReport,
    /// Time ticked since the last step (s): a tick sooner than
    /// [`MIN_TRANSFORM_STEP_S`] after the last step leaves it to the next.
    pub(super) owed_s: f64,
}

/// The shortest transform step (s), a little under the 120 Hz tick: the control
/// thread also ticks on every input frame (about 230 ticks a second with a
/// 120 Hz device), and a step costs the same however short it is, so steps are
/// taken at the timer's rate and a tick between them publishes the crowd as the
/// last step left it.
pub(super) const MIN_TRANSFORM_STEP_S: f64 = 1.0 / 125.0;

/// After a run: the agents hold still while the direct-control mesh is rebuilt
/// around them.
#[derive(Debug)]
pub(super) struct Remeshing {
    /// The formation to announce when the mesh is in (`None`: a touch ended the
    /// run; the crowd is in no library formation).
    pub(super) announce: Option<(String, Option<String>)>,
    /// Where each agent holds (m).
    pub(super) hold: Vec<Vec2>,
}

/// The engine's transforms (see the module doc).
pub(super) struct Transforms {
    pub(super) settings: TransformSettings,
    /// Bumped by every request, a touch, a reset or a resize: a prepared
    /// transform or rebuilt mesh of another epoch is stale.
    pub(super) epoch: u64,
    /// The request being prepared.
    pub(super) pending: Option<PendingTransform>,
    /// A request for the formation thread, until the pipeline takes it.
    pub(super) outbox: Option<TransformRequest>,
    /// A mesh to rebuild on the formation thread, until the pipeline takes it.
    pub(super) remesh_outbox: Option<RemeshRequest>,
    /// The run in progress.
    pub(super) running: Option<RunningTransform>,
    /// The mesh being rebuilt after a run.
    pub(super) remeshing: Option<Remeshing>,
    /// Prepared in the tick (replays) rather than on the formation thread.
    pub(super) inline: bool,
    /// Recycled progress messages.
    pub(super) views: ArcPool<TransformView>,
    /// This tick's progress message.
    pub(super) view: Option<Arc<TransformView>>,
    /// A summary to publish with this tick.
    pub(super) ended: Option<Arc<TransformSummary>>,
    /// Transforms started since start.
    pub(super) started: u64,
    /// The last summary.
    pub(super) last: Option<Arc<TransformSummary>>,
}

impl Transforms {
    pub(super) fn new(cfg: &Config, radius_m: f64) -> Transforms {
        Transforms {
            settings: TransformSettings::from_config(cfg, radius_m),
            epoch: 0,
            pending: None,
            outbox: None,
            remesh_outbox: None,
            running: None,
            remeshing: None,
            inline: true,
            views: ArcPool::new(),
            view: None,
            ended: None,
            started: 0,
            last: None,
        }
    }

    /// Whether a transform runs or its mesh is being rebuilt: the agents are not
    /// the direct controller's.
    pub(super) fn active(&self) -> bool {
        self.running.is_some() || self.remeshing.is_some()
    }

    /// Whether anything is asked for, running or being rebuilt.
    pub(super) fn busy(&self) -> bool {
        self.active() || self.pending.is_some() || self.outbox.is_some()
    }

    /// The formation the crowd is going to (one being prepared, a run, or one
    /// whose mesh is being rebuilt).
    pub(super) fn target(&self) -> Option<&str> {
        self.pending
            .as_ref()
            .map(|p| p.name.as_str())
            .or(self.running.as_ref().map(|r| &*r.name))
            .or(self
                .remeshing
                .as_ref()
                .and_then(|m| m.announce.as_ref())
                .map(|(name, _)| name.as_str()))
    }
}
