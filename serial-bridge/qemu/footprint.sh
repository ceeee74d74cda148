#!/usr/bin/env bash
# The firmware image's footprint on the emulated Cortex-M4F: flash, static RAM, painted-stack
# high-water mark, and exact instructions per particle per SIR step (N = 100), from a counting
# QEMU plugin. The step cost is the difference between the image and its `baseline` build,
# which skips the filter steps, divided by particles x steps. The image streams the bundled
# drive from the host over semihosting (as from a UART), so the flash figure is the product's.
#
# Needs: qemu-system-arm, binutils-arm-none-eabi (arm-none-eabi-size), gcc.
# Run from anywhere: bash serial-bridge/qemu/footprint.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
out=target/footprint
mkdir -p "$out"
gcc -O2 -shared -fPIC -o "$out/libicount.so" serial-bridge/qemu/icount.c

run() { # $1 = variant name, $2 = extra cargo flags
  CARGO_TARGET_DIR="$out/$1" cargo build -q --profile firmware -p foxhunt-bridge --bin foxhunt-firmware \
    --target thumbv7em-none-eabihf $2
  local elf="$out/$1/thumbv7em-none-eabihf/firmware/foxhunt-firmware"
  timeout 300 qemu-system-arm -machine netduinoplus2 -nographic \
    -semihosting-config enable=on,target=native -plugin "$out/libicount.so" -kernel "$elf" \
    > "$out/$1.out" 2> "$out/$1.err"
  echo "$elf"
}

full_elf=$(run full "")
run baseline "--features baseline" > /dev/null
count() { sed -n 's/^instructions //p' "$out/$1.err"; }
full=$(count full)
base=$(count baseline)
stack=$(sed -n 's/^stack //p' "$out/full.out")
read -r text data bss _ < <(arm-none-eabi-size "$full_elf" | tail -1)
particles=100
steps=$(sed -n 's/^bearings \([0-9]*\).*/\1/p' "$out/full.out")

echo "| quantity | value |"
echo "|---|---|"
echo "| flash (text + rodata + data) | $((text + data)) B |"
echo "| static RAM (data + bss) | $((data + bss)) B |"
echo "| stack high-water mark (painted) | $stack B |"
echo "| instructions, whole run (bridge + SIR + ML) | $full |"
echo "| instructions, run without the SIR steps | $base |"
echo "| SIR instructions per particle per step (N = $particles, $steps steps) | $(( (full - base) / (particles * steps) )) |"
