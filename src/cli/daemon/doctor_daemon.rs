//! `doctor`'s `daemon` check: asks the running daemon on its socket for its newest
//! `stats` and reads its health from them (latency, drops, lost transitions, the
//! devices' states).

use super::doctor_check::Check;
use super::unit::SERVICE_USER;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::{Duration, Instant};

/// What the running daemon said: its newest `stats` line.
pub fn ask_daemon(socket: &Path) -> Result<serde_json::Value, std::io::Error> {
    let s = UnixStream::connect(socket)?;
    s.set_read_timeout(Some(Duration::from_millis(500)))?;
    let mut w = s.try_clone()?;
    writeln!(
        w,
        r#"{{"type":"hello","protocol":1,"subscribe":["stats"]}}"#
    )?;
    let mut r = BufReader::new(s);
    let end = Instant::now() + Duration::from_secs(4);
    let mut line = String::new();
    while Instant::now() < end {
        line.clear();
        match r.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) => {
                if let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) {
                    if v["type"] == "stats" {
                        return Ok(v);
                    }
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::TimedOut,
        "connected, but no stats within 4 s",
    ))
}

/// `daemon`: running, and healthy by its last `stats`.
pub fn check_daemon(socket: &Path, daemon: Result<serde_json::Value, std::io::Error>) -> Check {
    let s = match daemon {
        Ok(s) => s,
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => {
            return Check::fail(
                "daemon",
                format!("{}: {e}: this user is not in its group", socket.display()),
                format!(
                    "sudo usermod -aG {SERVICE_USER} $USER, then log in again (or run doctor \
                     with sudo)"
                ),
            )
        }
        Err(e) => {
            return Check::fail(
                "daemon",
                format!("no daemon answers on {}: {e}", socket.display()),
                "sudo systemctl start crowdtouch; journalctl -u crowdtouch -b says why it \
                 stopped",
            )
        }
    };
    let e2e = s["stages"]
        .as_array()
        .and_then(|st| st.iter().find(|x| x["stage"] == "end_to_end"))
        .filter(|x| x["count"].as_u64().unwrap_or(0) > 0)
        .map(|x| {
            format!(
                "latency p50 {:.1} ms p99 {:.1} ms",
                x["p50_us"].as_f64().unwrap_or(0.0) / 1000.0,
                x["p99_us"].as_f64().unwrap_or(0.0) / 1000.0
            )
        })
        .unwrap_or_else(|| "no touch timed in the last interval".into());
    let devices: Vec<String> = s["devices"]
        .as_array()
        .map(|d| {
            d.iter()
                .map(|x| {
                    format!(
                        "inputs[{}] {} {}",
                        x["input"],
                        x["state"].as_str().unwrap_or("not tried yet"),
                        x["node"].as_str().unwrap_or("")
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let detail = format!(
        "running: {e2e}; {} touches, {} frames seen; {} snapshots dropped, {} transitions \
         lost; {} clients{}{}",
        s["touches"],
        s["frames"],
        s["snapshots_dropped"],
        s["transitions_lost"],
        s["clients"],
        if devices.is_empty() { "" } else { "; " },
        devices.join(", ")
    );
    let failed: Vec<String> = s["devices"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|x| x["state"] != "attached")
        .map(|x| {
            format!(
                "inputs[{}] is {}: {}",
                x["input"],
                x["state"].as_str().unwrap_or("not attached"),
                x["message"].as_str().unwrap_or("")
            )
        })
        .collect();
    if s["transitions_lost"].as_u64().unwrap_or(0) > 0 {
        Check::fail(
            "daemon",
            detail,
            "touch-downs or lifts were lost (a bug): a recording (crowdtouch record) and the \
             journal make a bug report",
        )
    } else if !failed.is_empty() {
        Check::fail(
            "daemon",
            format!("{detail}; {}", failed.join("; ")),
            "see the device checks above; journalctl -u crowdtouch shows the device's events",
        )
    } else {
        Check::ok("daemon", detail)
    }
}
