//! TUIO 2.0 encoding: one bundle series per frame, every component in it.
//!
//! ```text
//! /tuio2/frm f_id ttag dim source
//! /tuio2/ptr s tu_id c_id x y a shear radius press X Y P m p     (touches)
//! /tuio2/bnd s x y a w h f X Y A m r                             (controls)
//! /tuio2/tok s tu_id c_id x y a X Y A m r                        (agents)
//! /tuio2/alv s…
//! ```
//!
//! `f_id`, `s`, `tu_id`, `c_id`, `dim` are int32, `ttag` an OSC time tag, `source`
//! a string, everything else float32 (units in [`super::frame`]). Session ids are
//! unique across `ptr`, `bnd` and `tok`, and `alv` lists every one of them. `dim`
//! is the sensor size as TUIO 2.0 packs it, `width << 16 | height`; crowdtouch
//! gives the world's size in millimetres (each capped to 65,535), so a client can
//! recover the table's aspect ratio and scale. `tu_id` is 0 (no user, no type);
//! a token's `c_id` is the agent's class (its motion type); a pointer's is 0, its
//! angle, shear and radius 0 and its pressure 1 (touching: the surface reports no
//! pressure), its pressure speed and acceleration 0. A bound's angle, rotation
//! speed and acceleration are 0 (boxes are axis-aligned).
//!
//! When a frame does not fit one datagram, every bundle repeats `frm` (same
//! `f_id`) and the full `alv` (`split.rs`). Components are packed in the
//! order pointers, bounds, tokens, so a frame cut for room loses tokens first.

use super::frame::TuioFrame;
use super::split::{args_mut, message, Alive, AlivePlace, Datagrams, Packer};
use crate::geom::Rect;
use rosc::{OscPacket, OscTime, OscType};

/// The frame message.
pub const FRM: &str = "/tuio2/frm";
/// Pointers.
pub const PTR: &str = "/tuio2/ptr";
/// Tokens.
pub const TOK: &str = "/tuio2/tok";
/// Bounds.
pub const BND: &str = "/tuio2/bnd";
/// The alive list.
pub const ALV: &str = "/tuio2/alv";

/// The `dim` argument for a world of that size: millimetres, `width << 16 |
/// height`, each at least 1 and at most 65,535.
pub fn dimension(world: Rect) -> i32 {
    let mm = |m: f64| (m * 1000.0).round().clamp(1.0, 65_535.0) as u32;
    ((mm(world.width()) << 16) | mm(world.height())) as i32
}

/// Encodes frames; its template messages and packer are reused.
#[derive(Debug)]
pub struct Encoder20 {
    packer: Packer,
    frm: OscPacket,
    ptr: OscPacket,
    tok: OscPacket,
    bnd: OscPacket,
}

fn template(addr: &str, ints: usize, floats: usize) -> OscPacket {
    let mut args: Vec<OscType> = std::iter::repeat_n(OscType::Int(0), ints).collect();
    args.extend(std::iter::repeat_n(OscType::Float(0.0), floats));
    message(addr, args)
}

fn fill(args: &mut [OscType], from: usize, values: &[f32]) {
    for (slot, &v) in args[from..].iter_mut().zip(values) {
        *slot = OscType::Float(v);
    }
}

impl Encoder20 {
    /// An encoder for a table showing `world`, whose frames name `source`.
    pub fn new(source: &str, world: Rect) -> Encoder20 {
        Encoder20 {
            packer: Packer::default(),
            frm: message(
                FRM,
                vec![
                    OscType::Int(0),
                    OscType::Time(OscTime {
                        seconds: 0,
                        fractional: 1,
                    }),
                    OscType::Int(dimension(world)),
                    OscType::String(source.to_string()),
                ],
            ),
            ptr: template(PTR, 3, 11),
            tok: template(TOK, 3, 8),
            bnd: template(BND, 1, 11),
        }
    }

    /// Appends `frame`'s datagrams (each at most `max_bytes`) to `out`, with
    /// frame id `f_id` and time tag `ttag`. Returns how many components were left
    /// out because their alive list would not fit (`split.rs`).
    pub fn encode(
        &mut self,
        frame: &TuioFrame,
        f_id: i32,
        ttag: OscTime,
        max_bytes: usize,
        out: &mut Datagrams,
    ) -> usize {
        self.packer.reset();
        let a = args_mut(&mut self.frm);
        a[0] = OscType::Int(f_id);
        a[1] = OscType::Time(ttag);
        self.packer.head(&self.frm);
        for c in &frame.cursors {
            let a = args_mut(&mut self.ptr);
            a[0] = OscType::Int(c.session);
            fill(
                a,
                3,
                &[c.x, c.y, 0.0, 0.0, 0.0, 1.0, c.vx, c.vy, 0.0, c.accel, 0.0],
            );
            self.packer.item(c.session, &self.ptr);
        }
        for b in &frame.blobs {
            let a = args_mut(&mut self.bnd);
            a[0] = OscType::Int(b.session);
            fill(
                a,
                1,
                &[
                    b.x, b.y, 0.0, b.w, b.h, b.area, b.vx, b.vy, 0.0, b.accel, 0.0,
                ],
            );
            self.packer.item(b.session, &self.bnd);
        }
        for o in &frame.objects {
            let a = args_mut(&mut self.tok);
            a[0] = OscType::Int(o.session);
            a[2] = OscType::Int(o.class);
            fill(
                a,
                3,
                &[
                    o.x,
                    o.y,
                    o.angle,
                    o.vx,
                    o.vy,
                    o.rot_speed,
                    o.accel,
                    o.rot_accel,
                ],
            );
            self.packer.item(o.session, &self.tok);
        }
        self.packer.finish(
            max_bytes,
            // The bundle is for immediate use; the frame's time is in `frm`.
            OscTime {
                seconds: 0,
                fractional: 1,
            },
            Alive {
                addr: ALV,
                word: None,
                place: AlivePlace::StartOfTails,
            },
            out,
        )
    }
}
