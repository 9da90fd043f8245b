//! The slow work the control thread hands off: assignment solves and formation
//! switches, each on a worker thread of its own at nice 10.

use crate::crowd::assign::{Assigner, PointMetric};
use crate::crowd::control::{PreparedSwitch, SwitchRequest};
use crate::crowd::environment::{Planner, PlannerParams, Scene};
use crate::geom::Vec2;
use crate::rt::monotonic_now;
use crossbeam_channel::{Receiver, Sender};
use std::sync::Arc;

/// An assignment request and, once solved, its answer. Two of these circulate
/// between the control thread and the worker, so nothing is allocated per solve.
#[derive(Clone, Debug, Default)]
pub struct AssignJob {
    /// Crowd generation the state belongs to.
    pub generation: u64,
    /// Tick whose state this is.
    pub seq: u64,
    /// Agent positions (m).
    pub agents: Vec<Vec2>,
    /// Goal positions (m).
    pub goals: Vec<Vec2>,
    /// Scene time of the tick (s): where moving obstacles are.
    pub t_scene_s: f64,
    /// The scene the tick ran in and the planner parameters for it (`None`: no
    /// scene, Euclidean costs). The worker plans over exactly this scene, building
    /// a new planner when it differs from the last job's.
    pub environment: Option<(Arc<Scene>, PlannerParams)>,
    /// Answer: goal index per agent.
    pub goal_of: Vec<u32>,
    /// Answer with a scene: each agent's waypoint around obstacles (NaN: none).
    pub waypoints: Vec<Vec2>,
    /// Whether the solve succeeded.
    pub ok: bool,
    /// Solve time (µs).
    pub solve_us: u64,
}

/// The assignment worker: Euclidean costs ([`Assigner`]) without a scene, travel
/// costs and waypoints ([`Planner`]) with one. It plans over the scene each job
/// names, building a new planner here (not on the control thread) when the scene or
/// its parameters differ from the last job's, so a reloaded scene is planned for
/// from the first job solved in it.
pub(super) fn assignment_worker(
    cost: PointMetric,
    jobs: Receiver<Box<AssignJob>>,
    results: Sender<Box<AssignJob>>,
) {
    crate::rt::make_background("assignment worker");
    let mut assigner = Assigner::new(cost);
    let mut environment: Option<(Arc<Scene>, PlannerParams)> = None;
    let mut planner: Option<Planner> = None;
    let mut generation = u64::MAX;
    let mut failures = 0u64;
    for mut job in jobs.iter() {
        let t0 = monotonic_now();
        let same = match (&job.environment, &environment) {
            (Some((a, pa)), Some((b, pb))) => Arc::ptr_eq(a, b) && pa == pb,
            (None, None) => true,
            _ => false,
        };
        if !same {
            environment.clone_from(&job.environment);
            planner = environment
                .as_ref()
                .and_then(|(scene, params)| crate::engine::planner_for(scene, *params));
            generation = u64::MAX;
        }
        if job.generation != generation {
            assigner.forget();
            if let Some(p) = &mut planner {
                p.forget();
            }
            generation = job.generation;
        }
        let AssignJob {
            agents,
            goals,
            goal_of,
            waypoints,
            t_scene_s,
            ..
        } = &mut *job;
        let solved = match &mut planner {
            Some(p) => p
                .plan(agents, goals, *t_scene_s, goal_of, waypoints)
                .map_err(|e| e.to_string()),
            None => {
                waypoints.clear();
                assigner
                    .solve(agents, goals, goal_of)
                    .map_err(|e| e.to_string())
            }
        };
        job.ok = match solved {
            Ok(()) => true,
            Err(e) => {
                failures += 1;
                if failures.is_power_of_two() {
                    log::warn!("internal: assignment failed ({failures} times): {e}");
                }
                false
            }
        };
        job.solve_us = monotonic_now().saturating_since(t0).0;
        if results.send(job).is_err() {
            break;
        }
    }
}

/// The formation thread: prepares formation switches (the new mesh, its goal
/// samples, the least-effort pairing; [`SwitchRequest::prepare`]) so the control
/// thread never does that slow work. At nice 10, like the assignment worker.
pub(super) fn formation_worker(
    requests: Receiver<Box<SwitchRequest>>,
    done: Sender<Box<PreparedSwitch>>,
) {
    crate::rt::make_background("formation");
    for r in requests.iter() {
        if done.send(Box::new(r.prepare())).is_err() {
            break;
        }
    }
}
