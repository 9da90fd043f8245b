//! Real-time properties, proven by counting heap allocations on the calling thread:
//! the input path (decode + queue) and the control tick allocate nothing in steady
//! state.

use crowdtouch::config::Config;
use crowdtouch::engine::Engine;
use crowdtouch::input::evdev::{MtAxes, MtDecoder, EV_ABS, EV_SYN};
use crowdtouch::input::AxisRange;
use crowdtouch::pipeline::{FrameQueue, InputCounters};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{Contact, ContactFlags, ContactId, TouchFrame};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::Arc;

struct Counting;

thread_local! {
    static ARMED: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; only counts calls made on threads that
// armed the counter (thread-locals with const initialisers never allocate).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if ARMED.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if ARMED.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread.
fn allocations(f: impl FnOnce()) -> u64 {
    COUNT.with(|c| c.set(0));
    ARMED.with(|a| a.set(true));
    f();
    ARMED.with(|a| a.set(false));
    COUNT.with(Cell::get)
}

const ABS_MT_SLOT: u16 = 0x2f;
const ABS_MT_POSITION_X: u16 = 0x35;
const ABS_MT_POSITION_Y: u16 = 0x36;
const ABS_MT_TRACKING_ID: u16 = 0x39;

#[test]
fn input_decode_and_queue_do_not_allocate() {
    let axes = MtAxes {
        x: AxisRange {
            min: 0.0,
            max: 4095.0,
            resolution: 10.0,
        },
        y: AxisRange {
            min: 0.0,
            max: 4095.0,
            resolution: 10.0,
        },
        slots: 10,
        pressure: None,
        touch_major: None,
        touch_minor: None,
    };
    let mut dec = MtDecoder::new(axes, 1);
    let (tx, rx) = crossbeam_channel::bounded(64);
    let mut q = FrameQueue::new(tx, 0, Arc::new(InputCounters::default()));
    let mut frame = TouchFrame::default();
    // Warm-up: fingers down.
    let mut t = 0u64;
    let feed = |dec: &mut MtDecoder, q: &mut FrameQueue, frame: &mut TouchFrame, t: u64, k: i32| {
        for slot in 0..5 {
            dec.event(Micros(t), EV_ABS, ABS_MT_SLOT, slot, frame);
            if k == 0 {
                dec.event(Micros(t), EV_ABS, ABS_MT_TRACKING_ID, 100 + slot, frame);
            }
            dec.event(
                Micros(t),
                EV_ABS,
                ABS_MT_POSITION_X,
                100 + slot * 500 + k % 1000,
                frame,
            );
            dec.event(Micros(t), EV_ABS, ABS_MT_POSITION_Y, 2000 - k % 1000, frame);
        }
        if dec.event(Micros(t), EV_SYN, 0, 0, frame) {
            crowdtouch::input::FrameSink::push(q, frame);
        }
    };
    feed(&mut dec, &mut q, &mut frame, t, 0);
    while rx.try_recv().is_ok() {}
    // A device's calibration (rotation + matrix), region and palm threshold.
    let cal = crowdtouch::input::calibrate::Calibration {
        rotation: 90,
        flip_x: true,
        flip_y: false,
        matrix: Some([1.02, 0.01, -0.01, 0.0, 0.98, 0.01]),
    };
    let region = crowdtouch::input::calibrate::Region {
        x: 0.5,
        y: 0.0,
        width: 0.5,
        height: 1.0,
    };
    let transform = crowdtouch::input::calibrate::DeviceTransform::new(
        &cal,
        None,
        region,
        Some((600.0, 340.0)),
        Some(30.0),
    )
    .unwrap();
    let n = allocations(|| {
        for k in 1..20_000 {
            t += 8_333;
            feed(&mut dec, &mut q, &mut frame, t, k);
            let mut calibrated = frame;
            transform.apply(&mut calibrated);
            // A consumer that keeps up most of the time, and sometimes falls behind
            // so the backlog and coalescing paths run too.
            if k % 100 < 90 {
                while rx.try_recv().is_ok() {}
            }
        }
    });
    assert_eq!(n, 0, "the input path allocated {n} times");
}

/// A TUIO 1.1 bundle: `alive`, a `set` per cursor, `fseq` last (its value the
/// last four bytes, rewritten per datagram).
fn tuio_bundle(cursors: &[(i32, f32, f32)]) -> Vec<u8> {
    use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
    let m = |args: Vec<OscType>| {
        OscPacket::Message(OscMessage {
            addr: "/tuio/2Dcur".into(),
            args,
        })
    };
    let s = |v: &str| OscType::String(v.into());
    let mut alive = vec![s("alive")];
    alive.extend(cursors.iter().map(|c| OscType::Int(c.0)));
    let mut content = vec![m(vec![s("source"), s("bench@localhost")]), m(alive)];
    for &(id, x, y) in cursors {
        let mut set = vec![
            s("set"),
            OscType::Int(id),
            OscType::Float(x),
            OscType::Float(y),
        ];
        set.extend([0.0f32; 3].map(OscType::Float));
        content.push(m(set));
    }
    content.push(m(vec![s("fseq"), OscType::Int(0)]));
    rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
        timetag: OscTime::from((0, 1)),
        content,
    }))
    .unwrap()
}

#[test]
fn tuio_receive_decode_and_queue_do_not_allocate() {
    use crowdtouch::input::tuio::{Admit, FloodGate, TuioCounters, TuioDecoder};
    use crowdtouch::pipeline::device::{TransformSettings, TransformSink};
    // Five cursors moving, a sixth that comes and goes every 50 datagrams.
    let packets: Vec<Vec<u8>> = (0..100)
        .map(|k| {
            let mut c: Vec<(i32, f32, f32)> = (0..5)
                .map(|i| (i, 0.1 + 0.15 * i as f32, 0.2 + 0.006 * k as f32))
                .collect();
            if k % 50 < 25 {
                c.push((99, 0.9, 0.9 - 0.002 * k as f32));
            }
            tuio_bundle(&c)
        })
        .collect();
    let rx_sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    rx_sock.set_nonblocking(true).unwrap();
    let to = rx_sock.local_addr().unwrap();
    let tx_sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let (tx, rx) = crossbeam_channel::bounded(64);
    let q = FrameQueue::new(tx, 0, Arc::new(InputCounters::default()));
    let settings = TransformSettings {
        region: Some(crowdtouch::geom::Rect {
            min: [0.5, 0.0],
            max: [1.0, 1.0],
        }),
        ..TransformSettings::default()
    };
    let mut sink = TransformSink::fixed(q, settings, "TUIO input");
    let mut dec = TuioDecoder::new(Micros(1_000_000), Arc::new(TuioCounters::default()));
    // The source's per-peer flood cap, as it runs before the decoder.
    let mut gate = FloodGate::new(4_000, 8);
    let mut buf = vec![0u8; 65_536];
    let mut out = vec![0u8; 4096];
    let mut step = |k: usize, t: u64, dec: &mut TuioDecoder, sink: &mut TransformSink| {
        let p = &packets[k % packets.len()];
        let b = &mut out[..p.len()];
        b.copy_from_slice(p);
        b[p.len() - 4..].copy_from_slice(&(k as i32 + 1).to_be_bytes());
        tx_sock.send_to(b, to).unwrap();
        let (n, peer) = loop {
            match rx_sock.recv_from(&mut buf) {
                Ok(got) => break got,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => std::thread::yield_now(),
                Err(e) => panic!("recv: {e}"),
            }
        };
        assert_eq!(gate.admit(peer, Micros(t)), Admit::Take);
        dec.packet(&buf[..n], peer, Micros(t), sink).unwrap();
        dec.expire(Micros(t), sink);
    };
    // Warm-up: the cursors go down, the sender is learnt.
    step(0, 0, &mut dec, &mut sink);
    while rx.try_recv().is_ok() {}
    let mut t = 0;
    let n = allocations(|| {
        for k in 1..10_000 {
            t += 8_333;
            step(k, t, &mut dec, &mut sink);
            if k % 100 < 90 {
                while rx.try_recv().is_ok() {}
            }
        }
    });
    assert_eq!(n, 0, "the TUIO input path allocated {n} times");
    // The last datagram (k = 9999) has the five moving cursors, not the sixth.
    assert_eq!(dec.active_contacts(), 5, "the cursors are down");
}

/// Ticks `engine` with `frame_at(k, flags)` for `k` in `0..warm` (the first frame
/// puts the fingers down), then returns the allocations of the `steady` ticks that
/// follow (no event expected in them).
fn steady_allocations(
    engine: &mut Engine,
    frame_at: impl Fn(u64, ContactFlags) -> TouchFrame,
    warm: u64,
    steady: u64,
) -> u64 {
    for k in 0..warm {
        let flags = if k == 0 {
            ContactFlags::DOWN
        } else {
            ContactFlags::NONE
        };
        engine.push_frame(&frame_at(k, flags));
        drop(engine.tick(Micros(k * 8_333)));
        engine.clear_events();
    }
    allocations(|| {
        for k in warm..warm + steady {
            engine.push_frame(&frame_at(k, ContactFlags::NONE));
            let out = engine.tick(Micros(k * 8_333));
            assert!(out.events.is_empty());
            drop(out);
            engine.clear_events();
        }
    })
}

#[test]
fn a_steady_control_tick_does_not_allocate() {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 500;
    let mut engine = Engine::new(&cfg, None, false);
    let fingers = [(0.48f32, 0.45f32), (0.52, 0.45), (0.50, 0.52)];
    let frame_at = |k: u64, flags: ContactFlags| {
        let mut f = TouchFrame::new(Micros(k * 8_333));
        for (i, &(x, y)) in fingers.iter().enumerate() {
            let c = Contact {
                id: ContactId(i as u32 + 1),
                x: x + k as f32 * 1e-4,
                y,
                flags,
                ..Contact::default()
            };
            f.push(c).unwrap();
        }
        f
    };
    // Warm-up: the control begins, the window closes, buffers reach their size.
    let n = steady_allocations(&mut engine, frame_at, 120, 480);
    assert_eq!(n, 0, "480 control ticks allocated {n} times");
}

/// A formation transform driving the agents (social forces, subgroups, feedback,
/// measures, the progress message) allocates nothing in a steady tick: the run
/// reuses its buffers and progress messages are recycled.
#[test]
fn a_tick_of_a_running_transform_does_not_allocate() {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 300;
    let mut engine = Engine::new(&cfg, None, true);
    drop(engine.tick(Micros(0)));
    engine.clear_events();
    // Prepared in the tick (as in replays): a one-off, not counted.
    engine.set_formation("arrow", Micros(1)).unwrap();
    assert!(engine.transform_running());
    for k in 1..40 {
        let out = engine.tick(Micros(k * 8_333));
        assert!(out.transform.is_some());
        drop(out);
        engine.clear_events();
    }
    let mut progressed = 0;
    let n = allocations(|| {
        for k in 40..160 {
            let out = engine.tick(Micros(k * 8_333));
            assert!(out.events.is_empty() && out.transform_end.is_none());
            progressed += usize::from(out.transform.is_some());
            drop(out);
            engine.clear_events();
        }
    });
    assert_eq!(
        progressed, 120,
        "the transform ran through the counted ticks"
    );
    assert_eq!(n, 0, "120 transform ticks allocated {n} times");
}

/// After a fast one-finger drag lifts, the crowd goes on through the rest of the
/// drag's check points: those ticks allocate nothing either.
#[test]
fn a_tick_of_a_lifted_drag_going_on_does_not_allocate() {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 200;
    let mut engine = Engine::new(&cfg, None, false);
    // 6.4 cm a tick (7.7 m/s): faster than the handle may follow (3 m/s).
    let frame_at = |k: u64, flags: ContactFlags| {
        let mut f = TouchFrame::new(Micros(k * 8_333));
        let c = Contact {
            id: ContactId(1),
            x: 0.5 + k as f32 * 0.004,
            y: 0.5,
            flags,
            ..Contact::default()
        };
        f.push(c).unwrap();
        f
    };
    for k in 0..=40 {
        let flags = match k {
            0 => ContactFlags::DOWN,
            40 => ContactFlags::UP,
            _ => ContactFlags::NONE,
        };
        engine.push_frame(&frame_at(k, flags));
        drop(engine.tick(Micros(k * 8_333)));
        engine.clear_events();
    }
    let at_lift = engine.mesh_view().vertices.clone();
    let n = allocations(|| {
        for k in 41..101 {
            drop(engine.tick(Micros(k * 8_333)));
            engine.clear_events();
        }
    });
    let moved = engine.mesh_view().vertices[0].x - at_lift[0].x;
    assert!(moved > 0.5, "the drag went on after the lift: {moved} m");
    assert_eq!(n, 0, "60 ticks of a lifted drag allocated {n} times");
}

/// Warm-up ticks of the scene tests (1 s at 120 Hz): the drag into the scene.
const SCENE_WARM_UP: u64 = 120;
/// Ticks counted in the scene tests.
const SCENE_STEADY: u64 = 240;

/// Control ticks in a shipped scene, with an area control dragging the crowd
/// 2.0 m east and 1.5 m south into it during the warm-up and then holding it there
/// with small motions: returns the allocations of the [`SCENE_STEADY`] ticks after
/// the [`SCENE_WARM_UP`] and the engine. (Scene queries are slow in a debug build:
/// `agents` and the `mesh` size keep the run time in bounds.)
fn scene_ticks(scene: &str, agents: u32, mesh: (u32, u32)) -> (u64, Engine) {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    (cfg.mesh.cols, cfg.mesh.rows) = mesh;
    let scene = crowdtouch::crowd::environment::load_scene(
        std::path::Path::new(&format!("config/scenes/{scene}.ron")),
        cfg.crowd.agent_radius_m,
    )
    .expect("shipped scene loads");
    cfg.set_loaded_scene(Some(Arc::new(scene)));
    let mut engine = Engine::new(&cfg, None, false);
    let fingers = [(0.48f32, 0.45f32), (0.52, 0.45), (0.50, 0.52)];
    // Warm-up: to (+2.0 m, +1.5 m); then a 2 cm wobble.
    let offset = |k: u64| -> (f32, f32) {
        let s = (k.min(SCENE_WARM_UP) as f32) / SCENE_WARM_UP as f32;
        let wobble = 0.001 * ((k as f32) * 0.05).sin();
        (0.125 * s + wobble, 0.167 * s - wobble)
    };
    let frame_at = |k: u64, flags: ContactFlags| {
        let mut f = TouchFrame::new(Micros(k * 8_333));
        let (dx, dy) = offset(k);
        for (i, &(x, y)) in fingers.iter().enumerate() {
            let c = Contact {
                id: ContactId(i as u32 + 1),
                x: x + dx,
                y: y + dy,
                flags,
                ..Contact::default()
            };
            f.push(c).unwrap();
        }
        f
    };
    let n = steady_allocations(&mut engine, frame_at, SCENE_WARM_UP, SCENE_STEADY);
    (n, engine)
}

/// The steady tick in the obstacle course: the mesh pushed off obstacles by the
/// environment field, agents at their patch's speed, projected out of obstacles, and
/// their motions published. The test also checks that the crowd really is where
/// those paths run: some agents in a patch, some pressed against an obstacle.
#[test]
fn a_steady_control_tick_in_a_scene_does_not_allocate() {
    let (n, engine) = scene_ticks("obstacle_course", 200, (10, 8));
    let scene = Arc::clone(engine.scene().unwrap());
    let t = engine.scene_time_s();
    let r = engine.agent_radius_m();
    let in_patch = engine
        .motions()
        .iter()
        .filter(|m| **m != crowdtouch::vocab::MotionType::Run)
        .count();
    let against = engine
        .agent_positions()
        .iter()
        .filter(|p| scene.signed_distance(**p, t) < r + 0.02)
        .count();
    assert!(
        in_patch > 0,
        "no agent in a patch: the patch path did not run"
    );
    assert!(
        against > 0,
        "no agent at an obstacle: projection did not run"
    );
    assert_eq!(
        n, 0,
        "{SCENE_STEADY} control ticks in the obstacle course allocated {n} times"
    );
}

/// The same with moving obstacles (the street's cars): the final mesh is recomputed
/// every tick at the scene time. A small mesh: displacing and projecting its
/// vertices against the moving parts dominates the tick.
#[test]
fn a_steady_control_tick_among_moving_obstacles_does_not_allocate() {
    let (n, engine) = scene_ticks("street", 40, (6, 5));
    assert!(!engine.scene().unwrap().dynamic().is_empty());
    assert_eq!(
        n, 0,
        "{SCENE_STEADY} control ticks in the street allocated {n} times"
    );
}
