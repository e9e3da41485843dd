//! [`Outbox`]: what one tab's websocket writer sends next — latest-only
//! slots gated by the interaction sequence number.
//!
//! Model: the session's reader records every interaction (`seq`) here
//! before anything else; renders offer their images and messages tagged
//! with the `seq` they were made for. Each kind of message has one slot
//! that keeps only the newest (ack, state, error, scene file, keyframes,
//! preview, image, histogram, progress), so a client that reads slowly gets
//! fewer, newer messages instead of a growing backlog, and a render never
//! waits for a socket.
//!
//! Invariants (all under one lock):
//! - an offer whose `seq` is older than the latest recorded interaction is
//!   dropped, and recording an interaction empties the slots holding older
//!   messages — so once the writer has sent `ack n`, no message for an
//!   interaction before `n` follows it;
//! - the writer takes one message at a time, acks first, and sends it
//!   before taking the next, so the order on the wire is the order of the
//!   slots' updates under the lock.

use std::sync::Mutex;

use tokio::sync::Notify;

/// One outgoing websocket message.
#[derive(Clone, Debug, PartialEq)]
pub enum Outgoing {
    Text(String),
    Binary(Vec<u8>),
}

/// The slots a message can take (in the order the writer empties them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    Ack = 0,
    State = 1,
    Error = 2,
    Scene = 3,
    /// The keyframe list (camera paths).
    Keyframes = 4,
    /// A path preview's start and end.
    Preview = 5,
    Image = 6,
    Histogram = 7,
    Progress = 8,
}

const SLOTS: usize = 9;

#[derive(Default)]
struct Inner {
    latest: u64,
    slots: [Option<(u64, Outgoing)>; SLOTS],
    closed: bool,
}

/// See the module docs.
#[derive(Default)]
pub struct Outbox {
    inner: Mutex<Inner>,
    notify: Notify,
}

impl Outbox {
    pub fn new() -> Self {
        Outbox::default()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic elsewhere must not take the tab down with a poisoned lock.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records interaction `seq` (ignored unless newer than the latest; the
    /// first is ≥ 1),
    /// drops older messages and queues `ack`. Returns whether it was newer.
    pub fn interaction(&self, seq: u64, ack: Outgoing) -> bool {
        let mut g = self.lock();
        if seq <= g.latest {
            return false;
        }
        g.latest = seq;
        for s in g.slots.iter_mut() {
            if s.as_ref().is_some_and(|(q, _)| *q < seq) {
                *s = None;
            }
        }
        g.slots[Slot::Ack as usize] = Some((seq, ack));
        drop(g);
        self.notify.notify_one();
        true
    }

    /// The latest interaction recorded.
    pub fn latest(&self) -> u64 {
        self.lock().latest
    }

    /// Offers a message made for interaction `seq`; dropped (false) when a
    /// newer interaction was recorded since.
    pub fn offer(&self, slot: Slot, seq: u64, message: Outgoing) -> bool {
        let mut g = self.lock();
        if seq < g.latest || g.closed {
            return false;
        }
        g.slots[slot as usize] = Some((seq, message));
        drop(g);
        self.notify.notify_one();
        true
    }

    /// Whether `seq` is still the latest interaction (a render for an older
    /// one may stop).
    pub fn is_current(&self, seq: u64) -> bool {
        let g = self.lock();
        seq >= g.latest && !g.closed
    }

    /// Closes the outbox: offers are dropped and [`Outbox::next`] returns
    /// `None`.
    pub fn close(&self) {
        self.lock().closed = true;
        self.notify.notify_one();
    }

    pub fn is_closed(&self) -> bool {
        self.lock().closed
    }

    /// Takes the next message, if any (acks first).
    pub fn try_next(&self) -> Option<Outgoing> {
        let mut g = self.lock();
        g.slots.iter_mut().find_map(Option::take).map(|(_, m)| m)
    }

    /// Waits for the next message; `None` once closed.
    pub async fn next(&self) -> Option<Outgoing> {
        loop {
            // A notification sent between `try_next` and the wait is kept
            // as a permit by `Notify`, so no wake-up is lost.
            if self.is_closed() {
                return None;
            }
            if let Some(m) = self.try_next() {
                return Some(m);
            }
            self.notify.notified().await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(s: &str) -> Outgoing {
        Outgoing::Text(s.into())
    }

    #[test]
    fn older_images_are_dropped_once_a_newer_interaction_is_recorded() {
        let o = Outbox::new();
        assert!(o.interaction(1, text("ack1")));
        assert!(o.offer(Slot::Image, 1, text("img1")));
        assert!(o.interaction(2, text("ack2")));
        // The image of 1 was waiting: gone; a late image of 1: refused.
        assert!(!o.offer(Slot::Image, 1, text("late1")));
        assert_eq!(o.try_next(), Some(text("ack2")));
        assert_eq!(o.try_next(), None);
        assert!(o.offer(Slot::Image, 2, text("img2")));
        assert_eq!(o.try_next(), Some(text("img2")));
    }

    #[test]
    fn a_slot_keeps_only_the_newest_message() {
        let o = Outbox::new();
        o.interaction(1, text("ack"));
        o.offer(Slot::Progress, 1, text("p1"));
        o.offer(Slot::Progress, 1, text("p2"));
        assert_eq!(o.try_next(), Some(text("ack")));
        assert_eq!(o.try_next(), Some(text("p2")));
        assert_eq!(o.try_next(), None);
    }

    #[test]
    fn repeated_or_older_sequence_numbers_are_ignored() {
        let o = Outbox::new();
        assert!(o.interaction(5, text("a")));
        assert!(!o.interaction(5, text("b")));
        assert!(!o.interaction(3, text("c")));
        assert_eq!(o.latest(), 5);
    }
}
