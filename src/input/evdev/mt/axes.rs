//! What a decoder is built for: the protocol and the device's axes.

use crate::input::AxisRange;

/// Which protocol a decoder speaks.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum MtProtocol {
    /// Type B: slots selected with `ABS_MT_SLOT`, contacts named by
    /// `ABS_MT_TRACKING_ID`, incremental values.
    B,
    /// Type A: anonymous contact packets closed by `SYN_MT_REPORT`, every frame
    /// complete.
    A,
    /// No `ABS_MT_*` axes: one contact at `ABS_X/ABS_Y` while `BTN_TOUCH` is 1.
    SingleTouch,
}

/// The axes of a multi-touch device that the decoder needs.
#[derive(Clone, Debug, PartialEq)]
pub struct MtAxes {
    /// `ABS_MT_POSITION_X` range (`ABS_X` for single touch).
    pub x: AxisRange,
    /// `ABS_MT_POSITION_Y` range (`ABS_Y` for single touch).
    pub y: AxisRange,
    /// Number of slots (`ABS_MT_SLOT` max + 1), clamped to `1..=MAX_SLOTS`;
    /// `0` for a type-A device (no `ABS_MT_SLOT`).
    pub slots: usize,
    /// `ABS_MT_PRESSURE` range (`ABS_PRESSURE` for single touch), when the
    /// device reports pressure.
    pub pressure: Option<AxisRange>,
    /// `ABS_MT_TOUCH_MAJOR` range, when reported.
    pub touch_major: Option<AxisRange>,
    /// `ABS_MT_TOUCH_MINOR` range, when reported.
    pub touch_minor: Option<AxisRange>,
}
