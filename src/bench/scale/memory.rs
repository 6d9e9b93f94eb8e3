//! Heap bytes of one scale case: a counting wrapper of the system allocator.
//!
//! The resident set (`VmRSS`, `VmHWM`) keeps heap that an earlier case freed (the allocator
//! does not hand it back), so it hides a case's own growth. [`CountingAllocator`], installed as
//! the binary's global allocator (`src/main.rs`), counts the bytes allocated minus the bytes
//! freed while a measurement runs, and their peak: the largest heap a case needed beyond what
//! was live before it. Outside a measurement it adds one relaxed atomic load per allocation.
//! Where it is not installed (the test binaries) [`Measurement::stop`] returns None.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicI64, AtomicU64, Ordering::Relaxed};

static COUNTING: AtomicBool = AtomicBool::new(false);
static LIVE_BYTES: AtomicI64 = AtomicI64::new(0);
static PEAK_BYTES: AtomicI64 = AtomicI64::new(0);
static CALLS: AtomicU64 = AtomicU64::new(0);

/// The system allocator, counting while a [`Measurement`] runs.
pub struct CountingAllocator;

fn grow(bytes: i64) {
    if COUNTING.load(Relaxed) {
        CALLS.fetch_add(1, Relaxed);
        let live = LIVE_BYTES.fetch_add(bytes, Relaxed) + bytes;
        PEAK_BYTES.fetch_max(live, Relaxed);
    }
}

// SAFETY: every call is forwarded unchanged to `System`; the counters only read the layouts.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc`, passed on.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grow(layout.size() as i64);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc_zeroed`, passed on.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grow(layout.size() as i64);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract for `dealloc`, passed on.
        unsafe { System.dealloc(ptr, layout) };
        grow(-(layout.size() as i64));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract for `realloc`, passed on.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            grow(new_size as i64 - layout.size() as i64);
        }
        p
    }
}

/// One measurement (single-threaded use: the scale bench settles one case at a time).
pub struct Measurement;

impl Measurement {
    /// Starts counting from zero.
    pub fn start() -> Self {
        LIVE_BYTES.store(0, Relaxed);
        PEAK_BYTES.store(0, Relaxed);
        CALLS.store(0, Relaxed);
        COUNTING.store(true, Relaxed);
        Measurement
    }

    /// Stops counting: the peak of (allocated - freed) bytes since the start, None if no
    /// allocation was counted (the allocator is not installed).
    pub fn stop(self) -> Option<u64> {
        COUNTING.store(false, Relaxed);
        (CALLS.load(Relaxed) > 0).then(|| PEAK_BYTES.load(Relaxed).max(0) as u64)
    }
}
