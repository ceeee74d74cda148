//! The linked firmware image, read back from its disassembly and debug lines:
//!
//! - **Budgets**: flash (text + data) at most 128 KiB; static RAM (data + bss) at most 26 KiB,
//!   so that with the painted stack's 6 KiB (asserted on the hour-long QEMU run) RAM + stack
//!   stay within 32 KiB.
//! - **No panic path in the image's own code**: every call to a panic entry point
//!   (`core::panicking::*`, slice-index failures, `unwrap_failed`, ...) is attributed, through
//!   the inlining chain of its debug line, to the innermost frame outside the standard library;
//!   none may lie in the firmware or in the bridge library, but for the byte decoders that
//!   allow indexing their buffers (the library's lint list names the same: agrelo, geo, kraken,
//!   mt, nmea's field readers, stream). Their bounds checks, heapless' SPSC index arithmetic
//!   and the defmt logger's are listed on stderr.
//! - **No `core::fmt` machinery of the image's making**: no `Debug` impl, no `fmt::write`, no
//!   float formatting (what remains is the integer `Display` that core's own bounds-check
//!   panic message references).
//! - **No `f64` on the per-bearing fix path**: nothing reachable by direct calls from
//!   `WindowFix::push` (the core's windowed fix) is software double precision or an f64 libm function (but for the core's
//!   `sincos` fallback, dead for the window's angles: see the walk).

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::PathBuf;
use std::process::Command;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn image() -> PathBuf {
    let target = workspace().join("target/firmware-test");
    let build = Command::new(env!("CARGO"))
        .current_dir(workspace())
        .env("CARGO_TARGET_DIR", &target)
        .args([
            "build",
            "--profile",
            "firmware",
            "-p",
            "foxhunt-bridge",
            "--bin",
            "foxhunt-firmware",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .status()
        .expect("cargo runs");
    assert!(build.success(), "firmware build failed");
    target.join("thumbv7em-none-eabihf/firmware/foxhunt-firmware")
}

fn tool(name: &str, args: &[&str], elf: &PathBuf) -> String {
    let out = Command::new(name)
        .args(args)
        .arg(elf)
        .output()
        .unwrap_or_else(|e| panic!("{name}: {e} (apt-get install binutils-arm-none-eabi)"));
    assert!(out.status.success(), "{name} failed");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The disassembly as functions, their direct calls and their panic call sites.
#[derive(Default)]
struct Image {
    calls: BTreeMap<String, BTreeSet<String>>,
    /// (innermost frame outside the standard library, function, panic entry called).
    panics: Vec<(String, String, String)>,
}

fn is_panic_entry(target: &str) -> bool {
    target.starts_with("core::panicking::")
        || target.starts_with("core::slice::index::")
        || target.contains("unwrap_failed")
        || target.contains("expect_failed")
        || target.starts_with("core::str::slice_error_fail")
}

fn hex(s: &str) -> Option<u64> {
    u64::from_str_radix(s.trim(), 16).ok()
}

/// The innermost frame of an inlining chain outside the standard library.
fn site_of(chain: &[String]) -> String {
    chain
        .iter()
        .find(|l| !l.starts_with("/rustc/"))
        .or(chain.first())
        .cloned()
        .unwrap_or_default()
}

fn read_image(text: &str) -> Image {
    let mut img = Image::default();
    let mut function = String::new();
    let mut chain: Vec<String> = Vec::new();
    // Branches of the current function: (target, chain); panic calls: (address, chain, target).
    let mut branches: Vec<(u64, Vec<String>)> = Vec::new();
    let mut calls: Vec<(u64, Vec<String>, String)> = Vec::new();
    let flush = |function: &str,
                 branches: &mut Vec<(u64, Vec<String>)>,
                 calls: &mut Vec<(u64, Vec<String>, String)>,
                 img: &mut Image| {
        for (at, chain, target) in calls.drain(..) {
            // The compiler merges a function's panics into cold blocks at its end, whose own
            // line is the function's last: charge the branches that jump there instead.
            let from: Vec<_> = branches
                .iter()
                .filter(|(t, _)| *t + 12 >= at && *t <= at)
                .map(|(_, c)| site_of(c))
                .collect();
            if from.is_empty() {
                img.panics
                    .push((site_of(&chain), function.to_string(), target));
            } else {
                for site in from {
                    img.panics
                        .push((site, function.to_string(), target.clone()));
                }
            }
        }
        branches.clear();
    };
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("inlined by ") {
            chain.push(rest.split(" (").next().unwrap_or(rest).to_string());
            continue;
        }
        if line.starts_with('/') {
            chain = vec![line.to_string()];
            continue;
        }
        if line.ends_with(">:") && !line.starts_with(' ') {
            flush(&function, &mut branches, &mut calls, &mut img);
            if let (Some(a), Some(b)) = (line.find('<'), line.rfind('>')) {
                function = line[a + 1..b].to_string();
                img.calls.entry(function.clone()).or_default();
            }
            continue;
        }
        let Some((addr, insn)) = line.split_once(":\t") else {
            continue;
        };
        let Some(addr) = hex(addr) else { continue };
        let mut parts = insn.split('\t');
        let op = parts.next().unwrap_or("").trim();
        let operand = parts.next().unwrap_or("");
        let (Some(a), Some(b)) = (operand.find('<'), operand.rfind('>')) else {
            continue;
        };
        let target = operand[a + 1..b]
            .split('+')
            .next()
            .unwrap_or("")
            .to_string();
        let target_addr = operand
            .split_whitespace()
            .rev()
            .find_map(|w| hex(w.trim_end_matches(',')));
        let is_call =
            matches!(op, "bl" | "blx") || (matches!(op, "b.w" | "b") && target != function);
        if (op.starts_with('b') || op.starts_with("cb"))
            && let Some(t) = target_addr
        {
            branches.push((t, chain.clone()));
        }
        if !is_call || target == function {
            continue;
        }
        if is_panic_entry(&target) && !is_panic_entry(&function) {
            calls.push((addr, chain.clone(), target.clone()));
        }
        img.calls
            .entry(function.clone())
            .or_default()
            .insert(target);
    }
    flush(&function, &mut branches, &mut calls, &mut img);
    img
}

/// The bridge's files that allow indexing (`#![allow(clippy::indexing_slicing)]`), from
/// serial-bridge/src.
const DECODERS: [&str; 6] = [
    "agrelo.rs",
    "geo.rs",
    "kraken/",
    "mt.rs",
    "nmea/fields.rs",
    "stream/",
];

/// Whether a call site is the image's own code: the firmware, the core's windowed fix it runs
/// on every bearing, or the bridge library but for its decoders.
fn own(site: &str) -> bool {
    const LIB: &str = "serial-bridge/src/";
    site.contains("serial-bridge/src/bin/firmware")
        || site.contains("core/src/fix/window/")
        || site.find(LIB).is_some_and(|i| {
            let file = &site[i + LIB.len()..];
            !file.starts_with("bin/") && !DECODERS.iter().any(|d| file.starts_with(d))
        })
}

#[test]
fn the_image_fits_panics_nowhere_of_its_own_and_keeps_f64_off_the_fix_path() {
    let elf = image();
    let size = tool("arm-none-eabi-size", &[], &elf);
    let row: Vec<u64> = size
        .lines()
        .nth(1)
        .expect("size row")
        .split_whitespace()
        .take(3)
        .map(|v| v.parse().expect("number"))
        .collect();
    let (text, data, bss) = (row[0], row[1], row[2]);
    eprintln!("flash {} B, static RAM {} B", text + data, data + bss);
    assert!(text + data <= 128 * 1024, "flash {} B", text + data);
    // RAM + stack <= 32 KiB, split 26 + 6 (firmware_qemu.rs asserts the hour's painted stack
    // <= 6 KiB; about 2.9 KiB is used): the station table, the per-unit clocks and the window
    // fill 24.3 KiB.
    assert!(data + bss <= 26 * 1024, "static RAM {} B", data + bss);

    let dis = tool(
        "arm-none-eabi-objdump",
        &["-d", "-l", "--inlines", "-C", "--no-show-raw-insn"],
        &elf,
    );
    let img = read_image(&dis);
    assert!(img.calls.len() > 100, "disassembly not read");
    let mut by_site: BTreeMap<String, usize> = BTreeMap::new();
    for (site, _, _) in &img.panics {
        // Paths from the crate's directory on.
        let short = ["/index.crates.io-", "/work/wt/", "/rustc/"]
            .iter()
            .find_map(|p| site.find(p).map(|i| &site[i + p.len()..]))
            .map(|rest| rest.split_once('/').map_or(rest, |(_, r)| r))
            .unwrap_or(site);
        *by_site.entry(short.to_string()).or_default() += 1;
    }
    eprintln!("panic call sites outside the image's own code:");
    for (s, n) in &by_site {
        eprintln!("  {n:3} {s}");
    }
    let ours: Vec<_> = img.panics.iter().filter(|(s, _, _)| own(s)).collect();
    assert!(
        ours.is_empty(),
        "panic paths in the image's own code: {ours:#?}"
    );

    let nm = tool("arm-none-eabi-nm", &["-C"], &elf);
    let fmt_made: Vec<_> = nm
        .lines()
        .filter(|l| {
            l.contains("as core::fmt::Debug>")
                || l.contains("core::fmt::write")
                || l.contains("core::fmt::float")
                || l.contains("Formatter>::write_fmt")
                || l.contains("Formatter>::pad_formatted_parts")
        })
        .collect();
    assert!(fmt_made.is_empty(), "core::fmt in the image: {fmt_made:#?}");

    // Everything WindowFix::push reaches by direct calls.
    let roots: Vec<&String> = img
        .calls
        .keys()
        .filter(|f| f.starts_with("foxhunt_core::fix::window::WindowFix::push"))
        .collect();
    assert!(!roots.is_empty(), "WindowFix::push not found as a function");
    let mut seen: BTreeSet<String> = BTreeSet::new();
    let mut queue: VecDeque<String> = roots.into_iter().cloned().collect();
    // The core's `fastmath::sincos` falls back to libm's `sincosf` (f64 kernels) for
    // |x| > 8192 or NaN; the window passes only angles it holds in (-pi, pi] (its `sin_cos`
    // maps anything else to 0), so that branch is dead, though the compiler keeps it. The
    // walk stops there; a fallback-free core variant would let it go on.
    const DEAD: &str = "libm::math::sincosf::sincosf";
    while let Some(f) = queue.pop_front() {
        if f == DEAD || !seen.insert(f.clone()) {
            continue;
        }
        for g in img.calls.get(&f).into_iter().flatten() {
            queue.push_back(g.clone());
        }
    }
    let double = |f: &str| {
        f.starts_with("__aeabi_d")
            || f.starts_with("__aeabi_f2d")
            || f.contains("df3")
            || f.contains("extendsfdf")
            || f.contains("truncdfsf")
            || f.contains("float::") && f.contains("df")
            || f.starts_with("libm::math::") && {
                let name = f.rsplit("::").next().unwrap_or(f);
                name.starts_with("rem_pio2") || name.starts_with("k_") || !name.ends_with('f')
            }
    };
    let f64s: Vec<_> = seen.iter().filter(|f| double(f)).collect();
    for f in &seen {
        let bad: Vec<_> = img
            .calls
            .get(f)
            .into_iter()
            .flatten()
            .filter(|g| double(g))
            .collect();
        if !double(f) && !bad.is_empty() {
            eprintln!("  {f} calls {bad:?}");
        }
    }
    eprintln!("WindowFix::push reaches {} functions", seen.len());
    assert!(f64s.is_empty(), "f64 on the fix path: {f64s:#?}");
}
