use super::*;

fn body(s: &Sentence) -> Line {
    let mut line = Line::new();
    s.emit(&mut line).expect("fits");
    line
}

#[test]
fn spec_examples() {
    let Ok(Sentence::Gga(g)) =
        Sentence::parse("GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,")
    else {
        panic!("GGA")
    };
    assert_eq!(g.time.ms_of_day, (9 * 3600 + 27 * 60 + 50) * 1000);
    assert!((g.position.lat - (53.0 + 21.6802 / 60.0)).abs() < 1e-12);
    assert!((g.position.lon + (6.0 + 30.3372 / 60.0)).abs() < 1e-12);
    let Ok(Sentence::Rmc(r)) =
        Sentence::parse("GPRMC,092750.000,A,5321.6802,N,00630.3372,W,0.02,31.66,280511,,,A")
    else {
        panic!("RMC")
    };
    assert_eq!(
        r.date,
        Some(Date {
            year: 2011,
            month: 5,
            day: 28
        })
    );
    assert_eq!((r.speed_kn, r.course_deg), (Some(0.02), Some(31.66)));
    let Ok(Sentence::Pfoxb(b)) = Sentence::parse("PFOXB,092751.00,57.3,T,83,433.920") else {
        panic!("PFOXB")
    };
    assert_eq!(b.time.ms_of_day, (9 * 3600 + 27 * 60 + 51) * 1000);
    assert_eq!(
        (b.azimuth_deg, b.reference, b.quality),
        (57.3, Reference::True, 83.0)
    );
    assert_eq!(checksum("PFOXB,092751.00,57.3,T,83,433.920"), 0x28);
}

#[test]
fn protocols_examples_of_the_gpsd_grade_sentences() {
    // docs/src/formats/nmea.md's examples, each with the checksum the receiver sent.
    assert_eq!(checksum("GPVTG,330.63,T,345.26,M,0.00,N,0.00,K,A"), 0x20);
    let v = Vtg::parse("GPVTG,330.63,T,345.26,M,0.00,N,0.00,K,A").expect("VTG");
    assert_eq!(
        (v.course_deg, v.course_magnetic_deg, v.speed_kn, v.old_form),
        (Some(330.63), Some(345.26), Some(0.0), false)
    );
    let old = Vtg::parse("GPVTG,054.7,034.4,005.5,010.2").expect("old VTG");
    assert!(old.old_form && old.course_deg == Some(54.7) && old.speed_kn == Some(5.5));
    assert_eq!(checksum("GPHDT,274.07,T"), 0x03);
    assert_eq!(
        Hdt::parse("GPHDT,274.07,T").map(|h| h.heading_deg),
        Ok(274.07)
    );
    assert_eq!(checksum("GNTHS,244.28,A"), 0x11);
    let t = Ths::parse("GNTHS,244.28,A").expect("THS");
    assert_eq!((t.heading_deg, t.mode), (244.28, b'A'));
    assert_eq!(Ths::parse("GNTHS,,V"), Err(NmeaError::NoFix));
    assert_eq!(checksum("SDHDG,229.8,,,1.3,E"), 0x36);
    let h = Hdg::parse("SDHDG,229.8,,,1.3,E").expect("HDG");
    assert_eq!((h.deviation_deg, h.variation_deg), (None, Some(1.3)));
    assert!((h.true_deg().expect("variation") - 231.1).abs() < 1e-9);
    assert_eq!(checksum("APHDM,218.634,M"), 0x39);
    assert_eq!(
        Hdm::parse("APHDM,218.634,M").map(|h| h.heading_deg),
        Ok(218.634)
    );
    let long =
        "GPGGA,132820.60,4134.49821229,N,09345.03351845,W,2,09,1.0,278.020,M,-31.442,M,7.6,0133";
    assert_eq!(checksum(long), 0x7E);
    let g = Gga::parse(long).expect("RTK GGA");
    assert!((g.position.lat - (41.0 + 34.498_212_29 / 60.0)).abs() < 1e-12);
}

#[test]
fn hdg_signs_deviation_west_variation_west() {
    // Sensor 100, deviation 2 W: magnetic 98; variation 5.5 W: true 92.5.
    let h = Hdg::parse("HCHDG,100.0,2.0,W,5.5,W").expect("HDG");
    assert_eq!(h.magnetic_deg(), 98.0);
    assert_eq!(h.true_deg(), Some(92.5));
    // Across north: 359 + 3 E = 2.
    let h = Hdg::parse("HCHDG,359.0,,,3.0,E").expect("HDG");
    assert!((h.true_deg().expect("var") - 2.0).abs() < 1e-9);
    assert_eq!(
        Hdg::parse("HCHDG,10.0,1.0,X,,"),
        Err(NmeaError::BadField(3))
    );
}

#[test]
fn gll_gns_and_empty_quality_gga() {
    let l = Gll::parse("GPGLL,4916.45,N,12311.12,W,225444,A").expect("GLL");
    assert_eq!(
        l.time.map(|t| t.ms_of_day),
        Some((22 * 3600 + 54 * 60 + 44) * 1000)
    );
    assert!((l.position.lon + (123.0 + 11.12 / 60.0)).abs() < 1e-12);
    assert_eq!(
        Gll::parse("GPGLL,4916.45,N,12311.12,W,225444,V"),
        Err(NmeaError::NoFix)
    );
    assert!(
        Gll::parse("GPGLL,4916.45,N,12311.12,W").is_ok(),
        "NMEA 1.5 GLL"
    );
    let n = Gns::parse("GNGNS,122310.2,3722.425671,N,12258.856215,W,AAN,14,0.9,1005.543,6.5,,")
        .expect("GNS");
    assert_eq!((n.mode, n.satellites), (b'A', Some(14)));
    assert_eq!(
        Gns::parse("GNGNS,122310.2,,,,,NNN,0,,,,,"),
        Err(NmeaError::NoFix)
    );
    // myguide-3100 in GPSD's suite: empty quality, 3 satellites a fix, 2 none.
    let g = Gga::parse("GPGGA,105027.80,5612.9956,N,00306.6983,W,,3,2.506,160.002,M,,M,,")
        .expect("empty quality with three satellites");
    assert_eq!(g.quality, None);
    assert_eq!(
        Gga::parse("GPGGA,105025.80,5612.9999,N,00306.7096,W,,2,60.000,160.002,M,,M,,"),
        Err(NmeaError::NoFix)
    );
    // mtk-3301: quality 0 with 3 satellites is GPSD's 2D fix.
    assert!(
        Gga::parse("GPGGA,081434.590,5212.978993,N,00653.097906,E,0,3,,102.907,M,47.093,M,,")
            .is_ok()
    );
    assert_eq!(
        Sentence::parse("IIHDT,10.5,T").map(|_| ()),
        Ok(()),
        "any talker"
    );
}

#[test]
fn no_fix_and_bad_fields() {
    assert_eq!(
        Sentence::parse("GPGGA,092750.000,,,,,0,0,,,M,,M,,"),
        Err(NmeaError::NoFix)
    );
    assert_eq!(
        Sentence::parse("GNRMC,092750.000,V,5321.6802,N,00630.3372,W,,,280511,,,N"),
        Err(NmeaError::NoFix)
    );
    assert_eq!(
        Sentence::parse("GPGGA,092750.000,5391.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,"),
        Err(NmeaError::BadField(2))
    );
    assert_eq!(
        Sentence::parse("PFOXB,092751.00,360.0,T,83,433.920"),
        Err(NmeaError::BadField(2))
    );
    assert_eq!(
        Sentence::parse("PFOXB,092751.00,5,X,83,433.920"),
        Err(NmeaError::BadField(3))
    );
    assert_eq!(Sentence::parse("GPGSV,3,1,12"), Err(NmeaError::Unsupported));
    assert_eq!(Sentence::parse("xxGGA,1"), Err(NmeaError::Unsupported));
}

#[test]
fn every_type_round_trips_through_emit_and_parse() {
    let p = LatLon {
        lat: -37.784_788_333,
        lon: 175.314_896_667,
    };
    let t = UtcTime {
        ms_of_day: 11_239_500,
    };
    let all = [
        Sentence::Gga(Gga {
            talker: *b"GN",
            time: t,
            position: p,
            quality: Some(4),
            satellites: Some(12),
            hdop: Some(0.5),
            altitude_m: Some(61.5),
        }),
        Sentence::Rmc(Rmc {
            talker: *b"GP",
            time: t,
            date: Some(Date {
                year: 2026,
                month: 6,
                day: 1,
            }),
            position: p,
            speed_kn: Some(12.25),
            course_deg: Some(359.5),
        }),
        Sentence::Gll(Gll {
            talker: *b"GL",
            position: p,
            time: Some(t),
        }),
        Sentence::Gns(Gns {
            talker: *b"GN",
            time: t,
            position: p,
            mode: b'D',
            satellites: Some(9),
            hdop: Some(1.5),
            altitude_m: None,
        }),
        Sentence::Vtg(Vtg {
            talker: *b"GP",
            course_deg: Some(330.63),
            course_magnetic_deg: None,
            speed_kn: Some(1.5),
            speed_kmh: Some(2.78),
            old_form: false,
        }),
        Sentence::Vtg(Vtg {
            talker: *b"GP",
            course_deg: Some(54.7),
            course_magnetic_deg: Some(34.4),
            speed_kn: Some(5.5),
            speed_kmh: Some(10.19),
            old_form: true,
        }),
        Sentence::Hdt(Hdt {
            talker: *b"HE",
            heading_deg: 274.07,
        }),
        Sentence::Ths(Ths {
            talker: *b"GN",
            heading_deg: 244.28,
            mode: b'E',
        }),
        Sentence::Hdg(Hdg {
            talker: *b"HC",
            sensor_deg: 229.8,
            deviation_deg: Some(-2.5),
            variation_deg: Some(1.3),
        }),
        Sentence::Hdm(Hdm {
            talker: *b"AP",
            heading_deg: 218.634,
        }),
        Sentence::Pfoxb(Pfoxb {
            time: t,
            azimuth_deg: 359.99,
            reference: Reference::Relative,
            quality: 55.0,
            freq_mhz: 433.92,
            position: Some(p),
        }),
    ];
    for s in all {
        let line = body(&s);
        let back = Sentence::parse(&line).unwrap_or_else(|e| panic!("{line}: {e}"));
        // Six decimals of minutes: positions agree to 1e-6 / 60 degrees.
        let same = match (s, back) {
            (Sentence::Gga(a), Sentence::Gga(b)) => {
                near(a.position, b.position)
                    && Gga {
                        position: a.position,
                        ..b
                    } == a
            }
            (Sentence::Rmc(a), Sentence::Rmc(b)) => {
                near(a.position, b.position)
                    && Rmc {
                        position: a.position,
                        ..b
                    } == a
            }
            (Sentence::Gll(a), Sentence::Gll(b)) => {
                near(a.position, b.position)
                    && Gll {
                        position: a.position,
                        ..b
                    } == a
            }
            (Sentence::Gns(a), Sentence::Gns(b)) => {
                near(a.position, b.position)
                    && Gns {
                        position: a.position,
                        ..b
                    } == a
            }
            (Sentence::Pfoxb(a), Sentence::Pfoxb(b)) => {
                a.position.zip(b.position).is_some_and(|(x, y)| near(x, y))
                    && Pfoxb {
                        position: a.position,
                        ..b
                    } == a
            }
            (a, b) => a == b,
        };
        assert!(same, "{line}: {s:?} came back as {back:?}");
    }
}

fn near(a: LatLon, b: LatLon) -> bool {
    (a.lat - b.lat).abs() < 1e-8 && (a.lon - b.lon).abs() < 1e-8
}

#[test]
fn the_old_free_encoders_match_emit() {
    let p = LatLon {
        lat: 47.0,
        lon: 8.0,
    };
    let t = UtcTime { ms_of_day: 1000 };
    let mut line = Line::new();
    gga_body(&mut line, t, p, 8, 1.1).expect("fits");
    let g = Gga::parse(&line).expect("GGA");
    assert_eq!((g.satellites, g.quality), (Some(8), Some(1)));
}
