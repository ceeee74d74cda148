#!/usr/bin/env bash
# Flash and instructions per byte on the Cortex-M4F (QEMU netduinoplus2, counting plugin) of
# our NMEA decoder and of the nmea crate (0.8), each behind our framing, over the bundled
# drive; and the share of GPSD's positions each reproduces over its regression captures.
# Needs: qemu-system-arm, binutils-arm-none-eabi, gcc, the thumbv7em-none-eabihf target.
# Run: bash serial-bridge/nmea-compare/measure.sh [folder of GPSD captures; default: the
# vendored serial-bridge/tests/data/gpsd]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="$here/target"
mkdir -p "$out"
gcc -O2 -shared -fPIC -o "$out/libicount.so" "$here/../qemu/icount.c"
bytes=$(stat -c %s "$here/../captures/aoa-drive.nmea")
for v in none ours nmea-crate; do
  feat=""; [ "$v" != none ] && feat="--features $v"
  (cd "$here/mcu" && CARGO_TARGET_DIR="$out/$v" cargo build -q --release --target thumbv7em-none-eabihf $feat)
  elf="$out/$v/thumbv7em-none-eabihf/release/foxhunt-nmea-compare-mcu"
  set +e
  timeout 120 qemu-system-arm -machine netduinoplus2 -nographic \
    -semihosting-config enable=on,target=native -plugin "$out/libicount.so" -kernel "$elf" \
    > "$out/$v.out" 2> "$out/$v.err"
  status=$?
  set -e
  text=$(arm-none-eabi-size "$elf" | awk 'NR==2 {print $1}')
  n=$(sed -n 's/^instructions //p' "$out/$v.err")
  echo "$v text=$text instructions=$n fixes_mod_256=$status" | tee -a "$out/summary"
done
awk -v bytes="$bytes" '
  { split($2, t, "="); split($3, n, "="); text[$1] = t[2]; ins[$1] = n[2] }
  END {
    for (v in text) if (v != "none")
      printf "%s: decoder flash %d B, %.1f instructions per byte (framing alone: %.1f)\n",
        v, text[v] - text["none"], (ins[v] - ins["none"]) / bytes, ins["none"] / bytes
  }' "$out/summary"
rm -f "$out/summary"
(cd "$here/suite" && cargo run -q --release -- "${1:-$here/../tests/data/gpsd}" | tail -n 1)
