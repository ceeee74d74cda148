//! The STM32F405's peripherals as the image uses them: clocks, USARTs, the cycle clock, the
//! watchdog, the reset record and the painted stack.
//!
//! QEMU's netduinoplus2 models the USARTs, SysTick and the NVIC; RCC, GPIO, IWDG and the flash
//! interface read 0 and ignore writes. So everything that only configures (clock enables, pin
//! functions) is written on both; what waits on those blocks (the PLL locking, the watchdog)
//! is behind the `board` feature, and every wait is bounded.
//!
//! Registers are written through the PAC's typed fields. `unsafe` is allowed item by item,
//! each block with its reason: three PLL fields whose valid ranges the PAC leaves to the
//! caller, UART4's block seen as a USART's, the watchdog's key register reached without
//! owning IWDG, the reset record and the painted stack.

use core::sync::atomic::{AtomicU32, Ordering};
use stm32f4::stm32f405 as pac;

/// The core clock, Hz. QEMU's SysTick counts at 168 MHz whatever RCC says, so the QEMU image's
/// ticks are 168 MHz ticks too.
pub const CORE_HZ: u32 = 168_000_000;
/// SysTick reload: one interrupt a millisecond.
pub const TICKS_PER_MS: u32 = CORE_HZ / 1000;

/// Milliseconds since start (the SysTick handler counts them).
pub static MS: AtomicU32 = AtomicU32::new(0);

/// Core clock ticks since start, modulo 2^32 (25.6 s at 168 MHz): the millisecond count and
/// SysTick's current value, read consistently. SysTick may have wrapped without its handler
/// having counted the millisecond yet (the exception is pending for a few instructions): a
/// reload value read while it is pending belongs to the next millisecond.
pub fn ticks() -> u32 {
    loop {
        let m1 = MS.load(Ordering::Acquire);
        let cvr = cortex_m::peripheral::SYST::get_current();
        let pending = cortex_m::peripheral::SCB::is_pendst_pending();
        let m2 = MS.load(Ordering::Acquire);
        if m1 == m2 {
            let ms = if pending && cvr > TICKS_PER_MS / 2 {
                m1.wrapping_add(1)
            } else {
                m1
            };
            return ms
                .wrapping_mul(TICKS_PER_MS)
                .wrapping_add(TICKS_PER_MS.saturating_sub(1).saturating_sub(cvr));
        }
    }
}

/// Milliseconds since start.
pub fn ms() -> u32 {
    MS.load(Ordering::Acquire)
}

/// Start SysTick at 1 kHz on the core clock.
pub fn start_systick(mut syst: cortex_m::peripheral::SYST) {
    syst.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    syst.set_reload(TICKS_PER_MS - 1);
    syst.clear_current();
    syst.enable_counter();
    syst.enable_interrupt();
}

/// Baud rates: GPS receiver, DF unit, user port, ZigBee coordinator.
pub const BAUD: [u32; 4] = [9600, 4800, 115_200, 115_200];

/// The 168 MHz PLL from the 25 MHz crystal of the Netduino Plus 2 (APB1 42 MHz, APB2
/// 84 MHz, five flash wait states). Returns whether it locked; if not the chip stays on the
/// internal 16 MHz oscillator.
#[cfg(feature = "board")]
#[allow(unsafe_code)]
pub fn start_pll(rcc: &pac::RCC, flash: &pac::FLASH) -> bool {
    const SPINS: u32 = 1_000_000;
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    if !(0..SPINS).any(|_| rcc.cr().read().hserdy().bit_is_set()) {
        return false;
    }
    // PLLM 25, PLLN 336, PLLP 2, PLLQ 7, source HSE: 25 / 25 * 336 / 2 = 168 MHz.
    rcc.pllcfgr().write(|w| {
        // SAFETY: the PAC types PLLM, PLLN and PLLQ as raw bits, their valid ranges (RM0090:
        // 2-63, 50-432, 2-15) being the caller's to keep; 25, 336 and 7 lie inside them.
        unsafe { w.pllm().bits(25).plln().bits(336).pllq().bits(7) };
        w.pllp().div2().pllsrc().hse()
    });
    // Latency 5, prefetch, instruction and data caches.
    flash.acr().write(|w| {
        w.latency()
            .ws5()
            .prften()
            .enabled()
            .icen()
            .enabled()
            .dcen()
            .enabled()
    });
    // AHB /1, APB1 /4, APB2 /2.
    rcc.cfgr()
        .write(|w| w.hpre().div1().ppre1().div4().ppre2().div2());
    rcc.cr().modify(|_, w| w.pllon().set_bit());
    if !(0..SPINS).any(|_| rcc.cr().read().pllrdy().bit_is_set()) {
        return false;
    }
    rcc.cfgr().modify(|_, w| w.sw().pll());
    (0..SPINS).any(|_| rcc.cfgr().read().sws().is_pll())
}

/// APB clock of USART1 (APB2) and of the others (APB1), Hz.
fn pclk(apb2: bool) -> u32 {
    match (cfg!(feature = "board"), apb2) {
        (true, true) => 84_000_000,
        (true, false) => 42_000_000,
        (false, _) => 16_000_000,
    }
}

/// Clock the GPIO ports and the four USARTs, and give their pins to them: USART1 PA9/PA10,
/// USART2 PA2/PA3, USART3 PB10/PB11 (AF7), UART4 PA0/PA1 (AF8).
pub fn enable_clocks_and_pins(rcc: &pac::RCC, gpioa: &pac::GPIOA, gpiob: &pac::GPIOB) {
    rcc.ahb1enr()
        .modify(|_, w| w.gpioaen().enabled().gpioben().enabled());
    rcc.apb1enr().modify(|_, w| {
        w.usart2en()
            .enabled()
            .usart3en()
            .enabled()
            .uart4en()
            .enabled()
    });
    rcc.apb2enr().modify(|_, w| w.usart1en().enabled());
    gpioa.moder().modify(|_, w| {
        w.moder0()
            .alternate()
            .moder1()
            .alternate()
            .moder2()
            .alternate()
            .moder3()
            .alternate()
            .moder9()
            .alternate()
            .moder10()
            .alternate()
    });
    gpioa
        .afrl()
        .modify(|_, w| w.afrl0().af8().afrl1().af8().afrl2().af7().afrl3().af7());
    gpioa.afrh().modify(|_, w| w.afrh9().af7().afrh10().af7());
    gpiob
        .moder()
        .modify(|_, w| w.moder10().alternate().moder11().alternate());
    gpiob.afrh().modify(|_, w| w.afrh10().af7().afrh11().af7());
}

/// The USART register block (USART1-3 and UART4 share its layout).
pub type Usart = pac::usart1::RegisterBlock;

/// UART4's registers as a USART's (the same layout at the same offsets; it lacks only the
/// synchronous-mode bits, which the image never touches).
#[allow(unsafe_code)]
pub fn uart4(_owned: &pac::UART4) -> &'static Usart {
    // SAFETY: UART4's block is mapped for the program's life, and its SR, DR, BRR and CR1-3
    // sit where USART1's do; holding `pac::UART4` proves the caller owns it.
    unsafe { &*(pac::UART4::ptr() as *const Usart) }
}

/// 8N1 at `baud`, receiver and its interrupt on (and the transmitter if `tx`).
pub fn start_usart(u: &Usart, baud: u32, apb2: bool, tx: bool) {
    // The divider in sixteenths: mantissa and fraction side by side, as BRR holds them.
    let brr = (pclk(apb2) / baud).min(u32::from(u16::MAX)) as u16;
    u.brr().write(|w| {
        w.div_mantissa()
            .set(brr >> 4)
            .div_fraction()
            .set((brr & 0xF) as u8)
    });
    u.cr1().write(|w| {
        w.ue()
            .set_bit()
            .re()
            .set_bit()
            .rxneie()
            .set_bit()
            .te()
            .bit(tx)
    });
}

/// What a receive interrupt found.
pub enum Received {
    /// A byte.
    Byte(u8),
    /// A byte, after an overrun lost the one before it.
    Overrun(u8),
    /// Nothing to read.
    Nothing,
}

/// Read the receiver (reading DR clears RXNE and ORE).
pub fn receive(u: &Usart) -> Received {
    let sr = u.sr().read();
    let overrun = sr.ore().bit_is_set();
    if !sr.rxne().bit_is_set() && !overrun {
        return Received::Nothing;
    }
    let b = u.dr().read().dr().bits() as u8;
    if overrun {
        Received::Overrun(b)
    } else {
        Received::Byte(b)
    }
}

/// Whether the transmitter can take a byte.
pub fn tx_ready(u: &Usart) -> bool {
    u.sr().read().txe().bit_is_set()
}

/// Send a byte (the caller checked [`tx_ready`]).
pub fn transmit(u: &Usart, b: u8) {
    u.dr().write(|w| w.dr().set(u16::from(b)));
}

/// The independent watchdog: about a second without a feed resets the chip.
#[cfg(feature = "board")]
pub fn start_watchdog(iwdg: &pac::IWDG) {
    iwdg.kr().write(|w| w.key().unlock());
    // LSI 32 kHz / 64 = 500 Hz; 500 counts.
    iwdg.pr().write(|w| w.pr().divide_by64());
    iwdg.rlr().write(|w| w.rl().set(500));
    iwdg.kr().write(|w| w.key().start());
}

/// Feed the watchdog (from the main loop only: a stuck loop starves it).
#[cfg(feature = "board")]
#[allow(unsafe_code)]
pub fn feed_watchdog() {
    // SAFETY: the main loop does not own IWDG (init configured it and let it go); it only
    // writes the reload key to the key register, which has no other effect.
    let iwdg = unsafe { &*pac::IWDG::ptr() };
    iwdg.kr().write(|w| w.key().feed());
}

/// Whether the last reset was the watchdog's (and clear the flags).
#[cfg(feature = "board")]
pub fn watchdog_reset(rcc: &pac::RCC) -> bool {
    let was = rcc.csr().read().wdgrstf().bit_is_set();
    rcc.csr().modify(|_, w| w.rmvf().clear());
    was
}

/// Why the last reset happened, kept across the reset in RAM the startup code leaves alone.
#[repr(C)]
pub struct ResetRecord {
    magic: u32,
    cause: u32,
    /// Where: the panic's line, or the faulting PC.
    pub at: u32,
}

const MAGIC: u32 = 0xF0C5_F0C5;

// Placed in RAM the startup code neither zeroes nor initialises, so it survives the reset.
#[allow(unsafe_code)]
#[unsafe(link_section = ".uninit.foxhunt")]
static mut RECORD: core::mem::MaybeUninit<ResetRecord> = core::mem::MaybeUninit::uninit();

/// Record `cause` ('P', 'H') and where, then reset.
#[allow(unsafe_code)]
pub fn record_and_reset(cause: u8, at: u32) -> ! {
    // SAFETY: RECORD is plain words in .uninit; only this function and `take_record` touch
    // it, this one with interrupts about to be lost to the reset.
    unsafe {
        let p = core::ptr::addr_of_mut!(RECORD) as *mut ResetRecord;
        core::ptr::write_volatile(
            p,
            ResetRecord {
                magic: MAGIC,
                cause: u32::from(cause),
                at,
            },
        );
    }
    cortex_m::peripheral::SCB::sys_reset()
}

/// The record the last reset left (cause letter and where), cleared.
#[allow(unsafe_code)]
pub fn take_record() -> Option<(u8, u32)> {
    // SAFETY: as in `record_and_reset`; called once at start, before any interrupt.
    unsafe {
        let p = core::ptr::addr_of_mut!(RECORD) as *mut ResetRecord;
        let r = core::ptr::read_volatile(p);
        core::ptr::write_volatile(core::ptr::addr_of_mut!((*p).magic), 0);
        (r.magic == MAGIC).then_some((r.cause as u8, r.at))
    }
}

/// Paint the stack below the current frame again (after the start-up, whose one-off moves of
/// the big state would otherwise stand as the high-water mark): the mark then says what the
/// running loop needs. Interrupts are off while it paints.
#[inline(never)]
pub fn repaint_stack() {
    cortex_m::interrupt::free(|_| {
        crate::stack::paint_below(cortex_m::register::msp::read() as usize);
    });
}

/// Stack the high-water scan looks at, bytes: twice the budget's share. A mark at this
/// value means at least this much (the budget is then broken anyway); scanning no further
/// keeps the once-a-second scan to a few thousand words instead of the whole RAM.
pub const STACK_SCAN: usize = 16 * 1024;

/// Peak stack use, bytes: from the top down to the lowest word no longer painted.
pub fn stack_high_water() -> u32 {
    let (_, top) = crate::stack::bounds();
    (top - crate::stack::lowest_written(top.saturating_sub(STACK_SCAN))) as u32
}
