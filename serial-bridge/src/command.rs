//! Configuration commands on the unit's user port: `$PFOXC,<command>[,<arguments>]*hh`.
//!
//! Checksummed like every sentence (line noise must not reconfigure the unit), answered by a
//! `$PFOXA` acknowledgement ([`crate::telemetry`]) that echoes the setting as applied, and kept
//! until reset.
//!
//! | command | arguments | what it sets |
//! |---|---|---|
//! | `SIGMA` | degrees (0.05 to 45), or `EST` | the bearing noise: stated, or estimated from the residuals |
//! | `GATE` | quality 0 to 100 | PFOXB bearings at or below it are rejected |
//! | `REF` | `ddmm.mmmm,N\|S,dddmm.mmmm,E\|W`, or `AUTO` | the local frame's origin (`AUTO`: the first GPS fix) |
//! | `MOUNT` | degrees (-360 to 360) | the DF antenna's offset, clockwise from the vehicle's front |
//! | `WINDOW` | bearings (1 to 128), seconds (1 to 86400) | the tracker's window by count and age |
//! | `ZIGBEE` | `ON` or `OFF` | whether the third input port (MT frames) is read |
//! | `SHOW` | none | nothing: the acknowledgement lists every setting |
//!
//! `GATE`, `REF` and `MOUNT` restart the bridge (its fix history and heading state): bearings
//! resume with the next GPS fix. `REF` and `MOUNT` also empty the tracker's window, whose
//! bearings were placed in the old frame or turned by the old offset.

use crate::nmea::{LatLon, angle, number};
use foxhunt_core::fix::window::WINDOW;

/// A decoded command.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Bearing sigma in degrees, or `None`: estimate it.
    Sigma(Option<f32>),
    /// Quality gate, 0 to 100.
    Gate(f32),
    /// Local origin, or `None`: the first fix.
    Reference(Option<LatLon>),
    /// Mounting offset, degrees.
    Mount(f32),
    /// Window: bearings and seconds.
    Window {
        /// Bearings at most.
        count: u16,
        /// Age at most, seconds.
        seconds: u32,
    },
    /// Read the ZigBee port.
    Zigbee(bool),
    /// List the settings.
    Show,
}

/// Why a command was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandError {
    /// Not a `PFOXC` sentence.
    NotCommand,
    /// A command name this unit does not know.
    Unknown,
    /// An argument missing, malformed or out of range.
    BadArgument,
}

impl CommandError {
    /// The word the acknowledgement gives.
    pub fn word(self) -> &'static str {
        match self {
            Self::NotCommand => "NOT-COMMAND",
            Self::Unknown => "UNKNOWN",
            Self::BadArgument => "ARGUMENT",
        }
    }
}

impl core::fmt::Display for CommandError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NotCommand => "not a PFOXC command",
            Self::Unknown => "unknown command",
            Self::BadArgument => "command argument missing, malformed or out of range",
        })
    }
}

/// The name of a command sentence's command (for the acknowledgement of one that fails).
pub fn name_of(body: &str) -> &str {
    let mut f = body.split(',');
    match (f.next(), f.next()) {
        (Some("PFOXC"), Some(name))
            if name.len() <= 8 && name.bytes().all(|b| b.is_ascii_uppercase()) =>
        {
            name
        }
        _ => "?",
    }
}

fn real_in(s: Option<&str>, lo: f64, hi: f64) -> Result<f32, CommandError> {
    s.and_then(number)
        .filter(|v| (lo..=hi).contains(v))
        .map(|v| v as f32)
        .ok_or(CommandError::BadArgument)
}

fn uint_in(s: Option<&str>, lo: u32, hi: u32) -> Result<u32, CommandError> {
    s.filter(|s| !s.is_empty() && s.len() <= 6 && s.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|s| s.parse::<u32>().ok())
        .filter(|v| (lo..=hi).contains(v))
        .ok_or(CommandError::BadArgument)
}

impl Command {
    /// Decode a checked sentence body (`PFOXC,...`).
    pub fn parse(body: &str) -> Result<Self, CommandError> {
        let mut f = body.split(',');
        if f.next() != Some("PFOXC") {
            return Err(CommandError::NotCommand);
        }
        let name = f.next().ok_or(CommandError::Unknown)?;
        let mut args = [None::<&str>; 4];
        for a in args.iter_mut() {
            *a = f.next();
        }
        if f.next().is_some() {
            return Err(CommandError::BadArgument);
        }
        let [a, b, c, d] = args;
        let count = args.iter().flatten().count();
        let want = |n: usize| {
            if count == n {
                Ok(())
            } else {
                Err(CommandError::BadArgument)
            }
        };
        match name {
            "SIGMA" => {
                want(1)?;
                if a == Some("EST") {
                    Ok(Self::Sigma(None))
                } else {
                    real_in(a, 0.05, 45.0).map(|v| Self::Sigma(Some(v)))
                }
            }
            "GATE" => {
                want(1)?;
                real_in(a, 0.0, 100.0).map(Self::Gate)
            }
            "REF" => {
                if a == Some("AUTO") {
                    want(1)?;
                    return Ok(Self::Reference(None));
                }
                want(4)?;
                let (a, b, c, d) = (
                    a.unwrap_or(""),
                    b.unwrap_or(""),
                    c.unwrap_or(""),
                    d.unwrap_or(""),
                );
                let lat = angle(a, b, 90.0, b'N', b'S').ok_or(CommandError::BadArgument)?;
                let lon = angle(c, d, 180.0, b'E', b'W').ok_or(CommandError::BadArgument)?;
                Ok(Self::Reference(Some(LatLon { lat, lon })))
            }
            "MOUNT" => {
                want(1)?;
                real_in(a, -360.0, 360.0).map(Self::Mount)
            }
            "WINDOW" => {
                want(2)?;
                Ok(Self::Window {
                    count: uint_in(a, 1, WINDOW as u32)? as u16,
                    seconds: uint_in(b, 1, 86_400)?,
                })
            }
            "ZIGBEE" => {
                want(1)?;
                match a {
                    Some("ON") => Ok(Self::Zigbee(true)),
                    Some("OFF") => Ok(Self::Zigbee(false)),
                    _ => Err(CommandError::BadArgument),
                }
            }
            "SHOW" => {
                want(0)?;
                Ok(Self::Show)
            }
            _ => Err(CommandError::Unknown),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_parses() {
        assert_eq!(
            Command::parse("PFOXC,SIGMA,1.5"),
            Ok(Command::Sigma(Some(1.5)))
        );
        assert_eq!(Command::parse("PFOXC,SIGMA,EST"), Ok(Command::Sigma(None)));
        assert_eq!(Command::parse("PFOXC,GATE,55"), Ok(Command::Gate(55.0)));
        let Ok(Command::Reference(Some(p))) = Command::parse("PFOXC,REF,4700.6000,N,00800.3000,W")
        else {
            panic!("REF")
        };
        assert!((p.lat - 47.01).abs() < 1e-9 && (p.lon + 8.005).abs() < 1e-9);
        assert_eq!(
            Command::parse("PFOXC,REF,AUTO"),
            Ok(Command::Reference(None))
        );
        assert_eq!(
            Command::parse("PFOXC,MOUNT,-12.5"),
            Ok(Command::Mount(-12.5))
        );
        assert_eq!(
            Command::parse("PFOXC,WINDOW,60,120"),
            Ok(Command::Window {
                count: 60,
                seconds: 120
            })
        );
        assert_eq!(Command::parse("PFOXC,ZIGBEE,ON"), Ok(Command::Zigbee(true)));
        assert_eq!(Command::parse("PFOXC,SHOW"), Ok(Command::Show));
    }

    #[test]
    fn bad_commands_are_named() {
        use CommandError::*;
        for (body, e) in [
            ("GPGGA,1", NotCommand),
            ("PFOXC,REBOOT", Unknown),
            ("PFOXC,SIGMA,0", BadArgument),
            ("PFOXC,SIGMA,1,2", BadArgument),
            ("PFOXC,GATE,101", BadArgument),
            ("PFOXC,WINDOW,129,10", BadArgument),
            ("PFOXC,WINDOW,10", BadArgument),
            ("PFOXC,REF,9100.0,N,00800.0,E", BadArgument),
            ("PFOXC,ZIGBEE,MAYBE", BadArgument),
            ("PFOXC,SHOW,1", BadArgument),
            ("PFOXC,MOUNT,1,2,3,4,5", BadArgument),
        ] {
            assert_eq!(Command::parse(body), Err(e), "{body}");
        }
        assert_eq!(name_of("PFOXC,REBOOT"), "REBOOT");
        assert_eq!(name_of("PFOXC,re"), "?");
    }
}
