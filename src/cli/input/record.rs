//! `crowdtouch record`: a touch device's raw stream as a file that replays anywhere.
//!
//! evdev nodes are written as evemu (`evemu-play`/`evemu-device` replay it
//! through uinput on a kiosk; `crowdtouch replay` reads it), hidraw nodes as
//! hid-recorder logs (`hid-replay` from hid-tools replays them through uhid).
//! `crowdtouch replay --frames FILE` shows how crowdtouch decodes either;
//! `record --frames` writes that decoding directly, as our JSON Lines.

use crate::cli::common::output::errln;
use anyhow::{bail, Context, Result};
use crowdtouch::config::{Config, DeviceInterface, DeviceSelect, InputConfig};
use crowdtouch::input::discover::{discover, select};
use crowdtouch::input::evdev::{EvdevOptions, EvdevReader};
use crowdtouch::input::hid::{HidOptions, HidReader};
use crowdtouch::input::recording::JsonlWriter;
use crowdtouch::input::{DeviceKind, DeviceReader, FrameSink};
use crowdtouch::pipeline::device::{preference, selector, SystemProber};
use crowdtouch::vocab::TouchFrame;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// `crowdtouch record` arguments.
#[derive(clap::Args, Debug)]
pub struct RecordArgs {
    /// Device: `auto`, a node (`/dev/input/event5`, `/dev/hidraw2`), `VVVV:PPPP`
    /// (hex ids), `id=STABLE_ID` (as `crowdtouch devices` prints it), or a name
    /// pattern. Default: the config's Device input (see --input), else `auto`.
    #[arg(long, short)]
    device: Option<String>,
    /// Interface to record when the device has both.
    #[arg(long, value_enum, default_value_t = Interface::Any)]
    interface: Interface,
    /// Config whose Device input to record (default: the search path).
    #[arg(long, short)]
    config: Option<PathBuf>,
    /// Index of the input in the config (default: the first Device input).
    #[arg(long)]
    input: Option<usize>,
    /// Output file (default: stdout). evemu for evdev nodes, hid-recorder for hidraw.
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Stop after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    seconds: Option<f64>,
    /// Write the decoded touch frames as our JSON Lines recording instead of the raw
    /// stream (normalised; replays anywhere with `crowdtouch replay`).
    #[arg(long)]
    frames: bool,
}

/// Hands each decoded frame to the JSON Lines writer; a write error stops the
/// recording and is kept for the caller.
struct JsonlSink<'s, W: Write> {
    out: JsonlWriter<'s, W>,
    error: Option<std::io::Error>,
    stop: Arc<AtomicBool>,
}

impl<W: Write> FrameSink for JsonlSink<'_, W> {
    fn push(&mut self, frame: &TouchFrame) {
        if self.error.is_some() {
            return;
        }
        if let Err(e) = self.out.frame(frame).and_then(|()| self.out.flush()) {
            self.error = Some(e);
            self.stop.store(true, Ordering::Relaxed);
        }
    }
}

/// Records decoded frames from `node` as JSON Lines until `stop`.
fn record_frames(
    node: &Path,
    kind: DeviceKind,
    out: Box<dyn Write>,
    stop: &Arc<AtomicBool>,
) -> Result<u64> {
    let mut reader: Box<dyn DeviceReader> = match kind {
        DeviceKind::Evdev => Box::new(EvdevReader::open(node, &EvdevOptions { grab: false })?),
        DeviceKind::Hidraw => Box::new(HidReader::open(node, &HidOptions::default())?),
    };
    let surface = reader.info().surface.clone();
    let mut sink = JsonlSink {
        out: JsonlWriter::new(&surface, out)?,
        error: None,
        stop: Arc::clone(stop),
    };
    let run = reader.run(&mut sink, stop);
    // Contacts still down when the recording stops end as cancelled, so the file
    // replays without a stuck finger.
    let mut last = TouchFrame::default();
    if reader.cancel_all(crowdtouch::rt::monotonic_now(), &mut last) {
        sink.push(&last);
    }
    if let Some(e) = sink.error {
        return Err(e).context("writing the recording");
    }
    run?;
    Ok(sink.out.frames())
}

/// `--interface`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Interface {
    /// evdev when the kernel handles the device, else hidraw.
    Any,
    /// `/dev/input/eventN`.
    Evdev,
    /// `/dev/hidrawN`.
    Hidraw,
}

/// What `--device` means.
pub fn parse_device(s: &str) -> DeviceSelect {
    let s = s.trim();
    let hex4 = |p: &str| !p.is_empty() && p.len() <= 4 && p.bytes().all(|b| b.is_ascii_hexdigit());
    if s.eq_ignore_ascii_case("auto") {
        DeviceSelect::Auto
    } else if s.starts_with('/') {
        DeviceSelect::Path(PathBuf::from(s))
    } else if let Some(id) = s.strip_prefix("id=") {
        DeviceSelect::Id(id.to_string())
    } else if s.split_once(':').is_some_and(|(v, p)| hex4(v) && hex4(p)) {
        DeviceSelect::VendorProduct(s.to_string())
    } else {
        DeviceSelect::Name(s.to_string())
    }
}

/// The device the arguments name, and the interface preference.
fn what_to_record(a: &RecordArgs, cfg: &Config) -> Result<(DeviceSelect, DeviceInterface)> {
    let iface = match a.interface {
        Interface::Any => None,
        Interface::Evdev => Some(DeviceInterface::Evdev),
        Interface::Hidraw => Some(DeviceInterface::Hidraw),
    };
    if let Some(d) = &a.device {
        return Ok((parse_device(d), iface.unwrap_or_default()));
    }
    let devices: Vec<(usize, &DeviceSelect, DeviceInterface)> = cfg
        .inputs
        .iter()
        .enumerate()
        .filter_map(|(i, c)| match c {
            InputConfig::Device {
                select, interface, ..
            } => Some((i, select, *interface)),
            InputConfig::Replay { .. } | InputConfig::Tuio { .. } => None,
        })
        .collect();
    let pick = match a.input {
        Some(n) => match devices.iter().find(|(i, _, _)| *i == n) {
            Some(d) => Some(d),
            None => bail!(
                "--input {n}: the config has no Device input at that index (Device inputs: {:?})",
                devices.iter().map(|d| d.0).collect::<Vec<_>>()
            ),
        },
        None => devices.first(),
    };
    Ok(match pick {
        Some((_, sel, i)) => ((*sel).clone(), iface.unwrap_or(*i)),
        None => (DeviceSelect::Auto, iface.unwrap_or_default()),
    })
}

/// Records until Ctrl-C, SIGTERM or `--seconds`.
pub fn record(a: RecordArgs) -> Result<()> {
    let (cfg, _) = crate::cli::common::config::find_config(a.config.as_deref())?;
    let (sel, iface) = what_to_record(&a, &cfg)?;
    // A node given by path is recorded as it is (touch or not: a device crowdtouch
    // cannot read yet is worth a recording too); anything else goes through
    // discovery, as `run` does.
    let (node, kind, label) = match &sel {
        DeviceSelect::Path(p) => {
            if let Err(e) = std::fs::metadata(p) {
                bail!("{}: {e}", p.display());
            }
            let hidraw = p
                .file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("hidraw"));
            let kind = if hidraw {
                DeviceKind::Hidraw
            } else {
                DeviceKind::Evdev
            };
            (p.clone(), kind, String::new())
        }
        _ => {
            let found = discover(Path::new("/"), &SystemProber);
            let f = select(&found, &selector(&sel), preference(iface))
                .map_err(|e| anyhow::anyhow!("{e}"))
                .context("choosing the device to record (see `crowdtouch devices`)")?;
            let i = &f.info;
            (
                i.identity.node.clone(),
                i.identity.kind,
                format!(
                    " ({}, {:04x}:{:04x})",
                    i.identity.name, i.identity.vendor, i.identity.product
                ),
            )
        }
    };
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&stop))
            .context("installing signal handlers")?;
    }
    if let Some(s) = a.seconds {
        if !(s.is_finite() && s > 0.0) {
            bail!("--seconds must be a positive number of seconds, not {s}");
        }
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(s));
            stop.store(true, Ordering::Relaxed);
        });
    }
    let out: Box<dyn Write> = match &a.out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        )),
        None => Box::new(std::io::stdout().lock()),
    };
    let (format, what) = match (kind, a.frames) {
        (_, true) => ("crowdtouch JSON Lines", "frames"),
        (DeviceKind::Evdev, false) => ("evemu", "events"),
        (DeviceKind::Hidraw, false) => ("hid-recorder", "reports"),
    };
    errln!(
        "recording {}{label} as {format}{}; Ctrl-C stops",
        node.display(),
        a.out
            .as_ref()
            .map(|p| format!(" into {}", p.display()))
            .unwrap_or_default(),
    )?;
    let n = if a.frames {
        record_frames(&node, kind, out, &stop)
    } else {
        match kind {
            DeviceKind::Evdev => crowdtouch::input::evdev::record_evdev(&node, out, &stop),
            DeviceKind::Hidraw => crowdtouch::input::hid::record_hidraw(&node, out, &stop),
        }
        .map_err(anyhow::Error::from)
    }
    .with_context(|| format!("recording {}", node.display()))?;
    errln!("{n} {what} recorded")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_argument_forms() {
        assert_eq!(parse_device("auto"), DeviceSelect::Auto);
        assert_eq!(
            parse_device("/dev/hidraw3"),
            DeviceSelect::Path("/dev/hidraw3".into())
        );
        assert_eq!(
            parse_device("2575:0204"),
            DeviceSelect::VendorProduct("2575:0204".into())
        );
        assert_eq!(
            parse_device("id=pci-0000:00:14.0-usb-0:2:1.0"),
            DeviceSelect::Id("pci-0000:00:14.0-usb-0:2:1.0".into())
        );
        assert_eq!(
            parse_device("Dell Canvas*"),
            DeviceSelect::Name("Dell Canvas*".into())
        );
        assert_eq!(
            parse_device("ELAN:Touch"),
            DeviceSelect::Name("ELAN:Touch".into())
        );
    }
}
