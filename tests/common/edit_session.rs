//! An engine in edit mode driven tick by tick with fingers and commands, for the
//! edit mode's tests (`engine_edit.rs`, `engine_edit_authoring.rs`).

use crowdtouch::config::Config;
use crowdtouch::crowd::edit::TrackSet;
use crowdtouch::engine::Engine;
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::{
    Command, Contact, ContactFlags, ContactId, EditView, Event, Micros, TouchFrame, TracksView,
};
use std::sync::Arc;

/// One tick at 60 Hz (µs).
pub const TICK_US: u64 = 16_667;
/// A finger landing.
pub const DOWN: ContactFlags = ContactFlags::DOWN;
/// A finger moving or resting.
pub const MOVE: ContactFlags = ContactFlags::NONE;
/// A finger lifting.
pub const UP: ContactFlags = ContactFlags::UP;

pub struct Session {
    pub e: Engine,
    pub now: u64,
    pub tracks: Vec<Arc<TracksView>>,
    pub views: Vec<Arc<EditView>>,
    pub events: Vec<Event>,
    /// Jobs wait for [`Session::run_jobs`] (as on the daemon's formation thread).
    pub manual: bool,
}

impl Session {
    /// `set` loaded in an engine with the default config, paused, its jobs run
    /// in the tick.
    pub fn new(set: TrackSet) -> Session {
        Session::with(set, Config::embedded_default(), false)
    }

    /// `set` loaded and playing (not paused), its jobs run in the tick.
    pub fn playing(set: TrackSet) -> Session {
        let cfg = Config::embedded_default();
        let mut e = Engine::new(&cfg, None, true);
        e.tick(Micros(TICK_US));
        e.clear_events();
        e.load_tracks(set, "parade", Micros(TICK_US));
        let mut s = Session {
            e,
            now: TICK_US,
            tracks: Vec::new(),
            views: Vec::new(),
            events: Vec::new(),
            manual: false,
        };
        s.tick();
        s
    }

    /// `set` loaded with `cfg`, paused; with `manual`, jobs wait for
    /// [`Session::run_jobs`] as on the daemon's formation thread.
    pub fn with(set: TrackSet, cfg: Config, manual: bool) -> Session {
        let mut e = Engine::new(&cfg, None, !manual);
        e.set_switch_worker(manual);
        e.tick(Micros(TICK_US));
        e.clear_events();
        e.load_tracks(set, "authored", Micros(TICK_US));
        e.command(&Command::Pause, Micros(TICK_US)).unwrap();
        let mut s = Session {
            e,
            now: TICK_US,
            tracks: Vec::new(),
            views: Vec::new(),
            events: Vec::new(),
            manual,
        };
        s.tick();
        s.run_jobs();
        s
    }
    pub fn tick(&mut self) {
        self.now += TICK_US;
        let o = self.e.tick(Micros(self.now));
        if let Some(t) = &o.tracks {
            self.tracks.push(Arc::clone(t));
        }
        if let Some(v) = &o.edit {
            self.views.push(Arc::clone(v));
        }
        self.events.extend(o.events.iter().cloned());
        self.e.clear_events();
    }
    pub fn ticks(&mut self, n: usize) {
        for _ in 0..n {
            self.tick();
        }
    }
    pub fn run_jobs(&mut self) {
        while let Some(j) = self.e.take_edit_job() {
            let done = j.run();
            self.e.apply_edit(done, Micros(self.now));
        }
        self.tick();
    }
    /// Fingers at world positions (the default world is 16 × 9 m on the unit square).
    pub fn touch(&mut self, fingers: &[(u32, Vec2, ContactFlags)]) {
        let mut f = TouchFrame::new(Micros(self.now + 1));
        for &(id, p, flags) in fingers {
            f.push(Contact {
                id: ContactId(id),
                x: (p.x / 16.0) as f32,
                y: (p.y / 9.0) as f32,
                pressure: None,
                major_mm: None,
                minor_mm: None,
                flags,
            })
            .expect("room");
        }
        self.e.push_frame(&f);
    }
    /// One finger dragged from `from` by `by` in ten steps (two ticks each),
    /// other fingers `also` held still.
    pub fn drag(&mut self, id: u32, from: Vec2, by: Vec2, also: &[(u32, Vec2)]) {
        for k in 1..=10 {
            let mut f = vec![(id, from + by * (k as f64 / 10.0), MOVE)];
            f.extend(also.iter().map(|&(i, p)| (i, p, MOVE)));
            self.touch(&f);
            self.ticks(2);
            if self.manual {
                self.run_jobs();
            }
        }
        // Still: the newest drag's `tracks` message goes out (at most every 100 ms).
        let mut f = vec![(id, from + by, MOVE)];
        f.extend(also.iter().map(|&(i, p)| (i, p, MOVE)));
        self.touch(&f);
        self.ticks(8);
        if self.manual {
            self.run_jobs();
        }
    }
    pub fn command(&mut self, c: Command) {
        self.e.command(&c, Micros(self.now)).unwrap();
        self.tick();
        if self.manual {
            self.run_jobs();
        }
    }
    pub fn set(&self) -> Arc<TrackSet> {
        Arc::clone(self.e.edited_tracks().expect("editing"))
    }
    pub fn view(&self) -> &EditView {
        self.views.last().expect("an edit view")
    }
    /// Plays until the play time is `t_s` (paused again then).
    pub fn play_to(&mut self, t_s: f64) {
        self.command(Command::Resume);
        while self.play_t() < t_s - 0.5 * TICK_US as f64 / 1e6 {
            self.tick();
        }
        self.command(Command::Pause);
    }
    pub fn play_t(&self) -> f64 {
        self.e.edit_play_t_s().expect("editing")
    }
    /// One tick; the agents' positions in its snapshot.
    pub fn agents(&mut self) -> Vec<Vec2> {
        self.now += TICK_US;
        let o = self.e.tick(Micros(self.now));
        let a = o.snapshot.agents.iter().map(|a| a.pos).collect();
        self.e.clear_events();
        a
    }
}
