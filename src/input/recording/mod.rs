//! Touch recordings: readers for the formats people have, and our own writers.
//!
//! A [`RecordingStream`] detects the format and reads a recording a frame at a
//! time: the surface, then the frames normalised to the unit square with their
//! life-cycle flags already derived, timed relative to the start of the
//! recording. It holds one line and one frame at a time, so a recording of any
//! length is read in the same memory; replays use it, going back to the start
//! ([`RecordingStream::rewind`]) to loop. [`read_recording`] collects every
//! frame into a [`Recording`], for tools and tests.
//!
//! # Formats
//!
//! * **crowdtouch JSON Lines** (`.jsonl`, ours; `jsonl.rs`), written by
//!   [`write_jsonl`] and [`JsonlWriter`].
//! * **evemu** (`evemu-record` text; `evemu.rs`), also as a `.desc` with its
//!   events ([`read_evemu_with_desc`]); [`read_evemu_raw`] reads one without
//!   decoding it, and [`EvemuWriter`] writes one.
//! * **libinput record** YAML, version 1 (`libinput_yaml.rs`, on the YAML
//!   events of `yaml_events.rs`).
//! * **hid-recorder** (raw HID reports; `hid_recorder.rs`, decoded by
//!   `hid_stream.rs`): [`parse_hid_recorder`] reads one without decoding it, and
//!   [`HidRecorderWriter`] writes one.
//!
//! evemu and libinput record are evdev streams decoded by the multi-touch decoder
//! (`evdev_header.rs`, `event_stream.rs`): they must describe a multi-touch device,
//! or fail with [`RecordingError::Unsupported`].
//!
//! # Bad input
//!
//! Every reader reports what is wrong at the 1-based line where it is, and for
//! JSON Lines the field (`contacts[1].x`): a truncated line, a wrong type, a
//! timestamp going backwards, a missing header, an axis the header does not
//! declare, a frame listing more contacts than the header's `max_contacts`, a
//! line longer than [`MAX_LINE_BYTES`] (refused before it is buffered whole).
//! With [`OnBadFrame::Stop`] the first such problem is a
//! [`RecordingError::Parse`]; with [`OnBadFrame::Skip`] the frame holding it is
//! skipped (for evdev formats: every event up to and including the next
//! `SYN_REPORT`) and a [`RecordingIssue`] is recorded instead. Problems with the
//! header, text that is not UTF-8 and malformed YAML are always fatal. Values
//! the readers do not need (unknown keys) are skipped without being kept. The
//! readers never panic, whatever the input.
//!
//! # Time
//!
//! Timestamps must not go back. A jump of more than [`MAX_TIME_JUMP_US`] (a
//! day) between two frames is taken for a clock fault: a warning at its line
//! (`timestamp jumps by 584942 years; …`), and the jump is shortened to
//! [`JUMP_REPLAYED_US`], in every format. Times are `u64` microseconds; no
//! timestamp, up to `u64::MAX`, makes a reader overflow.
//!
//! # End of a recording
//!
//! Contacts still down after the last frame get a final frame, [`END_CANCEL_US`]
//! after it, that ends them as `CANCELLED`, so nothing sticks when the recording
//! is replayed.

mod error;
mod evdev_header;
mod evemu;
mod evemu_raw;
mod evemu_writer;
mod event_stream;
mod hid_recorder;
mod hid_stream;
mod jsonl;
mod jsonl_frame;
mod jsonl_values;
mod jsonl_writer;
mod libinput_yaml;
mod lines;
mod read;
mod recording_type;
mod shipped;
mod stream;
mod warnings;
mod yaml_events;

#[cfg(test)]
mod tests;

pub use error::{OnBadFrame, RecordingError, UnsupportedReason};
pub use evemu_raw::read_evemu_raw;
pub use evemu_writer::{write_evemu_header, EvemuTime, EvemuWriter, EVEMU_VERSION};
pub use hid_recorder::{parse_hid_recorder, HidEvent, HidRecorderLog, HidRecorderWriter};
pub use jsonl::{JSONL_FORMAT, JSONL_VERSION};
pub use jsonl_writer::{write_jsonl, JsonlWriter};
pub use lines::MAX_LINE_BYTES;
pub use read::{
    load_recording, parse_recording, read_evemu_with_desc, read_recording, MAX_RECORDING_BYTES,
};
pub use recording_type::{Recording, END_CANCEL_US};
pub use shipped::RECORDINGS;
pub use stream::{RecordingStream, JUMP_REPLAYED_US, MAX_TIME_JUMP_US};
pub use warnings::{RecordingIssue, MAX_WARNINGS};
