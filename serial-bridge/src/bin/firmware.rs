//! The MCU image: a recorded drive streamed in 64-byte reads (as from a UART's DMA buffer)
//! through the bridge into a SIR filter (N = 100) and the ML fix; the results go out over
//! semihosting and the image exits 0. On the host this binary is an empty stub (the library is
//! what the host runs).
//!
//! The bytes come from a host file over semihosting, standing in for the serial port: the
//! path is the image's first semihosting argument, by default the bundled drive
//! `serial-bridge/captures/aoa-drive.nmea` (relative to where QEMU runs). So the flash holds
//! the product, not a recording. Run it from the workspace root: `cargo run --profile firmware
//! -p foxhunt-bridge --bin foxhunt-firmware --target thumbv7em-none-eabihf` (the runner in
//! .cargo/config.toml starts QEMU netduinoplus2).
#![cfg_attr(target_os = "none", no_std, no_main)]

/// Particles of the image's SIR filter.
#[cfg(target_os = "none")]
const PARTICLES: usize = 100;

#[cfg(target_os = "none")]
mod image {
    use cortex_m as _;
    use cortex_m_rt::entry;
    use foxhunt_bridge::BridgeConfig;
    use foxhunt_bridge::replay::{READ_BUFFER, replay_from, write_summary};
    use semihosting::{fs::File, io::Read, print, println, process};

    /// The drive when no path is given: `foxhunt simulate --scenario aoa-drive` (run 0).
    const DEFAULT_CAPTURE: &str = "serial-bridge/captures/aoa-drive.nmea";

    /// The capture file named by the first semihosting argument (or the default), opened.
    /// A command line too long for the buffer, a path not UTF-8 or not openable is an error.
    fn open_capture() -> Result<File, semihosting::io::Error> {
        use semihosting::io::ErrorKind::InvalidInput;
        let args = semihosting::experimental::env::args::<512>()?;
        let mut it = &args;
        let _program = it.next();
        let path = it
            .next()
            .unwrap_or(Ok(DEFAULT_CAPTURE))
            .map_err(|_| InvalidInput)?;
        let mut c_path = [0u8; 512];
        if path.len() >= c_path.len() {
            return Err(InvalidInput.into());
        }
        c_path[..path.len()].copy_from_slice(path.as_bytes());
        File::open(core::ffi::CStr::from_bytes_until_nul(&c_path).map_err(|_| InvalidInput)?)
    }

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
            // The drive's bearing noise (aoa-drive's).
            sigma_rad: foxhunt_core::canonical::AOA_SIGMA,
            ..BridgeConfig::default()
        };
        // The baseline image skips the filter steps: the difference of two instruction counts
        // is the cost of the steps alone.
        let steps = if cfg!(feature = "baseline") {
            0
        } else {
            usize::MAX
        };
        let mut capture = match open_capture() {
            Ok(file) => file,
            Err(e) => {
                println!("capture error: {e}");
                process::exit(2)
            }
        };
        let read = |buf: &mut [u8]| capture.read(buf);
        let r = match replay_from::<{ super::PARTICLES }, _>(read, READ_BUFFER, config, 1, steps) {
            Ok(r) => r,
            Err(e) => {
                println!("capture error: {e}");
                process::exit(2)
            }
        };
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
