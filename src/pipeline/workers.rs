//! The slow work the control thread hands off: assignment solves, formation
//! switches and crowd resizes, each on a worker thread of its own at nice 10.
//!
//! Every job can be given up: the control thread keeps [`Freshness`] up to date
//! (the crowd generation, the switch epoch, the resize ticket, after every command
//! and tick) and the shutdown raises its `stop`; a worker's solve polls it
//! ([`Cancel`]) and abandons a job whose input is stale or when the daemon stops.

use crate::crowd::assign::{Assigner, Cancel, PointMetric};
use crate::crowd::control::{PreparedResize, PreparedSwitch, ResizeRequest, SwitchRequest};
use crate::crowd::edit::io::{read_track_entry, write_track_entry, ReadOptions};
use crate::crowd::edit::TrackSet;
use crate::crowd::environment::{Planner, PlannerParams, Scene};
use crate::crowd::motion::{
    GestureJob, PreparedGesture, PreparedRemesh, PreparedWindow, RemeshRequest, Synthesiser,
};
use crate::crowd::transform::{PreparedTransform, TransformRequest};
use crate::engine::{CollectDone, CollectJob, EditDone, EditFileJob, EditJob};
use crate::geom::Vec2;
use crate::gesture::continuous::WindowBuffers;
use crate::gesture::knn::Searcher;
use crate::rt::monotonic_now;
use crate::vocab::ClientId;
use crate::vocab::Micros;
use crossbeam_channel::{Receiver, Sender};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// What the workers poll to give up a job: what is current on the control thread,
/// and whether the daemon is stopping. Written by the control thread (and `stop`
/// by the shutdown), read by the workers; relaxed atomics, no lock.
#[derive(Debug, Default)]
pub(super) struct Freshness {
    /// The engine's crowd generation: an assignment job of another is stale.
    generation: AtomicU64,
    /// The engine's switch epoch: a switch request of another is stale.
    switch_epoch: AtomicU64,
    /// The engine's resize ticket: a resize request of another is stale.
    resize_ticket: AtomicU64,
    /// The engine's transform epoch: a transform request of another is stale.
    transform_epoch: AtomicU64,
    /// When one of the three last changed (µs, CLOCK_MONOTONIC): the start of an
    /// abandoned job's abandonment latency.
    changed_us: AtomicU64,
    /// The daemon is stopping: every job is abandoned.
    stop: AtomicBool,
}

impl Freshness {
    /// Stores what is current; notes the time when something changed.
    pub(super) fn update(
        &self,
        generation: u64,
        switch_epoch: u64,
        resize_ticket: u64,
        transform_epoch: u64,
    ) {
        let g = self.generation.swap(generation, Ordering::Relaxed);
        let s = self.switch_epoch.swap(switch_epoch, Ordering::Relaxed);
        let r = self.resize_ticket.swap(resize_ticket, Ordering::Relaxed);
        let t = self
            .transform_epoch
            .swap(transform_epoch, Ordering::Relaxed);
        if (g, s, r, t) != (generation, switch_epoch, resize_ticket, transform_epoch) {
            self.changed_us.store(monotonic_now().0, Ordering::Relaxed);
        }
    }

    /// Every job is abandoned from now on.
    pub(super) fn stop(&self) {
        self.stop.store(true, Ordering::SeqCst);
    }

    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// Time since the input of an abandoned job went stale.
    fn since_change(&self) -> u64 {
        monotonic_now()
            .saturating_since(Micros(self.changed_us.load(Ordering::Relaxed)))
            .0
    }
}

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
    /// The solve was given up because the crowd changed meanwhile (or the daemon
    /// is stopping): `abandon_us` after the change, not a failure.
    pub abandoned: bool,
    /// Solve time (µs).
    pub solve_us: u64,
    /// With `abandoned`: from the change that made the job stale to the solve
    /// giving up (µs).
    pub abandon_us: u64,
}

/// The assignment worker: Euclidean costs ([`Assigner`]) without a scene, travel
/// costs and waypoints ([`Planner`]) with one. It plans over the scene each job
/// names, building a new planner here (not on the control thread) when the scene or
/// its parameters differ from the last job's, so a reloaded scene is planned for
/// from the first job solved in it. A solve whose crowd generation is no longer
/// the current one, or that is running when the daemon stops, is abandoned.
pub(super) fn assignment_worker(
    cost: PointMetric,
    jobs: Receiver<Box<AssignJob>>,
    results: Sender<Box<AssignJob>>,
    fresh: Arc<Freshness>,
) {
    crate::rt::make_background("assignment worker");
    let mut assigner = Assigner::new(cost);
    let mut environment: Option<(Arc<Scene>, PlannerParams)> = None;
    let mut planner: Option<Planner> = None;
    let mut generation = u64::MAX;
    let mut failures = 0u64;
    for mut job in jobs.iter() {
        if fresh.stopping() {
            break;
        }
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
        let wanted = job.generation;
        let stale = || fresh.stopping() || fresh.generation.load(Ordering::Relaxed) != wanted;
        let cancel = Cancel::new(&stale);
        let AssignJob {
            agents,
            goals,
            goal_of,
            waypoints,
            t_scene_s,
            ..
        } = &mut *job;
        let solved = match &mut planner {
            // Stale before it started: nothing to solve.
            _ if stale() => Err((true, String::new())),
            Some(p) => p
                .plan_cancellable(agents, goals, *t_scene_s, goal_of, waypoints, cancel)
                .map_err(|e| (e.is_cancelled(), e.to_string())),
            None => {
                waypoints.clear();
                assigner
                    .solve_cancellable(agents, goals, goal_of, cancel)
                    .map_err(|e| {
                        let cancelled = e == crate::crowd::assign::AssignError::Cancelled;
                        (cancelled, e.to_string())
                    })
            }
        };
        job.abandoned = false;
        job.ok = match solved {
            Ok(()) => true,
            Err((true, _)) => {
                job.abandoned = true;
                job.abandon_us = fresh.since_change();
                false
            }
            Err((false, e)) => {
                failures += 1;
                if failures.is_power_of_two() {
                    log::warn!("internal: assignment failed ({failures} times): {e}");
                }
                false
            }
        };
        job.solve_us = monotonic_now().saturating_since(t0).0;
        if fresh.stopping() || results.send(job).is_err() {
            break;
        }
    }
}

/// A job for the formation thread.
#[derive(Debug)]
pub(super) enum FormationJob {
    /// A formation switch to prepare.
    Switch(Box<SwitchRequest>),
    /// A new crowd size to prepare.
    Resize(Box<ResizeRequest>),
    /// A gesture to recognise and play, or a mesh to rebuild after its motion.
    Gesture(Box<GestureJob>),
    /// A formation transform to prepare: targets, pairing, subgroups.
    Transform(Box<TransformRequest>),
    /// The direct-control mesh to rebuild after a transform.
    TransformRemesh(Box<RemeshRequest>),
    /// Edit mode: a drag on a cage, or what follows a release.
    Edit(Box<EditJob>),
    /// `library collect`: a motion to show, a gesture to record, the last one to
    /// remove (run even while the daemon stops: a gesture drawn is saved).
    Collect(Box<CollectJob>),
    /// Edit mode: a track file to read or write for a client's command.
    EditFile {
        /// The job.
        job: EditFileJob,
        /// Who asked.
        client: ClientId,
        /// Their id for the command.
        id: serde_json::Value,
    },
}

/// What the formation thread hands back.
#[derive(Debug)]
pub(super) enum FormationDone {
    /// A prepared switch.
    Switch(Box<PreparedSwitch>),
    /// A prepared resize.
    Resize(Box<PreparedResize>),
    /// A gesture recognised and its motion synthesised, with the µs it took.
    Gesture(Box<PreparedGesture>, u64),
    /// A mesh rebuilt around the crowd after a gesture motion.
    Remesh(Box<PreparedRemesh>),
    /// A live gesture's window recognised (continuous recognition).
    Window(Box<PreparedWindow>),
    /// A prepared transform, with the µs it took.
    Transform(Box<PreparedTransform>, u64),
    /// The mesh rebuilt after a transform.
    TransformRemesh(Box<PreparedRemesh>),
    /// An edit job done.
    Edit(Box<EditDone>),
    /// A collection job done.
    Collected(Box<CollectDone>),
    /// A track file read for `edit.load` (at that edit epoch).
    EditLoaded {
        /// The edit epoch the load was asked at.
        epoch: u64,
        /// The tracks, or why not.
        result: Result<Box<TrackSet>, String>,
        /// The entry of the edit directory.
        entry: String,
        /// Who asked.
        client: ClientId,
        /// Their id for the command.
        id: serde_json::Value,
    },
    /// Tracks written for `edit.save`.
    EditSaved {
        /// Whether they were, or why not.
        result: Result<(), String>,
        /// Who asked.
        client: ClientId,
        /// Their id for the command.
        id: serde_json::Value,
    },
    /// A job given up because a newer one superseded it: µs from the change to the
    /// preparation giving up.
    Abandoned(u64),
}

/// The formation thread: prepares formation switches (the new mesh, its goal
/// samples, the least-effort pairing; [`SwitchRequest::prepare`]) and resizes
/// (goal samples for the new count; [`ResizeRequest::prepare`]) so the control
/// thread never does that slow work. At nice 10, like the assignment worker. A job
/// superseded meanwhile (a reset or resize after a switch request, a newer resize)
/// or running when the daemon stops is abandoned.
pub(super) fn formation_worker(
    requests: Receiver<FormationJob>,
    done: Sender<FormationDone>,
    fresh: Arc<Freshness>,
) {
    crate::rt::make_background("formation");
    // Gesture commands' workspaces, reused from gesture to gesture.
    let mut searcher = Searcher::new();
    let mut synth = Synthesiser::new();
    let mut windows = WindowBuffers::new();
    for job in requests.iter() {
        if let FormationJob::Collect(job) = job {
            // A file write of milliseconds, never abandoned: what a person drew
            // is saved even while the daemon stops.
            if done
                .send(FormationDone::Collected(Box::new(job.run())))
                .is_err()
            {
                break;
            }
            continue;
        }
        if fresh.stopping() {
            break;
        }
        let out = match job {
            FormationJob::Collect(_) => None,
            FormationJob::Switch(r) => {
                let epoch = r.epoch;
                let stale =
                    || fresh.stopping() || fresh.switch_epoch.load(Ordering::Relaxed) != epoch;
                (!stale())
                    .then(|| r.prepare_cancellable(Cancel::new(&stale)))
                    .flatten()
                    .map(|p| FormationDone::Switch(Box::new(p)))
            }
            FormationJob::Resize(r) => {
                let ticket = r.ticket;
                let stale =
                    || fresh.stopping() || fresh.resize_ticket.load(Ordering::Relaxed) != ticket;
                (!stale())
                    .then(|| r.prepare(Cancel::new(&stale)))
                    .flatten()
                    .map(|p| FormationDone::Resize(Box::new(p)))
            }
            FormationJob::Transform(r) => {
                let epoch = r.epoch;
                let stale =
                    || fresh.stopping() || fresh.transform_epoch.load(Ordering::Relaxed) != epoch;
                let start = monotonic_now();
                (!stale())
                    .then(|| r.prepare(Cancel::new(&stale)))
                    .flatten()
                    .map(|p| {
                        let us = monotonic_now().saturating_since(start).0;
                        FormationDone::Transform(Box::new(p), us)
                    })
            }
            // Told apart by the transform epoch when stale; a mesh is milliseconds.
            FormationJob::TransformRemesh(r) => {
                Some(FormationDone::TransformRemesh(Box::new(r.prepare())))
            }
            // Edit work: a stale result is told apart by the engine's edit epoch.
            FormationJob::Edit(job) => Some(FormationDone::Edit(Box::new(job.run()))),
            // A regular file of the edit directory, capped: a FIFO or a device is
            // refused at the open, and the read gives up when the daemon stops.
            FormationJob::EditFile { job, client, id } => {
                Some(edit_file(job, client, id, &|| fresh.stopping()))
            }
            // Gesture work is short (milliseconds) and not cancelled; a result
            // made stale meanwhile is told apart by the engine's gesture epoch.
            FormationJob::Gesture(job) => match *job {
                GestureJob::Recognise(r) => {
                    let start = monotonic_now();
                    let p = r.prepare(&mut searcher, &mut synth);
                    let us = monotonic_now().saturating_since(start).0;
                    Some(FormationDone::Gesture(Box::new(p), us))
                }
                GestureJob::Remesh(r) => Some(FormationDone::Remesh(Box::new(r.prepare()))),
                GestureJob::Window(r) => {
                    Some(FormationDone::Window(Box::new(r.prepare(&mut windows))))
                }
            },
        };
        if fresh.stopping() {
            break;
        }
        let out = out.unwrap_or_else(|| FormationDone::Abandoned(fresh.since_change()));
        if done.send(out).is_err() {
            break;
        }
    }
}

/// Reads or writes an entry of the edit directory for the edit mode's `edit.load`
/// and `edit.save`; a read polls `stop` every MiB.
fn edit_file(
    job: EditFileJob,
    client: ClientId,
    id: serde_json::Value,
    stop: &dyn Fn() -> bool,
) -> FormationDone {
    let opts = ReadOptions::default();
    match job {
        EditFileJob::Load { dir, entry, epoch } => FormationDone::EditLoaded {
            epoch,
            result: read_track_entry(&dir, &entry, &opts, stop).map(Box::new),
            entry,
            client,
            id,
        },
        EditFileJob::Save {
            set,
            dir,
            entry,
            overwrite,
        } => FormationDone::EditSaved {
            result: write_track_entry(&set, &dir, &entry, &opts, overwrite),
            client,
            id,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use crossbeam_channel::bounded;

    fn job(n: usize, generation: u64) -> Box<AssignJob> {
        let mut rng = SplitMix64::new(5);
        let mut pts = |dx: f64| -> Vec<Vec2> {
            (0..n)
                .map(|_| Vec2::new(dx + 4.0 * rng.unit(), 3.0 * rng.unit()))
                .collect()
        };
        Box::new(AssignJob {
            generation,
            agents: pts(0.0),
            goals: pts(6.0),
            ..AssignJob::default()
        })
    }

    /// An `edit.load` read is given up when the daemon stops (the formation thread
    /// passes `Freshness::stopping` as the stop check), and reads its entry
    /// otherwise; a FIFO in the edit directory is refused, not waited on.
    #[test]
    fn an_edit_load_read_stops_with_the_daemon_and_refuses_a_fifo() {
        use crate::crowd::edit::io::{write_tracks, Format};
        use crate::crowd::edit::Track;
        let dir = tempfile::tempdir().unwrap();
        let set = TrackSet {
            tracks: vec![Track::linked(
                1,
                vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)],
                vec![0.0, 0.5],
            )],
            step_s: 0.5,
        };
        let o = ReadOptions::default();
        write_tracks(&set, &dir.path().join("a.jsonl"), Format::Jsonl, &o, false).unwrap();
        assert!(std::process::Command::new("mkfifo")
            .arg(dir.path().join("p.csv"))
            .status()
            .unwrap()
            .success());
        let load = |entry: &str, stopping: bool| {
            let job = EditFileJob::Load {
                dir: Arc::from(dir.path()),
                entry: entry.into(),
                epoch: 1,
            };
            match edit_file(job, 7, serde_json::Value::from(1), &|| stopping) {
                FormationDone::EditLoaded { result, .. } => result.map(|s| s.tracks.len()),
                _ => panic!("not a load"),
            }
        };
        assert_eq!(load("a.jsonl", false), Ok(1));
        assert_eq!(
            load("a.jsonl", true),
            Err("a.jsonl: reading stopped (the daemon is stopping)".into())
        );
        assert_eq!(
            load("p.csv", false),
            Err("p.csv: is a FIFO, not a regular file".into())
        );
    }

    /// A job of the current generation is solved; one made stale before it was
    /// picked up is given up and said so (not counted as a failure), with the time
    /// since the change; after `stop` the worker ends.
    #[test]
    fn the_worker_gives_up_stale_jobs_and_ends_on_stop() {
        let fresh = Arc::new(Freshness::default());
        fresh.update(1, 0, 0, 0);
        let (job_tx, job_rx) = bounded(1);
        let (res_tx, res_rx) = bounded(1);
        let f = Arc::clone(&fresh);
        let worker =
            std::thread::spawn(move || assignment_worker(PointMetric::Squared, job_rx, res_tx, f));
        job_tx.send(job(300, 1)).unwrap();
        let done = res_rx.recv().unwrap();
        assert!(done.ok && !done.abandoned);
        assert_eq!(done.goal_of.len(), 300);
        // The crowd changes before the next job is solved.
        fresh.update(2, 0, 0, 0);
        job_tx.send(job(300, 1)).unwrap();
        let done = res_rx.recv().unwrap();
        assert!(
            !done.ok && done.abandoned,
            "ok {} abandoned {}",
            done.ok,
            done.abandoned
        );
        fresh.stop();
        job_tx.send(job(300, 2)).unwrap();
        assert!(res_rx.recv().is_err(), "the worker ended without answering");
        worker.join().unwrap();
    }

    /// A resize superseded while its goals are being drawn is given up (drawing
    /// 20,000 goal samples takes seconds, tens of seconds in a debug build); a
    /// small one is prepared; after `stop` the thread ends.
    #[test]
    fn the_formation_thread_gives_up_a_superseded_resize() {
        use crate::crowd::mesh::TriMesh;
        use crate::geom::Rect;
        use std::time::Duration;
        let fresh = Arc::new(Freshness::default());
        fresh.update(0, 0, 1, 0);
        let (tx, rx) = bounded(2);
        let (done_tx, done_rx) = bounded(2);
        let f = Arc::clone(&fresh);
        let thread = std::thread::spawn(move || formation_worker(rx, done_tx, f));
        let mesh = TriMesh::grid(
            Rect {
                min: [0.0, 0.0],
                max: [8.0, 5.0],
            },
            12,
            8,
        );
        let resize = |count: u32, ticket: u64| {
            FormationJob::Resize(Box::new(ResizeRequest {
                count,
                ticket,
                topology: 1,
                mesh: mesh.clone(),
                start_mesh: None,
            }))
        };
        tx.send(resize(20_000, 1)).unwrap();
        std::thread::sleep(Duration::from_millis(50));
        fresh.update(0, 0, 2, 0);
        // Generous: a preparation that went on to the end would take far longer.
        match done_rx.recv_timeout(Duration::from_secs(10)) {
            Ok(FormationDone::Abandoned(_)) => {}
            other => panic!("expected the resize to be abandoned, got {other:?}"),
        }
        tx.send(resize(40, 2)).unwrap();
        match done_rx.recv_timeout(Duration::from_secs(10)) {
            Ok(FormationDone::Resize(p)) => assert_eq!((p.count, p.samples.len()), (40, 40)),
            other => panic!("expected the resize, got {other:?}"),
        }
        fresh.stop();
        tx.send(resize(20_000, 2)).unwrap();
        thread.join().unwrap();
    }
}
