//! `replay`: a recording through the engine on a virtual clock, as JSON Lines
//! snapshots (or its decoded frames, its tracks, a picture); `synth-recordings`.

use super::replay_svg;
use crate::cli::common::config::set_agents;
use crate::cli::common::output::{self, errln, outln};
use crate::cli::common::process::init_logging;
use anyhow::{Context, Result};
use clap::Args;
use crowdtouch::config::Config;
use crowdtouch::crowd::edit::{io::write_jsonl, TrackRecorder};
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::input::recording::{OnBadFrame, RecordingStream};
use crowdtouch::publish::protocol::{
    encode_event, encode_mesh_json, encode_snapshot_json, FieldSet,
};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// Recording (.jsonl, evemu, libinput record YAML, hid-recorder).
    pub file: PathBuf,
    /// Config (default: the embedded default).
    #[arg(long, short)]
    pub config: Option<PathBuf>,
    /// Number of agents (overrides the config).
    #[arg(long)]
    pub agents: Option<u32>,
    /// Play at the recording's own pace instead of as fast as possible.
    #[arg(long)]
    pub realtime: bool,
    /// Skip bad frames (with a warning naming the line) instead of stopping.
    #[arg(long)]
    pub skip_bad_frames: bool,
    /// Keep ticking this long after the last frame so the crowd settles (s).
    #[arg(long, default_value_t = 2.0)]
    pub settle: f64,
    /// Output file (default: stdout).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Also draw the replay (mesh before and after, agent and finger paths) as SVG.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Print the decoded touch frames (JSON Lines) instead of running the crowd: the
    /// daemon's own view of a recording, for bug reports.
    #[arg(long)]
    pub frames: bool,
    /// Also write every agent's track (JSON Lines tracks, docs/tracks.md): its
    /// position every `--track-step` seconds of replay time.
    #[arg(long, conflicts_with = "frames")]
    pub tracks: Option<PathBuf>,
    /// Time between two samples of the tracks (s).
    #[arg(long, default_value_t = 0.1, requires = "tracks")]
    pub track_step: f64,
}

pub fn replay(a: ReplayArgs) -> Result<()> {
    let (mut cfg, _) = match &a.config {
        Some(p) => (Config::load(p)?, Some(p.clone())),
        None => (Config::embedded_default(), None),
    };
    init_logging(cfg.log_level);
    set_agents(&mut cfg, a.agents)?;
    let on_bad = if a.skip_bad_frames {
        OnBadFrame::Skip
    } else {
        OnBadFrame::Stop
    };
    // Read a frame at a time: a recording of any length replays in the same memory.
    let mut stream = RecordingStream::load(&a.file, on_bad)?;
    let file = a.file.display().to_string();
    let warn = |stream: &mut RecordingStream| -> Result<(), output::OutputError> {
        for w in stream.take_warnings() {
            match w.line {
                0 => errln!("{file}: warning: {}", w.message)?,
                l => errln!("{file}:{l}: warning: {}", w.message)?,
            }
        }
        Ok(())
    };
    if a.frames {
        let mut out: Box<dyn Write> = match &a.out {
            Some(p) => Box::new(std::io::BufWriter::new(
                std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
            )),
            None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
        };
        loop {
            let next = stream.next_frame();
            let f = match next {
                Ok(Some(f)) => frame_json(f),
                Ok(None) => break,
                Err(e) => {
                    warn(&mut stream)?;
                    return Err(e.into());
                }
            };
            warn(&mut stream)?;
            writeln!(out, "{f}").context("writing frames")?;
        }
        warn(&mut stream)?;
        out.flush().context("writing frames")?;
        return Ok(());
    }
    let mut out: Box<dyn Write> = match &a.out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    let mut engine = Engine::new(&cfg, stream.surface().size_mm(), true);
    let clock = VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros::from_secs_f64(a.settle.max(0.0)),
        max_gap: Micros(crowdtouch::input::replay::MAX_GAP_US),
    };
    let mut buf = Vec::with_capacity(1 << 16);
    let start_wall = monotonic_now();
    let realtime = a.realtime;
    let mut sent_topology = 0;
    // Replay time of the tick about to run: the virtual clock less the gaps it
    // skipped, so tracks do not stand still through a skipped gap.
    let played_now = std::cell::Cell::new(Micros::ZERO);
    let pace = |played: Micros| {
        played_now.set(played);
        if realtime {
            let due = start_wall + played;
            let now = monotonic_now();
            if due > now {
                std::thread::sleep(Duration::from_micros((due - now).0));
            }
        }
    };
    let frames = std::iter::from_fn(|| {
        let next = match stream.next_frame() {
            Ok(f) => f.map(|f| Ok(*f)),
            Err(e) => Some(Err(anyhow::Error::from(e))),
        };
        if let Err(e) = warn(&mut stream) {
            return Some(Err(e.into()));
        }
        next
    });
    let mut trace = a.svg.as_ref().map(|_| replay_svg::Trace::default());
    let mut tracks = match &a.tracks {
        Some(_) => Some(TrackRecorder::new(a.track_step).context("--track-step")?),
        None => None,
    };
    let mut positions: Vec<crowdtouch::geom::Vec2> = Vec::new();
    replay_virtual(&mut engine, frames, clock, pace, |o| -> Result<()> {
        if let Some(t) = &mut trace {
            t.tick(&o.snapshot, o.mesh.as_deref());
        }
        if let Some(r) = &mut tracks {
            positions.clear();
            positions.extend(o.snapshot.agents.iter().map(|g| g.pos));
            r.tick(played_now.get().as_secs_f64(), &positions)
                .context("recording tracks")?;
        }
        buf.clear();
        for e in o.events {
            encode_event(e, &mut buf);
        }
        if let Some(m) = &o.mesh {
            encode_mesh_json(m, m.topology != sent_topology, &mut buf);
            sent_topology = m.topology;
        }
        encode_snapshot_json(&o.snapshot, None, 0, &FieldSet::ALL, &mut buf);
        out.write_all(&buf).context("writing snapshots")?;
        Ok(())
    })?;
    out.flush().context("writing snapshots")?;
    if let (Some(path), Some(r)) = (&a.tracks, tracks) {
        let set = r.finish();
        let source = a.file.file_name().map(|n| n.to_string_lossy());
        std::fs::write(path, write_jsonl(&set, source.as_deref()))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let (Some(path), Some(t)) = (&a.svg, &mut trace) {
        let title = a
            .file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        std::fs::write(path, t.render(cfg.surface.world, &title))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// One decoded frame as a JSON object: `t_us` and the contacts (unit-square
/// coordinates, life-cycle state, optional pressure and size).
pub fn frame_json(f: &crowdtouch::vocab::TouchFrame) -> serde_json::Value {
    use crowdtouch::vocab::ContactFlags;
    let contacts: Vec<serde_json::Value> = f
        .contacts()
        .iter()
        .map(|c| {
            let state = if c.flags.contains(ContactFlags::CANCELLED) {
                "cancelled"
            } else if c.flags.contains(ContactFlags::DOWN) && c.flags.contains(ContactFlags::UP) {
                "tap"
            } else if c.flags.contains(ContactFlags::DOWN) {
                "down"
            } else if c.flags.contains(ContactFlags::UP) {
                "up"
            } else {
                "move"
            };
            let mut o = serde_json::json!({
                "id": c.id.0,
                "x": (c.x as f64 * 1e5).round() / 1e5,
                "y": (c.y as f64 * 1e5).round() / 1e5,
                "state": state,
            });
            if let Some(p) = c.pressure {
                o["pressure"] = serde_json::json!((p as f64 * 1e3).round() / 1e3);
            }
            if let Some(m) = c.major_mm {
                o["major_mm"] = serde_json::json!((m as f64 * 10.0).round() / 10.0);
            }
            if let Some(m) = c.minor_mm {
                o["minor_mm"] = serde_json::json!((m as f64 * 10.0).round() / 10.0);
            }
            if c.flags.contains(ContactFlags::PALM) {
                o["palm"] = serde_json::json!(true);
            }
            o
        })
        .collect();
    serde_json::json!({ "t_us": f.t.0, "contacts": contacts })
}

pub fn synth(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let files = crowdtouch::input::synth::write_shipped(out)
        .with_context(|| format!("writing into {}", out.display()))?;
    for f in files {
        outln!("{}", f.display())?;
    }
    Ok(())
}
