//! A snapshot as TUIO sees it: every entity on the table in normalised units.
//!
//! # Units and orientation
//!
//! TUIO positions are in the unit square with (0, 0) at the top left. The world's
//! x points right and its y points away from the viewer, down the table
//! (`docs/protocol.md`, Conventions): the same way as TUIO's, so no axis flips:
//!
//! ```text
//!   world.min ─────────── x ──►                 (0,0) ─────────── x ──► (1,0)
//!      │                                           │
//!      y   world metres            ==>              y   TUIO unit square
//!      ▼                world.max                  ▼                    (1,1)
//! x_tuio = (x − world.min.x) / world.width,   y_tuio = (y − world.min.y) / world.height
//! ```
//!
//! Velocities are normalised units per second (m/s divided by the world's width
//! or height), accelerations their change per second. An agent's angle is its
//! heading, the direction of its velocity on the table, in radians `0 ..= 2π`
//! measured from +x towards +y (clockwise as seen from above the table); a
//! still agent keeps its last heading. Rotation speed is in turns per second
//! and rotation acceleration in turns per second², as in the TUIO reference
//! implementation. Derivatives are taken between the frames sent, and are 0 in
//! an entity's first frame.
//!
//! * cursors: the touches, keyed by contact id;
//! * objects: the agents, class id = the agent's motion type (its index in
//!   Table 1 order: run 0, crawl 1, duck 2, swim 3, jump 4, climb up 5, climb
//!   down 6) when the snapshot has motion types, else 0;
//! * blobs: the controls, each the axis-aligned box around its touches (centre,
//!   width, height, area = width × height in normalised units, angle 0; a point
//!   control's box has no extent).

use super::session::{Keyed, SessionIds};
use crate::geom::{Rect, Vec2};
use crate::vocab::{Micros, Snapshot};
use std::f64::consts::TAU;

/// Below this speed (m/s) an agent's heading is kept from the previous frame.
pub const STILL_SPEED_M_PER_S: f64 = 1e-3;

/// A touch (`/tuio/2Dcur`, `/tuio2/ptr`).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Cursor {
    /// Session id.
    pub session: i32,
    /// Position (normalised).
    pub x: f32,
    /// Position (normalised).
    pub y: f32,
    /// Velocity (normalised units per second).
    pub vx: f32,
    /// Velocity (normalised units per second).
    pub vy: f32,
    /// Motion acceleration (normalised units per second²).
    pub accel: f32,
}

/// An agent (`/tuio/2Dobj`, `/tuio2/tok`).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Object {
    /// Session id.
    pub session: i32,
    /// Class id: the motion type's index, or 0.
    pub class: i32,
    /// Position (normalised).
    pub x: f32,
    /// Position (normalised).
    pub y: f32,
    /// Heading (radians, 0 ..= 2π).
    pub angle: f32,
    /// Velocity (normalised units per second).
    pub vx: f32,
    /// Velocity (normalised units per second).
    pub vy: f32,
    /// Rotation speed (turns per second).
    pub rot_speed: f32,
    /// Motion acceleration (normalised units per second²).
    pub accel: f32,
    /// Rotation acceleration (turns per second²).
    pub rot_accel: f32,
}

/// A control's box (`/tuio/2Dblb`, `/tuio2/bnd`).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Blob {
    /// Session id.
    pub session: i32,
    /// Centre (normalised).
    pub x: f32,
    /// Centre (normalised).
    pub y: f32,
    /// Width (normalised).
    pub w: f32,
    /// Height (normalised).
    pub h: f32,
    /// Area (normalised units², `w × h`).
    pub area: f32,
    /// Velocity of the centre (normalised units per second).
    pub vx: f32,
    /// Velocity of the centre (normalised units per second).
    pub vy: f32,
    /// Motion acceleration (normalised units per second²).
    pub accel: f32,
}

/// One frame, normalised.
#[derive(Clone, Debug, Default)]
pub struct TuioFrame {
    /// The snapshot's time (CLOCK_MONOTONIC µs).
    pub t: Micros,
    /// Touches.
    pub cursors: Vec<Cursor>,
    /// Agents.
    pub objects: Vec<Object>,
    /// Controls.
    pub blobs: Vec<Blob>,
}

#[derive(Copy, Clone, Debug, Default)]
struct AgentTrack {
    session: i32,
    /// Whether a frame has shown this agent (derivatives need a previous one).
    seen: bool,
    angle: f64,
    rot_speed: f64,
    speed: f64,
}

#[derive(Copy, Clone, Debug, Default)]
struct PointTrack {
    pos: Vec2,
    speed: f64,
}

/// Turns snapshots into [`TuioFrame`]s, keeping what the derivatives and session
/// ids need from one frame to the next. Its buffers are reused.
#[derive(Debug)]
pub struct Framer {
    world: Rect,
    ids: SessionIds,
    agents: Vec<AgentTrack>,
    touches: Keyed<PointTrack>,
    controls: Keyed<PointTrack>,
    /// Per control id: the box of its touches (min, max), this frame.
    boxes: Vec<(u32, Vec2, Vec2)>,
    last_t: Option<Micros>,
    frame: TuioFrame,
}

impl Framer {
    /// A framer for a table showing `world` (m).
    pub fn new(world: Rect) -> Framer {
        Framer {
            world,
            ids: SessionIds::default(),
            agents: Vec::new(),
            touches: Keyed::default(),
            controls: Keyed::default(),
            boxes: Vec::new(),
            last_t: None,
            frame: TuioFrame::default(),
        }
    }

    /// World metres to the unit square.
    pub fn normalise(&self, p: Vec2) -> Vec2 {
        let w = self.world.width().max(f64::MIN_POSITIVE);
        let h = self.world.height().max(f64::MIN_POSITIVE);
        Vec2::new((p.x - self.world.min[0]) / w, (p.y - self.world.min[1]) / h)
    }

    fn scale(&self, v: Vec2) -> Vec2 {
        let w = self.world.width().max(f64::MIN_POSITIVE);
        let h = self.world.height().max(f64::MIN_POSITIVE);
        Vec2::new(v.x / w, v.y / h)
    }

    /// The frame of `snap`. Only the kinds asked for are filled (the others stay
    /// empty, and their sessions are not followed).
    pub fn build(
        &mut self,
        snap: &Snapshot,
        cursors: bool,
        objects: bool,
        blobs: bool,
    ) -> &TuioFrame {
        let dt_s = self
            .last_t
            .map(|t| snap.t.saturating_since(t).0 as f64 * 1e-6)
            .filter(|&d| d > 0.0);
        self.last_t = Some(snap.t);
        let rate = |d: f64| dt_s.map_or(0.0, |dt| d / dt);
        let mut frame = std::mem::take(&mut self.frame);
        frame.t = snap.t;
        frame.cursors.clear();
        frame.objects.clear();
        frame.blobs.clear();

        if cursors {
            self.touches.begin();
            for t in &snap.touches {
                let (session, prev) = self.touches.session(t.id, &mut self.ids);
                let pos = self.normalise(t.pos);
                let vel = prev.map_or(Vec2::new(0.0, 0.0), |p| {
                    Vec2::new(rate(pos.x - p.pos.x), rate(pos.y - p.pos.y))
                });
                let speed = vel.norm();
                let accel = prev.map_or(0.0, |p| rate(speed - p.speed));
                self.touches.keep(t.id, session, PointTrack { pos, speed });
                frame.cursors.push(Cursor {
                    session,
                    x: pos.x as f32,
                    y: pos.y as f32,
                    vx: vel.x as f32,
                    vy: vel.y as f32,
                    accel: accel as f32,
                });
            }
        }

        if objects {
            let n = snap.agents.len();
            self.agents.truncate(n);
            while self.agents.len() < n {
                let session = self.ids.fresh();
                self.agents.push(AgentTrack {
                    session,
                    ..AgentTrack::default()
                });
            }
            let classes = snap.motions.len() == n;
            for (i, a) in snap.agents.iter().enumerate() {
                let pos = self.normalise(a.pos);
                let vel = self.scale(a.vel);
                let speed = vel.norm();
                let track = self.agents[i];
                let fresh = !track.seen;
                let angle = if a.vel.norm() >= STILL_SPEED_M_PER_S {
                    a.vel.y.atan2(a.vel.x).rem_euclid(TAU)
                } else {
                    track.angle
                };
                let turned = (angle - track.angle + std::f64::consts::PI).rem_euclid(TAU)
                    - std::f64::consts::PI;
                let rot_speed = if fresh { 0.0 } else { rate(turned / TAU) };
                let accel = if fresh {
                    0.0
                } else {
                    rate(speed - track.speed)
                };
                let rot_accel = if fresh {
                    0.0
                } else {
                    rate(rot_speed - track.rot_speed)
                };
                self.agents[i] = AgentTrack {
                    session: track.session,
                    seen: true,
                    angle,
                    rot_speed,
                    speed,
                };
                frame.objects.push(Object {
                    session: track.session,
                    class: if classes { snap.motions[i] as i32 } else { 0 },
                    x: pos.x as f32,
                    y: pos.y as f32,
                    angle: angle as f32,
                    vx: vel.x as f32,
                    vy: vel.y as f32,
                    rot_speed: rot_speed as f32,
                    accel: accel as f32,
                    rot_accel: rot_accel as f32,
                });
            }
        } else {
            self.agents.clear();
        }

        if blobs {
            self.boxes.clear();
            for t in &snap.touches {
                let Some(c) = t.control else { continue };
                let p = self.normalise(t.pos);
                match self.boxes.iter_mut().find(|b| b.0 == c) {
                    Some(b) => {
                        b.1 = Vec2::new(b.1.x.min(p.x), b.1.y.min(p.y));
                        b.2 = Vec2::new(b.2.x.max(p.x), b.2.y.max(p.y));
                    }
                    None => self.boxes.push((c, p, p)),
                }
            }
            self.controls.begin();
            for &(c, lo, hi) in &self.boxes {
                let (session, prev) = self.controls.session(c, &mut self.ids);
                let centre = Vec2::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y));
                let vel = prev.map_or(Vec2::new(0.0, 0.0), |p| {
                    Vec2::new(rate(centre.x - p.pos.x), rate(centre.y - p.pos.y))
                });
                let speed = vel.norm();
                let accel = prev.map_or(0.0, |p| rate(speed - p.speed));
                self.controls
                    .keep(c, session, PointTrack { pos: centre, speed });
                let (w, h) = (hi.x - lo.x, hi.y - lo.y);
                frame.blobs.push(Blob {
                    session,
                    x: centre.x as f32,
                    y: centre.y as f32,
                    w: w as f32,
                    h: h as f32,
                    area: (w * h) as f32,
                    vx: vel.x as f32,
                    vy: vel.y as f32,
                    accel: accel as f32,
                });
            }
        }
        self.frame = frame;
        &self.frame
    }
}
