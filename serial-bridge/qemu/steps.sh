#!/usr/bin/env bash
# Instructions per particle per step of every filter on the emulated Cortex-M4F (N = 100), from
# the counting QEMU plugin: the step-bench image runs each filter with 0 steps and with 60, and
# the difference is the steps' cost. Prints a markdown table with each whole 60-step run in
# instructions and in milliseconds at 168 MHz (one instruction per cycle: a lower bound, flash
# wait states and divisions cost more).
#
# Needs: qemu-system-arm, gcc. Run from anywhere: bash serial-bridge/qemu/steps.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
source serial-bridge/qemu/step-bench.sh
build_step_bench icount
particles=100
steps=60

count() { # $1 = filter, $2 = steps
  run_step_bench "$1" "$2" "$out/libicount.so" | sed -n 's/^instructions //p'
}

echo "| filter (N = $particles, $steps steps) | instructions per particle per step | whole run, M instructions | at 168 MHz |"
echo "|---|---:|---:|---:|"
for f in sir gpf ekf fa-pf-imp pso-gpf gsa-gpf afsa-pf fa-pf gsa-gpf-rssi; do
  base=$(count "$f" 0)
  full=$(count "$f" "$steps")
  run=$((full - base))
  per=$((run / (particles * steps)))
  [ "$f" = ekf ] && per="- (no particles; $((run / steps)) per step)"
  awk -v f="$f" -v per="$per" -v run="$run" \
    'BEGIN { printf "| %s | %s | %.2f | %.1f ms |\n", f, per, run / 1e6, run / 168e3 }'
done
