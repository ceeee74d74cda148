#!/usr/bin/env bash
# Where one filter's MCU instructions go: runs the step-bench image (N = 100) for one filter
# under a block-counting QEMU plugin and prints the functions with the most executed
# instructions (inlined code counts toward the function it was inlined into; add
# #[inline(never)] to split one out).
#
# Usage: bash serial-bridge/qemu/hotspots.sh <filter> [steps] [rows]
#   filters as steps.sh: sir gpf ekf fa-pf-imp pso-gpf gsa-gpf afsa-pf fa-pf gsa-gpf-rssi
# Needs: qemu-system-arm, binutils-arm-none-eabi, gcc.
set -euo pipefail
cd "$(dirname "$0")/../.."
filter=${1:?usage: hotspots.sh <filter> [steps] [rows]}
steps=${2:-60}
rows=${3:-20}
source serial-bridge/qemu/step-bench.sh
build_step_bench hotspots
run_step_bench "$filter" "$steps" "$out/libhotspots.so,out=$out/blocks.txt" > /dev/null
# Function start addresses (Thumb bit cleared), then each block charged to the function that
# contains it.
arm-none-eabi-nm -n -C --defined-only "$elf" | awk '$2 ~ /^[tTwW]$/ {
  $2 = ""; addr = $1; $1 = ""; sub(/^ +/, ""); print addr, $0 }' > "$out/functions.txt"
awk -v rows="$rows" '
  function hex(s,   i, c, v) { v = 0; s = tolower(s)
    for (i = 1; i <= length(s); i++) { c = index("0123456789abcdef", substr(s, i, 1)) - 1; v = v * 16 + c }
    return v }
  FNR == NR { start[n] = hex($1) - hex($1) % 2; $1 = ""; name[n++] = substr($0, 2); next }
  { pc = hex($1); lo = 0; hi = n - 1
    while (lo < hi) { mid = int((lo + hi + 1) / 2); if (start[mid] <= pc) lo = mid; else hi = mid - 1 }
    cost[name[lo]] += $2 * $3; total += $2 * $3 }
  END { printf "%d instructions\n", total
    for (f in cost) printf "%6.2f %% %12d  %s\n", 100 * cost[f] / total, cost[f], f }' \
  "$out/functions.txt" "$out/blocks.txt" | { read -r head; echo "$head"; sort -rn | head -n "$rows"; }
