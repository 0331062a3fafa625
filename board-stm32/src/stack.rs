//! The stack's place in RAM (linker symbols) and its high-water mark by painting.
//!
//! Built with `flip-link` (`scripts/test.sh`, README), the stack sits at the bottom of RAM,
//! below `.data`/`.bss`: it grows down from [`Layout::stack_top`] to [`Layout::stack_limit`] =
//! the start of RAM, and an overflow faults on the unmapped addresses below instead of
//! silently overwriting the statics (the HardFault handler then moves the stack pointer back
//! to the top before it runs, see `main.rs`). Without flip-link (a plain `cargo build`),
//! cortex-m-rt puts the stack at the top of RAM, above `.bss`.
//!
//! [`paint`] fills the free stack with [`PAINT`] at start; [`high_water`] finds the lowest
//! word overwritten since, which bounds the deepest stack use (interrupts included).

/// The painted word.
pub const PAINT: u32 = 0xDEAD_BEEF;

extern "C" {
    // cortex-m-rt (link.x) and flip-link: initial stack pointer, the stack's lower end, and
    // the statics' bounds.
    static _stack_start: u32;
    static _stack_end: u32;
    static __sdata: u32;
    static __ebss: u32;
}

/// Addresses of the stack and the statics in RAM.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Initial stack pointer (the stack grows down from here).
    pub stack_top: usize,
    /// The lowest address the stack may use.
    pub stack_limit: usize,
    /// Start of `.data` (the first static).
    pub data_start: usize,
    /// End of `.bss`.
    pub bss_end: usize,
}

impl Layout {
    /// The layout this firmware was linked with.
    pub fn linked() -> Layout {
        // SAFETY: only the addresses of the linker's symbols are taken, never their contents
        // (no `unsafe` needed for that since Rust 1.82; this crate's MSRV is 1.81).
        #[allow(unused_unsafe)]
        unsafe {
            Layout {
                stack_top: core::ptr::addr_of!(_stack_start) as usize & !7,
                stack_limit: core::ptr::addr_of!(_stack_end) as usize,
                data_start: core::ptr::addr_of!(__sdata) as usize,
                bss_end: core::ptr::addr_of!(__ebss) as usize,
            }
        }
    }

    /// Bytes reserved for the stack.
    pub fn reserved(&self) -> usize {
        self.stack_top - self.stack_limit
    }

    /// Whether the stack lies below the statics (flip-link's layout): an overflow leaves RAM.
    pub fn stack_below_statics(&self) -> bool {
        self.stack_top <= self.data_start
    }
}

/// Paints the free stack, from [`Layout::stack_limit`] to 64 bytes below the current stack
/// pointer, with [`PAINT`]. Call before interrupts are enabled.
#[inline(never)]
pub fn paint(layout: &Layout) {
    let sp = cortex_m::register::msp::read() as usize;
    let top = sp.saturating_sub(64) & !3;
    let mut p = layout.stack_limit;
    while p < top {
        // SAFETY: [stack_limit, sp - 64) is stack nobody uses yet (below this function's frame;
        // interrupts not enabled), word-aligned RAM.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// Bytes of stack used at most since [`paint`]: from [`Layout::stack_top`] down to the lowest
/// overwritten word.
pub fn high_water(layout: &Layout) -> usize {
    let mut p = layout.stack_limit;
    // SAFETY: reads of the stack region painted by `paint` (word-aligned RAM).
    while p < layout.stack_top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    layout.stack_top - p
}

/// The high-water mark measured a little at a time, for a loop that cannot afford a full scan
/// (about 29,000 words, some 1.2 ms at 168 MHz) in one period: sweeps from
/// [`Layout::stack_limit`] up to the lowest overwritten word found so far, a few words per
/// call, and starts over. The stack only grows into painted words, so the mark only moves down
/// and a sweep finds any new low.
#[derive(Clone, Copy, Debug)]
pub struct HighWater {
    layout: Layout,
    pos: usize,
    lowest: usize,
}

impl HighWater {
    /// Starts sweeping `layout`'s stack (painted by [`paint`]).
    pub fn new(layout: Layout) -> HighWater {
        HighWater {
            layout,
            pos: layout.stack_limit,
            lowest: layout.stack_top,
        }
    }

    /// Checks up to `words` more words; returns the bytes used at most, as found so far.
    pub fn step(&mut self, words: usize) -> usize {
        for _ in 0..words {
            if self.pos >= self.lowest {
                self.pos = self.layout.stack_limit;
                break;
            }
            // SAFETY: a read of the painted stack region (word-aligned RAM below `lowest`).
            if unsafe { core::ptr::read_volatile(self.pos as *const u32) } != PAINT {
                self.lowest = self.pos;
                self.pos = self.layout.stack_limit;
                break;
            }
            self.pos += 4;
        }
        self.layout.stack_top - self.lowest
    }
}
