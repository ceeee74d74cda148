//! The MCU image: a recorded drive, embedded in flash, fed byte by byte through the bridge into
//! a SIR filter (N = 100) and the ML fix; the results go out over semihosting and the image
//! exits 0. On the host this binary is an empty stub (the library is what the host runs).
//!
//! Run it: `cargo run --profile firmware -p foxhunt-bridge --bin foxhunt-firmware --target
//! thumbv7em-none-eabihf` (the runner in .cargo/config.toml starts QEMU netduinoplus2).
#![cfg_attr(target_os = "none", no_std, no_main)]

/// Particles of the image's SIR filter.
#[cfg(target_os = "none")]
const PARTICLES: usize = 100;

#[cfg(target_os = "none")]
mod image {
    use cortex_m as _;
    use cortex_m_rt::entry;
    use foxhunt_bridge::BridgeConfig;
    use foxhunt_bridge::replay::{replay, write_summary};
    use semihosting::{print, process};

    /// The drive: `foxhunt simulate --scenario aoa-drive` (run 0, default origin).
    static CAPTURE: &[u8] = include_bytes!("../../captures/aoa-drive.nmea");

    /// Bytes in, formatted out, through semihosting.
    struct Console;

    impl core::fmt::Write for Console {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            print!("{s}");
            Ok(())
        }
    }

    #[entry]
    fn main() -> ! {
        let config = BridgeConfig {
            // aoa-drive's bearing noise: variance 3.801e-4 rad^2.
            sigma_rad: 0.019_496,
            ..BridgeConfig::default()
        };
        // The baseline image skips the filter steps: the difference of two instruction counts
        // is the cost of the steps alone.
        let steps = if cfg!(feature = "baseline") {
            0
        } else {
            usize::MAX
        };
        let r = replay::<{ super::PARTICLES }>(CAPTURE, 1, config, 1, steps);
        let _ = write_summary(&r, &mut Console);
        let _ = core::fmt::Write::write_fmt(
            &mut Console,
            format_args!("stack {}\n", stack_high_water()),
        );
        process::exit(if r.sir.is_ok() && r.ml.is_ok() { 0 } else { 1 })
    }

    /// Peak stack use: cortex-m-rt painted the stack with 0xCCCCCCCC before main; the lowest
    /// overwritten word marks the deepest the stack went.
    #[allow(unsafe_code)]
    fn stack_high_water() -> usize {
        unsafe extern "C" {
            static _stack_start: u32;
            static _stack_end: u32;
        }
        // SAFETY: the linker script defines both symbols as the bounds of the stack region,
        // which is mapped RAM; reading words inside it is always valid.
        unsafe {
            let top = core::ptr::addr_of!(_stack_start) as usize;
            let mut p = core::ptr::addr_of!(_stack_end) as usize;
            while p < top && core::ptr::read_volatile(p as *const u32) == 0xCCCC_CCCC {
                p += 4;
            }
            top - p
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
