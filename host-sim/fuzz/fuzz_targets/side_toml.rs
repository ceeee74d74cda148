//! Arbitrary text through the TOML side-file readers (anchors, calibration, scenario) and the
//! `--reference` value: a value or one line of error, never a panic.
#![no_main]
use foxhunt_sim::inputs::calibration::Calibration;
use foxhunt_sim::inputs::stations::parse_reference;
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_sim::track::indoor::AnchorsFile;
use libfuzzer_sys::fuzz_target;

fn one_line<T>(r: Result<T, String>) {
    if let Err(e) = r {
        assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
    }
}

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    one_line(AnchorsFile::from_toml(&text));
    one_line(Calibration::from_toml(&text));
    one_line(Scenario::from_toml(&text));
    one_line(parse_reference(&text));
});
