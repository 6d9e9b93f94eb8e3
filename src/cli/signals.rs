//! SIGINT/SIGTERM and the command's thread: the command runs on a thread of its own while the
//! main thread watches for a signal, so that every phase stops within
//! [`crate::run::stoppable::POLL_S`].

use super::EXIT_INTERNAL_ERROR;
use crate::report::EXIT_FAIL;
use crate::run::stoppable::{Halted, Stoppable};
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by SIGINT or SIGTERM: the running scenario stops at its next tick, the reports of what
/// ran are written, and the batch stops.
pub static CANCEL: AtomicBool = AtomicBool::new(false);

/// Set while the command runs a phase that stops by itself on [`CANCEL`] (the scenarios' runs and
/// the writing of their reports). In every other phase (parsing, an analytic solve, findings,
/// figures) a signal ends the command within [`crate::run::stoppable::POLL_S`]: its temporary files are
/// removed, its outputs stay as they were, exit 1.
static STOPS_ITSELF: AtomicBool = AtomicBool::new(false);

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
/// [`crate::run::stoppable::POLL_S`] of a signal in a phase that does not stop by itself (its temporary files
/// removed), or [`EXIT_INTERNAL_ERROR`] when it panicked (its message is printed).
pub fn run_stoppable(command: impl FnOnce() -> u8 + Send + 'static) -> u8 {
    let work = match Stoppable::spawn(Some(COMMAND_STACK_BYTES), command) {
        Ok(work) => work,
        Err(e) => {
            eprintln!("error: cannot start the command's thread: {e}");
            return EXIT_FAIL as u8;
        }
    };
    match work.wait(|| cancelled() && !STOPS_ITSELF.load(Ordering::SeqCst)) {
        Ok(code) => code,
        Err(Halted::Interrupted) => {
            crate::output::remove_partials();
            eprintln!("interrupted");
            EXIT_FAIL as u8
        }
        Err(Halted::Panicked) => {
            crate::output::remove_partials();
            EXIT_INTERNAL_ERROR
        }
    }
}
