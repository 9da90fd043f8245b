//! HID input reports → [`TouchFrame`]s, with the kernel's hid-multitouch semantics.
//!
//! [`HidDecoder`] is a state machine over raw input reports (the bytes a hidraw
//! `read` returns, report ID first when the descriptor uses IDs). It keeps a fixed
//! table of contacts (no allocation after [`HidDecoder::new`], none per report)
//! and fills a [`TouchFrame`] when a frame completes.
//!
//! # Frames
//!
//! * **Parallel mode**: every finger is in one report. The report's Contact Count
//!   says how many of its finger slots are valid (the first N; the rest are
//!   ignored, as with the kernel's `MT_QUIRK_CONTACT_CNT_ACCURATE`), and the frame
//!   completes with the report.
//! * **Hybrid mode**: more contacts than finger slots per report. A report with a
//!   Contact Count > 0 starts a frame expecting that many contacts; the following
//!   reports carry Contact Count 0 and more slots; the frame completes when the
//!   announced number of slots has been read. A Contact Count of 0 with no frame
//!   under way is an empty frame (no contact down).
//! * A new frame that starts before the previous one completed (a report was lost)
//!   counts in [`HidCounters::incomplete_frames`]; what the partial frame changed is
//!   kept and delivered with the next frame, so no touch-down or lift is lost.
//! * Without a Contact Count field (eGalax-style serial reporting, one finger per
//!   report) every report is a frame and every slot is read.
//!
//! # Contact life cycle
//!
//! ```text
//!                 tip 1, unknown id                 tip 0 (UP, last position)
//!   (not down) ─────────────────────► down ───────────────────────────────► (ended)
//!                    (DOWN)            │   not in a completed frame (UP)        ▲
//!                                      └────────────────────────────────────────┘
//!                                      cancel_all: CANCELLED
//! ```
//!
//! * A slot whose Tip Switch is 1 (or, without a Tip Switch, In Range is 1) is a
//!   contact; its HID Contact Identifier maps to a decoder id (counted up from the
//!   first id, never reused while the decoder lives).
//! * Tip Switch 0 for a contact that is down ends it with `UP` at its last position
//!   (where it was while touching), even if In Range is still 1 (no hover).
//! * When the device has a Contact Count, a frame lists every contact down (the
//!   Windows 8 digitizer rules); a contact missing from a completed frame ended
//!   (`UP`), as with the kernel's `MT_QUIRK_NOT_SEEN_MEANS_UP` — so a lost lift
//!   report cannot leave a touch stuck.
//! * Confidence 0 marks the contact [`ContactFlags::PALM`] in that frame.
//! * The same Contact Identifier twice in one frame: the second is ignored
//!   ([`HidCounters::duplicate_contacts`]), as the kernel's
//!   `MT_QUIRK_IGNORE_DUPLICATES`.
//!
//! A frame lists, transitions first: the contacts that ended (`UP`, or `DOWN|UP`
//! when one began and ended within the frame), the contacts that began (`DOWN`),
//! then the contacts that continue. Frames with no contact are returned too.
//!
//! # Values
//!
//! X and Y are normalised over their logical range to the unit square (clamped).
//! Tip Pressure is normalised over its logical range. Width and Height become
//! `major_mm` (the larger) and `minor_mm` (the smaller): through their own physical
//! range when its unit is a length (cm or inch), else as X (width) / Y (height)
//! logical units through the X/Y resolution, else they are left out.
//!
//! # Bad reports
//!
//! [`HidDecoder::decode`] returns a [`ReportError`] and changes nothing for an
//! empty report, a report ID the descriptor does not declare, a report shorter
//! than its layout, or a Contact Count above the maximum; each is counted in
//! [`HidCounters`]. Reports of other collections (pens, vendor reports) are
//! counted and ignored. Never panics.

use super::descriptor::{Finger, HidField, TouchCollection};
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};

/// Contacts the table holds: every contact down plus those that ended in the
/// frame under way.
const TABLE: usize = 2 * MAX_CONTACTS;
/// `report_index` value for "not a report of this collection".
const NO_REPORT: u8 = u8::MAX;

/// What a decoder has seen, for stats and import warnings.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct HidCounters {
    /// Reports fed.
    pub reports: u64,
    /// Frames completed.
    pub frames: u64,
    /// Empty reports (no byte at all).
    pub malformed: u64,
    /// Reports shorter than the descriptor's layout.
    pub truncated: u64,
    /// Reports whose ID the descriptor does not declare.
    pub unknown_report_id: u64,
    /// Reports of other collections (pen, mouse, vendor): ignored.
    pub other_reports: u64,
    /// Reports whose Contact Count was above the maximum.
    pub count_above_max: u64,
    /// Frames that started before the previous one completed (a report was lost).
    pub incomplete_frames: u64,
    /// Second appearances of a Contact Identifier in one frame (ignored).
    pub duplicate_contacts: u64,
    /// Contacts begun.
    pub contacts_begun: u64,
    /// Contacts ended by Tip Switch 0.
    pub contacts_lifted: u64,
    /// Contacts ended because a completed frame did not list them.
    pub contacts_not_seen: u64,
    /// Contacts ended by [`HidDecoder::cancel_all`].
    pub contacts_cancelled: u64,
    /// New contacts refused because the maximum number was already down.
    pub contacts_over_capacity: u64,
    /// Contacts that did not fit a frame of [`MAX_CONTACTS`].
    pub frame_overflow: u64,
}

/// Why a report was refused (and skipped).
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReportError {
    /// A read returned no byte.
    #[error("empty report")]
    Empty,
    /// Byte 0 names a report the descriptor does not declare.
    #[error("report ID {id} is not declared by the report descriptor")]
    UnknownReportId {
        /// The report ID found.
        id: u8,
    },
    /// Fewer bytes than the report's layout needs.
    #[error("report {} has {len} bytes; its layout needs {need}", fmt_id(*.report_id))]
    Truncated {
        /// Report ID (`None`: no IDs).
        report_id: Option<u8>,
        /// Bytes received.
        len: usize,
        /// Bytes needed.
        need: usize,
    },
    /// The Contact Count is larger than the device's maximum.
    #[error("Contact Count {count} is above the maximum of {max}")]
    CountAboveMax {
        /// Contact Count found.
        count: u32,
        /// The maximum.
        max: u32,
    },
}

fn fmt_id(id: Option<u8>) -> String {
    id.map_or_else(|| "(no ID)".to_string(), |i| format!("ID {i}"))
}

/// `offset + scale × raw`: a linear map from a raw field value.
#[derive(Copy, Clone, Debug)]
struct Lin {
    field: HidField,
    offset: f64,
    scale: f64,
}

impl Lin {
    /// Maps the logical range onto `[0, 1]`.
    fn unit(field: HidField) -> Option<Lin> {
        let span = f64::from(field.logical_max) - f64::from(field.logical_min);
        (span > 0.0).then(|| Lin {
            field,
            offset: -f64::from(field.logical_min) / span,
            scale: 1.0 / span,
        })
    }

    /// Maps a size field to millimetres: through its own physical range and length
    /// unit, else through `fallback_res` (units/mm of the matching position axis).
    ///
    /// # Formula
    /// `mm = (pmin + (v − lmin)·(pmax − pmin)/(lmax − lmin)) · mm_per_unit`, or `v / res`.
    fn size_mm(field: HidField, fallback_res: f64) -> Option<Lin> {
        let lspan = f64::from(field.logical_max) - f64::from(field.logical_min);
        let pspan = f64::from(field.physical_max) - f64::from(field.physical_min);
        if let Some(mm) = field.mm_per_physical_unit() {
            if lspan > 0.0 && pspan > 0.0 {
                let k = pspan / lspan * mm;
                return Some(Lin {
                    field,
                    offset: f64::from(field.physical_min) * mm - f64::from(field.logical_min) * k,
                    scale: k,
                });
            }
        }
        (fallback_res > 0.0).then(|| Lin {
            field,
            offset: 0.0,
            scale: 1.0 / fallback_res,
        })
    }

    #[inline]
    fn apply(&self, report: &[u8]) -> f64 {
        let raw = self.field.extract(report).unwrap_or(0) as f64;
        self.offset + self.scale * raw
    }
}

/// A finger slot with its value maps, built once.
#[derive(Copy, Clone, Debug)]
struct Plan {
    finger: Finger,
    x: Lin,
    y: Lin,
    pressure: Option<Lin>,
    width: Option<Lin>,
    height: Option<Lin>,
}

impl Plan {
    fn new(f: &Finger) -> Option<Plan> {
        let x = Lin::unit(f.x)?;
        let y = Lin::unit(f.y)?;
        Some(Plan {
            finger: *f,
            x,
            y,
            pressure: f.pressure.and_then(Lin::unit),
            width: f.width.and_then(|w| Lin::size_mm(w, f.x.resolution())),
            height: f.height.and_then(|h| Lin::size_mm(h, f.y.resolution())),
        })
    }
}

/// One input report's plans.
#[derive(Clone, Debug)]
struct ReportPlan {
    report_id: Option<u8>,
    size_bytes: usize,
    contact_count: Option<HidField>,
    fingers: Vec<Plan>,
}

/// A contact in the table.
#[derive(Copy, Clone, Debug, Default)]
struct Entry {
    hid_id: u32,
    contact: Contact,
    /// Began in the frame under way (DOWN not yet delivered).
    began: bool,
    /// Ended in the frame under way (UP not yet delivered).
    ended: bool,
    /// Reported in the frame under way.
    seen: bool,
}

/// Decodes a touch collection's input reports into [`TouchFrame`]s.
///
/// # Complexity
/// `report` is O(slots × contacts down) with at most 64 contacts; no allocation
/// after [`HidDecoder::new`].
///
/// # Example
/// ```
/// use crowdtouch::input::hid::{touch_collections, HidDecoder};
/// use crowdtouch::vocab::{ContactFlags, TouchFrame};
/// use crowdtouch::vocab::Micros;
///
/// // ActionStar 2101:1011 (hid-tools' test_multitouch.py), first report of its
/// // in-range sequence: two fingers down.
/// let rdesc = [0x05, 0x0d, 0x09, 0x04, 0xa1, 0x01, 0x85, 0x01, 0x09, 0x22, 0xa1, 0x02,
///   0x09, 0x42, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, 0x09, 0x32,
///   0x81, 0x02, 0x09, 0x47, 0x81, 0x02, 0x95, 0x05, 0x81, 0x03, 0x09, 0x51, 0x75, 0x08,
///   0x95, 0x01, 0x81, 0x02, 0x05, 0x01, 0x35, 0x00, 0x55, 0x0e, 0x65, 0x33, 0x75, 0x10,
///   0x95, 0x01, 0x09, 0x30, 0x26, 0xff, 0x4d, 0x46, 0x70, 0x03, 0x81, 0x02, 0x09, 0x31,
///   0x26, 0xff, 0x2b, 0x46, 0xf1, 0x01, 0x81, 0x02, 0x46, 0x00, 0x00, 0xc0, 0xa1, 0x02,
///   0x05, 0x0d, 0x09, 0x42, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02,
///   0x09, 0x32, 0x81, 0x02, 0x09, 0x47, 0x81, 0x02, 0x95, 0x05, 0x81, 0x03, 0x09, 0x51,
///   0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0x05, 0x01, 0x35, 0x00, 0x55, 0x0e, 0x65, 0x33,
///   0x75, 0x10, 0x95, 0x01, 0x09, 0x30, 0x26, 0xff, 0x4d, 0x46, 0x70, 0x03, 0x81, 0x02,
///   0x09, 0x31, 0x26, 0xff, 0x2b, 0x46, 0xf1, 0x01, 0x81, 0x02, 0x46, 0x00, 0x00, 0xc0,
///   0x05, 0x0d, 0x09, 0x54, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0x05, 0x0d, 0x85, 0x02,
///   0x09, 0x55, 0x25, 0x02, 0x75, 0x08, 0x95, 0x01, 0xb1, 0x02, 0xc0];
/// let tc = touch_collections(&rdesc).unwrap().remove(0);
/// let mut dec = HidDecoder::new(&tc);
/// let mut f = TouchFrame::default();
/// let r0 = [0x01, 0xff, 0x01, 0x57, 0x1b, 0x89, 0x09, 0xff, 0x02, 0x7b, 0x3b, 0xea, 0x07, 0x02];
/// assert!(dec.report(Micros(0), &r0, &mut f));
/// assert_eq!(f.len(), 2);
/// let c = f.contacts()[0];
/// assert_eq!(c.flags, ContactFlags::DOWN);
/// assert!((c.x - 6999.0 / 19967.0).abs() < 1e-6);
/// assert!((c.y - 2441.0 / 11263.0).abs() < 1e-6);
/// ```
#[derive(Clone, Debug)]
pub struct HidDecoder {
    reports: Vec<ReportPlan>,
    /// Report ID → index in `reports`, or `NO_REPORT`.
    report_index: [u8; 256],
    /// Report IDs the descriptor declares (any collection).
    declared: [bool; 256],
    uses_report_ids: bool,
    /// Most contacts down at once, and the largest Contact Count accepted.
    max_contacts: u32,
    table: [Entry; TABLE],
    len: usize,
    /// A frame has started and not completed.
    pending: bool,
    expected: u32,
    received: u32,
    next_id: u32,
    counters: HidCounters,
}

impl HidDecoder {
    /// A decoder for `collection`, numbering contacts from 1.
    pub fn new(collection: &TouchCollection) -> HidDecoder {
        HidDecoder::with_first_id(collection, 1)
    }

    /// A decoder numbering contacts from `first_id` upward (never reused).
    ///
    /// The contact maximum is the larger of the descriptor's Contact Count Maximum
    /// (when plausible, else [`MAX_CONTACTS`]) and the finger slots per report,
    /// capped at [`MAX_CONTACTS`]; [`HidDecoder::set_max_contacts`] refines it with
    /// the value read from the device.
    pub fn with_first_id(collection: &TouchCollection, first_id: u32) -> HidDecoder {
        let mut report_index = [NO_REPORT; 256];
        let mut reports = Vec::with_capacity(collection.reports.len());
        for r in &collection.reports {
            if reports.len() >= usize::from(NO_REPORT) {
                break;
            }
            let fingers: Vec<Plan> = r.fingers.iter().filter_map(Plan::new).collect();
            if fingers.is_empty() {
                continue;
            }
            if let Some(id) = r.report_id {
                if report_index[usize::from(id)] != NO_REPORT {
                    continue;
                }
                report_index[usize::from(id)] = reports.len() as u8;
            }
            let need = fingers
                .iter()
                .map(|p| p.finger.end_byte())
                .chain(r.contact_count.iter().map(HidField::end_byte))
                .max()
                .unwrap_or(0);
            reports.push(ReportPlan {
                report_id: r.report_id,
                size_bytes: r.size_bytes.max(need),
                contact_count: r.contact_count,
                fingers,
            });
        }
        let mut declared = [false; 256];
        for id in &collection.declared_input_ids {
            declared[usize::from(*id)] = true;
        }
        for r in &reports {
            if let Some(id) = r.report_id {
                declared[usize::from(id)] = true;
            }
        }
        let per_report = reports.iter().map(|r| r.fingers.len()).max().unwrap_or(0) as u32;
        let declared_max = collection
            .declared_max_contacts()
            .unwrap_or(MAX_CONTACTS as u32);
        let mut d = HidDecoder {
            reports,
            report_index,
            declared,
            uses_report_ids: collection.uses_report_ids,
            max_contacts: 1,
            table: [Entry::default(); TABLE],
            len: 0,
            pending: false,
            expected: 0,
            received: 0,
            next_id: first_id,
            counters: HidCounters::default(),
        };
        d.set_max_contacts(declared_max.max(per_report));
        d
    }

    /// Sets the most contacts down at once (also the largest Contact Count
    /// accepted), clamped to `1..=MAX_CONTACTS`; e.g. the Contact Count Maximum
    /// read from the device.
    pub fn set_max_contacts(&mut self, max: u32) {
        self.max_contacts = max.clamp(1, MAX_CONTACTS as u32);
    }

    /// The contact maximum in effect.
    pub fn max_contacts(&self) -> u32 {
        self.max_contacts
    }

    /// What the decoder has seen so far.
    pub fn counters(&self) -> HidCounters {
        self.counters
    }

    /// The id the next new contact will get.
    pub fn next_id(&self) -> u32 {
        self.next_id
    }

    /// Contacts currently down.
    pub fn active_contacts(&self) -> usize {
        self.table[..self.len].iter().filter(|e| !e.ended).count()
    }

    /// Whether a hybrid frame has started and not completed.
    pub fn frame_pending(&self) -> bool {
        self.pending
    }

    /// Largest input report of the collection, in bytes (for read buffers).
    pub fn max_report_bytes(&self) -> usize {
        self.reports.iter().map(|r| r.size_bytes).max().unwrap_or(0)
    }

    /// Feeds one report; true when it completed a frame (then `out` holds it).
    ///
    /// Bad reports are counted and skipped (see [`HidDecoder::decode`]).
    pub fn report(&mut self, t: Micros, bytes: &[u8], out: &mut TouchFrame) -> bool {
        self.decode(t, bytes, out).unwrap_or(false)
    }

    /// Feeds one report. `Ok(true)`: a frame completed and `out` (cleared first,
    /// `t` set) holds it; `Ok(false)`: no frame yet, or a report of another
    /// collection; `out` is untouched.
    ///
    /// # Errors
    /// [`ReportError`] for an empty report, an undeclared report ID, a report too
    /// short for its layout, a Contact Count above the maximum. The report is
    /// counted and changes nothing.
    pub fn decode(
        &mut self,
        t: Micros,
        bytes: &[u8],
        out: &mut TouchFrame,
    ) -> Result<bool, ReportError> {
        self.counters.reports += 1;
        let Some(&first) = bytes.first() else {
            self.counters.malformed += 1;
            return Err(ReportError::Empty);
        };
        let index = if self.uses_report_ids {
            match self.report_index[usize::from(first)] {
                NO_REPORT if self.declared[usize::from(first)] => {
                    self.counters.other_reports += 1;
                    return Ok(false);
                }
                NO_REPORT => {
                    self.counters.unknown_report_id += 1;
                    return Err(ReportError::UnknownReportId { id: first });
                }
                i => usize::from(i),
            }
        } else {
            0
        };
        let Some((report_id, size_bytes, count_field, nfingers)) = self
            .reports
            .get(index)
            .map(|p| (p.report_id, p.size_bytes, p.contact_count, p.fingers.len()))
        else {
            self.counters.unknown_report_id += 1;
            return Err(ReportError::UnknownReportId { id: first });
        };
        if bytes.len() < size_bytes {
            self.counters.truncated += 1;
            return Err(ReportError::Truncated {
                report_id,
                len: bytes.len(),
                need: size_bytes,
            });
        }
        let count = count_field.map(|f| f.extract_raw(bytes).unwrap_or(0));
        if let Some(c) = count {
            if c > self.max_contacts {
                self.counters.count_above_max += 1;
                return Err(ReportError::CountAboveMax {
                    count: c,
                    max: self.max_contacts,
                });
            }
        }
        match count {
            Some(c) if c > 0 => {
                if self.pending {
                    // The previous frame never completed: keep what it changed
                    // (begun and ended contacts are delivered with this frame)
                    // but not its "seen" marks — this frame lists every contact.
                    self.counters.incomplete_frames += 1;
                    for e in &mut self.table[..self.len] {
                        e.seen = false;
                    }
                }
                self.pending = true;
                self.expected = c;
                self.received = 0;
            }
            Some(_) if self.pending => {}
            Some(_) => {
                // Contact Count 0 and no frame under way: nobody touches.
                self.pending = true;
                self.expected = 0;
                self.received = 0;
            }
            None => {
                self.pending = true;
                self.expected = nfingers as u32;
                self.received = 0;
            }
        }
        for i in 0..nfingers {
            if self.received >= self.expected {
                break;
            }
            self.received += 1;
            let p = self.reports[index].fingers[i];
            self.slot(&p, bytes);
        }
        if self.received < self.expected {
            return Ok(false);
        }
        self.complete(t, count.is_some(), out);
        Ok(true)
    }

    /// Applies one finger slot.
    #[inline]
    fn slot(&mut self, p: &Plan, bytes: &[u8]) {
        let f = &p.finger;
        let flag = |field: Option<HidField>| field.map(|f| f.extract_raw(bytes).unwrap_or(0) != 0);
        let touching = flag(f.tip).or(flag(f.in_range)).unwrap_or(false);
        let hid_id = f.contact_id.extract_raw(bytes).unwrap_or(0);
        let palm = flag(f.confidence) == Some(false);
        let found = self.table[..self.len]
            .iter()
            .position(|e| !e.ended && e.hid_id == hid_id);
        if let Some(i) = found {
            if self.table[i].seen {
                self.counters.duplicate_contacts += 1;
                return;
            }
        }
        if !touching {
            if let Some(i) = found {
                let e = &mut self.table[i];
                e.ended = true;
                e.seen = true;
                if palm {
                    e.contact.flags.insert(ContactFlags::PALM);
                }
                self.counters.contacts_lifted += 1;
            }
            return;
        }
        let i = match found {
            Some(i) => i,
            None => {
                if self.active_contacts() >= self.max_contacts as usize || self.len >= TABLE {
                    self.counters.contacts_over_capacity += 1;
                    return;
                }
                let i = self.len;
                self.len += 1;
                self.table[i] = Entry {
                    hid_id,
                    contact: Contact {
                        id: ContactId(self.next_id),
                        ..Contact::default()
                    },
                    began: true,
                    ended: false,
                    seen: false,
                };
                self.next_id = self.next_id.wrapping_add(1);
                self.counters.contacts_begun += 1;
                i
            }
        };
        let (w, h) = (
            p.width.map(|l| l.apply(bytes).max(0.0) as f32),
            p.height.map(|l| l.apply(bytes).max(0.0) as f32),
        );
        let (major, minor) = match (w, h) {
            (Some(w), Some(h)) => (Some(w.max(h)), Some(w.min(h))),
            (Some(s), None) | (None, Some(s)) => (Some(s), None),
            (None, None) => (None, None),
        };
        let e = &mut self.table[i];
        e.seen = true;
        let c = &mut e.contact;
        c.x = p.x.apply(bytes).clamp(0.0, 1.0) as f32;
        c.y = p.y.apply(bytes).clamp(0.0, 1.0) as f32;
        c.pressure = p.pressure.map(|l| l.apply(bytes).clamp(0.0, 1.0) as f32);
        c.major_mm = major;
        c.minor_mm = minor;
        c.flags = if palm {
            ContactFlags::PALM
        } else {
            ContactFlags::NONE
        };
    }

    /// Completes the frame under way into `out`.
    fn complete(&mut self, t: Micros, not_seen_means_up: bool, out: &mut TouchFrame) {
        out.clear();
        out.t = t;
        self.counters.frames += 1;
        self.pending = false;
        self.expected = 0;
        self.received = 0;
        if not_seen_means_up {
            for e in &mut self.table[..self.len] {
                if !e.ended && !e.seen {
                    e.ended = true;
                    self.counters.contacts_not_seen += 1;
                }
            }
        }
        // Ended, begun, continuing.
        for pass in 0..3 {
            let mut i = 0;
            while i < self.len {
                let e = self.table[i];
                let this_pass = if e.ended {
                    0
                } else if e.began {
                    1
                } else {
                    2
                };
                if this_pass == pass {
                    let mut c = e.contact;
                    c.flags = ContactFlags(c.flags.0 & ContactFlags::PALM.0);
                    if e.began {
                        c.flags.insert(ContactFlags::DOWN);
                    }
                    if e.ended {
                        c.flags.insert(ContactFlags::UP);
                    }
                    if out.push(c).is_err() {
                        self.counters.frame_overflow += 1;
                        if e.began && !e.ended {
                            // Never delivered: forget it, so it cannot appear
                            // later without a DOWN. It comes back as a new
                            // contact in the next frame if still touching.
                            self.remove(i);
                            continue;
                        }
                    }
                }
                i += 1;
            }
        }
        // Drop the ended, clear the per-frame marks.
        let mut i = 0;
        while i < self.len {
            if self.table[i].ended {
                self.remove(i);
            } else {
                let e = &mut self.table[i];
                e.began = false;
                e.seen = false;
                i += 1;
            }
        }
    }

    /// Removes entry `i`, keeping the order of the others.
    fn remove(&mut self, i: usize) {
        if i < self.len {
            self.table.copy_within(i + 1..self.len, i);
            self.len -= 1;
        }
    }

    /// Ends every contact still down, as a frame of `CANCELLED` contacts at their
    /// last position; false (and `out` cleared) when none was down.
    ///
    /// A contact that ended in an unfinished frame is delivered as `UP`; one that
    /// began in it (never delivered) is dropped. The decoder is then idle.
    pub fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool {
        out.clear();
        out.t = t;
        let mut any = false;
        for e in &self.table[..self.len] {
            if e.began {
                continue;
            }
            let mut c = e.contact;
            c.flags = ContactFlags(c.flags.0 & ContactFlags::PALM.0);
            if e.ended {
                c.flags.insert(ContactFlags::UP);
            } else {
                c.flags.insert(ContactFlags::CANCELLED);
                self.counters.contacts_cancelled += 1;
            }
            any = true;
            if out.push(c).is_err() {
                self.counters.frame_overflow += 1;
            }
        }
        self.len = 0;
        self.pending = false;
        self.expected = 0;
        self.received = 0;
        any
    }
}
