//! The device header of the evdev formats (evemu, libinput record): the axes it
//! declares, and whether [`MtDecoder`](crate::input::evdev::MtDecoder) can decode
//! the device.
//!
//! The device must be multi-touch (`ABS_MT_POSITION_X/Y`): type B when the header
//! declares `ABS_MT_SLOT`, type A (anonymous contacts closed by `SYN_MT_REPORT`,
//! tracked by the decoder) when it does not. Single-touch devices are refused with
//! [`RecordingError::Unsupported`].

use super::error::{RecordingError, UnsupportedReason};
use super::warnings::Warnings;
use crate::input::evdev::{self as mt, MtAxes, ABS_MAX};
use crate::input::{AxisRange, SurfaceInfo};
use crate::vocab::MAX_CONTACTS;
use std::fmt;
use std::path::Path;

/// One evdev axis as a header declares it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) struct AbsInfo {
    pub(super) min: i32,
    pub(super) max: i32,
    pub(super) resolution: i32,
    /// Line that declared it.
    pub(super) line: usize,
}

/// What an evdev header says about a device.
#[derive(Clone, Debug)]
pub(super) struct DeviceHeader {
    pub(super) name: Option<String>,
    pub(super) abs: [Option<AbsInfo>; ABS_MAX as usize + 1],
}

impl Default for DeviceHeader {
    fn default() -> Self {
        DeviceHeader {
            name: None,
            abs: [None; ABS_MAX as usize + 1],
        }
    }
}

/// Where header problems are reported.
pub(super) struct HeaderCtx<'a> {
    pub(super) path: &'a Path,
    /// Prefix naming the description text, when separate.
    pub(super) prefix: &'static str,
}

impl HeaderCtx<'_> {
    pub(super) fn err(&self, line: usize, message: impl fmt::Display) -> RecordingError {
        RecordingError::parse(self.path, line, format!("{}{message}", self.prefix))
    }
}

impl DeviceHeader {
    fn axis_range(&self, code: u16) -> Option<AxisRange> {
        self.abs[code as usize].map(|a| AxisRange {
            min: f64::from(a.min),
            max: f64::from(a.max),
            resolution: f64::from(a.resolution.max(0)),
        })
    }

    /// The decoder axes and surface, or why this device cannot be decoded.
    ///
    /// `line` is where the header was found to be needed (the first event).
    pub(super) fn mt_axes(
        &self,
        ctx: &HeaderCtx<'_>,
        line: usize,
        default_name: &str,
        warnings: &mut Warnings,
    ) -> Result<(MtAxes, SurfaceInfo), RecordingError> {
        let unsupported = |reason| RecordingError::Unsupported {
            path: ctx.path.to_path_buf(),
            reason,
        };
        let has = |code: u16| self.abs[code as usize].is_some();
        if self.abs.iter().all(Option::is_none) {
            return Err(ctx.err(
                line,
                "missing device header: no `A:` axis line before the first event (for \
                 header-less .events files, pair them with their .desc)",
            ));
        }
        if !has(mt::ABS_MT_POSITION_X) || !has(mt::ABS_MT_POSITION_Y) {
            return Err(unsupported(UnsupportedReason::NoMultiTouch));
        }
        for code in [mt::ABS_MT_POSITION_X, mt::ABS_MT_POSITION_Y] {
            if let Some(a) = self.abs[code as usize] {
                if a.max <= a.min {
                    return Err(ctx.err(
                        a.line,
                        format_args!(
                            "axis {} has an empty range (min {}, max {})",
                            abs_name(code),
                            a.min,
                            a.max
                        ),
                    ));
                }
            }
        }
        // No ABS_MT_SLOT: protocol A (0 slots), up to a frame's worth of contacts.
        let mut slots = 0;
        let mut max_contacts = MAX_CONTACTS as u32;
        if let Some(slot) = self.abs[mt::ABS_MT_SLOT as usize] {
            if slot.max < 0 || slot.min != 0 {
                return Err(ctx.err(
                    slot.line,
                    format_args!(
                        "ABS_MT_SLOT must range from 0 (found min {}, max {})",
                        slot.min, slot.max
                    ),
                ));
            }
            let declared = slot.max as usize + 1;
            if declared > mt::MAX_SLOTS {
                warnings.push(
                    slot.line,
                    format!(
                        "the device declares {declared} slots; only the first {} are decoded",
                        mt::MAX_SLOTS
                    ),
                );
            }
            slots = declared.min(mt::MAX_SLOTS);
            max_contacts = slots as u32;
        }
        let (Some(x), Some(y)) = (
            self.axis_range(mt::ABS_MT_POSITION_X),
            self.axis_range(mt::ABS_MT_POSITION_Y),
        ) else {
            return Err(unsupported(UnsupportedReason::NoMultiTouch));
        };
        let axes = MtAxes {
            x,
            y,
            slots,
            pressure: self.axis_range(mt::ABS_MT_PRESSURE),
            touch_major: self.axis_range(mt::ABS_MT_TOUCH_MAJOR),
            touch_minor: self.axis_range(mt::ABS_MT_TOUCH_MINOR),
        };
        let surface = SurfaceInfo {
            name: self
                .name
                .clone()
                .unwrap_or_else(|| default_name.to_string()),
            x,
            y,
            max_contacts,
        };
        Ok((axes, surface))
    }
}

/// A readable name for an axis code.
fn abs_name(code: u16) -> String {
    match code {
        mt::ABS_MT_POSITION_X => "ABS_MT_POSITION_X".into(),
        mt::ABS_MT_POSITION_Y => "ABS_MT_POSITION_Y".into(),
        mt::ABS_MT_SLOT => "ABS_MT_SLOT".into(),
        _ => format!("0x{code:02x}"),
    }
}

/// The device name when the file gives none: the file's stem.
pub(super) fn default_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "unknown device".to_string())
}
