//! Reading and writing track sets. Every reader parses text it is given (the caller
//! reads the file, capped) and names the line and what is wrong; none panics.
//!
//! | format | file | what |
//! |---|---|---|
//! | [`Format::Jsonl`] | `jsonl.rs` | ours: a header line (`crowdtouch-tracks`, version, frame step), then one sample per line, explicit gaps |
//! | [`Format::Csv`] | `csv.rs` | `t,id,x,y` per line, an optional header; links from the frame step |
//! | `format.rs` | [`Format`], [`detect`], [`read`](read()), [`write`](write()): a format by name, extension or first line, and the reader or writer for it |
//! | `file.rs` | [`read_tracks`], [`read_tracks_flat`], [`write_tracks`]: files read capped (regular files only), written to a temporary file put in place; [`read_track_entry`], [`write_track_entry`]: the daemon's entries of its edit directory, by name |
//! | [`Format::Eth`] | `eth.rs` | the public pedestrian datasets (ETH/UCY as redistributed by trajectory-prediction projects): `frame id x y` per line, whitespace-separated, metres |

mod csv;
mod error;
mod eth;
mod file;
mod format;
mod jsonl;
#[cfg(test)]
mod tests;
mod text;

pub use csv::{median_step, read_csv, read_csv_flat, write_csv, LINK_STEPS, SINGLE_SAMPLE_STEP_S};
pub use error::ReadError;
pub use eth::{read_eth, write_eth, EthOptions};
pub use file::{
    read_track_entry, read_tracks, read_tracks_flat, without_quotes, write_track_entry,
    write_tracks, MAX_TRACK_FILE_BYTES,
};
pub use format::{detect, read, write, Format, ReadOptions};
pub use jsonl::{read_jsonl, write_jsonl, JSONL_FORMAT, JSONL_VERSION};
