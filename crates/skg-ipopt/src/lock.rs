//! The process-wide lock that serializes every use of Ipopt (Ipopt 3.11 with sequential
//! MUMPS keeps process-global state), and the per-thread guard that refuses a solve
//! started from inside a callback of another solve instead of deadlocking on that lock.

use std::cell::Cell;
use std::sync::{Mutex, MutexGuard};

#[cfg(doc)]
use crate::solve;

/// Serializes every use of Ipopt in the process (it is not thread-safe).
static IPOPT_LOCK: Mutex<()> = Mutex::new(());

thread_local! {
    /// Whether this thread is inside [`solve`] (to refuse nested solves instead of
    /// deadlocking on [`IPOPT_LOCK`]).
    static IN_SOLVE: Cell<bool> = const { Cell::new(false) };
}

/// Marks this thread as inside [`solve`] while alive.
pub(crate) struct NestGuard;

impl NestGuard {
    pub(crate) fn enter() -> Option<Self> {
        IN_SOLVE.with(|flag| if flag.replace(true) { None } else { Some(NestGuard) })
    }
}

impl Drop for NestGuard {
    fn drop(&mut self) {
        IN_SOLVE.with(|flag| flag.set(false));
    }
}

/// Acquires [`IPOPT_LOCK`], recovering from poisoning (the guarded data is `()`, and a
/// panic never leaves Ipopt itself half-way: callbacks catch them).
pub(crate) fn lock_ipopt() -> MutexGuard<'static, ()> {
    IPOPT_LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}
