//! The boards `evorec timing` measures (`--profile m4|m7`): the firmware image and QEMU machine
//! of each, its RAM budget, and the clock, pipeline and memory system of its cycle ESTIMATE.
//!
//! The instruction counts come from the same timing firmware code on both (the M7 image is the
//! M4 code built with feature `m7`: 320×240 frames, the M7 lengths of `memory.x`); only the
//! frame size, the QEMU machine and the cycle model differ.

use evorec_firmware::BoardProfile;

/// The flash and cache system of a part, as the wait-state model sees it (see `flash.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemorySystem {
    /// Extra CPU cycles of a flash access that misses the cache (the wait states, in CPU
    /// cycles).
    pub miss_cycles: f64,
    /// Bytes of one cache line (fetched per miss).
    pub line_bytes: u32,
    /// Bytes of the instruction cache.
    pub icache_bytes: u32,
    /// One line for the report's heading.
    pub label: &'static str,
    /// The assumptions, as stated in the report.
    pub assumptions: &'static [&'static str],
}

impl MemorySystem {
    /// STM32F4 at 168 MHz: 5 wait states behind the ART accelerator (RM0090).
    pub const STM32F4: Self = Self {
        miss_cycles: 5.0,
        line_bytes: 16,
        icache_bytes: 1024,
        label: "STM32F4, 168 MHz, 5 flash wait states, ART accelerator",
        assumptions: &[
            "flash: STM32F4 at 168 MHz with 5 wait states (RM0090, 2.7-3.6 V) behind the ART accelerator (64 x 128-bit instruction cache, 8 x 128-bit data cache, prefetch buffer): a flash access that misses the ART costs +5 cycles",
            "data: every load from flash misses the ART data cache (+5): PC-relative literals, tbb/tbh tables, and loads through a register holding a flash address (movw/movt, adr or a literal load, tracked forward through each function; e.g. constant tables in .rodata, the RGB565 -> hue table); the frames, the tracker and the stack are in SRAM (0 wait states)",
            "code outside the hot loop: every branch lands on a line that misses the instruction cache (+5); sequential fetch is covered by the prefetch buffer except a 16-byte line whose instructions execute in fewer than 6 cycles stalls for the difference; in the rest of the code, loads through registers of unknown provenance are counted as flash loads too",
            "hot loop (the sample points of the fitness kernel): if its unrolled code spans at most the 1 KiB ART instruction cache it hits after one miss per line per call of the integer walk (population x 2 cameras x 12 edges calls per generation); otherwise it is costed like the rest of the code",
        ],
    };

    /// STM32H743 at 480 MHz: flash on the AXI bus at 240 MHz with 4 wait states, behind the
    /// Cortex-M7's 16 KiB L1 caches (RM0433).
    pub const STM32H7: Self = Self {
        miss_cycles: 9.0,
        line_bytes: 32,
        icache_bytes: 16 * 1024,
        label: "STM32H743, 480 MHz, flash at 240 MHz with 4 wait states, 16 KiB L1 I- and D-caches",
        assumptions: &[
            "flash: STM32H743 at 480 MHz (VOS0), the flash on the AXI bus at ACLK = 240 MHz with 4 wait states (RM0433, table of flash wait states against AXI clock and VOS; STM32CubeH7's 480 MHz clock set-up programs FLASH_LATENCY_4): one 256-bit flash read takes 5 ACLK = 10 CPU cycles, so a flash access that misses the L1 cache costs +9 CPU cycles (bus arbitration not counted)",
            "caches: the Cortex-M7's L1 caches enabled (16 KiB instruction, 16 KiB data, 32-byte lines on the STM32H7); no code or data placed in ITCM/DTCM",
            "data: every load from flash misses the 16 KiB D-cache (+9): PC-relative literals, tbb/tbh tables and loads through a register holding a flash address (tracked as on the M4), e.g. the 64 KiB RGB565 -> hue table, read at random; the frames (2 x 150 KiB, AXI SRAM), the tracker and the stack are counted at 0 wait states (see the sensitivity for every unknown load missing)",
            "code outside the hot loop: every branch lands on a line that misses the I-cache (+9); a 32-byte line whose instructions execute in fewer than 10 cycles stalls for the difference (a pessimistic model for a 16 KiB cache that holds the whole generation's code after the first frame)",
            "hot loop (the sample points): spans far less than the 16 KiB I-cache, so it hits after one miss per line per call of the integer walk (population x 2 cameras x 12 edges calls per generation)",
        ],
    };
}

/// One board `evorec timing` can measure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Board {
    /// The firmware crate's profile (QEMU machine, frame size, name).
    pub profile: BoardProfile,
    /// The part the estimate is for.
    pub part: &'static str,
    /// Clock of the cycle estimate (Hz).
    pub clock_hz: f64,
    /// RAM of the budgeted part (the profile's memory map).
    pub ram_bytes: u64,
    /// The memory map's file.
    pub memory_map: &'static str,
    /// How to build this profile's images.
    pub build_hint: &'static str,
    /// The target directory below the workspace's (`None`: the workspace's own).
    pub target_subdir: Option<&'static str>,
    /// Cycles of every branch (taken, refill / misprediction included) in the estimate.
    pub branch_cycles: f64,
    /// The pipeline assumptions of the estimate, as stated in the report.
    pub pipeline: &'static str,
    /// Flash and caches.
    pub memory: MemorySystem,
}

impl Board {
    /// The Cortex-M4F profile (STM32F4-class, 160×120, `memory.x`).
    pub const M4: Self = Self {
        profile: BoardProfile::M4,
        part: "Cortex-M4F (STM32F4-class)",
        clock_hz: 168.0e6,
        ram_bytes: 128 * 1024,
        memory_map: "memory.x",
        build_hint: "cd hil-stubs && cargo build --release",
        target_subdir: None,
        branch_cycles: 4.0,
        pipeline: "Cortex-M4F at 168 MHz; per-class worst-case costs from the Cortex-M4 TRM (3-stage pipeline, every branch 1 + 3)",
        memory: MemorySystem::STM32F4,
    };

    /// The Cortex-M7 profile (STM32H7-class, 320×240, `memory.x` with `__evorec_m7`).
    pub const M7: Self = Self {
        profile: BoardProfile::M7,
        part: "Cortex-M7 (STM32H743-class)",
        clock_hz: 480.0e6,
        ram_bytes: 512 * 1024,
        memory_map: "memory.x, M7 profile",
        build_hint: "cd hil-stubs && CARGO_TARGET_DIR=../target/m7 cargo build --release --features m7",
        target_subdir: Some("m7"),
        branch_cycles: 8.0,
        pipeline: "Cortex-M7 at 480 MHz; Arm publishes no per-instruction cycle table for the M7, so the estimate takes the Cortex-M4 TRM's per-class worst-case costs (no credit for the M7's dual issue, which only lowers them) except branches: every branch counted as mispredicted on the 6-stage pipeline at 1 + 7 cycles (an assumed flush cost, not a documented figure)",
        memory: MemorySystem::STM32H7,
    };

    /// The board called `name` (`m4` or `m7`).
    pub fn by_name(name: &str) -> Option<Self> {
        [Self::M4, Self::M7].into_iter().find(|b| b.profile.name == name)
    }

    /// `-cpu … -machine …` for QEMU.
    pub fn qemu_machine(&self) -> [&'static str; 4] {
        ["-cpu", self.profile.qemu_cpu, "-machine", self.profile.qemu_machine]
    }

    /// Frame size as `W×H`.
    pub fn frame_size(&self) -> String {
        format!("{}×{}", self.profile.frame_width, self.profile.frame_height)
    }

    /// The clock in MHz.
    pub fn mhz(&self) -> f64 {
        self.clock_hz / 1e6
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boards_by_name() {
        assert_eq!(Board::by_name("m4"), Some(Board::M4));
        assert_eq!(Board::by_name("m7").map(|b| b.profile.frame_width), Some(320));
        assert_eq!(Board::by_name("m5"), None);
        assert_eq!(Board::M7.qemu_machine(), ["-cpu", "cortex-m7", "-machine", "mps2-an500"]);
    }
}
