//! `crowdtouch bench shutdown`: how soon `crowdtouch demo` exits after SIGTERM in
//! each state, and how soon a stale solve is given up when the crowd shrinks.
//!
//! Every run starts a fresh `demo` (this executable) on a socket of its own, with
//! one client subscribed to events and stats, brings it into the state, sends
//! SIGTERM and times the exit (`waitpid` polled every millisecond). The demo's log
//! gives the part `Daemon::shutdown` took (the rest is the supervisor noticing
//! the signal, up to its 200 ms wait for stats, and the process exit).

use super::rows::{row_from_samples, Row};
use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Longest wait for any one step (start-up, a stats message, an exit).
const STEP_TIMEOUT: Duration = Duration::from_secs(120);
/// How long a state is held before the signal: the slow work is under way.
const HOLD: Duration = Duration::from_millis(250);

/// The states the daemon is stopped in.
#[derive(Copy, Clone, Debug)]
enum State {
    /// 100 agents, everything running.
    Idle,
    /// 100 agents, a resize to the big count being prepared.
    Resizing,
    /// The big count, its assignment being solved.
    Solving,
    /// The big count, a formation switch of it being prepared.
    Switching,
}

/// One running `demo` and its client.
struct Demo {
    child: Child,
    reader: BufReader<UnixStream>,
    writer: UnixStream,
    sock: PathBuf,
}

impl Demo {
    fn start(agents: u32, run: usize) -> Result<Demo> {
        let sock = std::env::temp_dir().join(format!(
            "crowdtouch-bench-stop-{}-{run}.sock",
            std::process::id()
        ));
        let exe = std::env::current_exe().context("finding this executable")?;
        let child = Command::new(exe)
            .args(["demo", "--agents", &agents.to_string(), "--socket"])
            .arg(&sock)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .context("starting crowdtouch demo")?;
        let t0 = Instant::now();
        let stream = loop {
            if let Ok(s) = UnixStream::connect(&sock) {
                break s;
            }
            if t0.elapsed() > STEP_TIMEOUT {
                bail!(
                    "demo did not listen on {} within {STEP_TIMEOUT:?}",
                    sock.display()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let mut writer = stream.try_clone()?;
        writer.write_all(
            b"{\"type\":\"hello\",\"protocol\":1,\"subscribe\":[\"events\",\"stats\"]}\n",
        )?;
        stream.set_read_timeout(Some(Duration::from_millis(100)))?;
        Ok(Demo {
            child,
            reader: BufReader::new(stream),
            writer,
            sock,
        })
    }

    fn command(&mut self, id: u32, body: &str) -> Result<()> {
        writeln!(self.writer, r#"{{"type":"command","id":{id},{body}}}"#)?;
        Ok(())
    }

    /// The next message for which `f` holds, within [`STEP_TIMEOUT`].
    fn wait_for(&mut self, mut f: impl FnMut(&Value) -> bool) -> Result<Value> {
        let t0 = Instant::now();
        let mut line = String::new();
        while t0.elapsed() < STEP_TIMEOUT {
            line.clear();
            match self.reader.read_line(&mut line) {
                Ok(0) => bail!("the demo closed the socket"),
                Ok(_) => {
                    let v: Value = serde_json::from_str(&line)?;
                    if f(&v) {
                        return Ok(v);
                    }
                }
                Err(e)
                    if e.kind() == std::io::ErrorKind::WouldBlock
                        || e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) => return Err(e.into()),
            }
        }
        bail!("no awaited message within {STEP_TIMEOUT:?}")
    }

    /// Waits for stats showing `agents` agents and assignments being applied.
    fn solving(&mut self, agents: u32) -> Result<()> {
        self.wait_for(|v| {
            v["type"] == "stats" && v["agents"] == agents && v["assignments"].as_u64() > Some(0)
        })?;
        Ok(())
    }

    /// SIGTERM, then the time until the process has exited, and the time its
    /// `Daemon::shutdown` took by its log (µs).
    fn terminate(mut self) -> Result<(Duration, Option<f64>)> {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        let t0 = Instant::now();
        nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM)?;
        loop {
            if let Some(status) = self.child.try_wait()? {
                let took = t0.elapsed();
                let _ = std::fs::remove_file(&self.sock);
                let mut log = String::new();
                if let Some(mut e) = self.child.stderr.take() {
                    let _ = std::io::Read::read_to_string(&mut e, &mut log);
                }
                if !status.success() {
                    bail!("demo exited with {status} after SIGTERM:\n{log}");
                }
                return Ok((took, shutdown_ms(&log).map(|ms| ms * 1e3)));
            }
            if t0.elapsed() > STEP_TIMEOUT {
                let _ = self.child.kill();
                bail!("demo did not exit within {STEP_TIMEOUT:?} of SIGTERM");
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

/// The figure of the daemon's "shutdown: every thread stopped in X ms" line.
fn shutdown_ms(log: &str) -> Option<f64> {
    let line = log
        .lines()
        .rev()
        .find(|l| l.contains("every thread stopped in"))?;
    let at = line.find("stopped in ")? + "stopped in ".len();
    line[at..].split_whitespace().next()?.parse().ok()
}

/// One SIGTERM run in `state` (`big` agents for the states that need a big crowd).
fn sigterm_in(state: State, big: u32, run: usize) -> Result<(Duration, Option<f64>)> {
    let start_agents = match state {
        State::Idle | State::Resizing => 100,
        State::Solving | State::Switching => big,
    };
    let mut d = Demo::start(start_agents, run)?;
    d.solving(start_agents)?;
    match state {
        State::Idle | State::Solving => {}
        State::Resizing => d.command(1, &format!(r#""name":"set_agent_count","count":{big}"#))?,
        State::Switching => d.command(1, r#""name":"set_formation","formation":"square""#)?,
    }
    std::thread::sleep(HOLD);
    d.terminate()
}

/// A stale solve: `big` agents solving, shrunk back to 100. Returns the daemon's
/// figure for the abandonment (its `abandon` stage: the change → the worker giving
/// up, µs; `None` when no job was under way) and the time from the command to its
/// acknowledgement.
fn stale_solve(big: u32, run: usize) -> Result<(Option<f64>, Duration)> {
    let mut d = Demo::start(big, run)?;
    d.solving(big)?;
    std::thread::sleep(HOLD);
    let t0 = Instant::now();
    d.command(2, r#""name":"set_agent_count","count":100"#)?;
    let ack = d.wait_for(|v| v["id"] == 2)?;
    let acked = t0.elapsed();
    if ack["type"] != "ack" {
        bail!("the shrink was refused: {ack}");
    }
    // The next stats after the shrink carry the abandonment, if any.
    let mut worst: Option<f64> = None;
    for _ in 0..2 {
        let stats = d.wait_for(|v| v["type"] == "stats")?;
        let abandon = stats["stages"]
            .as_array()
            .and_then(|a| a.iter().find(|s| s["stage"] == "abandon"));
        if let Some(s) = abandon.filter(|s| s["count"].as_u64() > Some(0)) {
            let max = s["max_us"].as_f64().unwrap_or(0.0);
            worst = Some(worst.map_or(max, |w| w.max(max)));
        }
    }
    d.terminate()?;
    Ok((worst, acked))
}

/// The shutdown workload: `repeats` runs of each state, and of the stale solve.
pub fn shutdown(big: u32, repeats: usize) -> Result<Vec<Row>> {
    let repeats = repeats.max(1);
    let mut rows = Vec::new();
    let mut run = 0;
    for (state, what) in [
        (State::Idle, "100 agents, running".to_string()),
        (
            State::Resizing,
            format!("100 agents, resize to {big} being prepared"),
        ),
        (
            State::Solving,
            format!("{big} agents, assignment being solved"),
        ),
        (
            State::Switching,
            format!("{big} agents, formation switch being prepared"),
        ),
    ] {
        let (mut samples, mut inner) = (Vec::with_capacity(repeats), Vec::new());
        for _ in 0..repeats {
            run += 1;
            let (took, shutdown) = sigterm_in(state, big, run)?;
            samples.push(took.as_secs_f64() * 1e6);
            inner.extend(shutdown);
        }
        let name = format!("{state:?}").to_lowercase();
        rows.push(row_from_samples(
            &format!("sigterm {name}"),
            samples,
            format!("SIGTERM -> process exited (status 0): {what}"),
        ));
        rows.push(row_from_samples(
            &format!("  of which shutdown {name}"),
            inner,
            "Daemon::shutdown: workers told to give up -> every thread joined (by its log)".into(),
        ));
    }
    let (mut abandon, mut acks) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        run += 1;
        let (a, ack) = stale_solve(big, run)?;
        abandon.extend(a);
        acks.push(ack.as_secs_f64() * 1e6);
    }
    let given_up = abandon.len();
    rows.push(row_from_samples(
        "stale solve abandoned",
        abandon,
        format!(
            "the daemon's `abandon` stage: shrink from {big} to 100 applied -> the worker gave the stale job up (worst per run; {given_up} of {repeats} runs had one under way)"
        ),
    ));
    rows.push(row_from_samples(
        "shrink acknowledged",
        acks,
        format!("set_agent_count 100 sent at {big} agents -> its ack read"),
    ));
    Ok(rows)
}
