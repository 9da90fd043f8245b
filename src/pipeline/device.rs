//! Device supervision: find the configured touch device, read it on the input
//! thread, and when it goes away cancel its touches, say so, and wait for it to come
//! back — without a polling loop.
//!
//! ```text
//!            found + opened                     device error (ENODEV)
//!  ┌───────────┐ ───────────► ┌─────────┐ ──────────────────────────► ┌───────────┐
//!  │ Searching │              │ Reading │                             │ Unplugged │
//!  └───────────┘ ◄─────────── └─────────┘ ◄──────────────────────────┐ └───────────┘
//!     ▲     │   open failed (EACCES, EBUSY, not touch)               │      │
//!     │     ▼                                                        │      │ hotplug
//!  ┌────────┐  hotplug activity                                      │      ▼
//!  │ Failed │ ─────────────────► Searching ──── found (same stable id) ─────┘
//!  └────────┘
//! ```
//! Every transition that users care about is published as a `device` event
//! (`attached`, `unplugged`, `failed`). The supervisor is generic over a
//! [`DeviceEnv`], so the state machine is tested with a scripted environment; the
//! real one ([`SystemEnv`]) uses discovery, inotify and the evdev/hidraw readers.

use crate::config::{DeviceInterface, DeviceSelect};
use crate::input::{DeviceInfo, DeviceReader, FrameSink};
use crate::rt::monotonic_now;
use crate::vocab::DeviceState;
use crate::vocab::Micros;
use crate::vocab::TouchFrame;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How long the supervisor waits for hotplug activity before looking again anyway
/// (a safety net for missed notifications; not a polling loop — one scan per period).
pub const RESCAN_PERIOD: Duration = Duration::from_secs(5);

/// States of the supervisor.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum SupervisorState {
    /// Looking for the device.
    Searching,
    /// Reading frames.
    Reading,
    /// The device went away; waiting for it.
    Unplugged,
    /// It could not be opened; waiting for a change.
    Failed,
    /// Stopped.
    Stopped,
}

impl SupervisorState {
    /// Name for logs.
    pub fn as_str(self) -> &'static str {
        match self {
            SupervisorState::Searching => "searching",
            SupervisorState::Reading => "reading",
            SupervisorState::Unplugged => "unplugged",
            SupervisorState::Failed => "failed",
            SupervisorState::Stopped => "stopped",
        }
    }
}

/// What the supervisor needs from the system.
pub trait DeviceEnv {
    /// Finds the device `sel` names (or, after an unplug, the one with `stable_id`),
    /// ready to open. `Err` says what was found instead.
    fn find(
        &mut self,
        sel: &DeviceSelect,
        pref: DeviceInterface,
        stable_id: Option<&str>,
    ) -> Result<DeviceInfo, String>;
    /// Opens it for reading.
    ///
    /// # Errors
    /// Why it cannot be read.
    fn open(&mut self, info: &DeviceInfo) -> Result<Box<dyn DeviceReader>, crate::input::Error>;
    /// Blocks until device nodes change (or `timeout`, or `stop`).
    fn wait_change(&mut self, timeout: Duration, stop: &AtomicBool);
}

/// Where a device's frames go: a [`FrameSink`] told which device is attached (so it
/// can apply that device's calibration and size).
pub trait DeviceSink: FrameSink {
    /// The device now being read.
    fn attach(&mut self, info: &DeviceInfo);
}

impl DeviceSink for Vec<TouchFrame> {
    fn attach(&mut self, _: &DeviceInfo) {}
}

/// How a device's frames are corrected before they join the table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TransformSettings {
    /// Rotation, flips and matrix from the config.
    pub calibration: crate::config::CalibrationConfig,
    /// The part of the table the device covers (table units).
    pub region: Option<crate::geom::Rect>,
    /// Largest finger contact (mm).
    pub palm_max_mm: Option<f64>,
    /// Surface size (mm) when the device reports no resolution.
    pub size_mm: Option<(f64, f64)>,
}

/// The input-queue sink of a device: applies its calibration, region and palm
/// threshold, then queues the frame. Allocation-free per frame.
pub struct TransformSink {
    queue: super::FrameQueue,
    settings: TransformSettings,
    transform: Option<crate::input::calibrate::DeviceTransform>,
}

impl TransformSink {
    /// A sink feeding `queue`.
    pub fn new(queue: super::FrameQueue, settings: TransformSettings) -> TransformSink {
        TransformSink {
            queue,
            settings,
            transform: None,
        }
    }

    /// A sink for a source with no device behind it (TUIO): the settings'
    /// calibration and region apply from the first frame.
    pub fn fixed(
        queue: super::FrameQueue,
        settings: TransformSettings,
        who: &str,
    ) -> TransformSink {
        let t = transform_of(&settings, None, settings.size_mm, who);
        TransformSink {
            queue,
            settings,
            transform: Some(t),
        }
    }

    /// The queue (to flush it at the end).
    pub fn queue(&mut self) -> &mut super::FrameQueue {
        &mut self.queue
    }
}

impl FrameSink for TransformSink {
    fn push(&mut self, frame: &TouchFrame) {
        match &self.transform {
            Some(t) => {
                let mut f = *frame;
                t.apply(&mut f);
                self.queue.push(&f);
            }
            None => self.queue.push(frame),
        }
    }

    fn flush(&mut self) -> bool {
        self.queue.flush()
    }
}

impl DeviceSink for TransformSink {
    fn attach(&mut self, info: &DeviceInfo) {
        self.transform = Some(build_transform(&self.settings, info));
    }
}

/// The transform for a device: the config's calibration (or udev's matrix), its
/// region, its physical size for contact sizes, and the palm threshold.
pub fn build_transform(
    s: &TransformSettings,
    info: &DeviceInfo,
) -> crate::input::calibrate::DeviceTransform {
    let size = info.surface.size_mm().or(s.size_mm);
    let node = info.identity.node.display().to_string();
    transform_of(s, info.calibration, size, &node)
}

/// The transform of `s` with udev's matrix `udev` and the glass `size` (mm); a
/// failure is logged naming `who`.
fn transform_of(
    s: &TransformSettings,
    udev: Option<[f64; 6]>,
    size: Option<(f64, f64)>,
    who: &str,
) -> crate::input::calibrate::DeviceTransform {
    use crate::input::calibrate::{Calibration, DeviceTransform, Region};
    let c = &s.calibration;
    let cal = Calibration {
        rotation: c.rotation,
        flip_x: c.flip_x,
        flip_y: c.flip_y,
        matrix: c.matrix,
    };
    let region = s
        .region
        .map(|r| Region {
            x: r.min[0],
            y: r.min[1],
            width: r.width(),
            height: r.height(),
        })
        .unwrap_or_default();
    match DeviceTransform::new(&cal, udev, region, size, s.palm_max_mm) {
        Ok(t) => t,
        Err(e) => {
            // The config was validated; a bad udev matrix is the likely cause.
            log::error!("{who}: calibration not applied: {e}");
            DeviceTransform::identity()
        }
    }
}

/// A device event for the publisher.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceNotice {
    /// State reached.
    pub state: DeviceState,
    /// The device (or a placeholder while none was found).
    pub info: Option<DeviceInfo>,
    /// Why.
    pub message: Option<String>,
    /// When.
    pub t: Micros,
}

/// Runs one `Device` input until `stop`: the body of its input thread.
///
/// Frames go to `sink`; on every unplug or stop a frame cancelling the device's
/// touches follows, so nothing stays down. `notify` receives device events.
pub fn supervise(
    env: &mut dyn DeviceEnv,
    sel: &DeviceSelect,
    pref: DeviceInterface,
    sink: &mut dyn DeviceSink,
    stop: &AtomicBool,
    notify: &mut dyn FnMut(DeviceNotice),
) {
    let mut state = SupervisorState::Searching;
    let mut known: Option<DeviceInfo> = None;
    let mut last_failure: Option<String> = None;
    let mut frame = TouchFrame::default();
    while !stop.load(Ordering::Relaxed) {
        state = match state {
            SupervisorState::Searching => {
                let stable = known.as_ref().map(|k| k.stable_id.as_str());
                match env.find(sel, pref, stable) {
                    Err(why) => {
                        if last_failure.as_deref() != Some(why.as_str()) {
                            log::warn!("no touch device yet: {why}; waiting for one to appear");
                            notify(DeviceNotice {
                                state: DeviceState::Failed,
                                info: known.clone(),
                                message: Some(why.clone()),
                                t: monotonic_now(),
                            });
                            last_failure = Some(why);
                        }
                        SupervisorState::Failed
                    }
                    Ok(info) => match env.open(&info) {
                        Err(e) => {
                            let why = e.to_string();
                            if last_failure.as_deref() != Some(why.as_str()) {
                                log::error!("{why}");
                                notify(DeviceNotice {
                                    state: DeviceState::Failed,
                                    info: Some(info.clone()),
                                    message: Some(why.clone()),
                                    t: monotonic_now(),
                                });
                                last_failure = Some(why);
                            }
                            known = Some(info);
                            SupervisorState::Failed
                        }
                        Ok(mut reader) => {
                            last_failure = None;
                            log::info!(
                                "reading {} ({} {}, {:04x}:{:04x}, id {})",
                                info.identity.name,
                                info.identity.kind.as_str(),
                                info.identity.node.display(),
                                info.identity.vendor,
                                info.identity.product,
                                info.stable_id
                            );
                            notify(DeviceNotice {
                                state: DeviceState::Attached,
                                info: Some(info.clone()),
                                message: None,
                                t: monotonic_now(),
                            });
                            known = Some(info.clone());
                            sink.attach(&info);
                            let result = reader.run(sink, stop);
                            // Whatever ended the read, no touch stays down.
                            if reader.cancel_all(monotonic_now(), &mut frame) {
                                sink.push(&frame);
                            }
                            match result {
                                Ok(()) => SupervisorState::Stopped,
                                Err(e) => {
                                    let unplugged =
                                        matches!(e, crate::input::Error::Unplugged { .. });
                                    log::warn!("{e}; its touches were cancelled, waiting for it to come back");
                                    notify(DeviceNotice {
                                        state: if unplugged {
                                            DeviceState::Unplugged
                                        } else {
                                            DeviceState::Failed
                                        },
                                        info: Some(info),
                                        message: Some(e.to_string()),
                                        t: monotonic_now(),
                                    });
                                    SupervisorState::Unplugged
                                }
                            }
                        }
                    },
                }
            }
            SupervisorState::Failed | SupervisorState::Unplugged => {
                env.wait_change(RESCAN_PERIOD, stop);
                SupervisorState::Searching
            }
            SupervisorState::Reading | SupervisorState::Stopped => break,
        };
        if state == SupervisorState::Stopped {
            break;
        }
    }
}

/// The real environment: discovery over `/dev` and `/sys`, the udev database,
/// inotify for hotplug, and the evdev / hidraw readers.
pub struct SystemEnv {
    root: std::path::PathBuf,
    udev: crate::input::udev::UdevDb,
    watcher: Option<crate::input::hotplug::Watcher>,
    grab: bool,
}

/// Longest wait for udev to finish with a new node (and for its permissions).
pub const READY_TIMEOUT: Duration = Duration::from_secs(3);

impl SystemEnv {
    /// An environment rooted at `/` (tests and the HIL guest may use another root).
    pub fn new(root: &std::path::Path, grab: bool) -> SystemEnv {
        let watcher = match crate::input::hotplug::Watcher::new(root) {
            Ok(w) => Some(w),
            Err(e) => {
                log::warn!("cannot watch for touch devices coming and going ({e}); rescanning every {} s instead", RESCAN_PERIOD.as_secs());
                None
            }
        };
        SystemEnv {
            root: root.to_path_buf(),
            udev: crate::input::udev::UdevDb::new(root),
            watcher,
            grab,
        }
    }
}

/// Probes nodes with the evdev and hidraw readers.
pub struct SystemProber;

impl crate::input::discover::Prober for SystemProber {
    fn probe(
        &self,
        kind: crate::input::DeviceKind,
        node: &std::path::Path,
    ) -> Result<DeviceInfo, crate::input::Error> {
        match kind {
            crate::input::DeviceKind::Evdev => crate::input::evdev::probe(node),
            crate::input::DeviceKind::Hidraw => crate::input::hid::probe(node),
        }
    }
}

/// The discovery selector for a configured selection.
pub fn selector(sel: &DeviceSelect) -> crate::input::discover::Selector {
    use crate::input::discover::Selector;
    match sel {
        DeviceSelect::Auto => Selector::Auto,
        DeviceSelect::Name(n) => Selector::Name(n.clone()),
        DeviceSelect::VendorProduct(vp) => Selector::VendorProduct(vp.clone()),
        DeviceSelect::Path(p) => Selector::Path(p.clone()),
        DeviceSelect::Id(i) => Selector::Id(i.clone()),
    }
}

/// The discovery interface preference for a configured interface.
pub fn preference(i: DeviceInterface) -> crate::input::discover::InterfacePreference {
    use crate::input::discover::InterfacePreference;
    match i {
        DeviceInterface::Any => InterfacePreference::Any,
        DeviceInterface::Evdev => InterfacePreference::Evdev,
        DeviceInterface::Hidraw => InterfacePreference::Hidraw,
    }
}

impl DeviceEnv for SystemEnv {
    fn find(
        &mut self,
        sel: &DeviceSelect,
        pref: DeviceInterface,
        stable_id: Option<&str>,
    ) -> Result<DeviceInfo, String> {
        let found = crate::input::discover::discover(&self.root, &SystemProber);
        // Once attached, follow the physical device (not the node number) — unless
        // the config names a node.
        let sel = match (sel, stable_id) {
            (DeviceSelect::Path(_), _) | (_, None) => selector(sel),
            (_, Some(id)) => crate::input::discover::Selector::Id(id.to_string()),
        };
        let f = crate::input::discover::select(&found, &sel, preference(pref))
            .map_err(|e| e.to_string())?;
        if let Some(e) = &f.probe_error {
            return Err(e.clone());
        }
        if let Some(w) = &mut self.watcher {
            w.wait_ready(&f.info.identity.node, &self.udev, READY_TIMEOUT)
                .map_err(|e| e.to_string())?;
        }
        Ok(f.info.clone())
    }

    fn open(&mut self, info: &DeviceInfo) -> Result<Box<dyn DeviceReader>, crate::input::Error> {
        match info.identity.kind {
            crate::input::DeviceKind::Evdev => crate::input::evdev::EvdevReader::open(
                &info.identity.node,
                &crate::input::evdev::EvdevOptions { grab: self.grab },
            )
            .map(|r| Box::new(r) as Box<dyn DeviceReader>),
            crate::input::DeviceKind::Hidraw => crate::input::hid::HidReader::open(
                &info.identity.node,
                &crate::input::hid::HidOptions {},
            )
            .map(|r| Box::new(r) as Box<dyn DeviceReader>),
        }
    }

    fn wait_change(&mut self, timeout: Duration, stop: &AtomicBool) {
        let end = std::time::Instant::now() + timeout;
        let step = Duration::from_micros(crate::input::STOP_CHECK_US);
        while !stop.load(Ordering::Relaxed) {
            let left = end.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return;
            }
            match &mut self.watcher {
                Some(w) => match w.next(left.min(step)) {
                    Ok(Some(_)) => return,
                    Ok(None) => {}
                    Err(e) => {
                        log::warn!("hotplug watch failed ({e}); rescanning on a timer");
                        self.watcher = None;
                    }
                },
                None => std::thread::sleep(left.min(step)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::{AxisRange, DeviceIdentity, DeviceKind, SurfaceInfo};
    use crate::vocab::{Contact, ContactFlags, ContactId};
    use std::collections::VecDeque;
    use std::path::PathBuf;
    use std::sync::Arc;

    fn info(node: &str) -> DeviceInfo {
        DeviceInfo {
            identity: DeviceIdentity {
                kind: DeviceKind::Evdev,
                node: PathBuf::from(node),
                name: "Test Table".into(),
                bus: 3,
                vendor: 0x2575,
                product: 0x0204,
                serial: None,
            },
            id_path: Some("pci-0000:00:14.0-usb-0:2:1.0".into()),
            stable_id: "pci-0000:00:14.0-usb-0:2:1.0".into(),
            surface: SurfaceInfo {
                name: "Test Table".into(),
                x: AxisRange {
                    min: 0.0,
                    max: 32767.0,
                    resolution: 55.0,
                },
                y: AxisRange {
                    min: 0.0,
                    max: 32767.0,
                    resolution: 98.0,
                },
                max_contacts: 10,
            },
            direct: true,
            calibration: None,
        }
    }

    /// A reader that plays frames, then fails (or waits for stop).
    struct Scripted {
        info: DeviceInfo,
        frames: Vec<TouchFrame>,
        then: Option<crate::input::Error>,
        down: Vec<ContactId>,
    }

    impl DeviceReader for Scripted {
        fn info(&self) -> &DeviceInfo {
            &self.info
        }
        fn run(
            &mut self,
            sink: &mut dyn FrameSink,
            stop: &AtomicBool,
        ) -> Result<(), crate::input::Error> {
            for f in &self.frames {
                for c in f.contacts() {
                    if c.flags.contains(ContactFlags::DOWN) {
                        self.down.push(c.id);
                    }
                    if c.flags.ended() {
                        self.down.retain(|&d| d != c.id);
                    }
                }
                sink.push(f);
            }
            match self.then.take() {
                Some(e) => Err(e),
                None => {
                    while !stop.load(Ordering::Relaxed) {
                        std::thread::sleep(Duration::from_millis(1));
                    }
                    Ok(())
                }
            }
        }
        fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool {
            *out = TouchFrame::new(t);
            for &id in &self.down {
                let _ = out.push(Contact {
                    id,
                    flags: ContactFlags::CANCELLED,
                    ..Contact::default()
                });
            }
            self.down.clear();
            !out.is_empty()
        }
    }

    enum Step {
        Find(Result<DeviceInfo, String>),
        Open(Result<Scripted, crate::input::Error>),
    }

    struct Env {
        script: VecDeque<Step>,
        waits: usize,
        stop: Arc<AtomicBool>,
        asked_stable: Vec<Option<String>>,
    }

    impl DeviceEnv for Env {
        fn find(
            &mut self,
            _: &DeviceSelect,
            _: DeviceInterface,
            stable_id: Option<&str>,
        ) -> Result<DeviceInfo, String> {
            self.asked_stable.push(stable_id.map(str::to_string));
            match self.script.pop_front() {
                Some(Step::Find(r)) => r,
                _ => {
                    self.stop.store(true, Ordering::SeqCst);
                    Err("script over".into())
                }
            }
        }
        fn open(&mut self, _: &DeviceInfo) -> Result<Box<dyn DeviceReader>, crate::input::Error> {
            match self.script.pop_front() {
                Some(Step::Open(Ok(r))) => Ok(Box::new(r)),
                Some(Step::Open(Err(e))) => Err(e),
                _ => panic!("script expected an open"),
            }
        }
        fn wait_change(&mut self, _: Duration, _: &AtomicBool) {
            self.waits += 1;
        }
    }

    fn touch(t: u64, id: u32, flags: ContactFlags) -> TouchFrame {
        let mut f = TouchFrame::new(Micros(t));
        f.push(Contact {
            id: ContactId(id),
            x: 0.5,
            y: 0.5,
            flags,
            ..Contact::default()
        })
        .unwrap();
        f
    }

    #[test]
    fn unplug_mid_touch_cancels_waits_and_reattaches_at_a_new_node() {
        let stop = Arc::new(AtomicBool::new(false));
        let first = Scripted {
            info: info("/dev/input/event5"),
            frames: vec![
                touch(1, 1, ContactFlags::DOWN),
                touch(2, 1, ContactFlags::NONE),
            ],
            then: Some(crate::input::Error::Unplugged {
                node: "/dev/input/event5".into(),
            }),
            down: vec![],
        };
        let second = Scripted {
            info: info("/dev/input/event7"),
            frames: vec![
                touch(10, 1, ContactFlags::DOWN),
                touch(11, 1, ContactFlags::UP),
            ],
            then: Some(crate::input::Error::Unplugged {
                node: "/dev/input/event7".into(),
            }),
            down: vec![],
        };
        let mut env = Env {
            script: VecDeque::from([
                Step::Find(Ok(info("/dev/input/event5"))),
                Step::Open(Ok(first)),
                Step::Find(Err("nothing matches".into())),
                Step::Find(Ok(info("/dev/input/event7"))),
                Step::Open(Ok(second)),
            ]),
            waits: 0,
            stop: Arc::clone(&stop),
            asked_stable: vec![],
        };
        let mut frames: Vec<TouchFrame> = vec![];
        let mut notices = vec![];
        supervise(
            &mut env,
            &DeviceSelect::Auto,
            DeviceInterface::Any,
            &mut frames,
            &stop,
            &mut |n| notices.push(n),
        );
        // Every touch-down has an end; the unplugged one is cancelled, not lifted.
        let flags: Vec<(u32, ContactFlags)> = frames
            .iter()
            .flat_map(|f| f.contacts().iter().map(|c| (c.id.0, c.flags)))
            .collect();
        assert_eq!(
            flags,
            vec![
                (1, ContactFlags::DOWN),
                (1, ContactFlags::NONE),
                (1, ContactFlags::CANCELLED),
                (1, ContactFlags::DOWN),
                (1, ContactFlags::UP),
            ]
        );
        let states: Vec<DeviceState> = notices.iter().map(|n| n.state).collect();
        assert_eq!(
            states,
            vec![
                DeviceState::Attached,
                DeviceState::Unplugged,
                DeviceState::Failed,
                DeviceState::Attached,
                DeviceState::Unplugged,
                DeviceState::Failed
            ]
        );
        assert_eq!(
            notices[3].info.as_ref().unwrap().identity.node,
            PathBuf::from("/dev/input/event7")
        );
        // After the first attach, the search is for the same physical device.
        assert_eq!(env.asked_stable[0], None);
        assert!(env.asked_stable[1..]
            .iter()
            .all(|s| s.as_deref() == Some("pci-0000:00:14.0-usb-0:2:1.0")));
        assert!(env.waits >= 2);
    }

    #[test]
    fn permission_denied_is_reported_once_and_retried_on_change() {
        let stop = Arc::new(AtomicBool::new(false));
        let denied = || crate::input::Error::PermissionDenied {
            node: "/dev/input/event5".into(),
            source: std::io::Error::from_raw_os_error(nix::libc::EACCES),
        };
        let mut env = Env {
            script: VecDeque::from([
                Step::Find(Ok(info("/dev/input/event5"))),
                Step::Open(Err(denied())),
                Step::Find(Ok(info("/dev/input/event5"))),
                Step::Open(Err(denied())),
            ]),
            waits: 0,
            stop: Arc::clone(&stop),
            asked_stable: vec![],
        };
        let mut frames: Vec<TouchFrame> = vec![];
        let mut notices = vec![];
        supervise(
            &mut env,
            &DeviceSelect::Auto,
            DeviceInterface::Any,
            &mut frames,
            &stop,
            &mut |n| notices.push(n),
        );
        let failed: Vec<&DeviceNotice> = notices
            .iter()
            .filter(|n| n.state == DeviceState::Failed)
            .collect();
        assert!(
            failed[0]
                .message
                .as_ref()
                .unwrap()
                .contains("permission denied"),
            "{:?}",
            failed[0].message
        );
        // The same failure twice is reported once (then "script over").
        assert_eq!(failed.len(), 2);
        assert!(frames.is_empty());
    }

    #[test]
    fn stop_while_reading_cancels_every_touch() {
        let stop = Arc::new(AtomicBool::new(false));
        let reader = Scripted {
            info: info("/dev/input/event5"),
            frames: vec![
                touch(1, 1, ContactFlags::DOWN),
                touch(2, 2, ContactFlags::DOWN),
            ],
            then: None,
            down: vec![],
        };
        let mut env = Env {
            script: VecDeque::from([
                Step::Find(Ok(info("/dev/input/event5"))),
                Step::Open(Ok(reader)),
            ]),
            waits: 0,
            stop: Arc::clone(&stop),
            asked_stable: vec![],
        };
        let s2 = Arc::clone(&stop);
        let stopper = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(30));
            s2.store(true, Ordering::SeqCst);
        });
        let mut frames: Vec<TouchFrame> = vec![];
        supervise(
            &mut env,
            &DeviceSelect::Auto,
            DeviceInterface::Any,
            &mut frames,
            &stop,
            &mut |_| {},
        );
        stopper.join().unwrap();
        let last = frames.last().unwrap();
        let cancelled: Vec<u32> = last
            .contacts()
            .iter()
            .filter(|c| c.flags.contains(ContactFlags::CANCELLED))
            .map(|c| c.id.0)
            .collect();
        assert_eq!(cancelled, vec![1, 2]);
    }
}
