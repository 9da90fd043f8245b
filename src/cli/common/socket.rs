//! The tools' Unix socket client.

use anyhow::{Context, Result};
use crowdtouch::config::Config;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;

/// Reads lines from a Unix socket client, for the tools.
pub fn connect(socket: Option<PathBuf>) -> Result<BufReader<std::os::unix::net::UnixStream>> {
    let path = socket.unwrap_or_else(|| Config::embedded_default().socket.resolved_path());
    let s = std::os::unix::net::UnixStream::connect(&path).with_context(|| {
        format!(
            "connecting to {} (is the daemon running? try `crowdtouch demo`)",
            path.display()
        )
    })?;
    Ok(BufReader::new(s))
}

/// Reads one line; `None` at end of stream.
pub fn read_line(r: &mut impl BufRead, buf: &mut String) -> Result<Option<()>> {
    buf.clear();
    let n = r.read_line(buf).context("reading from the socket")?;
    Ok((n > 0).then_some(()))
}
