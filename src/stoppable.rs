//! Work on a thread of its own, waited for one poll at a time so that the waiting thread can
//! stop waiting: the command of the CLI (on SIGINT or SIGTERM), a run's analytic computations
//! (on its cancel flag) and the Python package's runs (on Ctrl-C) all wait this way.
//!
//! (Its own module, below `run` and `eigen` both: a dense eigenproblem waits this way too.)

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::Mutex;
use std::thread::JoinHandle;
use std::time::Duration;

/// How often a waiting thread looks for a reason to stop while the work runs \[s\].
pub const POLL_S: f64 = 0.05;

/// Why work on a thread of its own gave no result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Halted {
    /// The waiter stopped waiting (a signal, a cancel flag).
    #[error("interrupted")]
    Interrupted,
    /// The work's thread panicked.
    #[error("panicked")]
    Panicked,
}

/// Work running on a thread of its own, its result awaited one poll ([`POLL_S`]) at a time.
pub struct Stoppable<T> {
    /// In a mutex so that the waiter may poll from any thread (the Python package polls
    /// without the GIL).
    result: Mutex<Receiver<T>>,
    thread: JoinHandle<()>,
}

impl<T: Send + 'static> Stoppable<T> {
    /// Starts `work` on a thread of its own with `stack_bytes` of stack (None: the default).
    pub fn spawn(stack_bytes: Option<usize>, work: impl FnOnce() -> T + Send + 'static) -> std::io::Result<Self> {
        let (tx, rx) = mpsc::channel();
        let builder = std::thread::Builder::new();
        let builder = match stack_bytes {
            Some(bytes) => builder.stack_size(bytes),
            None => builder,
        };
        let thread = builder.spawn(move || {
            // The receiver is gone only when its waiter stopped waiting: nobody wants the result.
            let _ = tx.send(work());
        })?;
        Ok(Stoppable { result: Mutex::new(rx), thread })
    }

    /// Waits up to [`POLL_S`] for the result: `Some` the result, `None` still working, or
    /// [`Halted::Panicked`].
    pub fn poll(&self) -> Result<Option<T>, Halted> {
        let result = self.result.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        match result.recv_timeout(Duration::from_secs_f64(POLL_S)) {
            Ok(value) => Ok(Some(value)),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => Err(Halted::Panicked),
        }
    }

    /// Waits for the result, asking `stop` after every poll that brought none:
    /// [`Halted::Interrupted`] as soon as it says so (the thread is left to finish on its own,
    /// or to end with the process).
    pub fn wait(&self, mut stop: impl FnMut() -> bool) -> Result<T, Halted> {
        loop {
            if let Some(value) = self.poll()? {
                return Ok(value);
            }
            if stop() {
                return Err(Halted::Interrupted);
            }
        }
    }

    /// Waits for the thread to end (after its result, or once the flag it watches is raised).
    pub fn join(self) {
        let _ = self.thread.join();
    }
}

/// Runs `f` on a thread of its own and waits for its result, looking at `cancel` every
/// [`POLL_S`]: [`Halted::Interrupted`] when cancelled first (the thread is left to finish on
/// its own, or to end with the process), [`Halted::Panicked`] when it panicked. Analytic
/// computations (findings, solves) have no ticks to stop at; this makes them interruptible
/// without threading a flag through every model.
pub fn interruptible<T: Send + 'static>(
    cancel: Option<&AtomicBool>,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, Halted> {
    let Some(cancel) = cancel else { return Ok(f()) };
    let cancelled = || cancel.load(Ordering::SeqCst);
    if cancelled() {
        return Err(Halted::Interrupted);
    }
    Stoppable::spawn(None, f).expect("a thread starts").wait(cancelled)
}
