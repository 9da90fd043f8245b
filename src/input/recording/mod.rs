//! Touch recordings: readers for the formats people have, and our own writers.
//!
//! [`read_recording`] detects the format and returns a [`Recording`]: the
//! surface, and the frames normalised to the unit square with their life-cycle
//! flags already derived, timed relative to the start of the recording.
//!
//! # Formats
//!
//! * **crowdtouch JSON Lines** (`.jsonl`, ours; `jsonl.rs`), written by
//!   [`write_jsonl`] and [`JsonlWriter`].
//! * **evemu** (`evemu-record` text; `evemu.rs`), also as a `.desc` with its
//!   events ([`read_evemu_with_desc`]); [`read_evemu_raw`] reads one without
//!   decoding it, and [`EvemuWriter`] writes one.
//! * **libinput record** YAML, version 1 (`libinput_yaml.rs`).
//! * **hid-recorder** (raw HID reports; `hid_recorder.rs`): [`read_hid_recorder`],
//!   and [`HidRecorderWriter`].
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
//! declare. With [`OnBadFrame::Stop`] the first such problem is a
//! [`RecordingError::Parse`]; with [`OnBadFrame::Skip`] the frame holding it is
//! skipped (for evdev formats: every event up to and including the next
//! `SYN_REPORT`) and a [`RecordingIssue`] is recorded instead. Problems with the
//! header are always fatal. The readers never panic, whatever the input.
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
mod jsonl;
mod jsonl_writer;
mod libinput_yaml;
mod read;
mod recording_type;
mod shipped;
mod warnings;

pub use error::{OnBadFrame, RecordingError, UnsupportedReason};
pub use evemu::read_evemu_with_desc;
pub use evemu_raw::read_evemu_raw;
pub use evemu_writer::{write_evemu_header, EvemuTime, EvemuWriter, EVEMU_VERSION};
pub use hid_recorder::{
    decode_hid_recording, parse_hid_recorder, read_hid_recorder, HidEvent, HidRecorderLog,
    HidRecorderWriter,
};
pub use jsonl::{JSONL_FORMAT, JSONL_VERSION};
pub use jsonl_writer::{write_jsonl, JsonlWriter};
pub use read::{parse_recording, read_recording, MAX_RECORDING_BYTES};
pub use recording_type::{Recording, END_CANCEL_US};
pub use shipped::{load_recording, RECORDINGS};
pub use warnings::{RecordingIssue, MAX_WARNINGS};
