#!/usr/bin/env bash
# The firmware image's figures on the emulated Cortex-M4F, as one markdown table: flash,
# static RAM, painted stack, queue high-water marks, instructions per byte (all in), per
# bearing and per fix, and the worst latency from a record's last byte to its fix sentence's
# last byte.
#
# A capture (default: a 15-minute drive round an 800 m loop past an emitter, 900 bearings of
# 2 degrees, written by `foxhunt simulate` from a scenario file made here: long enough that
# the window fills and the fix runs at its steady cost) goes through the image's USARTs (uart-replay.sh)
# under `-icount shift=0` (one instruction, one nanosecond: the image's SysTick ticks at
# 168 MHz of that time are 0.168 per instruction) and the counting plugin (icount.c): once
# whole, once without its bearings. Instructions per byte = the whole run's count over the
# bytes fed (it includes the 1 kHz tick and the once-a-second status over the run's length);
# per bearing = the difference of the two runs over the bearings (record, bridge, fix and
# sentence); the worst fix and latency are the image's own tick measurements. Milliseconds
# are at 168 MHz and one instruction a cycle (a lower bound: flash wait states cost more).
#
# Needs: qemu-system-arm, binutils-arm-none-eabi, gcc. Usage:
#   bash serial-bridge/qemu/footprint.sh [CAPTURE] [SPEED]   (SPEED 10 by default: faster, QEMU's GPS
#   line lags its DF line and bearings arrive after the fixes kept for them)
set -euo pipefail
cd "$(dirname "$0")/../.."
speed=${2:-10}
out=target/footprint
mkdir -p "$out"
if [ -n "${1:-}" ]; then
  capture=$(realpath "$1")
else
  awk 'BEGIN { printf "name = \"loop900\"\nemitter = [1500.0, 1200.0]\nbearing_sigma_deg = 2.0\npoints = ["
    for (k = 0; k < 900; k++) { a = k * 10 / 800; printf "%s[%.3f, %.3f]", (k ? ", " : ""), 800 * sin(a), 800 * (1 - cos(a)) }
    print "]" }' > "$out/loop900.toml"
  cargo run -q --profile ci -p foxhunt-sim -- simulate --scenario-file "$out/loop900.toml" \
    --out "$out/loop900.nmea" --force > /dev/null
  capture=$(realpath "$out/loop900.nmea")
fi
gcc -O2 -shared -fPIC -o "$out/libicount.so" serial-bridge/qemu/icount.c
grep -av '^\$PFOXB' "$capture" > "$out/no-bearings.nmea" || true

run() { # $1 = name, $2 = capture
  bash serial-bridge/qemu/uart-replay.sh --icount --plugin "$(realpath "$out/libicount.so")" \
    --speed "$speed" --out "$(realpath "$out")/$1" "$2" > "$out/$1.user"
}
run whole "$capture"
run gps "$out/no-bearings.nmea"
elf=${CARGO_TARGET_DIR:-target}/thumbv7em-none-eabihf/firmware/foxhunt-firmware
count() { sed -n 's/^instructions //p' "$out/$1/qemu.err"; }
bytes() { cat "$out/$1"/{gps,df,zigbee,user}.bin | wc -c; }
last() { grep -a "^\$$2," "$out/$1.user" | tail -1 | sed 's/\*.*//'; }
whole=$(count whole)
gps=$(count gps)
IFS=, read -r _ up stack hw_gps hw_df hw_zb hw_out latency fix _ <<< "$(last whole PFOXS)"
IFS=, read -r _ _ _ _ _ _ _ _ bearings fixes <<< "$(last whole PFOXL)"
read -r text data bss _ < <(arm-none-eabi-size "$elf" | tail -1)
awk -v text="$text" -v data="$data" -v bss="$bss" -v stack="$stack" \
  -v whole="$whole" -v gps="$gps" -v bw="$(bytes whole)" -v bg="$(bytes gps)" \
  -v bearings="$bearings" -v fixes="$fixes" -v latency="$latency" -v fix="$fix" \
  -v hw="$hw_gps / $hw_df / $hw_zb / $hw_out" -v name="$(basename "$capture")" 'BEGIN {
  li = latency / 0.168; fi = fix / 0.168; pb = (whole - gps) / bearings
  printf "| quantity (%s, %d bearings, %d fixes) | value | budget |\n", name, bearings, fixes
  print "|---|---:|---:|"
  printf "| flash (text + data) | %d B | 131072 B |\n", text + data
  printf "| static RAM (data + bss) | %d B | |\n", data + bss
  printf "| painted stack, high-water mark | %d B | |\n", stack
  printf "| RAM + stack | %d B | 32768 B |\n", data + bss + stack
  printf "| queue high-water marks, bytes (GPS / DF / ZigBee / output) | %s | capacity 512 / 512 / 256 / 1024 |\n", hw
  printf "| instructions per byte, all in (%d instructions, %d bytes) | %.0f | |\n", whole, bw, whole / bw
  printf "| instructions per byte, GPS only (no bearings) | %.0f | |\n", gps / bg
  printf "| instructions per bearing, all in (record, bridge, fix, sentence) | %.0f (%.2f ms) | |\n", pb, pb / 168e3
  printf "| worst fix update (the read that completed the bearing) | %.0f instructions (%.2f ms) | |\n", fi, fi / 168e3
  printf "| worst latency, record last byte to fix sentence last byte | %.0f instructions (%.2f ms) | 20 ms |\n", li, li / 168e3
}'
