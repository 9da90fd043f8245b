//! What a decoder has seen: the counts behind stats and import warnings.

/// What a decoder has seen, for stats and import warnings.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct MtCounters {
    /// Events fed.
    pub events: u64,
    /// Frames returned (one per `SYN_REPORT` outside a dropped block).
    pub frames: u64,
    /// Contacts begun.
    pub contacts_begun: u64,
    /// Contacts ended by a lift (`UP`).
    pub contacts_ended: u64,
    /// Contacts ended without a clean lift (`CANCELLED`): by
    /// [`MtDecoder::cancel_all`](super::MtDecoder::cancel_all), a [`MtDecoder::resync`](super::MtDecoder::resync), or missing from the
    /// first type-A frame after a `SYN_DROPPED`.
    pub contacts_cancelled: u64,
    /// `ABS_MT_SLOT` values outside `0..slots`; the `ABS_MT_*` events after one
    /// are ignored until a valid slot is selected.
    pub slot_out_of_range: u64,
    /// `ABS_MT_*` events ignored because the selected slot was out of range.
    pub ignored_slot_events: u64,
    /// Contacts that did not fit a frame of [`MAX_CONTACTS`](crate::vocab::MAX_CONTACTS).
    pub frame_overflow: u64,
    /// Type-A packets beyond [`MAX_CONTACTS`](crate::vocab::MAX_CONTACTS) in one frame (dropped).
    pub contacts_over_capacity: u64,
    /// `SYN_DROPPED` events seen.
    pub dropped_sync: u64,
    /// Events discarded after a `SYN_DROPPED` (up to the next `SYN_REPORT`).
    pub discarded_events: u64,
    /// Resynchronisations applied ([`MtDecoder::resync`](super::MtDecoder::resync)).
    pub resyncs: u64,
    /// `SYN_MT_REPORT` events (type-A packets; ignored by type B).
    pub mt_report: u64,
    /// Type-A packets not closed by `SYN_MT_REPORT` before `SYN_REPORT` (kept).
    pub unterminated_packets: u64,
    /// Type-A packets ignored because `BTN_TOUCH 0` came in the same frame.
    pub packets_after_lift: u64,
    /// Contacts that began and ended within one frame (not reported).
    pub transient_contacts: u64,
    /// A slot's active tracking id sent again without a release (continues).
    pub tracking_id_reused: u64,
    /// An active slot given a different tracking id without a release (the old
    /// contact ends, the new one begins).
    pub tracking_id_switched: u64,
    /// Events for an axis the device does not declare (ignored).
    pub undeclared_axis: u64,
}
