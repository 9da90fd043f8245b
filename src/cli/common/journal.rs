//! Log lines for journald: under systemd the daemon's stderr is a stream to the
//! journal, which stamps every line itself and reads its priority from a `<N>`
//! prefix (sd-daemon(3)). There the lines carry that prefix and no timestamp or
//! level word of their own; anywhere else `env_logger`'s usual format stays.
//!
//! systemd sets `JOURNAL_STREAM=DEV:INODE` to the stream it connected stderr to
//! (systemd.exec(5)); the variable is inherited by children whose stderr may be
//! something else, so the device and inode are compared with stderr's own.

use std::os::unix::fs::MetadataExt;

/// The syslog priority of a log level (sd-daemon(3): `<3>` error, `<4>` warning,
/// `<6>` info, `<7>` debug).
pub fn priority(level: log::Level) -> u8 {
    match level {
        log::Level::Error => 3,
        log::Level::Warn => 4,
        log::Level::Info => 6,
        log::Level::Debug | log::Level::Trace => 7,
    }
}

/// Whether `journal_stream` (the value of `JOURNAL_STREAM`) names the file whose
/// device and inode are `stderr`.
pub fn names_stderr(journal_stream: &str, stderr: (u64, u64)) -> bool {
    let Some((dev, ino)) = journal_stream.split_once(':') else {
        return false;
    };
    matches!((dev.parse::<u64>(), ino.parse::<u64>()), (Ok(d), Ok(i)) if (d, i) == stderr)
}

/// Whether this process's stderr is the journal's stream.
pub fn stderr_is_journal() -> bool {
    let Ok(stream) = std::env::var("JOURNAL_STREAM") else {
        return false;
    };
    // The file descriptor's own link: stat follows it to the socket or file.
    match std::fs::metadata("/proc/self/fd/2") {
        Ok(m) => names_stderr(&stream, (m.dev(), m.ino())),
        Err(_) => false,
    }
}

/// Sets `b` to write journal lines: `<N>message`, continuation lines of a
/// multi-line message with the same prefix (each line is a journal entry).
pub fn use_journal_format(b: &mut env_logger::Builder) {
    use std::io::Write;
    b.format(|f, record| {
        let p = priority(record.level());
        let text = record.args().to_string();
        for line in text.lines() {
            writeln!(f, "<{p}>{line}")?;
        }
        if text.is_empty() {
            writeln!(f, "<{p}>")?;
        }
        Ok(())
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn priorities_follow_sd_daemon() {
        assert_eq!(priority(log::Level::Error), 3);
        assert_eq!(priority(log::Level::Warn), 4);
        assert_eq!(priority(log::Level::Info), 6);
        assert_eq!(priority(log::Level::Debug), 7);
        assert_eq!(priority(log::Level::Trace), 7);
    }

    #[test]
    fn only_stderrs_own_device_and_inode_count() {
        assert!(names_stderr("25:4711", (25, 4711)));
        assert!(!names_stderr("25:4711", (25, 4712)));
        assert!(!names_stderr("25", (25, 4711)));
        assert!(!names_stderr("x:y", (25, 4711)));
        assert!(!names_stderr("", (0, 0)));
    }
}
