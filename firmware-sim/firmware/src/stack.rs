//! Stack high-water mark: cortex-m-rt paints all free RAM (`_stack_end`..`_stack_start`) with
//! [`cortex_m_rt::STACK_PAINT_VALUE`] at reset; the lowest word no longer painted is the
//! deepest the stack has grown.

unsafe extern "C" {
    static _stack_start: u32;
    static _stack_end: u32;
}

/// Bytes of stack used so far (deepest point since reset).
pub fn high_water_bytes() -> u32 {
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let bottom = core::ptr::addr_of!(_stack_end) as usize;
    let mut address = bottom;
    while address < top {
        // SAFETY: every word in `_stack_end.._stack_start` is RAM this program owns.
        let word = unsafe { core::ptr::read_volatile(address as *const u32) };
        if word != cortex_m_rt::STACK_PAINT_VALUE {
            break;
        }
        address += 4;
    }
    (top - address) as u32
}
