//! `crowdtouch calibrate`: touch four targets, get a calibration matrix.
//!
//! The person touches four points shown as positions on the table (printed here as a
//! map and percentages). Each capture is the mean position of the first finger from
//! [`SETTLE_US`] after it lands until it lifts. The matrix maps the device's raw
//! unit-square coordinates so that, after the configured rotation and flips, the
//! touches land on the targets (libinput's LIBINPUT_CALIBRATION_MATRIX convention).

use crate::cli::common::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use crowdtouch::config::{CalibrationConfig, Config, InputConfig};
use crowdtouch::input::calibrate::{apply_matrix, solve_matrix, Calibration, Matrix};
use crowdtouch::input::FrameSink;
use crowdtouch::pipeline::device::{DeviceEnv, SystemEnv};
use crowdtouch::vocab::{ContactFlags, ContactId, TouchFrame};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The four targets, in table units (x right, y down): 10 % in from each corner.
pub const TARGETS: [(f64, f64); 4] = [(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9)];
/// Samples taken after a finger lands are ignored for this long (µs), while it settles.
pub const SETTLE_US: u64 = 100_000;
/// How long a person has for each target.
pub const TARGET_TIMEOUT: Duration = Duration::from_secs(60);

/// Collects one touch per target from a stream of frames.
#[derive(Debug, Default)]
pub struct Session {
    touched: Vec<(f64, f64)>,
    current: Option<Capture>,
}

#[derive(Debug)]
struct Capture {
    id: ContactId,
    t_down: u64,
    first: (f64, f64),
    sum: (f64, f64),
    n: u32,
}

/// What a frame did to the session.
#[derive(Clone, Debug, PartialEq)]
pub enum Progress {
    /// Nothing yet for this target.
    Waiting,
    /// A finger is on the glass.
    Holding,
    /// Target `i` captured at this raw position.
    Captured(usize, (f64, f64)),
}

impl Session {
    /// Raw positions captured so far, one per target.
    #[cfg(test)]
    pub fn touched(&self) -> &[(f64, f64)] {
        &self.touched
    }

    /// Whether every target has a capture.
    pub fn done(&self) -> bool {
        self.touched.len() >= TARGETS.len()
    }

    /// Feeds one raw (uncalibrated) frame.
    pub fn frame(&mut self, f: &TouchFrame) -> Progress {
        let mut progress = if self.current.is_some() {
            Progress::Holding
        } else {
            Progress::Waiting
        };
        for c in f.contacts() {
            if c.flags.contains(ContactFlags::PALM) {
                continue;
            }
            let p = (c.x as f64, c.y as f64);
            let done = self.done();
            match &mut self.current {
                None if c.flags.contains(ContactFlags::DOWN) && !done => {
                    self.current = Some(Capture {
                        id: c.id,
                        t_down: f.t.0,
                        first: p,
                        sum: (0.0, 0.0),
                        n: 0,
                    });
                    progress = Progress::Holding;
                }
                Some(cap) if cap.id == c.id && f.t.0.saturating_sub(cap.t_down) >= SETTLE_US => {
                    cap.sum.0 += p.0;
                    cap.sum.1 += p.1;
                    cap.n += 1;
                }
                _ => {}
            }
            let ends = self.current.as_ref().is_some_and(|cap| cap.id == c.id) && c.flags.ended();
            if ends {
                let cap = self
                    .current
                    .take()
                    .unwrap_or_else(|| unreachable!("checked above"));
                if c.flags.contains(ContactFlags::CANCELLED) {
                    progress = Progress::Waiting;
                    continue;
                }
                let at = if cap.n > 0 {
                    (cap.sum.0 / cap.n as f64, cap.sum.1 / cap.n as f64)
                } else {
                    cap.first
                };
                self.touched.push(at);
                progress = Progress::Captured(self.touched.len() - 1, at);
            }
        }
        progress
    }

    /// The matrix for `rotation`/flips: raw touches → (after rotation and flips) targets.
    ///
    /// # Errors
    /// When the touches are too few or degenerate (e.g. all at one spot).
    pub fn matrix(&self, cal: &CalibrationConfig) -> Result<Matrix> {
        let after = Calibration {
            rotation: cal.rotation,
            flip_x: cal.flip_x,
            flip_y: cal.flip_y,
            matrix: None,
        }
        .combined(None)
        .map_err(|e| anyhow!("{e}"))?;
        let inv =
            invert(&after).ok_or_else(|| anyhow!("rotation/flip matrix is not invertible"))?;
        let targets: Vec<(f64, f64)> = TARGETS
            .iter()
            .map(|&(x, y)| apply_matrix(&inv, x, y))
            .collect();
        solve_matrix(&targets, &self.touched)
            .map_err(|e| anyhow!("cannot compute a calibration: {e}"))
    }
}

/// Inverse of an affine 2×3 matrix.
fn invert(m: &Matrix) -> Option<Matrix> {
    let [a, b, c, d, e, f] = *m;
    let det = a * e - b * d;
    if det.abs() < 1e-12 {
        return None;
    }
    let (ia, ib, id, ie) = (e / det, -b / det, -d / det, a / det);
    Some([ia, ib, -(ia * c + ib * f), id, ie, -(id * c + ie * f)])
}

/// A map of the table with target `i` marked, for the terminal.
pub fn target_map(i: usize) -> String {
    const W: usize = 41;
    const H: usize = 13;
    let mut rows = vec![vec![' '; W]; H];
    for (k, &(x, y)) in TARGETS.iter().enumerate() {
        let (cx, cy) = (
            ((W - 1) as f64 * x).round() as usize,
            ((H - 1) as f64 * y).round() as usize,
        );
        rows[cy][cx] = if k == i {
            '@'
        } else if k < i {
            '+'
        } else {
            '.'
        };
    }
    let mut s = format!("┌{}┐\n", "─".repeat(W));
    for r in rows {
        s.push('│');
        s.extend(r);
        s.push_str("│\n");
    }
    s.push_str(&format!("└{}┘", "─".repeat(W)));
    s
}

struct ChannelSink(crossbeam_channel::Sender<TouchFrame>);

impl FrameSink for ChannelSink {
    fn push(&mut self, frame: &TouchFrame) {
        let _ = self.0.try_send(*frame);
    }
}

/// Runs the interactive calibration of input `input` (the first `Device` input
/// when `None`) of the config at `path`.
pub fn calibrate(
    cfg: &Config,
    path: Option<&Path>,
    input: Option<usize>,
    write: bool,
) -> Result<()> {
    let (index, select, interface, calibration) = cfg
        .inputs
        .iter()
        .enumerate()
        .find_map(|(i, inp)| match inp {
            InputConfig::Device {
                select,
                interface,
                calibration,
                ..
            } if input.is_none_or(|n| n == i) => {
                Some((i, select.clone(), *interface, calibration.clone()))
            }
            _ => None,
        })
        .ok_or_else(|| match input {
            Some(n) => anyhow!("inputs[{n}] of the config is not a Device input"),
            None => anyhow!("the config has no Device input (see config/kiosk.ron)"),
        })?;
    let mut env = SystemEnv::new(Path::new("/"), false);
    let info = env
        .find(&select, interface, None)
        .map_err(|e| anyhow!("no touch device: {e}"))?;
    let mut reader = env.open(&info)?;
    outln!(
        "Calibrating {} ({}) for inputs[{index}].",
        info.identity.name,
        info.identity.node.display()
    )?;
    outln!(
        "Touch each target on the table with one finger, hold it still for a moment, then lift.\n"
    )?;
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = crossbeam_channel::bounded::<TouchFrame>(1024);
    let reader_stop = Arc::clone(&stop);
    let handle = std::thread::spawn(move || reader.run(&mut ChannelSink(tx), &reader_stop));
    let mut session = Session::default();
    let names = ["top-left", "top-right", "bottom-right", "bottom-left"];
    let result = (|| -> Result<()> {
        for (i, &(x, y)) in TARGETS.iter().enumerate() {
            outln!("{}", target_map(i))?;
            outln!(
                "Target {} of 4 ({}): {:.0} % from the left edge, {:.0} % from the top.",
                i + 1,
                names[i],
                x * 100.0,
                y * 100.0
            )?;
            let deadline = Instant::now() + TARGET_TIMEOUT;
            loop {
                let left = deadline.saturating_duration_since(Instant::now());
                let f = rx.recv_timeout(left).map_err(|_| {
                    anyhow!(
                        "no touch for target {} within {} s",
                        i + 1,
                        TARGET_TIMEOUT.as_secs()
                    )
                })?;
                if let Progress::Captured(_, at) = session.frame(&f) {
                    outln!("  captured at raw ({:.4}, {:.4})\n", at.0, at.1)?;
                    break;
                }
            }
        }
        Ok(())
    })();
    stop.store(true, Ordering::SeqCst);
    let _ = handle.join();
    result?;
    let m = session.matrix(&calibration)?;
    let ron = format!(
        "matrix: Some(({:.6}, {:.6}, {:.6}, {:.6}, {:.6}, {:.6}))",
        m[0], m[1], m[2], m[3], m[4], m[5]
    );
    outln!(
        "Calibration matrix (libinput convention): {}",
        m.map(|v| format!("{v:.6}")).join(" ")
    )?;
    match (write, path) {
        (true, Some(p)) => {
            let text = crowdtouch::located::read_text(p, crowdtouch::config::MAX_CONFIG_BYTES).map_err(|e| anyhow!("{e}"))?;
            let edited = crowdtouch::config::set_calibration_matrix(&text, index, m).map_err(|e| anyhow!("{}: {e}", p.display()))?;
            let backup = PathBuf::from(format!("{}.bak", p.display()));
            std::fs::write(&backup, &text).with_context(|| format!("writing {}", backup.display()))?;
            std::fs::write(p, edited).with_context(|| format!("writing {}", p.display()))?;
            outln!("Written into {} (previous version in {}).", p.display(), backup.display())?;
            outln!("Reload the daemon to use it: systemctl reload crowdtouch (or send SIGHUP).")?;
        }
        (true, None) => bail!("no config file to write into (give --config FILE); put this in inputs[{index}].calibration:\n  {ron}"),
        (false, _) => outln!("Put this in inputs[{index}].calibration of the config (or run with --write):\n  {ron}")?,
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crowdtouch::vocab::Contact;
    use crowdtouch::vocab::Micros;

    fn frame(t_ms: u64, id: u32, p: (f64, f64), flags: ContactFlags) -> TouchFrame {
        let mut f = TouchFrame::new(Micros(t_ms * 1000));
        f.push(Contact {
            id: ContactId(id),
            x: p.0 as f32,
            y: p.1 as f32,
            flags,
            ..Contact::default()
        })
        .unwrap();
        f
    }

    /// A device mounted rotated by 90° and slightly offset: raw = device(table).
    fn device(p: (f64, f64)) -> (f64, f64) {
        // Raw coordinates as the device reports them for a touch at table point p.
        (0.02 + 0.95 * p.1, 0.97 - 0.93 * p.0)
    }

    #[test]
    fn four_touches_give_a_matrix_that_maps_them_onto_the_targets() {
        let mut s = Session::default();
        let mut t = 0;
        for (i, &target) in TARGETS.iter().enumerate() {
            let raw = device(target);
            let id = i as u32 + 1;
            assert_eq!(
                s.frame(&frame(t, id, (raw.0 + 0.01, raw.1), ContactFlags::DOWN)),
                Progress::Holding
            );
            // Settling samples are ignored; the rest average to `raw`.
            for k in 1..20 {
                let jitter = if k % 2 == 0 { 0.001 } else { -0.001 };
                let p = if k < 5 {
                    (raw.0 + 0.01, raw.1)
                } else {
                    (raw.0 + jitter, raw.1 - jitter)
                };
                s.frame(&frame(t + k * 10, id, p, ContactFlags::NONE));
            }
            match s.frame(&frame(t + 200, id, raw, ContactFlags::UP)) {
                Progress::Captured(k, at) => {
                    assert_eq!(k, i);
                    assert!(
                        (at.0 - raw.0).abs() < 2e-3 && (at.1 - raw.1).abs() < 2e-3,
                        "{at:?} vs {raw:?}"
                    );
                }
                p => panic!("expected a capture, got {p:?}"),
            }
            t += 1000;
        }
        assert!(s.done());
        let m = s.matrix(&CalibrationConfig::default()).unwrap();
        for &target in &TARGETS {
            let raw = device(target);
            let (x, y) = apply_matrix(&m, raw.0, raw.1);
            assert!(
                (x - target.0).abs() < 3e-3 && (y - target.1).abs() < 3e-3,
                "({x},{y}) vs {target:?}"
            );
        }
        // With a configured rotation the matrix absorbs only what the rotation does not.
        let rotated = CalibrationConfig {
            rotation: 90,
            ..Default::default()
        };
        let m90 = s.matrix(&rotated).unwrap();
        let after = Calibration {
            rotation: 90,
            flip_x: false,
            flip_y: false,
            matrix: Some(m90),
        }
        .combined(None)
        .unwrap();
        for &target in &TARGETS {
            let raw = device(target);
            let (x, y) = apply_matrix(&after, raw.0, raw.1);
            assert!((x - target.0).abs() < 3e-3 && (y - target.1).abs() < 3e-3);
        }
    }

    #[test]
    fn cancelled_touches_and_palms_are_not_captured() {
        let mut s = Session::default();
        s.frame(&frame(0, 1, (0.5, 0.5), ContactFlags::DOWN));
        assert_eq!(
            s.frame(&frame(300, 1, (0.5, 0.5), ContactFlags::CANCELLED)),
            Progress::Waiting
        );
        s.frame(&frame(
            400,
            2,
            (0.5, 0.5),
            ContactFlags::DOWN | ContactFlags::PALM,
        ));
        assert_eq!(
            s.frame(&frame(
                600,
                2,
                (0.5, 0.5),
                ContactFlags::UP | ContactFlags::PALM
            )),
            Progress::Waiting
        );
        assert!(s.touched().is_empty());
        // A second finger while the first is held is ignored.
        s.frame(&frame(700, 3, (0.2, 0.2), ContactFlags::DOWN));
        s.frame(&frame(710, 4, (0.8, 0.8), ContactFlags::DOWN));
        s.frame(&frame(720, 4, (0.8, 0.8), ContactFlags::UP));
        assert!(matches!(
            s.frame(&frame(900, 3, (0.2, 0.2), ContactFlags::UP)),
            Progress::Captured(0, _)
        ));
        assert_eq!(s.touched(), &[(0.2f32 as f64, 0.2f32 as f64)]);
    }

    #[test]
    fn degenerate_touches_are_refused() {
        let mut s = Session::default();
        for i in 0..4u64 {
            s.frame(&frame(
                i * 1000,
                i as u32 + 1,
                (0.5, 0.5),
                ContactFlags::DOWN,
            ));
            s.frame(&frame(
                i * 1000 + 300,
                i as u32 + 1,
                (0.5, 0.5),
                ContactFlags::UP,
            ));
        }
        assert!(s
            .matrix(&CalibrationConfig::default())
            .unwrap_err()
            .to_string()
            .contains("cannot compute"));
    }

    #[test]
    fn the_map_marks_the_current_target() {
        let m = target_map(2);
        assert_eq!(m.matches('@').count(), 1);
        assert_eq!(m.matches('+').count(), 2);
        assert_eq!(m.matches('.').count(), 1);
    }
}
