#!/usr/bin/env bash
# Feed a capture to the firmware image on QEMU's netduinoplus2 through its emulated USARTs
# and print on stdout exactly the bytes the image sent on its user port (USART3): the ready
# banner, a $PFOXF fix after every bearing, $PFOXS/$PFOXL status once a second, $PFOXA
# acknowledgements. See serial-bridge/src/bin/uart-replay.rs for how the capture is split and
# paced.
#
# Usage: bash serial-bridge/qemu/uart-replay.sh [uart-replay options] CAPTURE
#   e.g. --speed 20 (pace 20 times faster than the capture's own times), --out DIR (keep the
#   per-port streams, the defmt log and QEMU's stderr there), --icount, --plugin SO.
# Needs: qemu-system-arm (and defmt-print to read DIR/defmt.bin).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$root"
cargo build -q --profile firmware -p foxhunt-bridge --bin foxhunt-firmware \
  --target thumbv7em-none-eabihf >&2
cargo build -q --profile ci -p foxhunt-bridge --bin uart-replay >&2
args=()
for a in "$@"; do
  # Paths relative to where the caller stood.
  if [ -e "$OLDPWD/$a" ] && [ "${a#/}" = "$a" ]; then a="$OLDPWD/$a"; fi
  args+=("$a")
done
t="${CARGO_TARGET_DIR:-target}"
exec "$t/ci/uart-replay" --elf "$t/thumbv7em-none-eabihf/firmware/foxhunt-firmware" "${args[@]}"
