//! TUIO 1.1 encoding: one bundle series per profile and frame.
//!
//! ```text
//! /tuio/2Dcur source <name>        /tuio/2Dobj source <name>        /tuio/2Dblb source <name>
//! /tuio/2Dcur alive s…             /tuio/2Dobj alive s…             /tuio/2Dblb alive s…
//! /tuio/2Dcur set s x y X Y m      /tuio/2Dobj set s i x y a X Y A m r
//!                                  /tuio/2Dblb set s x y a w h f X Y A m r
//! /tuio/2Dcur fseq f               /tuio/2Dobj fseq f               /tuio/2Dblb fseq f
//! ```
//!
//! `s` and `i` are int32, everything else float32; units in [`super::frame`]. A
//! profile is sent every frame, with a `set` for every entity (a full update), so a
//! client that missed a datagram catches up on the next frame and an empty alive
//! list says that everything lifted. Each profile's bundles go in datagrams of their
//! own (a client reads one profile per bundle), split by [`super::split`] with the
//! same `fseq` in each.

use super::frame::TuioFrame;
use super::split::{args_mut, message, Alive, AlivePlace, Datagrams, Packer};
use rosc::{OscPacket, OscTime, OscType};

/// The cursor profile's address.
pub const CUR: &str = "/tuio/2Dcur";
/// The object profile's address.
pub const OBJ: &str = "/tuio/2Dobj";
/// The blob profile's address.
pub const BLB: &str = "/tuio/2Dblb";

/// TUIO 1.1 bundles are sent for immediate use (the reference servers do the same).
pub const IMMEDIATE: OscTime = OscTime {
    seconds: 0,
    fractional: 1,
};

/// Which profiles a frame carries.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Profiles {
    /// Touches.
    pub cursors: bool,
    /// Agents.
    pub objects: bool,
    /// Controls.
    pub blobs: bool,
}

/// Encodes frames; its template messages and packer are reused.
#[derive(Debug)]
pub struct Encoder11 {
    packer: Packer,
    cur: OscPacket,
    obj: OscPacket,
    blb: OscPacket,
    fseq: [OscPacket; 3],
    source: [OscPacket; 3],
}

fn floats(n: usize) -> impl Iterator<Item = OscType> {
    std::iter::repeat_n(OscType::Float(0.0), n)
}

fn set(addr: &str, ints: usize, n_floats: usize) -> OscPacket {
    let mut args = vec![OscType::String("set".to_string())];
    args.extend(std::iter::repeat_n(OscType::Int(0), ints));
    args.extend(floats(n_floats));
    message(addr, args)
}

impl Encoder11 {
    /// An encoder whose frames name `source`.
    pub fn new(source: &str) -> Encoder11 {
        let src = |a: &str| {
            message(
                a,
                vec![
                    OscType::String("source".to_string()),
                    OscType::String(source.to_string()),
                ],
            )
        };
        let fseq = |a: &str| {
            message(
                a,
                vec![OscType::String("fseq".to_string()), OscType::Int(0)],
            )
        };
        Encoder11 {
            packer: Packer::default(),
            cur: set(CUR, 1, 5),
            obj: set(OBJ, 2, 8),
            blb: set(BLB, 1, 11),
            fseq: [fseq(CUR), fseq(OBJ), fseq(BLB)],
            source: [src(CUR), src(OBJ), src(BLB)],
        }
    }

    /// Appends `frame`'s datagrams (each at most `max_bytes`) to `out`. Returns
    /// how many entities were left out because their alive list would not fit
    /// (`split.rs`).
    pub fn encode(
        &mut self,
        frame: &TuioFrame,
        profiles: Profiles,
        fseq: i32,
        max_bytes: usize,
        out: &mut Datagrams,
    ) -> usize {
        let mut cut = 0;
        for (k, (on, addr)) in [
            (profiles.cursors, CUR),
            (profiles.objects, OBJ),
            (profiles.blobs, BLB),
        ]
        .into_iter()
        .enumerate()
        {
            if !on {
                continue;
            }
            self.packer.reset();
            self.packer.head(&self.source[k]);
            match k {
                0 => {
                    for c in &frame.cursors {
                        let a = args_mut(&mut self.cur);
                        a[1] = OscType::Int(c.session);
                        for (slot, v) in a[2..].iter_mut().zip([c.x, c.y, c.vx, c.vy, c.accel]) {
                            *slot = OscType::Float(v);
                        }
                        self.packer.item(c.session, &self.cur);
                    }
                }
                1 => {
                    for o in &frame.objects {
                        let a = args_mut(&mut self.obj);
                        a[1] = OscType::Int(o.session);
                        a[2] = OscType::Int(o.class);
                        let v = [
                            o.x,
                            o.y,
                            o.angle,
                            o.vx,
                            o.vy,
                            o.rot_speed,
                            o.accel,
                            o.rot_accel,
                        ];
                        for (slot, v) in a[3..].iter_mut().zip(v) {
                            *slot = OscType::Float(v);
                        }
                        self.packer.item(o.session, &self.obj);
                    }
                }
                _ => {
                    for b in &frame.blobs {
                        let a = args_mut(&mut self.blb);
                        a[1] = OscType::Int(b.session);
                        let v = [
                            b.x, b.y, 0.0, b.w, b.h, b.area, b.vx, b.vy, 0.0, b.accel, 0.0,
                        ];
                        for (slot, v) in a[2..].iter_mut().zip(v) {
                            *slot = OscType::Float(v);
                        }
                        self.packer.item(b.session, &self.blb);
                    }
                }
            }
            if let Some(slot) = args_mut(&mut self.fseq[k]).get_mut(1) {
                *slot = OscType::Int(fseq);
            }
            self.packer.tail(&self.fseq[k]);
            cut += self.packer.finish(
                max_bytes,
                IMMEDIATE,
                Alive {
                    addr,
                    word: Some("alive"),
                    place: AlivePlace::EndOfHeads,
                },
                out,
            );
        }
        cut
    }
}
