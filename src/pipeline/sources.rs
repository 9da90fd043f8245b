//! The inputs a config names, made ready to run: recordings opened and read through
//! once (so a bad frame refuses the start, at its line), devices described.

use super::device;
use super::error::Error;
use crate::config::{Config, DeviceInterface, DeviceSelect, InputConfig};
use crate::input::recording::OnBadFrame;
use crate::input::replay::ReplayItem;
use crate::vocab::{Micros, TouchFrame};
use crossbeam_channel::Receiver;

/// An input source the daemon runs.
pub enum SourceSpec {
    /// Recordings replayed in real time.
    Replay {
        /// The files, opened (read a frame at a time as they play).
        items: Vec<ReplayItem>,
        /// Play forever.
        looped: bool,
        /// Pause between files.
        gap: Micros,
        /// Reset the crowd before each file.
        reset_between: bool,
        /// Surface size (mm) from the first recording, if known.
        glass_mm: Option<(f64, f64)>,
    },
    /// A touch device found by discovery and re-attached after unplugging.
    Device {
        /// Index of the input in the config.
        input: u16,
        /// Which device, and through which interface.
        select: DeviceSelect,
        /// evdev, hidraw or either.
        interface: DeviceInterface,
        /// Exclusive grab.
        grab: bool,
        /// Calibration, region and palm settings applied to its frames.
        transform: device::TransformSettings,
    },
    /// TUIO cursors received over UDP (the socket bound at start).
    Tuio {
        /// The bound source.
        source: Box<crate::input::tuio::TuioSource>,
        /// Calibration and region applied to its frames.
        transform: device::TransformSettings,
    },
    /// Frames handed in by the embedding program through a channel: a virtual
    /// device for tests, benchmarks and tools. Frames keep the time stamp they were
    /// given (stamp them with [`monotonic_now`](crate::rt::monotonic_now) when sent to measure latency). The
    /// source ends when the sender is dropped.
    Channel {
        /// Where the frames come from.
        rx: Receiver<TouchFrame>,
        /// Surface size (mm), if known.
        glass_mm: Option<(f64, f64)>,
    },
}

/// Opens the recordings a config names and reads each through once; their
/// warnings are logged. A config without inputs gives no source: its touches
/// come from clients ([`TouchSources`](super::TouchSources)).
///
/// # Errors
/// [`Error::Recording`] naming the file and line; [`Error::TuioInput`] when a TUIO
/// port cannot be bound.
pub fn sources_from_config(cfg: &Config) -> Result<Vec<SourceSpec>, Error> {
    let mut out = Vec::new();
    for (i, input) in cfg.inputs.iter().enumerate() {
        match input {
            InputConfig::Replay {
                files,
                looped,
                gap_ms,
                reset_between,
            } => {
                let mut items = Vec::new();
                let mut glass = None;
                for f in files {
                    let (item, surface, warnings) = ReplayItem::open(f, OnBadFrame::Stop)?;
                    for w in &warnings {
                        log::warn!("{}: {w}", f.display());
                    }
                    if glass.is_none() {
                        glass = surface.size_mm();
                    }
                    items.push(item);
                }
                out.push(SourceSpec::Replay {
                    items,
                    looped: *looped,
                    gap: Micros(gap_ms * 1000),
                    reset_between: *reset_between,
                    glass_mm: glass,
                });
            }
            InputConfig::Device {
                select,
                interface,
                grab,
                region,
                calibration,
                palm_max_mm,
                size_mm,
            } => {
                out.push(SourceSpec::Device {
                    input: i as u16,
                    select: select.clone(),
                    interface: *interface,
                    grab: *grab,
                    transform: device::TransformSettings {
                        calibration: calibration.clone(),
                        region: *region,
                        palm_max_mm: *palm_max_mm,
                        size_mm: size_mm.or(cfg.surface.size_mm),
                    },
                });
            }
            InputConfig::Tuio {
                listen,
                region,
                calibration,
                timeout_ms,
                max_sessions_per_frame,
                max_senders,
                max_packets_per_s,
            } => {
                // Validated: `listen` parses.
                let listen = listen
                    .parse()
                    .map_err(|_| Error::BadListen(listen.clone()))?;
                let settings = crate::input::tuio::TuioSettings {
                    listen,
                    timeout: Micros(timeout_ms * 1000),
                    // Validated: within the decoder's bounds (it clamps them too).
                    limits: crate::input::tuio::TuioLimits {
                        sessions_per_frame: *max_sessions_per_frame as usize,
                        senders: *max_senders as usize,
                        packets_per_s: *max_packets_per_s,
                    },
                };
                out.push(SourceSpec::Tuio {
                    source: Box::new(crate::input::tuio::TuioSource::bind(&settings)?),
                    transform: device::TransformSettings {
                        calibration: calibration.clone(),
                        region: *region,
                        palm_max_mm: None,
                        size_mm: cfg.surface.size_mm,
                    },
                });
            }
        }
    }
    Ok(out)
}
