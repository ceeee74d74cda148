use super::*;
use std::string::String;

/// Feed one record through a decoder in reads of `chunk` bytes, as the demultiplexer
/// does (tokens are cut from the front; incomplete ones wait for more).
fn csv(line: &str, spectrum: &mut [f32]) -> Result<KrakenCsv, KrakenError> {
    let mut d = CsvDecoder::new();
    let b = line.as_bytes();
    let mut at = 0;
    loop {
        match d.step(&b[at..], true, spectrum) {
            Step::Took(n) => at += n,
            Step::Done(_, r) => return Ok(r),
            Step::Reject(e, _) => return Err(e),
            Step::NeedMore => return Err(KrakenError::Structure),
        }
    }
}

fn xml(text: &str) -> Result<KrakenXml, KrakenError> {
    let mut d = XmlDecoder::new();
    let b = text.as_bytes();
    let mut at = 0;
    loop {
        match d.step(&b[at..]) {
            Step::Took(n) => at += n,
            Step::Done(_, r) => return Ok(r),
            Step::Reject(e, _) => return Err(e),
            Step::NeedMore => return Err(KrakenError::Structure),
        }
    }
}

/// The line a user posted in ckoval7/df-aggregator issue 11 (2023, integer bearing), its
/// spectrum completed to 360 values.
pub(crate) fn issue_11_line() -> String {
    let mut s = String::from(
        "1679512414650, 134, 0.41, -48.5, 151880000, UCA, 100, dingus, 66.961348, -66.4438057, 0, 0, GPS, R, R, R, R, 0.07, 0.08",
    );
    for i in 2..SPECTRUM_LEN {
        s.push_str(&std::format!(", {}.{:02}", i / 100, i % 100));
    }
    s.push_str(" \n");
    s
}

#[test]
fn the_line_from_df_aggregator_issue_11() {
    let mut spectrum = [0f32; SPECTRUM_LEN];
    let r = csv(&issue_11_line(), &mut spectrum).expect("line");
    assert_eq!(r.epoch_ms, 1_679_512_414_650);
    assert_eq!(
        (r.bearing_deg, r.confidence, r.power_db),
        (134.0, 0.41, -48.5)
    );
    assert_eq!(
        (r.freq_hz, r.array, r.latency_ms),
        (151_880_000, ArrayType::Uca, 100)
    );
    assert_eq!(r.station.as_str(), "dingus");
    let p = r.position.expect("fix");
    assert_eq!((p.lat, p.lon), (66.961348, -66.4438057));
    assert_eq!(
        (spectrum[0], spectrum[1], spectrum[359]),
        (0.07, 0.08, 3.59)
    );
    assert_eq!(r.relative_deg(CsvConvention::Clockwise), 134.0);
    assert_eq!(r.relative_deg(CsvConvention::Anticlockwise), 226.0);
}

#[test]
fn csv_round_trip_and_rejects() {
    let mut spectrum = [0f32; SPECTRUM_LEN];
    let r = csv(&issue_11_line(), &mut spectrum).expect("line");
    let mut out = String::new();
    r.emit(&spectrum, &mut out).expect("string");
    let mut back = [0f32; SPECTRUM_LEN];
    assert_eq!(csv(&out, &mut back), Ok(r));
    assert_eq!(back, spectrum);
    assert!(out.len() > 2000, "a line is ~2.5 KB: {}", out.len());
    // No fix is (0, 0); 360 reads as 0; a line without its end at the end of a file.
    let zero = out.replacen("66.9613480, -66.4438057", "0.0, 0.0", 1);
    assert_eq!(csv(&zero, &mut back).map(|r| r.position), Ok(None));
    assert_eq!(
        csv(out.trim_end(), &mut back).map(|r| r.epoch_ms),
        Ok(1_679_512_414_650)
    );
    let short = out.replacen(", 0.07", "", 1);
    assert_eq!(csv(&short, &mut back), Err(KrakenError::Structure));
    let bad = out.replacen("134", "1x4", 1);
    assert_eq!(csv(&bad, &mut back), Err(KrakenError::BadField(2)));
    let epoch = out.replacen("1679512414650", "167951241465", 1);
    assert_eq!(csv(&epoch, &mut back), Err(KrakenError::BadField(1)));
}

#[test]
fn kerberos_sample_and_current_form() {
    // ckoval7/rdf-sim kerbs_xml_sample.xml, byte for byte.
    let sample = "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<DATA>\n\t<STATION_ID>K3CPK-1</STATION_ID>\n\t<TIME>1568052311</TIME>\n\t<FREQUENCY>162.4</FREQUENCY>\n\t<LOCATION>\n\t\t<LATITUDE>39.124526</LATITUDE>\n\t\t<LONGITUDE>-76.519717</LONGITUDE>\n\t\t<HEADING>0</HEADING>\n\t</LOCATION>\n\t<DOA>120</DOA>\n\t<PWR>19.265165</PWR>\n\t<CONF>15</CONF>\n</DATA>\n";
    let r = xml(sample).expect("sample");
    assert_eq!(r.station.as_str(), "K3CPK-1");
    assert_eq!(r.time_ms, Some(1_568_052_311_000), "seconds there");
    assert_eq!(
        (r.freq_mhz, r.doa_deg, r.conf),
        (Some(162.4), 120.0, Some(15.0))
    );
    let p = r.position.expect("position");
    assert_eq!((p.lat, p.lon), (39.124526, -76.519717));
    // df-aggregator's true bearing: heading + 360 - DOA.
    assert_eq!(r.true_deg(), Some(240.0));
    // The current one-line form round-trips; its TIME is in ms.
    let mut out = String::new();
    r.emit(&mut out).expect("string");
    assert!(!out.contains('\n') && out.starts_with("<DATA><STATION_ID>K3CPK-1"));
    let back = xml(&out).expect("one line");
    assert_eq!(
        (back.time_ms, back.doa_deg, back.position),
        (r.time_ms, 120.0, r.position)
    );
    let mut legacy = String::new();
    r.emit_legacy(&mut legacy).expect("string");
    assert_eq!(xml(&legacy).map(|b| b.time_ms), Ok(r.time_ms));
    // KrakenSDR's wr_xml element order with the fields the old form lacks.
    let kraken = "<DATA><STATION_ID>NOCALL</STATION_ID><TIME>1700000000123</TIME><GPS_TIME>0</GPS_TIME><FREQUENCY>433.92</FREQUENCY><LOCATION><LATITUDE>0.0</LATITUDE><LONGITUDE>0.0</LONGITUDE><HEADING>0.0</HEADING><SPEED>0.0</SPEED></LOCATION><DOA>270</DOA><PWR>52.5</PWR><CONF>1234</CONF><LATENCY>100</LATENCY><PROCESSING_TIME>42</PROCESSING_TIME><ADC_OVERDRIVE>False</ADC_OVERDRIVE><NUM_CORRELATED_SOURCES>0</NUM_CORRELATED_SOURCES><SNR_DB>12.5</SNR_DB></DATA>";
    let k = xml(kraken).expect("kraken");
    assert_eq!(
        (k.time_ms, k.gps_time_ms, k.position),
        (Some(1_700_000_000_123), None, None)
    );
    assert_eq!(k.relative_deg(), 90.0);
    assert_eq!(
        xml("<DATA><CONF>1</CONF></DATA>"),
        Err(KrakenError::NoBearing)
    );
    assert_eq!(
        xml("<DATA><DOA>1</CONF></DATA>"),
        Err(KrakenError::Structure)
    );
}

#[test]
fn an_xml_record_with_a_doubled_element_or_a_frequency_below_zero_is_refused() {
    let one = "<DATA><STATION_ID>K</STATION_ID><TIME>1700000000123</TIME><FREQUENCY>433.92</FREQUENCY><DOA>270</DOA><CONF>50</CONF></DATA>";
    assert!(xml(one).is_ok());
    // Two bearings in one record: neither can be told to be the right one.
    assert_eq!(
        xml(&one.replace("<DOA>270</DOA>", "<DOA>270</DOA><DOA>90</DOA>")),
        Err(KrakenError::Structure)
    );
    assert_eq!(
        xml(&one.replace("<TIME>", "<TIME>1</TIME><TIME>")),
        Err(KrakenError::Structure)
    );
    // A frequency below zero (or zero) is no channel: refused as the CSV refuses it, not
    // joined to the bearings without a frequency.
    for f in ["-433.92", "0", "-0.5"] {
        assert_eq!(
            xml(&one.replace("433.92", f)),
            Err(KrakenError::BadField(0)),
            "{f}"
        );
    }
    // Elements the decoder does not read may repeat.
    assert!(xml(&one.replace("<CONF>", "<SNR_DB>1</SNR_DB><SNR_DB>2</SNR_DB><CONF>")).is_ok());
}
