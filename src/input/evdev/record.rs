//! Recording an evdev node: the thin device shell behind `crowdtouch record`. It opens
//! the node, snapshots its capabilities and writes every event it reads, as an evemu
//! file ([`EvemuWriter`]), until told to stop.

use crate::input::recording::EvemuWriter;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Records the raw events of the evdev device `node` into `w` as an evemu file,
/// until `stop` is set (checked at least every [`crate::input::STOP_CHECK_US`]).
///
/// Every event the device sends is written as it came (a `SYN_DROPPED` too),
/// with times relative to the first one. The device is not grabbed and its
/// clock is not switched (the times are relative anyway). Returns the number
/// of events written.
///
/// # Errors
/// [`crate::input::Error`] from opening the node, `Unplugged` when it goes away, and
/// [`crate::input::Error::Io`] (op `"write recording"`) when `w` fails.
pub fn record_evdev(
    node: &Path,
    w: impl Write,
    stop: &AtomicBool,
) -> Result<u64, crate::input::Error> {
    let dev = super::device::open_node(node)?;
    let caps = super::device::capabilities(&dev)
        .map_err(|e| crate::input::Error::from_io(node, "query capabilities", e))?;
    let werr = |source| crate::input::Error::Io {
        node: node.to_path_buf(),
        op: "write recording",
        source,
    };
    let mut out = EvemuWriter::new(&caps, w).map_err(werr)?;
    let mut buf = [0u8; super::device::READ_BUF_BYTES];
    while !stop.load(Ordering::Relaxed) {
        let n = super::device::wait_read(
            &dev,
            node,
            &mut buf,
            (crate::input::STOP_CHECK_US / 1000) as u16,
        )?;
        for ev in super::device::parse_input_events(&buf[..n]) {
            out.event(&ev).map_err(werr)?;
        }
        if n > 0 {
            out.flush().map_err(werr)?;
        }
    }
    out.flush().map_err(werr)?;
    Ok(out.events())
}
