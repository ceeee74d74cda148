//! The painted stack, shared by the firmware and the step-bench images: the stack below the
//! live frames is filled with a pattern, and the lowest word no longer holding it marks the
//! deepest the stack has reached since.

/// The pattern painted.
const PAINT: u32 = 0xCCCC_CCCC;

/// Bytes left unpainted below the stack pointer: the painting function's own frame.
const MARGIN: usize = 256;

// SAFETY: the linker script defines both symbols; only their addresses are taken.
#[allow(unsafe_code)]
unsafe extern "C" {
    static _stack_start: u32;
    static _stack_end: u32;
}

/// The stack's (bottom, top) addresses.
pub fn bounds() -> (usize, usize) {
    (
        core::ptr::addr_of!(_stack_end) as usize,
        core::ptr::addr_of!(_stack_start) as usize,
    )
}

/// Paint the stack from its bottom to [`MARGIN`] below `sp`, the caller's stack pointer.
#[inline(always)]
#[allow(unsafe_code)]
pub fn paint_below(sp: usize) {
    let (bottom, _) = bounds();
    let mut p = bottom;
    while p + MARGIN < sp {
        // SAFETY: [bottom, sp - MARGIN) is stack below every live frame, mapped RAM.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// The lowest stack address written since the last paint, looking no lower than `from`.
#[allow(unsafe_code)]
pub fn lowest_written(from: usize) -> usize {
    let (bottom, top) = bounds();
    let mut p = bottom.max(from);
    // SAFETY: every word in [bottom, top) is mapped RAM in the stack region.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    p
}
