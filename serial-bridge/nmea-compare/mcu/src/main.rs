//! The bundled drive (GGA, RMC, PFOXB) in 64-byte reads through the framing and one NMEA
//! decoder: ours (feature `ours`), the nmea crate's (`nmea-crate`), or none. The drive sits in
//! flash in every variant, so flash and instruction differences are the decoder's.
//! `measure.sh` builds the three and counts instructions in QEMU.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod image {
    use core::hint::black_box;
    use cortex_m as _;
    use cortex_m_rt::entry;
    use foxhunt_bridge::{Demux, Frame};

    const DRIVE: &[u8] = include_bytes!("../../../captures/aoa-drive.nmea");

    /// Latitude of a fix the decoder finds in a sentence body.
    #[allow(unused_variables)]
    fn decode(body: &str) -> Option<f64> {
        #[cfg(feature = "ours")]
        {
            use foxhunt_bridge::nmea::Sentence;
            return match Sentence::parse(body) {
                Ok(Sentence::Gga(g)) => Some(g.position.lat),
                Ok(Sentence::Rmc(r)) => Some(r.position.lat),
                Ok(Sentence::Gll(g)) => Some(g.position.lat),
                Ok(Sentence::Gns(g)) => Some(g.position.lat),
                _ => None,
            };
        }
        #[cfg(feature = "nmea-crate")]
        {
            use core::fmt::Write;
            use nmea::ParseResult as P;
            let mut line = heapless::String::<140>::new();
            write!(line, "${body}*{:02X}", foxhunt_bridge::nmea::checksum(body)).ok()?;
            return match nmea::parse_str(&line).ok()? {
                P::GGA(g) => g.latitude,
                P::RMC(r) => r.lat,
                P::GLL(g) => g.latitude,
                P::GNS(g) => g.lat,
                _ => None,
            };
        }
        #[allow(unreachable_code)]
        black_box(None)
    }

    #[entry]
    fn main() -> ! {
        let mut demux = Demux::<600>::new();
        let (mut fixes, mut sum) = (0u32, 0.0f64);
        let mut sink = |f: Frame<'_>| {
            if let Frame::Nmea(body) = f
                && let Some(lat) = decode(black_box(body))
            {
                fixes += 1;
                sum += lat;
            }
        };
        for chunk in black_box(DRIVE).chunks(64) {
            demux.feed(chunk, &mut sink);
        }
        demux.finish_into(&mut sink);
        black_box(sum);
        // Exit status: fixes found (modulo 256), so a run shows the decoder worked.
        semihosting::process::exit((fixes % 256) as i32)
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
