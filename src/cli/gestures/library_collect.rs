//! `crowdtouch library collect`: gestures from people at the table (gesture-driven
//! section 4). The daemon runs as `run` does (the config's inputs and outputs,
//! touches from clients' `touch` commands and the viewer too); a session in its
//! engine shows each chosen library motion (`demo_motion`, and the crowd plays
//! it), records the gesture the person draws for it with their participant id
//! and the device, and saves the library after every gesture (written whole
//! beside the file and renamed into place: stopping at any moment leaves the
//! gestures recorded so far). Clients steer it with `collect.skip`,
//! `collect.undo` and `collect.again`; the live viewer (`--http`) shows the
//! motion and the session's progress, with buttons for those commands.
//!
//! This file chooses what to ask for and reports what was stored; `cli.rs`
//! starts and supervises the daemon.

use super::classes::class_of;
use crate::cli::common::config::find_config;
use crate::cli::common::output::outln;
use crate::cli::common::process::{demo_websocket, init_logging, signals, status_line, supervise};
use crate::cli::common::running::Running;
use anyhow::{bail, Context, Result};
use crowdtouch::engine::CollectPlan;
use crowdtouch::gesture::library::{
    read_library_with, shipped, Library, LoadPolicy, MAX_LIBRARY_BYTES, MAX_PARTICIPANT_BYTES,
};
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions, SourceSpec};
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::Micros;
use std::path::{Path, PathBuf};

/// `crowdtouch library collect` arguments.
#[derive(clap::Args, Debug)]
pub struct CollectArgs {
    /// The library the gestures are added to; saved after every gesture. When it
    /// does not exist it starts as a copy of `--library` (default: the shipped
    /// library); when it does, the session adds to it.
    #[arg(long, short)]
    pub out: PathBuf,
    /// Who draws (stored with every gesture; `library eval --by participant`).
    #[arg(long)]
    pub participant: String,
    /// The library to start from when `--out` does not exist yet.
    #[arg(long)]
    pub library: Option<PathBuf>,
    /// Classes whose motions are shown (default: every class with a motion).
    #[arg(long = "class", value_delimiter = ',')]
    pub classes: Vec<String>,
    /// Motions shown per class (the first ones of each class in the library).
    #[arg(long, default_value_t = 1)]
    pub motions_per_class: usize,
    /// How many times each motion is asked for.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
    /// Ask in the library's order instead of a shuffled one.
    #[arg(long)]
    pub in_order: bool,
    /// Seed of the order and of the crowd shown.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Seconds a finished demonstration waits before it plays again.
    #[arg(long, default_value_t = 2.0)]
    pub replay_after_s: f64,
    /// Config file (its inputs and outputs; default: the search path, else the
    /// embedded default).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Socket path (default: the config's).
    #[arg(long)]
    pub socket: Option<PathBuf>,
    /// Serve the live viewer, in its collection mode, on ADDR (ip:port; a
    /// privileged WebSocket output as `demo --http` adds).
    #[arg(long, value_name = "ADDR")]
    pub http: Option<String>,
    /// Token the viewer's URL must carry (required off loopback).
    #[arg(long)]
    pub token: Option<String>,
}

/// What to ask for: every chosen class's first `per_class` motions, each `repeat`
/// times, shuffled (Fisher–Yates) unless `in_order`.
pub fn choose_motions(lib: &Library, a: &CollectArgs) -> Result<Vec<u32>> {
    if a.motions_per_class == 0 || a.repeat == 0 {
        bail!("--motions-per-class and --repeat are at least 1");
    }
    let classes = if a.classes.is_empty() {
        let mut ids: Vec<_> = lib.motions.iter().map(|m| m.class).collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    } else {
        a.classes
            .iter()
            .map(|c| class_of(lib, c))
            .collect::<Result<Vec<_>>>()?
    };
    let mut motions = Vec::new();
    for c in classes {
        let of_class: Vec<u32> = (0..lib.motions.len() as u32)
            .filter(|&m| lib.motions[m as usize].class == c)
            .take(a.motions_per_class)
            .collect();
        if of_class.is_empty() {
            bail!(
                "the library has no {} motion to show (import one with `library import-motion --class {}`)",
                lib.class_name(c),
                lib.class_name(c)
            );
        }
        motions.extend(of_class);
    }
    if motions.is_empty() {
        bail!("the library has no motions to show");
    }
    let mut items: Vec<u32> = (0..a.repeat)
        .flat_map(|_| motions.iter().copied())
        .collect();
    if !a.in_order {
        let mut rng = SplitMix64::new(a.seed);
        for i in (1..items.len()).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            items.swap(i, j);
        }
    }
    Ok(items)
}

/// The library the session starts from, and where it came from (for the
/// announcement).
pub fn starting_library(a: &CollectArgs) -> Result<(Library, String)> {
    let read = |p: &Path| -> Result<Library> {
        let bytes = crowdtouch::located::read_bytes(p, MAX_LIBRARY_BYTES as u64)
            .with_context(|| format!("{}: cannot read the library", p.display()))?;
        Ok(read_library_with(
            &bytes,
            &p.display().to_string(),
            LoadPolicy::Partial,
        )?)
    };
    if a.out.exists() {
        if a.library.is_some() {
            bail!(
                "{} exists: the session adds to it; --library names where a new one starts from",
                a.out.display()
            );
        }
        return Ok((read(&a.out)?, format!("adding to {}", a.out.display())));
    }
    match &a.library {
        Some(p) => Ok((read(p)?, format!("a copy of {}", p.display()))),
        None => Ok((shipped()?, "a copy of the shipped library".into())),
    }
}

/// The session the daemon runs, on `library` ([`starting_library`]).
pub fn plan(a: &CollectArgs, sources: &[SourceSpec], library: Library) -> Result<CollectPlan> {
    let participant = a.participant.trim().to_string();
    if participant.is_empty()
        || participant.len() > MAX_PARTICIPANT_BYTES
        || participant.chars().any(char::is_control)
    {
        bail!("--participant: 1 to {MAX_PARTICIPANT_BYTES} bytes, no control characters");
    }
    if !(a.replay_after_s.is_finite() && (0.0..=600.0).contains(&a.replay_after_s)) {
        bail!("--replay-after-s: 0 to 600 s");
    }
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            bail!("{}: no such directory for the library", dir.display());
        }
    }
    let motions = choose_motions(&library, a)?;
    Ok(CollectPlan {
        library,
        path: a.out.clone(),
        participant,
        motions,
        devices: device_names(sources),
        seed: a.seed,
        replay_after: Micros::from_secs_f64(a.replay_after_s),
    })
}

/// A name for each input, stored with the gestures drawn on it.
pub fn device_names(sources: &[SourceSpec]) -> Vec<String> {
    sources
        .iter()
        .enumerate()
        .map(|(i, s)| match s {
            SourceSpec::Replay { items, .. } => items.first().map_or_else(
                || format!("replay {i}"),
                |r| format!("recording {}", r.name()),
            ),
            SourceSpec::Device { select, .. } => format!("device {select:?}"),
            SourceSpec::Tuio { source, .. } => source
                .local_addr()
                .map_or_else(|| "tuio".to_string(), |a| format!("tuio {a}")),
            SourceSpec::Channel { .. } => format!("channel {i}"),
        })
        .collect()
}

/// What the person at the table reads first.
pub fn announce(a: &CollectArgs, plan: &CollectPlan, from: &str, socket: &Path) -> Result<()> {
    let lib = &plan.library;
    let mut classes: Vec<&str> = plan
        .motions
        .iter()
        .map(|&m| lib.class_name(lib.motions[m as usize].class))
        .collect();
    classes.sort_unstable();
    classes.dedup();
    outln!(
        "crowdtouch library collect: {} motions to draw for {} ({}); library {} ({from})",
        plan.motions.len(),
        plan.participant,
        classes.join(", "),
        a.out.display()
    )?;
    outln!("  each motion is played by the crowd; draw the gesture you would use for it.")?;
    outln!(
        "  socket:  {} (collect.skip, collect.undo, collect.again)",
        socket.display()
    )?;
    if let Some(addr) = &a.http {
        let query = crate::cli::common::output::token_query(a.token.as_deref());
        outln!("  viewer:  http://{addr}/{query} (collection mode)")?;
    }
    outln!("  Ctrl-C stops; what was drawn so far is saved.")?;
    Ok(())
}

/// The closing summary: what the file holds from this participant (`before` of
/// theirs were in it when the session started).
pub fn summary(out: &Path, participant: &str, before: usize) -> Result<()> {
    if !out.exists() {
        outln!("nothing recorded; {} was not written", out.display())?;
        return Ok(());
    }
    let bytes = crowdtouch::located::read_bytes(out, MAX_LIBRARY_BYTES as u64)
        .with_context(|| format!("{}: cannot read the library back", out.display()))?;
    let lib = read_library_with(&bytes, &out.display().to_string(), LoadPolicy::Partial)?;
    let mine = lib
        .gestures
        .iter()
        .filter(|g| g.participant == participant)
        .count();
    outln!(
        "{}: {} gestures recorded this session; {mine} from {participant}, {} gestures and {} motions in all",
        out.display(),
        mine.saturating_sub(before),
        lib.gestures.len(),
        lib.motions.len()
    )?;
    Ok(())
}

/// `library collect`: the daemon on the config's inputs and outputs (and the
/// viewer with `--http`), running a collection session until it has asked for
/// every motion, or until SIGTERM/SIGINT.
pub fn collect(a: CollectArgs) -> Result<()> {
    let sig = signals()?;
    let (mut cfg, path) = find_config(a.config.as_deref())?;
    init_logging(cfg.log_level);
    if let Some(addr) = &a.http {
        cfg.outputs
            .push(demo_websocket(addr, a.token.clone(), &[], false)?);
    }
    let (start, from) = starting_library(&a)?;
    let sources = sources_from_config(&cfg)?;
    let before = start
        .gestures
        .iter()
        .filter(|g| g.participant == a.participant.trim())
        .count();
    let plan = plan(&a, &sources, start)?;
    let socket_path = a
        .socket
        .clone()
        .unwrap_or_else(|| cfg.socket.resolved_path());
    announce(&a, &plan, &from, &socket_path)?;
    let participant = plan.participant.clone();
    let daemon = Running(Some(Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path,
            collect: Some(plan),
        },
    )?));
    supervise(sig, daemon, path, None, |r| {
        log::debug!("{}", status_line(r));
        Ok(())
    })?;
    summary(&a.out, &participant, before)
}
