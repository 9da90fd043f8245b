//! The kernel's input event types and codes (`linux/input-event-codes.h`) that touch
//! devices use, and their names for evemu comments and messages.

/// Event type: synchronisation.
pub const EV_SYN: u16 = 0;
/// Event type: keys and buttons.
pub const EV_KEY: u16 = 1;
/// Event type: relative axes.
pub const EV_REL: u16 = 2;
/// Event type: absolute axes.
pub const EV_ABS: u16 = 3;
/// Event type: miscellaneous (e.g. `MSC_TIMESTAMP`).
pub const EV_MSC: u16 = 4;
/// Event type: switches.
pub const EV_SW: u16 = 0x05;
/// Event type: LEDs.
pub const EV_LED: u16 = 0x11;
/// Event type: sounds.
pub const EV_SND: u16 = 0x12;
/// Event type: key repeat.
pub const EV_REP: u16 = 0x14;
/// Event type: force feedback.
pub const EV_FF: u16 = 0x15;
/// Number of event types (`EV_CNT`).
pub const EV_CNT: usize = 0x20;

/// `EV_SYN` code closing a frame.
pub const SYN_REPORT: u16 = 0;
/// `EV_SYN` code (unused by touch devices).
pub const SYN_CONFIG: u16 = 1;
/// `EV_SYN` code closing one contact packet in protocol A.
pub const SYN_MT_REPORT: u16 = 2;
/// `EV_SYN` code: the client's event buffer overflowed, events were lost.
pub const SYN_DROPPED: u16 = 3;

/// `EV_KEY` code: at least one tool touches the surface.
pub const BTN_TOUCH: u16 = 0x14a;
/// `EV_KEY` code: one finger (mostly touchpads).
pub const BTN_TOOL_FINGER: u16 = 0x145;
/// `EV_KEY` code: two fingers.
pub const BTN_TOOL_DOUBLETAP: u16 = 0x14d;
/// `EV_KEY` code: three fingers.
pub const BTN_TOOL_TRIPLETAP: u16 = 0x14e;
/// `EV_KEY` code: four fingers.
pub const BTN_TOOL_QUADTAP: u16 = 0x14f;
/// `EV_KEY` code: five fingers.
pub const BTN_TOOL_QUINTTAP: u16 = 0x148;

/// `EV_ABS` code: single-touch X.
pub const ABS_X: u16 = 0x00;
/// `EV_ABS` code: single-touch Y.
pub const ABS_Y: u16 = 0x01;
/// `EV_ABS` code: single-touch pressure.
pub const ABS_PRESSURE: u16 = 0x18;
/// `EV_ABS` code: selects the slot later `ABS_MT_*` events apply to.
pub const ABS_MT_SLOT: u16 = 0x2f;
/// `EV_ABS` code: major axis of the contact ellipse (surface units).
pub const ABS_MT_TOUCH_MAJOR: u16 = 0x30;
/// `EV_ABS` code: minor axis of the contact ellipse (surface units).
pub const ABS_MT_TOUCH_MINOR: u16 = 0x31;
/// `EV_ABS` code: major axis of the approaching tool.
pub const ABS_MT_WIDTH_MAJOR: u16 = 0x32;
/// `EV_ABS` code: minor axis of the approaching tool.
pub const ABS_MT_WIDTH_MINOR: u16 = 0x33;
/// `EV_ABS` code: ellipse orientation.
pub const ABS_MT_ORIENTATION: u16 = 0x34;
/// `EV_ABS` code: contact centre X.
pub const ABS_MT_POSITION_X: u16 = 0x35;
/// `EV_ABS` code: contact centre Y.
pub const ABS_MT_POSITION_Y: u16 = 0x36;
/// `EV_ABS` code: tool type (`MT_TOOL_*`).
pub const ABS_MT_TOOL_TYPE: u16 = 0x37;
/// `EV_ABS` code: blob id (protocol A grouping).
pub const ABS_MT_BLOB_ID: u16 = 0x38;
/// `EV_ABS` code: contact identity; `-1` ends the contact of the slot.
pub const ABS_MT_TRACKING_ID: u16 = 0x39;
/// `EV_ABS` code: contact pressure.
pub const ABS_MT_PRESSURE: u16 = 0x3a;
/// `EV_ABS` code: hover distance.
pub const ABS_MT_DISTANCE: u16 = 0x3b;
/// `EV_ABS` code: tool centre X.
pub const ABS_MT_TOOL_X: u16 = 0x3c;
/// `EV_ABS` code: tool centre Y.
pub const ABS_MT_TOOL_Y: u16 = 0x3d;
/// Highest `EV_ABS` code the kernel defines.
pub use crate::sys::ABS_MAX;
/// Number of absolute axis codes (`ABS_CNT`).
pub const ABS_CNT: usize = ABS_MAX as usize + 1;

/// `ABS_MT_TOOL_TYPE` value: a finger.
pub const MT_TOOL_FINGER: i32 = 0;
/// `ABS_MT_TOOL_TYPE` value: a pen.
pub const MT_TOOL_PEN: i32 = 1;
/// `ABS_MT_TOOL_TYPE` value: a palm.
pub const MT_TOOL_PALM: i32 = 2;

/// Property bit: the device moves a pointer (touchpads).
pub const INPUT_PROP_POINTER: u16 = 0x00;
/// Property bit: the device is mapped onto a screen (touchscreens).
pub const INPUT_PROP_DIRECT: u16 = 0x01;

/// The kernel name of an event type, or `?`.
pub fn type_name(ev_type: u16) -> &'static str {
    match ev_type {
        EV_SYN => "EV_SYN",
        EV_KEY => "EV_KEY",
        EV_REL => "EV_REL",
        EV_ABS => "EV_ABS",
        EV_MSC => "EV_MSC",
        EV_SW => "EV_SW",
        EV_LED => "EV_LED",
        EV_SND => "EV_SND",
        EV_REP => "EV_REP",
        EV_FF => "EV_FF",
        0x16 => "EV_PWR",
        0x17 => "EV_FF_STATUS",
        _ => "?",
    }
}

/// The kernel name of an event code touch devices send, or `?`.
pub fn code_name(ev_type: u16, code: u16) -> &'static str {
    const ABS: [&str; ABS_CNT] = [
        "ABS_X",
        "ABS_Y",
        "ABS_Z",
        "ABS_RX",
        "ABS_RY",
        "ABS_RZ",
        "ABS_THROTTLE",
        "ABS_RUDDER",
        "ABS_WHEEL",
        "ABS_GAS",
        "ABS_BRAKE",
        "?",
        "?",
        "?",
        "?",
        "?",
        "ABS_HAT0X",
        "ABS_HAT0Y",
        "ABS_HAT1X",
        "ABS_HAT1Y",
        "ABS_HAT2X",
        "ABS_HAT2Y",
        "ABS_HAT3X",
        "ABS_HAT3Y",
        "ABS_PRESSURE",
        "ABS_DISTANCE",
        "ABS_TILT_X",
        "ABS_TILT_Y",
        "ABS_TOOL_WIDTH",
        "?",
        "?",
        "?",
        "ABS_VOLUME",
        "ABS_PROFILE",
        "?",
        "?",
        "?",
        "?",
        "?",
        "?",
        "ABS_MISC",
        "?",
        "?",
        "?",
        "?",
        "?",
        "ABS_RESERVED",
        "ABS_MT_SLOT",
        "ABS_MT_TOUCH_MAJOR",
        "ABS_MT_TOUCH_MINOR",
        "ABS_MT_WIDTH_MAJOR",
        "ABS_MT_WIDTH_MINOR",
        "ABS_MT_ORIENTATION",
        "ABS_MT_POSITION_X",
        "ABS_MT_POSITION_Y",
        "ABS_MT_TOOL_TYPE",
        "ABS_MT_BLOB_ID",
        "ABS_MT_TRACKING_ID",
        "ABS_MT_PRESSURE",
        "ABS_MT_DISTANCE",
        "ABS_MT_TOOL_X",
        "ABS_MT_TOOL_Y",
        "?",
        "?",
    ];
    match (ev_type, code) {
        (EV_SYN, 0) => "SYN_REPORT",
        (EV_SYN, 1) => "SYN_CONFIG",
        (EV_SYN, 2) => "SYN_MT_REPORT",
        (EV_SYN, 3) => "SYN_DROPPED",
        (EV_ABS, c) => ABS.get(usize::from(c)).copied().unwrap_or("?"),
        (EV_KEY, 0x110) => "BTN_LEFT",
        (EV_KEY, 0x111) => "BTN_RIGHT",
        (EV_KEY, 0x112) => "BTN_MIDDLE",
        (EV_KEY, 0x140) => "BTN_TOOL_PEN",
        (EV_KEY, 0x141) => "BTN_TOOL_RUBBER",
        (EV_KEY, BTN_TOOL_FINGER) => "BTN_TOOL_FINGER",
        (EV_KEY, BTN_TOOL_QUINTTAP) => "BTN_TOOL_QUINTTAP",
        (EV_KEY, BTN_TOUCH) => "BTN_TOUCH",
        (EV_KEY, 0x14b) => "BTN_STYLUS",
        (EV_KEY, 0x14c) => "BTN_STYLUS2",
        (EV_KEY, BTN_TOOL_DOUBLETAP) => "BTN_TOOL_DOUBLETAP",
        (EV_KEY, BTN_TOOL_TRIPLETAP) => "BTN_TOOL_TRIPLETAP",
        (EV_KEY, BTN_TOOL_QUADTAP) => "BTN_TOOL_QUADTAP",
        (EV_MSC, 0) => "MSC_SERIAL",
        (EV_MSC, 4) => "MSC_SCAN",
        (EV_MSC, 5) => "MSC_TIMESTAMP",
        _ => "?",
    }
}
