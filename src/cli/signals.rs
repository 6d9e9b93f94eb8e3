//! SIGINT/SIGTERM and the command's thread: the command runs on a thread of its own while the
//! main thread watches for a signal, so that every phase stops within [`SIGNAL_POLL_S`].

use super::EXIT_INTERNAL_ERROR;
use crate::report::EXIT_FAIL;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

/// Set by SIGINT or SIGTERM: the running scenario stops at its next tick, the reports of what
/// ran are written, and the batch stops.
pub static CANCEL: AtomicBool = AtomicBool::new(false);

/// Set while the command runs a phase that stops by itself on [`CANCEL`] (the scenarios' runs and
/// the writing of their reports). In every other phase (parsing, an analytic solve, findings,
/// figures) a signal ends the command within [`SIGNAL_POLL_S`]: its temporary files are
/// removed, its outputs stay as they were, exit 1.
static STOPS_ITSELF: AtomicBool = AtomicBool::new(false);

/// How often the main thread looks for a signal while the command's thread works [s].
const SIGNAL_POLL_S: f64 = 0.05;

/// Stack of the command's thread [bytes] (the main thread's usual 8 MiB, with room).
const COMMAND_STACK_BYTES: usize = 64 << 20;

extern "C" fn on_signal(_signal: libc::c_int) {
    CANCEL.store(true, Ordering::SeqCst);
}

/// SIGINT and SIGTERM set [`CANCEL`]; a closed pipe (`tensegrity list | head -1`) ends the
/// process quietly, as it does any Unix filter, instead of a panic in println!.
pub fn install_handlers() {
    let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe; SIGPIPE gets
    // its default disposition back before any thread starts.
    unsafe {
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// From here on the command stops by itself at its next tick on a signal and writes what ran.
pub fn stops_itself_from_now() {
    STOPS_ITSELF.store(true, Ordering::SeqCst);
}

/// Whether a signal came.
pub fn cancelled() -> bool {
    CANCEL.load(Ordering::SeqCst)
}

/// Runs `command` on its own thread and returns its exit code, or exit 1 within
/// [`SIGNAL_POLL_S`] of a signal in a phase that does not stop by itself (its temporary files
/// removed), or [`EXIT_INTERNAL_ERROR`] when it panicked (its message is printed).
pub fn run_stoppable(command: impl FnOnce() -> u8 + Send + 'static) -> u8 {
    let (tx, rx) = std::sync::mpsc::channel();
    let worker = std::thread::Builder::new().stack_size(COMMAND_STACK_BYTES).spawn(move || {
        let _ = tx.send(command());
    });
    if let Err(e) = worker {
        eprintln!("error: cannot start the command's thread: {e}");
        return EXIT_FAIL as u8;
    }
    loop {
        match rx.recv_timeout(Duration::from_secs_f64(SIGNAL_POLL_S)) {
            Ok(code) => return code,
            Err(RecvTimeoutError::Timeout) => {
                if cancelled() && !STOPS_ITSELF.load(Ordering::SeqCst) {
                    crate::output::remove_partials();
                    eprintln!("interrupted");
                    return EXIT_FAIL as u8;
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                crate::output::remove_partials();
                return EXIT_INTERNAL_ERROR;
            }
        }
    }
}
