//! The timing firmware's `unsafe` code (target only): the CMSDK APB TIMER0 of `mps2-an386`
//! and re-painting the unused stack before a measured call.
//!
//! TIMER0 (Arm CMSDK "APB timer", at `0x4000_0000` on the MPS2 FPGA images AN385/AN386) is a
//! 32-bit down-counter clocked by SYSCLK (25 MHz): `CTRL` (+0x00, bit 0 enable), `VALUE`
//! (+0x04, the current count), `RELOAD` (+0x08, loaded when the count reaches 0). Under QEMU
//! with `-icount` it runs on the virtual clock, i.e. it counts executed instructions.

use core::ptr;

use crate::timing::DownCounter;

const TIMER0_BASE: usize = 0x4000_0000;
const CTRL: usize = TIMER0_BASE;
const VALUE: usize = TIMER0_BASE + 0x04;
const RELOAD: usize = TIMER0_BASE + 0x08;

/// TIMER0, running freely from `u32::MAX` down, without interrupts.
#[derive(Debug)]
pub struct Timer0 {
    _private: (),
}

impl Timer0 {
    /// Stops TIMER0, loads `u32::MAX` into `RELOAD` and `VALUE` and starts it.
    pub fn start() -> Self {
        // SAFETY: CTRL, RELOAD and VALUE are TIMER0's word-aligned MMIO registers on
        // mps2-an386 (always mapped); writing them only reconfigures the timer, whose
        // interrupt stays disabled (CTRL bit 3 = 0), and no other code uses TIMER0.
        unsafe {
            ptr::write_volatile(CTRL as *mut u32, 0);
            ptr::write_volatile(RELOAD as *mut u32, u32::MAX);
            ptr::write_volatile(VALUE as *mut u32, u32::MAX);
            ptr::write_volatile(CTRL as *mut u32, 1);
        }
        Self { _private: () }
    }
}

impl DownCounter for Timer0 {
    #[inline(always)]
    fn read(&self) -> u32 {
        // SAFETY: VALUE is a word-aligned, always-mapped MMIO register; reading it has no side
        // effects.
        unsafe { ptr::read_volatile(VALUE as *const u32) }
    }
}

unsafe extern "C" {
    /// Lowest address of the stack region (end of .bss/.uninit), from cortex-m-rt's link.x.
    static _stack_end: u32;
}

/// Bytes below the current stack pointer left alone by [`repaint_free_stack`] (this
/// function's own frame and slack).
const REPAINT_GAP: usize = 256;

/// Fills the stack region below the current stack pointer (less [`REPAINT_GAP`]) with
/// cortex-m-rt's paint value again, so that `sys::stack_usage` afterwards reports the
/// high-water mark of what runs from here on, not of earlier, deeper calls.
#[inline(never)]
pub fn repaint_free_stack() {
    let sp = cortex_m::register::msp::read() as usize;
    let bottom = &raw const _stack_end as usize;
    let end = sp.saturating_sub(REPAINT_GAP) & !3;
    let mut p = bottom;
    while p < end {
        // SAFETY: `p` is word-aligned (link.x aligns `_stack_end` to 4, `end` is rounded
        // down) and lies between the bottom of the stack region and REPAINT_GAP bytes below
        // the live stack pointer: memory that no live frame uses (no interrupt handler runs,
        // none is enabled), so overwriting it cannot change any Rust value.
        unsafe { ptr::write_volatile(p as *mut u32, cortex_m_rt::STACK_PAINT_VALUE) };
        p += 4;
    }
}
