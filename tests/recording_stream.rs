//! Recordings read as streams, in every format: memory that does not grow with a
//! recording's length (heap bytes counted on the reading thread), over-long lines
//! and over-full frames refused before they are buffered, unknown keys skipped
//! unread, time jumps warned about at their line, and gaps that cost nothing to
//! replay, up to `u64::MAX` timestamps.
//!
//! The files are generated in a temporary directory, at sizes that show the
//! growth (or its absence) without making the tests slow; the issue's full-size
//! reproductions are measured with the release build in `docs/benchmarks.md`.

mod common;

use crowdtouch::config::Config;
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::input::recording::{
    OnBadFrame, RecordingError, RecordingStream, JUMP_REPLAYED_US, MAX_LINE_BYTES, MAX_TIME_JUMP_US,
};
use crowdtouch::input::replay::MAX_GAP_US;
use crowdtouch::vocab::{Contact, ContactFlags, ContactId, Micros, TouchFrame};
use proptest::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::convert::Infallible;
use std::io::Write;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------------------
// Heap use of the calling thread

struct Counting;

thread_local! {
    static ARMED: Cell<bool> = const { Cell::new(false) };
    static LIVE: Cell<i64> = const { Cell::new(0) };
    static PEAK: Cell<i64> = const { Cell::new(0) };
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
}

fn grow(bytes: i64) {
    if ARMED.with(Cell::get) {
        let live = LIVE.with(|l| {
            l.set(l.get() + bytes);
            l.get()
        });
        PEAK.with(|p| p.set(p.get().max(live)));
        if bytes > 0 {
            ALLOCS.with(|a| a.set(a.get() + 1));
        }
    }
}

// SAFETY: forwards to the system allocator; only counts what threads that armed
// the counter do (thread-locals with const initialisers never allocate).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        grow(l.size() as i64);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        if ARMED.with(Cell::get) {
            LIVE.with(|v| v.set(v.get() - l.size() as i64));
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        grow(n as i64 - l.size() as i64);
        ALLOCS.with(|a| a.set(a.get() + u64::from(ARMED.with(Cell::get))));
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The most heap `f` held at once on this thread, in bytes, and its result.
fn peak_heap<T>(f: impl FnOnce() -> T) -> (T, i64) {
    LIVE.with(|l| l.set(0));
    PEAK.with(|p| p.set(0));
    ARMED.with(|a| a.set(true));
    let r = f();
    ARMED.with(|a| a.set(false));
    (r, PEAK.with(Cell::get))
}

/// Allocations `f` made on this thread.
fn allocations(f: impl FnOnce()) -> u64 {
    ALLOCS.with(|a| a.set(0));
    ARMED.with(|a| a.set(true));
    f();
    ARMED.with(|a| a.set(false));
    ALLOCS.with(Cell::get)
}

// ---------------------------------------------------------------------------
// Generated recordings

const JH: &str = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"gen","x":{"min":0,"max":32767,"resolution":27},"y":{"min":0,"max":32767,"resolution":48},"max_contacts":10}}"#;

/// A file in `dir` written by `body`.
fn gen(dir: &Path, name: &str, body: impl FnOnce(&mut dyn Write)) -> PathBuf {
    let path = dir.join(name);
    let mut w = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    body(&mut w);
    w.flush().unwrap();
    path
}

/// The issue's shape: a header, one frame with a contact, then `n` empty frames.
fn empty_frames(dir: &Path, n: usize) -> PathBuf {
    gen(dir, &format!("empty-{n}.jsonl"), |w| {
        writeln!(w, "{JH}").unwrap();
        writeln!(
            w,
            r#"{{"t_us":0,"contacts":[{{"id":1,"x":16000,"y":16000}}]}}"#
        )
        .unwrap();
        for i in 1..=n {
            writeln!(w, r#"{{"t_us":{},"contacts":[]}}"#, i * 8333).unwrap();
        }
    })
}

/// One contact dragged for `n` frames (the issue's 200k-frame shape).
fn long_drag(dir: &Path, n: usize) -> PathBuf {
    gen(dir, &format!("drag-{n}.jsonl"), |w| {
        writeln!(w, "{JH}").unwrap();
        for i in 0..n {
            let x = 1000 + (i * 7) % 30000;
            writeln!(
                w,
                r#"{{"t_us":{},"contacts":[{{"id":1,"x":{x},"y":2000}}]}}"#,
                i * 8333
            )
            .unwrap();
        }
    })
}

const EH: &str =
    "N: gen\nA: 2f 0 9 0 0 0\nA: 35 0 1000 0 0 0\nA: 36 0 1000 0 0 0\nA: 39 0 65535 0 0 0\n";

/// An evemu recording of `n` touches (down, two moves, up).
fn evemu_taps(dir: &Path, n: usize) -> PathBuf {
    gen(dir, &format!("taps-{n}.evemu"), |w| {
        write!(w, "{EH}").unwrap();
        let mut t = 0u64;
        let ev = |w: &mut dyn Write, t: u64, ty: u16, code: u16, v: i32| {
            writeln!(
                w,
                "E: {}.{:06} {ty:04x} {code:04x} {v}",
                t / 1_000_000,
                t % 1_000_000
            )
            .unwrap();
        };
        for i in 0..n {
            let id = (i % 60000) as i32;
            for (k, tid) in [(0, id), (1, -2), (2, -2), (3, -1)] {
                t += 8333;
                match tid {
                    -2 => ev(w, t, 3, 0x35, 100 + k),
                    tid => {
                        ev(w, t, 3, 0x39, tid);
                        if tid >= 0 {
                            ev(w, t, 3, 0x35, 100);
                            ev(w, t, 3, 0x36, 100);
                        }
                    }
                }
                ev(w, t, 0, 0, 0);
            }
        }
    })
}

const YH: &str = "version: 1\ndevices:\n- evdev:\n    name: gen\n    absinfo:\n      47: [0, 9, 0, 0, 0]\n      53: [0, 1000, 0, 0, 0]\n      54: [0, 1000, 0, 0, 0]\n      57: [0, 65535, 0, 0, 0]\n  events:\n";

/// A libinput record of `n` touches.
fn yaml_taps(dir: &Path, n: usize) -> PathBuf {
    gen(dir, &format!("taps-{n}.yml"), |w| {
        write!(w, "{YH}").unwrap();
        let mut t = 0u64;
        for i in 0..n {
            for (code, v) in [(0x39, (i % 60000) as i64), (0x35, 200), (0x39, -1)] {
                t += 8333;
                let (s, us) = (t / 1_000_000, t % 1_000_000);
                writeln!(
                    w,
                    "  - evdev:\n    - [{s}, {us}, 3, {code}, {v}]\n    - [{s}, {us}, 0, 0, 0]"
                )
                .unwrap();
            }
        }
    })
}

/// The Wacom hid-recorder fixture's reports repeated `n` times, later each time.
fn hid_repeated(dir: &Path, n: usize) -> PathBuf {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/hid/wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid");
    let text = std::fs::read_to_string(fixture).unwrap();
    gen(dir, &format!("wacom-{n}.hid"), |w| {
        for l in text.lines().filter(|l| !l.starts_with("E:")) {
            writeln!(w, "{l}").unwrap();
        }
        for k in 0..n as u64 {
            for l in text.lines().filter(|l| l.starts_with("E:")) {
                let (time, rest) = l[3..].split_once(' ').unwrap();
                let (s, us) = time.split_once('.').unwrap();
                let t = s.parse::<u64>().unwrap() * 1_000_000 + us.parse::<u64>().unwrap();
                let t = t + k * 1_000_000;
                writeln!(w, "E: {:06}.{:06} {rest}", t / 1_000_000, t % 1_000_000).unwrap();
            }
        }
    })
}

/// Streams a recording to its end: frames, warnings and the error, if any.
fn stream_all(
    path: &Path,
    on_bad: OnBadFrame,
) -> (u64, Vec<(usize, String)>, Option<RecordingError>) {
    let mut warnings = Vec::new();
    let mut s = match RecordingStream::open(path, on_bad) {
        Ok(s) => s,
        Err(e) => return (0, warnings, Some(e)),
    };
    let mut err = None;
    loop {
        match s.next_frame() {
            Ok(Some(_)) => {}
            Ok(None) => break,
            Err(e) => {
                err = Some(e);
                break;
            }
        }
        warnings.extend(s.take_warnings().into_iter().map(|w| (w.line, w.message)));
    }
    warnings.extend(s.take_warnings().into_iter().map(|w| (w.line, w.message)));
    (s.frames_read(), warnings, err)
}

/// Heap held at most while streaming a recording; the reading must succeed.
fn streaming_peak(path: &Path) -> (u64, i64) {
    let ((frames, _, err), peak) = peak_heap(|| stream_all(path, OnBadFrame::Stop));
    assert!(err.is_none(), "{}: {err:?}", path.display());
    (frames, peak)
}

// ---------------------------------------------------------------------------
// Memory independent of length

/// Most heap a stream may hold: its file buffer (64 KiB), a line, one or two
/// frames and its decoder, with room to spare; far below a frame per line.
const STREAM_HEAP_BYTES: i64 = 512 * 1024;

/// The same shape at two lengths, ten times apart, takes the same heap.
fn assert_flat(make: impl Fn(&Path, usize) -> PathBuf, small: usize) {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (make(dir.path(), small), make(dir.path(), small * 10));
    let ((fa, pa), (fb, pb)) = (streaming_peak(&a), streaming_peak(&b));
    assert!(fb > fa * 5, "{fa} vs {fb} frames");
    assert!(pb < STREAM_HEAP_BYTES, "{}: {pb} bytes", b.display());
    // Warnings and buffers may differ by a few hundred bytes, not by frames.
    assert!(pb - pa < 8 * 1024, "{}: {pa} → {pb} bytes", b.display());
}

#[test]
fn jsonl_streams_in_memory_independent_of_length() {
    assert_flat(empty_frames, 10_000);
    assert_flat(long_drag, 5_000);
}

#[test]
fn evemu_streams_in_memory_independent_of_length() {
    assert_flat(evemu_taps, 1_000);
}

#[test]
fn libinput_yaml_streams_in_memory_independent_of_length() {
    assert_flat(yaml_taps, 500);
}

#[test]
fn hid_recorder_streams_in_memory_independent_of_length() {
    assert_flat(hid_repeated, 20);
}

/// Past the first frames, reading a frame allocates nothing (JSON Lines, evemu,
/// hid-recorder): the input thread's steady state.
#[test]
fn streaming_a_frame_allocates_nothing_in_steady_state() {
    let dir = tempfile::tempdir().unwrap();
    for path in [
        long_drag(dir.path(), 3_000),
        evemu_taps(dir.path(), 500),
        hid_repeated(dir.path(), 10),
    ] {
        let mut s = RecordingStream::open(&path, OnBadFrame::Stop).unwrap();
        for _ in 0..100 {
            s.next_frame().unwrap().unwrap();
        }
        let mut frames = 0;
        let n = allocations(|| {
            while frames < 1000 {
                match s.next_frame() {
                    Ok(Some(_)) => frames += 1,
                    _ => break,
                }
            }
        });
        assert!(frames > 300, "{}: {frames}", path.display());
        assert_eq!(
            n,
            0,
            "{}: {n} allocations in {frames} frames",
            path.display()
        );
    }
}

// ---------------------------------------------------------------------------
// Lines, contacts and keys refused or skipped before they are kept

#[test]
fn an_over_long_line_is_refused_before_it_is_buffered() {
    let dir = tempfile::tempdir().unwrap();
    // The issue's 1.9-million-contact frame, at two megabytes.
    let path = gen(dir.path(), "wide.jsonl", |w| {
        writeln!(w, "{JH}").unwrap();
        write!(w, r#"{{"t_us":0,"contacts":["#).unwrap();
        for i in 0..100_000 {
            write!(w, r#"{{"id":{i},"x":1,"y":2}},"#).unwrap();
        }
        writeln!(w, r#"{{"id":0,"x":1,"y":2}}]}}"#).unwrap();
        writeln!(w, r#"{{"t_us":5,"contacts":[{{"id":1,"x":1,"y":2}}]}}"#).unwrap();
    });
    assert!(std::fs::metadata(&path).unwrap().len() > 2 * MAX_LINE_BYTES as u64);
    let ((_, _, err), peak) = peak_heap(|| stream_all(&path, OnBadFrame::Stop));
    match err {
        Some(RecordingError::Parse {
            line: 2, message, ..
        }) => {
            assert!(message.contains("longer than"), "{message}")
        }
        e => panic!("{e:?}"),
    }
    assert!(
        peak < 2 * MAX_LINE_BYTES as i64 + STREAM_HEAP_BYTES,
        "{peak}"
    );
    // Skipping it reads on.
    let (frames, warnings, err) = stream_all(&path, OnBadFrame::Skip);
    assert!(err.is_none(), "{err:?}");
    assert_eq!(frames, 2); // the last frame, and its cancel
    assert_eq!(warnings[0].0, 2);
    assert!(warnings[0].1.contains("frame skipped"), "{warnings:?}");
}

#[test]
fn a_frame_over_the_headers_max_contacts_is_refused_unkept() {
    let dir = tempfile::tempdir().unwrap();
    let path = gen(dir.path(), "full.jsonl", |w| {
        writeln!(w, "{JH}").unwrap();
        let contacts: Vec<String> = (0..5_000)
            .map(|i| format!(r#"{{"id":{i},"x":1,"y":2}}"#))
            .collect();
        writeln!(w, r#"{{"t_us":0,"contacts":[{}]}}"#, contacts.join(",")).unwrap();
    });
    let ((_, _, err), peak) = peak_heap(|| stream_all(&path, OnBadFrame::Stop));
    match err {
        Some(RecordingError::Parse {
            line: 2, message, ..
        }) => assert!(
            message.contains("more than the 10 contacts") && message.contains("max_contacts"),
            "{message}"
        ),
        e => panic!("{e:?}"),
    }
    // The line is buffered (under the line limit); the contacts are not.
    assert!(peak < STREAM_HEAP_BYTES + 256 * 1024, "{peak}");
}

#[test]
fn unknown_keys_are_skipped_without_being_kept() {
    let dir = tempfile::tempdir().unwrap();
    // The issue's 30-million-zero key, at 400 thousand (just under the line limit).
    let path = gen(dir.path(), "junk.jsonl", |w| {
        writeln!(w, "{JH}").unwrap();
        write!(w, r#"{{"t_us":0,"junk":{{"a":["#).unwrap();
        for _ in 0..400_000 {
            write!(w, "0,").unwrap();
        }
        writeln!(
            w,
            r#"0]}},"contacts":[{{"id":1,"x":1,"y":2,"note":"x"}}]}}"#
        )
        .unwrap();
    });
    let ((frames, warnings, err), peak) = peak_heap(|| stream_all(&path, OnBadFrame::Stop));
    assert!(err.is_none() && warnings.is_empty(), "{err:?} {warnings:?}");
    assert_eq!(frames, 2);
    // A tree of 400 000 values would take more than 12 MB.
    assert!(peak < MAX_LINE_BYTES as i64 + STREAM_HEAP_BYTES, "{peak}");
}

// ---------------------------------------------------------------------------
// Time jumps: a located warning in every format, shortened

/// The frames' times and the warnings of a recording held in memory.
fn times(text: &str, name: &str) -> (Vec<u64>, Vec<(usize, String)>) {
    let mut s =
        RecordingStream::from_bytes(text.as_bytes().to_vec(), Path::new(name), OnBadFrame::Stop)
            .unwrap();
    let mut t = Vec::new();
    while let Some(f) = s.next_frame().unwrap() {
        t.push(f.t.0);
    }
    let w = s
        .take_warnings()
        .into_iter()
        .map(|w| (w.line, w.message))
        .collect();
    (t, w)
}

fn assert_jump(text: &str, name: &str, line: usize, unit: &str) {
    let (t, w) = times(text, name);
    assert_eq!(w.len(), 1, "{name}: {w:?}");
    assert_eq!(w[0].0, line, "{name}: {w:?}");
    assert!(
        w[0].1.starts_with("timestamp jumps by ") && w[0].1.contains(unit),
        "{name}: {}",
        w[0].1
    );
    let gaps: Vec<u64> = t.windows(2).map(|p| p[1] - p[0]).collect();
    assert!(gaps.contains(&JUMP_REPLAYED_US), "{name}: {t:?}");
    assert!(gaps.iter().all(|&g| g <= MAX_TIME_JUMP_US), "{name}: {t:?}");
}

#[test]
fn a_jump_of_decades_is_a_located_warning_in_every_format() {
    let drag = std::fs::read_to_string(common::shipped("01-point-drag.jsonl")).unwrap();
    let mut jsonl: String = drag.lines().take(6).map(|l| format!("{l}\n")).collect();
    jsonl.push_str("{\"t_us\":18446744073709551615,\"contacts\":[]}\n");
    assert_jump(&jsonl, "gap.jsonl", 7, "years");

    let tap = |t: &str, id: i32| {
        format!("E: {t} 0003 0039 {id}\nE: {t} 0003 0035 5\nE: {t} 0000 0000 0\n")
    };
    let evemu = format!("{EH}{}{}", tap("1.0", 1), tap("1000000001.0", -1));
    assert_jump(&evemu, "gap.evemu", 11, "years");

    let yaml = format!(
        "{YH}  - evdev:\n    - [1, 0, 3, 57, 1]\n    - [1, 0, 0, 0, 0]\n  - evdev:\n    - [864001, 0, 3, 53, 9]\n    - [864001, 0, 0, 0, 0]\n  - evdev:\n    - [864002, 0, 3, 57, -1]\n    - [864002, 0, 0, 0, 0]\n"
    );
    assert_jump(&yaml, "gap.yml", 16, "days");

    let hid =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(
            "tests/fixtures/hid/wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
        ))
        .unwrap();
    let mut seen = 0;
    let mut jump_line = 0;
    let shifted: String = hid
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if l.starts_with("E:") {
                seen += 1;
                if seen == 30 {
                    jump_line = i + 1;
                }
                if seen >= 30 {
                    return l.replacen("E: 000000.", "E: 999999999.", 1) + "\n";
                }
            }
            format!("{l}\n")
        })
        .collect();
    assert_jump(&shifted, "gap.hid", jump_line, "years");
}

// ---------------------------------------------------------------------------
// Gaps cost nothing to replay

fn small_cfg() -> Config {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 12;
    cfg
}

fn clock(cfg: &Config) -> VirtualClock {
    VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros(500_000),
        max_gap: Micros(MAX_GAP_US),
    }
}

/// Ticks of a virtual replay of `frames`, and the time of each.
fn ticks(frames: Vec<TouchFrame>) -> Vec<Micros> {
    let cfg = small_cfg();
    let mut engine = Engine::new(&cfg, None, true);
    let mut at = Vec::new();
    replay_virtual(
        &mut engine,
        frames.into_iter().map(Ok::<_, Infallible>),
        clock(&cfg),
        |_| {},
        |o| {
            at.push(o.snapshot.t);
            Ok(())
        },
    )
    .unwrap();
    at
}

fn frame(t: u64, contacts: &[(u32, ContactFlags)]) -> TouchFrame {
    let mut f = TouchFrame::new(Micros(t));
    for &(id, flags) in contacts {
        f.push(Contact {
            id: ContactId(id),
            x: 0.5,
            y: 0.5,
            flags,
            ..Contact::default()
        })
        .unwrap();
    }
    f
}

/// The most ticks a replay of `frames` frames may take at the default tick rate:
/// a gap's timer ticks and the frame's own, then half a second of settling.
fn tick_bound(frames: usize) -> usize {
    let period = clock(&small_cfg()).period.0;
    let per_gap = (MAX_GAP_US / period) as usize;
    frames * (per_gap + 1) + (500_000 / period) as usize
}

#[test]
fn a_gap_of_any_length_is_played_in_a_bounded_number_of_ticks() {
    // A contact held across the gap, ended at u64::MAX (no reader to shorten it).
    for end in [100_000_000, 1_000_000_000, u64::MAX] {
        let at = ticks(vec![
            frame(0, &[(1, ContactFlags::DOWN)]),
            frame(8_000, &[(1, ContactFlags::NONE)]),
            frame(end, &[(1, ContactFlags::UP)]),
        ]);
        assert!(at.len() <= tick_bound(3), "{end}: {} ticks", at.len());
        // The frame after the gap is played at its own time.
        assert!(at.contains(&Micros(end)), "{end}");
        assert!(at.windows(2).all(|w| w[0] <= w[1]));
    }
    // Nothing down: a run of empty frames is one gap.
    let mut frames = vec![
        frame(0, &[(1, ContactFlags::DOWN)]),
        frame(8_333, &[(1, ContactFlags::UP)]),
    ];
    frames.extend((2..100_000u64).map(|i| frame(i * 8_333, &[])));
    assert!(ticks(frames).len() <= tick_bound(3));
    // Frames at the very end of the clock.
    let at = ticks(vec![
        frame(u64::MAX - 5, &[(1, ContactFlags::DOWN)]),
        frame(u64::MAX, &[(1, ContactFlags::UP)]),
    ]);
    assert!(at.len() <= 3, "{at:?}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, rng_seed: proptest::test_runner::RngSeed::Fixed(0x6a95), failure_persistence: None, ..ProptestConfig::default() })]

    /// Any timestamps, any contacts: a replay ends, in a bounded number of ticks.
    #[test]
    fn replay_of_any_timestamps_ends_in_bounded_ticks(
        steps in proptest::collection::vec((prop_oneof![0u64..50_000, 0u64..10_000_000_000, Just(u64::MAX)], any::<bool>()), 1..12),
    ) {
        let mut t = 0u64;
        let mut down = false;
        let mut frames = Vec::new();
        for (dt, toggle) in steps {
            t = t.saturating_add(dt);
            let flags = match (down, toggle) {
                (false, true) => ContactFlags::DOWN,
                (true, true) => ContactFlags::UP,
                (true, false) => ContactFlags::NONE,
                (false, false) => {
                    frames.push(frame(t, &[]));
                    continue;
                }
            };
            down ^= toggle;
            frames.push(frame(t, &[(1, flags)]));
        }
        let n = frames.len();
        let at = ticks(frames);
        prop_assert!(at.len() <= tick_bound(n), "{} ticks for {n} frames", at.len());
        prop_assert!(at.windows(2).all(|w| w[0] <= w[1]));
    }

    /// Any `t_us`, up to `u64::MAX`: the reader never panics, times never go
    /// back, no gap is longer than a day, each longer jump is one warning.
    #[test]
    fn jsonl_timestamps_of_any_size(ts in proptest::collection::vec(prop_oneof![0u64..1_000_000, any::<u64>(), Just(u64::MAX)], 1..20)) {
        let mut text = format!("{JH}\n");
        for (i, t) in ts.iter().enumerate() {
            let id = 1 + (i % 2);
            text.push_str(&format!("{{\"t_us\":{t},\"contacts\":[{{\"id\":{id},\"x\":5,\"y\":5}}]}}\n"));
        }
        let mut s = RecordingStream::from_bytes(text.into_bytes(), Path::new("p"), OnBadFrame::Skip).unwrap();
        let mut out = Vec::new();
        while let Some(f) = s.next_frame().unwrap() {
            out.push(f.t.0);
        }
        prop_assert!(out.windows(2).all(|w| w[0] <= w[1] && w[1] - w[0] <= MAX_TIME_JUMP_US));
        let jumps = s.take_warnings().iter().filter(|w| w.message.starts_with("timestamp jumps")).count();
        let mut kept = Vec::new();
        for &t in &ts {
            if kept.last().is_none_or(|&p| t >= p) {
                kept.push(t);
            }
        }
        let expected = kept.windows(2).filter(|w| w[1] - w[0] > MAX_TIME_JUMP_US).count();
        prop_assert_eq!(jumps, expected);
    }

    /// evemu seconds of any size: an error or frames, never a panic.
    #[test]
    fn evemu_timestamps_of_any_size(secs in proptest::collection::vec(any::<u64>(), 1..6)) {
        let mut text = String::from(EH);
        let mut sorted = secs.clone();
        sorted.sort_unstable();
        for (i, s) in sorted.iter().enumerate() {
            let tid = if i + 1 == sorted.len() { -1 } else { 1 };
            text.push_str(&format!("E: {s}.000000 0003 0039 {tid}\nE: {s}.000000 0000 0000 0\n"));
        }
        for on_bad in [OnBadFrame::Stop, OnBadFrame::Skip] {
            if let Ok(mut s) = RecordingStream::from_bytes(text.clone().into_bytes(), Path::new("e"), on_bad) {
                let mut prev = 0;
                while let Ok(Some(f)) = s.next_frame() {
                    prop_assert!(f.t.0 >= prev);
                    prev = f.t.0;
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------
// The binary on the reproductions

fn bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

/// Runs `replay` on `path` with `args`, and returns (success, snapshot lines, stderr).
fn replay(path: &Path, args: &[&str]) -> (bool, usize, String) {
    let out = bin()
        .arg("replay")
        .args(["--agents", "12", "--settle", "0.5"])
        .args(args)
        .arg(path)
        .output()
        .unwrap();
    let lines = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.contains("\"type\":\"snapshot\""))
        .count();
    (
        out.status.success(),
        lines,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn replay_of_a_u64_max_timestamp_ends_with_a_located_warning() {
    let dir = tempfile::tempdir().unwrap();
    let drag = std::fs::read_to_string(common::shipped("01-point-drag.jsonl")).unwrap();
    let path = gen(dir.path(), "gap-max.jsonl", |w| {
        for l in drag.lines().take(6) {
            writeln!(w, "{l}").unwrap();
        }
        writeln!(w, "{{\"t_us\":18446744073709551615,\"contacts\":[]}}").unwrap();
    });
    let (ok, snapshots, err) = replay(&path, &[]);
    assert!(ok, "{err}");
    assert!(
        err.contains("gap-max.jsonl:7: warning: timestamp jumps by"),
        "{err}"
    );
    assert!(snapshots <= tick_bound(6), "{snapshots}");
}

#[test]
fn replay_of_many_empty_frames_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let path = empty_frames(dir.path(), 50_000);
    let (ok, snapshots, err) = replay(&path, &[]);
    assert!(ok, "{err}");
    assert!(snapshots <= tick_bound(3), "{snapshots}");
}

#[test]
fn replay_refuses_an_over_long_line_at_its_line_or_skips_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = gen(dir.path(), "junk.jsonl", |w| {
        writeln!(w, "{JH}").unwrap();
        writeln!(w, r#"{{"t_us":0,"contacts":[{{"id":1,"x":1,"y":2}}]}}"#).unwrap();
        write!(w, r#"{{"t_us":1,"contacts":[],"junk":["#).unwrap();
        for _ in 0..(MAX_LINE_BYTES / 2 + 10) {
            write!(w, "0,").unwrap();
        }
        writeln!(w, "0]}}").unwrap();
        writeln!(w, r#"{{"t_us":2,"contacts":[{{"id":1,"x":1,"y":2}}]}}"#).unwrap();
    });
    let (ok, _, err) = replay(&path, &[]);
    assert!(!ok);
    assert!(
        err.contains("junk.jsonl:3: the line is longer than"),
        "{err}"
    );
    let (ok, snapshots, err) = replay(&path, &["--skip-bad-frames"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("junk.jsonl:3: warning:") && err.contains("frame skipped"),
        "{err}"
    );
    assert!(snapshots > 0);
}

// ---------------------------------------------------------------------------
// `run`: a replay source is checked before it starts, then streamed

#[test]
fn run_refuses_a_bad_frame_deep_in_a_recording_before_it_starts() {
    use crowdtouch::config::InputConfig;
    use crowdtouch::pipeline::{sources_from_config, SourceSpec};
    let dir = tempfile::tempdir().unwrap();
    let good = long_drag(dir.path(), 2_000);
    let bad = gen(dir.path(), "bad.jsonl", |w| {
        w.write_all(&std::fs::read(&good).unwrap()).unwrap();
        writeln!(w, r#"{{"t_us":1,"contacts":[]}}"#).unwrap();
    });
    let mut cfg = Config::embedded_default();
    let replay = |files: Vec<PathBuf>| InputConfig::Replay {
        files,
        looped: true,
        gap_ms: 0,
        reset_between: false,
    };
    cfg.inputs = vec![replay(vec![good.clone(), bad])];
    let err = sources_from_config(&cfg)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("bad.jsonl:2002:") && err.contains("earlier"),
        "{err}"
    );
    cfg.inputs = vec![replay(vec![good])];
    match sources_from_config(&cfg).unwrap().pop() {
        Some(SourceSpec::Replay {
            items, glass_mm, ..
        }) => {
            assert_eq!(items.len(), 1);
            assert_eq!(items[0].name(), "drag-2000.jsonl");
            let (w, h) = glass_mm.unwrap();
            assert!((w - 32767.0 / 27.0).abs() < 1e-6 && (h - 32767.0 / 48.0).abs() < 1e-6);
        }
        _ => panic!("not a replay source"),
    }
}
