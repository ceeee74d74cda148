//! What a record is, from its first bytes: the one place the crate and its users tell a GPS
//! position from a heading, a bearing, the DF unit's own sentences or an MT frame.
//!
//! Two levels. [`Framing::of`] reads a record's first byte, which is all the demultiplexer
//! needs to pick the check it runs: a sentence (`$`), a TI Monitor-and-Test frame (`0xFE`),
//! an Agrelo bearing (`%`), a KrakenSDR XML record (`<`) or CSV line (a digit). [`RecordKind`]
//! names the record itself, down to the sentence type, with a stable short name
//! ([`RecordKind::name`], what `foxhunt frames` prints as `kind`) and its class
//! ([`RecordKind::class`]: position, heading, bearing, ...).
//!
//! A sentence's type is read from its address, exactly: a talker of two capital letters (not
//! `P`, which starts a proprietary address in NMEA 0183), three capital letters of type, then
//! `,` or the end of the address (`*`, or the end of a checked body): `$1AGGA` and `$GPGGAX`
//! are no GGA. Of proprietary addresses this project's own are named (`PFOXB` and the unit's
//! `PFOXF`, `PFOXS`, `PFOXL`, `PFOXR`, `PFOXA`, `PFOXC`), matched whole; every other sentence
//! is [`RecordKind::Nmea`].

use crate::mt::MT_SOF;
use core::fmt;

/// How a record is framed, from its first byte: which check the demultiplexer runs on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Framing {
    /// An NMEA-style sentence, `$` ... `*hh` and a line end.
    Sentence,
    /// A TI Monitor-and-Test frame (`0xFE`, LEN, CMD0, CMD1, data, FCS).
    Mt,
    /// An Agrelo bearing, `%` to the line end.
    Agrelo,
    /// A KrakenSDR / KerberosSDR XML record, from `<`.
    KrakenXml,
    /// A KrakenSDR CSV line, from its first digit.
    KrakenCsv,
}

impl Framing {
    /// The framing a record starting with `first` has; `None`: no record starts with it.
    pub const fn of(first: u8) -> Option<Self> {
        match first {
            b'$' => Some(Self::Sentence),
            MT_SOF => Some(Self::Mt),
            b'%' => Some(Self::Agrelo),
            b'<' => Some(Self::KrakenXml),
            b'0'..=b'9' => Some(Self::KrakenCsv),
            _ => None,
        }
    }
}

/// What a record is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordKind {
    /// GGA: fix time, position, quality.
    Gga,
    /// RMC: time, date, position, speed and course.
    Rmc,
    /// GLL: position and its time.
    Gll,
    /// GNS: the multi-constellation fix.
    Gns,
    /// VTG: course and speed over ground.
    Vtg,
    /// HDT: true heading.
    Hdt,
    /// THS: true heading and its mode.
    Ths,
    /// HDG: a magnetic sensor's heading.
    Hdg,
    /// HDM: magnetic heading.
    Hdm,
    /// `$PFOXB`: a bearing from the direction finder.
    Pfoxb,
    /// `$PFOXF`: the unit's fix.
    Pfoxf,
    /// `$PFOXS`: the unit's status.
    Pfoxs,
    /// `$PFOXL`: the unit's link counters.
    Pfoxl,
    /// `$PFOXR`: the unit's ready banner.
    Pfoxr,
    /// `$PFOXA`: the unit's acknowledgement of a command.
    Pfoxa,
    /// `$PFOXC`: a configuration command for the unit.
    Pfoxc,
    /// Any other sentence.
    Nmea,
    /// An Agrelo `%` bearing.
    Agrelo,
    /// A KrakenSDR XML record.
    KrakenXml,
    /// A KrakenSDR CSV line.
    KrakenCsv,
    /// A TI Monitor-and-Test frame.
    Mt,
}

/// The class of a record kind: what the bridge and the unit do with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordClass {
    /// A GPS position sentence: GGA, RMC, GLL, GNS.
    Position,
    /// A heading or course sentence: HDT, THS, HDG, HDM, VTG.
    Heading,
    /// A bearing: `$PFOXB`, Agrelo, KrakenSDR CSV or XML.
    Bearing,
    /// The DF unit's own sentences: `$PFOXF`, `$PFOXS`, `$PFOXL`, `$PFOXR`, `$PFOXA`.
    Unit,
    /// A command to the unit: `$PFOXC`.
    Command,
    /// Any other sentence.
    OtherSentence,
    /// A TI Monitor-and-Test frame (link qualities).
    Mt,
}

/// Sentence types by their three address letters after a talker.
const TYPES: [(&[u8; 3], RecordKind); 9] = [
    (b"GGA", RecordKind::Gga),
    (b"RMC", RecordKind::Rmc),
    (b"GLL", RecordKind::Gll),
    (b"GNS", RecordKind::Gns),
    (b"VTG", RecordKind::Vtg),
    (b"HDT", RecordKind::Hdt),
    (b"THS", RecordKind::Ths),
    (b"HDG", RecordKind::Hdg),
    (b"HDM", RecordKind::Hdm),
];

/// This project's proprietary addresses, whole.
const PROPRIETARY: [(&[u8; 5], RecordKind); 7] = [
    (b"PFOXB", RecordKind::Pfoxb),
    (b"PFOXF", RecordKind::Pfoxf),
    (b"PFOXS", RecordKind::Pfoxs),
    (b"PFOXL", RecordKind::Pfoxl),
    (b"PFOXR", RecordKind::Pfoxr),
    (b"PFOXA", RecordKind::Pfoxa),
    (b"PFOXC", RecordKind::Pfoxc),
];

impl RecordKind {
    /// Every kind, in declaration order.
    pub const ALL: [Self; 21] = [
        Self::Gga,
        Self::Rmc,
        Self::Gll,
        Self::Gns,
        Self::Vtg,
        Self::Hdt,
        Self::Ths,
        Self::Hdg,
        Self::Hdm,
        Self::Pfoxb,
        Self::Pfoxf,
        Self::Pfoxs,
        Self::Pfoxl,
        Self::Pfoxr,
        Self::Pfoxa,
        Self::Pfoxc,
        Self::Nmea,
        Self::Agrelo,
        Self::KrakenXml,
        Self::KrakenCsv,
        Self::Mt,
    ];

    /// The kind of the record `record` starts (its raw bytes from `$`, `0xFE`, `%`, `<` or a
    /// digit; a sentence needs its address, up to `,` or `*`). `None`: no record starts with
    /// its first byte.
    pub fn of_record(record: &[u8]) -> Option<Self> {
        Some(match Framing::of(*record.first()?)? {
            Framing::Sentence => Self::of_address(record.get(1..).unwrap_or_default()),
            Framing::Mt => Self::Mt,
            Framing::Agrelo => Self::Agrelo,
            Framing::KrakenXml => Self::KrakenXml,
            Framing::KrakenCsv => Self::KrakenCsv,
        })
    }

    /// The kind of a checked sentence from its body, the text between `$` and `*` (what
    /// [`crate::Frame::Nmea`] carries).
    pub fn of_sentence(body: &str) -> Self {
        Self::of_address(body.as_bytes())
    }

    /// A sentence's kind from the bytes after its `$`: the address ends at `,`, `*` or the
    /// end of the bytes.
    fn of_address(after_dollar: &[u8]) -> Self {
        let end = after_dollar
            .iter()
            .position(|&b| b == b',' || b == b'*')
            .unwrap_or(after_dollar.len());
        let address = after_dollar.get(..end).unwrap_or_default();
        if let Some((_, kind)) = PROPRIETARY.iter().find(|(a, _)| address == a.as_slice()) {
            return *kind;
        }
        match address {
            [t0, t1, kind @ ..]
                if t0.is_ascii_uppercase() && *t0 != b'P' && t1.is_ascii_uppercase() =>
            {
                TYPES
                    .iter()
                    .find(|(t, _)| kind == t.as_slice())
                    .map_or(Self::Nmea, |(_, k)| *k)
            }
            _ => Self::Nmea,
        }
    }

    /// The stable short name (`gga`, `pfoxb`, `kraken_csv`, ...): `foxhunt frames`' `kind`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Gga => "gga",
            Self::Rmc => "rmc",
            Self::Gll => "gll",
            Self::Gns => "gns",
            Self::Vtg => "vtg",
            Self::Hdt => "hdt",
            Self::Ths => "ths",
            Self::Hdg => "hdg",
            Self::Hdm => "hdm",
            Self::Pfoxb => "pfoxb",
            Self::Pfoxf => "pfoxf",
            Self::Pfoxs => "pfoxs",
            Self::Pfoxl => "pfoxl",
            Self::Pfoxr => "pfoxr",
            Self::Pfoxa => "pfoxa",
            Self::Pfoxc => "pfoxc",
            Self::Nmea => "nmea",
            Self::Agrelo => "agrelo",
            Self::KrakenXml => "kraken_xml",
            Self::KrakenCsv => "kraken_csv",
            Self::Mt => "mt",
        }
    }

    /// What the record is for.
    pub const fn class(self) -> RecordClass {
        match self {
            Self::Gga | Self::Rmc | Self::Gll | Self::Gns => RecordClass::Position,
            Self::Vtg | Self::Hdt | Self::Ths | Self::Hdg | Self::Hdm => RecordClass::Heading,
            Self::Pfoxb | Self::Agrelo | Self::KrakenXml | Self::KrakenCsv => RecordClass::Bearing,
            Self::Pfoxf | Self::Pfoxs | Self::Pfoxl | Self::Pfoxr | Self::Pfoxa => {
                RecordClass::Unit
            }
            Self::Pfoxc => RecordClass::Command,
            Self::Nmea => RecordClass::OtherSentence,
            Self::Mt => RecordClass::Mt,
        }
    }

    /// How the record is framed.
    pub const fn framing(self) -> Framing {
        match self {
            Self::Agrelo => Framing::Agrelo,
            Self::KrakenXml => Framing::KrakenXml,
            Self::KrakenCsv => Framing::KrakenCsv,
            Self::Mt => Framing::Mt,
            _ => Framing::Sentence,
        }
    }
}

impl fmt::Display for RecordKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sentence_types_are_matched_exactly() {
        let cases: [(&[u8], Option<RecordKind>); 18] = [
            (b"$GPGGA,1", Some(RecordKind::Gga)),
            (b"$GNRMC*00", Some(RecordKind::Rmc)),
            (b"$GLGLL", Some(RecordKind::Gll)),
            (b"$HEHDT,274.07,T*03\r\n", Some(RecordKind::Hdt)),
            (b"$GPGGAX,1", Some(RecordKind::Nmea)),
            (b"$1AGGA,1", Some(RecordKind::Nmea)),
            (b"$gpgga,1", Some(RecordKind::Nmea)),
            (b"$GGA,1", Some(RecordKind::Nmea)),
            // A proprietary address is no talker: Garmin's PGRMC is no RMC.
            (b"$PGRMC,1", Some(RecordKind::Nmea)),
            (b"$PFOXB,1", Some(RecordKind::Pfoxb)),
            (b"$PFOXBX,1", Some(RecordKind::Nmea)),
            (b"$PFOXC,SHOW*00", Some(RecordKind::Pfoxc)),
            (b"$PFOXF,", Some(RecordKind::Pfoxf)),
            (b"%136/8\r\n", Some(RecordKind::Agrelo)),
            (b"<DATA>", Some(RecordKind::KrakenXml)),
            (b"1679512414650, 134", Some(RecordKind::KrakenCsv)),
            (&[0xFE, 0x02, 0x44, 0x81], Some(RecordKind::Mt)),
            (b"xx$GPGGA", None),
        ];
        for (record, want) in cases {
            assert_eq!(
                RecordKind::of_record(record),
                want,
                "{}",
                String::from_utf8_lossy(record)
            );
        }
        assert_eq!(RecordKind::of_record(b""), None);
        assert_eq!(RecordKind::of_sentence("GNGNS,122310.2"), RecordKind::Gns);
        assert_eq!(RecordKind::of_sentence("APHDM"), RecordKind::Hdm);
        assert_eq!(RecordKind::of_sentence(""), RecordKind::Nmea);
    }

    #[test]
    fn names_are_distinct_and_framing_agrees_with_the_first_byte() {
        let mut names: std::vec::Vec<&str> = RecordKind::ALL.iter().map(|k| k.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), RecordKind::ALL.len());
        for k in RecordKind::ALL {
            let first = match k.framing() {
                Framing::Sentence => b'$',
                Framing::Mt => MT_SOF,
                Framing::Agrelo => b'%',
                Framing::KrakenXml => b'<',
                Framing::KrakenCsv => b'7',
            };
            assert_eq!(Framing::of(first), Some(k.framing()), "{k}");
        }
        assert_eq!(Framing::of(b' '), None);
    }
}
