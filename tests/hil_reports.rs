//! The hardware-in-the-loop harness generates a real device's input reports from its
//! descriptor with its own, independent HID parser (`hil/hidgen.py`), so a HIL failure
//! points at the daemon, not at the harness. Here the two are checked against each
//! other on the host: every report the harness would send for the HIL devices decodes,
//! through the daemon's own `HidDecoder`, to exactly the contacts the harness meant.
//!
//! Needs `python3` (the harness's only requirement); without it the test says so and
//! passes, as the HIL stage itself is then skipped too.

use crowdtouch::input::hid::{touch_collections, HidDecoder};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{ContactFlags, TouchFrame};
use std::path::{Path, PathBuf};
use std::process::Command;

fn descriptor(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/hid/descriptors")
        .join(name)
}

/// (id, x, y, tip) in logical units.
type Spec = Vec<(u32, u32, u32, bool)>;

fn hidgen(name: &str, frames: &[Spec]) -> Option<Vec<Vec<Vec<u8>>>> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("hil/hidgen.py");
    let args: Vec<String> = frames
        .iter()
        .map(|f| {
            f.iter()
                .map(|&(i, x, y, t)| format!("{i}:{x}:{y}:{}", u8::from(t)))
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect();
    let out = match Command::new("python3")
        .arg(&script)
        .arg("reports")
        .arg(descriptor(name))
        .args(&args)
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            eprintln!("SKIPPED: python3 not runnable ({e}); the HIL stage needs it too");
            return None;
        }
    };
    assert!(
        out.status.success(),
        "hidgen failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    Some(
        text.lines()
            .map(|l| {
                l.split_whitespace()
                    .map(|h| {
                        (0..h.len())
                            .step_by(2)
                            .map(|i| u8::from_str_radix(&h[i..i + 2], 16).unwrap())
                            .collect()
                    })
                    .collect()
            })
            .collect(),
    )
}

/// Feeds each frame's reports; returns the frame the decoder completed for it.
fn decode(name: &str, reports: &[Vec<Vec<u8>>]) -> Vec<TouchFrame> {
    let bytes = std::fs::read(descriptor(name)).unwrap();
    let c = touch_collections(&bytes).unwrap().remove(0);
    let mut dec = HidDecoder::new(&c);
    let mut frames = Vec::new();
    for (k, frame) in reports.iter().enumerate() {
        let mut f = TouchFrame::default();
        let mut done = 0;
        for r in frame {
            if dec.report(Micros(1000 * (k as u64 + 1)), r, &mut f) {
                done += 1;
            }
        }
        assert_eq!(
            done,
            1,
            "{name}: frame {k} ({} reports) completes exactly once",
            frame.len()
        );
        frames.push(f);
    }
    frames
}

/// Down, move, one lift while others stay, all lifted; `n` contacts.
fn script(n: u32, (xmax, ymax): (u32, u32)) -> Vec<Spec> {
    let at = |i: u32, step: u32| (xmax / 4 + i * xmax / 40 + step * 7, ymax / 3 + step * 5);
    let down: Spec = (0..n)
        .map(|i| (i + 1, at(i, 0).0, at(i, 0).1, true))
        .collect();
    let moved: Spec = (0..n)
        .map(|i| (i + 1, at(i, 1).0, at(i, 1).1, true))
        .collect();
    let mut one_up = moved.clone();
    one_up[0].3 = false;
    let rest: Spec = moved[1..]
        .iter()
        .map(|&(i, x, y, _)| (i, x, y, false))
        .collect();
    vec![down, moved, one_up, rest]
}

fn check(name: &str, n: u32, range: (u32, u32)) {
    let frames = script(n, range);
    let Some(reports) = hidgen(name, &frames) else {
        return;
    };
    let got = decode(name, &reports);
    for (k, (want, f)) in frames.iter().zip(&got).enumerate() {
        // Contacts lifted in an earlier frame are no longer reported.
        let live: Vec<_> = want.iter().collect();
        assert_eq!(
            f.contacts().len(),
            live.len(),
            "{name} frame {k}: contact count"
        );
        for &&(id, x, y, tip) in &live {
            let c = f
                .contacts()
                .iter()
                .find(|c| c.id.0 == id)
                .unwrap_or_else(|| panic!("{name} frame {k}: contact {id} missing"));
            let (ex, ey) = (x as f32 / range.0 as f32, y as f32 / range.1 as f32);
            assert!(
                (c.x - ex).abs() < 1e-4 && (c.y - ey).abs() < 1e-4,
                "{name} frame {k} contact {id}: ({}, {}) vs ({ex}, {ey})",
                c.x,
                c.y
            );
            let flags = c.flags;
            if k == 0 {
                assert!(flags.contains(ContactFlags::DOWN), "{name}: {id} down");
            }
            assert_eq!(flags.ended(), !tip, "{name} frame {k}: contact {id} ended");
        }
    }
}

#[test]
fn parallel_reports_with_report_id_16() {
    check("3m_0596_0500.rdesc", 5, (32767, 32767));
}

#[test]
fn hybrid_reports_twelve_contacts_in_two() {
    check("zytronic_14c8_0006.rdesc", 12, (4096, 4096));
}

#[test]
fn hybrid_reports_one_contact_each_with_report_id_3() {
    check("ite_06cb_2968.rdesc", 5, (1051, 571));
}
