//! Reading a touch device through its evdev node (`/dev/input/eventN`).
//!
//! A thin shell around the pure pieces: [`parse_input_events`] turns the bytes
//! `read(2)` returns into [`RawEvent`]s, [`MtDecoder`] turns those into frames,
//! [`EvdevCapabilities::decoder_setup`] decides how to decode a device, and
//! [`slot_state_from`] builds the [`MtSlotState`] a resync needs from what the
//! ioctls returned. What is left here opens the node, asks the kernel and
//! loops; it cannot run without a device.
//!
//! # The read loop ([`EvdevReader`])
//!
//! ```text
//! open (O_RDONLY | O_NONBLOCK) → capabilities → EVIOCSCLOCKID(CLOCK_MONOTONIC)
//!   → EVIOCGRAB (if asked) → query slots → resync (fingers already down)
//! loop: flush held-back frames → poll(POLLIN, STOP_CHECK_US, or FLUSH_RETRY_US while frames are held back) → stop? → read ≤ READ_EVENTS events
//!   → decoder.event each → frame? push to the sink
//!                         → dropped block ended? query slots → resync → push
//! ENODEV (or EOF) → Err(Unplugged)
//! ```
//!
//! Setting the clock makes the kernel flush the client buffer and queue a
//! `SYN_DROPPED`, so the first frame after open is discarded and a second
//! resync follows; nothing is lost that the state query does not restore.
//! The loop allocates nothing: a fixed read buffer, a fixed frame, a fixed
//! [`MtSlotState`].

use super::capabilities::{AbsAxisInfo, DecoderSetup, EvdevCapabilities};
use super::codes::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE, ABS_MT_SLOT, ABS_MT_TOOL_TYPE,
    ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, ABS_MT_TRACKING_ID, ABS_PRESSURE, ABS_X, ABS_Y,
    BTN_TOUCH, EV_ABS,
};
use super::mt::{MtDecoder, MtProtocol, MtSlotState, RawEvent, MAX_SLOTS};
use crate::input::{DeviceIdentity, DeviceInfo, DeviceKind, DeviceReader, Error, FrameSink};
use crate::rt::monotonic_now;
use crate::sys;
use crate::vocab::Micros;
use crate::vocab::TouchFrame;
use nix::errno::Errno;
use nix::libc;
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use std::io;
use std::os::fd::{AsFd, AsRawFd};
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

pub use evdev::raw_stream::RawDevice;

/// Bytes of one `struct input_event` on this platform: two `long`s of
/// `timeval`, then `u16` type, `u16` code, `i32` value (24 on 64-bit).
pub const INPUT_EVENT_BYTES: usize = 2 * std::mem::size_of::<libc::c_long>() + 8;
const _: () = assert!(INPUT_EVENT_BYTES == std::mem::size_of::<libc::input_event>());

/// Events read with one `read(2)`.
pub const READ_EVENTS: usize = 64;
/// Bytes of the read buffer.
pub const READ_BUF_BYTES: usize = READ_EVENTS * INPUT_EVENT_BYTES;

/// Microseconds from a `timeval` (negative times clamp to zero).
pub fn timeval_micros(sec: i64, usec: i64) -> Micros {
    let us = i128::from(sec) * 1_000_000 + i128::from(usec);
    Micros(us.clamp(0, i128::from(u64::MAX)) as u64)
}

/// Parses one `struct input_event` from the first [`INPUT_EVENT_BYTES`] of
/// `b` (native byte order, as `read(2)` returns it); `None` when `b` is shorter.
pub fn parse_input_event(b: &[u8]) -> Option<RawEvent> {
    const W: usize = std::mem::size_of::<libc::c_long>();
    let b = b.get(..INPUT_EVENT_BYTES)?;
    // `c_long` is `i64` on 64-bit targets and `i32` on 32-bit ones.
    #[allow(clippy::useless_conversion)]
    let long = |at: usize| -> i64 {
        let mut v = [0u8; W];
        v.copy_from_slice(&b[at..at + W]);
        i64::from(libc::c_long::from_ne_bytes(v))
    };
    let u16_at = |at: usize| u16::from_ne_bytes([b[at], b[at + 1]]);
    Some(RawEvent {
        t: timeval_micros(long(0), long(W)),
        ev_type: u16_at(2 * W),
        code: u16_at(2 * W + 2),
        value: i32::from_ne_bytes([b[2 * W + 4], b[2 * W + 5], b[2 * W + 6], b[2 * W + 7]]),
    })
}

/// The events in `bytes`, in order; a trailing partial event is ignored (the
/// kernel only returns whole events).
pub fn parse_input_events(bytes: &[u8]) -> impl Iterator<Item = RawEvent> + '_ {
    bytes
        .chunks_exact(INPUT_EVENT_BYTES)
        .filter_map(parse_input_event)
}

/// Options for [`EvdevReader::open`].
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct EvdevOptions {
    /// Take the device exclusively (`EVIOCGRAB`): the desktop no longer sees it.
    pub grab: bool,
}

/// Opens `node` read-only and non-blocking and reads its identity and
/// capability bits (through the `evdev` crate).
///
/// # Errors
/// [`Error::from_io`] of the open; [`Error::NotTouch`] when the node is not
/// an evdev device.
pub fn open_node(node: &Path) -> Result<RawDevice, Error> {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(node)
        .map_err(|e| Error::from_io(node, "open", e))?;
    RawDevice::from_fd(file.into()).map_err(|e| {
        if e.raw_os_error() == Some(libc::ENOTTY) {
            Error::NotTouch {
                node: node.to_path_buf(),
                reason: "not an evdev node".to_string(),
            }
        } else {
            Error::from_io(node, "query device", e)
        }
    })
}

/// The capability snapshot of an open device.
///
/// # Errors
/// The absinfo query's error.
pub fn capabilities(dev: &RawDevice) -> io::Result<EvdevCapabilities> {
    let mut c = EvdevCapabilities::new(dev.name().unwrap_or_default());
    let id = dev.input_id();
    c.bus = id.bus_type().0;
    c.vendor = id.vendor();
    c.product = id.product();
    c.version = id.version();
    for p in dev.properties().iter() {
        c.set_property(p.0);
    }
    // EVIOCGBIT(0): the event types, as the kernel (and old evemu) put in `B: 00`.
    for t in dev.supported_events().iter() {
        c.set_code(0, t.0);
    }
    let mut set = |ty: u16, codes: &mut dyn Iterator<Item = u16>| {
        for code in codes {
            c.set_code(ty, code);
        }
    };
    if let Some(s) = dev.supported_keys() {
        set(super::codes::EV_KEY, &mut s.iter().map(|k| k.0));
    }
    if let Some(s) = dev.supported_relative_axes() {
        set(super::codes::EV_REL, &mut s.iter().map(|k| k.0));
    }
    if let Some(s) = dev.misc_properties() {
        set(super::codes::EV_MSC, &mut s.iter().map(|k| k.0));
    }
    if let Some(s) = dev.supported_switches() {
        set(super::codes::EV_SW, &mut s.iter().map(|k| k.0));
    }
    if let Some(s) = dev.supported_leds() {
        set(super::codes::EV_LED, &mut s.iter().map(|k| k.0));
    }
    if let Some(s) = dev.supported_sounds() {
        set(super::codes::EV_SND, &mut s.iter().map(|k| k.0));
    }
    if let Some(s) = dev.supported_ff() {
        set(super::codes::EV_FF, &mut s.iter().map(|k| k.0));
    }
    for (code, a) in dev.get_absinfo()? {
        c.set_abs(
            code.0,
            AbsAxisInfo {
                value: a.value(),
                minimum: a.minimum(),
                maximum: a.maximum(),
                fuzz: a.fuzz(),
                flat: a.flat(),
                resolution: a.resolution(),
            },
        );
    }
    Ok(c)
}

/// What discovery learns from the device itself (udev facts — `id_path`,
/// calibration — are filled in by discovery): name, ids, `uniq` as serial,
/// `stable_id` from `vendor:product:serial`, the surface and whether it is a
/// touchscreen.
pub fn device_info(
    node: &Path,
    caps: &EvdevCapabilities,
    setup: &DecoderSetup,
    uniq: Option<&str>,
) -> DeviceInfo {
    let serial = uniq
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_string);
    DeviceInfo {
        identity: DeviceIdentity {
            kind: DeviceKind::Evdev,
            node: node.to_path_buf(),
            name: caps.name.clone(),
            bus: caps.bus,
            vendor: caps.vendor,
            product: caps.product,
            serial: serial.clone(),
        },
        id_path: None,
        stable_id: DeviceInfo::make_stable_id(None, caps.vendor, caps.product, serial.as_deref()),
        surface: caps.surface(setup),
        direct: caps.is_direct(),
        calibration: None,
    }
}

/// Opens `node` read-only and describes it.
///
/// # Errors
/// [`Error::NotTouch`] (with the reason) when it has no usable touch axes;
/// I/O errors classified by [`Error::from_io`].
pub fn probe(node: &Path) -> Result<DeviceInfo, Error> {
    let dev = open_node(node)?;
    let caps = capabilities(&dev).map_err(|e| Error::from_io(node, "query absinfo", e))?;
    let setup = caps.decoder_setup().map_err(|r| Error::NotTouch {
        node: node.to_path_buf(),
        reason: r.to_string(),
    })?;
    Ok(device_info(node, &caps, &setup, dev.unique_name()))
}

/// The `ABS_MT_*` codes a type-B resync queries for a device: tracking id and
/// position always, then the optional axes it declares. Unused entries are 0.
pub fn slot_codes(caps: &EvdevCapabilities, setup: &DecoderSetup) -> ([u16; 7], usize) {
    let mut codes = [0u16; 7];
    let mut n = 0;
    let mut add = |c: u16| {
        codes[n] = c;
        n += 1;
    };
    add(ABS_MT_TRACKING_ID);
    add(ABS_MT_POSITION_X);
    add(ABS_MT_POSITION_Y);
    if setup.axes.pressure.is_some() {
        add(ABS_MT_PRESSURE);
    }
    if setup.axes.touch_major.is_some() {
        add(ABS_MT_TOUCH_MAJOR);
    }
    if setup.axes.touch_minor.is_some() {
        add(ABS_MT_TOUCH_MINOR);
    }
    if caps.has_code(EV_ABS, ABS_MT_TOOL_TYPE) {
        add(ABS_MT_TOOL_TYPE);
    }
    (codes, n)
}

/// Builds the single-touch resync state: slot 0 is down while `BTN_TOUCH` is
/// set in `keys` (the `EVIOCGKEY` bitmask), at `x`, `y`, with `pressure`.
pub fn single_touch_state(
    keys: &[u8],
    x: i32,
    y: i32,
    pressure: Option<i32>,
    out: &mut MtSlotState,
) {
    let down = keys
        .get(usize::from(BTN_TOUCH / 8))
        .is_some_and(|b| (b >> (BTN_TOUCH % 8)) & 1 == 1);
    *out = MtSlotState::new(1);
    let s = &mut out.slots_mut()[0];
    s.tracking_id = if down { 0 } else { -1 };
    s.x = x;
    s.y = y;
    s.pressure = pressure;
}

/// Fills `state` (already sized to the slot count) from per-code slot columns
/// and the selected slot: `columns[k]` holds the values of `codes[k]`.
pub fn slot_state_from(
    codes: &[u16],
    columns: &[[i32; MAX_SLOTS]],
    selected: i32,
    state: &mut MtSlotState,
) {
    let n = state.len();
    for (&code, col) in codes.iter().zip(columns) {
        state.set_column(code, &col[..n]);
    }
    state.selected = Some(selected);
}

/// Waits up to `timeout_ms` for `dev` to be readable and reads what it
/// has into `buf`; 0 bytes when nothing came (or a signal interrupted).
///
/// # Errors
/// [`Error::Unplugged`] on `ENODEV` or end of file; other errors classified by
/// [`Error::from_io`].
pub fn wait_read(
    dev: &RawDevice,
    node: &Path,
    buf: &mut [u8],
    timeout_ms: u16,
) -> Result<usize, Error> {
    let fd = dev.as_fd();
    let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
    let timeout = PollTimeout::from(timeout_ms);
    match poll(&mut fds, timeout) {
        Ok(0) | Err(Errno::EINTR) => return Ok(0),
        Ok(_) => {}
        Err(e) => return Err(Error::from_io(node, "poll", io::Error::from(e))),
    }
    match nix::unistd::read(fd.as_raw_fd(), buf) {
        Ok(0) => Err(Error::Unplugged {
            node: node.to_path_buf(),
        }),
        Ok(n) => Ok(n),
        Err(Errno::EAGAIN | Errno::EINTR) => Ok(0),
        Err(e) => Err(Error::from_io(node, "read", io::Error::from(e))),
    }
}

/// An open evdev touch device, decoded on the input thread.
#[derive(Debug)]
pub struct EvdevReader {
    dev: RawDevice,
    info: DeviceInfo,
    decoder: MtDecoder,
    /// `ABS_MT_*` codes a resync queries.
    codes: [u16; 7],
    ncodes: usize,
    state: MtSlotState,
    columns: [[i32; MAX_SLOTS]; 7],
    buf: [u8; READ_BUF_BYTES],
    frame: TouchFrame,
    /// The frame of the resync at open, not yet handed to a sink.
    initial: bool,
    resync_failures: u64,
    /// `EVIOCGRAB` asked for and not yet done (a finger was down).
    grab_pending: bool,
    /// `SYN_DROPPED` blocks already reported in the log.
    drops_seen: u64,
    /// When a `SYN_DROPPED` was last logged (the log is rate-limited).
    last_drop_log: Option<Micros>,
}

/// Shortest interval between two log lines about `SYN_DROPPED` from one device (µs).
pub const DROP_LOG_INTERVAL_US: u64 = 5_000_000;

impl EvdevReader {
    /// Opens `node`: checks it is a touch device, switches its clock to
    /// CLOCK_MONOTONIC, and reads which contacts are already down (delivered as
    /// the first frame of [`DeviceReader::run`]).
    ///
    /// With [`EvdevOptions::grab`] the device is taken exclusively (`EVIOCGRAB`)
    /// as soon as no finger is down: at once when the glass is clear, otherwise
    /// after the last lift, so that a desktop that already saw a touch also sees
    /// it end instead of keeping a stuck finger.
    ///
    /// # Errors
    /// `PermissionDenied` (EACCES), `Busy` (EBUSY on grab: another program holds
    /// the device; also from [`DeviceReader::run`] for a deferred grab),
    /// `Unplugged` (ENODEV), `NotFound`, `NotTouch`, or `Io`.
    pub fn open(node: &Path, opts: &EvdevOptions) -> Result<EvdevReader, Error> {
        let dev = open_node(node)?;
        let caps = capabilities(&dev).map_err(|e| Error::from_io(node, "query absinfo", e))?;
        let setup = caps.decoder_setup().map_err(|r| Error::NotTouch {
            node: node.to_path_buf(),
            reason: r.to_string(),
        })?;
        let info = device_info(node, &caps, &setup, dev.unique_name());
        sys::set_clock_monotonic(dev.as_fd())
            .map_err(|e| Error::from_io(node, "EVIOCSCLOCKID", e))?;
        let (codes, ncodes) = slot_codes(&caps, &setup);
        let slots = setup.axes.slots;
        let decoder = MtDecoder::with_protocol(setup.axes, setup.protocol, 1);
        let mut r = EvdevReader {
            dev,
            info,
            decoder,
            codes,
            ncodes,
            state: MtSlotState::new(slots),
            columns: [[0; MAX_SLOTS]; 7],
            buf: [0; READ_BUF_BYTES],
            frame: TouchFrame::default(),
            initial: false,
            resync_failures: 0,
            grab_pending: opts.grab,
            drops_seen: 0,
            last_drop_log: None,
        };
        r.initial = r.query_and_resync(monotonic_now())?;
        r.grab_when_clear()?;
        Ok(r)
    }

    /// Takes the pending exclusive grab once no contact is down.
    fn grab_when_clear(&mut self) -> Result<(), Error> {
        if self.grab_pending && self.decoder.active_contacts() == 0 {
            self.dev
                .grab()
                .map_err(|e| Error::from_io(&self.info.identity.node, "EVIOCGRAB", e))?;
            self.grab_pending = false;
            log::debug!("{}: grabbed (exclusive)", self.info.identity.node.display());
        }
        Ok(())
    }

    /// Whether the exclusive grab asked for is still waiting for the glass to
    /// clear.
    pub fn grab_pending(&self) -> bool {
        self.grab_pending
    }

    /// What the decoder has seen.
    pub fn counters(&self) -> super::mt::MtCounters {
        self.decoder.counters()
    }

    /// State queries that failed (the contacts were then cancelled).
    pub fn resync_failures(&self) -> u64 {
        self.resync_failures
    }

    /// Queries the device state into `self.state`.
    fn query_state(&mut self) -> io::Result<()> {
        let fd = self.dev.as_fd();
        match self.decoder.protocol() {
            MtProtocol::A => {}
            MtProtocol::B => {
                let n = self.state.len();
                for k in 0..self.ncodes {
                    sys::mt_slots(fd, self.codes[k], &mut self.columns[k][..n])?;
                }
                let selected = sys::abs_info(fd, ABS_MT_SLOT)?[0];
                slot_state_from(
                    &self.codes[..self.ncodes],
                    &self.columns[..self.ncodes],
                    selected,
                    &mut self.state,
                );
            }
            MtProtocol::SingleTouch => {
                let mut keys = [0u8; sys::KEY_STATE_BYTES];
                sys::key_state(fd, &mut keys)?;
                let x = sys::abs_info(fd, ABS_X)?[0];
                let y = sys::abs_info(fd, ABS_Y)?[0];
                let p = match self.decoder.axes().pressure {
                    Some(_) => Some(sys::abs_info(fd, ABS_PRESSURE)?[0]),
                    None => None,
                };
                single_touch_state(&keys, x, y, p, &mut self.state);
            }
        }
        Ok(())
    }

    /// Logs (at most every [`DROP_LOG_INTERVAL_US`]) that the kernel dropped events
    /// since the last call. Only reached after a `SYN_DROPPED`, never per event.
    fn note_dropped(&mut self, t: Micros) {
        let n = self.decoder.counters().dropped_sync;
        if n <= self.drops_seen {
            return;
        }
        self.drops_seen = n;
        if self
            .last_drop_log
            .is_some_and(|l| t.saturating_since(l).0 < DROP_LOG_INTERVAL_US)
        {
            return;
        }
        self.last_drop_log = Some(t);
        log::warn!(
            "{}: the kernel dropped input events (SYN_DROPPED, {n} time(s) since open): this \
             reader fell behind (system overloaded, or the daemon was stopped); touches \
             resynchronised from the device's slot state",
            self.info.identity.node.display()
        );
    }

    /// Queries the state and resyncs the decoder into `self.frame`; on a failed
    /// query (other than unplug) cancels every contact instead. Returns whether
    /// the frame holds contacts to deliver.
    fn query_and_resync(&mut self, t: Micros) -> Result<bool, Error> {
        if self.decoder.protocol() == MtProtocol::A {
            // Nothing to query: the next type-A frame lists every contact.
            return Ok(false);
        }
        match self.query_state() {
            Ok(()) => Ok(self.decoder.resync(t, &self.state, &mut self.frame)),
            Err(e) if e.raw_os_error() == Some(libc::ENODEV) => Err(Error::Unplugged {
                node: self.info.identity.node.clone(),
            }),
            Err(_) => {
                self.resync_failures += 1;
                Ok(self.decoder.cancel_all(t, &mut self.frame))
            }
        }
    }
}

impl DeviceReader for EvdevReader {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn run(&mut self, sink: &mut dyn FrameSink, stop: &AtomicBool) -> Result<(), Error> {
        if self.initial {
            self.initial = false;
            sink.push(&self.frame);
        }
        let node: PathBuf = self.info.identity.node.clone();
        while !stop.load(Ordering::Relaxed) {
            let timeout_ms = crate::input::reader_timeout_ms(sink);
            let n = wait_read(&self.dev, &node, &mut self.buf, timeout_ms)?;
            let mut at = 0;
            while at + INPUT_EVENT_BYTES <= n {
                let Some(ev) = parse_input_event(&self.buf[at..n]) else {
                    break;
                };
                at += INPUT_EVENT_BYTES;
                // A frame closed, or a dropped block ended and the resync
                // produced one.
                let ready = self.decoder.feed(&ev, &mut self.frame)
                    || (self.decoder.wants_resync() && {
                        self.note_dropped(ev.t);
                        self.query_and_resync(ev.t)?
                    });
                if ready {
                    sink.push(&self.frame);
                    if self.grab_pending {
                        self.grab_when_clear()?;
                    }
                }
            }
        }
        Ok(())
    }

    fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool {
        self.decoder.cancel_all(t, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::evdev::{EV_SYN, SYN_REPORT};

    fn raw(sec: i64, usec: i64, ty: u16, code: u16, value: i32) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(&(sec as libc::c_long).to_ne_bytes());
        b.extend_from_slice(&(usec as libc::c_long).to_ne_bytes());
        b.extend_from_slice(&ty.to_ne_bytes());
        b.extend_from_slice(&code.to_ne_bytes());
        b.extend_from_slice(&value.to_ne_bytes());
        b
    }

    #[test]
    fn parses_input_events() {
        #[cfg(target_pointer_width = "64")]
        assert_eq!(INPUT_EVENT_BYTES, 24);
        let mut bytes = raw(12, 345_678, EV_ABS, ABS_MT_TRACKING_ID, -1);
        bytes.extend(raw(12, 345_679, EV_SYN, SYN_REPORT, 0));
        bytes.extend_from_slice(&[1, 2, 3]); // partial trailing event
        let evs: Vec<RawEvent> = parse_input_events(&bytes).collect();
        assert_eq!(
            evs,
            vec![
                RawEvent {
                    t: Micros(12_345_678),
                    ev_type: EV_ABS,
                    code: ABS_MT_TRACKING_ID,
                    value: -1
                },
                RawEvent {
                    t: Micros(12_345_679),
                    ev_type: EV_SYN,
                    code: SYN_REPORT,
                    value: 0
                },
            ]
        );
        assert_eq!(parse_input_event(&bytes[..INPUT_EVENT_BYTES - 1]), None);
        assert_eq!(timeval_micros(-5, 10), Micros(0));
        assert_eq!(timeval_micros(i64::MAX, 0), Micros(u64::MAX));
    }

    #[test]
    fn single_touch_state_reads_btn_touch() {
        let mut keys = [0u8; sys::KEY_STATE_BYTES];
        let mut s = MtSlotState::new(0);
        single_touch_state(&keys, 5, 6, None, &mut s);
        assert_eq!((s.len(), s.slots()[0].tracking_id), (1, -1));
        keys[usize::from(BTN_TOUCH / 8)] |= 1 << (BTN_TOUCH % 8);
        single_touch_state(&keys, 5, 6, Some(7), &mut s);
        let v = s.slots()[0];
        assert_eq!((v.tracking_id, v.x, v.y, v.pressure), (0, 5, 6, Some(7)));
    }

    #[test]
    fn missing_or_non_evdev_nodes_are_classified() {
        let e = probe(Path::new("/nonexistent/event0")).unwrap_err();
        assert!(matches!(e, Error::NotFound { .. }), "{e}");
        let e = probe(Path::new("/dev/null")).unwrap_err();
        assert!(matches!(e, Error::NotTouch { .. }), "{e}");
        let e = EvdevReader::open(Path::new("/dev/null"), &EvdevOptions::default()).unwrap_err();
        assert!(matches!(e, Error::NotTouch { .. }), "{e}");
    }
}
