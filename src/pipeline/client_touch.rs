//! Touches sent by clients (`touch` commands: a viewer page's mouse or fingers),
//! turned into touch frames on the control thread.
//!
//! Each client is a virtual surface covering the table (`client <id>`). A
//! `touch` command lists the contacts it has down now, in table units: a new id
//! begins (`DOWN`), a known one moves, one no longer listed is lifted (`UP`). The
//! frame is stamped at receipt and fed to the engine as a device's frame is.
//! Contacts get daemon-wide ids from the input counters, so they never collide
//! with a device's. A client whose last `touch` is older than
//! [`CLIENT_TOUCH_TIMEOUT_US`] has its contacts ended (`CANCELLED`): a page that
//! holds a finger still must repeat its contacts; a client that disconnects is
//! ended at once (the socket sends an empty `touch` on its behalf).

use super::queue::InputCounters;
use crate::vocab::{
    ClientContact, ClientId, Contact, ContactFlags, ContactId, Micros, TouchFrame,
    MAX_CLIENT_CONTACTS,
};
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// A client silent this long (µs) with contacts down has them ended.
pub const CLIENT_TOUCH_TIMEOUT_US: u64 = 1_000_000;

/// Most clients touching at once; a further one is refused until one ends.
pub const MAX_TOUCHING_CLIENTS: usize = 16;

#[derive(Debug)]
struct Touching {
    client: ClientId,
    /// (client's id, daemon id, x, y) of the contacts down.
    down: Vec<(u32, u32, f32, f32)>,
    last: Micros,
}

/// Every client's contacts; see the module doc.
#[derive(Debug)]
pub struct ClientTouches {
    clients: Vec<Touching>,
    counters: Arc<InputCounters>,
    frame: TouchFrame,
}

impl ClientTouches {
    /// Contact ids come from `counters` (shared with the input queues).
    pub fn new(counters: Arc<InputCounters>) -> ClientTouches {
        let mut frame = TouchFrame::default();
        frame.device = crate::vocab::CLIENT_DEVICE;
        ClientTouches {
            clients: Vec::with_capacity(MAX_TOUCHING_CLIENTS),
            counters,
            frame,
        }
    }

    /// Contacts down, over every client.
    #[cfg(test)]
    fn active_contacts(&self) -> usize {
        self.clients.iter().map(|c| c.down.len()).sum()
    }

    /// Applies `client`'s touch command at `now`: the frame it makes goes to `feed`.
    ///
    /// # Errors
    /// A message for the client when [`MAX_TOUCHING_CLIENTS`] others are touching.
    pub fn touch(
        &mut self,
        client: ClientId,
        contacts: &[ClientContact],
        now: Micros,
        feed: &mut dyn FnMut(&TouchFrame),
    ) -> Result<(), String> {
        let i = match self.clients.iter().position(|c| c.client == client) {
            Some(i) => i,
            None if contacts.is_empty() => return Ok(()),
            None if self.clients.len() >= MAX_TOUCHING_CLIENTS => {
                return Err(format!(
                    "busy: {MAX_TOUCHING_CLIENTS} clients are touching the table; try again"
                ))
            }
            None => {
                self.clients.push(Touching {
                    client,
                    down: Vec::with_capacity(MAX_CLIENT_CONTACTS),
                    last: now,
                });
                self.clients.len() - 1
            }
        };
        let f = &mut self.frame;
        f.clear();
        f.t = now;
        f.t_queued = now;
        let c = &mut self.clients[i];
        c.last = now;
        c.down.retain(|&(id, daemon, x, y)| {
            let kept = contacts.iter().any(|k| k.id == id);
            if !kept {
                let _ = f.push(contact(daemon, x, y, ContactFlags::UP));
            }
            kept
        });
        // The parser caps the list at MAX_CLIENT_CONTACTS (10): it and the lifts fit.
        for k in contacts.iter().take(MAX_CLIENT_CONTACTS) {
            let (x, y) = (k.x.clamp(0.0, 1.0) as f32, k.y.clamp(0.0, 1.0) as f32);
            let flags = match c.down.iter_mut().find(|d| d.0 == k.id) {
                Some(d) => {
                    (d.2, d.3) = (x, y);
                    let _ = f.push(contact(d.1, x, y, ContactFlags::NONE));
                    continue;
                }
                None => ContactFlags::DOWN,
            };
            let daemon = self
                .counters
                .last_contact_id
                .fetch_add(1, Ordering::Relaxed)
                .wrapping_add(1);
            c.down.push((k.id, daemon, x, y));
            let _ = f.push(contact(daemon, x, y, flags));
        }
        if c.down.is_empty() {
            self.clients.swap_remove(i);
        }
        if !self.frame.is_empty() {
            self.counters.frames.fetch_add(1, Ordering::Relaxed);
            feed(&self.frame);
        }
        Ok(())
    }

    /// Ends (`CANCELLED`) the contacts of every client silent for longer than
    /// [`CLIENT_TOUCH_TIMEOUT_US`] at `now`.
    pub fn expire(&mut self, now: Micros, feed: &mut dyn FnMut(&TouchFrame)) {
        let mut i = 0;
        while i < self.clients.len() {
            let c = &self.clients[i];
            if now.saturating_since(c.last).0 <= CLIENT_TOUCH_TIMEOUT_US {
                i += 1;
                continue;
            }
            log::info!(
                "client {}: no touch for {} ms: its {} contacts are lifted",
                c.client,
                CLIENT_TOUCH_TIMEOUT_US / 1000,
                c.down.len()
            );
            self.frame.clear();
            self.frame.t = now;
            self.frame.t_queued = now;
            for &(_, daemon, x, y) in &c.down {
                let _ = self
                    .frame
                    .push(contact(daemon, x, y, ContactFlags::CANCELLED));
            }
            self.clients.swap_remove(i);
            feed(&self.frame);
        }
    }
}

fn contact(id: u32, x: f32, y: f32, flags: ContactFlags) -> Contact {
    Contact {
        id: ContactId(id),
        x,
        y,
        flags,
        ..Contact::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(id: u32, x: f64, y: f64) -> ClientContact {
        ClientContact { id, x, y }
    }

    fn run(
        t: &mut ClientTouches,
        client: u64,
        c: &[ClientContact],
        now: u64,
    ) -> Vec<(u32, f32, ContactFlags)> {
        let mut out = vec![];
        t.touch(client, c, Micros(now), &mut |f| {
            out.extend(f.contacts().iter().map(|c| (c.id.0, c.x, c.flags)))
        })
        .unwrap();
        out
    }

    #[test]
    fn contacts_begin_move_and_lift_per_client() {
        let counters = Arc::new(InputCounters::default());
        counters.last_contact_id.store(41, Ordering::Relaxed);
        let mut t = ClientTouches::new(Arc::clone(&counters));
        assert_eq!(
            run(&mut t, 1, &[at(0, 0.5, 0.5)], 0),
            vec![(42, 0.5, ContactFlags::DOWN)]
        );
        // Another client's id 0 is another contact.
        assert_eq!(
            run(&mut t, 2, &[at(0, 0.1, 0.1)], 1),
            vec![(43, 0.1, ContactFlags::DOWN)]
        );
        assert_eq!(
            run(&mut t, 1, &[at(0, 0.6, 0.5), at(7, 0.2, 0.2)], 2),
            vec![(42, 0.6, ContactFlags::NONE), (44, 0.2, ContactFlags::DOWN)]
        );
        assert_eq!(
            run(&mut t, 1, &[], 3),
            vec![(42, 0.6, ContactFlags::UP), (44, 0.2, ContactFlags::UP)]
        );
        assert_eq!(t.active_contacts(), 1);
        // Client 2 falls silent: ended after the timeout, not before.
        let mut out = vec![];
        t.expire(Micros(1 + CLIENT_TOUCH_TIMEOUT_US), &mut |f| out.push(*f));
        assert!(out.is_empty());
        t.expire(Micros(2 + CLIENT_TOUCH_TIMEOUT_US), &mut |f| out.push(*f));
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].contacts()[0].flags, ContactFlags::CANCELLED);
        assert_eq!(t.active_contacts(), 0);
    }
}
