//! A time budget for work inside the driver, which nothing else can interrupt.
//!
//! Building a pipeline runs the driver's shader compiler synchronously: lavapipe compiled a
//! 130-byte shader that fills a 65,536-element local array in a loop for more than 900 s, and a
//! 20,000-case switch for more than 120 s. wgpu offers no way to cancel either. A program that
//! must not hang — the `gdsky` command line — sets a [`DriverBudget`] once; every pipeline build
//! and every wait for a render is then watched by a thread that calls the budget's `expired`
//! when the work outlives the limit. `expired` cannot return into the stuck call: the CLI's
//! prints the error and ends the process (exit 1). Without a budget (a library user's own
//! program, the tests) nothing is watched, and the render's own poll timeout still applies.

use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::Duration;

/// What happens when work in the driver passes its limit.
#[derive(Clone, Copy, Debug)]
pub struct DriverBudget {
    /// How long one pipeline build, or one render's wait, may take.
    pub limit: Duration,
    /// Called on a watcher thread with what was being done and the limit; it does not return
    /// (it ends the process), since the call it watches cannot be interrupted.
    pub expired: fn(&str, Duration) -> !,
}

static BUDGET: OnceLock<DriverBudget> = OnceLock::new();

/// Sets the process's budget, once; a second call is ignored (returns `false`).
pub fn set_driver_budget(budget: DriverBudget) -> bool {
    BUDGET.set(budget).is_ok()
}

/// Runs `work` (described by `what`, computed only when the budget expires) under the budget.
pub(crate) fn watched<T>(what: impl FnOnce() -> String + Send + 'static, work: impl FnOnce() -> T) -> T {
    let Some(budget) = BUDGET.get().copied() else {
        return work();
    };
    let done = Arc::new((Mutex::new(false), Condvar::new()));
    let watcher = {
        let done = Arc::clone(&done);
        std::thread::Builder::new().name("gdsky-driver-watchdog".into()).spawn(move || {
            let (flag, signal) = &*done;
            let guard = flag.lock().unwrap_or_else(|p| p.into_inner());
            let (guard, timeout) = signal
                .wait_timeout_while(guard, budget.limit, |finished| !*finished)
                .unwrap_or_else(|p| p.into_inner());
            if timeout.timed_out() && !*guard {
                drop(guard);
                (budget.expired)(&what(), budget.limit);
            }
        })
    };
    let result = work();
    let (flag, signal) = &*done;
    *flag.lock().unwrap_or_else(|p| p.into_inner()) = true;
    signal.notify_all();
    if let Ok(handle) = watcher {
        let _ = handle.join();
    }
    result
}
