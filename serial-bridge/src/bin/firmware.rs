//! The DF unit's MCU image (STM32F405; QEMU's netduinoplus2): GPS NMEA on USART1, the DF
//! unit's bearings on USART2, the ZigBee coordinator's MT frames on UART4 when configured,
//! commands in and the unit's sentences out on USART3 (see `foxhunt_bridge::telemetry` and
//! `foxhunt_bridge::command`).
//!
//! On RTIC 2, receiving is interrupt-driven: each receive interrupt puts its byte into a
//! lock-free SPSC queue (a full queue or a receiver overrun is counted, never silent). The idle
//! loop drains the queues into `foxhunt_bridge::unit::Unit`, settles a line that went quiet
//! for `IDLE_MS`, and sends a status and a link sentence once a second. Its sentences go into
//! an output queue that the loop itself hands to the user port's transmitter, polling it as
//! it goes (as many bytes as the transmitter takes each time round; QEMU models no transmit
//! interrupt), so a sentence never blocks the loop (one that does not fit the queue is
//! dropped and counted). SysTick counts milliseconds and gives the cycle clock the latency and
//! fix-cost figures are measured with.
//!
//! For each read that completed a frame the loop logs `feed <port> <bytes so far>` (and
//! `idle ...` for a settle): the host replays exactly that order (`foxhunt_bridge::replay`)
//! and gets the same bits. Logs go through defmt: semihosting in QEMU, RTT on the board.
//!
//! Never stuck: the `board` build feeds the independent watchdog from the loop; the panic and
//! hard-fault handlers record the reason in RAM that survives the reset, and reset; the next
//! ready banner and every status sentence say why the unit last reset. The image's own code
//! (this binary, and the bridge library but for its byte decoders that index their buffers:
//! agrelo, geo, kraken, mt, nmea's field readers, stream) denies the lints of panicking
//! paths, and `tests/tests/firmware_image.rs` checks that the linked image has no panic call
//! in that code; the decoders' bounds checks (and heapless' and the logger's) are what remain,
//! listed by that test, and a panic there resets the unit as above.
#![cfg_attr(target_os = "none", no_std, no_main)]
// The library's list (a binary is a crate of its own).
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::unreachable,
    clippy::todo,
    clippy::unimplemented
)]

/// A line quiet this long has ended its record, ms.
#[cfg(target_os = "none")]
const IDLE_MS: u32 = 20;

#[cfg(target_os = "none")]
#[path = "firmware/hw.rs"]
mod hw;

#[cfg(target_os = "none")]
#[path = "shared/stack.rs"]
mod stack;

#[cfg(target_os = "none")]
#[rtic::app(device = stm32f4::stm32f405, peripherals = true)]
mod app {
    use super::hw::{self, Received};
    use core::sync::atomic::{AtomicU32, Ordering};
    use cortex_m as _;
    #[cfg(feature = "board")]
    use defmt_rtt as _;
    #[cfg(not(feature = "board"))]
    use defmt_semihosting as _;
    use foxhunt_bridge::telemetry::{ReadySentence, ResetCause, StatusSentence};
    use foxhunt_bridge::unit::{Port, Unit};
    use heapless::spsc::{Consumer, Producer, Queue};
    use stm32f4::stm32f405 as pac;

    /// Receive queue slots of the GPS and DF lines (one is kept free by the queue): 53 ms of
    /// 9600 baud, and room for QEMU's bursts (it delivers a port's bytes as fast as its main
    /// loop runs, not at a baud rate).
    const RX: usize = 513;
    /// Receive queue slots of the ZigBee and user ports.
    const RX_SMALL: usize = 257;
    /// Output queue slots.
    const TX: usize = 1025;
    /// Bytes the loop takes from a queue at once.
    const CHUNK: usize = 64;

    /// Bytes lost to receiver overruns and to full queues, by input port.
    static OVERRUNS: AtomicU32 = AtomicU32::new(0);
    static FULL: AtomicU32 = AtomicU32::new(0);
    /// Queue high-water marks: GPS, DF, ZigBee, user input.
    static HIGH: [AtomicU32; 4] = [const { AtomicU32::new(0) }; 4];
    /// Bytes each receive queue took in and gave out: their difference is its fill, without
    /// the queue's own `len` (whose index arithmetic keeps a division the compiler cannot
    /// prove safe).
    static TAKEN: [AtomicU32; 4] = [const { AtomicU32::new(0) }; 4];
    static GIVEN: [AtomicU32; 4] = [const { AtomicU32::new(0) }; 4];

    #[shared]
    struct Shared {
        user: pac::USART3,
    }

    #[local]
    struct Local {
        gps: pac::USART1,
        df: pac::USART2,
        zigbee: pac::UART4,
        gps_in: RxIn,
        df_in: RxIn,
        zigbee_in: RxIn,
        user_in: RxIn,
        rx: [RxOut; 4],
        out: Producer<'static, u8>,
        out_next: Consumer<'static, u8>,
        reset: ResetCause,
    }

    /// A receive queue's producer side: each byte and the tick it arrived at (so a latency
    /// starts at its record's last byte, not at whatever the loop took with it).
    pub struct RxIn {
        bytes: Producer<'static, u8>,
        ticks: Producer<'static, u32>,
    }

    /// A receive queue's consumer side.
    pub struct RxOut {
        bytes: Consumer<'static, u8>,
        ticks: Consumer<'static, u32>,
    }

    #[init(local = [
        q_gps: Queue<u8, RX> = Queue::new(),
        q_df: Queue<u8, RX> = Queue::new(),
        q_zigbee: Queue<u8, RX_SMALL> = Queue::new(),
        q_user: Queue<u8, RX_SMALL> = Queue::new(),
        t_gps: Queue<u32, RX> = Queue::new(),
        t_df: Queue<u32, RX> = Queue::new(),
        t_zigbee: Queue<u32, RX_SMALL> = Queue::new(),
        t_user: Queue<u32, RX_SMALL> = Queue::new(),
        q_out: Queue<u8, TX> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let record = hw::take_record();
        #[cfg(feature = "board")]
        let watchdog = hw::watchdog_reset(&dp.RCC);
        #[cfg(not(feature = "board"))]
        let watchdog = false;
        let reset = match record {
            Some((b'P', _)) => ResetCause::Panic,
            Some((b'H', _)) => ResetCause::HardFault,
            _ if watchdog => ResetCause::Watchdog,
            _ => ResetCause::PowerOn,
        };
        #[cfg(feature = "board")]
        if !hw::start_pll(&dp.RCC, &dp.FLASH) {
            defmt::error!("PLL did not lock: running on the internal oscillator");
        }
        hw::enable_clocks_and_pins(&dp.RCC, &dp.GPIOA, &dp.GPIOB);
        hw::start_systick(cx.core.SYST);
        hw::start_usart(&dp.USART1, hw::BAUD[0], true, false);
        hw::start_usart(&dp.USART2, hw::BAUD[1], false, false);
        hw::start_usart(&dp.USART3, hw::BAUD[2], false, true);
        hw::start_usart(hw::uart4(&dp.UART4), hw::BAUD[3], false, false);
        #[cfg(feature = "board")]
        hw::start_watchdog(&dp.IWDG);
        if let Some((cause, at)) = record {
            defmt::warn!("reset by {=u8} at {=u32:#x}", cause, at);
        }
        fn pair<const N: usize>(
            b: &'static mut Queue<u8, N>,
            t: &'static mut Queue<u32, N>,
        ) -> (RxIn, RxOut) {
            let (bi, bo) = b.split();
            let (ti, to) = t.split();
            (
                RxIn {
                    bytes: bi,
                    ticks: ti,
                },
                RxOut {
                    bytes: bo,
                    ticks: to,
                },
            )
        }
        let l = cx.local;
        let (gps_in, gps_rx) = pair(l.q_gps, l.t_gps);
        let (df_in, df_rx) = pair(l.q_df, l.t_df);
        let (zigbee_in, zigbee_rx) = pair(l.q_zigbee, l.t_zigbee);
        let (user_in, user_rx) = pair(l.q_user, l.t_user);
        let (out, out_next) = l.q_out.split();
        (
            Shared { user: dp.USART3 },
            Local {
                gps: dp.USART1,
                df: dp.USART2,
                zigbee: dp.UART4,
                gps_in,
                df_in,
                zigbee_in,
                user_in,
                rx: [gps_rx, df_rx, zigbee_rx, user_rx],
                out,
                out_next,
                reset,
            },
        )
    }

    /// One received byte into its queue, counted.
    fn take(u: &hw::Usart, q: &mut RxIn, port: usize) {
        let b = match hw::receive(u) {
            Received::Byte(b) => b,
            Received::Overrun(b) => {
                OVERRUNS.fetch_add(1, Ordering::Relaxed);
                b
            }
            Received::Nothing => return,
        };
        if q.bytes.enqueue(b).is_err() {
            FULL.fetch_add(1, Ordering::Relaxed);
            return;
        }
        // The two queues have one capacity and move in step: this cannot fail.
        let _ = q.ticks.enqueue(hw::ticks());
        if let (Some(h), Some(t), Some(g)) = (HIGH.get(port), TAKEN.get(port), GIVEN.get(port)) {
            let taken = t.fetch_add(1, Ordering::Relaxed).wrapping_add(1);
            h.fetch_max(
                taken.wrapping_sub(g.load(Ordering::Relaxed)),
                Ordering::Relaxed,
            );
        }
    }

    #[task(binds = USART1, local = [gps, gps_in])]
    fn usart1(cx: usart1::Context) {
        take(cx.local.gps, cx.local.gps_in, 0);
    }

    #[task(binds = USART2, local = [df, df_in])]
    fn usart2(cx: usart2::Context) {
        take(cx.local.df, cx.local.df_in, 1);
    }

    #[task(binds = UART4, local = [zigbee, zigbee_in])]
    fn uart4(cx: uart4::Context) {
        take(hw::uart4(cx.local.zigbee), cx.local.zigbee_in, 2);
    }

    /// The user port's receiver: commands in.
    #[task(binds = USART3, shared = [user], local = [user_in])]
    fn usart3(mut cx: usart3::Context) {
        let input = cx.local.user_in;
        cx.shared.user.lock(|u| take(u, input, 3));
    }

    #[task(binds = SysTick, priority = 2)]
    fn systick(_: systick::Context) {
        hw::MS.fetch_add(1, Ordering::Release);
    }

    /// What the loop measures.
    #[derive(Default)]
    struct Meter {
        /// Bytes queued for the user port so far, and sent.
        queued: u32,
        sent: u32,
        /// A latency being measured: its start tick and the count of sent bytes that ends it.
        pending: Option<(u32, u32)>,
        worst_latency: u32,
        worst_fix: u32,
        out_high: u32,
    }

    /// Sleep until an interrupt, unless a byte came in since the queues were last looked at:
    /// they are checked with interrupts masked, and WFI wakes on a pending one even then (a
    /// byte arriving between the check and WFI would otherwise wait for the next SysTick).
    fn sleep(rx: &[RxOut; 4]) {
        cortex_m::interrupt::disable();
        if rx.iter().all(|q| !q.bytes.ready()) {
            cortex_m::asm::wfi();
        }
        // SAFETY: interrupts were enabled when this was called (the idle loop runs with them
        // on); no critical section spans this point.
        #[allow(unsafe_code)]
        unsafe {
            cortex_m::interrupt::enable()
        };
    }

    /// The unit, built in its static slot by a call of its own: the temporary it is built
    /// from lives in this frame, gone when it returns (the idle loop's frame never is).
    #[inline(never)]
    fn build(slot: &'static mut Option<Unit>) -> &'static mut Unit {
        slot.insert(Unit::default())
    }

    /// Queue a sentence whole for the user port, or refuse it (no room).
    fn send(out: &mut Producer<'static, u8>, meter: &mut Meter, bytes: &[u8]) -> bool {
        // The fill from the loop's own counts (see TAKEN).
        let fill = meter.queued.wrapping_sub(meter.sent) as usize;
        if out.capacity().saturating_sub(fill) < bytes.len() {
            return false;
        }
        for &b in bytes {
            let _ = out.enqueue(b);
        }
        meter.queued = meter.queued.wrapping_add(bytes.len() as u32);
        let fill = meter.queued.wrapping_sub(meter.sent);
        meter.out_high = meter.out_high.max(fill);
        true
    }

    #[idle(shared = [user], local = [rx, out, out_next, reset, unit: Option<Unit> = None])]
    fn idle(cx: idle::Context) -> ! {
        let local = cx.local;
        let mut user = cx.shared.user;
        let reset = *local.reset;
        let unit = build(local.unit);
        hw::repaint_stack();
        let out = local.out;
        let out_next = local.out_next;
        let rx = local.rx;
        let mut meter = Meter::default();
        // The transmitter, polled: as many bytes as it takes now (QEMU models no transmit
        // interrupt; its transmitter takes every byte at once).
        let mut pump = |meter: &mut Meter| {
            user.lock(|u| {
                while hw::tx_ready(u) {
                    let Some(b) = out_next.dequeue() else {
                        break;
                    };
                    hw::transmit(u, b);
                    meter.sent = meter.sent.wrapping_add(1);
                    if let Some((start, mark)) = meter.pending
                        && meter.sent == mark
                    {
                        let t = hw::ticks().wrapping_sub(start);
                        meter.worst_latency = meter.worst_latency.max(t);
                        meter.pending = None;
                    }
                }
                out_next.is_empty()
            })
        };
        let mut banner = ReadySentence { version: 1, reset }.write();
        if let Some(b) = banner.finish() {
            send(out, &mut meter, b);
        }
        let _ = pump(&mut meter);
        defmt::info!("ready");
        let mut fed = [0u32; 4];
        let mut last_rx = [0u32; 4];
        let mut quiet = [true; 4];
        let mut next_status = hw::ms().wrapping_add(1000);
        let mut buf = [0u8; CHUNK];
        let mut arrived = [0u32; CHUNK];
        loop {
            #[cfg(feature = "board")]
            hw::feed_watchdog();
            let mut busy = false;
            for (i, (q, port)) in rx.iter_mut().zip(Port::ALL).enumerate() {
                let mut n = 0;
                for (slot, tick) in buf.iter_mut().zip(arrived.iter_mut()) {
                    match q.bytes.dequeue() {
                        Some(b) => *slot = b,
                        None => break,
                    }
                    *tick = q.ticks.dequeue().unwrap_or(0);
                    n += 1;
                }
                if n == 0 {
                    continue;
                }
                if let Some(g) = GIVEN.get(i) {
                    g.fetch_add(n as u32, Ordering::Relaxed);
                }
                busy = true;
                if port == Port::Zigbee && !unit.zigbee_enabled() {
                    continue;
                }
                let Some(count) = fed.get_mut(i) else {
                    continue;
                };
                // Fed in pieces that end at a record's last byte (a line end, an XML tag's
                // `>`): a fix's latency starts at the arrival of the piece's last byte.
                let mut from = 0;
                while from < n {
                    let end = buf
                        .get(from..n)
                        .and_then(|r| r.iter().position(|b| matches!(b, b'\n' | b'\r' | b'>')))
                        .map_or(n, |k| from + k + 1);
                    let (Some(piece), Some(&last)) = (buf.get(from..end), arrived.get(end - 1))
                    else {
                        break;
                    };
                    let t0 = hw::ticks();
                    let mut sink = |s: &[u8]| send(out, &mut meter, s);
                    let r = unit.feed(port, piece, &mut sink);
                    *count = count.wrapping_add(piece.len() as u32);
                    if r.frames > 0 {
                        defmt::info!("feed {=u8} {=u32}", i as u8, *count);
                    }
                    if r.fixes > 0 {
                        meter.worst_fix = meter.worst_fix.max(hw::ticks().wrapping_sub(t0));
                        if meter.pending.is_none() {
                            meter.pending = Some((last, meter.queued));
                        }
                    }
                    let _ = pump(&mut meter);
                    from = end;
                }
                if let (Some(t), Some(q)) = (last_rx.get_mut(i), quiet.get_mut(i)) {
                    *t = hw::ms();
                    *q = false;
                }
            }
            let now = hw::ms();
            for (i, port) in Port::ALL.into_iter().enumerate() {
                let (Some(t), Some(q), Some(count)) =
                    (last_rx.get(i), quiet.get_mut(i), fed.get(i))
                else {
                    continue;
                };
                if !*q && now.wrapping_sub(*t) >= super::IDLE_MS {
                    *q = true;
                    let mut sink = |s: &[u8]| send(out, &mut meter, s);
                    let r = unit.idle(port, &mut sink);
                    if r.frames > 0 {
                        defmt::info!("idle {=u8} {=u32}", i as u8, *count);
                    }
                }
            }
            if now.wrapping_sub(next_status) < u32::MAX / 2 {
                next_status = next_status.wrapping_add(1000);
                let status = StatusSentence {
                    uptime_s: now / 1000,
                    stack_bytes: hw::stack_high_water(),
                    queue_high: [
                        HIGH[0].load(Ordering::Relaxed),
                        HIGH[1].load(Ordering::Relaxed),
                        HIGH[2].load(Ordering::Relaxed),
                        meter.out_high,
                    ],
                    latency_ticks: meter.worst_latency,
                    fix_ticks: meter.worst_fix,
                    reset: Some(reset),
                };
                let mut link = unit.link();
                link.overruns = OVERRUNS.load(Ordering::Relaxed);
                link.full = FULL.load(Ordering::Relaxed);
                for mut s in [status.write(), link.write()] {
                    if let Some(b) = s.finish() {
                        send(out, &mut meter, b);
                    }
                }
            }
            let drained = pump(&mut meter);
            if !busy && drained {
                sleep(rx);
            }
        }
    }
}

/// A panic records where and resets (no message formatting: `core::fmt` stays out).
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    let line = info.location().map(|l| l.line()).unwrap_or(0);
    defmt::error!("panic at line {=u32}", line);
    hw::record_and_reset(b'P', line)
}

/// A hard fault records the faulting PC and resets.
#[cfg(target_os = "none")]
#[cortex_m_rt::exception]
#[allow(unsafe_code)]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    hw::record_and_reset(b'H', frame.pc())
}

#[cfg(not(target_os = "none"))]
fn main() {}
