//! A `static` that hands out its `&'static mut` exactly once: how the firmware owns its large
//! buffers (the blob, the models) without a heap and without `static mut`.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

/// Storage for one `T`, borrowed mutably at most once for the program's life.
pub struct Slot<T> {
    value: UnsafeCell<T>,
    taken: AtomicBool,
}

// SAFETY: the only access is through `take`, which succeeds once.
unsafe impl<T> Sync for Slot<T> {}

impl<T> Slot<T> {
    /// A slot holding `value`.
    pub const fn new(value: T) -> Self {
        Slot {
            value: UnsafeCell::new(value),
            taken: AtomicBool::new(false),
        }
    }

    /// The value, the first time; `None` afterwards.
    pub fn take(&'static self) -> Option<&'static mut T> {
        if self.taken.swap(true, Ordering::AcqRel) {
            None
        } else {
            // SAFETY: `taken` was false, so no other reference to the value exists, and none
            // will be created.
            Some(unsafe { &mut *self.value.get() })
        }
    }
}
