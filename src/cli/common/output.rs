//! Writing to stdout and stderr without panicking, and the exit status a failed
//! write gives.
//!
//! `println!` and `eprintln!` panic when the write fails (a full disk, `>/dev/full`,
//! a reader that went away), so the commands write through [`outln!`] and
//! [`errln!`] instead, which return the error. What happens then:
//!
//! * **A broken pipe** (`crowdtouch replay x | head`): the reader has taken what
//!   it wanted. The command stops, cleans up (the daemon removes its socket) and
//!   exits **0** without a message, as ripgrep and other Rust tools do; a command
//!   that had already failed (an invalid config) keeps its own status. The process
//!   is not killed by SIGPIPE (the Rust runtime ignores it): the daemon must get to
//!   its clean-up.
//! * **Any other write error** (`ENOSPC`, `EIO`): one line, `crowdtouch: error:
//!   cannot write to stdout: No space left on device (os error 28)`, on stderr (if
//!   stderr itself is what fails, nothing more can be said) and exit status **1**.
//!
//! The daemon's log lines (`env_logger`, on stderr) are the exception: a log line
//! that cannot be written is dropped and the daemon keeps running.

use std::fmt;
use std::io::{self, Write};

/// A write to stdout or stderr failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot write to {stream}")]
pub struct OutputError {
    /// `stdout` or `stderr`.
    stream: &'static str,
    /// Cause.
    #[source]
    source: io::Error,
}

/// Writes `args` to stdout and flushes it.
///
/// # Errors
/// [`OutputError`] when the write or the flush fails.
pub fn write_out(args: fmt::Arguments<'_>) -> Result<(), OutputError> {
    let mut o = io::stdout().lock();
    o.write_fmt(args)
        .and_then(|()| o.flush())
        .map_err(|source| OutputError {
            stream: "stdout",
            source,
        })
}

/// Writes `args` to stderr.
///
/// # Errors
/// [`OutputError`] when the write fails.
pub fn write_err(args: fmt::Arguments<'_>) -> Result<(), OutputError> {
    let mut e = io::stderr().lock();
    e.write_fmt(args)
        .and_then(|()| e.flush())
        .map_err(|source| OutputError {
            stream: "stderr",
            source,
        })
}

/// `println!` that returns `Result<(), OutputError>` instead of panicking.
macro_rules! outln {
    () => {
        $crate::cli::common::output::write_out(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::cli::common::output::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` that returns `Result<(), OutputError>` instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::common::output::write_out(format_args!($($arg)*))
    };
}

/// `eprintln!` that returns `Result<(), OutputError>` instead of panicking.
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::cli::common::output::write_err(format_args!("{}\n", format_args!($($arg)*)))
    };
}

pub(crate) use {errln, out, outln};

/// Whether `e` or any of its causes is a broken pipe: the reader went away.
pub fn is_broken_pipe(e: &(dyn std::error::Error + 'static)) -> bool {
    let mut cur = Some(e);
    while let Some(c) = cur {
        if c.downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
        {
            return true;
        }
        cur = c.source();
    }
    false
}

/// An error and its causes on one line, `a: b: c`. A cause whose text its error
/// already shows (`#[error("…: {source}")]` with `#[source]`, the convention of
/// the library's error enums) is written once.
pub fn chain_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// The exit status of a command: its own on success; 0 when it stopped because a
/// reader went away; otherwise 1, after one `crowdtouch: error: …` line on stderr.
pub fn exit_status(result: anyhow::Result<i32>) -> i32 {
    let (code, message) = outcome(result);
    if let Some(m) = message {
        // Nothing more can be done when stderr is what fails.
        let _ = errln!("{m}");
    }
    code
}

/// The exit status of a command and the line to write on stderr, if any.
fn outcome(result: anyhow::Result<i32>) -> (i32, Option<String>) {
    match result {
        Ok(code) => (code, None),
        Err(e) if is_broken_pipe(e.as_ref()) => (0, None),
        Err(e) => (1, Some(format!("crowdtouch: error: {}", chain_line(&e)))),
    }
}

/// Writes a report of a failure (an invalid file) on stderr and returns `code`:
/// the failure decides the exit status whether or not its report could be written.
pub fn fail_with(code: i32, report: fmt::Arguments<'_>) -> i32 {
    let _ = write_err(format_args!("{report}\n"));
    code
}

/// The viewer URL's query for a WebSocket token (`?token=T`, or nothing).
pub fn token_query(token: Option<&str>) -> String {
    token.map(|t| format!("?token={t}")).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("/x/y.sock: cannot bind the socket: {source}")]
    struct Bind {
        #[source]
        source: io::Error,
    }

    #[test]
    fn a_cause_the_message_already_shows_is_written_once() {
        let io = io::Error::from_raw_os_error(2);
        let e = anyhow::Error::from(Bind { source: io }).context("starting the daemon");
        assert_eq!(
            chain_line(&e),
            "starting the daemon: /x/y.sock: cannot bind the socket: No such file or directory (os error 2)"
        );
        // A cause not in the message is added after it.
        let e = anyhow::Error::from(io::Error::from_raw_os_error(28)).context("writing frames");
        assert_eq!(
            chain_line(&e),
            "writing frames: No space left on device (os error 28)"
        );
    }

    #[test]
    fn a_broken_pipe_anywhere_in_the_chain_ends_quietly_with_status_0() {
        let pipe = OutputError {
            stream: "stdout",
            source: io::Error::from(io::ErrorKind::BrokenPipe),
        };
        let e = anyhow::Error::from(pipe).context("writing snapshots");
        assert!(is_broken_pipe(e.as_ref()));
        assert_eq!(outcome(Err(e)), (0, None));
        let full = OutputError {
            stream: "stdout",
            source: io::Error::from_raw_os_error(28),
        };
        assert!(!is_broken_pipe(&full));
        assert_eq!(
            outcome(Err(full.into())),
            (
                1,
                Some(
                    "crowdtouch: error: cannot write to stdout: No space left on device (os error 28)"
                        .to_string()
                )
            )
        );
        assert_eq!(outcome(Ok(2)), (2, None));
    }
}
