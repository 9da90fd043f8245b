//! Touch frames: the contacts of one input frame, as every source produces them.
//!
//! # Contact life cycle
//!
//! A frame lists every contact that is down, plus the ones that ended in this frame.
//! A contact first appears with [`ContactFlags::DOWN`], then in later frames with no
//! flag while it moves, and last with [`ContactFlags::UP`] (a deliberate lift) or
//! [`ContactFlags::CANCELLED`] (it vanished: device unplugged, resync after a
//! dropped buffer, shutdown). When frames are coalesced a contact may carry both
//! `DOWN` and `UP`: it began and ended between two delivered frames.

use super::time::Micros;
use serde::{Deserialize, Serialize};

/// The most contacts one frame holds. Large touch tables declare up to 60.
pub const MAX_CONTACTS: usize = 64;

/// The `device` of frames made from clients' `touch` commands (a viewer's mouse or
/// fingers): no input of the config has this index.
pub const CLIENT_DEVICE: u16 = u16::MAX;

/// A contact identifier, unique across devices and never reused while the daemon runs.
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct ContactId(pub u32);

/// Life-cycle and classification bits of a contact in one frame.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct ContactFlags(pub u8);

impl ContactFlags {
    /// No flag: the contact continues.
    pub const NONE: ContactFlags = ContactFlags(0);
    /// The contact began in this frame.
    pub const DOWN: ContactFlags = ContactFlags(1);
    /// The contact was lifted in this frame (deliberately).
    pub const UP: ContactFlags = ContactFlags(2);
    /// The contact ended without a clean lift (unplug, resync, shutdown).
    pub const CANCELLED: ContactFlags = ContactFlags(4);
    /// Firmware or size filter says this is a palm: not used for control.
    pub const PALM: ContactFlags = ContactFlags(8);

    /// Whether every bit of `other` is set.
    pub fn contains(self, other: ContactFlags) -> bool {
        self.0 & other.0 == other.0
    }
    /// Sets the bits of `other`.
    pub fn insert(&mut self, other: ContactFlags) {
        self.0 |= other.0;
    }
    /// Whether the contact ended in this frame (lifted or cancelled).
    pub fn ended(self) -> bool {
        self.0 & (Self::UP.0 | Self::CANCELLED.0) != 0
    }
}

impl std::ops::BitOr for ContactFlags {
    type Output = ContactFlags;
    fn bitor(self, rhs: ContactFlags) -> ContactFlags {
        ContactFlags(self.0 | rhs.0)
    }
}

/// One contact in surface coordinates (unit square, x right, y down).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Contact {
    /// Identifier, stable for the contact's life.
    pub id: ContactId,
    /// Horizontal position in `[0, 1]`.
    pub x: f32,
    /// Vertical position in `[0, 1]`.
    pub y: f32,
    /// Pressure in `[0, 1]` when the device reports it.
    pub pressure: Option<f32>,
    /// Contact ellipse major axis in millimetres, when reported.
    pub major_mm: Option<f32>,
    /// Contact ellipse minor axis in millimetres, when reported.
    pub minor_mm: Option<f32>,
    /// Life-cycle flags in this frame.
    pub flags: ContactFlags,
}

/// Error returned when a frame already holds [`MAX_CONTACTS`] contacts.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct FrameFull;

/// The contacts of one input frame with the time the kernel stamped it.
///
/// Fixed capacity, `Copy`, no heap: the input thread fills one in place and the
/// queue moves it by value.
#[derive(Copy, Clone, Debug)]
pub struct TouchFrame {
    /// Input timestamp (kernel event time on CLOCK_MONOTONIC; virtual in replays).
    pub t: Micros,
    /// When the input thread handed the frame to the queue (CLOCK_MONOTONIC).
    pub t_queued: Micros,
    /// Index of the source device (0 for a single device).
    pub device: u16,
    len: u8,
    contacts: [Contact; MAX_CONTACTS],
}

impl Default for TouchFrame {
    fn default() -> Self {
        TouchFrame::new(Micros::ZERO)
    }
}

impl PartialEq for TouchFrame {
    fn eq(&self, other: &Self) -> bool {
        self.t == other.t && self.device == other.device && self.contacts() == other.contacts()
    }
}

impl TouchFrame {
    /// An empty frame at time `t`.
    pub fn new(t: Micros) -> TouchFrame {
        TouchFrame {
            t,
            t_queued: Micros::ZERO,
            device: 0,
            len: 0,
            contacts: [Contact::default(); MAX_CONTACTS],
        }
    }

    /// The contacts, in insertion order.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts[..self.len as usize]
    }

    /// The contacts, mutable.
    pub fn contacts_mut(&mut self) -> &mut [Contact] {
        &mut self.contacts[..self.len as usize]
    }

    /// Number of contacts.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the frame holds no contact.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Removes every contact, keeping the time.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends a contact.
    ///
    /// # Errors
    /// [`FrameFull`] when the frame already holds [`MAX_CONTACTS`].
    pub fn push(&mut self, c: Contact) -> Result<(), FrameFull> {
        if self.len as usize >= MAX_CONTACTS {
            return Err(FrameFull);
        }
        self.contacts[self.len as usize] = c;
        self.len += 1;
        Ok(())
    }

    /// Whether the frame changes which contacts are down (a touch began or ended).
    ///
    /// Frames that only move contacts may be coalesced; these may not.
    pub fn has_transitions(&self) -> bool {
        self.contacts()
            .iter()
            .any(|c| c.flags.contains(ContactFlags::DOWN) || c.flags.ended())
    }

    /// Folds a later frame into this one, as if both had been delivered together.
    ///
    /// Positions come from `later`; life-cycle flags of both are kept, so a contact
    /// that began in `self` and ended in `later` carries `DOWN | UP`. Contacts that
    /// ended in `self` and are absent from `later` stay, so no lift is lost.
    ///
    /// # Errors
    /// [`FrameFull`] when the union has more than [`MAX_CONTACTS`] contacts; the
    /// contacts that fit are merged, transitions first.
    pub fn merge_later(&mut self, later: &TouchFrame) -> Result<(), FrameFull> {
        let mut result = Ok(());
        self.t = later.t;
        self.t_queued = later.t_queued;
        for c in later.contacts() {
            if let Some(mine) = self.contacts_mut().iter_mut().find(|m| m.id == c.id) {
                let flags = mine.flags | c.flags;
                *mine = *c;
                mine.flags = flags;
            } else if self.push(*c).is_err() {
                result = Err(FrameFull);
            }
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(id: u32, x: f32, flags: ContactFlags) -> Contact {
        Contact {
            id: ContactId(id),
            x,
            y: 0.5,
            flags,
            ..Contact::default()
        }
    }

    #[test]
    fn merge_keeps_down_and_up() {
        let mut a = TouchFrame::new(Micros(10));
        a.push(c(1, 0.1, ContactFlags::DOWN)).unwrap();
        a.push(c(2, 0.2, ContactFlags::UP)).unwrap();
        let mut b = TouchFrame::new(Micros(20));
        b.push(c(1, 0.3, ContactFlags::UP)).unwrap();
        b.push(c(3, 0.4, ContactFlags::DOWN)).unwrap();
        a.merge_later(&b).unwrap();
        assert_eq!(a.t, Micros(20));
        let got: Vec<_> = a
            .contacts()
            .iter()
            .map(|c| (c.id.0, c.x, c.flags))
            .collect();
        assert_eq!(
            got,
            vec![
                (1, 0.3, ContactFlags::DOWN | ContactFlags::UP),
                (2, 0.2, ContactFlags::UP),
                (3, 0.4, ContactFlags::DOWN)
            ]
        );
    }

    #[test]
    fn push_past_capacity_is_refused() {
        let mut f = TouchFrame::new(Micros(0));
        for i in 0..MAX_CONTACTS as u32 {
            f.push(c(i, 0.0, ContactFlags::NONE)).unwrap();
        }
        assert_eq!(f.push(c(999, 0.0, ContactFlags::NONE)), Err(FrameFull));
        assert_eq!(f.len(), MAX_CONTACTS);
    }
}
