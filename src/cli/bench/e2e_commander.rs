//! `bench e2e --transform NAME`'s commander: a second socket client that keeps
//! formation transforms running (to `NAME`, back to `start`) and counts what the
//! daemon answered.

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::time::Duration;

/// What the transform commander saw.
#[derive(Default)]
pub struct Commanded {
    /// `set_formation` commands acknowledged.
    pub started: u64,
    /// `transform` progress messages read.
    pub progress: u64,
    /// Transforms that ended, by outcome.
    pub outcomes: Vec<(String, u64)>,
    /// The first refusal, if any.
    pub refused: Option<String>,
}

/// Sends `set_formation` to `name` and back to `start` over `stream`, the next one
/// when the last one ended, until the daemon closes the stream.
pub fn command_transforms(stream: UnixStream, name: &str) -> Commanded {
    let mut out = Commanded::default();
    let Ok(mut w) = stream.try_clone() else {
        return out;
    };
    let mut r = BufReader::new(stream);
    if w.write_all(b"{\"type\":\"hello\",\"protocol\":1,\"subscribe\":[\"transform\"]}\n")
        .is_err()
    {
        return out;
    }
    let targets = [name, "start"];
    let mut k = 0usize;
    let mut line = String::new();
    let send = |w: &mut UnixStream, k: usize| {
        let cmd = format!(
            "{{\"type\":\"command\",\"id\":{k},\"name\":\"set_formation\",\"formation\":\"{}\",\"method\":\"transform\"}}\n",
            targets[k % 2]
        );
        w.write_all(cmd.as_bytes()).is_ok()
    };
    let mut hellos = 0;
    // A request that starts no transform (refused, or the formation the crowd is
    // in) is followed by the next one after this long without progress.
    let _ = r.get_ref().set_read_timeout(Some(Duration::from_secs(5)));
    loop {
        line.clear();
        match r.read_line(&mut line) {
            Ok(0) => return out,
            Ok(_) => {}
            Err(e)
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut =>
            {
                k += 1;
                if hellos < 2 || !send(&mut w, k) {
                    return out;
                }
                continue;
            }
            Err(_) => return out,
        }
        let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) else {
            continue;
        };
        match v["type"].as_str() {
            Some("hello") => {
                hellos += 1;
                if hellos == 2 && !send(&mut w, k) {
                    return out;
                }
            }
            Some("ack") => out.started += 1,
            Some("error") => {
                out.refused
                    .get_or_insert_with(|| v["message"].as_str().unwrap_or("").to_string());
            }
            Some("transform") => out.progress += 1,
            Some("transform_end") => {
                let o = v["outcome"].as_str().unwrap_or("?").to_string();
                match out.outcomes.iter_mut().find(|(n, _)| *n == o) {
                    Some((_, c)) => *c += 1,
                    None => out.outcomes.push((o, 1)),
                }
                if v["outcome"] != "superseded" {
                    k += 1;
                    if !send(&mut w, k) {
                        return out;
                    }
                }
            }
            _ => {}
        }
    }
}
