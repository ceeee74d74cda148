//! A recorded drive, end to end: bytes through the bridge into a SIR filter and the ML fix.
//!
//! The firmware image and the host run this same function on the same capture and seed; the
//! QEMU test compares their answers bit for bit.

use crate::bridge::{BridgeConfig, BridgeCounters, Event, Receiver};
use crate::stream::StreamCounters;
use foxhunt_core::estimator::with_bearing_filter;
use foxhunt_core::fix::init::initial_particles;
use foxhunt_core::fix::intersection::MIN_CROSSING;
use foxhunt_core::fix::ml::{MlOptions, ml};
use foxhunt_core::{Bearing, Error, Filter, Fix, Gaussian, Method, ParticleSet, WithFilter};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Most bearings one replay keeps (a drive of two minutes at one bearing a second).
pub const MAX_BEARINGS: usize = 128;

/// What a replay found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Replay {
    /// The SIR filter's final mean, or why it has none.
    pub sir: Result<[f32; 2], Error>,
    /// The ML fix, or why it has none.
    pub ml: Result<Fix, Error>,
    /// Bearings used.
    pub bearings: usize,
    /// Bearings beyond [`MAX_BEARINGS`], not used.
    pub dropped: usize,
    /// What the demultiplexer rejected.
    pub stream: StreamCounters,
    /// What the bridge rejected.
    pub bridge: BridgeCounters,
}

/// Feed `capture` in reads of `chunk` bytes (1 to [`READ_BUFFER`]) through a receiver, then
/// run a SIR filter with `N` particles (initialised from bearing pairs, as the bench does) over
/// the first `steps` bearings (all of them with `usize::MAX`; 0 gives the cost of everything
/// but the steps) and the ML fix.
pub fn replay<const N: usize>(
    mut capture: &[u8],
    chunk: usize,
    config: BridgeConfig,
    seed: u64,
    steps: usize,
) -> Replay {
    let read = |buf: &mut [u8]| {
        let n = buf.len().min(capture.len());
        buf[..n].copy_from_slice(&capture[..n]);
        capture = &capture[n..];
        Ok::<usize, core::convert::Infallible>(n)
    };
    match replay_from::<N, _>(read, chunk, config, seed, steps) {
        Ok(r) => r,
        Err(never) => match never {},
    }
}

/// Largest read [`replay_from`] asks for: a UART driver's DMA buffer.
pub const READ_BUFFER: usize = 64;

/// [`replay`] from a byte source: `read` fills the buffer it is given (at most `chunk` bytes)
/// and returns how many it wrote, 0 at the end, as a serial driver or a file does. A read
/// error ends the replay with that error.
pub fn replay_from<const N: usize, E>(
    mut read: impl FnMut(&mut [u8]) -> Result<usize, E>,
    chunk: usize,
    config: BridgeConfig,
    seed: u64,
    steps: usize,
) -> Result<Replay, E> {
    let mut rx = Receiver::<0>::new(config, []);
    let mut bearings = heapless::Vec::<Bearing, MAX_BEARINGS>::new();
    let mut dropped = 0;
    let mut sink = |e: Event| {
        if let Event::Bearing(b) = e
            && bearings.push(b.bearing).is_err()
        {
            dropped += 1;
        }
    };
    let mut buf = [0u8; READ_BUFFER];
    let buf = &mut buf[..chunk.clamp(1, READ_BUFFER)];
    loop {
        let n = read(buf)?.min(buf.len());
        if n == 0 {
            break;
        }
        rx.feed(&buf[..n], &mut sink);
    }
    rx.finish(&mut sink);
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let sir = run_sir::<N>(&bearings, steps, &mut rng);
    let ml = ml(&bearings, None, &Gaussian, MlOptions::default());
    let (stream, bridge) = rx.counters();
    Ok(Replay {
        sir,
        ml,
        bearings: bearings.len(),
        dropped,
        stream: *stream,
        bridge: *bridge,
    })
}

/// The registry's tuned `sir` stepped over the first `steps` bearings from `cloud`.
struct FirstSteps<'a> {
    cloud: &'a [[f32; 2]],
    bearings: &'a [Bearing],
    steps: usize,
    rng: &'a mut XorShiftRng,
}

impl WithFilter<2, Bearing> for FirstSteps<'_> {
    type Output = Result<[f32; 2], Error>;
    fn visit<F: Filter<2, Measurement = Bearing>>(self, f: &mut F) -> Self::Output {
        f.initialise(self.cloud, self.rng)?;
        for b in self.bearings.iter().take(self.steps) {
            let _ = f.step(b, self.rng);
        }
        Ok(f.estimate()?.mean)
    }
}

fn run_sir<const N: usize>(
    bearings: &[Bearing],
    steps: usize,
    rng: &mut XorShiftRng,
) -> Result<[f32; 2], Error> {
    let mut cloud = ParticleSet::<N, 2>::new();
    initial_particles(bearings, MIN_CROSSING, &mut cloud, rng)?;
    let run = FirstSteps {
        cloud: &cloud.states,
        bearings,
        steps,
        rng,
    };
    with_bearing_filter::<N, _>(Method::Sir, 0.0, run)?
}

/// The lines both the firmware and the host print for a replay: the bits of every result, so
/// two runs agree exactly or visibly not.
pub fn write_summary(r: &Replay, out: &mut impl core::fmt::Write) -> core::fmt::Result {
    match r.sir {
        Ok(p) => writeln!(out, "sir {:08x} {:08x}", bits(p[0]), bits(p[1]))?,
        Err(e) => writeln!(out, "sir error {e:?}")?,
    }
    match r.ml {
        Ok(f) => writeln!(
            out,
            "ml {:08x} {:08x} cov {:08x} {:08x} {:08x} iterations {}",
            bits(f.position[0]),
            bits(f.position[1]),
            bits(f.covariance[0][0]),
            bits(f.covariance[0][1]),
            bits(f.covariance[1][1]),
            f.iterations
        )?,
        Err(e) => writeln!(out, "ml error {e:?}")?,
    }
    writeln!(
        out,
        "bearings {} dropped {} sentences {} rejected {} fixes {}",
        r.bearings,
        r.dropped,
        r.stream.sentences,
        r.stream.rejected(),
        r.bridge.fixes
    )
}

/// The bits of a result, NaN made canonical (x86 and ARM differ in NaN payloads only).
pub fn bits(v: f32) -> u32 {
    if v.is_nan() { 0x7fc0_0000 } else { v.to_bits() }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAPTURE: &[u8] = include_bytes!("../captures/aoa-drive.nmea");

    /// A byte source that hands out `step` bytes per read (fewer than asked, as a UART does)
    /// and fails after `fail_after` bytes.
    fn source(
        step: usize,
        fail_after: usize,
    ) -> impl FnMut(&mut [u8]) -> Result<usize, &'static str> {
        let mut at = 0;
        move |buf: &mut [u8]| {
            if at >= fail_after {
                return Err("line dropped");
            }
            let n = step.min(buf.len()).min(CAPTURE.len() - at);
            buf[..n].copy_from_slice(&CAPTURE[at..at + n]);
            at += n;
            Ok(n)
        }
    }

    #[test]
    fn short_reads_give_the_same_replay() {
        let config = BridgeConfig::default();
        let whole = replay::<20>(CAPTURE, READ_BUFFER, config, 3, usize::MAX);
        assert_eq!(whole.bearings, 60);
        for step in [1, 7, 64] {
            let r =
                replay_from::<20, _>(source(step, usize::MAX), READ_BUFFER, config, 3, usize::MAX);
            assert_eq!(r, Ok(whole), "reads of {step}");
        }
    }

    #[test]
    fn a_read_error_ends_the_replay_with_it() {
        let r = replay_from::<20, _>(source(64, 1000), 64, BridgeConfig::default(), 3, usize::MAX);
        assert_eq!(r, Err("line dropped"));
    }
}
