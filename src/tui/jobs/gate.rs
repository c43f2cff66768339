//! A gate that background work waits at between its steps while it is held: background triage
//! waits at each volume while the open volume's own work runs.

use std::sync::{Arc, Condvar, Mutex, PoisonError};

/// Whether the gate is held, and how many wait at it; shared by clones.
#[derive(Clone, Default)]
pub struct Gate(Arc<(Mutex<State>, Condvar)>);

#[derive(Default)]
struct State {
    held: bool,
    waiting: usize,
}

impl Gate {
    /// Holds the gate (`true`) or lets everyone waiting at it through (`false`).
    pub fn hold(&self, held: bool) {
        let (state, changed) = &*self.0;
        state.lock().unwrap_or_else(PoisonError::into_inner).held = held;
        changed.notify_all();
    }

    /// Returns at once when the gate is open, else when it opens.
    pub fn wait(&self) {
        let (state, changed) = &*self.0;
        let mut s = state.lock().unwrap_or_else(PoisonError::into_inner);
        s.waiting += 1;
        while s.held {
            s = changed.wait(s).unwrap_or_else(PoisonError::into_inner);
        }
        s.waiting -= 1;
    }

    /// [`wait`](Self::wait), at most `limit`: whether the gate opened (else the time ran out).
    pub fn wait_at_most(&self, limit: std::time::Duration) -> bool {
        let (state, changed) = &*self.0;
        let mut s = state.lock().unwrap_or_else(PoisonError::into_inner);
        s.waiting += 1;
        let end = std::time::Instant::now() + limit;
        while s.held {
            let left = end.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                break;
            }
            s = changed
                .wait_timeout(s, left)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
        s.waiting -= 1;
        !s.held
    }

    /// Whether it is held.
    #[cfg(test)]
    pub fn held(&self) -> bool {
        self.0.0.lock().unwrap_or_else(PoisonError::into_inner).held
    }

    /// How many wait at it.
    #[cfg(test)]
    pub fn waiting(&self) -> usize {
        self.0
            .0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .waiting
    }
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc::{TryRecvError, channel};

    use super::*;

    #[test]
    fn work_waits_at_a_held_gate_until_it_opens() {
        let gate = Gate::default();
        gate.wait();
        gate.hold(true);
        assert!(gate.held());
        let (tx, rx) = channel();
        let waiter = gate.clone();
        let thread = std::thread::spawn(move || {
            waiter.wait();
            tx.send(()).unwrap();
        });
        // Until the worker waits at the gate (no clock: it gets there or the test hangs).
        while gate.waiting() == 0 {
            std::thread::yield_now();
        }
        assert_eq!(rx.try_recv(), Err(TryRecvError::Empty), "held: it waits");
        gate.hold(false);
        rx.recv().unwrap();
        thread.join().unwrap();
        assert_eq!(gate.waiting(), 0);
        // Held, a bounded wait ends when its time runs out, saying so.
        gate.hold(true);
        assert!(!gate.wait_at_most(std::time::Duration::from_millis(20)));
        gate.hold(false);
        assert!(gate.wait_at_most(std::time::Duration::from_secs(60)));
    }
}
