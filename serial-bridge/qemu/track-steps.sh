#!/usr/bin/env bash
# The moving-emitter tracker on the emulated Cortex-M4F (docs/src/firmware.md, "Tracking a
# moving emitter on the microcontroller"): instructions per step of its parts at N = 128 and
# 256, four stations reporting at 10 Hz, from the counting QEMU plugin. The step-bench image
# runs each part (serial-bridge/src/bin/step-bench/track.rs) with 0 steps and with $steps; the
# difference is the steps' cost, and each part's cost is its run's less the run of the part
# before it (epochs < predict < weigh < resample). "step" is the filter's own step (resampling
# only when the effective sample size falls below N / 2), less the epochs'. RAM: the tracker's
# state (a firmware's static) and the stack its steps need below it (painted-stack mark; up to
# 256 B of it is the repaint's margin). Milliseconds at 168 MHz and one instruction a cycle
# (a lower bound); the CPU share is one step per 0.1 s.
#
# Needs: qemu-system-arm, gcc. Run from anywhere: bash serial-bridge/qemu/track-steps.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
source serial-bridge/qemu/step-bench.sh
build_step_bench icount
steps=600

count() { # $1 = filter, $2 = steps
  run_step_bench "$1" "$2" "$out/libicount.so" | sed -n 's/^instructions //p'
}
# The image's own line for a run: state bytes, step stack, rmse.
said() { # $1 = filter, $2 = steps
  timeout 600 qemu-system-arm -machine netduinoplus2 -nographic \
    -semihosting-config "enable=on,target=native,arg=step-bench,arg=$1,arg=$2" \
    -kernel "$elf" | sed -n 's/^state \([0-9]*\) B, step stack \([0-9]*\) B, D \([0-9]*\), rmse \([0-9.NaN]*\) m.*/\1 \2 \3 \4/p'
}

echo "| N (D = 13, $steps steps at 10 Hz) | epoch | predict | weigh (4 bearings) | resample + kernel | filter step (all in) | per particle | at 168 MHz | CPU at 10 Hz | state | step stack | rmse after 30 s |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for n in 128 256; do
  declare -A cost=()
  for part in epochs predict weigh resample step; do
    base=$(count "track-$n-$part" 0)
    full=$(count "track-$n-$part" "$steps")
    cost[$part]=$(((full - base) / steps))
  done
  read -r state stack _ rmse <<< "$(said "track-$n-step" "$steps")"
  read -r _ rstack _ _ <<< "$(said "track-$n-resample" "$steps")"
  [ "$rstack" -gt "$stack" ] && stack=$rstack
  awk -v n="$n" -v e="${cost[epochs]}" -v p="${cost[predict]}" -v w="${cost[weigh]}" \
    -v r="${cost[resample]}" -v s="${cost[step]}" -v state="$state" -v stack="$stack" \
    -v rmse="$rmse" 'BEGIN {
    step = s - e
    printf "| %d | %d | %d | %d | %d | %d | %d | %.2f ms | %.1f %% | %d B | %d B | %.0f m |\n",
      n, e, p - e, w - p, r - w, step, step / n, step / 168e3, 100 * step / 16.8e6, state, stack, rmse
  }'
done
