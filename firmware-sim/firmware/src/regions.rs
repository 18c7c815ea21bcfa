//! Markers around timed code: the instruction-counting QEMU plugin counts guest instructions
//! between a call to [`neurosurf_region_start`] and the next call to [`neurosurf_region_stop`].
//! They are never inlined, their bodies differ (else LLVM merges them into one symbol), and
//! each makes a volatile store (else LLVM deletes calls to functions without effects).

use core::sync::atomic::AtomicU32;

static MARK: AtomicU32 = AtomicU32::new(0);

/// Opens a timed region.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "C" fn neurosurf_region_start() {
    mark(0x5354_4152);
}

/// Closes the timed region.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "C" fn neurosurf_region_stop() {
    mark(0x5354_4f50);
}

#[inline(always)]
fn mark(value: u32) {
    // SAFETY: MARK is a valid, aligned u32; the firmware is single-threaded.
    unsafe { core::ptr::write_volatile(MARK.as_ptr(), value) }
}

/// Runs `f` inside a timed region.
#[inline(always)]
pub fn timed<T>(f: impl FnOnce() -> T) -> T {
    neurosurf_region_start();
    let out = core::hint::black_box(f());
    neurosurf_region_stop();
    out
}
