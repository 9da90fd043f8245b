//! evdev touch devices: the kernel's event codes and their names, the multi-touch
//! decoder (protocol B slots, protocol A matching), what a device declares
//! (capabilities), the device shell that reads a node, and recording a node as an
//! evemu file.

mod capabilities;
mod codes;
mod device;
mod mt;
mod record;

#[cfg(test)]
pub(crate) use capabilities::sample_panel;
pub use capabilities::{
    AbsAxisInfo, DecoderSetup, EvdevCapabilities, NotTouchReason, MASK_BYTES, PROP_BYTES,
};
pub use codes::{
    code_name, type_name, ABS_CNT, ABS_MAX, ABS_MT_BLOB_ID, ABS_MT_DISTANCE, ABS_MT_ORIENTATION,
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE, ABS_MT_SLOT, ABS_MT_TOOL_TYPE,
    ABS_MT_TOOL_X, ABS_MT_TOOL_Y, ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, ABS_MT_TRACKING_ID,
    ABS_MT_WIDTH_MAJOR, ABS_MT_WIDTH_MINOR, ABS_PRESSURE, ABS_X, ABS_Y, BTN_TOOL_DOUBLETAP,
    BTN_TOOL_FINGER, BTN_TOOL_QUADTAP, BTN_TOOL_QUINTTAP, BTN_TOOL_TRIPLETAP, BTN_TOUCH, EV_ABS,
    EV_CNT, EV_FF, EV_KEY, EV_LED, EV_MSC, EV_REL, EV_REP, EV_SND, EV_SW, EV_SYN,
    INPUT_PROP_DIRECT, INPUT_PROP_POINTER, MT_TOOL_FINGER, MT_TOOL_PALM, MT_TOOL_PEN, SYN_CONFIG,
    SYN_DROPPED, SYN_MT_REPORT, SYN_REPORT,
};
pub use device::{
    capabilities, device_info, open_node, parse_input_event, parse_input_events, probe,
    single_touch_state, slot_codes, slot_state_from, timeval_micros, wait_read, EvdevOptions,
    EvdevReader, DROP_LOG_INTERVAL_US, INPUT_EVENT_BYTES, READ_BUF_BYTES, READ_EVENTS,
};
pub use mt::{
    assign_min_cost, MtAxes, MtCounters, MtDecoder, MtProtocol, MtSlotState, MtSlotValues,
    RawEvent, ASSIGN_MAX, MAX_SLOTS, TYPE_A_MAX_JUMP_MM, TYPE_A_MAX_JUMP_UNIT,
};
pub use record::record_evdev;
