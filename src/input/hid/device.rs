//! hidraw touch devices through hidapi: a thin shell around [`HidDecoder`].
//!
//! [`HidReader::open`] opens a hidraw node by path, reads its report descriptor,
//! picks the first touch collection, reads the Contact Count Maximum feature,
//! switches the device to multi-touch reporting (Input Mode = 2, or 3 for
//! touchpads; Surface/Button Switch = 1) and then, as a
//! [`DeviceReader`], reads reports with a timeout of [`STOP_CHECK_US`], decodes
//! them and hands complete frames on.
//!
//! # Timestamps
//!
//! hidraw delivers bare report bytes: unlike evdev there is no kernel event time.
//! Each report is stamped with [`monotonic_now`] (CLOCK_MONOTONIC) when `read`
//! returns, so frame times include the wake-up latency of the input thread (tens
//! of µs on an idle real-time thread, more under load), and a hybrid frame carries
//! the time of its last report.
//!
//! # Errors
//!
//! Open errors are classified from the `io::Error` of a plain `open(2)` of the
//! node (done first, with [`input::Error::from_io`](crate::input::Error::from_io)):
//! missing node, permission, busy. hidapi reports its own failures as text; those
//! become [`Error::Io`] naming the node and the operation. A vanished device (read
//! error `ENODEV`, or `POLLHUP`/`POLLERR`, which hidapi reports as "device
//! disconnected") is [`Error::Unplugged`].
//!
//! This machine has no hidraw node; this shell is exercised in a VM later. Its
//! logic (uevent parsing, feature reports, error mapping) is in pure functions
//! tested here.

use super::descriptor::{touch_collections, Application, FeatureSetting, TouchCollection};
use super::report::HidDecoder;
use crate::input::{
    DeviceIdentity, DeviceInfo, DeviceKind, DeviceReader, Error, FrameSink, STOP_CHECK_US,
};
use crate::rt::monotonic_now;
use crate::vocab::Micros;
use crate::vocab::TouchFrame;
use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Read buffer size: the kernel's largest HID report (`HID_MAX_BUFFER_SIZE`).
const READ_BUFFER_BYTES: usize = 16_384;
/// Largest report descriptor read from a device.
const DESCRIPTOR_BUFFER_BYTES: usize = super::descriptor::MAX_DESCRIPTOR_BYTES;
/// Linux bus numbers (`BUS_*` in `linux/input.h`).
const BUS_USB: u16 = 0x03;
const BUS_BLUETOOTH: u16 = 0x05;
const BUS_I2C: u16 = 0x18;
const BUS_SPI: u16 = 0x1C;

/// Options for [`HidReader::open`] (none yet; room for later ones, e.g. which
/// touch collection to read, or not switching the input mode).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HidOptions {}

/// What a hidraw node's `device/uevent` says.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HidUevent {
    /// Bus (`HID_ID` first field).
    pub bus: u16,
    /// Vendor id.
    pub vendor: u16,
    /// Product id.
    pub product: u16,
    /// `HID_NAME`.
    pub name: String,
    /// `HID_UNIQ` (serial or unique name), when not empty.
    pub uniq: Option<String>,
}

/// Parses a HID device's `uevent` text (`HID_ID=0003:00002101:00001011`,
/// `HID_NAME=…`, `HID_UNIQ=…`); `None` without a valid `HID_ID`.
pub fn parse_hid_uevent(text: &str) -> Option<HidUevent> {
    let mut out = HidUevent::default();
    let mut have_id = false;
    for line in text.lines() {
        let Some((k, v)) = line.split_once('=') else {
            continue;
        };
        match k.trim() {
            "HID_ID" => {
                let mut it = v.trim().split(':');
                let mut next = || u32::from_str_radix(it.next()?, 16).ok();
                let (bus, vendor, product) = (next()?, next()?, next()?);
                out.bus = u16::try_from(bus).ok()?;
                out.vendor = u16::try_from(vendor).ok()?;
                out.product = u16::try_from(product).ok()?;
                have_id = true;
            }
            "HID_NAME" => out.name = v.trim().to_string(),
            "HID_UNIQ" => out.uniq = Some(v.trim().to_string()).filter(|s| !s.is_empty()),
            _ => {}
        }
    }
    have_id.then_some(out)
}

/// The sysfs directory of a hidraw node (`/sys/class/hidraw/hidrawN`).
fn sysfs_dir(node: &Path) -> Result<PathBuf, Error> {
    let real = std::fs::canonicalize(node).map_err(|e| Error::from_io(node, "resolve", e))?;
    let name = real.file_name().ok_or_else(|| Error::NotFound {
        node: node.to_path_buf(),
    })?;
    Ok(Path::new("/sys/class/hidraw").join(name))
}

/// Builds the [`DeviceInfo`] of a touch device from what sysfs or hidapi tell.
///
/// # Errors
/// [`Error::NotTouch`] when the descriptor has no touch collection this crate reads.
pub fn device_info(
    node: &Path,
    uevent: &HidUevent,
    descriptor: &[u8],
) -> Result<(DeviceInfo, TouchCollection), Error> {
    let mut collections = touch_collections(descriptor).map_err(|e| Error::NotTouch {
        node: node.to_path_buf(),
        reason: e.reason,
    })?;
    let tc = collections.remove(0);
    let name = if uevent.name.is_empty() {
        format!("HID {:04x}:{:04x}", uevent.vendor, uevent.product)
    } else {
        uevent.name.clone()
    };
    let surface = tc.surface(&name);
    let info = DeviceInfo {
        identity: DeviceIdentity {
            kind: DeviceKind::Hidraw,
            node: node.to_path_buf(),
            name,
            bus: uevent.bus,
            vendor: uevent.vendor,
            product: uevent.product,
            serial: uevent.uniq.clone(),
        },
        id_path: None,
        stable_id: DeviceInfo::make_stable_id(
            None,
            uevent.vendor,
            uevent.product,
            uevent.uniq.as_deref(),
        ),
        surface,
        direct: tc.application == Application::TouchScreen,
        calibration: None,
    };
    Ok((info, tc))
}

/// Reads a hidraw node's identity and descriptor from sysfs.
fn probe_full(node: &Path) -> Result<(DeviceInfo, TouchCollection), Error> {
    std::fs::metadata(node).map_err(|e| Error::from_io(node, "stat", e))?;
    let dir = sysfs_dir(node)?;
    let uevent = std::fs::read_to_string(dir.join("device/uevent"))
        .map_err(|e| Error::from_io(node, "read sysfs uevent", e))?;
    let uevent = parse_hid_uevent(&uevent).ok_or_else(|| Error::NotTouch {
        node: node.to_path_buf(),
        reason: "not a HID device (no HID_ID in its sysfs uevent)".into(),
    })?;
    let descriptor = std::fs::read(dir.join("device/report_descriptor"))
        .map_err(|e| Error::from_io(node, "read sysfs report_descriptor", e))?;
    device_info(node, &uevent, &descriptor)
}

/// What a hidraw node is, from sysfs (no need to open it).
///
/// # Errors
/// [`Error::NotFound`] for a missing node, [`Error::NotTouch`] when it is not a
/// touch device this crate reads, other variants for sysfs read failures.
pub fn probe(node: &Path) -> Result<DeviceInfo, Error> {
    probe_full(node).map(|(info, _)| info)
}

/// Linux bus number of a hidapi bus type.
fn bus_number(b: hidapi::BusType) -> u16 {
    match b {
        hidapi::BusType::Usb => BUS_USB,
        hidapi::BusType::Bluetooth => BUS_BLUETOOTH,
        hidapi::BusType::I2c => BUS_I2C,
        hidapi::BusType::Spi => BUS_SPI,
        hidapi::BusType::Unknown => 0,
    }
}

/// The hidraw nodes with a touch collection, from hidapi's enumeration (one entry
/// per node; hidapi lists a node once per top-level usage). Nodes that cannot be
/// probed are left out (logged at debug level); an enumeration failure gives an
/// empty list (logged as a warning).
pub fn enumerate() -> Vec<DeviceInfo> {
    let api = match hidapi::HidApi::new() {
        Ok(api) => api,
        Err(e) => {
            log::warn!("hidraw enumeration failed: {e}");
            return Vec::new();
        }
    };
    let mut out: Vec<DeviceInfo> = Vec::new();
    for d in api.device_list() {
        let Ok(path) = d.path().to_str() else {
            continue;
        };
        let node = PathBuf::from(path);
        if out.iter().any(|i| i.identity.node == node) {
            continue;
        }
        match probe(&node) {
            Ok(mut info) => {
                // hidapi's strings where sysfs had none.
                if info.identity.serial.is_none() {
                    info.identity.serial = d
                        .serial_number()
                        .filter(|s| !s.is_empty())
                        .map(str::to_string);
                    info.stable_id = DeviceInfo::make_stable_id(
                        None,
                        info.identity.vendor,
                        info.identity.product,
                        info.identity.serial.as_deref(),
                    );
                }
                if info.identity.bus == 0 {
                    info.identity.bus = bus_number(d.bus_type());
                }
                out.push(info);
            }
            Err(Error::NotTouch { .. }) => {}
            Err(e) => log::debug!("hidraw: skipping {}: {e}", node.display()),
        }
    }
    out
}

/// Maps a hidapi error to an [`Error`] naming the node.
fn hid_error(node: &Path, op: &'static str, e: hidapi::HidError) -> Error {
    match e {
        hidapi::HidError::IoError { error } => Error::from_io(node, op, error),
        hidapi::HidError::HidApiError { message } if message.contains("disconnected") => {
            Error::Unplugged {
                node: node.to_path_buf(),
            }
        }
        other => Error::Io {
            node: node.to_path_buf(),
            op,
            source: std::io::Error::other(other.to_string()),
        },
    }
}

/// The feature report buffer for a setting: hidapi's convention puts the report ID
/// (or 0 when the descriptor has none) in byte 0. Returns the buffer and the bit
/// offset of the report data in it.
fn feature_buffer(s: &FeatureSetting) -> (Vec<u8>, usize) {
    match s.field.report_id {
        Some(id) => {
            let mut b = vec![0u8; s.report_bytes.max(s.field.end_byte())];
            b[0] = id;
            (b, 0)
        }
        None => (vec![0u8; 1 + s.report_bytes.max(s.field.end_byte())], 1),
    }
}

/// Writes one feature setting: GET_FEATURE (so other fields keep their values;
/// zeros if that fails), set the field, SET_FEATURE.
fn apply_setting(dev: &hidapi::HidDevice, node: &Path, s: &FeatureSetting) -> Result<(), Error> {
    let (mut buf, data_at) = feature_buffer(s);
    if dev.get_feature_report(&mut buf).is_err() {
        let id = buf[0];
        buf.fill(0);
        buf[0] = id;
    }
    s.apply(&mut buf[data_at..]);
    dev.send_feature_report(&buf)
        .map_err(|e| hid_error(node, "set feature report", e))
}

/// Reads the Contact Count Maximum feature from the device.
fn read_contact_max(dev: &hidapi::HidDevice, tc: &TouchCollection) -> Option<u32> {
    let f = tc.contact_count_max?;
    let s = FeatureSetting {
        field: f,
        report_bytes: tc.contact_count_max_report_bytes,
        value: 0,
    };
    let (mut buf, data_at) = feature_buffer(&s);
    let n = dev.get_feature_report(&mut buf).ok()?;
    let v = f.extract_raw(buf.get(data_at..n.max(data_at))?)?;
    (v > 0).then_some(v)
}

/// An open hidraw touch device.
pub struct HidReader {
    info: DeviceInfo,
    device: hidapi::HidDevice,
    decoder: HidDecoder,
    buf: Vec<u8>,
    frame: TouchFrame,
}

impl std::fmt::Debug for HidReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HidReader")
            .field("info", &self.info)
            .field("decoder", &self.decoder.counters())
            .finish()
    }
}

impl HidReader {
    /// Opens a hidraw node, builds the decoder and switches the device to
    /// multi-touch reporting (see the [module docs](crate::input::hid)).
    ///
    /// # Errors
    /// [`Error::NotFound`], [`Error::PermissionDenied`], [`Error::Busy`] from the
    /// open; [`Error::NotTouch`] when the descriptor has no touch collection;
    /// [`Error::Io`] for hidapi failures. A failed Input Mode write is logged, not
    /// fatal (many devices report multi-touch without it).
    pub fn open(node: &Path, _options: &HidOptions) -> Result<HidReader, Error> {
        // A plain open first: its io::Error tells missing node, permission, busy.
        drop(
            std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(node)
                .map_err(|e| Error::from_io(node, "open", e))?,
        );
        let (mut info, _) = probe_full(node)?;
        let path = node
            .to_str()
            .and_then(|s| CString::new(s).ok())
            .ok_or_else(|| Error::Io {
                node: node.to_path_buf(),
                op: "open",
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "hidapi needs a UTF-8 path without NUL",
                ),
            })?;
        let api = hidapi::HidApi::new().map_err(|e| hid_error(node, "initialise hidapi", e))?;
        let device = api
            .open_path(&path)
            .map_err(|e| hid_error(node, "open", e))?;
        let mut rdesc = vec![0u8; DESCRIPTOR_BUFFER_BYTES];
        let n = device
            .get_report_descriptor(&mut rdesc)
            .map_err(|e| hid_error(node, "read report descriptor", e))?;
        rdesc.truncate(n);
        let uevent = HidUevent {
            bus: info.identity.bus,
            vendor: info.identity.vendor,
            product: info.identity.product,
            name: info.identity.name.clone(),
            uniq: info.identity.serial.clone(),
        };
        let (fresh, tc) = device_info(node, &uevent, &rdesc)?;
        info.surface = fresh.surface;
        info.direct = fresh.direct;
        let mut decoder = HidDecoder::new(&tc);
        if let Some(max) = read_contact_max(&device, &tc) {
            decoder.set_max_contacts(max);
            info.surface.max_contacts = decoder.max_contacts();
        }
        for s in tc.input_mode.iter().chain(tc.switches.iter()) {
            if let Err(e) = apply_setting(&device, node, s) {
                log::warn!(
                    "{}: could not switch to multi-touch reporting (feature report {:?}): {e}",
                    node.display(),
                    s.field.report_id
                );
            }
        }
        Ok(HidReader {
            info,
            device,
            decoder,
            buf: vec![0u8; READ_BUFFER_BYTES],
            frame: TouchFrame::default(),
        })
    }

    /// The decoder (counters, contacts down).
    pub fn decoder(&self) -> &HidDecoder {
        &self.decoder
    }
}

impl DeviceReader for HidReader {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn run(&mut self, sink: &mut dyn FrameSink, stop: &AtomicBool) -> Result<(), Error> {
        while !stop.load(Ordering::Relaxed) {
            let timeout_ms = i32::from(crate::input::reader_timeout_ms(sink));
            let n = self
                .device
                .read_timeout(&mut self.buf, timeout_ms)
                .map_err(|e| hid_error(&self.info.identity.node, "read", e))?;
            if n == 0 {
                continue;
            }
            let t = monotonic_now();
            let bytes = &self.buf[..n.min(self.buf.len())];
            if self.decoder.report(t, bytes, &mut self.frame) {
                sink.push(&self.frame);
            }
        }
        Ok(())
    }

    fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool {
        self.decoder.cancel_all(t, out)
    }
}

/// Records the raw input reports of the hidraw node `node` into `w` as a
/// hid-recorder log (descriptor and identity from sysfs, then one `E:` line per
/// report, stamped with CLOCK_MONOTONIC when read), until `stop` is set (checked
/// at least every [`STOP_CHECK_US`]). The device is not switched to multi-touch
/// mode: the log shows what it sends as it is. Returns the number of reports.
///
/// Any hidraw node can be recorded, touch or not, so that a device this crate
/// does not read can still be sent in a bug report.
///
/// # Errors
/// [`Error::from_io`] of the sysfs reads and the open; [`Error::Unplugged`] when
/// the device goes away; [`Error::Io`] (op `"write recording"`) when `w` fails.
pub fn record_hidraw(node: &Path, w: impl std::io::Write, stop: &AtomicBool) -> Result<u64, Error> {
    use nix::errno::Errno;
    use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
    use std::io::Read;
    use std::os::fd::AsFd;
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::metadata(node).map_err(|e| Error::from_io(node, "stat", e))?;
    let dir = sysfs_dir(node)?;
    let uevent = std::fs::read_to_string(dir.join("device/uevent"))
        .map_err(|e| Error::from_io(node, "read sysfs uevent", e))?;
    let uevent = parse_hid_uevent(&uevent).unwrap_or_default();
    let descriptor = std::fs::read(dir.join("device/report_descriptor"))
        .map_err(|e| Error::from_io(node, "read sysfs report_descriptor", e))?;
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_CLOEXEC)
        .open(node)
        .map_err(|e| Error::from_io(node, "open", e))?;
    let werr = |source| Error::Io {
        node: node.to_path_buf(),
        op: "write recording",
        source,
    };
    let mut out = crate::input::recording::HidRecorderWriter::new(
        w,
        &descriptor,
        &uevent.name,
        uevent.bus,
        uevent.vendor,
        uevent.product,
    )
    .map_err(werr)?;
    out.flush().map_err(werr)?;
    let mut buf = vec![0u8; READ_BUFFER_BYTES];
    let timeout = PollTimeout::from(u16::try_from(STOP_CHECK_US / 1000).unwrap_or(u16::MAX));
    while !stop.load(Ordering::Relaxed) {
        let ready = {
            let mut fds = [PollFd::new(file.as_fd(), PollFlags::POLLIN)];
            match poll(&mut fds, timeout) {
                Ok(0) | Err(Errno::EINTR) => false,
                Ok(_) => {
                    let r = fds[0].revents().unwrap_or(PollFlags::empty());
                    if r.intersects(PollFlags::POLLHUP | PollFlags::POLLERR)
                        && !r.contains(PollFlags::POLLIN)
                    {
                        return Err(Error::Unplugged {
                            node: node.to_path_buf(),
                        });
                    }
                    true
                }
                Err(e) => return Err(Error::from_io(node, "poll", std::io::Error::from(e))),
            }
        };
        if !ready {
            continue;
        }
        // One report per read; drain what is queued.
        loop {
            match file.read(&mut buf) {
                Ok(0) => {
                    return Err(Error::Unplugged {
                        node: node.to_path_buf(),
                    })
                }
                Ok(n) => {
                    let t = monotonic_now().0;
                    out.report(t, &buf[..n]).map_err(werr)?;
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::from_io(node, "read", e)),
            }
        }
        out.flush().map_err(werr)?;
    }
    out.flush().map_err(werr)?;
    Ok(out.reports())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uevent() {
        let text = "DRIVER=hid-multitouch\nHID_ID=0003:00002101:00001011\nHID_NAME=ActionStar Touch\n\
                    HID_PHYS=usb-0000:00:14.0-2/input0\nHID_UNIQ=\nMODALIAS=hid:b0003g0004v00002101p00001011\n";
        let u = parse_hid_uevent(text).unwrap();
        assert_eq!((u.bus, u.vendor, u.product), (3, 0x2101, 0x1011));
        assert_eq!(u.name, "ActionStar Touch");
        assert_eq!(u.uniq, None);
        assert!(parse_hid_uevent("HID_NAME=x\n").is_none());
        assert!(parse_hid_uevent("HID_ID=zz:1:2\n").is_none());
        let u = parse_hid_uevent("HID_ID=0018:000027C6:00000E30\nHID_UNIQ=abc\n").unwrap();
        assert_eq!((u.bus, u.uniq.as_deref()), (0x18, Some("abc")));
    }

    #[test]
    fn error_mapping() {
        let node = Path::new("/dev/hidraw9");
        let e = hid_error(
            node,
            "read",
            hidapi::HidError::IoError {
                error: std::io::Error::from_raw_os_error(nix::libc::ENODEV),
            },
        );
        assert!(matches!(e, Error::Unplugged { .. }), "{e}");
        let e = hid_error(
            node,
            "read",
            hidapi::HidError::HidApiError {
                message: "unexpected poll error (device disconnected)".into(),
            },
        );
        assert!(matches!(e, Error::Unplugged { .. }), "{e}");
        let e = hid_error(
            node,
            "open",
            hidapi::HidError::HidApiError {
                message: "boom".into(),
            },
        );
        assert!(matches!(e, Error::Io { op: "open", .. }) && e.to_string().contains("hidraw9"));
        let e =
            HidReader::open(Path::new("/nonexistent/hidraw0"), &HidOptions::default()).unwrap_err();
        assert!(matches!(e, Error::NotFound { .. }), "{e}");
        assert!(matches!(
            probe(Path::new("/nonexistent/hidraw0")),
            Err(Error::NotFound { .. })
        ));
    }

    #[test]
    fn feature_buffers_follow_hidapi_convention() {
        let field = crate::input::hid::HidField {
            usage_page: 0x0D,
            usage: 0x52,
            report_id: Some(0x11),
            bit_offset: 8,
            bit_size: 8,
            logical_min: 0,
            logical_max: 10,
            physical_min: 0,
            physical_max: 0,
            unit: 0,
            unit_exponent: 0,
            signed: false,
        };
        let s = FeatureSetting {
            field,
            report_bytes: 3,
            value: 2,
        };
        let (mut b, at) = feature_buffer(&s);
        assert_eq!((b.len(), at, b[0]), (3, 0, 0x11));
        assert!(s.apply(&mut b[at..]));
        assert_eq!(b, vec![0x11, 2, 0]);
        let no_id = FeatureSetting {
            field: crate::input::hid::HidField {
                report_id: None,
                bit_offset: 0,
                ..field
            },
            report_bytes: 2,
            value: 3,
        };
        let (mut b, at) = feature_buffer(&no_id);
        assert_eq!((b.len(), at), (3, 1));
        assert!(no_id.apply(&mut b[at..]));
        assert_eq!(b, vec![0, 3, 0]);
    }
}
