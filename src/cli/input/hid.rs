//! `crowdtouch hid …`: tools for raw HID digitizers.

use crate::cli::common::output::outln;
use anyhow::Result;
use crowdtouch::input::hid::{describe, read_descriptor_file};
use std::path::PathBuf;

/// `crowdtouch hid` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum HidCmd {
    /// Print, as JSON, the digitizer layout crowdtouch finds in a report descriptor:
    /// one object per touch collection (application, contacts per report, maximum
    /// contacts, report ids, per-finger fields with logical/physical ranges and
    /// units), or `{"touch": false, "reason": …}`.
    ///
    /// FILE is a raw descriptor (`/sys/class/hidraw/hidrawN/device/report_descriptor`,
    /// an .rdesc dump), a hid-recorder log (its R: line) or a hex dump.
    Describe {
        /// Descriptor file.
        file: PathBuf,
    },
}

/// Runs a `hid` subcommand. A descriptor that is not a touch digitizer is a
/// result (printed, exit 0), not an error; an unreadable file is an error.
pub fn hid(cmd: HidCmd) -> Result<()> {
    match cmd {
        HidCmd::Describe { file } => {
            let bytes = read_descriptor_file(&file)?;
            outln!("{}", serde_json::to_string_pretty(&describe(&bytes))?)?;
            Ok(())
        }
    }
}
