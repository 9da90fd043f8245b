//! The problems a reader notes without stopping: located issues, capped at
//! [`MAX_WARNINGS`] per reading, one collector for every reader. A stream hands
//! them out as it goes ([`Warnings::take`]), so none is held longer than needed.

use std::fmt;

/// Most issues a recording keeps; later ones are only counted in a last issue.
pub const MAX_WARNINGS: usize = 1_000;

/// A problem found in a recording.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordingIssue {
    /// 1-based line in the file; 0 when the issue is about the whole file.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for RecordingIssue {
    /// `line N: message`, the control characters the message quotes from the file
    /// escaped.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let message = crate::located::Escaped(&self.message);
        if self.line == 0 {
            write!(f, "{message}")
        } else {
            write!(f, "line {}: {message}", self.line)
        }
    }
}

/// The issues of a recording, capped at [`MAX_WARNINGS`].
#[derive(Debug, Default)]
pub(super) struct Warnings {
    list: Vec<RecordingIssue>,
    /// Issues listed so far, including those already taken.
    listed: usize,
    dropped: usize,
}

impl Warnings {
    pub(super) fn push(&mut self, line: usize, message: String) {
        if self.listed < MAX_WARNINGS {
            self.list.push(RecordingIssue { line, message });
            self.listed += 1;
        } else {
            self.dropped += 1;
        }
    }

    /// The issues listed since the last call (no allocation when there is none).
    pub(super) fn take(&mut self) -> Vec<RecordingIssue> {
        std::mem::take(&mut self.list)
    }

    /// Lists how many issues went unlisted, once, at the end of a reading.
    pub(super) fn close(&mut self) {
        if self.dropped > 0 {
            self.list.push(RecordingIssue {
                line: 0,
                message: format!("{} more issues not listed", self.dropped),
            });
            self.dropped = 0;
        }
    }

    pub(super) fn finish(mut self) -> Vec<RecordingIssue> {
        self.close();
        self.list
    }
}
